//! One contact, particle–particle or particle–wall: the geometry is computed once (normal, overlap
//! with the multi-contact radii, relative velocities), then the normal and tangential sub-models
//! of [`super::hertz`] (or [`super::hooke`]) read it. Same operations, same order as LIGGGHTS `surface default` +
//! `hertz` + `tangential history`, so both engines agree to round-off.

use std::fmt;

use super::hertz::{self, NormalForce, Tangential};
use super::material::{NormalLaw, PairCoeffs, RollingLaw};
use super::Vec3;
use super::{hooke, hooke_hysteresis, rolling_cdt, rolling_epsd, sjkr};

/// Kinematic state of one spherical body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    /// Centre [m].
    pub x: Vec3,
    /// Velocity [m/s].
    pub v: Vec3,
    /// Angular velocity [rad/s].
    pub omega: Vec3,
    /// Original radius [m].
    pub radius: f64,
    /// Mass [kg].
    pub mass: f64,
}

/// A rigid wall at one contact: the closest wall point to the particle centre and its velocity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallPoint {
    /// Closest point of the wall to the particle centre [m].
    pub point: Vec3,
    /// Velocity of the wall at that point [m/s].
    pub velocity: Vec3,
}

/// Forces and geometry of one active contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactForce {
    /// Total force on body i [N] (the force on j is its negative).
    pub force_i: Vec3,
    /// Torque on body i [N m].
    pub torque_i: Vec3,
    /// Torque on body j [N m] (zero for a wall).
    pub torque_j: Vec3,
    /// Unit normal from j (or the wall) to i.
    pub en: Vec3,
    /// Effective overlap δ' = r_i' + r_j' − |x_i − x_j| [m] (docs/spec.md §2).
    pub overlap: f64,
    /// Contact point [m]: midpoint of the overlap of the modified spheres (LIGGGHTS convention);
    /// for a wall, the point on the wall.
    pub point: Vec3,
    /// Normal sub-model output (force, stiffnesses, damping).
    pub normal: NormalForce,
}

/// A contact the model cannot integrate: the caller stops the run and names particle and step.
#[derive(Debug, Clone, PartialEq)]
pub enum ContactError {
    /// The overlap reached a particle radius: the contact law has left its range of validity
    /// (typically standard MC with too large a γ, or a time step far too large).
    OverlapBeyondRadius { overlap: f64, radius: f64 },
    /// Coincident centres (or a centre on the wall): no contact normal exists.
    CoincidentCentres,
    /// A force or torque came out NaN or infinite.
    NonFinite,
}

impl fmt::Display for ContactError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ContactError::OverlapBeyondRadius { overlap, radius } => write!(
                f,
                "overlap {overlap:.6e} m reached the particle radius {radius:.6e} m (contact law out of range: a time step too large for this contact, or a compression beyond what the law can hold; a stop that stays when the time step is halved is the law's)"
            ),
            ContactError::CoincidentCentres => {
                write!(f, "coincident centres: the contact normal is undefined")
            }
            ContactError::NonFinite => write!(f, "contact force is not finite"),
        }
    }
}

impl std::error::Error for ContactError {}

/// Contact geometry, computed once per contact and read by the sub-models (LAMMPS GRANULAR style).
struct Geometry {
    en: Vec3,
    overlap: f64,
    point: Vec3,
    /// Relative translational velocity v_i − v_j.
    vr: Vec3,
    /// cr_i ω_i + cr_j ω_j: rotation seen at the contact point.
    w: Vec3,
    /// Lever arms r' − δ'/2 of i and j (j's is 0 for a wall).
    cri: f64,
    crj: f64,
    reff: f64,
    meff: f64,
    /// Centre distance (centre to wall point for a wall) and the radii the overlap is measured
    /// with (r_j = 0 for a wall): what the cohesion's contact area reads.
    r: f64,
    ri: f64,
    rj: f64,
    wall: bool,
    /// Relative rolling velocity, read by the rolling friction only: ω_i − ω_j for a pair, the
    /// rotation at the contact (r − δ/2) ω_i for a wall (LIGGGHTS `wr` times r).
    wroll: Vec3,
    /// Masses of i and j (j's is unread for a wall): the rolling inertia of `epsd`.
    mi: f64,
    mj: f64,
}

