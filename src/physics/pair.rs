//! One contact, particle–particle or particle–wall: the geometry is computed once (normal, overlap
//! with the multi-contact radii, relative velocities), then the normal and tangential sub-models
//! of [`super::hertz`] read it. Same operations, same order as LIGGGHTS `surface default` +
//! `hertz` + `tangential history`, so both engines agree to round-off.

use std::fmt;

use super::hertz::{self, NormalForce, Tangential};
use super::material::PairCoeffs;
use super::Vec3;

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
    /// Effective overlap δ' = r_i' + r_j' − |x_i − x_j| [m] (SPEC §2).
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
                "overlap {overlap:.6e} m reached the particle radius {radius:.6e} m (contact law out of range: reduce the time step or the multi-contact prefactor)"
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
}

// Always inlined: the caller then keeps only the fields it reads, instead of copying the whole
// ContactForce through memory (measured: ~20 % of a Hertz step when it was an out-of-line call).
#[inline(always)]
fn forces(c: &PairCoeffs, g: &Geometry, dt: f64, shear: &mut Vec3) -> Result<ContactForce, ContactError> {
    let vn = g.vr.dot(&g.en);
    let normal = hertz::normal(c, g.overlap, g.reff, g.meff, vn);
    let mut force_i = g.en * normal.force;
    let (mut torque_i, mut torque_j) = (Vec3::zeros(), Vec3::zeros());
    if c.friction > 0.0 {
        // Relative tangential velocity at the contact point, rotation included (SPEC §1).
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
    if !(force_i.iter().all(|v| v.is_finite()) && torque_i.iter().all(|v| v.is_finite())) {
        return Err(ContactError::NonFinite);
    }
    Ok(ContactForce { force_i, torque_i, torque_j, en: g.en, overlap: g.overlap, point: g.point, normal })
}

/// Particle–particle contact. `dri`, `drj` are the multi-contact radius changes of i and j at this
/// contact (0 for Hertz). Returns `Ok(None)` (and clears the tangential history) when the modified
/// spheres do not overlap.
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
    let (ri, rj) = (bi.radius + dri, bj.radius + drj);
    let d = bi.x - bj.x;
    let radsum = ri + rj;
    let rsq = d.norm_squared();
    if rsq >= radsum * radsum {
        *shear = Vec3::zeros();
        return Ok(None);
    }
    let r = rsq.sqrt();
    if r == 0.0 {
        return Err(ContactError::CoincidentCentres);
    }
    let overlap = radsum - r;
    let rmin = bi.radius.min(bj.radius);
    if overlap >= rmin {
        return Err(ContactError::OverlapBeyondRadius { overlap, radius: rmin });
    }
    // One division, then products: the normal LIGGGHTS computes (and cheaper than d / r).
    let en = d * (1.0 / r);
    let cri = ri - 0.5 * overlap;
    let crj = rj - 0.5 * overlap;
    let (reff, meff) = hertz::effective_radius_and_mass(ri, rj, bi.mass, bj.mass);
    let g = Geometry {
        en,
        overlap,
        point: bi.x - en * cri,
        vr: bi.v - bj.v,
        w: cri * bi.omega + crj * bj.omega,
        cri,
        crj,
        reff,
        meff,
    };
    forces(c, &g, dt, shear).map(Some)
}

/// Particle–wall contact; the wall is rigid (no radius change on its side). `dri` is the particle's
/// multi-contact radius change at this contact. Returns `Ok(None)` (and clears the history) when
/// the modified sphere does not reach the wall.
#[inline]
pub fn particle_wall(
    c: &PairCoeffs,
    bi: &Body,
    wall: &WallPoint,
    dri: f64,
    dt: f64,
    shear: &mut Vec3,
) -> Result<Option<ContactForce>, ContactError> {
    let ri = bi.radius + dri;
    let d = bi.x - wall.point;
    let rsq = d.norm_squared();
    if rsq >= ri * ri {
        *shear = Vec3::zeros();
        return Ok(None);
    }
    let r = rsq.sqrt();
    if r == 0.0 {
        return Err(ContactError::CoincidentCentres);
    }
    let overlap = ri - r;
    if overlap >= bi.radius {
        return Err(ContactError::OverlapBeyondRadius { overlap, radius: bi.radius });
    }
    let cri = ri - 0.5 * overlap;
    let g = Geometry {
        en: d * (1.0 / r),
        overlap,
        point: wall.point,
        vr: bi.v - wall.velocity,
        w: cri * bi.omega,
        cri,
        crj: 0.0,
        // The wall is the limit of an infinite, infinitely heavy partner (see
        // `hertz::effective_radius_and_mass`).
        reff: ri,
        meff: bi.mass,
    };
    forces(c, &g, dt, shear).map(Some)
}
