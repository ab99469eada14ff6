//! Accuracy budget of the multi-contact pass (`mcAccuracy EPS`): per particle and per step, either
//! the Eq. 2 radius changes are evaluated exactly (and the geometry of that evaluation kept as the
//! particle's reference), or they are formed from this step's loads and the kept geometry, decided
//! by a cheap upper bound on how far that can be from the exact values now.
//!
//! # The bound (Ghods et al. 2022, Eq. 2; Brodu et al. 2015)
//!
//! For one particle with contact points p_k (relative to its centre) and effective loads F_k (the
//! previous step's normal forces, 0 at or below the kernel's loaded threshold), Eq. 2 gives at
//! contact c
//!
//! Δ_c = P · Σ_{k≠c} F_k · h(p_k, p_c),  h = B(n_k, n_c, u_kc) / d_kc,  P = −γ(1+ν)/(2πE)
//!
//! with d_kc = |p_c − p_k|, u_kc = (p_c − p_k)/d_kc, n = −p/|p| and B the curly bracket of Eq. 2
//! (`physics::brodu2015::bracket`). Δ is linear in the loads at fixed points: with the matrix
//! g⁰ = P h(p⁰) of the reference points (`contact_set::influence`, the geometry tolerance's
//! matrix), Δ̃_c = Σ_k F_k g⁰_kc takes this step's loads exactly (n² multiply-adds, the Eq. 3 cap
//! applied to its terms as the kernel does), and
//!
//! Δ_c − Δ̃_c = P Σ_k F_k (h_kc − h⁰_kc),  |Δ_c − Δ̃_c| ≤ |P| Σ_k F_k · max_c |Δh_kc|:
//!
//! only the geometry term (kernel change × load) remains; the loads, which change fastest, no
//! longer spend the budget (an earlier form kept Δ⁰ itself and paid |ΔF_k| · max_c |h⁰_kc| for
//! them: on every bench scene the loads moved more than EPS of the scale per step and nearly every
//! particle-step was recomputed). The parts of the geometry term, for a pair
//! whose points moved by ε = |Δp_k| + |Δp_c| (bounded by ε_k + max_c ε_c), with D = 1 + n_k·u_kc
//! the denominator of B's third term, a = 2ε/ρ_min and b = 2ε/d (|Δn| ≤ a, |Δu| ≤ b: a unit
//! vector x/|x| moves by at most 2|Δx|/|x|):
//!
//! - |B| ≤ B_m(D) = 1 + |3−4ν| + 2|1−2ν|/D (each dot product of unit vectors is ≤ 1 in size);
//! - |ΔB| ≤ 2(a+b) + 2|3−4ν|a + |1−2ν| [ (3a+b)/D_lo + 2(a+b)/D_lo² ] (product and quotient
//!   rules, exact algebra between the two end points, no path needed);
//! - |Δh| ≤ |ΔB|/(d−ε) + B_m · ε/(d(d−ε)), decreasing in d, so the source's smallest reference
//!   chord d_min,k bounds every target;
//! - D at the reference ≥ 1 + (|p_k| − |p_c|)/d_kc ≥ 1 − (ρ_max − |p_k|)/d_min,k (Cauchy–Schwarz),
//!   and now ≥ D_lo = that − a − b.
//!
//! The bound is refused (the particle is recomputed) where its premises fail: a different number
//! of contacts or other parameters, ε beyond a quarter of the chord, D_lo < 1/2 (far from the
//! kernel's guard of B's third term, where B would jump), a reference that the Eq. 3 cap switched
//! back to Hertz, or a term that could reach δ_max = MPR·r now: the cap makes Δ discontinuous.
//! Each term F_k g_kc moves by at most |P| F_k max_c |Δh_kc| from its value with g⁰, so Δ̃ is
//! formed with the cap lowered by the largest such move; if no term trips that lowered cap, no
//! exact term reaches δ_max (an earlier form compared the loose upper bound |P| F_k B_m/(d−ε) of
//! every term with δ_max and refused most particles of the dense scenes).
//!
//! The particle is recomputed when the bound exceeds EPS × its scale, the largest |Δ̃_c| of this
//! step, floored at [`FLOOR_STRAIN`] × r so that barely loaded particles (whose Δ is near zero) do
//! not force work for errors far below anything the forces could show. (Δ̃ is within the bound of
//! Δ, so relative to the exact values' own scale the error is at most EPS/(1 − EPS).)

