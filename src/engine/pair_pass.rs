//! The pair stage: every candidate pair's contact force, by one of three strategies that give
//! the same sums bit for bit (every particle receives its terms in pair order).

use crate::physics::hertz::Tangential;
use crate::physics::pair::PairLanes;
use crate::physics::{NormalLaw, PairCoeffs, RollingLaw, Vec3};
use crate::team::SplitMut;

use super::blocks::{BALANCE_PASSES, MAX_PAIR_BLOCKS, MIN_BLOCK_PAIRS};
use super::pair_eval::{ContactHistory, PairCtx};
use super::sinks::{Keep, OwnedSums, PairOut, SharedSums, SumInto};
use super::{StepError, World};

/// Buffers of the pair pass, kept between steps (no allocation in the loop).
#[derive(Debug, Default)]
pub(super) struct PairScratch {
    pub(super) pair_out: Vec<PairOut>,
    pub(super) f_buf: Vec<Vec3>,
    pub(super) t_buf: Vec<Vec3>,
}

/// How this step's pair pass runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum PairStrategy {
    /// In pair order on the calling thread (no team, or too few pairs for two blocks).
    Serial,
    /// One block of pairs per member, adding straight into the sums of the particles it owns and
    /// deferring its terms to the others, added after the blocks in block then pair order
    /// ([`World::assign_owners`]).
    OwnedBlocks { blocks: usize },
    /// Equal shares of the pairs per member, every pair's result kept; then each particle sums
    /// its own pairs' results in pair order (when too many pair ends are shared for the blocks).
    KeepAll,
}

impl World {
    /// The strategy of this step's pair pass on `threads` threads, with the blocks or incidence
    /// rows it needs brought up to date. Threads, when the timing probe says they pay: one block
    /// of pairs each (more blocks share more particles, whose sums are deferred), none below two
    /// blocks' worth of pairs.
    fn pair_strategy(&mut self, threads: usize) -> PairStrategy {
        let n = self.p.len();
        let blocks = threads.min(self.contacts.pairs.len() / MIN_BLOCK_PAIRS).min(MAX_PAIR_BLOCKS);
        let threaded = threads > 1 && blocks > 1;
        if threaded && self.blocks.owner_key != Some((self.contacts.pairs.len(), blocks, n)) {
            self.assign_owners(blocks);
        }
        if threaded
            && !self.blocks.owned_blocks_pay
            && (self.blocks.inc_start.len() != n + 1
                || self.blocks.inc.len() != 2 * self.contacts.pairs.len())
        {
            // After every neighbour build, and when particles were added since.
            self.build_incidence();
        }
        match (threaded, self.blocks.owned_blocks_pay) {
            (false, _) => PairStrategy::Serial,
            (true, true) => PairStrategy::OwnedBlocks { blocks },
            (true, false) => PairStrategy::KeepAll,
        }
    }

    /// Whether the pair and wall passes evaluate in vectorised batches: they evaluate `tangential
    /// history` and the Hertz law with the radii of docs/spec.md §2; the LIGGGHTS `surface
    /// multicontact` radii, `no_history`, `model hooke`, cohesion and rolling friction take the pair-by-pair path.
    pub(super) fn batched(&self) -> bool {
        let plain = |c: &PairCoeffs| {
            c.tangential == Tangential::History
                && c.normal == NormalLaw::Hertz
                && c.cohesion == 0.0
                && c.rolling_friction == 0.0
        };
        !self.liggghts_radii
            && self.coeffs.iter().all(plain)
            && self.wall_coeffs.as_ref().is_none_or(|w| w.iter().all(plain))
            && PairLanes::vectorised()
    }

    /// The pair law keeps a history value per contact (`hooke/hysteresis`).
    pub(super) fn normal_history(&self) -> bool {
        self.coeffs.iter().any(|c| c.normal.has_history())
    }

    /// The pairs' rolling model keeps a spring per contact (`epsd`, `epsd2`).
    pub(super) fn rolling_history(&self) -> bool {
        self.coeffs.iter().any(|c| c.rolling_friction > 0.0 && matches!(c.rolling_law, RollingLaw::Spring(_)))
    }

