//! Physics self-checks of the contact core against analytic limits and independent formulas.
//! `mcdem validate` runs them; every check states its reference, its error and its tolerance.

use crate::physics::brodu2015::{bracket, bracket_on_sphere};
use crate::physics::contact_set::{radius_changes, ContactLoad, McParams};
use crate::physics::ghods2022::{Cap, MprTest};
use crate::physics::hertz::hertz_force;
use crate::physics::material::{Material, PairCoeffs};
use crate::physics::pair::{particle_particle, particle_wall, Body, WallPoint};
use crate::physics::Vec3;

/// Outcome of one check.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Check {
    pub name: &'static str,
    pub what: &'static str,
    pub error: f64,
    pub tolerance: f64,
    pub passed: bool,
}

fn check(name: &'static str, what: &'static str, error: f64, tolerance: f64) -> Check {
    Check { name, what, error, tolerance, passed: error.is_finite() && error <= tolerance }
}

/// Paper Table 1 hydrogel: E = 23.3 kPa, ν = 0.5.
pub const HYDROGEL_E: f64 = 23.3e3;
pub const HYDROGEL_NU: f64 = 0.5;

/// Relative difference |a − b| / max(|b|, floor).
pub fn rel(a: f64, b: f64, floor: f64) -> f64 {
    (a - b).abs() / b.abs().max(floor)
}

/// Eq. 2 evaluated from 3-D vectors on a sphere equals the closed form B(s) (docs/spec.md §2).
fn sphere_bracket() -> Check {
    let r = 1e-3;
    let mut worst: f64 = 0.0;
    for &nu in &[0.0, 0.25, 0.3, 0.5] {
        for i in 1..=179 {
            let a = (i as f64).to_radians();
            let pk = Vec3::new(0.0, 0.0, r);
            let pc = Vec3::new(r * a.sin(), 0.0, r * a.cos());
            let u = (pc - pk).normalize();
            let b3 = bracket(&(-pk / r), &(-pc / r), &u, nu);
            worst = worst.max((b3 - bracket_on_sphere((a / 2.0).sin(), nu)).abs());
        }
    }
    check(
        "eq2_sphere",
        "Eq. 2 from 3-D vectors vs B(s) = 2(1-v) + 2(1-2v)s - (7-8v)s^2, max abs diff",
        worst,
        1e-12,
    )
}

/// Eq. 2 equals the Boussinesq point-load displacement (Johnson 1985, eq. 3.21) projected on n_c,
/// written here in the load's own Cartesian frame: an independent formula.
pub fn boussinesq_projected(nk: &Vec3, nc: &Vec3, chord: &Vec3, nu: f64) -> f64 {
    // Frame: z along the inward normal n_k (into the solid), x along the horizontal chord part.
    let z = chord.dot(nk);
    let h = chord - nk * z;
    let rho = chord.norm();
    let (ex, hx) = if h.norm() > 0.0 { (h.normalize(), h.norm()) } else { (Vec3::zeros(), 0.0) };
    // u_x, u_z per unit P(1+ν)/(2πE), times ρ (Eq. 2 carries 1/d outside the bracket).
    let ux = hx * z / (rho * rho) - (1.0 - 2.0 * nu) * hx / (rho + z);
    let uz = z * z / (rho * rho) + 2.0 * (1.0 - nu);
    (ex * ux + nk * uz).dot(nc)
}

