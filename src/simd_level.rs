//! Which vector instruction set the kernels run with: the best one this CPU has, or one
//! forced by the user (`--simd`) so that every path the program can take on some CPU can be
//! run, timed and tested on this one.
//!
//! Three families of kernels depend on it: the direct f64 kernels (`field::simd`, generic
//! over pulp's [`pulp::Simd`]), the perturbation engine's single-step lanes
//! (`orbit::perturb::lanes`, generic over the same trait, with one small load routine per
//! instruction set), and colouring's arithmetic passes (transfers, distance styles, palette
//! coordinates: plain loops compiled under the level's features by pulp's dispatch, which
//! the compiler vectorises). Every level gives the same bits: the kernels do the same IEEE
//! operations in the same order whatever the vector width, which the tests check by running
//! every level the CPU has against the scalar one. So the level is a property of a run, never
//! of a scene: it is not stored in scene files, only reported (`--stats`, the EXR header).

use std::fmt;

/// An instruction set the kernels can run with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SimdLevel {
    /// No vector unit: one f64 at a time (the perturbation engine keeps two samples in
    /// flight instead).
    Scalar,
    /// x86-64 AVX2 with FMA (pulp's x86-64-v3): 4 f64 lanes.
    Avx2,
    /// x86-64 AVX-512 F/BW/CD/DQ/VL (pulp's x86-64-v4): 8 f64 lanes.
    Avx512,
    /// aarch64 NEON: 2 f64 lanes.
    Neon,
}

/// What the user requested: the best available level, or one in particular.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SimdChoice {
    /// The best level this CPU has.
    #[default]
    Auto,
    /// This level, refused where the CPU lacks it.
    Level(SimdLevel),
}

/// A level was requested that this CPU (or this build's target) cannot run.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("--simd {asked}: {why}; this CPU runs {available}")]
pub struct SimdUnavailable {
    /// The level requested (its flag spelling).
    pub asked: &'static str,
    /// Why it cannot run.
    pub why: &'static str,
    /// The levels that can run here, comma-separated.
    pub available: String,
}

/// The flag spellings `--simd` accepts, `auto` first.
pub const CHOICES: [&str; 5] = ["auto", "scalar", "avx2", "avx512", "neon"];

impl SimdLevel {
    /// Every level, narrowest first.
    pub const ALL: [SimdLevel; 4] = [SimdLevel::Scalar, SimdLevel::Neon, SimdLevel::Avx2, SimdLevel::Avx512];

