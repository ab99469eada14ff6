//! The multi-contact pass (LIGGGHTS `fix multicontact/halfspace` pre_force): every particle's radius
//! change at every one of its contacts from the previous step's normal forces (Eq. 2, capped by
//! Eq. 3 where the material carries a cap), through [`crate::physics::contact_set`].

use std::cell::RefCell;
use std::ops::Range;
use std::sync::Mutex;

use crate::physics::contact_set::{
    loaded_threshold, radius_changes, ContactLoad, InfluenceCache, KeptInfluence, McParams,
};
use crate::physics::{Material, Vec3};
use crate::team::{SplitMut, Team};

use super::contacts::{Pair, PairHist};
use super::mc_budget::{BudgetParams, Decision, KeptExact};
use super::particles::Particles;
use super::{Domain, StepError, World};

/// What the multi-contact pass keeps between steps (no allocation in the loop).
#[derive(Debug, Default)]
pub(super) struct McState {
    /// Step of the next full multi-contact pass under `mc_every`.
    pub(super) mc_due: u64,
    /// Neighbour builds at the last full multi-contact pass (a build renumbers the pairs).
    pub(super) mc_builds: u64,
    pub(super) mc_types: Vec<McType>,
    /// Per particle, its first slot (compressed rows: particle i owns slots
    /// `slot_start[i]..slot_start[i + 1]`, its pairs in pair order, then its wall contacts).
    pub(super) slot_start: Vec<u32>,
    /// Per pair in the multi-contact set: its slot at i and at j (unused for the other pairs).
    pub(super) pair_slot: Vec<[u32; 2]>,
    /// Per wall contact: its slot.
    pub(super) wall_slot: Vec<u32>,
    pub(super) slot_fill: Vec<u32>,
    /// Per slot: the contact point and previous force the kernel reads, written in slot order
    /// so that a particle's contact list is one contiguous slice (no gather in the kernel pass).
    pub(super) slot_loads: Vec<ContactLoad>,
    /// Radius change per slot, from this step's kernel pass.
    pub(super) slot_dr: Vec<f64>,
    /// The slot lists no longer match the pairs and wall contacts (neighbour build, a wall
    /// contact appeared or left, a pair entered or left the multi-contact set).
    pub(super) slots_stale: bool,
    /// Geometry tolerance: the kept influence matrices, one per particle.
    pub(super) mc_cache: Option<InfluenceCache>,
    pub(super) pair_mc: Vec<bool>,
    /// Accuracy budget: per particle, the reference of its last exact Eq. 2 evaluation.
    pub(super) budget: Vec<KeptExact>,
    /// Accuracy budget: what it did since the counters were last read.
    pub(super) budget_stats: super::mc_budget::BudgetStats,
    /// Shadow check: this step's exact radius changes per slot (scratch).
    pub(super) shadow_dr: Vec<f64>,
}

/// Per-type MC kernel parameters without the radius (filled in per particle).
#[derive(Debug, Clone, Copy)]
pub(super) struct McType {
    pub(super) material: Material,
}

/// Particles per leaf of the threaded multi-contact pass.
pub(super) const MC_GRAIN: usize = 64;

/// Kernel calls, fallbacks to Hertz and influence-matrix recomputations of a multi-contact pass.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct McCounts {
    pub(super) contacts: u64,
    pub(super) fallbacks: u64,
    pub(super) recomputed: u64,
    /// Accuracy budget: particles with two or more contacts (evaluated or reused).
    pub(super) multi: u64,
    /// Accuracy budget: largest bound / (EPS × scale) of a reused result.
    pub(super) worst: f64,
}

