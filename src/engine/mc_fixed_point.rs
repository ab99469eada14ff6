//! Eq. 2 iterated to self-consistency within the step: an option beside the paper's one-step lag.
//!
//! The multi-contact pass reads the previous step's normal forces (Ghods et al. 2022, App. A, as
//! LIGGGHTS `fix multicontact/halfspace`), so the radius changes and the forces they produce form a
//! loop closed over one step: a larger force changes the radii, which changes the overlaps and with
//! them the next force. Per step that loop is the map F ↦ F(δ + Δ(F)) at the step's geometry, and
//! the lagged scheme takes one application of it per step. Its gain (the dominant eigenvalue of
//! the map's Jacobian, ∂Δ/∂F through the contact stiffness) does not depend on Δt, so a gain beyond
//! ±1 would make the lag run away at every step size. This option applies the map repeatedly at the
//! frozen geometry until the forces stop changing (Picard iteration, optionally under-relaxed), so
//! the step uses the law's self-consistent state, and measures the gain from the ratio of
//! successive corrections. It tells a stop of the lag (the self-consistent state stays in range)
//! from one of the law (it reaches a radius too).
//!
//! Measured on the dense shear reproducers (docs/shear.md, "Runs that stop"): the iteration
//! converges to 1e-6 of the largest force in 11–18 passes with |gain| 0.5–0.8, and the runs stop at
//! the same contact as the lagged ones (standard MC at φ 0.9, μ 1: the same step). Where an Eq. 3
//! decision flips between passes the map is discontinuous and can have no fixed point (a two-cycle,
//! gain −1): such a step keeps its last iterate and is counted ([`FixedPointStats::switched`]).
//!
//! Each repetition starts from the histories the step started with (tangential springs, rolling
//! springs, hysteresis), so a converged step advances them once, as a plain step does; only the
//! closure's own state (previous force and modified radii per contact) is carried from one
//! repetition to the next. One repetition is exactly the lagged step.

use crate::physics::Vec3;

use super::{StepError, World};

/// Settings of the within-step iteration of Eq. 2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixedPoint {
    /// Most force passes per step (≥ 1; 1 is the lagged scheme).
    pub max_passes: u32,
    /// Converged when no contact's normal force changed by more than this fraction of the
    /// step's largest normal force in the last pass.
    pub tolerance: f64,
    /// Under-relaxation ω ∈ (0, 1]: the next pass reads F + ω (F_new − F). ω < 1 turns a loop
    /// gain λ into 1 − ω + ω λ: it damps an oscillating loop (λ < −1) but not a growing one.
    pub relax: f64,
}

impl FixedPoint {
    pub fn new(max_passes: u32, tolerance: f64, relax: f64) -> Result<Self, String> {
        if max_passes == 0 {
            return Err("Eq. 2 fixed point: at least one pass per step".into());
        }
        if !(tolerance > 0.0 && tolerance < 1.0) {
            return Err(format!("Eq. 2 fixed point: tolerance {tolerance} is not in (0, 1)"));
        }
        if !(relax > 0.0 && relax <= 1.0) {
            return Err(format!("Eq. 2 fixed point: relaxation {relax} is not in (0, 1]"));
        }
        Ok(FixedPoint { max_passes, tolerance, relax })
    }
}

/// What the iteration did since the counters were last zeroed.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FixedPointStats {
    /// Steps iterated.
    pub steps: u64,
    /// Force passes over those steps (≥ steps).
    pub passes: u64,
    /// Most passes in one step.
    pub most_passes: u32,
    /// Steps that used all their passes without converging (the last iterate stands).
    pub unconverged: u64,
    /// Unconverged steps whose last pass changed an Eq. 3 decision (a contact switched between
    /// Hertz and the corrected law): the law is discontinuous there and may have no fixed point at
    /// all. The other unconverged steps are mostly a contact opening and closing between passes,
    /// the map's other discontinuity.
    pub switched: u64,
    /// Loop gain estimates (ratio of successive corrections, signed by whether they point the same
    /// way, at the last pass of a step that took three or more): the largest and the smallest.
    pub gain_max: f64,
    pub gain_min: f64,
}

/// Scratch of the iteration, kept between steps (no allocation in the loop once grown).
#[derive(Debug, Default)]
pub(super) struct FpScratch {
    shear: Vec<Vec3>,
    dmax: Vec<f64>,
    roll: Vec<Vec3>,
    wall: Vec<(Vec3, Vec3)>,
    /// The normal forces the last pass read (pairs, then wall contacts).
    read: Vec<f64>,
    /// This pass's and the previous pass's correction F_new − F_read, per contact.
    cur: Vec<f64>,
    last: Vec<f64>,
    /// Per pair end, whether the last pass left it without a radius change (the Eq. 3 switch
    /// back to Hertz, or a particle with a single contact), two bits per pair.
    plain: Vec<u8>,
}

/// Loop gain from two successive corrections: |d_k| / |d_{k−1}|, negative when they point in
/// opposite directions (an oscillating loop).
fn gain(d: &[f64], d_prev: &[f64]) -> Option<f64> {
    let (mut dd, mut pp, mut dp) = (0.0, 0.0, 0.0);
    for (a, b) in d.iter().zip(d_prev) {
        dd += a * a;
        pp += b * b;
        dp += a * b;
    }
    (pp > 0.0).then(|| (dd / pp).sqrt() * if dp < 0.0 { -1.0 } else { 1.0 })
}