fn boussinesq_identity() -> Check {
    // Deterministic pseudo-random geometries (a fixed LCG keeps the check reproducible).
    let mut rng = crate::rng::Lcg64(0x9E37_79B9_7F4A_7C15);
    let mut next = || rng.symmetric();
    let mut worst: f64 = 0.0;
    for _ in 0..2000 {
        let nk = Vec3::new(next(), next(), next()).normalize();
        let nc = Vec3::new(next(), next(), next()).normalize();
        let mut chord = Vec3::new(next(), next(), next());
        // Points inside the half-space (z > 0 along n_k), away from the 1 + n_k·u = 0 line.
        if chord.dot(&nk) < 0.0 {
            chord -= 2.0 * chord.dot(&nk) * nk;
        }
        let nu = 0.25 * (next() + 1.0);
        let u = chord.normalize();
        let b = bracket(&nk, &nc, &u, nu);
        let reference = boussinesq_projected(&nk, &nc, &chord, nu);
        worst = worst.max((b - reference).abs());
    }
    check(
        "eq2_boussinesq",
        "Eq. 2 bracket vs Boussinesq displacement projected on n_c, 2000 random geometries, max abs diff",
        worst,
        1e-12,
    )
}

fn limits_of_b() -> Check {
    let mut worst: f64 = 0.0;
    for &nu in &[0.0, 0.2, 0.3, 0.45, 0.5] {
        worst = worst.max((bracket_on_sphere(0.0, nu) - 2.0 * (1.0 - nu)).abs());
        worst = worst.max((bracket_on_sphere(1.0, nu) - (2.0 * nu - 3.0)).abs());
    }
    check("eq2_limits", "B(0) = 2(1-v) and B(1) = 2v - 3, max abs diff", worst, 1e-14)
}

fn hertz_closed_form() -> Check {
    let m = Material::hertz(HYDROGEL_E, HYDROGEL_NU).unwrap();
    let c = PairCoeffs::new(&m, &m, 0.95, 0.0).unwrap();
    let r = 1e-3;
    let mut worst: f64 = 0.0;
    for i in 1..=50 {
        let delta = r * 0.3 * i as f64 / 50.0;
        let bi = Body {
            x: Vec3::new(0.0, 0.0, 2.0 * r - delta),
            v: Vec3::zeros(),
            omega: Vec3::zeros(),
            radius: r,
            mass: 1e-6,
        };
        let bj = Body { x: Vec3::zeros(), ..bi };
        let f = particle_particle(&c, &bi, &bj, 0.0, 0.0, 1e-5, &mut Vec3::zeros()).unwrap().unwrap();
        // E* = E / (2(1 − ν²)) for identical spheres, R = r/2: independent of PairCoeffs.
        let e_star = HYDROGEL_E / (2.0 * (1.0 - HYDROGEL_NU * HYDROGEL_NU));
        let reference = 4.0 / 3.0 * e_star * (r / 2.0).sqrt() * delta.powf(1.5);
        worst = worst.max(rel(f.force_i.z, reference, 1e-300));
    }
    check(
        "hertz_closed_form",
        "static pair force vs (4/3) E* sqrt(R) delta^1.5 up to delta = 0.3 r, max rel diff",
        worst,
        1e-13,
    )
}

fn mpr_limits() -> Check {
    let r = 1e-3;
    let contacts: Vec<ContactLoad> = [(0.0, 0.0, -1.0), (0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 0.6, 0.8)]
        .iter()
        .map(|&(x, y, z)| ContactLoad { point: Vec3::new(x, y, z) * 0.95 * r, force: 1e-3 })
        .collect();
    let base = McParams { radius: r, youngs_modulus: HYDROGEL_E, poisson_ratio: 0.3, gamma: 0.81, cap: None };
    let run = |cap| {
        let mut d = vec![0.0; contacts.len()];
        let mut fb = vec![false; contacts.len()];
        radius_changes(&McParams { cap, ..base }, &contacts, &mut d, &mut fb).unwrap();
        d
    };
    let standard = run(None);
    let zero = run(Some(Cap { mpr: 0.0, test: MprTest::Abs }));
    let large = run(Some(Cap { mpr: 1e6, test: MprTest::Abs }));
    let err = zero.iter().map(|v| v.abs()).fold(0.0, f64::max)
        + standard.iter().zip(&large).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    check(
        "eq3_limits",
        "MPR = 0 gives zero correction and MPR = 1e6 equals standard MC, bit for bit (abs diff)",
        err,
        0.0,
    )
}

