//! One pair's contact through [`crate::physics::pair`]: pair by pair or in vectorised batches,
//! with or without the multi-contact closure's state (the [`PairState`] of a pass).

use crate::physics::pair::{
    particle_particle_with_history, Body, ContactError, PairLanes, RollSpring, LANES,
};
use crate::physics::{PairCoeffs, Vec3};

use super::contacts::{contact_error, Pair, PairDr, PairHist, RECEIVER_GAP};
use super::sinks::{PairOut, PairSink};
use super::{Domain, Particles, StepError};

/// Read-only view of the state that one pair evaluation needs (shared between threads).
pub(super) struct PairCtx<'a> {
    pub(super) p: &'a Particles,
    pub(super) coeffs: &'a [PairCoeffs],
    pub(super) nt: usize,
    pub(super) domain: Domain,
    pub(super) dt: f64,
    /// The run's time step, whatever `update`: the rolling spring advances by it on every pass
    /// (as LIGGGHTS' does), kept only on a time step.
    pub(super) roll_dt: f64,
    pub(super) update: bool,
    pub(super) step: u64,
    pub(super) liggghts_radii: bool,
}

impl<'a> PairCtx<'a> {
    /// The view of a pass; a pass that does not advance the histories (`update` false: the
    /// set-up pass, per-contact output) integrates over no time.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        p: &'a Particles,
        coeffs: &'a [PairCoeffs],
        nt: usize,
        domain: Domain,
        dt: f64,
        update: bool,
        step: u64,
        liggghts_radii: bool,
    ) -> Self {
        let roll_dt = dt;
        let dt = if update { dt } else { 0.0 };
        PairCtx { p, coeffs, nt, domain, dt, roll_dt, update, step, liggghts_radii }
    }
}

impl PairCtx<'_> {
    /// Force on i and torques on i and j of one pair into `out` (`touching` false when apart);
    /// updates the pair's history when `update`.
    #[inline]
    pub(super) fn eval(
        &self,
        pr: &mut Pair,
        k: usize,
        state: &mut impl PairState,
        out: &mut PairOut,
    ) -> Result<(), Box<StepError>> {
        let dr = state.dr(k);
        let Some((d, kimg)) = self.approach(pr, k, dr, state) else {
            *out = PairOut::default();
            return Ok(());
        };
        let p = self.p;
        let (i, j) = (pr.i as usize, pr.j as usize);
        let (ri, rj) = (p.radius[i] + dr[0], p.radius[j] + dr[1]);
        let bi = Body { x: p.x[i], v: p.v[i], omega: p.omega[i], radius: p.radius[i], mass: p.mass[i] };
        // The image of j across a sheared boundary carries the Lees–Edwards velocity jump.
        let mut vj = p.v[j];
        vj.x += kimg * self.domain.le_vjump;
        let mut bj = Body { x: p.x[i] - d, v: vj, omega: p.omega[j], radius: p.radius[j], mass: p.mass[j] };
        let mut dri = dr[0];
        let mut ri_stored = ri;
        if self.liggghts_radii && dr[0] != 0.0 {
            // LIGGGHTS 3.8 `surface multicontact` keeps particle i's original radius in R_eff and
            // in its lever arm (only the overlap sees r_i + Δ). Same effect through the physics
            // core: original r_i, and j moved Δ_i closer along the normal.
            let r = d.norm();
            if r > dr[0] {
                bj.x = p.x[i] - d * ((r - dr[0]) / r);
                dri = 0.0;
                ri_stored = p.radius[i];
            }
        }
        let c = &self.coeffs[p.typ[i] * self.nt + p.typ[j]];
        let mut shear = pr.shear;
        let mut delta_max = state.delta_max(k);
        let mut roll = state.roll(k);
        let spring = RollSpring { spring: &mut roll, dt: self.roll_dt };
        let r = particle_particle_with_history(
            c,
            &bi,
            &bj,
            dri,
            dr[1],
            self.dt,
            &mut shear,
            &mut delta_max,
            spring,
        )
        .map_err(|e| Box::new(contact_error(self.step, p.id[i], Some(p.id[j]), e)))?;
        let fnorm = match r {
            Some(cf) => {
                *out = PairOut {
                    touching: true,
                    force: cf.force_i,
                    torque_i: cf.torque_i,
                    torque_j: cf.torque_j,
                };
                cf.force_i.dot(&cf.en).abs()
            }
            None => {
                *out = PairOut::default();
                0.0
            }
        };
        if self.update {
            pr.shear = shear;
            state.keep(k, fnorm, ri_stored, rj);
            state.keep_delta_max(k, delta_max);
            state.keep_roll(k, roll);
        }
        Ok(())
    }

    /// What both pair passes do first: the centre difference d = x_i − x_j (minimum image) and
    /// the image count across a sheared boundary, and the `near` flag. A pair whose modified
    /// spheres are apart gets its history reset, and `None`.
    #[inline(always)]
    pub(super) fn approach(
        &self,
        pr: &mut Pair,
        k: usize,
        dr: PairDr,
        state: &mut impl PairState,
    ) -> Option<(Vec3, f64)> {
        let p = self.p;
        let (i, j) = (pr.i as usize, pr.j as usize);
        let mut d = p.x[i] - p.x[j];
        let kimg = self.domain.minimum_image_k(&mut d);
        let (ri, rj) = (p.radius[i] + dr[0], p.radius[j] + dr[1]);
        let radsum = ri + rj;
        let d2 = d.norm_squared();
        let reach = (1.0 + RECEIVER_GAP) * (p.radius[i] + p.radius[j]);
        state.near(k, d2 < reach * reach);
        if d2 >= radsum * radsum {
            if self.update {
                pr.shear = Vec3::zeros();
                state.keep(k, 0.0, ri, rj);
                state.keep_delta_max(k, 0.0);
                state.keep_roll(k, Vec3::zeros());
            }
            return None;
        }
        Some((d, kimg))
    }
}

