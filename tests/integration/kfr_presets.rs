//! Kalles Fraktaler's formula presets (`formulas_*.kfr`, shipped with KF 2.15): each
//! converts to a scene of the family it names or is refused with KF's name for it, and
//! none panics. A handful are fixtures (`tests/fixtures/kfr/`); the whole set is swept when
//! a folder of them is at hand (`KF_FILES`, else `/work/shared/kf-files`), and skipped
//! otherwise.

use std::path::{Path, PathBuf};

use deepfield::formula::Formula;
use deepfield::scene::kfr::{kf_type_name, kfr_to_toml};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/kfr").join(name)
}

/// The `[formula]` a preset converts to, as `kind` and `power`, or the error's message.
fn convert(path: &Path) -> Result<(String, Option<i64>), String> {
    let text = std::fs::read_to_string(path).unwrap();
    let toml_text = kfr_to_toml(&path.display().to_string(), &text).map_err(|e| e.message)?;
    let t: toml::Table = toml_text.parse().unwrap_or_else(|e| panic!("{}: {e}\n{toml_text}", path.display()));
    let kind = t["formula"]["kind"].as_str().unwrap().to_string();
    let power = t["formula"].get("power").and_then(|p| p.as_integer());
    Formula::parse(&kind, power.map(|p| p as u32)).unwrap_or_else(|e| panic!("{}: {kind}: {e}", path.display()));
    assert_eq!(t["view"]["zoom"].as_str(), Some("1"), "{}: KF's opening view", path.display());
    Ok((kind, power))
}

#[test]
fn preset_fixtures_convert_or_are_refused_by_name() {
    let ok = |name: &str| convert(&fixture(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    let no = |name: &str| convert(&fixture(name)).expect_err(name);
    assert_eq!(ok("formulas_00-2-Mandelbrot.kfr"), ("mandelbrot".into(), None));
    assert_eq!(ok("formulas_01-3-Burning-Ship.kfr"), ("burning-ship".into(), Some(3)));
    assert_eq!(ok("formulas_02-2-Buffalo.kfr"), ("buffalo".into(), None));
    assert_eq!(ok("formulas_10-3-Cubic-Quasi-Burning-Ship.kfr"), ("cubic-quasi-burning-ship".into(), None));
    // The preset's hybrid is conj(z)³, not KF's built-in Mandelbar³ (-Re z³ + i Im z³).
    let e = no("formulas_04-3-Mandelbar.kfr");
    assert!(e.contains("none of deepfield's families") && e.contains("Mandelbar"), "{e}");
    // TheRedshiftRider 1's line z^2 + z^3 is a z² + z³ with a = 1.
    assert_eq!(ok("formulas_42-3-TheRedshiftRider-1.kfr"), ("redshift-rider-1".into(), None));
    // HPDZ Buffalo's line (|x| + i|y|)^2 - (|x| + i|y|) is W² - W with W folded.
    assert_eq!(ok("formulas_41-2-HPDZ-Buffalo.kfr"), ("hpdz-buffalo".into(), None));
    // A product of z² and (|x| + i|y|)²: SimonBrot 4th and Mothbrot 2×2 are one map.
    assert_eq!(ok("formulas_58-4-Mothbrot-4th-2x2-aka-Simonbrot-4th.kfr").0, "mothbrot-2x2");
}

#[test]
fn every_kf_preset_converts_or_is_refused_by_name() {
    let dir = std::env::var_os("KF_FILES").map_or_else(|| PathBuf::from("/work/shared/kf-files"), PathBuf::from);
    let Ok(entries) = std::fs::read_dir(&dir) else {
        eprintln!("skipped: no folder of KF presets at {}", dir.display());
        return;
    };
    let mut files: Vec<PathBuf> = entries
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name().unwrap().to_string_lossy().starts_with("formulas_")
                && p.extension().is_some_and(|x| x == "kfr")
        })
        .collect();
    files.sort();
    let (mut converted, mut refused) = (0, 0);
    for path in &files {
        let text = std::fs::read_to_string(path).unwrap();
        let kf_type: u64 =
            text.lines().find_map(|l| l.trim().strip_prefix("FractalType:")).map_or(0, |v| v.trim().parse().unwrap());
        match convert(path) {
            Ok(_) => converted += 1,
            Err(message) => {
                refused += 1;
                let name = kf_type_name(kf_type).unwrap_or_else(|| panic!("{}: FractalType {kf_type}", path.display()));
                eprintln!("{}: {message}", path.file_name().unwrap().to_string_lossy());
                assert!(message.contains(name), "{}: the refusal names no formula ({name}): {message}", path.display());
            }
        }
    }
    eprintln!("{} presets: {converted} convert, {refused} refused", files.len());
    assert_eq!(converted + refused, files.len());
}
