//! What a built engine tells its callers: the settings it was built for, its reference
//! orbits and tables (sizes, timings, the primary table for statistics) and interior
//! detection's decision. The loop's state itself stays private to the engine; renders,
//! the viewer's engine cache and `--stats` read it through these methods.

use std::sync::Arc;

use super::Perturbation;
use crate::num::FloatExp;
use crate::orbit::DeepSpec;
use crate::orbit::bla::BlaTable;
use crate::orbit::interior::{Check, Decision};
use crate::orbit::reference::Reference;

impl Perturbation {
    /// Whether this engine was built for the settings of `spec` that the loop depends on
    /// (iteration limit, escape radius, derivative, Mandelbrot or Julia, interior
    /// detection), so that a render of `spec`'s view may reuse it.
    pub fn built_for(&self, spec: &DeepSpec) -> bool {
        (self.max_iter, self.escape2, self.derivative, self.mandelbrot, self.interior_asked)
            == (
                spec.max_iter,
                spec.escape_radius * spec.escape_radius,
                spec.derivative,
                spec.julia.is_none(),
                spec.interior,
            )
    }

    /// The reference orbits ([primary, orbit of 0 after rebasing]; Mandelbrot has one),
    /// shared by every engine derived from this one.
    pub fn references(&self) -> &Arc<Vec<Reference>> {
        &self.refs
    }

    /// Whether `other` iterates against the very same reference orbits (not a copy).
    pub fn shares_references(&self, other: &Perturbation) -> bool {
        Arc::ptr_eq(&self.refs, &other.refs)
    }

    /// The largest |δc| (plane units) the tables were built for.
    pub fn extent(&self) -> FloatExp {
        self.extent
    }

    /// Where the raster's centre lies from the reference point (plane units): zero for an
    /// engine built for its own view.
    pub fn origin(&self) -> [FloatExp; 2] {
        self.origin
    }

    /// Seconds the reference orbit(s) took.
    pub fn orbit_seconds(&self) -> f64 {
        self.orbit_seconds
    }

    /// Seconds the BLA tables took.
    pub fn tables_seconds(&self) -> f64 {
        self.tables_seconds
    }

    /// The primary reference's BLA table for f64 deltas (None: BLA off).
    pub fn primary_table(&self) -> Option<&BlaTable<f64>> {
        self.bla_f64[0].as_ref()
    }

    /// The view's series (see [`crate::orbit::Series`]): its degree and the iteration it
    /// reaches; None where the BLA skip reaches as far or BLA is off.
    pub fn series_reach(&self) -> Option<(usize, u32)> {
        self.series.as_ref().map(|s| (s.degree(), s.far.m))
    }

    /// What was decided about interior detection, and why.
    pub fn interior_decision(&self) -> Decision {
        self.interior_decision
    }

    /// Interior detection's check (None: off).
    pub fn interior_check(&self) -> Option<Check> {
        self.interior
    }

    /// Bytes the reference orbits and BLA tables take.
    pub fn bytes(&self) -> (usize, usize) {
        let refs = self.refs.iter().map(Reference::bytes).sum();
        let bla = self.bla_fe.iter().flatten().map(BlaTable::bytes).sum::<usize>()
            + self.bla_f64.iter().flatten().map(BlaTable::bytes).sum::<usize>();
        (refs, bla)
    }

    /// Whether a sample may have the steps of whole blocks built during the render (the
    /// reference goes on past BLA's tree): a render then watches their build's progress.
    /// (The f64 tables are there wherever BLA is, and the FloatExp ones share their blocks.)
    pub fn builds_blocks(&self) -> bool {
        self.bla_f64.iter().flatten().any(BlaTable::has_blocks)
    }

    /// While the steps of whole blocks are being built, the iterations folded so far and of
    /// how many (one build for every table of an orbit).
    pub fn blocks_progress(&self) -> Option<(u64, u64)> {
        self.bla_f64.iter().flatten().find_map(BlaTable::blocks_progress)
    }

    /// Precision of the reference orbit, in bits.
    pub fn bits(&self) -> u64 {
        self.refs[0].bits()
    }

    /// True when the primary reference escaped before the iteration limit (samples that
    /// outlive it continue by rebasing).
    pub fn reference_escaped(&self) -> bool {
        self.refs[0].escaped()
    }

    /// Length of the primary reference (its last index).
    pub fn reference_length(&self) -> u32 {
        self.refs[0].end()
    }

    /// Iterations of the primary reference stored densely (its last dense index; the rest,
    /// up to [`Perturbation::reference_length`], is packed).
    pub fn reference_dense(&self) -> u32 {
        self.refs[0].last()
    }
}