impl World {
    /// Per particle, the list of its multi-contact slots (pairs in pair order, then wall
    /// contacts), as compressed rows. Rebuilt only when the pairs or wall contacts changed.
    pub(super) fn build_slots(&mut self) {
        let n = self.p.len();
        let m = &mut self.multi;
        m.slot_start.clear();
        m.slot_start.resize(n + 1, 0);
        for (pr, _) in self.contacts.pairs.iter().zip(&m.pair_mc).filter(|(_, t)| **t) {
            m.slot_start[pr.i as usize + 1] += 1;
            m.slot_start[pr.j as usize + 1] += 1;
        }
        for c in &self.contacts.wc {
            m.slot_start[c.p as usize + 1] += 1;
        }
        for i in 0..n {
            m.slot_start[i + 1] += m.slot_start[i];
        }
        m.slot_fill.clear();
        m.slot_fill.extend_from_slice(&m.slot_start[..n]);
        m.pair_slot.clear();
        m.pair_slot.resize(self.contacts.pairs.len(), [0; 2]);
        for ((pr, &t), ps) in self.contacts.pairs.iter().zip(&m.pair_mc).zip(m.pair_slot.iter_mut()) {
            if !t {
                continue;
            }
            let (i, j) = (pr.i as usize, pr.j as usize);
            *ps = [m.slot_fill[i], m.slot_fill[j]];
            m.slot_fill[i] += 1;
            m.slot_fill[j] += 1;
        }
        m.wall_slot.clear();
        for c in &self.contacts.wc {
            let i = c.p as usize;
            m.wall_slot.push(m.slot_fill[i]);
            m.slot_fill[i] += 1;
        }
        m.slots_stale = false;
    }

