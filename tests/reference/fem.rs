//! Verification of the finite-element continuum reference (`mcdem::fem`): a homogeneous patch test
//! against closed-form stresses, one sphere between two plates against Hertz corrected for the
//! finite sphere, and the F-bar
//! (mean-dilatation) remedy against volumetric locking near incompressibility.

use mcdem::fem::material::Lame;
use mcdem::fem::mesh::cuboid;
use mcdem::fem::octant::intervals;
use mcdem::fem::solver::{Plane, Problem, Settings, Solver};
use mcdem::fem::{finite_sphere_plates_force, hertz_plane_force, Law, SphereRun, Volumetric, Walls};

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
    let mut p = Problem { mesh, law, lame, vol, fixed, planes, pairs: Vec::new() };
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
        intervals: intervals(level),
        walls,
        delta_over_r,
    };
    run.run(|_| {}).unwrap().iter().map(|p| p.plate_force).collect()
}

/// The convergence check of the two-plate sphere at Δ/r = 0.02 against a reference force `reference`
/// [N], given the plate forces `f1`, `f2` [N] of mesh levels 1 and 2 (4 and 8 intervals per edge).
///
/// Measured (validation/recorded/continuum_die/refinement.md): the plate force rises monotonically
/// under refinement, 8.160, 8.651, 8.916, 8.991, 9.019 Pa at 4, 8, 12, 16, 18 intervals, so every
/// level lies below the converged value and a reference the coarse levels exceed cannot be it.
/// Against the finite-sphere Hertz force (9.032 Pa, `finite_sphere_plates_force`) level 2 is at
/// −4.2 % and the Richardson value over 8/12/18 intervals (9.084 ± 0.065 Pa) at +0.6 %. The 5 %
/// bound is the measured −4.2 % plus 0.8 %, less than the 5.5 % step to level 1: a level-2 force
/// outside it is a regression of the solve; the convergence itself is the recorded study's claim.
fn converges_to(f1: f64, f2: f64, reference: f64) -> Result<(f64, f64), String> {
    let (e1, e2) = (f1 / reference - 1.0, f2 / reference - 1.0);
    if !(e1 < e2 && e2 < 0.0) {
        return Err(format!(
            "levels 1, 2 at {:+.2} %, {:+.2} %: not a monotone approach from below",
            100.0 * e1,
            100.0 * e2
        ));
    }
    if e2.abs() > 0.05 {
        return Err(format!("level 2 at {:+.2} %, beyond the 5 % bound", 100.0 * e2));
    }
    Ok((e1, e2))
}

