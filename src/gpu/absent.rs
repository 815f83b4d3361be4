//! The stand-in for the wgpu device in builds without the `gpu` feature (headless servers
//! and cluster nodes, built with `--no-default-features`).
//!
//! [`GpuContext`] is then an enum with no values: [`GpuContext::shared`] always answers
//! [`GpuError::NotBuilt`], so `--engine gpu` is refused with that reason, and every function
//! that takes a context (such as [`super::field::compute_planes`]) type-checks but can never
//! be called. Nothing pretends to compute.

use std::sync::Arc;

use super::GpuError;

/// No GPU device: this build has none (see the module documentation).
#[derive(Debug)]
pub enum GpuContext {}

impl GpuContext {
    /// Always [`GpuError::NotBuilt`].
    pub fn shared() -> Result<Arc<GpuContext>, GpuError> {
        Err(GpuError::NotBuilt)
    }

    /// Unreachable: no context exists.
    pub fn adapter_name(&self) -> &str {
        match *self {}
    }

    /// Unreachable: no context exists.
    pub fn software(&self) -> bool {
        match *self {}
    }
}