    /// Multi-contact pass (LIGGGHTS `fix multicontact/halfspace` pre_force): radius change of
    /// every particle at every one of its contacts from the previous step's normal forces.
    pub(super) fn multicontact(&mut self) -> Result<(), StepError> {
        // Between updates under `mc_every` the radius changes of the last pass stand: pairs keep
        // theirs by index (valid until the next neighbour build) and wall contacts by key
        // (`wall_contacts::collect`).
        if self.mc_every > 1
            && self.step < self.multi.mc_due
            && self.builds == self.multi.mc_builds
            && self.contacts.pair_dr.len() == self.contacts.pairs.len()
        {
            return Ok(());
        }
        self.multi.mc_due = self.step.saturating_add(self.mc_every.max(1));
        self.multi.mc_builds = self.builds;
        self.mc_updates += 1;
        let n = self.p.len();
        let domain = self.domain.expect("domain checked in setup");
        for c in &mut self.contacts.wc {
            c.dr = 0.0;
        }
        if self.multi.pair_mc.len() != self.contacts.pairs.len() {
            self.multi.pair_mc.clear();
            self.multi.pair_mc.resize(self.contacts.pairs.len(), false);
            self.multi.slots_stale = true;
        }
        if self.contacts.pair_hist.len() != self.contacts.pairs.len() {
            // The closure started since the last neighbour build: every pair is new to it.
            self.contacts.pair_hist.clear();
            self.contacts.pair_hist.resize(self.contacts.pairs.len(), PairHist::NEW);
        }
        // Pairs outside the multi-contact set get no slot, hence no change (set in the scatter below).
        if self.contacts.pair_dr.len() != self.contacts.pairs.len() {
            self.contacts.pair_dr.resize(self.contacts.pairs.len(), [0.0; 2]);
        }
        // Who takes part: a pair if loaded, or close enough that radius growth could make it touch
        // (gap below RECEIVER_GAP of the radii at the last evaluation; a pair moves far less than
        // that in a step): far candidates would only cost kernel time.
        let mut stale = false;
        for (h, m) in self.contacts.pair_hist.iter().zip(self.multi.pair_mc.iter_mut()) {
            let now = h.fn_prev > 0.0 || h.near;
            if *m != now {
                *m = now;
                stale = true;
            }
        }
        if stale || self.multi.slots_stale {
            self.build_slots();
        }
        // Every taking part pair's contact points and previous force, written straight into the
        // slots of both particles, so that the kernel reads each particle's contacts as one slice;
        // on the team (each member a range of pairs) when the kernel pass runs there.
        let threaded = n >= 2 * MC_GRAIN && self.threads().is_some();
        let team = self.blocks.team.as_ref().filter(|_| threaded);
        let np = self.contacts.pairs.len();
        let m = &mut self.multi;
        m.slot_loads.resize(m.slot_start[n] as usize, ContactLoad { point: Vec3::zeros(), force: 0.0 });
        let src = PairSrc {
            p: &self.p,
            mc_types: &m.mc_types,
            domain,
            pairs: &self.contacts.pairs,
            hist: &self.contacts.pair_hist,
            pair_mc: &m.pair_mc,
            pair_slot: &m.pair_slot,
        };
        let loads = SplitMut::new(&mut m.slot_loads);
        match team {
            Some(team) => team.for_shares(np, |_, r| src.put_loads(r, &loads)),
            None => src.put_loads(0..np, &loads),
        }
        for (c, &sl) in self.contacts.wc.iter().zip(&m.wall_slot) {
            m.slot_loads[sl as usize] = ContactLoad { point: c.rel_prev, force: c.fn_prev };
        }
        // The kernel particle by particle into one Δ per slot (threads on disjoint particle
        // ranges when they pay), then Δ to the pairs and wall contacts.
        self.multi.slot_dr.resize(self.multi.slot_loads.len(), 0.0);
        let ctx = McCtx {
            p: &self.p,
            mc_types: &self.multi.mc_types,
            slot_start: &self.multi.slot_start,
            loads: &self.multi.slot_loads,
            step: self.step,
            accuracy: self.mc_accuracy,
        };
        let (tolerance, kept) = match self.multi.mc_cache.as_mut() {
            Some(c) => {
                let (t, k) = c.slots_mut(n);
                (t, Some(k))
            }
            None => (0.0, None),
        };
        // EPS = 0 leaves the budget out entirely: the exact pass, bit for bit.
        let budget = if self.mc_accuracy > 0.0 {
            self.multi.budget.resize_with(n, Default::default);
            Some(&mut self.multi.budget[..n])
        } else {
            None
        };
        let counts = match self.blocks.team.as_ref().filter(|_| threaded) {
            Some(team) => ctx.kernel_on(team, &mut self.multi.slot_dr, kept, tolerance, budget)?,
            None => ctx.kernel(0, n, &mut self.multi.slot_dr, kept, tolerance, budget)?,
        };
        self.mc_kernel_contacts += counts.contacts;
        self.mc_kernel_fallbacks += counts.fallbacks;
        if let Some(c) = self.multi.mc_cache.as_mut() {
            c.recomputed += counts.recomputed;
        }
        if self.mc_accuracy > 0.0 {
            let st = &mut self.multi.budget_stats;
            st.multi += counts.multi;
            st.recomputed += counts.recomputed;
            st.worst_bound = st.worst_bound.max(counts.worst);
            if self.mc_accuracy_check > 0 && self.step % self.mc_accuracy_check == 0 {
                self.shadow_check()?;
            }
        }
        let m = &self.multi;
        let (dr, pair_dr) = (&m.slot_dr, SplitMut::new(&mut self.contacts.pair_dr));
        let scatter = |r: Range<usize>| {
            // SAFETY: the members' shares are disjoint ranges of pairs.
            let out = unsafe { pair_dr.range(r.clone()) };
            for ((d, &t), ps) in out.iter_mut().zip(&m.pair_mc[r.clone()]).zip(&m.pair_slot[r]) {
                *d = if t { [dr[ps[0] as usize], dr[ps[1] as usize]] } else { [0.0; 2] };
            }
        };
        match self.blocks.team.as_ref().filter(|_| threaded) {
            Some(team) => team.for_shares(np, |_, r| scatter(r)),
            None => scatter(0..np),
        }
        for (c, &sl) in self.contacts.wc.iter_mut().zip(&m.wall_slot) {
            c.dr = dr[sl as usize];
        }
        Ok(())
    }
}

/// What the pairs' contact loads are computed from (shared between threads).
struct PairSrc<'a> {
    p: &'a Particles,
    mc_types: &'a [McType],
    domain: Domain,
    pairs: &'a [Pair],
    hist: &'a [PairHist],
    pair_mc: &'a [bool],
    pair_slot: &'a [[u32; 2]],
}

