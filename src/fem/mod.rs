//! Finite-element continuum reference for one soft sphere between rigid frictionless walls: the
//! ground truth the contact laws (Hertz, standard and advanced multi-contact) and the nonlocal
//! kernels are measured against on the single-particle die of Ghods et al. (2022) App. B.
//!
//! Independent of the MPM solver: 3-D quasi-static total-Lagrangian finite elements with trilinear
//! hexahedra (`element`), linear elastic or compressible Neo-Hookean material (`material`), a
//! mean-dilatation F-bar / B-bar remedy against volumetric locking, frictionless rigid-plane
//! contact by a nodal active set and Newton's method with a line search and a sparse direct solve
//! (`solver`), on a graded octant mesh of the sphere (`mesh`, `octant`). `scene` reads the JSON
//! scene of `mcdem continuum` and writes its CSV and plot.

// The element and material loops index several fixed-size arrays with one index, as the tensor
// notation of the formulas they implement does; iterator chains would hide that correspondence.
#![allow(clippy::needless_range_loop)]

pub mod bcc;
pub mod element;
pub mod material;
pub mod mesh;
pub mod octant;
pub mod scene;
pub mod solver;
pub mod surface;

pub use element::{Law, Volumetric};
pub use octant::{Point, SphereRun, Walls};

/// Hertz force of one sphere–rigid-plane contact, F = (4/3) E* √R δ^{3/2} with
/// E* = E / (1 − ν²) (Johnson, *Contact Mechanics*, 1985, Eq. 4.22–4.23; rigid plane).
pub fn hertz_plane_force(e: f64, nu: f64, r: f64, delta: f64) -> f64 {
    4.0 / 3.0 * e / (1.0 - nu * nu) * r.sqrt() * delta.max(0.0).powf(1.5)
}

/// Axial displacement w(z) [m], positive into the body, at depth z [m] on the axis of a Hertz
/// pressure p(ρ) = p₀ √(1 − ρ²/a²), p₀ = 3F/(2πa²), of total force F [N] and contact radius a [m]
/// on a linear elastic half-space (E [Pa], ν). Boussinesq's concentrated normal force gives on the
/// axis of a ring of radius ρ the displacement (1 + ν)/(2πE) · [z²/L³ + 2(1 − ν)/L] per unit load,
/// L = √(ρ² + z²) (Johnson, *Contact Mechanics*, 1985, §3.2); integrated over the Hertz pressure
/// (Johnson §4.2) in closed form, with x = a/z:
///
///   w(z) = (1 + ν) p₀ / E · [ z (x − atan x)/x + (1 − ν) ((a² + z²) atan x − a z)/a ].
///
/// Limits: w(0) = π (1 − ν²) p₀ a / (2E), Hertz's surface approach δ = a²/R; for z ≫ a,
/// w → F (1 + ν)(3 − 2ν)/(2πE z), the point-force value. Both are unit-tested.
pub fn hertz_axial_displacement(e: f64, nu: f64, force: f64, a: f64, z: f64) -> f64 {
    let p0 = 3.0 * force / (2.0 * std::f64::consts::PI * a * a);
    if z <= 0.0 {
        return std::f64::consts::PI * (1.0 - nu * nu) * p0 * a / (2.0 * e);
    }
    let x = a / z;
    let at = x.atan();
    // x − atan x loses digits for small x; its series x³/3 − x⁵/5 + x⁷/7 is exact to 1e-17 there.
    let x_minus_atan = if x < 1e-2 { x.powi(3) / 3.0 - x.powi(5) / 5.0 + x.powi(7) / 7.0 } else { x - at };
    (1.0 + nu) * p0 / e * (z * x_minus_atan / x + (1.0 - nu) * ((a * a + z * z) * at - a * z) / a)
}