/// A contact's rolling spring (`rolling_friction epsd|epsd2`; unread by the other models): the
/// spring torque of the last step, advanced in place, and the time step it advances by (LIGGGHTS
/// advances it by the run's time step on every pass, the set-up pass too, where the caller then
/// does not keep it).
pub struct RollSpring<'a> {
    pub spring: &'a mut Vec3,
    pub dt: f64,
}

impl RollSpring<'_> {
    /// For the callers whose laws keep no rolling spring.
    #[inline(always)]
    fn unused(spring: &mut Vec3) -> RollSpring<'_> {
        RollSpring { spring, dt: 0.0 }
    }
}

// Always inlined: the caller then keeps only the fields it reads, instead of copying the whole
// ContactForce through memory (measured: ~20 % of a Hertz step when it was an out-of-line call).
// No early exit and no error: a loop over a batch of contacts ([`PairLanes`]) then vectorises;
// the callers check the result ([`finite`]).
#[inline(always)]
// `delta_max`: the normal law's history (the largest overlap of `hooke/hysteresis`), unread by
// the other laws.
// `roll`: the rolling spring, read by `epsd`/`epsd2` only.
fn forces(
    c: &PairCoeffs,
    g: &Geometry,
    dt: f64,
    shear: &mut Vec3,
    delta_max: &mut f64,
    roll: RollSpring,
) -> ContactForce {
    let vn = g.vr.dot(&g.en);
    let mut normal = match &c.normal {
        NormalLaw::Hertz => hertz::normal(c, g.overlap, g.reff, g.meff, vn),
        NormalLaw::Hooke(h) => hooke::normal(c.e_star, h, g.overlap, g.reff, g.meff, vn),
        NormalLaw::HookeHysteresis(h, hy) => {
            hooke_hysteresis::normal(c.e_star, (h, hy), g.overlap, g.reff, g.meff, vn, delta_max)
        }
    };
    let mut force_i = g.en * normal.force;
    if c.cohesion > 0.0 {
        // `cohesion sjkr` after the normal law, as LIGGGHTS orders its sub-models.
        let area = if g.wall {
            sjkr::wall_contact_area(g.r, g.ri)
        } else {
            sjkr::pair_contact_area(g.r, g.ri, g.rj)
        };
        let f_coh = sjkr::force(c.cohesion, area);
        force_i += g.en * f_coh;
        if c.tangential_reduce {
            normal.force += f_coh;
        }
    }
    let (mut torque_i, mut torque_j) = (Vec3::zeros(), Vec3::zeros());
    if c.friction > 0.0 {
        // Relative tangential velocity at the contact point, rotation included (docs/spec.md §1).
        let vtr = g.vr - g.en * vn + g.en.cross(&g.w);
        let ft = match c.tangential {
            Tangential::History => hertz::tangential_history(shear, &vtr, &g.en, dt, &normal, c.friction),
            Tangential::NoHistory => hertz::tangential_no_history(&vtr, &normal, c.friction),
        };
        let tor = g.en.cross(&ft);
        force_i += ft;
        torque_i = -g.cri * tor;
        torque_j = -g.crj * tor;
    } else {
        // μ = 0: the history model gives exactly zero and resets ξ; skip the work.
        *shear = Vec3::zeros();
    }
    if c.rolling_friction > 0.0 {
        // The rolling model after the tangential model, as LIGGGHTS orders its sub-models; the
        // wall's lever is the particle radius (see [`rolling_cdt`]).
        let lever = if g.wall { g.ri } else { rolling_cdt::pair_lever(g.ri, g.rj) };
        let t = match c.rolling_law {
            RollingLaw::Cdt => {
                rolling_cdt::torque(c.rolling_friction, normal.kn, g.overlap, lever, g.wroll, g.en)
            }
            RollingLaw::Spring(model) => rolling_spring(c.rolling_friction, model, g, &normal, lever, roll),
        };
        torque_i += t;
        if !g.wall {
            torque_j -= t;
        }
    }
    ContactForce { force_i, torque_i, torque_j, en: g.en, overlap: g.overlap, point: g.point, normal }
}

