//! `deepfield view`: opens the explorer window (the library's `viewer` module).

use anyhow::anyhow;
#[cfg(feature = "viewer")]
use deepfield::viewer::{self, ViewerError, ViewerOptions};

use super::Failure;
use super::args::ViewArgs;

/// Runs `deepfield view`.
#[cfg(feature = "viewer")]
pub fn run(args: ViewArgs) -> Result<(), Failure> {
    // Bad input is reported (exit 2, file:line:column) before any window opens.
    if let Some(p) = &args.scene {
        let (origin, text, base) = super::scene::read_source(p)?;
        super::scene::load_text(&origin, &text, &base, |_| {})?;
    }
    let options = ViewerOptions { scene: args.scene, screenshot: args.screenshot, inline: false };
    let size = args.size.map(|(w, h)| [w as f32, h as f32]);
    match viewer::run(options, size) {
        Ok(()) => Ok(()),
        Err(ViewerError::Scene(e)) => Err(Failure::Input(anyhow!(e))),
        Err(e) => Err(Failure::Runtime(anyhow!(e))),
    }
}

/// In a headless build (`--no-default-features`) the subcommand exists, so scripts get a
/// reason rather than "unrecognised subcommand", and refuses.
#[cfg(not(feature = "viewer"))]
pub fn run(_args: ViewArgs) -> Result<(), Failure> {
    Err(Failure::Runtime(anyhow!(
        "this deepfield was built without the `viewer` feature (rebuild with default features for the explorer)"
    )))
}
