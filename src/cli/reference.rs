//! `deepfield reference`: a deep view's reference orbits computed once and written to a file;
//! and reading such a file for `render --reference`.

use std::path::Path;

use anyhow::anyhow;
use deepfield::orbit::saved::{SavedReferences, key_of};
use deepfield::render::{self, Options};

use super::Failure;
use super::args::ReferenceArgs;

/// Runs `deepfield reference`.
pub fn run(args: ReferenceArgs) -> Result<(), Failure> {
    let cancel = super::terminal::install_ctrlc();
    let scene = super::scene::load(&args.scene)?;
    if !scene.formula.is_quadratic() {
        return Err(Failure::Input(anyhow!(
            "reference files hold z^2 + c's reference orbits; this scene's formula is {} (its renders compute their own)",
            scene.formula
        )));
    }
    let plan = super::engine_plan(&scene)?;
    let simd = super::simd_level(args.simd.as_deref())?;
    let options = Options { simd, dense_orbit: args.dense_orbit, ..Options::default() };
    let (_, spec) = render::deep_spec(&scene, &plan, &options);
    let Some(spec) = spec else {
        return Err(Failure::Input(anyhow!(
            "the scene runs the {} engine, which uses no reference orbit: there is nothing to write",
            plan.name
        )));
    };
    // Opened first: an unwritable path fails before the work.
    let opened = deepfield::io::AtomicFile::create(&args.output).map_err(Failure::input)?;
    let bar = super::terminal::bar(args.quiet, spec.max_iter as u64);
    let progress = |done: u64, _total: u64| {
        if let Some(b) = &bar {
            b.set_position(done);
        }
    };
    let refs = deepfield::orbit::references(&spec, &progress, &cancel).map_err(|_| Failure::Cancelled)?;
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let saved = SavedReferences { key: key_of(&spec), refs: std::sync::Arc::new(refs) };
    super::commit_bytes(opened, &saved.encode())
}

/// Reads a reference file (bad input, with the path, when it is not one).
pub fn read(path: &Path) -> Result<SavedReferences, Failure> {
    let bytes = std::fs::read(path).map_err(|e| Failure::Input(anyhow!("{}: {e}", path.display())))?;
    SavedReferences::decode(&bytes).map_err(|e| Failure::Input(anyhow!("{}: {e}", path.display())))
}
