//! What a scene's raw planes depend on, as one comparable value: two scenes with equal
//! [`RenderInputs`] compute the same planes wherever their layers read the same quantities,
//! so a change elsewhere (the colouring stack, the background, the output settings) only
//! recolours. The viewer decides "recolour or render" by comparing these typed values.

use super::{EngineChoice, FamilySpec, Scene};
use crate::field::{Projection, Transform};
use crate::num::Decimal;
use crate::orbit::Scale;
use crate::orbit::interior::Detection;

/// Everything of a scene that decides its planes, besides which quantities its layers
/// read and the traps they run ([`crate::compose::Stack::needs`], [`Scene::traps`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderInputs<'a> {
    /// Mandelbrot or Julia form.
    pub family: &'a FamilySpec,
    /// The map.
    pub formula: crate::formula::Formula,
    /// The view's centre.
    pub center: &'a [Decimal; 2],
    /// The view's scale as written.
    pub scale: &'a Scale,
    /// Rotation and stretch.
    pub transform: Transform,
    /// Flat or exponential map.
    pub projection: Projection,
    /// Image size in pixels.
    pub size: [u32; 2],
    /// Supersampling factor.
    pub aa: u32,
    /// Iteration limit.
    pub max_iter: u32,
    /// Escape radius.
    pub escape_radius: f64,
    /// The engine requested.
    pub engine: EngineChoice,
    /// BLA tolerance.
    pub bla: Option<f64>,
    /// Interior detection.
    pub interior_detection: Detection,
}

impl Scene {
    /// What this scene's planes depend on besides its layers' needs and traps.
    pub fn render_inputs(&self) -> RenderInputs<'_> {
        RenderInputs {
            family: &self.family,
            formula: self.formula,
            center: &self.center,
            scale: &self.scale,
            transform: self.transform,
            projection: self.projection,
            size: [self.width, self.height],
            aa: self.aa,
            max_iter: self.max_iter,
            escape_radius: self.escape_radius,
            engine: self.engine,
            bla: self.bla,
            interior_detection: self.interior_detection,
        }
    }

    /// True when `self`'s planes serve `new`: the same render inputs, every quantity `new`'s
    /// layers read computed here, and the same traps (or none needed).
    pub fn planes_serve(&self, new: &Scene) -> bool {
        let (have, want) = (self.stack.needs(&self.traps), new.stack.needs(&new.traps));
        self.render_inputs() == new.render_inputs()
            && (have.nf || !want.nf)
            && (have.t || !want.t)
            && (have.de || !want.de)
            && (self.traps == new.traps || new.traps.is_empty())
    }
}