/// Plate force [N] of a linear elastic sphere (radius r [m], E [Pa], ν) between two rigid
/// frictionless plates at total plate approach Δ [m], Hertz corrected for the finite sphere.
///
/// Hertz's δ in F = (4/3) E* √r δ^{3/2} is the approach of the plate to points of the sphere far
/// from the contact, counted as if the sphere were a half-space whose distant points do not move.
/// In the sphere the reference point is the centre, at distance r from each contact, and each
/// contact's load also reaches the other pole. Superposing the two contacts' half-space fields
/// (each plate pushes its half-space by its own Hertz field; the centre stays at rest by symmetry),
/// the top pole moves by δ toward the centre under its own load and by w(2r) away from it under
/// the opposite load, so the plate-to-centre approach is
///
///   Δ/2 = δ − w(2r),     w = `hertz_axial_displacement` at depth 2r, F = F_Hertz(δ), a = √(r δ),
///
/// solved here for δ by fixed-point iteration (contraction ≈ 1.5 w/δ ≈ 0.55 √(δ/r) at ν = 0.3).
/// To our reading this is the structure of Tatara's correction (*J. Eng. Mater. Technol.* 113,
/// 1991, 285: the Boussinesq displacement of the opposite contact load at the distance 2r is
/// subtracted, there with the load lumped on a ring of radius a, a difference of O(a²/r²) of the
/// correction); the derivation above stands on its own and was not checked against the paper's
/// equations. Rejected alternative: δ − w(r) (one contact alone, the centre as its distant point)
/// moves the centre, which symmetry forbids, and doubles the correction. Neglected: the
/// correction that makes the spherical surface traction-free away from the contacts (the
/// half-space fields are not), of the same order F/(E r) as w(2r), and the large-strain terms.
/// The correction raises the force by ≈ 1.5 (3 − 2ν)/(3π(1 − ν)) √(Δ/(2r)) relative to plain Hertz
/// at δ = Δ/2 (+5.8 % at Δ/r = 0.02, ν = 0.3, at leading order) and vanishes as Δ → 0.
pub fn finite_sphere_plates_force(e: f64, nu: f64, r: f64, delta_total: f64) -> Result<f64, String> {
    if !(e > 0.0 && e.is_finite()) {
        return Err(format!("finite_sphere_plates_force: Young's modulus must be positive, got {e} Pa"));
    }
    if !(nu > -1.0 && nu < 0.5) {
        return Err(format!("finite_sphere_plates_force: Poisson ratio must lie in (-1, 0.5), got {nu}"));
    }
    if !(r > 0.0 && r.is_finite()) {
        return Err(format!("finite_sphere_plates_force: radius must be positive, got {r} m"));
    }
    if !(delta_total >= 0.0 && delta_total < r) {
        return Err(format!(
            "finite_sphere_plates_force: plate approach must lie in [0, r) = [0, {r}) m for this small-strain correction, got {delta_total} m"
        ));
    }
    if delta_total == 0.0 {
        // No load: the contact radius a = 0 would make the pressure scale p₀ undefined.
        return Ok(0.0);
    }
    let half = 0.5 * delta_total;
    let mut delta = half;
    for _ in 0..200 {
        let force = hertz_plane_force(e, nu, r, delta);
        let next = half + hertz_axial_displacement(e, nu, force, (r * delta).sqrt(), 2.0 * r);
        if (next - delta).abs() <= 1e-15 * r {
            return Ok(hertz_plane_force(e, nu, r, next));
        }
        delta = next;
    }
    Err(format!(
        "finite_sphere_plates_force: no fixed point at plate approach {delta_total} m (radius {r} m)"
    ))
}

/// Richardson extrapolation from three meshes refined by a constant ratio q = n₂/n₁ = n₃/n₂ > 1
/// (coarse f₁, medium f₂, fine f₃): observed order p = ln((f₁ − f₂)/(f₂ − f₃)) / ln q,
/// extrapolated value f₃ + (f₃ − f₂)/(q^p − 1), and as error bar the distance |f_ext − f₃| of the
/// fine mesh from it (Roache, *Verification and Validation in Computational Science*, 1998, §5.4;
/// the "grid-convergence" estimate with safety factor 1). When the three values are not monotone
/// (p undefined) the order is taken as 1 and the error bar as the larger of the two differences,
/// a deliberately conservative fallback.
#[derive(Clone, Copy, Debug)]
pub struct Richardson {
    pub value: f64,
    pub error: f64,
    pub order: f64,
}