/// The `epsd`/`epsd2` torque on i of a contact (see [`rolling_epsd`]) from its geometry and normal
/// force. LIGGGHTS reads ω_i − ω_j for a pair, and for a wall the surface model's `wr`:
/// (r − δ/2) ω_i / (r − δ), the rotation at the contact over the centre's distance to the wall.
#[inline(never)]
fn rolling_spring(
    mu_r: f64,
    model: rolling_epsd::Epsd,
    g: &Geometry,
    normal: &NormalForce,
    lever: f64,
    roll: RollSpring,
) -> Vec3 {
    let (wr, inertia) = if g.wall {
        (g.wroll * (1.0 / g.r), rolling_epsd::wall_inertia(g.mi, lever))
    } else {
        (g.wroll, rolling_epsd::pair_inertia(g.mi, g.ri, g.mj, g.rj))
    };
    let r = rolling_epsd::Rolling {
        mu_r,
        reff: lever,
        kn: normal.kn,
        kt: normal.kt,
        fnorm: normal.force,
        inertia,
        wr,
        en: g.en,
    };
    rolling_epsd::torque(model, &r, roll.dt, roll.spring)
}

#[inline(always)]
fn finite(cf: &ContactForce) -> bool {
    cf.force_i.iter().chain(cf.torque_i.iter()).all(|v| v.is_finite())
}

/// Contact of two particles whose modified spheres overlap, from the centre difference
/// d = x_i − x_j and the relative velocity vr = v_i − v_j: the one place the pair geometry is
/// built. `point` comes out relative to x_i. Nothing is checked (see [`particle_particle`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn overlapping_pair(
    c: &PairCoeffs,
    d: Vec3,
    vr: Vec3,
    (omega_i, omega_j): (Vec3, Vec3),
    (radius_i, radius_j): (f64, f64),
    (dri, drj): (f64, f64),
    (mass_i, mass_j): (f64, f64),
    dt: f64,
    (shear, delta_max, roll): (&mut Vec3, &mut f64, RollSpring),
) -> ContactForce {
    let (ri, rj) = (radius_i + dri, radius_j + drj);
    let r = d.norm_squared().sqrt();
    let overlap = ri + rj - r;
    // One division, then products: the normal LIGGGHTS computes (and cheaper than d / r).
    let en = d * (1.0 / r);
    let cri = ri - 0.5 * overlap;
    let crj = rj - 0.5 * overlap;
    let (reff, meff) = hertz::effective_radius_and_mass(ri, rj, mass_i, mass_j);
    let g = Geometry {
        en,
        overlap,
        point: -en * cri,
        vr,
        w: cri * omega_i + crj * omega_j,
        cri,
        crj,
        reff,
        meff,
        r,
        ri,
        rj,
        wall: false,
        wroll: omega_i - omega_j,
        mi: mass_i,
        mj: mass_j,
    };
    forces(c, &g, dt, shear, delta_max, roll)
}

/// Particle–particle contact. `dri`, `drj` are the multi-contact radius changes of i and j at this
/// contact (0 for Hertz). Returns `Ok(None)` (and clears the tangential history) when the modified
/// spheres do not overlap. For normal laws without a history of their own (all but
/// `hooke/hysteresis`, which needs [`particle_particle_with_history`]).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn particle_particle(
    c: &PairCoeffs,
    bi: &Body,
    bj: &Body,
    dri: f64,
    drj: f64,
    dt: f64,
    shear: &mut Vec3,
) -> Result<Option<ContactForce>, ContactError> {
    particle_particle_with_history(
        c,
        bi,
        bj,
        dri,
        drj,
        dt,
        shear,
        &mut 0.0,
        RollSpring::unused(&mut Vec3::zeros()),
    )
}

