//! LIGGGHTS 3.8 `pair_style gran ... rolling_friction cdt` (rolling_model_cdt.h): a constant
//! directional torque that opposes the relative rolling of the two surfaces (Ai et al. 2011,
//! Powder Technol. 206, 269, model A):
//!
//! M_r = −μ_r k_n δ R_r ω̂, with the part along the contact normal removed,
//!
//! μ_r the type pair's `coefficientRollingFriction`, k_n δ the normal law's stiffness times the
//! overlap (the elastic normal force of Hertz and hooke, without damping), ω̂ the direction of the
//! relative angular velocity and R_r the lever: for a pair R* = r_i r_j / (r_i + r_j) with
//! ω_rel = ω_i − ω_j; for a wall the particle radius r with ω_rel = ω_i (LIGGGHTS 3.8 as run by
//! Debian's build, primitive and mesh walls alike: the lever r − δ/2 that the source reads off its
//! contact data gave torques δ/(2r) too small against it, the radius agrees to round-off; see
//! tests/dem/rolling_friction.rs). The torque is added
//! to particle i with the minus sign and to j with the plus sign (a torque only, no force); no
//! torque while ω_rel = 0. It has no history.

use super::Vec3;

/// The rolling torque on i of a contact (the torque on a partner particle is its negative):
/// `mu_r` = μ_r, `kn` the normal law's stiffness, `overlap` δ, `lever` R_r, `w_rel` the relative
/// rolling velocity (any positive multiple of ω_rel: only its direction is read), `en` the unit
/// normal. Same operations in the same order as LIGGGHTS.
#[inline]
pub fn torque(mu_r: f64, kn: f64, overlap: f64, lever: f64, w_rel: Vec3, en: Vec3) -> Vec3 {
    let wmag = w_rel.norm();
    if wmag <= 0.0 {
        return Vec3::zeros();
    }
    let t = w_rel * (mu_r * kn * overlap * lever / wmag);
    // Torsion (the part along the normal) is not rolling: LIGGGHTS removes it.
    let tn = en * t.dot(&en);
    -(t - tn)
}

/// R* = r_i r_j / (r_i + r_j), the pair's rolling lever (LIGGGHTS uses the particles' radii).
#[inline]
pub fn pair_lever(ri: f64, rj: f64) -> f64 {
    ri * rj / (ri + rj)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Magnitude μ_r k_n δ R, direction against the rolling, nothing along the normal.
    #[test]
    fn opposes_rolling_and_drops_torsion() {
        let en = Vec3::new(0.0, 0.0, 1.0);
        let t = torque(0.1, 2.0e4, 1e-4, 5e-3, Vec3::new(3.0, 0.0, 7.0), en);
        assert_eq!(t.z, 0.0);
        let m = 0.1 * 2.0e4 * 1e-4 * 5e-3 * 3.0 / (3.0f64 * 3.0 + 49.0).sqrt();
        assert!((t.x + m).abs() < 1e-15 * m.max(1e-30) + 1e-20);
        assert_eq!(torque(0.1, 1.0, 1.0, 1.0, Vec3::zeros(), en), Vec3::zeros());
    }
}
