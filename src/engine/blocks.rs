//! Thread blocks of the force passes: the team, the pair blocks that own their particles (with
//! measured rebalancing), and the per-particle incidence rows of the keep-every-result pass.

use std::time::{Duration, Instant};

use crate::team::{share, Team};

use super::probe::{self, ThreadProbe};
use super::sinks::Deferred;
use super::World;

/// The threads of the force passes and how the work is cut between them.
#[derive(Debug, Default)]
pub(super) struct Blocks {
    /// Per particle, its pairs (see `build_incidence`), as compressed rows.
    pub(super) inc_start: Vec<u32>,
    pub(super) inc: Vec<u32>,
    /// Scratch of `build_incidence`: the next free entry of each particle's row.
    pub(super) inc_fill: Vec<u32>,
    /// Threaded pair pass: per particle, the block of pairs that writes its sums directly (the
    /// first block, in pair order, with a pair on it; see [`World::assign_owners`]).
    pub(super) owner: Vec<u16>,
    /// (pairs, blocks, particles) the owners were computed for; None after a neighbour build.
    pub(super) owner_key: Option<(usize, usize, usize)>,
    /// Where the blocks of the owning threaded pass start in the pair list (and the end): equal
    /// runs after each assignment, then moved by [`World::balance_blocks`] to even out the
    /// members' measured times.
    pub(super) pair_cuts: Vec<usize>,
    /// Per block, nanoseconds spent in the threaded pair pass since the last balancing, and the
    /// passes counted.
    pub(super) block_ns: Vec<u64>,
    pub(super) block_passes: u32,
    /// Few enough pair ends fall on particles another block owns for the blocks to pay (else the
    /// threaded pass keeps every pair's result and sums per particle afterwards).
    pub(super) owned_blocks_pay: bool,
    /// Threaded pair passes so far: (by owned blocks, keeping every pair's result).
    pub(super) threaded_passes: (u64, u64),
    /// Threaded pair pass: per block, its contributions to particles another block owns, in pair
    /// order (kept between steps: no allocation in the loop once grown).
    pub(super) deferred: Vec<Vec<Deferred>>,
    /// This step's force passes and half-kicks run on the team (set every step from
    /// [`World::pair_threads`] and the timing probe).
    pub(super) parallel: bool,
    /// When `PairThreads::Auto` times steps with and without threads, and what it measured.
    pub(super) probe: ThreadProbe,
    /// The threads of the threaded passes (`rayon::current_num_threads()` members, started at
    /// the first threaded step and kept for the run).
    pub(super) team: Option<Team>,
    /// Per member of the threaded wall pass: its first wall contact and first particle (and
    /// after the last member, the ends).
    pub(super) wall_cuts: Vec<[usize; 2]>,
}

/// The probe's timing of one step: started before the first stage when the probe times this
/// step, with what [`StepTimer::leave_out`] excluded.
#[derive(Debug)]
pub(super) struct StepTimer {
    start: Option<Instant>,
    left_out: Duration,
}

impl StepTimer {
    /// Runs `stage` outside the timed part of the step.
    pub(super) fn leave_out<T>(&mut self, stage: impl FnOnce() -> T) -> T {
        let t = self.start.is_some().then(Instant::now);
        let r = stage();
        self.left_out = t.map_or(Duration::ZERO, |t| t.elapsed());
        r
    }
}

impl Blocks {
    /// Decides whether this step's passes use the team (fixed by `mode`, or by the probe's plan
    /// under [`PairThreads::Auto`]) and starts the step's timer if the probe times it.
    pub(super) fn begin_step(&mut self, mode: PairThreads, step: u64) -> StepTimer {
        let plan = match mode {
            PairThreads::Auto => self.probe.plan(step),
            fixed => {
                self.parallel = fixed == PairThreads::Parallel;
                None
            }
        };
        if let Some(s) = plan {
            self.parallel = s.threads;
        }
        StepTimer { start: plan.filter(|s| s.timed).map(|_| Instant::now()), left_out: Duration::ZERO }
    }

    /// Gives the probe the step's time, and takes its choice when a comparison is complete.
    pub(super) fn end_step(&mut self, step: u64, timer: StepTimer) {
        if let Some(t0) = timer.start {
            let ns = t0.elapsed().saturating_sub(timer.left_out).as_nanos() as u64;
            if let Some(threads) = self.probe.record(step, ns) {
                self.parallel = threads;
            }
        }
    }
}