impl PairSrc<'_> {
    /// The contact points and previous force of the taking part pairs in `r`, into their slots.
    /// Contact points once per pair, both sides from one centre distance; as LIGGGHTS: the
    /// midpoint of the modified spheres' surfaces along the centre line when loaded, else each
    /// particle's own surface point.
    fn put_loads(&self, r: Range<usize>, loads: &SplitMut<ContactLoad>) {
        let p = self.p;
        // The kernel's loaded threshold of particle a (LIGGGHTS switches the point on the same).
        let eps = |a: usize| loaded_threshold(self.mc_types[p.typ[a]].material.youngs_modulus, p.radius[a]);
        for k in r {
            if !self.pair_mc[k] {
                continue;
            }
            let (pr, h) = (&self.pairs[k], &self.hist[k]);
            let (a, b) = (pr.i as usize, pr.j as usize);
            let mut xab = p.x[b] - p.x[a];
            self.domain.minimum_image(&mut xab);
            let len = xab.norm().max(1e-300);
            let points = if h.fn_prev > eps(a) {
                let tmp = xab * ((h.ri_prev - h.rj_prev) * 0.5 / len);
                [tmp + 0.5 * xab, tmp - 0.5 * xab]
            } else {
                [xab * (h.ri_prev / len), -xab * (h.rj_prev / len)]
            };
            for (&sl, point) in self.pair_slot[k].iter().zip(points) {
                let sl = sl as usize;
                // SAFETY: every pair end has a slot of its own (`build_slots`) and the members'
                // pairs are disjoint, so no slot is written twice.
                unsafe { loads.range(sl..sl + 1)[0] = ContactLoad { point, force: h.fn_prev } };
            }
        }
    }
}

thread_local! {
    /// One particle's fallback flags: per thread, grown to the largest contact set seen and
    /// reused (no allocation in the step loop).
    static MC_SCRATCH: RefCell<Vec<bool>> = RefCell::default();
}

/// Read-only view of what the multi-contact kernel pass needs (shared between threads).
pub(super) struct McCtx<'a> {
    pub(super) p: &'a Particles,
    pub(super) mc_types: &'a [McType],
    pub(super) slot_start: &'a [u32],
    /// Per slot: contact point and previous force (see [`McState::slot_loads`]).
    pub(super) loads: &'a [ContactLoad],
    pub(super) step: u64,
    /// Accuracy budget EPS (0: exact).
    pub(super) accuracy: f64,
}

