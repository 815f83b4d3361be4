//! The viewer's difference mode: the same view computed by the GPU f32 shader (headless
//! compute on the shared wgpu context) and coloured by the same layers as the CPU render,
//! shown as the per-pixel difference |CPU - GPU| (amplified 4x), with the fraction of
//! pixels whose escape count N differs. Computed on a background thread once per render.

use std::sync::mpsc::{self, Receiver};

use crate::field::{ChannelSet, Planes};
use crate::formula::end::INTERIOR;
use crate::gpu::{self, Precision};
use crate::render;
use crate::scene::Scene;

/// A finished comparison.
#[derive(Debug, Clone)]
pub struct Difference {
    /// The render it compares (the viewer's job serial number).
    pub job: u64,
    /// Pixels.
    pub size: [u32; 2],
    /// |CPU - GPU| x 4 per channel, 8-bit RGB.
    pub rgb8: Vec<u8>,
    /// Fraction of samples whose N differs.
    pub n_mismatch: f64,
}

/// A comparison in flight.
pub struct Pending {
    rx: Receiver<Result<Difference, String>>,
}

/// Starts comparing the CPU planes of a render with the GPU's.
pub fn start(job: u64, scene: Scene, cpu: Vec<Planes>, precision: Precision) -> Pending {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(compare(job, &scene, &cpu, precision));
    });
    Pending { rx }
}

impl Pending {
    /// The result, once there is one.
    pub fn poll(&self) -> Option<Result<Difference, String>> {
        self.rx.try_recv().ok()
    }
}

fn compare(job: u64, scene: &Scene, cpu: &[Planes], precision: Precision) -> Result<Difference, String> {
    let ctx = gpu::GpuContext::shared().map_err(|e| e.to_string())?;
    let params = render::field_params(scene, ChannelSet::default());
    let rows = scene.height * scene.aa;
    let gpu_planes = gpu::field::compute_planes(&ctx, &params, precision, 0..rows).map_err(|e| e.to_string())?;
    let a = render::recolor_rgb8(&scene.stack, cpu, scene.aa).map_err(|e| e.to_string())?.concat();
    let b = render::recolor_rgb8(&scene.stack, std::slice::from_ref(&gpu_planes), scene.aa)
        .map_err(|e| e.to_string())?
        .concat();
    let rgb8 = a.iter().zip(&b).map(|(x, y)| (x.abs_diff(*y) as u32 * 4).min(255) as u8).collect();
    let cpu_n = cpu.iter().flat_map(|p| p.n.iter().copied());
    let (mut differ, mut total) = (0usize, 0usize);
    for (x, y) in cpu_n.zip(gpu_planes.n.iter().copied()) {
        total += 1;
        if x != y && !(x == INTERIOR && y == INTERIOR) {
            differ += 1;
        }
    }
    Ok(Difference { job, size: [scene.width, scene.height], rgb8, n_mismatch: differ as f64 / total.max(1) as f64 })
}