use crate::physics::contact_set::{influence, radius_changes, radius_changes_with, ContactLoad, McParams};
use crate::physics::Vec3;

use super::{StepError, World};

/// Floor of the budget's scale as a strain of the particle radius: a particle whose radius
/// changes are all below r × 1e-4 is held to EPS × r × 1e-4 (an overlap error far below the
/// Hertz overlaps of a loaded contact, which are of order 1e-2 r in a compressed packing).
pub const FLOOR_STRAIN: f64 = 1e-4;

/// Largest relative move ε/d the bound accepts: beyond it the particle is recomputed.
const MAX_RELATIVE_MOVE: f64 = 0.25;

/// Smallest D = 1 + n_k·u_kc the bound accepts (the kernel drops B's third term below 1e-6).
const MIN_DENOMINATOR: f64 = 0.5;

/// Shadow-check round-off allowance, relative to the particle's scale: the exact sums are
/// floating-point sums of a few terms (relative error about 1e-15 of their sizes).
pub const ROUNDOFF: f64 = 1e-12;

/// `mcAccuracyCheck yes` of a deck: the shadow check runs every this many steps.
pub const DEFAULT_CHECK_EVERY: u64 = 10;

/// The particle-side constants of the bound.
#[derive(Debug, Clone, Copy)]
pub(super) struct BudgetParams {
    /// The particle's kernel parameters (a reference is valid only for the same ones).
    pub(super) params: McParams,
    /// |P| = γ(1+ν)/(2πE).
    pub(super) pref: f64,
    /// Loaded threshold: loads at or below it enter Eq. 2 as 0.
    pub(super) threshold: f64,
}

impl BudgetParams {
    pub(super) fn new(params: McParams) -> Self {
        let nu = params.poisson_ratio;
        let pref =
            (crate::physics::brodu2015::compliance_prefactor(params.gamma, params.youngs_modulus, nu)).abs();
        BudgetParams { params, pref, threshold: params.loaded_threshold() }
    }

    /// The load a contact exerts in Eq. 2 (0 when unloaded, as the kernel).
    #[inline]
    fn load(&self, f: f64) -> f64 {
        if f > self.threshold {
            f
        } else {
            0.0
        }
    }
}

/// The bound of a step and the largest change of a single term (for the Eq. 3 cap), both [m].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Bound {
    pub(super) bound: f64,
    pub(super) term_change: f64,
}

/// Why a particle with two or more contacts was evaluated exactly in a step (the budget's own
/// account of where its work goes, reported beside the recompute fraction).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Why {
    /// No reference yet (the particle's first multi-contact step, or one after a back-off run).
    NoReference = 0,
    /// Another number of contacts or other kernel parameters than at the reference.
    ContactSet = 1,
    /// A contact point moved beyond the bound's premises (a quarter of the chord, D ≥ 1/2); also
    /// contacts whose order changed at a neighbour build, which look like large moves.
    Moved = 2,
    /// The Eq. 3 cap switched a contact to Hertz at the reference, or could be reached now.
    Cap = 3,
    /// The bound exceeds EPS × scale.
    OverBudget = 4,
    /// In a run of exact steps after fresh references kept failing at once.
    BackOff = 5,
}

/// Names of [`Why`]'s reasons, in its order.
pub const WHY: [&str; 6] = [
    "no reference",
    "contact set changed",
    "moved beyond reach",
    "Eq. 3 cap",
    "bound above budget",
    "back-off",
];