impl PairCtx<'_> {
    /// Evaluates `pairs` in order as [`PairCtx::eval`] does, overlapping pairs in vectorised
    /// batches of [`LANES`]; hands each pair's result to `sink.put(k, i, j, out)` (k: index in
    /// `pairs`). Touching pairs reach the sink in pair order; pairs apart may come earlier.
    pub(super) fn eval_batched(
        &self,
        pairs: &mut [Pair],
        state: &mut impl PairState,
        sink: &mut impl PairSink,
    ) -> Result<(), Box<StepError>> {
        let p = self.p;
        let mut lanes = PairLanes::default();
        let mut slot = [0usize; LANES];
        let mut n = 0;
        for k in 0..pairs.len() {
            let (pr, dr) = (&mut pairs[k], state.dr(k));
            let (i, j) = (pr.i as usize, pr.j as usize);
            let Some((d, kimg)) = self.approach(pr, k, dr, state) else {
                sink.put(k, i, j, &PairOut::default());
                continue;
            };
            // The image of j across a sheared boundary carries the Lees–Edwards velocity jump.
            let mut vj = p.v[j];
            vj.x += kimg * self.domain.le_vjump;
            let c = &self.coeffs[p.typ[i] * self.nt + p.typ[j]];
            let l = n;
            for a in 0..3 {
                lanes.d[a][l] = d[a];
                lanes.vr[a][l] = p.v[i][a] - vj[a];
                lanes.omega_i[a][l] = p.omega[i][a];
                lanes.omega_j[a][l] = p.omega[j][a];
                lanes.shear[a][l] = pr.shear[a];
            }
            lanes.radius_i[l] = p.radius[i];
            lanes.radius_j[l] = p.radius[j];
            lanes.dri[l] = dr[0];
            lanes.drj[l] = dr[1];
            lanes.mass_i[l] = p.mass[i];
            lanes.mass_j[l] = p.mass[j];
            lanes.coeffs.set(l, c);
            slot[n] = k;
            n += 1;
            if n == LANES {
                self.flush(&mut lanes, &slot[..n], pairs, state, sink)?;
                n = 0;
            }
        }
        if n > 0 {
            lanes.pad_from_first(n);
            self.flush(&mut lanes, &slot[..n], pairs, state, sink)?;
        }
        Ok(())
    }

    /// Evaluates a filled batch and writes each used lane back to its pair and to the sink.
    pub(super) fn flush(
        &self,
        lanes: &mut PairLanes,
        slot: &[usize],
        pairs: &mut [Pair],
        state: &mut impl PairState,
        sink: &mut impl PairSink,
    ) -> Result<(), Box<StepError>> {
        lanes.evaluate(self.dt);
        for (l, &k) in slot.iter().enumerate() {
            let pr = &mut pairs[k];
            if !lanes.ok[l] {
                // The pair-by-pair path names the cause (its history is still the step's input).
                let mut o = PairOut::default();
                self.eval(pr, k, state, &mut o)?;
                let (i, j) = (pr.i as usize, pr.j as usize);
                return Err(Box::new(contact_error(
                    self.step,
                    self.p.id[i],
                    Some(self.p.id[j]),
                    ContactError::NonFinite,
                )));
            }
            let lane = |a: &[[f64; LANES]; 3]| Vec3::new(a[0][l], a[1][l], a[2][l]);
            let o = PairOut {
                touching: true,
                force: lane(&lanes.force),
                torque_i: lane(&lanes.torque_i),
                torque_j: lane(&lanes.torque_j),
            };
            if self.update {
                pr.shear = lane(&lanes.shear);
                let (ri, rj) = (lanes.radius_i[l] + lanes.dri[l], lanes.radius_j[l] + lanes.drj[l]);
                state.keep(k, lanes.fnorm[l], ri, rj);
            }
            sink.put(k, pr.i as usize, pr.j as usize, &o);
        }
        Ok(())
    }
}

