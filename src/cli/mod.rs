//! The command line: what the user typed ([`args`]), turned into scenes and runs.
//!
//! Two layers, as in ripgrep: [`args`] is pure parsing and validation of flags (no I/O);
//! [`render`] builds the scene and the output writers from them and runs the library.
//! Errors carry an exit code: 2 for bad input of any kind (flags, scene files, missing
//! files, unwritable outputs, a view the engines cannot address), 1 for failures while
//! working, 130 for a cancelled run. `main` prints `error: ` and the chain of causes
//! ([`describe`]) and never panics on input.

mod args;
mod compare;
mod find;
mod frames;
mod palettes;
mod recolor;
mod reference;
mod render;
mod scene;
mod sheet;
mod terminal;
mod view;
mod zoom;

use std::process::ExitCode;

use clap::Parser;

/// A failure with the exit code it maps to.
#[derive(Debug)]
pub enum Failure {
    /// Bad input: exit code 2.
    Input(anyhow::Error),
    /// Failure while working: exit code 1.
    Runtime(anyhow::Error),
    /// Cancelled by the user: exit code 130.
    Cancelled,
}

impl From<deepfield::render::RenderError> for Failure {
    /// Cancelled stays cancelled; a bad scene, engine, reference file or rows are bad
    /// input (exit 2); anything else failed while working.
    fn from(e: deepfield::render::RenderError) -> Self {
        match e {
            deepfield::render::RenderError::Cancelled => Failure::Cancelled,
            e if e.is_bad_input() => Failure::Input(e.into()),
            e => Failure::Runtime(e.into()),
        }
    }
}

/// The engine that renders `scene` ([`deepfield::render::engine::plan`]). A view no engine
/// (or not the forced one) can address is bad input; the library's message names the scene
/// setting, and this adds the flag that sets it.
fn engine_plan(scene: &deepfield::scene::Scene) -> Result<deepfield::render::engine::EnginePlan, Failure> {
    deepfield::render::engine::plan(scene)
        .map_err(|e| Failure::Input(anyhow::anyhow!("{e} (on the command line: --engine)")))
}

impl Failure {
    fn input(e: impl Into<anyhow::Error>) -> Self {
        Failure::Input(e.into())
    }
}

/// Writes `text` into an atomic file opened earlier (so that an unwritable path failed
/// before any work) and puts the file in place.
fn commit_text(
    opened: (deepfield::io::AtomicFile, std::io::BufWriter<std::fs::File>),
    text: &str,
) -> Result<(), Failure> {
    commit_bytes(opened, text.as_bytes())
}

/// [`commit_text`] for bytes.
fn commit_bytes(
    (file, mut w): (deepfield::io::AtomicFile, std::io::BufWriter<std::fs::File>),
    bytes: &[u8],
) -> Result<(), Failure> {
    use std::io::Write as _;
    w.write_all(bytes).map_err(|e| Failure::Runtime(e.into()))?;
    let path = file.dest().display().to_string();
    drop(w.into_inner().map_err(|e| Failure::Runtime(anyhow::anyhow!("{path}: {}", e.error())))?);
    file.commit_written().map_err(|e| Failure::Runtime(e.into()))
}

/// The instruction set `--simd` asks for (none: the widest this CPU has); a level the CPU
/// lacks is bad input.
fn simd_level(flag: Option<&str>) -> Result<deepfield::simd_level::SimdLevel, Failure> {
    use deepfield::simd_level::SimdChoice;
    // clap accepted only the spellings `parse` knows.
    let choice = flag.and_then(SimdChoice::parse).unwrap_or_default();
    choice.resolve().map_err(Failure::input)
}

/// `deepfield formulas`: every family with its powers, Kalles Fraktaler type and map.
fn formulas_table() -> String {
    use deepfield::formula::kind::KINDS;
    let mut out =
        String::from("name                                       powers  KF type  map (at the smallest power)\n");
    for k in KINDS {
        let powers = if k.min_power == k.max_power {
            k.min_power.to_string()
        } else {
            format!("{}-{}", k.min_power, k.max_power)
        };
        out.push_str(&format!("{:<42} {:<7} {:<8} {}\n", k.name, powers, k.kf_type, k.kind.definition(k.min_power)));
    }
    out.push_str(
        "\njulia: z^2 + c's Julia set (--julia-c RE,IM); --julia-c gives any family its Julia form.\n\
         Hybrids: phases joined by ',', each NAME or NAME^P, iteration n using phase n mod their number\n\
         (burning-ship,mandelbrot^3).\n\
         a: the coefficient of the redshift-rider families (--formula-a RE,IM; default 1,0).\n",
    );
    out
}

/// Entry point of the binary.
pub fn main() -> ExitCode {
    let cli = match args::Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { 2 } else { 0 });
        }
    };
    let result = match cli.command {
        args::Command::Render(r) => render::run(*r),
        args::Command::Compare(c) => compare::run(*c),
        args::Command::Recolor(r) => recolor::run(*r),
        args::Command::Sheet(s) => sheet::run(*s),
        args::Command::Palettes(p) => palettes::run(p),
        args::Command::Formulas => {
            use std::io::Write as _;
            std::io::stdout().lock().write_all(formulas_table().as_bytes()).map_err(|e| Failure::Runtime(e.into()))
        }
        args::Command::View(v) => view::run(v),
        args::Command::Find(f) => find::run(*f),
        args::Command::Reference(r) => reference::run(*r),
        args::Command::Zoom(z) => zoom::run(*z),
        args::Command::Frames(f) => frames::run(*f),
        args::Command::Assemble(a) => {
            let exr = a.output.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
            let assemble = if exr { deepfield::io::assemble_exr } else { deepfield::io::assemble_png };
            assemble(&a.units, &a.output, &|_, _| {}).map_err(Failure::input)
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Input(e)) => {
            eprintln!("error: {}", describe(&e));
            ExitCode::from(2)
        }
        Err(Failure::Runtime(e)) => {
            if is_broken_pipe(&e) {
                return ExitCode::SUCCESS;
            }
            eprintln!("error: {}", describe(&e));
            ExitCode::from(1)
        }
        Err(Failure::Cancelled) => {
            eprintln!("cancelled; no output was written");
            ExitCode::from(130)
        }
    }
}

/// The error and its causes, joined by `: ` as `{:#}` joins them, each said once: a
/// library error that quotes its cause in its message (as the I/O layer's errors quote the
/// system's) is followed by that cause in the chain.
fn describe(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for link in e.chain() {
        let said = link.to_string();
        if text.ends_with(&said) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&said);
    }
    text
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| c.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A message that quotes its cause is not followed by the cause again.
    #[test]
    fn each_cause_is_said_once() {
        let quoted = anyhow::Error::new(std::io::Error::other("disk full")).context("out.png: disk full");
        assert_eq!(describe(&quoted), "out.png: disk full");
        let plain = anyhow::Error::new(std::io::Error::other("disk full")).context("out.png");
        assert_eq!(describe(&plain), "out.png: disk full");
    }
}