/// One particle's reference: the inputs and result of its last exact evaluation, and per source
/// the constants of its part of the bound, so that a step's test costs one square root and two
/// multiply-adds per contact (the kernel it replaces costs n/2 square roots and divisions).
#[derive(Debug, Default, Clone)]
pub struct KeptExact {
    params: Option<McParams>,
    points: Vec<Vec3>,
    /// The influence matrix g⁰ of `points` (n² values and the kernel's padding).
    g: Vec<f64>,
    /// Scratch of the cap flags of a step formed from g⁰.
    fallback: Vec<bool>,
    /// Per source, see [`SourceBound`].
    sources: Vec<SourceBound>,
    dr: Vec<f64>,
    /// The cap switched a contact back to Hertz at the reference.
    capped: bool,
    /// max(max |Δ⁰|, FLOOR_STRAIN · r).
    pub(super) scale: f64,
    /// The bound of the step's result (0 when it was evaluated exactly this step).
    pub(super) bound: f64,
    /// Steps the reference has been reused.
    age: u32,
    /// Steps left to evaluate exactly without testing or keeping a reference.
    skip: u32,
    /// The current length of such runs: doubled (up to [`MAX_BACKOFF`]) each time a fresh
    /// reference fails its first test, zeroed when one is reused.
    backoff: u32,
    /// Exact evaluations by [`Why`] since the counters were last read.
    why: [u32; 6],
}

/// Longest run of exact steps without a bound test after references kept failing at once.
const MAX_BACKOFF: u32 = 16;

/// What the budget decided for one particle this step.
pub(super) enum Decision {
    /// Reuse the kept radius changes; the bound relative to EPS × scale.
    Reuse(f64),
    /// Evaluate exactly; `keep`: keep the result as the new reference ([`KeptExact::store`]).
    Exact { keep: bool },
}

/// One source's constants of the bound, from its smallest reference chord d, its distance ρ_k
/// from the centre and the particle's ρ_min, ρ_max (the module's doc). Within the accepted moves
/// (ε ≤ d/4, so d − ε ≥ 3d/4, and D_lo ≥ 1/2) every part is at most linear in ε with these
/// coefficients.
#[derive(Debug, Default, Clone, Copy)]
struct SourceBound {
    /// max_c |Δh_kc| ≤ ε · this: the geometry term's coefficient of F_k ε.
    geometry: f64,
    /// Largest pair move ε the coefficients hold for (0: none, the source forces a recomputation
    /// as soon as it carries a load).
    reach: f64,
}

impl SourceBound {
    fn new(nu: f64, d: f64, rho_k: f64, rho_min: f64, rho_max: f64) -> Self {
        let (k34, k12) = ((3.0 - 4.0 * nu).abs(), (1.0 - 2.0 * nu).abs());
        let b_max = |den: f64| 1.0 + k34 + 2.0 * k12 / den;
        if !(d > 0.0 && rho_min > 0.0 && d.is_finite()) {
            // No reach: the source forces a recomputation as soon as it carries a load.
            return SourceBound::default();
        }
        let d0 = 1.0 - (rho_max - rho_k).max(0.0) / d;
        // a = 2ε/ρ_min and b = 2ε/d per unit ε.
        let (a, b) = (2.0 / rho_min, 2.0 / d);
        // D_lo = D⁰ − (a + b) ε ≥ 1/2 and ε ≤ d/4.
        let reach = (MAX_RELATIVE_MOVE * d).min(((d0 - MIN_DENOMINATOR) / (a + b)).max(0.0));
        let (inv_lo, inv_lo2) = (1.0 / MIN_DENOMINATOR, 1.0 / (MIN_DENOMINATOR * MIN_DENOMINATOR));
        let db = 2.0 * (a + b) + 2.0 * k34 * a + k12 * ((3.0 * a + b) * inv_lo + 2.0 * (a + b) * inv_lo2);
        let inv_chord = 1.0 / ((1.0 - MAX_RELATIVE_MOVE) * d);
        let bm = b_max(MIN_DENOMINATOR);
        SourceBound { geometry: db * inv_chord + bm * inv_chord / d, reach }
    }
}