/// [`particle_particle`] with the normal law's history `delta_max` of the contact (the largest
/// overlap of `hooke/hysteresis`; unread by the other laws) and the rolling spring `roll`
/// (`epsd`/`epsd2`; unread by the other models), updated in place and reset to 0 when the spheres
/// do not overlap.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn particle_particle_with_history(
    c: &PairCoeffs,
    bi: &Body,
    bj: &Body,
    dri: f64,
    drj: f64,
    dt: f64,
    shear: &mut Vec3,
    delta_max: &mut f64,
    roll: RollSpring,
) -> Result<Option<ContactForce>, ContactError> {
    let d = bi.x - bj.x;
    let radsum = (bi.radius + dri) + (bj.radius + drj);
    let rsq = d.norm_squared();
    if rsq >= radsum * radsum {
        *shear = Vec3::zeros();
        *delta_max = 0.0;
        *roll.spring = Vec3::zeros();
        return Ok(None);
    }
    pair_error(d, radsum, bi.radius.min(bj.radius)).map_or(Ok(()), Err)?;
    let mut cf = overlapping_pair(
        c,
        d,
        bi.v - bj.v,
        (bi.omega, bj.omega),
        (bi.radius, bj.radius),
        (dri, drj),
        (bi.mass, bj.mass),
        dt,
        (shear, delta_max, roll),
    );
    if !finite(&cf) {
        return Err(ContactError::NonFinite);
    }
    cf.point += bi.x;
    Ok(Some(cf))
}

/// Geometry of a particle–wall contact whose modified sphere (radius `ri`) reaches the wall, from
/// d = centre − closest wall point and r = |d| > 0: the one place it is built (scalar and batched).
#[inline(always)]
fn wall_geometry(d: Vec3, r: f64, ri: f64, point: Vec3, vr: Vec3, omega: Vec3, mass: f64) -> Geometry {
    let overlap = ri - r;
    let cri = ri - 0.5 * overlap;
    Geometry {
        en: d * (1.0 / r),
        overlap,
        point,
        vr,
        w: cri * omega,
        cri,
        crj: 0.0,
        // The wall is the limit of an infinite, infinitely heavy partner (see
        // `hertz::effective_radius_and_mass`).
        reff: ri,
        meff: mass,
        r,
        ri,
        rj: 0.0,
        wall: true,
        wroll: cri * omega,
        mi: mass,
        mj: 0.0,
    }
}

/// Why an overlapping pair (centre difference `d`, modified radii summing to `radsum`, smaller
/// original radius `rmin`) cannot be integrated, if it cannot.
#[inline(always)]
fn pair_error(d: Vec3, radsum: f64, rmin: f64) -> Option<ContactError> {
    let r = d.norm_squared().sqrt();
    if r == 0.0 {
        Some(ContactError::CoincidentCentres)
    } else {
        overlap_error(radsum - r, rmin)
    }
}

/// The range of the contact law: an overlap that reached the smaller original radius `rmin` of the
/// bodies (the particle's own for a wall) means the particles are passing through each other.
#[inline(always)]
pub fn overlap_error(overlap: f64, rmin: f64) -> Option<ContactError> {
    if overlap >= rmin {
        Some(ContactError::OverlapBeyondRadius { overlap, radius: rmin })
    } else {
        None
    }
}

/// Width of a [`PairLanes`] batch: wide enough for two 4-lane vectors, small enough to stay in
/// registers and L1.
pub const LANES: usize = 8;