/// Sphere between two rigid frictionless plates, linear, ν = 0.3 (far from locking), E = 23.3 kPa,
/// r = 1 mm, total plate approach Δ/r = 0.02 (reached through 0.01, one load step each): levels 1
/// and 2 must approach the finite-sphere Hertz force from below within 5 % at level 2, and the same
/// check must reject plain Hertz at δ = Δ/2 (which level 2 already exceeds, +1.4 %) and Hertz at
/// δ = Δ (a factor 2^{3/2} above it), so the test discriminates the reference, not only the solve.
#[test]
fn sphere_between_plates_converges_to_finite_sphere_hertz() {
    let (e, nu, r) = (23.3e3, 0.3, 1e-3);
    let steps = vec![0.01, 0.02];
    let f: Vec<f64> = (1..=2)
        .map(|l| sphere(Law::Linear, Volumetric::MeanDilatation, nu, l, Walls::Plates, steps.clone())[1])
        .collect();
    let d = 0.02 * r;
    let reference = finite_sphere_plates_force(e, nu, r, d).unwrap();
    let plain = hertz_plane_force(e, nu, r, 0.5 * d);
    let full_overlap = hertz_plane_force(e, nu, r, d);
    eprintln!(
        "plate force levels 1, 2: {:.5e}, {:.5e} N; finite-sphere Hertz {reference:.5e} N, plain Hertz {plain:.5e} N",
        f[0], f[1]
    );
    let (e1, e2) = converges_to(f[0], f[1], reference).unwrap_or_else(|m| panic!("finite-sphere Hertz: {m}"));
    eprintln!(
        "errors against finite-sphere Hertz: level 1 {:+.2} %, level 2 {:+.2} %",
        100.0 * e1,
        100.0 * e2
    );
    assert!(converges_to(f[0], f[1], plain).is_err(), "the check does not reject plain Hertz");
    assert!(converges_to(f[0], f[1], full_overlap).is_err(), "the check does not reject delta = Delta");
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

/// Two equal spheres pressed together (centres moved Δ closer) at the octant of each: A below, its
/// centre fixed; B above, its cut plane moved by −Δ. Returns the contact force on the whole sphere
/// [N] and the largest penetration left [m] relative to the pair's gap tolerance.
fn two_spheres(level: u32, matching: bool, delta_over_r: f64) -> (f64, f64) {
    use mcdem::fem::mesh::sphere_octant;
    use mcdem::fem::surface::{boundary_faces, SurfacePair};
    let (e, nu, r) = (23.3e3, 0.3, 1e-3);
    let n = intervals(level);
    let a = sphere_octant(r, n);
    let b = if matching { a.mirrored(2, r) } else { sphere_octant(r, n + 1).mirrored(2, r) };
    let mesh = a.joined(&b);
    let na = a.x.len();
    let on_cut = |x: &[f64; 3], k: usize, at: f64| (x[k] - at).abs() < 1e-9 * r;
    let mut fixed = Vec::new();
    for (i, x) in mesh.x.iter().enumerate() {
        for k in 0..2 {
            if on_cut(x, k, 0.0) {
                fixed.push((3 * i + k, 0.0));
            }
        }
        if i < na && on_cut(x, 2, 0.0) {
            fixed.push((3 * i + 2, 0.0));
        }
        if i >= na && on_cut(x, 2, 2.0 * r) {
            fixed.push((3 * i + 2, -delta_over_r * r));
        }
    }
    // The spheres' surfaces: boundary faces not lying in a cut plane.
    let surface = |elems: std::ops::Range<usize>| -> Vec<[usize; 4]> {
        boundary_faces(&mesh, elems)
            .into_iter()
            .filter(|f| {
                !(0..3)
                    .any(|k| f.iter().all(|&i| on_cut(&mesh.x[i], k, 0.0) || on_cut(&mesh.x[i], k, 2.0 * r)))
            })
            .collect()
    };
    let ea = a.hex.len();
    let slave = surface(0..ea);
    let master = surface(ea..mesh.hex.len());
    let pair = SurfacePair::new(&mesh, &slave, master, [0.0, 0.0, -1.0], 0.4 * r, e, 100.0).unwrap();
    let tol = pair.gap_tolerance;
    let p = Problem {
        mesh,
        law: Law::Linear,
        lame: Lame::from_e_nu(e, nu),
        vol: Volumetric::MeanDilatation,
        fixed,
        planes: vec![],
        pairs: vec![pair],
    };
    let mut solver = Solver::new(&p).unwrap();
    let mut state = solver.rest(&p);
    let eq = solver.solve(&p, &mut state, &Settings::default()).unwrap();
    (-4.0 * eq.pair_force[0][2], eq.pair_penetration[0] / tol)
}

/// Body–body contact (`fem::surface`: node to bilinear face along the line of centres,
/// augmented-Lagrangian penalty) against the rigid plane it must reproduce: two equal spheres
/// pressed together are, by symmetry, one sphere against a frictionless plane at r − Δ/2 from its
/// centre. Linear, ν = 0.3, Δ/r = 0.01.
///
/// * Matching meshes (B the mirror image of A, mesh level 1): in the symmetric solution A's contact
///   nodes meet B's on the mid-plane, so the two problems are the same up to the penetration Uzawa
///   leaves (1.9e-11 m against Δ/2 = 5e-6 m). Measured −0.002 %; bound 1e-4.
/// * Non-matching meshes (B one interval per edge finer): the contact patches no longer share
///   nodes and the difference is a discretisation error, measured −4.6 % at level 1 and −2.4 % at
///   level 2 (4 and 15 slave nodes in contact); it must shrink with refinement and stay within
///   3 % at level 2.
///
/// Known limit (docs/continuum.md): a slave node on a master vertex sees a kink of the gap's slope
/// between the faces around it, and Newton cycles there (matching meshes at Δ/r = 0.02).
#[test]
fn two_spheres_pressed_together_match_one_sphere_against_a_plane() {
    let d = 0.01;
    let plane =
        |level| sphere(Law::Linear, Volumetric::MeanDilatation, 0.3, level, Walls::Plates, vec![d])[0];
    let (f, pen) = two_spheres(1, true, d);
    let rel = f / plane(1) - 1.0;
    assert!(
        rel.abs() < 1e-4 && pen <= 1.0,
        "matching meshes: {f:e} N vs plane {:e} N ({rel:+e}), penetration/tol {pen}",
        plane(1)
    );
    let errs: Vec<f64> = (1..=2)
        .map(|level| {
            let (f, pen) = two_spheres(level, false, d);
            assert!(pen <= 1.0, "level {level}: penetration/tol {pen}");
            f / plane(level) - 1.0
        })
        .collect();
    assert!(
        errs[1].abs() < errs[0].abs() && errs[1].abs() < 0.03,
        "non-matching meshes, levels 1, 2: {errs:?}"
    );
}

/// The bcc cell's set-up (`fem::bcc`: the corner sphere whole, held only by frictionless contacts,
/// and the centre sphere's octant) at its first load step, Δ/r = 0.02, Neo-Hookean ν = 0.45, 4
/// intervals: the corner sphere is in equilibrium under the plate, the two side walls and the
/// centre sphere, so in the octant the plate force (a quarter of the die's) balances the contact's
/// z component and each side wall its x and y components. The bound 1e-3 is ten times the Newton
/// tolerance of the bcc runs (1e-4 of the largest reaction). The diagonal chain loads the plate
/// and the side walls alike (measured 0.351 and 0.359 Pa; the DEM laws give 0.42–0.44 Pa on both
/// at ν = 0.5).
#[test]
fn bcc_corner_sphere_is_in_equilibrium_at_the_first_load_step() {
    use mcdem::fem::bcc::BccRun;
    let run = BccRun {
        spec: SphereRun {
            radius: 1e-3,
            youngs_modulus: 23.3e3,
            poisson_ratio: 0.45,
            law: Law::NeoHookean,
            vol: Volumetric::MeanDilatation,
            intervals: 4,
            walls: Walls::Die,
            delta_over_r: vec![0.02],
        },
    };
    let pt = run.run(|_| {}).unwrap()[0];
    let quarter = |f: f64| f / 4.0;
    for (wall, along, what) in [
        (quarter(pt.plate_force), pt.contact[2], "plate / z"),
        (quarter(pt.side_force), pt.contact[0], "side / x"),
    ] {
        let rel = (wall + along) / wall;
        assert!(
            wall > 0.0 && rel.abs() < 1e-3,
            "{what}: wall {wall:e} N, contact component {along:e} N ({rel:+e})"
        );
    }
    assert!(pt.contact_nodes >= 3 && pt.plate_nodes >= 1 && pt.side_nodes >= 1, "{pt:?}");
}