impl KeptExact {
    /// The bound on max_c |Δ_c(now) − Δ⁰_c| for this step's `contacts`, or `None` when the
    /// reference cannot be reused (see the module's doc).
    pub(super) fn bound(&self, bp: &BudgetParams, contacts: &[ContactLoad]) -> Result<Bound, Why> {
        if self.params.is_none() {
            return Err(Why::NoReference);
        }
        if self.params != Some(bp.params) || self.points.len() != contacts.len() {
            return Err(Why::ContactSet);
        }
        if self.capped {
            return Err(Why::Cap);
        }
        // Σ F l ε_k + ε_max Σ F l, the smallest reach left after the source's move, and for the
        // cap's margin the largest F l ε_k and F l.
        let (mut geom, mut weight, mut eps_max, mut room) = (0.0, 0.0, 0.0f64, f64::INFINITY);
        let (mut top_moved, mut top_weight) = (0.0f64, 0.0f64);
        for ((c, p0), s) in contacts.iter().zip(&self.points).zip(&self.sources) {
            let eps = (c.point - p0).norm();
            // A non-finite input goes to the exact kernel, which stops the run naming it.
            if !(eps.is_finite() && c.force.is_finite()) {
                return Err(Why::Moved);
            }
            eps_max = eps_max.max(eps);
            let f = bp.load(c.force);
            if f == 0.0 {
                continue;
            }
            geom += f * s.geometry * eps;
            weight += f * s.geometry;
            room = room.min(s.reach - eps);
            top_moved = top_moved.max(f * s.geometry * eps);
            top_weight = top_weight.max(f * s.geometry);
        }
        if eps_max > room {
            return Err(Why::Moved);
        }
        let bound = bp.pref * (geom + eps_max * weight);
        // No single term F_k g_kc moves by more than this from its value with the kept geometry.
        let term_change = bp.pref * (top_moved + eps_max * top_weight);
        if bound.is_finite() && term_change.is_finite() {
            Ok(Bound { bound, term_change })
        } else {
            Err(Why::OverBudget)
        }
    }

    /// This step's radius changes from its loads and the kept matrix, into `dr`, when the Eq. 3
    /// cap cannot switch a contact now: every term with the kept geometry stays below δ_max by
    /// more than `term_change` (the cap is applied with δ_max lowered by it, and must not trip),
    /// so no exact term reaches δ_max either and the cap leaves both alike. `false`: the cap
    /// could act, or the kernel found a non-finite value (the exact kernel then decides).
    fn form(&mut self, bp: &BudgetParams, contacts: &[ContactLoad], term_change: f64) -> bool {
        let mut params = bp.params;
        if let Some(cap) = params.cap.as_mut() {
            cap.mpr -= term_change / params.radius;
            if cap.mpr.is_nan() || cap.mpr < 0.0 {
                return false;
            }
        }
        self.fallback.resize(contacts.len(), false);
        radius_changes_with(&params, &self.g, contacts, &mut self.dr, &mut self.fallback)
            .is_ok_and(|s| s.fallbacks == 0)
    }

    /// Reuse or exact evaluation under the budget `eps`, for this step's `contacts`. A particle
    /// whose fresh reference fails its very first test (its inputs change faster than the budget
    /// allows) is evaluated exactly without test or reference for a run of steps that doubles
    /// each time this repeats, so that the budget costs little more than the exact pass there.
    pub(super) fn decide(&mut self, bp: &BudgetParams, contacts: &[ContactLoad], eps: f64) -> Decision {
        self.bound = 0.0;
        if self.skip > 0 {
            self.skip -= 1;
            self.count(Why::BackOff);
            return Decision::Exact { keep: self.skip == 0 };
        }
        match self.bound(bp, contacts) {
            Ok(Bound { bound, term_change }) => {
                if self.form(bp, contacts, term_change) {
                    let largest = self.dr.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                    let scale = largest.max(FLOOR_STRAIN * bp.params.radius);
                    let budget = eps * scale;
                    if bound <= budget {
                        self.scale = scale;
                        self.bound = bound;
                        self.age += 1;
                        self.backoff = 0;
                        return Decision::Reuse(bound / budget);
                    }
                    self.count(Why::OverBudget);
                } else {
                    self.count(Why::Cap);
                }
            }
            Err(why) => self.count(why),
        }
        if self.age == 0 && self.params.is_some() {
            self.backoff = (2 * self.backoff + 1).min(MAX_BACKOFF);
            self.skip = self.backoff;
            return Decision::Exact { keep: false };
        }
        Decision::Exact { keep: true }
    }

    fn count(&mut self, why: Why) {
        let c = &mut self.why[why as usize];
        *c = c.saturating_add(1);
    }

