//! Verification of the finite-element continuum reference (`mcdem::fem`): a homogeneous patch test
//! against closed-form stresses, one sphere between two plates against Hertz, and the F-bar
//! (mean-dilatation) remedy against volumetric locking near incompressibility.

use mcdem::fem::material::Lame;
use mcdem::fem::mesh::cuboid;
use mcdem::fem::solver::{Plane, Problem, Settings, Solver};
use mcdem::fem::{hertz_plane_force, Law, SphereRun, Volumetric, Walls};

/// Unit cube of distorted hexahedra between frictionless walls: symmetry planes x = y = z = 0,
/// side walls at x = 1 and y = 1, the top plate pushed down to z = 1 − d. The exact solution is
/// homogeneous uniaxial strain F = diag(1, 1, s), s = 1 − d, which trilinear hexahedra represent
/// exactly on any mesh, so the wall reactions must match the closed-form first Piola stress to
/// solver tolerance. Returns (top force, side force) on the unit reference faces [N per Pa·m²].
fn uniaxial_strain(law: Law, vol: Volumetric, lame: Lame, d: f64) -> (f64, f64) {
    let mesh = cuboid([1.0, 1.0, 1.0], [3, 3, 3], 0.2);
    let mut fixed = Vec::new();
    for (i, x) in mesh.x.iter().enumerate() {
        for (a, xa) in x.iter().enumerate() {
            if xa.abs() < 1e-12 {
                fixed.push((3 * i + a, 0.0));
            }
        }
    }
    let planes = vec![
        Plane { axis: 2, pos: 1.0, upper: true },
        Plane { axis: 0, pos: 1.0, upper: true },
        Plane { axis: 1, pos: 1.0, upper: true },
    ];
    let mut p = Problem { mesh, law, lame, vol, fixed, planes };
    let mut solver = Solver::new(&p).unwrap();
    let mut state = solver.rest(&p);
    let set = Settings::default();
    // Two load steps so the active set is established on the way, as in the sphere runs.
    let mut eq = None;
    for f in [0.5, 1.0] {
        p.planes[0].pos = 1.0 - f * d;
        eq = Some(solver.solve(&p, &mut state, &set).unwrap());
    }
    let eq = eq.unwrap();
    (eq.plane_force[0], eq.plane_force[1])
}

#[test]
fn patch_test_uniaxial_strain_linear_and_neo_hookean() {
    let lame = Lame::from_e_nu(23.3e3, 0.45);
    let (mu, lambda) = (lame.mu, lame.lambda);
    let d = 0.1;
    let s: f64 = 1.0 - d;
    // Linear (ε_zz = −d): σ_zz = −(λ + 2μ) d, σ_xx = −λ d; the walls carry the negatives.
    let lin = [(lambda + 2.0 * mu) * d, lambda * d];
    // Neo-Hookean (Bonet & Wood Eq. 6.28 pulled back): P = μ (F − F⁻ᵀ) + λ ln J F⁻ᵀ, J = s:
    // P_zz = μ (s − 1/s) + λ ln s / s, P_xx = λ ln s, reference faces of unit area.
    let nh = [-(mu * (s - 1.0 / s) + lambda * s.ln() / s), -lambda * s.ln()];
    for vol in [Volumetric::Full, Volumetric::MeanDilatation] {
        for (law, exact) in [(Law::Linear, lin), (Law::NeoHookean, nh)] {
            let (top, side) = uniaxial_strain(law, vol, lame, d);
            for (got, want, what) in [(top, exact[0], "top"), (side, exact[1], "side")] {
                let rel = (got / want - 1.0).abs();
                assert!(
                    rel < 1e-8,
                    "{law:?} {vol:?} {what}: {got:.12e} N vs exact {want:.12e} N (rel {rel:.2e})"
                );
            }
        }
    }
}

fn sphere(law: Law, vol: Volumetric, nu: f64, level: u32, walls: Walls, delta_over_r: Vec<f64>) -> Vec<f64> {
    let run = SphereRun {
        radius: 1e-3,
        youngs_modulus: 23.3e3,
        poisson_ratio: nu,
        law,
        vol,
        level,
        walls,
        delta_over_r,
    };
    run.run(|_| {}).unwrap().iter().map(|p| p.plate_force).collect()
}