impl PairCtx<'_> {
    /// Evaluates `pairs` in order into `sink` (vectorised batches when `batched`), with their
    /// radius changes and closure state when the multi-contact closure is on (`closure`, one
    /// entry per pair each), or with the per-contact histories of the laws that keep one
    /// (`history`: `hooke/hysteresis`, the `epsd` rolling springs; no multi-contact form, no batches).
    pub(super) fn pass(
        &self,
        pairs: &mut [Pair],
        closure: Option<(&[PairDr], &mut [PairHist])>,
        history: Option<ContactHistory>,
        batched: bool,
        sink: &mut impl PairSink,
    ) -> Result<(), Box<StepError>> {
        if let Some(mut h) = history {
            return self.pass_with(pairs, &mut h, false, sink);
        }
        match closure {
            None => self.pass_with(pairs, &mut NoClosure, batched, sink),
            Some((dr, hist)) => {
                let n = pairs.len();
                let mut state = ClosureState { dr: &dr[..n], hist: &mut hist[..n] };
                self.pass_with(pairs, &mut state, batched, sink)
            }
        }
    }

    pub(super) fn pass_with(
        &self,
        pairs: &mut [Pair],
        state: &mut impl PairState,
        batched: bool,
        sink: &mut impl PairSink,
    ) -> Result<(), Box<StepError>> {
        if batched {
            return self.eval_batched(pairs, state, sink);
        }
        let mut o = PairOut::default();
        for (k, pr) in pairs.iter_mut().enumerate() {
            self.eval(pr, k, state, &mut o)?;
            sink.put(k, pr.i as usize, pr.j as usize, &o);
        }
        Ok(())
    }
}