    /// The flag spelling (`scalar`, `avx2`, `avx512`, `neon`).
    pub fn name(self) -> &'static str {
        match self {
            SimdLevel::Scalar => "scalar",
            SimdLevel::Avx2 => "avx2",
            SimdLevel::Avx512 => "avx512",
            SimdLevel::Neon => "neon",
        }
    }

    /// A description for statistics, e.g. "AVX2+FMA (4 f64 lanes)".
    pub fn describe(self) -> &'static str {
        match self {
            SimdLevel::Scalar => "scalar (1 f64 lane)",
            SimdLevel::Avx2 => "AVX2+FMA (4 f64 lanes)",
            SimdLevel::Avx512 => "AVX-512 (8 f64 lanes)",
            SimdLevel::Neon => "NEON (2 f64 lanes)",
        }
    }

    /// f64 values per vector.
    pub fn f64_lanes(self) -> usize {
        match self {
            SimdLevel::Scalar => 1,
            SimdLevel::Neon => 2,
            SimdLevel::Avx2 => 4,
            SimdLevel::Avx512 => 8,
        }
    }

    /// Why this CPU cannot run the level, or None when it can.
    fn missing(self) -> Option<&'static str> {
        match self {
            SimdLevel::Scalar => None,
            #[cfg(target_arch = "x86_64")]
            SimdLevel::Avx2 => pulp::x86::V3::try_new().is_none().then_some("this CPU lacks AVX2, FMA or BMI2"),
            #[cfg(target_arch = "x86_64")]
            SimdLevel::Avx512 => {
                pulp::x86::V4::try_new().is_none().then_some("this CPU lacks AVX-512 (F, BW, CD, DQ and VL are needed)")
            }
            #[cfg(not(target_arch = "x86_64"))]
            SimdLevel::Avx2 | SimdLevel::Avx512 => {
                Some("it is an x86-64 instruction set and this is not an x86-64 build")
            }
            #[cfg(target_arch = "aarch64")]
            SimdLevel::Neon => pulp::aarch64::Neon::try_new().is_none().then_some("this CPU lacks NEON"),
            #[cfg(not(target_arch = "aarch64"))]
            SimdLevel::Neon => Some("it is an aarch64 instruction set and this is not an aarch64 build"),
        }
    }

    /// True when this CPU runs the level.
    pub fn available(self) -> bool {
        self.missing().is_none()
    }

    /// Every level this CPU runs, narrowest first (scalar always).
    pub fn usable() -> Vec<SimdLevel> {
        SimdLevel::ALL.into_iter().filter(|l| l.available()).collect()
    }

    /// The widest level this CPU runs.
    pub fn detect() -> SimdLevel {
        SimdLevel::usable().into_iter().max_by_key(|l| l.f64_lanes()).unwrap_or(SimdLevel::Scalar)
    }

    /// Replaces every value of `v` by `f` of it, in a loop compiled under this level's
    /// features (pulp's dispatch), which the compiler vectorises where `f` is branch-free
    /// arithmetic: the run-wise form of colouring's per-sample functions. `f` is inlined
    /// into the loop, so every level computes the same operations in the same order.
    #[inline(always)]
    pub fn map(self, v: &mut [f64], f: impl Fn(f64) -> f64) {
        self.arch().dispatch(
            #[inline(always)]
            || {
                for x in v.iter_mut() {
                    *x = f(*x);
                }
            },
        )
    }

    /// pulp's dispatcher for this level (scalar if the CPU cannot run it; levels are checked
    /// where they are chosen, [`SimdChoice::resolve`]).
    pub(crate) fn arch(self) -> pulp::Arch {
        match self {
            #[cfg(target_arch = "x86_64")]
            SimdLevel::Avx2 => pulp::x86::V3::try_new().map_or(pulp::Arch::Scalar, pulp::Arch::V3),
            #[cfg(target_arch = "x86_64")]
            SimdLevel::Avx512 => pulp::x86::V4::try_new().map_or(pulp::Arch::Scalar, pulp::Arch::V4),
            #[cfg(target_arch = "aarch64")]
            SimdLevel::Neon => pulp::aarch64::Neon::try_new().map_or(pulp::Arch::Scalar, pulp::Arch::Neon),
            _ => pulp::Arch::Scalar,
        }
    }
}

/// A computation over lanes of f64 compiled for one level at that level's width: two
/// vectors' worth of lanes, `L` (the hybrids' kernels, whose tables of per-family functions
/// are compiled once per level, not once per width).
pub trait LaneJob {
    /// What the job returns.
    type Output;
    /// Runs the job under `simd`'s target features with `L` lanes.
    fn run<S: pulp::Simd, const L: usize>(self, simd: S) -> Self::Output;
}

impl SimdLevel {
    /// Runs `job` under this level's target features with two vectors' worth of lanes
    /// (AVX2: 8, AVX-512: 16, NEON: 4); gives the job back at the scalar level, or where
    /// this CPU lacks the level.
    pub fn run_lanes<J: LaneJob>(self, job: J) -> Result<J::Output, J> {
        /// The job at width `L`, as pulp's dispatch takes it.
        struct On<J, const L: usize>(J);
        impl<J: LaneJob, const L: usize> pulp::WithSimd for On<J, L> {
            type Output = J::Output;
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, simd: S) -> J::Output {
                self.0.run::<S, L>(simd)
            }
        }
        #[cfg(target_arch = "x86_64")]
        match self {
            SimdLevel::Avx2 => {
                if let Some(simd) = pulp::x86::V3::try_new() {
                    return Ok(pulp::Simd::vectorize(simd, On::<J, 8>(job)));
                }
            }
            SimdLevel::Avx512 => {
                if let Some(simd) = pulp::x86::V4::try_new() {
                    return Ok(pulp::Simd::vectorize(simd, On::<J, 16>(job)));
                }
            }
            _ => {}
        }
        #[cfg(target_arch = "aarch64")]
        if self == SimdLevel::Neon
            && let Some(simd) = pulp::aarch64::Neon::try_new()
        {
            return Ok(pulp::Simd::vectorize(simd, On::<J, 4>(job)));
        }
        Err(job)
    }
}