/// Hertz for the sphere between two rigid plates: Δ is the total approach of the plates, each of
/// the two contacts is compressed by δ = Δ/2, and F = (4/3) E* √r δ^{3/2}, E* = E/(1 − ν²)
/// (`hertz_plane_force`). Linear elasticity, ν = 0.3 (far from locking), Δ/r = 0.01 and 0.02.
#[test]
fn sphere_between_plates_matches_hertz() {
    let (e, nu, r) = (23.3e3, 0.3, 1e-3);
    let steps = vec![0.01, 0.02];
    let levels: Vec<Vec<f64>> = (1..=2)
        .map(|l| sphere(Law::Linear, Volumetric::MeanDilatation, nu, l, Walls::Plates, steps.clone()))
        .collect();
    for (i, dr) in steps.iter().enumerate() {
        let hz = hertz_plane_force(e, nu, r, 0.5 * dr * r);
        let errs: Vec<f64> = levels.iter().map(|f| f[i] / hz - 1.0).collect();
        eprintln!("delta/r {dr}: hertz {hz:.5e} N, relative errors by level {errs:?}");
        // Measured at level 2 (docs/continuum.md): +5.5 % at 0.01, +1.4 % at 0.02. The bound is that
        // plus ~0.5 % margin, a regression check of the coarse solve and of the contact convention
        // (δ = Δ instead of Δ/2 would be off by a factor 2^{3/2}), not a convergence claim: level 3
        // gives +3.8 % and +5.3 %, drifting away from Hertz at 0.02, an open defect (docs/continuum.md).
        let tol = if i == 0 { 0.06 } else { 0.02 };
        assert!(
            errs[1].abs() < tol,
            "level 2 at delta/r {dr}: {:.2} % from Hertz (bound {:.0} %)",
            100.0 * errs[1],
            100.0 * tol
        );
    }
}

/// Volumetric locking: at ν = 0.499 the plain trilinear hexahedron is over-stiff; the
/// mean-dilatation (F-bar) element is not and follows the ν = 0.45 → 0.49 trend.
#[test]
fn f_bar_removes_locking() {
    let steps = vec![0.02];
    let f = |nu: f64, vol: Volumetric| sphere(Law::NeoHookean, vol, nu, 1, Walls::Plates, steps.clone())[0];
    let plain = f(0.499, Volumetric::Full);
    let fbar = f(0.499, Volumetric::MeanDilatation);
    let f45 = f(0.45, Volumetric::MeanDilatation);
    let f49 = f(0.49, Volumetric::MeanDilatation);
    eprintln!("plate force at delta/r 0.02: nu 0.45 {f45:.5e}, 0.49 {f49:.5e}, 0.499 F-bar {fbar:.5e}, plain {plain:.5e} N");
    assert!(plain > 1.2 * fbar, "plain {plain:.4e} N not clearly stiffer than F-bar {fbar:.4e} N");
    // Near the incompressible limit the force at small approach follows Hertz's E* = E/(1 − ν²):
    // the F-bar forces must scale with it from 0.45 to 0.49 and from 0.49 to 0.499 (E* ratios
    // 1.0495 and 1.0119); 3 % allows for the sphere's bulk compliance, which falls with ν, and the
    // Neo-Hookean departure from Hertz at Δ/r = 0.02. A locked element overshoots the second by
    // far more (the plain/F-bar ratio above).
    let estar = |nu: f64| 1.0 / (1.0 - nu * nu);
    for (hi, lo, nh, nl) in [(f49, f45, 0.49, 0.45), (fbar, f49, 0.499, 0.49)] {
        let dev = (hi / lo) / (estar(nh) / estar(nl)) - 1.0;
        assert!(
            dev.abs() < 0.03,
            "F-bar force ratio nu {nh}/{nl} departs {:.2} % from the E* ratio",
            100.0 * dev
        );
    }
}
