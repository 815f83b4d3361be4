//! TEMPORARY shim until the gpu branch merges (deleted at merge).
#![allow(missing_docs, dead_code)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Precision {
    F32,
    DoubleFloat,
}
impl Precision {
    pub fn exhausted(self, _s: f64, _c: [f64; 2]) -> bool {
        false
    }
}
pub mod paint {
    use eframe::egui;
    pub struct PaintParams {
        pub center: [f64; 2],
        pub spacing: f64,
        pub size_px: [u32; 2],
        pub julia: Option<[f64; 2]>,
        pub max_iter: u32,
        pub escape_radius: f64,
        pub precision: super::Precision,
        pub palette: Vec<[f32; 4]>,
        pub density: f32,
        pub offset: f32,
        pub distance_k: Option<f32>,
    }
    pub fn register(_rs: &eframe::egui_wgpu::RenderState) {}
    pub fn paint_callback(rect: egui::Rect, _p: PaintParams) -> egui::Shape {
        egui::Shape::rect_filled(rect, 0.0, egui::Color32::from_rgb(40, 0, 40))
    }
}