fn newton_and_torque() -> Check {
    let m = Material::hertz(HYDROGEL_E, 0.3).unwrap();
    let c = PairCoeffs::new(&m, &m, 0.5, 0.4).unwrap();
    let bi = Body {
        x: Vec3::new(0.3e-3, 0.2e-3, 1.9e-3),
        v: Vec3::new(0.1, -0.2, -0.3),
        omega: Vec3::new(5.0, 1.0, -2.0),
        radius: 1e-3,
        mass: 4e-6,
    };
    let bj = Body {
        x: Vec3::zeros(),
        v: Vec3::new(-0.1, 0.3, 0.2),
        omega: Vec3::new(-1.0, 3.0, 2.0),
        radius: 1.1e-3,
        mass: 6e-6,
    };
    let mut shear = Vec3::new(1e-6, -2e-6, 0.5e-6);
    let f = particle_particle(&c, &bi, &bj, 1e-5, -2e-5, 1e-5, &mut shear).unwrap().unwrap();
    // Angular momentum about the origin: τ_i + τ_j + x_i × F_i + x_j × (−F_i) = 0.
    let l = f.torque_i + f.torque_j + bi.x.cross(&f.force_i) - bj.x.cross(&f.force_i);
    let scale = f.force_i.norm() * bi.radius;
    check(
        "newton_torque",
        "pair torque balance |tau_i + tau_j + (x_i - x_j) x F_i| / (|F| r)",
        l.norm() / scale,
        1e-12,
    )
}

/// A sphere between two plates under lagged MC converges to the fixed point
/// F = Hertz(R = r + Δ, δ0 + Δ), Δ = −γ(1+ν)F/(2πE·d)·(2ν−3) with the chord d = 2(r − δ0)
/// between the two wall contact points (antipodal contacts, docs/spec.md §2; R uses the modified radius).
fn two_plate_fixed_point() -> Check {
    let (r, nu, gamma, e) = (1e-3, HYDROGEL_NU, 0.82, HYDROGEL_E);
    let sphere = Material::new(e, nu, gamma, None).unwrap();
    let wall = Material::hertz(5e7, 0.5).unwrap();
    let c = PairCoeffs::new(&sphere, &wall, 0.95, 0.0).unwrap();
    let delta0 = 0.1 * r;
    let b = Body { x: Vec3::zeros(), v: Vec3::zeros(), omega: Vec3::zeros(), radius: r, mass: 1e-6 };
    let walls = [Vec3::new(0.0, 0.0, -(r - delta0)), Vec3::new(0.0, 0.0, r - delta0)];
    let params = McParams::new(r, &sphere).unwrap();
    let mut forces = [0.0; 2];
    let mut delta = [0.0; 2];
    let mut fb = [false; 2];
    for _ in 0..200 {
        let loads = [0, 1].map(|k| ContactLoad { point: walls[k], force: forces[k] });
        radius_changes(&params, &loads, &mut delta, &mut fb).unwrap();
        for k in 0..2 {
            let w = WallPoint { point: walls[k], velocity: Vec3::zeros() };
            let f = particle_wall(&c, &b, &w, delta[k], 1e-5, &mut Vec3::zeros()).unwrap().unwrap();
            forces[k] = f.normal.force;
        }
    }
    // Independent fixed point by bisection on the closed forms.
    let chord = 2.0 * (r - delta0);
    let k_anti = -gamma * (1.0 + nu) / (2.0 * std::f64::consts::PI * e * chord) * (2.0 * nu - 3.0);
    let g = |f: f64| hertz_force(c.e_star, r + k_anti * f, delta0 + k_anti * f) - f;
    // Bracket the physical (smallest) root: g(0) > 0 and g < 0 at ten times the Hertz force; for
    // much larger F the lagged map has a second, divergent branch.
    let (mut lo, mut hi) = (0.0, 10.0 * hertz_force(c.e_star, r, delta0));
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid) > 0.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    check(
        "two_plate_mc",
        "sphere between plates, lagged standard MC vs closed-form fixed point, rel diff",
        rel(forces[1], 0.5 * (lo + hi), 1e-300),
        1e-10,
    )
}