/// Whether the force passes of a step (pairs, wall contacts, the multi-contact kernel) run on the
/// threads' team ([`Team`], as many members as the rayon pool the step runs in has threads).
/// The results are bit-identical either way (every sum is taken in the serial order),
/// so this only decides speed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PairThreads {
    /// Time windows of steps with and without threads (alternating in slices) and keep the
    /// faster: every 5 000 steps, sooner after a choice of one core (`probe.rs`).
    #[default]
    Auto,
    Serial,
    Parallel,
}

/// Steps after which the first serial-vs-threads probe has decided (benchmarks warm up this long).
pub const THREAD_PROBE_STEPS: u64 = 2 * probe::WINDOW;

/// Fewest pairs in a block of the threaded pair pass, and most blocks (block indices are kept
/// in a `u16` per particle).
pub(super) const MIN_BLOCK_PAIRS: usize = 512;
pub(super) const MAX_PAIR_BLOCKS: usize = 64;

/// Owning threaded pair passes between two rebalancings of their blocks ([`World::balance_blocks`]).
pub(super) const BALANCE_PASSES: u32 = 200;

impl World {
    /// The team of the threaded passes when this step uses threads and there are several to use
    /// (as many members as the rayon pool the step runs in has threads), started on first use.
    pub(super) fn threads(&mut self) -> Option<&Team> {
        if !self.blocks.parallel {
            return None;
        }
        self.start_team()
    }

    /// The team, started if there is none of the pool's size yet; none on a one-thread pool.
    pub(super) fn start_team(&mut self) -> Option<&Team> {
        let size = rayon::current_num_threads();
        if size < 2 {
            return None;
        }
        if self.blocks.team.as_ref().is_none_or(|t| t.size() != size) {
            self.blocks.team = Some(Team::new(size));
        }
        self.blocks.team.as_ref()
    }

    /// Threaded pair passes so far: (by blocks that own their particles, keeping every pair's
    /// result and summing per particle afterwards). Both give the serial sums bit for bit; which
    /// one runs depends on how many pair ends the blocks share (`assign_owners`).
    pub fn threaded_passes(&self) -> (u64, u64) {
        self.blocks.threaded_passes
    }

    /// Splits the pairs into `blocks` equal runs ([`share`]) and gives each particle to the
    /// first block (in pair order) with a pair on it ([`World::own_blocks`]).
    pub(super) fn assign_owners(&mut self, blocks: usize) {
        let np = self.contacts.pairs.len();
        self.blocks.pair_cuts.clear();
        self.blocks.pair_cuts.extend((0..blocks).map(|b| share(np, blocks, b).start));
        self.blocks.pair_cuts.push(np);
        self.blocks.block_ns.clear();
        self.blocks.block_ns.resize(blocks, 0);
        self.blocks.block_passes = 0;
        self.own_blocks();
    }

    /// Moves the block boundaries so that each member's share of the pairs is proportional to
    /// the rate at which it evaluated them over the last [`BALANCE_PASSES`] passes (equal runs of
    /// pairs need not cost the same: touching pairs cost more than those apart, and the data a
    /// member reads may sit in the other core's cache), and reassigns the owners if a boundary
    /// moved by more than 1 % of the pairs. Where the boundaries lie changes nothing in the
    /// results: every particle still receives its terms in pair order.
    pub(super) fn balance_blocks(&mut self) {
        let np = self.contacts.pairs.len();
        let blocks = self.blocks.pair_cuts.len() - 1;
        let rate = |b: usize| {
            let len = (self.blocks.pair_cuts[b + 1] - self.blocks.pair_cuts[b]) as f64;
            len / (self.blocks.block_ns[b].max(1) as f64)
        };
        let total: f64 = (0..blocks).map(rate).sum();
        if !(total.is_finite() && total > 0.0) {
            return;
        }
        // Half-way to the balanced boundaries each time: the times are noisy. On the stack: at
        // most MAX_PAIR_BLOCKS + 1 boundaries.
        let mut buf = [0usize; MAX_PAIR_BLOCKS + 1];
        let cuts = &mut buf[..=blocks];
        cuts.copy_from_slice(&self.blocks.pair_cuts);
        let mut acc = 0.0;
        for b in 1..blocks {
            acc += rate(b - 1) / total;
            let target = 0.5 * (self.blocks.pair_cuts[b] as f64 + acc * np as f64);
            cuts[b] = (target.round() as usize).clamp(cuts[b - 1], np);
        }
        self.blocks.block_ns.iter_mut().for_each(|t| *t = 0);
        self.blocks.block_passes = 0;
        if cuts.iter().zip(&self.blocks.pair_cuts).any(|(a, b)| a.abs_diff(*b) * 100 > np) {
            self.blocks.pair_cuts.copy_from_slice(cuts);
            self.own_blocks();
        }
    }