    /// Keeps this step's exact evaluation `dr` of `contacts` as the reference.
    pub(super) fn store(&mut self, bp: &BudgetParams, contacts: &[ContactLoad], dr: &[f64], capped: bool) {
        let n = contacts.len();
        self.params = Some(bp.params);
        self.points.clear();
        self.points.extend(contacts.iter().map(|c| c.point));
        // The matrix of these points; a kernel error leaves no reference (the next step is exact).
        self.g.clear();
        self.g.resize(n * n + crate::physics::contact_set::LANES, 0.0);
        if influence(&bp.params, contacts, &mut self.g).is_err() {
            self.params = None;
            return;
        }
        self.dr.clear();
        self.dr.extend_from_slice(dr);
        // Each source's smallest chord, from squared chords (one pass over the pairs, no square
        // root per pair), into `sources[k].reach` until the constants are set below.
        self.sources.clear();
        self.sources.resize(n, SourceBound { reach: f64::INFINITY, ..Default::default() });
        for a in 0..n {
            for b in a + 1..n {
                let d2 = (self.points[b] - self.points[a]).norm_squared();
                self.sources[a].reach = self.sources[a].reach.min(d2);
                self.sources[b].reach = self.sources[b].reach.min(d2);
            }
        }
        let (rho_min, rho_max) = self
            .points
            .iter()
            .map(|p| p.norm())
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), r| (lo.min(r), hi.max(r)));
        let nu = bp.params.poisson_ratio;
        for (s, p) in self.sources.iter_mut().zip(&self.points) {
            *s = SourceBound::new(nu, s.reach.sqrt(), p.norm(), rho_min, rho_max);
        }
        self.capped = capped;
        let largest = dr.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        self.scale = largest.max(FLOOR_STRAIN * bp.params.radius);
        self.bound = 0.0;
        self.age = 0;
    }

    /// The kept radius changes.
    pub(super) fn dr(&self) -> &[f64] {
        &self.dr
    }
}

/// Reorders kept references after a spatial sort: the one in slot `old_of_new[k]` moves to k.
pub(super) fn reorder(kept: &mut Vec<KeptExact>, old_of_new: &[u32]) {
    let mut old = std::mem::take(kept);
    *kept =
        old_of_new.iter().map(|&o| old.get_mut(o as usize).map(std::mem::take).unwrap_or_default()).collect();
}

/// What the budget did over a run (zeroed at each `run` start by the deck's summary).
#[derive(Debug, Default, Clone, Copy)]
pub struct BudgetStats {
    /// Particle-steps with two or more multi-contact slots (the ones Eq. 2 concerns).
    pub multi: u64,
    /// Of those, the exact evaluations.
    pub recomputed: u64,
    /// Largest bound / (EPS × scale) of a reused result (≤ 1 by construction).
    pub worst_bound: f64,
    /// Shadow checks run.
    pub checks: u64,
    /// Largest measured |kept − exact| / scale over the checks.
    pub worst_measured: f64,
    /// Largest bound / scale over the particles of the checks.
    pub worst_checked_bound: f64,
    /// The exact evaluations by reason, in the order of [`WHY`].
    pub why: [u64; 6],
}

impl World {
    /// The shadow check (`mcAccuracyCheck`): every particle's exact radius changes from this
    /// step's inputs, not used for the forces, against the ones the budget chose. A measured
    /// difference above the particle's bound (plus round-off) means the bound is wrong: the run
    /// stops rather than report an error estimate it cannot keep.
    pub(super) fn shadow_check(&mut self) -> Result<(), StepError> {
        let n = self.p.len();
        let m = &mut self.multi;
        m.shadow_dr.resize(m.slot_dr.len(), 0.0);
        let mut fb = Vec::new();
        let (mut measured, mut bounds): (f64, f64) = (0.0, 0.0);
        for i in 0..n.min(m.budget.len()) {
            let (s0, s1) = (m.slot_start[i] as usize, m.slot_start[i + 1] as usize);
            if s1 - s0 < 2 {
                continue;
            }
            let mat = m.mc_types[self.p.typ[i]].material;
            let params = McParams {
                radius: self.p.radius[i],
                youngs_modulus: mat.youngs_modulus,
                poisson_ratio: mat.poisson_ratio,
                gamma: mat.gamma,
                cap: mat.cap,
            };
            fb.resize(s1 - s0, false);
            let exact = &mut m.shadow_dr[s0..s1];
            radius_changes(&params, &m.slot_loads[s0..s1], exact, &mut fb).map_err(|e| StepError {
                step: self.step,
                particle: self.p.id[i],
                cause: format!("multi-contact kernel (accuracy check): {e}"),
                contact: None,
            })?;
            let k = &m.budget[i];
            let diff = exact.iter().zip(&m.slot_dr[s0..s1]).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            if diff > k.bound + ROUNDOFF * k.scale {
                return Err(StepError {
                    step: self.step,
                    particle: self.p.id[i],
                    cause: format!(
                        "mcAccuracy check: measured radius-change error {diff:e} m exceeds its bound {:e} m (the bound is wrong)",
                        k.bound
                    ),
                    contact: None,
                });
            }
            measured = measured.max(diff / k.scale);
            bounds = bounds.max(k.bound / k.scale);
        }
        let st = &mut m.budget_stats;
        st.checks += 1;
        st.worst_measured = st.worst_measured.max(measured);
        st.worst_checked_bound = st.worst_checked_bound.max(bounds);
        Ok(())
    }

