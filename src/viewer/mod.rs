//! `deepfield view`: an egui explorer (eframe with the wgpu renderer) over the library's
//! render path.
//!
//! - [`nav`]: the view as exact decimal centre and zoom, pans, zooms about a point, box zoom,
//!   history (pure, tested);
//! - [`newton`]: Newton zooming to the minibrot or Misiurewicz point near a pixel;
//! - [`worker`]: progressive rendering on a background thread, cancelled by newer views;
//! - [`app`]: the window: image, panels, input, recolouring, Julia preview, GPU modes;
//! - [`layers_panel`]: the layers panel, a control for every key each layer's kind takes;
//! - [`palette_editor`], [`export`]: the palette editor and PNG/EXR export;
//! - [`difference`]: the CPU-vs-GPU per-pixel difference view;
//! - [`paint`]: the egui paint callback that draws the escape-time image with the GPU.
//!
//! eframe (and egui) live only here, as docs/design.md lays out; the rest of the crate never sees them.

pub mod app;
pub mod difference;
pub mod export;
pub mod layers_panel;
pub mod nav;
pub mod newton;
pub mod paint;
pub mod palette_editor;
pub mod worker;

pub use app::{Counters, ViewMode, ViewerApp, ViewerOptions};

/// Why the viewer could not run.
#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    /// The scene could not be opened.
    #[error("{0}")]
    Scene(String),
    /// The window system or renderer failed.
    #[error("cannot open the viewer window: {0}")]
    Window(String),
}

/// Opens the viewer window and runs until it is closed (or, with a screenshot path, until
/// the screenshot is written). `size` is the window's inner size in points.
pub fn run(options: ViewerOptions, size: Option<[f32; 2]>) -> Result<(), ViewerError> {
    let mut viewport = eframe::egui::ViewportBuilder::default().with_title("deepfield");
    viewport = viewport.with_inner_size(size.unwrap_or([1280.0, 800.0])).with_drag_and_drop(true);
    let native = eframe::NativeOptions {
        viewport,
        renderer: eframe::Renderer::Wgpu,
        // A screenshot run leaves the user's saved session alone.
        persist_window: options.screenshot.is_none(),
        ..Default::default()
    };
    let screenshot = options.screenshot.clone();
    eframe::run_native(
        "deepfield",
        native,
        Box::new(|cc| match ViewerApp::new(cc, options) {
            Ok(app) => Ok(Box::new(app)),
            Err(e) => Err(e.into()),
        }),
    )
    .map_err(|e| ViewerError::Window(e.to_string()))?;
    if let Some(path) = screenshot
        && !path.exists()
    {
        return Err(ViewerError::Window(format!("no screenshot was written to {}", path.display())));
    }
    Ok(())
}