    /// Gives each particle to the first block (in pair order, blocks as in `pair_cuts`) with a
    /// pair on it; particles on no pair get `u16::MAX` (nobody writes them).
    /// Every contribution a particle receives from its owner comes before any from later blocks,
    /// so the owner may add straight into the sums while later blocks defer theirs: the threaded
    /// pass then adds in exactly the serial order. With the particles sorted in space, only a
    /// thin layer at each block boundary is shared.
    pub(super) fn own_blocks(&mut self) {
        let (n, np, blocks) = (self.p.len(), self.contacts.pairs.len(), self.blocks.pair_cuts.len() - 1);
        self.blocks.owner.clear();
        self.blocks.owner.resize(n, u16::MAX);
        self.blocks.deferred.resize_with(blocks, Vec::new);
        let mut shared = 0;
        for b in 0..blocks {
            let block = &self.contacts.pairs[self.blocks.pair_cuts[b]..self.blocks.pair_cuts[b + 1]];
            let before = shared;
            for pr in block {
                for a in [pr.i as usize, pr.j as usize] {
                    if self.blocks.owner[a] == u16::MAX {
                        self.blocks.owner[a] = b as u16;
                    }
                    shared += usize::from(self.blocks.owner[a] != b as u16);
                }
            }
            // Room for every deferral the block can make, so the pair loop never grows the list.
            let d = &mut self.blocks.deferred[b];
            d.clear();
            d.reserve(shared - before);
        }
        // Deferred ends cost a serial pass after the blocks, one addition each; keeping every
        // pair's result instead costs two more passes over all pairs and a second threaded
        // section. With the particles sorted, a particle's partners j > i lie up to about two
        // layers of bins ahead in index order, so few ends are shared: with two blocks 2.3 % at
        // 97 556 spheres in the dense packing, 4 % at 19 652, 9 % at 2 048, 12 % in the
        // 514-particle hydrogel deck (there the blocks take 2.1-2.3 s per stroke against
        // 3.2-3.3 s keeping every result, serial 2.8 s). Unsorted numberings share about half.
        self.blocks.owned_blocks_pay = shared * 4 <= 2 * np;
        self.blocks.owner_key = Some((np, blocks, n));
    }

    /// Per particle, its pairs in pair order (index × 2 + side, side 1 when it is the pair's j),
    /// as compressed rows: the threaded force pass sums each particle's pair results from these,
    /// in the order the serial pass adds them.
    pub(super) fn build_incidence(&mut self) {
        let n = self.p.len();
        self.blocks.inc_start.clear();
        self.blocks.inc_start.resize(n + 1, 0);
        for pr in &self.contacts.pairs {
            self.blocks.inc_start[pr.i as usize + 1] += 1;
            self.blocks.inc_start[pr.j as usize + 1] += 1;
        }
        for i in 0..n {
            self.blocks.inc_start[i + 1] += self.blocks.inc_start[i];
        }
        self.blocks.inc.resize(2 * self.contacts.pairs.len(), 0);
        self.blocks.inc_fill.clear();
        self.blocks.inc_fill.extend_from_slice(&self.blocks.inc_start[..n]);
        for (k, pr) in self.contacts.pairs.iter().enumerate() {
            for (a, side) in [(pr.i, 0), (pr.j, 1)] {
                let at = &mut self.blocks.inc_fill[a as usize];
                self.blocks.inc[*at as usize] = 2 * k as u32 + side;
                *at += 1;
            }
        }
    }
}
