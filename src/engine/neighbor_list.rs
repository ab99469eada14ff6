//! The neighbour stage: the skin test, the rebuild of the pair list (periodic wrap, history carried
//! over) and the spatial sort of the particles.

use crate::physics::Vec3;

use super::contacts::{Pair, PairHist, RECEIVER_GAP};
use super::neighbor::CellList;
use super::{Closure, Domain, StepError, World};

/// The neighbour stage's state: cell list, candidates, and what the skin test compares with.
#[derive(Debug, Default)]
pub(super) struct NeighborList {
    pub(super) next_sort: u64,

    pub(super) cells: CellList,
    pub(super) cand: Vec<(u32, u32)>,
    pub(super) x_build: Vec<Vec3>,
    pub(super) need_build: bool,
    /// Lees–Edwards offset travelled since the last neighbour build (not wrapped) [m].
    pub(super) le_travel: f64,
    /// Interaction cutoff without skin, 2 r_max × pair_reach, at the last build [m].
    pub(super) cut_build: f64,
    /// Radii at the last build, and the largest growth of one since (set by
    /// [`World::radii_changed`]; 0 while radii stay fixed) [m].
    pub(super) r_build: Vec<f64>,
    pub(super) growth: f64,
}

impl World {
    /// Rebuilds the neighbour list when a pair could have closed the skin since the last build
    /// (or on request). Without shear that is LAMMPS' test, some particle moved more than skin/2.
    /// Under Lees–Edwards shear each particle's displacement is split into the affine streaming
    /// part at its build position, γ (y_build − y_mid) x̂ for the strain γ since the build, and
    /// the rest (the fluctuation, largest m). Two particles that can touch now are less than the
    /// cutoff r_c + 2m apart in y, so their separation changed by at most 2m + γ (r_c + 2m); the
    /// image across the sheared boundary moves with the offset, which cancels the streaming jump
    /// there. Rebuilding when that bound reaches the skin keeps the list complete, and the
    /// interval no longer shrinks with the box size: the lab displacement of particles near the
    /// boundary grows with L_y, the relative motion of neighbours does not.
    pub(super) fn neighbor_check(&mut self) -> Result<(), StepError> {
        if !self.lists.need_build && !self.rebuild_every_step {
            let Some(domain) = self.domain else { return Ok(()) };
            // Lees–Edwards strain since the build (0 without shear).
            let strain = if self.lists.le_travel == 0.0 {
                0.0
            } else {
                self.lists.le_travel / (domain.hi.y - domain.lo.y)
            };
            // A pair left out of the list was a skin apart beyond its radii at the build; radius
            // growth g closes that gap like motion does, so each particle may travel only
            // skin/2 - g (g the largest growth of any radius since the build).
            let growth = self.lists.growth;
            let moved = if strain == 0.0 {
                let half = 0.5 * self.skin - growth;
                half <= 0.0
                    || self
                        .p
                        .x
                        .iter()
                        .zip(&self.lists.x_build)
                        .any(|(x, x0)| (x - x0).norm_squared() > half * half)
            } else {
                let ymid = 0.5 * (domain.lo.y + domain.hi.y);
                let m2 = self
                    .p
                    .x
                    .iter()
                    .zip(&self.lists.x_build)
                    .map(|(x, x0)| {
                        let mut d = x - x0;
                        d.x -= strain * (x0.y - ymid);
                        d.norm_squared()
                    })
                    .fold(0.0, f64::max);
                let m = m2.sqrt() + growth;
                2.0 * m + strain.abs() * (self.lists.cut_build + 2.0 * m) > self.skin
            };
            if !moved {
                return Ok(());
            }
        }
        self.lists.need_build = false;
        self.builds += 1;
        let domain = self.domain.expect("domain checked in setup");
        // Periodic wrap and lost-particle check happen at rebuilds, as in LAMMPS. y first: a
        // Lees–Edwards crossing shifts x, which is then wrapped too.
        for i in 0..self.p.len() {
            for a in [1, 0, 2] {
                let (lo, hi) = (domain.lo[a], domain.hi[a]);
                let xi = &mut self.p.x[i];
                let x = &mut xi[a];
                if domain.periodic[a] {
                    let l = hi - lo;
                    let mut crossed = 0.0;
                    while *x >= hi {
                        *x -= l;
                        self.p.image[i][a] += 1;
                        crossed -= 1.0;
                    }
                    while *x < lo {
                        *x += l;
                        self.p.image[i][a] -= 1;
                        crossed += 1.0;
                    }
                    if a == 1 && crossed != 0.0 {
                        // Leaving through the top of a sheared box: back in at the bottom,
                        // shifted and slowed by the image's offset and velocity jump.
                        xi.x += crossed * domain.le_offset;
                        self.p.v[i].x += crossed * domain.le_vjump;
                    }
                } else if !(*x >= lo && *x <= hi) {
                    return Err(StepError {
                        step: self.step,
                        particle: self.p.id[i],
                        cause: format!(
                            "left the box along {} (coordinate {:e} m outside [{:e}, {:e}]): lost particle",
                            ["x", "y", "z"][a],
                            *x,
                            lo,
                            hi
                        ),
                        contact: None,
                    });
                }
            }
        }
        // The pair cutoff without skin, read by the sort's bins and by the next rebuild test.
        self.lists.cut_build = 2.0 * self.p.radius.iter().copied().fold(0.0, f64::max) * self.pair_reach();
        if self.sort_every > 0 && self.step >= self.lists.next_sort {
            self.sort_spatially(&domain);
            self.lists.next_sort = self.step + self.sort_every;
        }
        self.lists.cells.build(
            &domain,
            &self.p.x,
            &self.p.radius,
            self.skin,
            self.pair_reach(),
            &mut self.lists.cand,
        );
        // Carry the history over: both lists are sorted by (i, j). The closure's state rides
        // along when it is kept (a closure that starts later finds every pair new).
        std::mem::swap(&mut self.contacts.pairs, &mut self.contacts.pairs_old);
        std::mem::swap(&mut self.contacts.pair_hist, &mut self.contacts.pair_hist_old);
        self.contacts.pairs.clear();
        self.contacts.pair_hist.clear();
        let keep_hist = self.closure == Some(Closure::MultiContact);
        let old_hist = self.contacts.pair_hist_old.len() == self.contacts.pairs_old.len();
        // The normal law's history rides along the same way.
        std::mem::swap(&mut self.contacts.pair_dmax, &mut self.contacts.pair_dmax_old);
        self.contacts.pair_dmax.clear();
        let keep_dmax = self.normal_history();
        let old_dmax = self.contacts.pair_dmax_old.len() == self.contacts.pairs_old.len();
        // And the rolling spring.
        std::mem::swap(&mut self.contacts.pair_roll, &mut self.contacts.pair_roll_old);
        self.contacts.pair_roll.clear();
        let keep_roll = self.rolling_history();
        let old_roll = self.contacts.pair_roll_old.len() == self.contacts.pairs_old.len();
        let mut k = 0;
        for &(i, j) in &self.lists.cand {
            while k < self.contacts.pairs_old.len()
                && (self.contacts.pairs_old[k].i, self.contacts.pairs_old[k].j) < (i, j)
            {
                k += 1;
            }
            let old = self.contacts.pairs_old.get(k).filter(|o| o.i == i && o.j == j);
            self.contacts.pairs.push(old.copied().unwrap_or(Pair { i, j, shear: Vec3::zeros() }));
            if keep_hist {
                let h = old.filter(|_| old_hist).map(|_| self.contacts.pair_hist_old[k]);
                self.contacts.pair_hist.push(h.unwrap_or(PairHist::NEW));
            }
            if keep_dmax {
                let h = old.filter(|_| old_dmax).map(|_| self.contacts.pair_dmax_old[k]);
                self.contacts.pair_dmax.push(h.unwrap_or(0.0));
            }
            if keep_roll {
                let h = old.filter(|_| old_roll).map(|_| self.contacts.pair_roll_old[k]);
                self.contacts.pair_roll.push(h.unwrap_or(Vec3::zeros()));
            }
        }
        self.multi.slots_stale = true;
        self.blocks.owner_key = None;
        // The incidence rows are built when the threaded pass first needs them.
        self.blocks.inc.clear();
        self.lists.x_build.clear();
        self.lists.x_build.extend_from_slice(&self.p.x);
        self.lists.r_build.clear();
        self.lists.r_build.extend_from_slice(&self.p.radius);
        self.lists.growth = 0.0;
        self.lists.le_travel = 0.0;
        Ok(())
    }