    /// Pair forces and torques into every particle's sums (from zero), each pair's force recorded
    /// for the outputs, and on a time step (`update`) the pairs' histories advanced. `mc`: the
    /// multi-contact closure is on (its radius changes are read, its state kept).
    pub(super) fn pair_pass(
        &mut self,
        update: bool,
        mc: bool,
        threads: usize,
        batched: bool,
    ) -> Result<(), StepError> {
        // A law with a per-pair history runs on one thread: its history array is not split into
        // the threads' shares (the decks that use it are small).
        let hist = self.normal_history() || self.rolling_history();
        let strategy = if hist { PairStrategy::Serial } else { self.pair_strategy(threads) };
        let np = self.contacts.pairs.len();
        if !self.normal_history() {
            self.contacts.pair_dmax.clear();
        } else if self.contacts.pair_dmax.len() != np {
            // A law that starts now finds every pair new.
            self.contacts.pair_dmax.clear();
            self.contacts.pair_dmax.resize(np, 0.0);
        }
        if !self.rolling_history() {
            self.contacts.pair_roll.clear();
        } else if self.contacts.pair_roll.len() != np {
            self.contacts.pair_roll.clear();
            self.contacts.pair_roll.resize(np, Vec3::zeros());
        }
        if !mc {
            // Hertz keeps no closure state: a closure that starts later finds every pair new.
            self.contacts.pair_hist.clear();
        }
        // Every entry is overwritten below: only the length has to match (no per-step fill).
        if self.contacts.pair_force.len() != np {
            self.contacts.pair_force.resize(np, Vec3::zeros());
        }
        match strategy {
            PairStrategy::Serial => self.pairs_serial(update, mc, batched),
            PairStrategy::OwnedBlocks { blocks } => self.pairs_owned_blocks(update, mc, batched, blocks),
            PairStrategy::KeepAll => self.pairs_keep_all(update, mc, batched),
        }
    }

    /// [`PairStrategy::Serial`]. The threaded strategies add in this order too: identical sums.
    fn pairs_serial(&mut self, update: bool, mc: bool, batched: bool) -> Result<(), StepError> {
        let n = self.p.len();
        let ctx = PairCtx::new(
            &self.p,
            &self.coeffs,
            self.ntypes,
            self.domain.expect("domain checked in setup"),
            self.dt,
            update,
            self.step,
            self.liggghts_radii,
        );

        // The threaded passes add in this order too: identical sums.
        let (f, torque) = (&mut self.pair_scratch.f_buf, &mut self.pair_scratch.t_buf);
        f.clear();
        f.resize(n, Vec3::zeros());
        torque.clear();
        torque.resize(n, Vec3::zeros());
        let mut sums = SumInto { f, torque, force: &mut self.contacts.pair_force };
        let closure = mc.then_some((&self.contacts.pair_dr[..], &mut self.contacts.pair_hist[..]));
        let np = self.contacts.pairs.len();
        let history = ContactHistory::of(&mut self.contacts.pair_dmax, &mut self.contacts.pair_roll, np);
        ctx.pass(&mut self.contacts.pairs, closure, history, batched, &mut sums).map_err(|e| *e)?;
        std::mem::swap(&mut self.p.f, &mut self.pair_scratch.f_buf);
        std::mem::swap(&mut self.p.torque, &mut self.pair_scratch.t_buf);
        Ok(())
    }

    /// [`PairStrategy::OwnedBlocks`] on the team: member b takes block b.
    fn pairs_owned_blocks(
        &mut self,
        update: bool,
        mc: bool,
        batched: bool,
        blocks: usize,
    ) -> Result<(), StepError> {
        let n = self.p.len();
        let ctx = PairCtx::new(
            &self.p,
            &self.coeffs,
            self.ntypes,
            self.domain.expect("domain checked in setup"),
            self.dt,
            update,
            self.step,
            self.liggghts_radii,
        );

        self.blocks.threaded_passes.0 += 1;
        let team = self.blocks.team.as_ref().expect("threads() started the team");
        let (f, torque) = (&mut self.pair_scratch.f_buf, &mut self.pair_scratch.t_buf);
        f.resize(n, Vec3::zeros());
        torque.resize(n, Vec3::zeros());
        {
            // Cleared by the members, each its own particles: the lines then sit in the
            // cache of the core that adds into most of them next.
            let (fs, ts) = (SplitMut::new(f), SplitMut::new(torque));
            team.for_shares(n, |_, r| {
                // SAFETY: the members' shares are disjoint ranges of particles.
                unsafe { (fs.range(r.clone()).fill(Vec3::zeros()), ts.range(r).fill(Vec3::zeros())) };
            });
        }
        let sums = SharedSums { f: f.as_mut_ptr(), torque: torque.as_mut_ptr(), n };
        // Every list emptied first: a block without pairs (fewer runs than blocks) adds none.
        self.blocks.deferred.iter_mut().for_each(Vec::clear);
        // Member b takes block b: its pairs, radius changes, recorded forces and deferrals,
        // and times itself for `balance_blocks`.
        let (owner, cuts) = (&self.blocks.owner, &self.blocks.pair_cuts);
        let (pairs, forces) =
            (SplitMut::new(&mut self.contacts.pairs), SplitMut::new(&mut self.contacts.pair_force));
        let deferred = SplitMut::new(&mut self.blocks.deferred[..blocks]);
        let block_ns = SplitMut::new(&mut self.blocks.block_ns[..blocks]);
        let (drs, hists) = (&self.contacts.pair_dr, SplitMut::new(&mut self.contacts.pair_hist));
        team.run(|b| {
            if b >= blocks {
                return Ok(());
            }
            let t0 = std::time::Instant::now();
            let r = cuts[b]..cuts[b + 1];
            // SAFETY: the cuts do not decrease, so each member has its own range of pairs,
            // and its own block.
            let (prs, force, deferred, ns) = unsafe {
                let d = &mut deferred.range(b..b + 1)[0];
                (pairs.range(r.clone()), forces.range(r.clone()), d, &mut block_ns.range(b..b + 1)[0])
            };
            // SAFETY: as the pairs.
            let closure = mc.then(|| (&drs[r.clone()], unsafe { hists.range(r) }));
            let mut sink = OwnedSums { sums, owner, block: b as u16, deferred, force };
            let res = ctx.pass(prs, closure, None, batched, &mut sink);
            *ns += t0.elapsed().as_nanos() as u64;
            res
        })
        .map_err(|e| *e)?;
        // Later blocks' contributions to shared particles, in block then pair order: the
        // serial pass's order.
        for d in self.blocks.deferred.iter().flatten() {
            self.pair_scratch.f_buf[d.p as usize] += d.f;
            self.pair_scratch.t_buf[d.p as usize] += d.torque;
        }
        std::mem::swap(&mut self.p.f, &mut self.pair_scratch.f_buf);
        std::mem::swap(&mut self.p.torque, &mut self.pair_scratch.t_buf);
        // After the deferred ends are added: a new assignment clears their lists.
        self.blocks.block_passes += 1;
        if self.blocks.block_passes >= BALANCE_PASSES {
            self.balance_blocks();
        }
        Ok(())
    }