    /// The accuracy budget's counters since the last call (zeroed by it).
    pub fn take_budget_stats(&mut self) -> BudgetStats {
        let mut st = std::mem::take(&mut self.multi.budget_stats);
        for k in &mut self.multi.budget {
            for (t, c) in st.why.iter_mut().zip(std::mem::take(&mut k.why)) {
                *t += u64::from(c);
            }
        }
        st
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> McParams {
        McParams { radius: 1e-2, youngs_modulus: 2.33e4, poisson_ratio: 0.45, gamma: 1.125, cap: None }
    }

    /// A few contacts near the sphere of radius r, loaded with `f`.
    fn contacts(shift: f64, f: &[f64]) -> Vec<ContactLoad> {
        let r = 0.99e-2;
        let dirs = [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 0.1).normalize(),
            Vec3::new(-0.5, 0.8, 0.0).normalize(),
            Vec3::new(-0.3, -0.9, 0.2).normalize(),
        ];
        dirs.iter()
            .zip(f)
            .enumerate()
            .map(|(k, (d, &f))| {
                let wobble = Vec3::new((k as f64).sin(), (k as f64 * 1.7).cos(), 0.3) * shift;
                ContactLoad { point: d * r + wobble, force: f }
            })
            .collect()
    }

    /// Over many perturbations of loads and points, the exact radius changes never differ from the
    /// ones formed with the reference geometry by more than the bound.
    #[test]
    fn the_bound_holds_on_perturbed_contact_sets() {
        let p = params();
        let bp = BudgetParams::new(p);
        let f0 = [0.2, 0.3, 0.05, 0.1, 0.0];
        let c0 = contacts(0.0, &f0);
        let mut dr0 = vec![0.0; c0.len()];
        let mut fb = vec![false; c0.len()];
        radius_changes(&p, &c0, &mut dr0, &mut fb).unwrap();
        let mut kept = KeptExact::default();
        kept.store(&bp, &c0, &dr0, false);
        let mut tightest: f64 = 0.0;
        for s in 0..200 {
            let t = s as f64 / 200.0;
            let f: Vec<f64> =
                f0.iter().enumerate().map(|(k, x)| x * (1.0 + 0.3 * t * (k as f64 - 2.0))).collect();
            let c = contacts(1e-5 * t * 40.0, &f);
            let mut dr = vec![0.0; c.len()];
            radius_changes(&p, &c, &mut dr, &mut fb).unwrap();
            let mut formed = vec![0.0; c.len()];
            radius_changes_with(&p, &kept.g, &c, &mut formed, &mut fb).unwrap();
            let measured = dr.iter().zip(&formed).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            if let Ok(Bound { bound: b, .. }) = kept.bound(&bp, &c) {
                assert!(
                    measured <= b + ROUNDOFF * kept.scale,
                    "step {s}: measured {measured:e} > bound {b:e}"
                );
                if b > 0.0 {
                    tightest = tightest.max(measured / b);
                }
            }
        }
        // The bound is not vacuous: it is within two orders of magnitude of the change somewhere.
        assert!(tightest > 1e-2, "measured/bound at most {tightest:e}");
        // Unchanged inputs: zero bound.
        assert_eq!(kept.bound(&bp, &c0).map(|b| b.bound), Ok(0.0));
    }
}