impl World {
    /// Multi-contact pass, pairs and walls of a time step, repeated under [`World::mc_fixed_point`]
    /// until Eq. 2 and the forces agree (see the module text).
    pub(super) fn fixed_point_passes(
        &mut self,
        fp: FixedPoint,
        threads: usize,
        batched: bool,
    ) -> Result<(), StepError> {
        let mut s = std::mem::take(&mut self.fp_scratch);
        let r = self.iterate(fp, threads, batched, &mut s);
        self.fp_scratch = s;
        r
    }

    fn iterate(
        &mut self,
        fp: FixedPoint,
        threads: usize,
        batched: bool,
        s: &mut FpScratch,
    ) -> Result<(), StepError> {
        let c = &self.contacts;
        s.shear.clear();
        s.shear.extend(c.pairs.iter().map(|p| p.shear));
        s.dmax.clone_from(&c.pair_dmax);
        s.roll.clone_from(&c.pair_roll);
        s.wall.clear();
        s.wall.extend(c.wc.iter().map(|w| (w.shear, w.roll)));
        s.last.clear();
        let (mut last_gain, mut passes) = (None, 0u32);
        let (res, toggled) = loop {
            self.read_forces(&mut s.read);
            self.multicontact()?;
            self.pair_pass(true, true, threads, batched)?;
            self.wall_pass(true, threads, batched)?;
            passes += 1;
            let mut toggled = 0usize;
            let plain = |d: &[f64; 2]| u8::from(d[0] == 0.0) | u8::from(d[1] == 0.0) << 1;
            let c = &self.contacts;
            if passes == 1 {
                s.plain.clear();
                s.plain.extend(c.pair_dr.iter().map(plain));
            } else {
                for (b, d) in s.plain.iter_mut().zip(&c.pair_dr) {
                    toggled += usize::from(plain(d) != *b);
                    *b = plain(d);
                }
            }
            // This pass's correction per contact, its largest entry against the largest force,
            // and the gain against the previous pass's correction.
            let (mut fmax, mut dmax): (f64, f64) = (0.0, 0.0);
            s.cur.clear();
            for (f, &f0) in self.forces().zip(&s.read) {
                fmax = fmax.max(f);
                dmax = dmax.max((f - f0).abs());
                s.cur.push(f - f0);
            }
            // The first correction holds the step's motion too; from the third on only the loop.
            if passes >= 3 && s.last.len() == s.cur.len() {
                last_gain = gain(&s.cur, &s.last).or(last_gain);
            }
            std::mem::swap(&mut s.cur, &mut s.last);
            let res = if fmax > 0.0 { dmax / fmax } else { 0.0 };
            if res <= fp.tolerance || passes >= fp.max_passes {
                break (res, toggled);
            }
            // The next pass starts from the step's histories, reading the relaxed forces; the
            // wall pass adds into the meshes' totals, so they restart from zero as in the step.
            for m in &mut self.meshes {
                m.force = Vec3::zeros();
            }
            let c = &mut self.contacts;
            for (p, &sh) in c.pairs.iter_mut().zip(&s.shear) {
                p.shear = sh;
            }
            c.pair_dmax.clone_from(&s.dmax);
            c.pair_roll.clone_from(&s.roll);
            for (w, &(sh, ro)) in c.wc.iter_mut().zip(&s.wall) {
                (w.shear, w.roll) = (sh, ro);
            }
            if fp.relax < 1.0 {
                let np = c.pairs.len().min(c.pair_hist.len());
                let pairs = c.pair_hist[..np].iter_mut().map(|h| &mut h.fn_prev);
                for (f, &f0) in pairs.chain(c.wc.iter_mut().map(|w| &mut w.fn_prev)).zip(&s.read) {
                    *f = f0 + fp.relax * (*f - f0);
                }
            }
        };
        let st = &mut self.mc_fp_stats;
        if let Some(g) = last_gain {
            let first = st.gain_max == 0.0 && st.gain_min == 0.0;
            st.gain_max = if first { g } else { st.gain_max.max(g) };
            st.gain_min = if first { g } else { st.gain_min.min(g) };
        }
        st.steps += 1;
        st.passes += u64::from(passes);
        st.most_passes = st.most_passes.max(passes);
        // A step that does not settle keeps its last iterate: the contact law itself stops a run
        // whose iterates grow (its overlap reaches a radius within the passes).
        if res > fp.tolerance {
            st.unconverged += 1;
            st.switched += u64::from(toggled > 0);
        }
        Ok(())
    }

    /// The normal forces the multi-contact pass reads, pairs then wall contacts.
    fn forces(&self) -> impl Iterator<Item = f64> + '_ {
        let c = &self.contacts;
        let np = c.pairs.len().min(c.pair_hist.len());
        c.pair_hist[..np].iter().map(|h| h.fn_prev).chain(c.wc.iter().map(|w| w.fn_prev))
    }

    fn read_forces(&self, out: &mut Vec<f64>) {
        out.clear();
        out.extend(self.forces());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gain_is_the_signed_ratio_of_successive_corrections() {
        assert_eq!(gain(&[0.5, 0.0], &[1.0, 0.0]), Some(0.5));
        assert_eq!(gain(&[-2.0, 0.0], &[1.0, 0.0]), Some(-2.0));
        assert_eq!(gain(&[1.0], &[0.0]), None);
    }

    #[test]
    fn settings_out_of_range_are_refused() {
        assert!(FixedPoint::new(0, 1e-6, 1.0).is_err());
        assert!(FixedPoint::new(10, 0.0, 1.0).is_err());
        assert!(FixedPoint::new(10, 1e-6, 0.0).is_err());
        assert!(FixedPoint::new(10, 1e-6, 1.5).is_err());
        assert!(FixedPoint::new(10, 1e-6, 0.5).is_ok());
    }
}