impl Default for SimdLevel {
    /// The widest level this CPU runs.
    fn default() -> Self {
        SimdLevel::detect()
    }
}

impl fmt::Display for SimdLevel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl SimdChoice {
    /// Parses a flag spelling ([`CHOICES`]).
    pub fn parse(text: &str) -> Option<SimdChoice> {
        if text == "auto" {
            return Some(SimdChoice::Auto);
        }
        SimdLevel::ALL.into_iter().find(|l| l.name() == text).map(SimdChoice::Level)
    }

    /// The level to run: the best one for `Auto`, else the one requested if this CPU runs it.
    pub fn resolve(self) -> Result<SimdLevel, SimdUnavailable> {
        match self {
            SimdChoice::Auto => Ok(SimdLevel::detect()),
            SimdChoice::Level(l) => match l.missing() {
                None => Ok(l),
                Some(why) => Err(SimdUnavailable {
                    asked: l.name(),
                    why,
                    available: SimdLevel::usable().iter().map(|l| l.name()).collect::<Vec<_>>().join(", "),
                }),
            },
        }
    }
}

/// Checks for run-wise kernels written as plain loops under pulp's dispatch.
#[cfg(test)]
pub(crate) mod testing {
    use super::SimdLevel;

    /// `n` numbers uniform in [0, 1), pseudo-random from `seed` (a fixed generator: every
    /// run and platform sees the same).
    pub(crate) fn uniform(seed: u64, n: usize) -> Vec<f64> {
        let mut state = seed;
        (0..n)
            .map(|_| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64
            })
            .collect()
    }

    /// `all` over `inputs` at every level this CPU runs gives `one` of each input, bit for bit.
    pub(crate) fn every_level_matches(
        inputs: &[f64],
        one: impl Fn(f64) -> f64,
        all: impl Fn(SimdLevel, &mut [f64]),
        what: &str,
    ) {
        let want: Vec<u64> = inputs.iter().map(|&x| one(x).to_bits()).collect();
        for level in SimdLevel::usable() {
            let mut v = inputs.to_vec();
            all(level, &mut v);
            assert_eq!(v.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), want, "{what} {level}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scalar_is_always_available_and_auto_picks_the_widest() {
        assert!(SimdLevel::Scalar.available());
        let best = SimdChoice::Auto.resolve().expect("auto always resolves");
        assert!(SimdLevel::usable().iter().all(|l| l.f64_lanes() <= best.f64_lanes()));
        for l in SimdLevel::usable() {
            assert_eq!(SimdChoice::Level(l).resolve(), Ok(l));
        }
    }

    #[test]
    fn a_level_the_cpu_lacks_is_refused_with_a_reason() {
        // NEON and the x86 levels cannot both be available in one build.
        let foreign = if cfg!(target_arch = "aarch64") { SimdLevel::Avx2 } else { SimdLevel::Neon };
        let e = SimdChoice::Level(foreign).resolve().expect_err("not this architecture");
        assert_eq!(e.asked, foreign.name());
        assert!(e.to_string().contains("scalar"), "{e}");
    }

    /// The levels the tests loop over are the ones the CPU really has: on an x86-64 CPU with
    /// AVX2, FMA and BMI2 the AVX2 paths are among them (so they are held to the scalar bits
    /// here, not silently skipped), and AVX-512 exactly when the CPU has it.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn usable_levels_follow_the_cpu_features() {
        let usable = SimdLevel::usable();
        assert_eq!(usable[0], SimdLevel::Scalar);
        use std::arch::is_x86_feature_detected as has;
        // pulp's x86-64-v3 set: AVX2, FMA, BMI1/2, LZCNT, POPCNT and the SSE levels below.
        let avx2 = has!("avx2") && has!("fma") && has!("bmi1") && has!("bmi2") && has!("lzcnt") && has!("popcnt");
        assert_eq!(usable.contains(&SimdLevel::Avx2), avx2, "{usable:?}");
        let avx512 = has!("avx512f") && has!("avx512bw") && has!("avx512dq") && has!("avx512vl") && has!("avx512cd");
        assert_eq!(usable.contains(&SimdLevel::Avx512), avx512, "{usable:?}");
    }

    #[test]
    fn every_spelling_parses() {
        for c in CHOICES {
            assert!(SimdChoice::parse(c).is_some(), "{c}");
        }
        assert_eq!(SimdChoice::parse("sse"), None);
    }
}
