//! `deepfield view`: opens the explorer window (the library's `viewer` module).

use anyhow::anyhow;
#[cfg(feature = "viewer")]
use std::sync::Arc;

#[cfg(feature = "viewer")]
use deepfield::orbit::saved::SavedReferences;
#[cfg(feature = "viewer")]
use deepfield::render::{self, Options};
#[cfg(feature = "viewer")]
use deepfield::scene::Scene;
#[cfg(feature = "viewer")]
use deepfield::viewer::{self, ViewerError, ViewerOptions};

use super::Failure;
use super::args::ViewArgs;

/// Runs `deepfield view`.
#[cfg(feature = "viewer")]
pub fn run(args: ViewArgs) -> Result<(), Failure> {
    // Bad input is reported (exit 2, file:line:column) before any window opens.
    let scene = match &args.scene {
        Some(p) => {
            let (origin, text, base) = super::scene::read_source(p)?;
            Some(super::scene::load_text(&origin, &text, &base, |_| {})?)
        }
        None => None,
    };
    let references = match (&args.reference, &scene) {
        (Some(path), Some(scene)) => Some(Arc::new(reference_for(path, scene)?)),
        _ => None,
    };
    let options = ViewerOptions { scene: args.scene, screenshot: args.screenshot, inline: false, references };
    let size = args.size.map(|(w, h)| [w as f32, h as f32]);
    match viewer::run(options, size) {
        Ok(()) => Ok(()),
        Err(ViewerError::Scene(e)) => Err(Failure::Input(anyhow!(e))),
        Err(e) => Err(Failure::Runtime(anyhow!(e))),
    }
}

/// The reference file at `path`, checked against `scene` as the scene file frames it.
#[cfg(feature = "viewer")]
fn reference_for(path: &std::path::Path, scene: &Scene) -> Result<SavedReferences, Failure> {
    let saved = super::reference::read(path)?;
    let plan = super::engine_plan(scene)?;
    let Some(spec) = render::deep_spec(scene, &plan, &Options::default()).1 else {
        return Err(Failure::Input(anyhow!(
            "{}: the scene does not use reference orbits ({} engine)",
            path.display(),
            plan.name
        )));
    };
    saved.serves(&spec).map_err(|e| Failure::Input(anyhow!("{}: {e}", path.display())))?;
    Ok(saved)
}

/// In a headless build (`--no-default-features`) the subcommand exists, so scripts get a
/// reason rather than "unrecognised subcommand", and refuses.
#[cfg(not(feature = "viewer"))]
pub fn run(_args: ViewArgs) -> Result<(), Failure> {
    Err(Failure::Runtime(anyhow!(
        "this deepfield was built without the `viewer` feature (rebuild with default features for the explorer)"
    )))
}