/// What a pair pass reads and keeps of the multi-contact closure, pair k of the pass: a trait so
/// that each pass is compiled for one case, and a Hertz pass neither loads radius changes that
/// are all zero nor stores a state nobody reads (at large N both would stream from memory).
pub(super) trait PairState {
    /// This step's radius changes of pair k.
    fn dr(&self, k: usize) -> PairDr;
    /// Whether pair k is near enough to receive multi-contact terms.
    fn near(&mut self, k: usize, near: bool);
    /// What the next multi-contact pass reads of pair k: |F·n| and the modified radii.
    fn keep(&mut self, k: usize, fnorm: f64, ri: f64, rj: f64);
    /// The normal law's history of pair k (largest overlap of `hooke/hysteresis`; 0 otherwise).
    #[inline(always)]
    fn delta_max(&self, _: usize) -> f64 {
        0.0
    }
    /// Keeps the normal law's history of pair k (nothing to keep for the other laws).
    #[inline(always)]
    fn keep_delta_max(&mut self, _: usize, _: f64) {}
    /// The rolling spring of pair k (`epsd`, `epsd2`; zero otherwise).
    #[inline(always)]
    fn roll(&self, _: usize) -> Vec3 {
        Vec3::zeros()
    }
    /// Keeps the rolling spring of pair k (nothing to keep for the other models).
    #[inline(always)]
    fn keep_roll(&mut self, _: usize, _: Vec3) {}
}

/// Hertz: no radius changes, nothing kept.
pub(super) struct NoClosure;

impl PairState for NoClosure {
    #[inline(always)]
    fn dr(&self, _: usize) -> PairDr {
        [0.0; 2]
    }
    #[inline(always)]
    fn near(&mut self, _: usize, _: bool) {}
    #[inline(always)]
    fn keep(&mut self, _: usize, _: f64, _: f64, _: f64) {}
}

/// The multi-contact closure: this step's radius changes in, the pairs' state out.
pub(super) struct ClosureState<'a> {
    pub(super) dr: &'a [PairDr],
    pub(super) hist: &'a mut [PairHist],
}

impl PairState for ClosureState<'_> {
    #[inline(always)]
    fn dr(&self, k: usize) -> PairDr {
        self.dr[k]
    }
    #[inline(always)]
    fn near(&mut self, k: usize, near: bool) {
        self.hist[k].near = near;
    }
    #[inline(always)]
    fn keep(&mut self, k: usize, fnorm: f64, ri: f64, rj: f64) {
        let h = &mut self.hist[k];
        (h.fn_prev, h.ri_prev, h.rj_prev) = (fnorm, ri, rj);
    }
}

/// The per-pair histories of the laws that keep one, no radius changes: the largest overlap of
/// `hooke/hysteresis` (`delta_max`) and the rolling spring of `epsd`/`epsd2` (`roll`), one entry
/// per pair each, or empty when the law is not in use.
pub(super) struct ContactHistory<'a> {
    pub(super) delta_max: &'a mut [f64],
    pub(super) roll: &'a mut [Vec3],
}

impl<'a> ContactHistory<'a> {
    /// The histories of `np` pairs: each array that holds one entry per pair (the others are
    /// empty when their law is not in use); None when neither does.
    pub(super) fn of(delta_max: &'a mut [f64], roll: &'a mut [Vec3], np: usize) -> Option<Self> {
        let (d, r) = (delta_max.len() == np, roll.len() == np);
        (np > 0 && (d || r)).then(|| ContactHistory {
            delta_max: &mut delta_max[..if d { np } else { 0 }],
            roll: &mut roll[..if r { np } else { 0 }],
        })
    }
}

impl PairState for ContactHistory<'_> {
    #[inline(always)]
    fn dr(&self, _: usize) -> PairDr {
        [0.0; 2]
    }
    #[inline(always)]
    fn near(&mut self, _: usize, _: bool) {}
    #[inline(always)]
    fn keep(&mut self, _: usize, _: f64, _: f64, _: f64) {}
    #[inline(always)]
    fn delta_max(&self, k: usize) -> f64 {
        self.delta_max.get(k).copied().unwrap_or(0.0)
    }
    #[inline(always)]
    fn keep_delta_max(&mut self, k: usize, v: f64) {
        if let Some(d) = self.delta_max.get_mut(k) {
            *d = v;
        }
    }
    #[inline(always)]
    fn roll(&self, k: usize) -> Vec3 {
        self.roll.get(k).copied().unwrap_or(Vec3::zeros())
    }
    #[inline(always)]
    fn keep_roll(&mut self, k: usize, v: Vec3) {
        if let Some(m) = self.roll.get_mut(k) {
            *m = v;
        }
    }
}