    /// To be called after particle radii changed between the neighbour check and the forces of a
    /// step (a deck's `fix adapt`): the skin test learns how far radii grew since the last build,
    /// and the list is rebuilt now if that growth alone could already let a pair left out of it
    /// touch (so the forces of this step see every contact, however fast the radii grow); the
    /// time step is checked against the Rayleigh time of the new sizes.
    pub fn radii_changed(&mut self) -> Result<(), StepError> {
        let growth = if self.lists.r_build.len() == self.p.len() {
            self.p.radius.iter().zip(&self.lists.r_build).map(|(r, r0)| r - r0).fold(0.0, f64::max)
        } else {
            // Particles added since the build: a rebuild is due anyway.
            self.lists.need_build = true;
            0.0
        };
        self.lists.growth = growth;
        if let Some((t_r, i)) = self.rayleigh_worst() {
            if self.dt > t_r {
                return Err(StepError {
                    step: self.step,
                    particle: self.p.id[i],
                    cause: format!(
                        "after a radius change the time step {:e} s is above the Rayleigh time {:e} s: the run would be unstable",
                        self.dt, t_r
                    ),
                    contact: None,
                });
            }
        }
        if self.lists.need_build || growth >= 0.5 * self.skin {
            self.lists.need_build = true;
        }
        // Runs the skin test with the new growth: rebuilds when motion and growth together reach
        // half a skin.
        self.neighbor_check()
    }

