//! Contact records and their history: candidate pairs (with what the multi-contact closure keeps of
//! them) and particle–wall contacts, as the stages pass them on from step to step.

use crate::physics::pair::ContactError;
use crate::physics::Vec3;

use super::StepError;

/// Contact records of the step: candidate pairs with their history and per-step
/// transients, and wall contacts with their forces.
#[derive(Debug, Default)]
pub(super) struct Contacts {
    pub(super) pairs: Vec<Pair>,
    pub(super) pairs_old: Vec<Pair>,
    /// Per pair, under the multi-contact closure: what its next pass reads (empty under Hertz).
    pub(super) pair_hist: Vec<PairHist>,
    pub(super) pair_hist_old: Vec<PairHist>,
    /// Per pair, under a normal law with a history of its own (`hooke/hysteresis`): the largest
    /// overlap δ_max of the contact (0 when apart). Empty under the other laws, so their passes
    /// neither load nor store it.
    pub(super) pair_dmax: Vec<f64>,
    pub(super) pair_dmax_old: Vec<f64>,
    /// Per pair, under a rolling model with a spring (`epsd`, `epsd2`): the rolling spring torque
    /// M_k of the contact (zero when apart). Empty under the other models, as `pair_dmax`.
    pub(super) pair_roll: Vec<Vec3>,
    pub(super) pair_roll_old: Vec<Vec3>,
    pub(super) wc: Vec<WallContact>,
    pub(super) wc_old: Vec<WallContact>,
    /// Per pair, under the multi-contact closure: this step's radius changes (a Hertz pass reads none).
    pub(super) pair_dr: Vec<PairDr>,
    /// Per pair: the total contact force on i from j at the last force pass (zero when apart),
    /// for the stress and coordination outputs.
    pub(super) pair_force: Vec<Vec3>,
    /// Per wall contact: its force on the particle at the last force pass (for the mesh sums).
    pub(super) wall_force: Vec<Vec3>,
}

/// Candidate pair with its tangential history ξ: what every step reads and writes per pair, 32
/// bytes, two to a cache line. What only the multi-contact closure needs lives beside it in
/// [`PairHist`], and per-step transients (this step's radius changes, the recorded force) in their
/// own arrays: at large N the pairs no longer fit in cache and stream from memory every step, so a
/// Hertz pass moves half the bytes it would if the closure's state rode along.
#[derive(Debug, Clone, Copy)]
#[repr(align(32))]
pub(super) struct Pair {
    pub(super) i: u32,
    pub(super) j: u32,
    pub(super) shear: Vec3,
}

/// What the multi-contact pass reads of a pair, written by the pair pass before it (kept, one per
/// pair, only under the closure).
#[derive(Debug, Clone, Copy)]
pub(super) struct PairHist {
    /// |F·n| of the previous step (Eq. 2 is lagged one step).
    pub(super) fn_prev: f64,
    /// Modified radii r + Δ used at the previous step (contact point of the next step, as LIGGGHTS).
    pub(super) ri_prev: f64,
    pub(super) rj_prev: f64,
    /// Centres closer than (1 + RECEIVER_GAP)(r_i + r_j) at the last evaluation: the pair may
    /// receive multi-contact terms (growth could make it touch). True for a new pair.
    pub(super) near: bool,
}

impl PairHist {
    /// A pair just found by the neighbour search. LIGGGHTS starts a pair's history at zero radii:
    /// the contact point sits at the centre and receives no multi-contact term until the pair is
    /// evaluated.
    pub(super) const NEW: PairHist = PairHist { fn_prev: 0.0, ri_prev: 0.0, rj_prev: 0.0, near: true };
}

/// This step's multi-contact radius changes of a pair: [Δ of i at this contact, Δ of j].
pub(super) type PairDr = [f64; 2];

/// One touching particle pair as output sees it (indices into the particle arrays).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairContact {
    pub i: usize,
    pub j: usize,
    /// x_i − x_j, minimum image.
    pub branch: Vec3,
    /// The pair touches across a periodic boundary.
    pub periodic: bool,
    /// Contact force on i [N].
    pub force: Vec3,
    /// Contact torque on i [N m].
    pub torque: Vec3,
    /// The tangential spring of `tangential history` [m] (what LIGGGHTS stores as the pair's
    /// contact history); zero under `no_history`.
    pub shear: Vec3,
}

/// A particle and a wall element (plane, or one triangle of a mesh) that may come within reach
/// before the wall candidates are rebuilt.
#[derive(Debug, Clone, Copy)]
pub(super) struct WallCandidate {
    pub(super) p: u32,
    pub(super) wall: u32,
    pub(super) mesh: u32,
    pub(super) tri: u32,
}

/// A particle close to a wall element (plane, or one triangle of a mesh) with its history.
#[derive(Debug, Clone, Copy)]
pub(super) struct WallContact {
    pub(super) p: u32,
    pub(super) wall: u32,
    pub(super) mesh: u32,
    pub(super) tri: u32,
    pub(super) point: Vec3,
    pub(super) velocity: Vec3,
    pub(super) shear: Vec3,
    pub(super) fn_prev: f64,
    /// Contact point relative to the centre at the previous step (LIGGGHTS `surfPos`): the
    /// multi-contact pass reads it, as LIGGGHTS does; zero for a contact seen for the first time.
    pub(super) rel_prev: Vec3,
    pub(super) dr: f64,
    /// The rolling spring torque M_k of `epsd`/`epsd2` (zero under the other models and for a
    /// contact seen for the first time).
    pub(super) roll: Vec3,
}

impl WallContact {
    /// A contact seen for the first time: no tangential history, no previous force or surface point.
    pub(super) fn fresh(p: usize, wall: usize, mesh: usize, tri: usize, point: Vec3, velocity: Vec3) -> Self {
        WallContact {
            p: p as u32,
            wall: wall as u32,
            mesh: mesh as u32,
            tri: tri as u32,
            point,
            velocity,
            shear: Vec3::zeros(),
            fn_prev: 0.0,
            rel_prev: Vec3::zeros(),
            dr: 0.0,
            roll: Vec3::zeros(),
        }
    }

    #[inline]
    pub(super) fn key(&self) -> (u32, u32, u32, u32) {
        (self.p, self.wall, self.mesh, self.tri)
    }
}

/// Relative gap (fraction of r_i + r_j) within which an unloaded pair still receives a
/// multi-contact radius change: growth beyond 10 % of both radii together is outside the
/// model's range (Eq. 3 caps each neighbour term at MPR r, about 0.1 r).
pub(super) const RECEIVER_GAP: f64 = 0.1;

#[cold]
#[inline(never)]
pub(super) fn contact_error(step: u64, particle: i64, other: Option<i64>, e: ContactError) -> StepError {
    let with = match other {
        Some(j) => format!("contact with particle {j}"),
        None => "wall contact".to_string(),
    };
    StepError { step, particle, cause: format!("{with}: {e}"), contact: Some(e) }
}
