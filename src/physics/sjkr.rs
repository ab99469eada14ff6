//! LIGGGHTS 3.8 `cohesion sjkr` (cohesion_model_sjkr.h): the simplified JKR cohesion. While two
//! surfaces overlap, an attractive normal force F_coh = −k_c A acts, with k_c the
//! `cohesionEnergyDensity` of the type pair [J/m³] and A the area of the contact disc.
//!
//! The disc is where the two spheres' surfaces intersect: for centres r apart and radii r_i, r_j
//! (the radii the overlap is measured with) its radius a obeys
//! a² = (r − r_i − r_j)(r + r_i − r_j)(r − r_i + r_j)(r + r_i + r_j) / (−4 r²)
//! (the chord of two intersecting circles), so A = π a². For a wall the sphere is cut by a plane
//! at distance r from its centre: A = π (r_i² − r²). LIGGGHTS also scales the wall force by the
//! wall element's area ratio, which is 1 for the walls mcdem models (primitives and mesh
//! triangles without overlap correction).
//!
//! How it meets the other sub-models (as in LIGGGHTS 3.8, whose contact model calls surface,
//! normal, cohesion, tangential in that order): F_coh is added to the normal force after the
//! normal law (damping included), and by default the Coulomb limit of the tangential force does
//! not see it (μ|F_n| with F_n the normal law's force only); `tangential_reduce on` adds F_coh
//! to F_n before the tangential sub-model, so a cohesive contact slides more easily.

use std::f64::consts::PI;

/// Area π a² [m²] of the contact disc of two spheres with radii `ri`, `rj` and centres `r`
/// apart (0 < r < r_i + r_j). Same factors in the same order as LIGGGHTS.
#[inline(always)]
pub fn pair_contact_area(r: f64, ri: f64, rj: f64) -> f64 {
    -PI / 4.0 * ((r - ri - rj) * (r + ri - rj) * (r - ri + rj) * (r + ri + rj)) / (r * r)
}

/// Area π (r_i² − r²) [m²] of the disc a plane at distance `r` < `ri` cuts from a sphere of radius `ri`.
#[inline(always)]
pub fn wall_contact_area(r: f64, ri: f64) -> f64 {
    (ri * ri - r * r) * PI
}

/// The cohesive normal force −k_c A [N] (negative: it pulls the bodies together) for the pair's
/// cohesion energy density `energy_density` [J/m³] and contact area `area` [m²].
#[inline(always)]
pub fn force(energy_density: f64, area: f64) -> f64 {
    -energy_density * area
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two equal spheres r_i = r_j = R with centres r apart: the disc's radius is
    /// a = √(R² − (r/2)²), so A = π (R² − r²/4).
    #[test]
    fn equal_spheres_give_the_chord_disc() {
        let (rad, r) = (0.0015, 0.0029);
        let a = pair_contact_area(r, rad, rad);
        let want = PI * (rad * rad - r * r / 4.0);
        assert!(((a - want) / want).abs() < 1e-12, "{a} vs {want}");
        assert_eq!(force(300_000.0, a), -300_000.0 * a);
    }

    /// A sphere against a much larger one tends to the sphere against a plane.
    #[test]
    fn large_partner_tends_to_the_wall() {
        let (ri, delta) = (0.001, 1e-5);
        let rj = 1e4;
        let r = ri + rj - delta;
        // The plane sits where the big sphere's surface is: at distance ri - delta from i's centre
        // (to first order); the disc of the big sphere is then that of the plane.
        let pair = pair_contact_area(r, ri, rj);
        let wall = wall_contact_area(ri - delta, ri);
        assert!(((pair - wall) / wall).abs() < 1e-3, "{pair} vs {wall}");
    }
}
