//! Where a pair pass puts each pair's result: the serial sums, the kept results of the threaded
//! pass, the owned blocks' sums with their deferrals, and the touching contacts for output.

use crate::physics::Vec3;

use super::contacts::PairContact;
use super::Domain;

/// One pair's contribution: force on i, torques on i and j, when touching. Written in place by
/// `PairCtx::eval` (a returned tuple travels through memory on every pair, and reading it back
/// stalled the serial loop).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct PairOut {
    pub(super) touching: bool,
    pub(super) force: Vec3,
    pub(super) torque_i: Vec3,
    pub(super) torque_j: Vec3,
}

/// Where [`PairCtx::eval_batched`] puts each pair's result. A trait rather than a closure so the
/// call is inlined into the batch loop (a closure stayed an out-of-line call: 15 % of a Hertz step).
pub(super) trait PairSink {
    fn put(&mut self, k: usize, i: usize, j: usize, o: &PairOut);
}

/// Serial pass: forces and torques straight into the per-particle sums; each pair's force
/// recorded for the outputs.
pub(super) struct SumInto<'a> {
    pub(super) f: &'a mut [Vec3],
    pub(super) torque: &'a mut [Vec3],
    pub(super) force: &'a mut [Vec3],
}

impl PairSink for SumInto<'_> {
    #[inline(always)]
    fn put(&mut self, k: usize, i: usize, j: usize, o: &PairOut) {
        self.force[k] = o.force;
        if o.touching {
            self.f[i] += o.force;
            self.f[j] -= o.force;
            self.torque[i] += o.torque_i;
            self.torque[j] += o.torque_j;
        }
    }
}

/// Threaded pass: each pair's result kept for the ordered sum afterwards, and its force recorded
/// for the outputs.
pub(super) struct Keep<'a> {
    pub(super) outs: &'a mut [PairOut],
    pub(super) force: &'a mut [Vec3],
}

impl PairSink for Keep<'_> {
    #[inline(always)]
    fn put(&mut self, k: usize, _i: usize, _j: usize, o: &PairOut) {
        self.outs[k] = *o;
        self.force[k] = o.force;
    }
}

/// [`World::touching_pairs`]: every pair carrying a force, with its branch vector.
pub(super) struct Touching<'a> {
    pub(super) x: &'a [Vec3],
    pub(super) domain: Domain,
    pub(super) out: Vec<PairContact>,
    /// The pair index of each entry of `out` (its history is read after the pass).
    pub(super) pair: Vec<usize>,
}

impl PairSink for Touching<'_> {
    fn put(&mut self, k: usize, i: usize, j: usize, o: &PairOut) {
        if o.force == Vec3::zeros() {
            return;
        }
        let raw = self.x[i] - self.x[j];
        let mut branch = raw;
        self.domain.minimum_image(&mut branch);
        self.out.push(PairContact {
            i,
            j,
            branch,
            periodic: branch != raw,
            force: o.force,
            torque: o.torque_i,
            shear: Vec3::zeros(),
        });
        self.pair.push(k);
    }
}

/// The per-particle sums of the threaded pass, written by several threads at once.
#[derive(Clone, Copy)]
pub(super) struct SharedSums {
    pub(super) f: *mut Vec3,
    pub(super) torque: *mut Vec3,
    pub(super) n: usize,
}

// SAFETY: the threads write disjoint entries: particle p only from the block that owns it
// (`World::assign_owners`), and the buffers outlive the parallel pass that uses them.
unsafe impl Send for SharedSums {}
unsafe impl Sync for SharedSums {}

/// A contribution to a particle that another block owns, added after the blocks finish.
#[derive(Debug, Clone, Copy)]
pub(super) struct Deferred {
    pub(super) p: u32,
    pub(super) f: Vec3,
    pub(super) torque: Vec3,
}

/// Threaded pass, one block of pairs: forces and torques straight into the sums of the particles
/// this block owns, deferred for the others; each pair's force recorded for the outputs.
pub(super) struct OwnedSums<'a> {
    pub(super) sums: SharedSums,
    pub(super) owner: &'a [u16],
    pub(super) block: u16,
    pub(super) deferred: &'a mut Vec<Deferred>,
    pub(super) force: &'a mut [Vec3],
}

impl OwnedSums<'_> {
    #[inline(always)]
    pub(super) fn add(&mut self, p: usize, f: Vec3, torque: Vec3) {
        if self.owner[p] == self.block {
            assert!(p < self.sums.n);
            // SAFETY: in bounds (checked), and only this block writes particle p (its owner).
            unsafe {
                *self.sums.f.add(p) += f;
                *self.sums.torque.add(p) += torque;
            }
        } else {
            self.deferred.push(Deferred { p: p as u32, f, torque });
        }
    }
}

impl PairSink for OwnedSums<'_> {
    #[inline(always)]
    fn put(&mut self, k: usize, i: usize, j: usize, o: &PairOut) {
        self.force[k] = o.force;
        if o.touching {
            // −F added is F subtracted, bit for bit (IEEE a − b = a + (−b)): the serial sums.
            self.add(i, o.force, o.torque_i);
            self.add(j, -o.force, o.torque_j);
        }
    }
}