pub fn richardson(f1: f64, f2: f64, f3: f64, ratio: f64) -> Richardson {
    let (d12, d23) = (f1 - f2, f2 - f3);
    if d23 == 0.0 {
        return Richardson { value: f3, error: d12.abs(), order: f64::INFINITY };
    }
    let g = d12 / d23;
    if g > 1.0 {
        let p = g.ln() / ratio.ln();
        let value = f3 - d23 / (ratio.powf(p) - 1.0);
        Richardson { value, error: (value - f3).abs(), order: p }
    } else {
        Richardson { value: f3 - d23, error: d12.abs().max(d23.abs()), order: 1.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const E: f64 = 23.3e3;
    const NU: f64 = 0.3;
    const R: f64 = 1e-3;

    /// The closed-form axial displacement against its two independent limits: Hertz's surface
    /// approach δ = a²/R at z = 0 (Johnson Eq. 4.23) and the Boussinesq point force far away.
    #[test]
    fn hertz_axial_displacement_limits() {
        let delta = 1e-5;
        let a = (R * delta).sqrt();
        let f = hertz_plane_force(E, NU, R, delta);
        let w0 = hertz_axial_displacement(E, NU, f, a, 0.0);
        // The z → 0⁺ branch of the closed form must join the surface value continuously.
        let w_eps = hertz_axial_displacement(E, NU, f, a, 1e-9 * a);
        assert!((w0 / delta - 1.0).abs() < 1e-12, "w(0) = {w0:e} m vs a²/R = {delta:e} m");
        assert!((w_eps / w0 - 1.0).abs() < 1e-8, "w(0+) = {w_eps:e} m vs w(0) = {w0:e} m");
        // Far field: the relative difference to the point force is O(a²/z²) = 1e-6 at z = 1000 a.
        let z = 1000.0 * a;
        let point = f * (1.0 + NU) * (3.0 - 2.0 * NU) / (2.0 * std::f64::consts::PI * E * z);
        let w = hertz_axial_displacement(E, NU, f, a, z);
        assert!((w / point - 1.0).abs() < 1e-5, "w(1000 a) = {w:e} m vs point force {point:e} m");
    }

    /// Small-load limit: the corrected force tends to plain Hertz at δ = Δ/2, and its relative
    /// excess follows the leading term 1.5 c √(Δ/(2r)), c = (3 − 2ν)/(3π(1 − ν)), from the point-force
    /// displacement at 2r; the next term is O(c² Δ/r), 1e-3 of the leading one at Δ/r = 1e-6.
    #[test]
    fn finite_sphere_force_tends_to_hertz_at_small_load() {
        let c = (3.0 - 2.0 * NU) / (3.0 * std::f64::consts::PI * (1.0 - NU));
        for dr in [1e-8, 1e-6] {
            let d = dr * R;
            let ratio =
                finite_sphere_plates_force(E, NU, R, d).unwrap() / hertz_plane_force(E, NU, R, 0.5 * d);
            let lead = 1.5 * c * (0.5 * dr).sqrt();
            assert!(ratio > 1.0 && ratio - 1.0 < 1e-3, "delta/r {dr}: ratio to plain Hertz {ratio}");
            assert!(
                ((ratio - 1.0) / lead - 1.0).abs() < 0.01,
                "delta/r {dr}: excess {:e} vs leading term {lead:e}",
                ratio - 1.0
            );
        }
        assert_eq!(finite_sphere_plates_force(E, NU, R, 0.0).unwrap(), 0.0);
    }

    /// Richardson on an exact power law f(h) = f* + C h^p, h = 1/n, recovers f* and p for the
    /// refinement ratios 2 and 1.5 (to rounding).
    #[test]
    fn richardson_recovers_a_power_law() {
        for (ratio, p) in [(2.0, 1.0), (1.5, 0.7), (1.5, 2.0)] {
            let f = |n: f64| 9.0 - 3.0 * n.powf(-p);
            let r = richardson(f(8.0), f(8.0 * ratio), f(8.0 * ratio * ratio), ratio);
            assert!((r.value - 9.0).abs() < 1e-12 && (r.order - p).abs() < 1e-9, "{ratio} {p}: {r:?}");
        }
    }

    #[test]
    fn finite_sphere_force_rejects_bad_input() {
        for (e, nu, r, d, what) in [
            (-1.0, NU, R, 1e-5, "Young"),
            (E, 0.5, R, 1e-5, "Poisson"),
            (E, NU, 0.0, 1e-5, "radius"),
            (E, NU, R, -1e-5, "plate approach"),
            (E, NU, R, 2e-3, "plate approach"),
        ] {
            let err = finite_sphere_plates_force(e, nu, r, d).unwrap_err();
            assert!(err.contains(what), "{err}");
        }
    }
}