/// A batch of overlapping particle pairs in structure-of-arrays form, one pair per lane, for a
/// vectorised evaluation of the same formulas as [`particle_particle`] (bit-identical results:
/// the same operations in the same order, and IEEE vector square roots and divisions round as
/// the scalar ones do). Used by the DEM's pair loop; the tangential model is `history`.
// Cache-line aligned: every lane array is one 64-byte line, so no 4-lane load or store straddles
// two lines. Left to its natural 8-byte alignment, the batch's speed depended on where the
// compiler happened to place it on the stack (measured ±15 % between builds of unrelated code).
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(64))]
pub struct PairLanes {
    /// x_i − x_j (minimum image) [m].
    pub d: [[f64; LANES]; 3],
    /// v_i − v_j (Lees–Edwards jump included) [m/s].
    pub vr: [[f64; LANES]; 3],
    pub omega_i: [[f64; LANES]; 3],
    pub omega_j: [[f64; LANES]; 3],
    /// Original radii [m].
    pub radius_i: [f64; LANES],
    pub radius_j: [f64; LANES],
    /// Multi-contact radius changes [m].
    pub dri: [f64; LANES],
    pub drj: [f64; LANES],
    pub mass_i: [f64; LANES],
    pub mass_j: [f64; LANES],
    /// The pair's coefficients, lane by lane.
    pub coeffs: CoeffLanes,
    /// Tangential history ξ, updated in place [m].
    pub shear: [[f64; LANES]; 3],
    /// Outputs: force on i [N], torques on i and j [N m], |F·n| [N], and whether the lane's
    /// contact can be integrated (false: the caller asks [`particle_particle`] why not).
    pub force: [[f64; LANES]; 3],
    pub torque_i: [[f64; LANES]; 3],
    pub torque_j: [[f64; LANES]; 3],
    pub fnorm: [f64; LANES],
    /// Signed normal force F_n = k_n δ − γ_n v_n [N] (what LIGGGHTS's normal sub-model gives).
    pub normal: [f64; LANES],
    pub ok: [bool; LANES],
}

#[inline(always)]
fn lane3(a: &[[f64; LANES]; 3], l: usize) -> Vec3 {
    Vec3::new(a[0][l], a[1][l], a[2][l])
}

#[inline(always)]
fn set_lane3(a: &mut [[f64; LANES]; 3], l: usize, v: &Vec3) {
    a[0][l] = v.x;
    a[1][l] = v.y;
    a[2][l] = v.z;
}

/// Lanes `used..` of one lane array take lane 0's value (a batch is always evaluated whole).
#[inline(always)]
fn pad(a: &mut [f64; LANES], used: usize) {
    let first = a[0];
    a[used..].fill(first);
}

/// The contact coefficients of a batch, lane by lane (tangential model `history`).
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(64))]
pub struct CoeffLanes {
    pub e_star: [f64; LANES],
    pub g_star: [f64; LANES],
    pub beta: [f64; LANES],
    pub friction: [f64; LANES],
    pub damping_ratio_t_n: [f64; LANES],
}

impl CoeffLanes {
    /// Gives lane `l` the coefficients `c` (whose tangential model must be `history` and normal
    /// law Hertz: the batches are Hertz only).
    #[inline(always)]
    pub fn set(&mut self, l: usize, c: &PairCoeffs) {
        self.e_star[l] = c.e_star;
        self.g_star[l] = c.g_star;
        self.beta[l] = c.beta;
        self.friction[l] = c.friction;
        self.damping_ratio_t_n[l] = c.damping_ratio_t_n;
    }

    #[inline(always)]
    fn get(&self, l: usize) -> PairCoeffs {
        PairCoeffs {
            e_star: self.e_star[l],
            g_star: self.g_star[l],
            beta: self.beta[l],
            friction: self.friction[l],
            tangential: Tangential::History,
            normal: NormalLaw::Hertz,
            cohesion: 0.0,
            tangential_reduce: false,
            rolling_friction: 0.0,
            rolling_law: RollingLaw::Cdt,
            damping_ratio_t_n: self.damping_ratio_t_n[l],
        }
    }

    fn pad_from_first(&mut self, used: usize) {
        for v in [
            &mut self.e_star,
            &mut self.g_star,
            &mut self.beta,
            &mut self.friction,
            &mut self.damping_ratio_t_n,
        ] {
            pad(v, used);
        }
    }
}

/// A batch of contacts evaluated lane by lane with the same formulas as the scalar contact, so
/// that [`evaluate_batch`] can compile the loop a second time for AVX2.
trait Batch {
    fn evaluate_lanes(&mut self, dt: f64);
}

/// Runs a batch's lane loop, the AVX2 build of it when the CPU has AVX2 (four lanes per
/// instruction; see [`super::avx2`]).
#[inline]
fn evaluate_batch<B: Batch>(b: &mut B, dt: f64) {
    #[cfg(target_arch = "x86_64")]
    if super::avx2() {
        // SAFETY: the CPU supports AVX2 (checked just above).
        unsafe { evaluate_avx2(b, dt) };
        return;
    }
    b.evaluate_lanes(dt);
}