impl McCtx<'_> {
    /// [`McCtx::kernel`] of all particles on the members of `team`, each on a consecutive range
    /// of particles with about equal numbers of contacts (the kernel's cost grows with them).
    /// Every particle's result is the one of a serial pass, and of several failures the lowest
    /// particle's is reported (the lowest member's, whose range comes first).
    pub(super) fn kernel_on(
        &self,
        team: &Team,
        dr: &mut [f64],
        kept: Option<&mut [KeptInfluence]>,
        tolerance: f64,
        budget: Option<&mut [KeptExact]>,
    ) -> Result<McCounts, StepError> {
        let n = self.slot_start.len() - 1;
        let (size, total) = (team.size(), self.slot_start[n] as usize);
        debug_assert_eq!(self.slot_start[0], 0);
        let cut = |k: usize| {
            if k >= size {
                n
            } else {
                self.slot_start[..n].partition_point(|&s| (s as usize) * size < k * total)
            }
        };
        let (dr, kept, budget) = (SplitMut::new(dr), kept.map(SplitMut::new), budget.map(SplitMut::new));
        let counts = Mutex::new(McCounts::default());
        team.run(|k| {
            let (lo, hi) = (cut(k), cut(k + 1));
            let slots = self.slot_start[lo] as usize..self.slot_start[hi] as usize;
            // SAFETY: `cut` does not decrease with k, so the members' particle ranges lo..hi are
            // disjoint, and with them their slots, kept matrices and budget references.
            let (d, kp, bu) = unsafe {
                (
                    dr.range(slots),
                    kept.as_ref().map(|v| v.range(lo..hi)),
                    budget.as_ref().map(|v| v.range(lo..hi)),
                )
            };
            let c = self.kernel(lo, hi, d, kp, tolerance, bu)?;
            let mut sum = counts.lock().unwrap_or_else(|p| p.into_inner());
            sum.contacts += c.contacts;
            sum.fallbacks += c.fallbacks;
            sum.recomputed += c.recomputed;
            sum.multi += c.multi;
            sum.worst = sum.worst.max(c.worst);
            Ok(())
        })?;
        Ok(counts.into_inner().unwrap_or_else(|p| p.into_inner()))
    }

    /// Radius changes of particles lo..hi into `dr` (exactly their slots), kept matrices in
    /// `kept` (exactly those particles) under a geometry tolerance; of several failures the
    /// lowest particle's is reported.
    pub(super) fn kernel(
        &self,
        lo: usize,
        hi: usize,
        dr: &mut [f64],
        kept: Option<&mut [KeptInfluence]>,
        tolerance: f64,
        budget: Option<&mut [KeptExact]>,
    ) -> Result<McCounts, StepError> {
        MC_SCRATCH.with(|buf| {
            let fb_buf = &mut *buf.borrow_mut();
            let mut counts = McCounts::default();
            let mut kept = kept;
            let mut budget = budget;
            let base = self.slot_start[lo] as usize;
            for i in lo..hi {
                let (s0, s1) = (self.slot_start[i] as usize, self.slot_start[i + 1] as usize);
                let out = &mut dr[s0 - base..s1 - base];
                if s1 - s0 < 2 {
                    out.fill(0.0);
                    continue;
                }
                let loads = &self.loads[s0..s1];
                let m = self.mc_types[self.p.typ[i]].material;
                let params = McParams {
                    radius: self.p.radius[i],
                    youngs_modulus: m.youngs_modulus,
                    poisson_ratio: m.poisson_ratio,
                    gamma: m.gamma,
                    cap: m.cap,
                };
                let nl = loads.len();
                if fb_buf.len() < nl {
                    fb_buf.resize(nl, false);
                }
                // The particle's slots are its contacts in order: Δ goes straight into them.
                let fb = &mut fb_buf[..nl];
                if let Some(b) = budget.as_deref_mut() {
                    // The accuracy budget: reuse the reference while its bound stays in budget.
                    let (bp, k) = (BudgetParams::new(params), &mut b[i - lo]);
                    counts.multi += 1;
                    let keep = match k.decide(&bp, loads, self.accuracy) {
                        Decision::Reuse(used) => {
                            out.copy_from_slice(k.dr());
                            counts.worst = counts.worst.max(used);
                            continue;
                        }
                        Decision::Exact { keep } => keep,
                    };
                    let summary = radius_changes(&params, loads, out, fb).map_err(|e| self.failed(i, e))?;
                    if keep {
                        k.store(&bp, loads, out, summary.fallbacks > 0);
                    }
                    counts.contacts += nl as u64;
                    counts.fallbacks += summary.fallbacks as u64;
                    counts.recomputed += 1;
                    continue;
                }
                let res = match kept.as_deref_mut() {
                    Some(k) => {
                        if let Some(next) = k.get(i - lo + 1) {
                            next.prefetch();
                        }
                        k[i - lo].radius_changes(tolerance, &params, loads, out, fb)
                    }
                    None => radius_changes(&params, loads, out, fb).map(|s| (s, false)),
                };
                let (summary, recomputed) = res.map_err(|e| self.failed(i, e))?;
                counts.contacts += nl as u64;
                counts.fallbacks += summary.fallbacks as u64;
                counts.recomputed += u64::from(recomputed);
            }
            Ok(counts)
        })
    }

    /// The stop of a kernel call that failed at particle `i`.
    fn failed(&self, i: usize, e: crate::physics::contact_set::KernelError) -> StepError {
        StepError {
            step: self.step,
            particle: self.p.id[i],
            cause: format!("multi-contact kernel: {e}"),
            contact: None,
        }
    }
}
