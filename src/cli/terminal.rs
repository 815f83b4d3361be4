//! What a run shows and hears on the terminal, for every command that renders or computes
//! a reference: the progress bar (on a terminal only) and the Ctrl-C flag.

use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use deepfield::render;
use indicatif::{ProgressBar, ProgressStyle};

/// Installs the Ctrl-C handler: the flag it sets is polled by the kernels. Failing to
/// install it only loses Ctrl-C handling.
pub fn install_ctrlc() -> Arc<AtomicBool> {
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    let _ = ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed));
    cancel
}

/// Shows render progress on the bar, if there is one.
pub fn show(bar: &Option<ProgressBar>, p: render::Progress) {
    if let Some(b) = bar {
        match p {
            render::Progress::Reference { done, total } => b.set_message(format!("{} {done}/{total}", p.name())),
            render::Progress::Blocks { done, total } => {
                b.set_message(format!("{} {:.0}%", p.name(), 100.0 * done as f64 / total as f64));
            }
            render::Progress::Rows(rows) => {
                b.set_message("");
                b.set_position(rows);
            }
        }
    }
}

/// A progress bar over `rows` output rows, on a terminal only.
pub fn bar(quiet: bool, rows: u64) -> Option<ProgressBar> {
    if quiet || !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = ProgressBar::new(rows);
    let style =
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} rows, ETA {eta} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    Some(bar)
}