/// The lane loop compiled for AVX2 (the `#[inline(always)]` loop is inlined here and takes on
/// the target feature).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn evaluate_avx2<B: Batch>(b: &mut B, dt: f64) {
    b.evaluate_lanes(dt);
}

impl PairLanes {
    /// Fills lanes `used..` with copies of lane 0 (a batch is always evaluated whole).
    pub fn pad_from_first(&mut self, used: usize) {
        for a in 0..3 {
            for v in [&mut self.d, &mut self.vr, &mut self.omega_i, &mut self.omega_j, &mut self.shear] {
                pad(&mut v[a], used);
            }
        }
        for v in [
            &mut self.radius_i,
            &mut self.radius_j,
            &mut self.dri,
            &mut self.drj,
            &mut self.mass_i,
            &mut self.mass_j,
        ] {
            pad(v, used);
        }
        self.coeffs.pad_from_first(used);
    }

    /// Whether [`PairLanes::evaluate`] runs vectorised on this CPU (see [`super::avx2`]). Without
    /// it the lane loop stays scalar and a batch is slower than the pair-by-pair path (measured
    /// +12 % on the hydrogel deck): callers use this to choose.
    pub fn vectorised() -> bool {
        super::avx2()
    }

    /// Evaluates every lane (all must hold overlapping pairs; pad unused lanes with a copy of a
    /// used one). Time step `dt` as in [`particle_particle`].
    pub fn evaluate(&mut self, dt: f64) {
        evaluate_batch(self, dt);
    }
}

impl Batch for PairLanes {
    #[inline(always)]
    fn evaluate_lanes(&mut self, dt: f64) {
        for l in 0..LANES {
            let c = self.coeffs.get(l);
            let d = lane3(&self.d, l);
            let mut shear = lane3(&self.shear, l);
            let (ri, rj) = (self.radius_i[l], self.radius_j[l]);
            let cf = overlapping_pair(
                &c,
                d,
                lane3(&self.vr, l),
                (lane3(&self.omega_i, l), lane3(&self.omega_j, l)),
                (ri, rj),
                (self.dri[l], self.drj[l]),
                (self.mass_i[l], self.mass_j[l]),
                dt,
                (&mut shear, &mut 0.0, RollSpring::unused(&mut Vec3::zeros())),
            );
            let radsum = (ri + self.dri[l]) + (rj + self.drj[l]);
            self.ok[l] = pair_error(d, radsum, ri.min(rj)).is_none() && finite(&cf);
            set_lane3(&mut self.force, l, &cf.force_i);
            set_lane3(&mut self.torque_i, l, &cf.torque_i);
            set_lane3(&mut self.torque_j, l, &cf.torque_j);
            set_lane3(&mut self.shear, l, &shear);
            self.fnorm[l] = cf.force_i.dot(&cf.en).abs();
            self.normal[l] = cf.normal.force;
        }
    }
}

/// Particle–wall contact; the wall is rigid (no radius change on its side). `dri` is the particle's
/// multi-contact radius change at this contact. Returns `Ok(None)` (and clears the history) when
/// the modified sphere does not reach the wall. For rolling models without a history (all but
/// `epsd`/`epsd2`, which need [`particle_wall_with_history`]).
#[inline]
pub fn particle_wall(
    c: &PairCoeffs,
    bi: &Body,
    wall: &WallPoint,
    dri: f64,
    dt: f64,
    shear: &mut Vec3,
) -> Result<Option<ContactForce>, ContactError> {
    particle_wall_with_history(c, bi, wall, dri, dt, shear, RollSpring::unused(&mut Vec3::zeros()))
}