    /// [`PairStrategy::KeepAll`] on the team.
    fn pairs_keep_all(&mut self, update: bool, mc: bool, batched: bool) -> Result<(), StepError> {
        let (n, np) = (self.p.len(), self.contacts.pairs.len());
        let ctx = PairCtx::new(
            &self.p,
            &self.coeffs,
            self.ntypes,
            self.domain.expect("domain checked in setup"),
            self.dt,
            update,
            self.step,
            self.liggghts_radii,
        );

        self.blocks.threaded_passes.1 += 1;
        if self.pair_scratch.pair_out.len() != np {
            self.pair_scratch.pair_out.resize(np, PairOut::default());
        }
        let team = self.blocks.team.as_ref().expect("threads() started the team");
        {
            let (pairs, outs) =
                (SplitMut::new(&mut self.contacts.pairs), SplitMut::new(&mut self.pair_scratch.pair_out));
            let forces = SplitMut::new(&mut self.contacts.pair_force);
            let (drs, hists) = (&self.contacts.pair_dr, SplitMut::new(&mut self.contacts.pair_hist));
            team.run_shares(np, |_, r| {
                // SAFETY: the members' shares are disjoint ranges of pairs.
                let (prs, outs, force, closure) = unsafe {
                    let closure = mc.then(|| (&drs[r.clone()], hists.range(r.clone())));
                    (pairs.range(r.clone()), outs.range(r.clone()), forces.range(r), closure)
                };
                ctx.pass(prs, closure, None, batched, &mut Keep { outs, force })
            })
            .map_err(|e| *e)?;
        }
        // Each particle sums its own pairs' results in pair order, as the serial pass adds
        // them (from zero: the sums were cleared above): no write is shared between threads.
        let (start, inc, outs) = (&self.blocks.inc_start, &self.blocks.inc, &self.pair_scratch.pair_out);
        let (fs, ts) = (SplitMut::new(&mut self.p.f), SplitMut::new(&mut self.p.torque));
        team.for_shares(n, |_, r| {
            // SAFETY: the members' shares are disjoint ranges of particles.
            let (fs, ts) = unsafe { (fs.range(r.clone()), ts.range(r.clone())) };
            for (i, (f, t)) in r.zip(fs.iter_mut().zip(ts.iter_mut())) {
                let (mut fa, mut ta) = (Vec3::zeros(), Vec3::zeros());
                for &e in &inc[start[i] as usize..start[i + 1] as usize] {
                    let out = &outs[(e >> 1) as usize];
                    if out.touching {
                        if e & 1 == 0 {
                            fa += out.force;
                            ta += out.torque_i;
                        } else {
                            fa -= out.force;
                            ta += out.torque_j;
                        }
                    }
                }
                (*f, *t) = (fa, ta);
            }
        });
        Ok(())
    }
}