/// Energy of an undamped frictionless head-on collision (e = 1, μ = 0) with velocity Verlet.
fn energy_conservation() -> Check {
    let m = Material::hertz(HYDROGEL_E, HYDROGEL_NU).unwrap();
    let c = PairCoeffs::new(&m, &m, 1.0, 0.0).unwrap();
    let (r, rho) = (1e-3, 1000.0);
    let mass = rho * 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    let mut x = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 2.0 * r + 1e-5)];
    let mut v = [Vec3::new(0.0, 0.0, 0.05), Vec3::new(0.0, 0.0, -0.05)];
    let e0 = 0.5 * mass * (v[0].norm_squared() + v[1].norm_squared());
    let dt = 1e-6;
    let body = |x: Vec3, v: Vec3| Body { x, v, omega: Vec3::zeros(), radius: r, mass };
    let force = |x: &[Vec3; 2], v: &[Vec3; 2]| {
        particle_particle(&c, &body(x[0], v[0]), &body(x[1], v[1]), 0.0, 0.0, dt, &mut Vec3::zeros())
            .unwrap()
            .map_or(Vec3::zeros(), |f| f.force_i)
    };
    let mut f = force(&x, &v);
    let mut steps = 0;
    while steps < 200_000 && (x[1].z - x[0].z < 2.0 * r + 2e-5 || v[1].z < 0.0) {
        v[0] += 0.5 * dt * f / mass;
        v[1] -= 0.5 * dt * f / mass;
        x[0] += dt * v[0];
        x[1] += dt * v[1];
        f = force(&x, &v);
        v[0] += 0.5 * dt * f / mass;
        v[1] -= 0.5 * dt * f / mass;
        steps += 1;
    }
    let e1 = 0.5 * mass * (v[0].norm_squared() + v[1].norm_squared());
    check(
        "energy_collision",
        "undamped frictionless collision, kinetic energy after vs before, rel diff (dt = 1e-6 s)",
        rel(e1, e0, 1e-300),
        1e-6,
    )
}

/// All self-checks, in a stable order.
pub fn run_all() -> Vec<Check> {
    vec![
        sphere_bracket(),
        boussinesq_identity(),
        limits_of_b(),
        hertz_closed_form(),
        mpr_limits(),
        newton_and_torque(),
        two_plate_fixed_point(),
        energy_conservation(),
    ]
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_self_check_passes() {
        for c in super::run_all() {
            assert!(c.passed, "{}: error {:e} > tolerance {:e} ({})", c.name, c.error, c.tolerance, c.what);
        }
    }

    #[test]
    fn displacement_helper_matches_kernel_term() {
        use super::*;
        use crate::physics::brodu2015::displacement;
        let pk = Vec3::new(0.0, 0.0, -0.9e-3);
        let pc = Vec3::new(0.9e-3, 0.0, 0.0);
        let d = displacement(&pk, &pc, 1e-3, 1.0, HYDROGEL_E, 0.3);
        let p =
            McParams { radius: 1e-3, youngs_modulus: HYDROGEL_E, poisson_ratio: 0.3, gamma: 1.0, cap: None };
        let loads = [ContactLoad { point: pk, force: 1e-3 }, ContactLoad { point: pc, force: 0.0 }];
        let (mut out, mut fb) = ([0.0; 2], [false; 2]);
        radius_changes(&p, &loads, &mut out, &mut fb).unwrap();
        // Same formula, brought over one denominator in the kernel: equal to round-off.
        assert!((out[1] - d).abs() <= 1e-14 * d.abs(), "{} vs {d}", out[1]);
        assert_eq!(out[0], 0.0);
    }
}