/// [`particle_wall`] with the contact's rolling spring `roll` (`epsd`/`epsd2`; unread by the
/// other models), updated in place and reset to 0 when the sphere does not reach the wall.
#[inline]
pub fn particle_wall_with_history(
    c: &PairCoeffs,
    bi: &Body,
    wall: &WallPoint,
    dri: f64,
    dt: f64,
    shear: &mut Vec3,
    roll: RollSpring,
) -> Result<Option<ContactForce>, ContactError> {
    let ri = bi.radius + dri;
    let d = bi.x - wall.point;
    let rsq = d.norm_squared();
    if rsq >= ri * ri {
        *shear = Vec3::zeros();
        *roll.spring = Vec3::zeros();
        return Ok(None);
    }
    let r = rsq.sqrt();
    if r == 0.0 {
        return Err(ContactError::CoincidentCentres);
    }
    overlap_error(ri - r, bi.radius).map_or(Ok(()), Err)?;
    let g = wall_geometry(d, r, ri, wall.point, bi.v - wall.velocity, bi.omega, bi.mass);
    // Walls run laws without a normal history (the decks' `fix wall/gran` refuses
    // `hooke/hysteresis`).
    let cf = forces(c, &g, dt, shear, &mut 0.0, roll);
    if finite(&cf) {
        Ok(Some(cf))
    } else {
        Err(ContactError::NonFinite)
    }
}

/// A batch of particle–wall contacts whose modified spheres reach the wall, in structure-of-arrays
/// form, one contact per lane: the same formulas as [`particle_wall`] (bit-identical results, as
/// for [`PairLanes`]), tangential model `history`.
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(64))]
pub struct WallLanes {
    /// Particle centre − closest wall point [m].
    pub d: [[f64; LANES]; 3],
    /// Particle velocity − wall velocity at that point [m/s].
    pub vr: [[f64; LANES]; 3],
    pub omega: [[f64; LANES]; 3],
    /// Original radius and multi-contact radius change [m], mass [kg].
    pub radius: [f64; LANES],
    pub dr: [f64; LANES],
    pub mass: [f64; LANES],
    /// The particle–wall coefficients, lane by lane.
    pub coeffs: CoeffLanes,
    /// Tangential history ξ, updated in place [m].
    pub shear: [[f64; LANES]; 3],
    /// Outputs: force [N] and torque [N m] on the particle, |F·n| [N], and whether the contact
    /// can be integrated (false: the caller asks [`particle_wall`] why not).
    pub force: [[f64; LANES]; 3],
    pub torque: [[f64; LANES]; 3],
    pub fnorm: [f64; LANES],
    pub ok: [bool; LANES],
}

impl WallLanes {
    /// Fills lanes `used..` with copies of lane 0 (a batch is always evaluated whole).
    pub fn pad_from_first(&mut self, used: usize) {
        for a in 0..3 {
            for v in [&mut self.d, &mut self.vr, &mut self.omega, &mut self.shear] {
                pad(&mut v[a], used);
            }
        }
        for v in [&mut self.radius, &mut self.dr, &mut self.mass] {
            pad(v, used);
        }
        self.coeffs.pad_from_first(used);
    }

    /// Evaluates every lane (all must hold contacts that reach the wall; pad unused lanes with
    /// a copy of a used one). Time step `dt` as in [`particle_wall`].
    pub fn evaluate(&mut self, dt: f64) {
        evaluate_batch(self, dt);
    }
}

impl Batch for WallLanes {
    #[inline(always)]
    fn evaluate_lanes(&mut self, dt: f64) {
        for l in 0..LANES {
            let c = self.coeffs.get(l);
            let d = lane3(&self.d, l);
            let ri = self.radius[l] + self.dr[l];
            let r = d.norm_squared().sqrt();
            let g = wall_geometry(
                d,
                r,
                ri,
                Vec3::zeros(),
                lane3(&self.vr, l),
                lane3(&self.omega, l),
                self.mass[l],
            );
            let mut shear = lane3(&self.shear, l);
            let cf = forces(&c, &g, dt, &mut shear, &mut 0.0, RollSpring::unused(&mut Vec3::zeros()));
            self.ok[l] = r != 0.0 && g.overlap < self.radius[l] && finite(&cf);
            set_lane3(&mut self.force, l, &cf.force_i);
            set_lane3(&mut self.torque, l, &cf.torque_i);
            set_lane3(&mut self.shear, l, &shear);
            self.fnorm[l] = cf.force_i.dot(&cf.en).abs();
        }
    }
}