    /// Centre distance, as a multiple of r_i + r_j, out to which a pair can matter: touching
    /// (Hertz), or receiving multi-contact radius changes (within RECEIVER_GAP; a pair further
    /// apart gets none and cannot touch). The neighbour list needs no more, whatever `mc_range`
    /// asks for: wider lists only cost memory traffic.
    pub(super) fn pair_reach(&self) -> f64 {
        match self.closure {
            Some(Closure::MultiContact) => self.mc_range.min(1.0 + RECEIVER_GAP),
            _ => 1.0,
        }
    }

    /// Renumbers the particles bin by bin in row-major order (x fastest, as LAMMPS' `atom_modify
    /// sort`), bins half a neighbour cutoff wide, and remaps everything keyed by particle index:
    /// pair history (a pair whose indices change order is turned round), wall contacts and kept
    /// influence matrices. Positions must be inside the box (called after the periodic wrap) and
    /// `cut_build` current. The physics is unchanged; only summation orders, hence round-off,
    /// differ from an unsorted run.
    ///
    /// Why row-major and not a space-filling curve: the pair loop walks particle i in index order
    /// and touches each partner j > i. In row-major order every partner lies at most about one
    /// xy-layer of bins ahead (N^(2/3) particles), and the partners' indices rise steadily with i,
    /// so the hardware prefetcher follows them. A Morton order keeps most partners closer but
    /// sends a fraction across its coarse blocks, up to N/2 ahead, and each of those loads misses
    /// the cache: on the 97 556-particle packing it measured 20-25 % slower per particle-step.
    pub(super) fn sort_spatially(&mut self, domain: &Domain) {
        let n = self.p.len();
        if n < 2 {
            return;
        }
        let bin = 0.5 * (self.lists.cut_build + self.skin);
        let len = domain.hi - domain.lo;
        // Bins per axis; coarser bins only for absurdly large boxes (the key must fit 64 bits).
        let bins = |a: usize| ((len[a] / bin).ceil().clamp(1.0, (1u64 << 21) as f64)) as u64;
        let nb = [bins(0), bins(1), bins(2)];
        let mut keys: Vec<(u64, u32)> = (0..n)
            .map(|i| {
                let x = self.p.x[i];
                let b = |a: usize| {
                    let s = ((x[a] - domain.lo[a]) / len[a]).clamp(0.0, 1.0);
                    ((s * nb[a] as f64) as u64).min(nb[a] - 1)
                };
                ((b(2) * nb[1] + b(1)) * nb[0] + b(0), i as u32)
            })
            .collect();
        keys.sort_unstable();
        if keys.iter().enumerate().all(|(k, &(_, o))| k == o as usize) {
            return;
        }
        let old_of_new: Vec<u32> = keys.iter().map(|&(_, o)| o).collect();
        let mut new_of_old = vec![0u32; n];
        for (k, &o) in old_of_new.iter().enumerate() {
            new_of_old[o as usize] = k as u32;
        }
        self.p.permute(&old_of_new);
        for (k, pr) in self.contacts.pairs.iter_mut().enumerate() {
            let (a, b) = (new_of_old[pr.i as usize], new_of_old[pr.j as usize]);
            if a < b {
                (pr.i, pr.j) = (a, b);
            } else {
                // The same contact seen from the other particle: the history is i's tangential
                // displacement relative to j, so it changes sign; the radii trade places.
                (pr.i, pr.j) = (b, a);
                pr.shear = -pr.shear;
                if let Some(h) = self.contacts.pair_hist.get_mut(k) {
                    std::mem::swap(&mut h.ri_prev, &mut h.rj_prev);
                }
                // The rolling spring is the torque on j (−M on i), built from ω_i − ω_j: it
                // changes sign too.
                if let Some(m) = self.contacts.pair_roll.get_mut(k) {
                    *m = -*m;
                }
            }
        }
        if self.contacts.pair_dmax.len() == self.contacts.pairs.len() {
            // The largest overlap is the same seen from either particle; it follows its pair.
            let mut order: Vec<u32> = (0..self.contacts.pairs.len() as u32).collect();
            order.sort_unstable_by_key(|&k| {
                (self.contacts.pairs[k as usize].i, self.contacts.pairs[k as usize].j)
            });
            self.contacts.pair_dmax = order.iter().map(|&k| self.contacts.pair_dmax[k as usize]).collect();
        } else {
            self.contacts.pair_dmax.clear();
        }
        if self.contacts.pair_roll.len() == self.contacts.pairs.len() {
            // The rolling spring follows its pair the same way.
            let mut order: Vec<u32> = (0..self.contacts.pairs.len() as u32).collect();
            order.sort_unstable_by_key(|&k| {
                (self.contacts.pairs[k as usize].i, self.contacts.pairs[k as usize].j)
            });
            self.contacts.pair_roll = order.iter().map(|&k| self.contacts.pair_roll[k as usize]).collect();
        } else {
            self.contacts.pair_roll.clear();
        }
        if self.contacts.pair_hist.len() == self.contacts.pairs.len() {
            // One permutation for both lists.
            let mut order: Vec<u32> = (0..self.contacts.pairs.len() as u32).collect();
            order.sort_unstable_by_key(|&k| {
                (self.contacts.pairs[k as usize].i, self.contacts.pairs[k as usize].j)
            });
            self.contacts.pairs = order.iter().map(|&k| self.contacts.pairs[k as usize]).collect();
            self.contacts.pair_hist = order.iter().map(|&k| self.contacts.pair_hist[k as usize]).collect();
        } else {
            self.contacts.pair_hist.clear();
            self.contacts.pairs.sort_unstable_by_key(|pr| (pr.i, pr.j));
        }
        for c in &mut self.contacts.wc {
            c.p = new_of_old[c.p as usize];
        }
        self.contacts.wc.sort_unstable_by_key(|c| c.key());
        if let Some(cache) = self.multi.mc_cache.as_mut() {
            cache.reorder(&old_of_new);
        }
        if !self.multi.budget.is_empty() {
            super::mc_budget::reorder(&mut self.multi.budget, &old_of_new);
        }
        self.multi.slots_stale = true;
        self.sorts += 1;
    }
}
