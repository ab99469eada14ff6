//! Checks of the implicit MPM (src/mpm) against closed forms and conservation laws.

use mcdem::mpm::constitutive::{Constitutive, Hooke, Law, Mat, NeoHookean, SaintVenantKirchhoff};

const LAMBDA: f64 = 100e6;
const MU: f64 = 1.5e6;

fn laws() -> [(&'static str, Law); 3] {
    [
        ("hooke", Law::Hooke(Hooke::new(LAMBDA, MU).unwrap())),
        ("svk", Law::SaintVenantKirchhoff(SaintVenantKirchhoff::new(LAMBDA, MU).unwrap())),
        ("neohookean", Law::NeoHookean(NeoHookean::new(LAMBDA, MU).unwrap())),
    ]
}

/// A general F with J > 0: stretch, shear and rotation mixed.
fn sample_f<const D: usize>() -> Mat<D> {
    Mat::<D>::from_fn(|i, j| {
        let base = if i == j { 1.0 + 0.07 * (i as f64 + 1.0) } else { 0.0 };
        base + 0.05 * ((3 * i + 2 * j) as f64).sin()
    })
}

fn check_tangent<const D: usize>() {
    for (name, law) in laws() {
        let f = sample_f::<D>();
        let (p0, a) = <Law as Constitutive<D>>::pk1_tangent(&law, &f).unwrap();
        assert!((p0 - <Law as Constitutive<D>>::pk1(&law, &f).unwrap()).norm() == 0.0);
        let scale = a.iter().flatten().flatten().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        // Central differences: truncation O(h²)·|P'''| ~ 1e-12 relative for h = 1e-6, round-off
        // ε|P|/h ~ 1e-10 relative; 1e-6 leaves room for neither to matter yet catches any wrong term
        // (the smallest true term, μ = 1.5e6 against scale ~1e8, is 1.5e-2 relative).
        let h = 1e-6;
        for k in 0..D {
            for l in 0..D {
                let mut fp = f;
                let mut fm = f;
                fp[(k, l)] += h;
                fm[(k, l)] -= h;
                let pp = <Law as Constitutive<D>>::pk1(&law, &fp).unwrap();
                let pm = <Law as Constitutive<D>>::pk1(&law, &fm).unwrap();
                for i in 0..D {
                    for j in 0..D {
                        let fd = (pp[(i, j)] - pm[(i, j)]) / (2.0 * h);
                        let err = (fd - a[i][j][k][l]).abs() / scale;
                        assert!(
                            err < 1e-6,
                            "{name} D={D}: dP{i}{j}/dF{k}{l} = {} against FD {fd} (rel {err:.2e})",
                            a[i][j][k][l]
                        );
                    }
                }
                // P = ∂W/∂F, the energy used in the energy balance.
                let wp = <Law as Constitutive<D>>::energy(&law, &fp).unwrap();
                let wm = <Law as Constitutive<D>>::energy(&law, &fm).unwrap();
                let fd = (wp - wm) / (2.0 * h);
                let err = (fd - p0[(k, l)]).abs() / p0.norm();
                assert!(
                    err < 1e-6,
                    "{name} D={D}: dW/dF{k}{l} = {fd} against P = {} (rel {err:.2e})",
                    p0[(k, l)]
                );
            }
        }
    }
}

#[test]
fn tangents_match_central_differences_2d() {
    check_tangent::<2>();
}

#[test]
fn tangents_match_central_differences_3d() {
    check_tangent::<3>();
}

#[test]
fn zero_stress_at_identity() {
    for (name, law) in laws() {
        let p2 = <Law as Constitutive<2>>::pk1(&law, &Mat::<2>::identity()).unwrap();
        let p3 = <Law as Constitutive<3>>::pk1(&law, &Mat::<3>::identity()).unwrap();
        assert_eq!(p2.norm() + p3.norm(), 0.0, "{name}");
    }
}

/// Uniaxial strain F = diag(1, s) in plane strain, written out from Eqs. 17 and 18.
#[test]
fn uniaxial_strain_closed_forms() {
    for s in [0.8, 0.95, 1.05, 1.2] {
        let f = Mat::<2>::new(1.0, 0.0, 0.0, s);
        // Neo-Hookean: P = μ(F − F⁻ᵀ) + λ ln J F⁻ᵀ with J = s.
        let nh = NeoHookean::new(LAMBDA, MU).unwrap();
        let p = <NeoHookean as Constitutive<2>>::pk1(&nh, &f).unwrap();
        let pyy = MU * (s - 1.0 / s) + LAMBDA * s.ln() / s;
        let pxx = LAMBDA * s.ln();
        assert!((p[(1, 1)] - pyy).abs() <= 1e-12 * pyy.abs(), "NH P_yy {} vs {pyy}", p[(1, 1)]);
        assert!((p[(0, 0)] - pxx).abs() <= 1e-12 * pxx.abs(), "NH P_xx {} vs {pxx}", p[(0, 0)]);
        assert!(p[(0, 1)].abs() + p[(1, 0)].abs() == 0.0);
        // SVK: γ_yy = (s² − 1)/2, S_yy = (λ + 2μ) γ_yy, S_xx = λ γ_yy, P = F S.
        let svk = SaintVenantKirchhoff::new(LAMBDA, MU).unwrap();
        let p = <SaintVenantKirchhoff as Constitutive<2>>::pk1(&svk, &f).unwrap();
        let g = 0.5 * (s * s - 1.0);
        assert!((p[(1, 1)] - s * (LAMBDA + 2.0 * MU) * g).abs() <= 1e-12 * p[(1, 1)].abs());
        assert!((p[(0, 0)] - LAMBDA * g).abs() <= 1e-12 * p[(0, 0)].abs());
    }
}

#[test]
fn finite_strain_laws_are_frame_indifferent() {
    let f = sample_f::<3>();
    let (a, b) = (0.7f64, -1.1f64);
    let q = Mat::<3>::new(a.cos(), -a.sin(), 0.0, a.sin(), a.cos(), 0.0, 0.0, 0.0, 1.0)
        * Mat::<3>::new(1.0, 0.0, 0.0, 0.0, b.cos(), -b.sin(), 0.0, b.sin(), b.cos());
    for (name, law) in laws() {
        let p = <Law as Constitutive<3>>::pk1(&law, &f).unwrap();
        let pq = <Law as Constitutive<3>>::pk1(&law, &(q * f)).unwrap();
        let err = (pq - q * p).norm() / p.norm();
        if name == "hooke" {
            // The small-strain law is not objective: the rotation itself produces stress.
            assert!(err > 1e-2, "hooke unexpectedly objective ({err:.2e})");
        } else {
            // P(QF) = Q P(F) exactly up to round-off of products of O(1) matrices (~1e-15).
            assert!(err < 1e-13, "{name}: P(QF) − Q P(F) relative {err:.2e}");
        }
    }
}

#[test]
fn bad_moduli_are_rejected_with_their_name() {
    let e = NeoHookean::new(3e6, -1.0).unwrap_err();
    assert!(e.contains("μ") && e.contains("positive"), "{e}");
    let e = SaintVenantKirchhoff::new(-2.0, 1e6).unwrap_err();
    assert!(e.contains("λ"), "{e}");
    let nh = NeoHookean::new(3e6, 1e6).unwrap();
    let inverted = Mat::<2>::new(1.0, 0.0, 0.0, -0.5);
    assert!(<NeoHookean as Constitutive<2>>::pk1(&nh, &inverted).is_err());
}

// ---------------------------------------------------------------------------------------------
// The implicit step on one body.

use mcdem::mpm::grid::{Grid, Vector};
use mcdem::mpm::implicit::{step, Body, Fixed, Locking, Newton, StepOptions, Wall, WallsOn, Workspace};
use mcdem::mpm::points::Points;

const RHO: f64 = 990.0;

/// A block [0, w]^D (height `hgt` along the last axis) of `ppc` points per cell and axis on a grid
/// of cell size h that leaves `margin` cells around it.
fn block<const D: usize>(law: Law, h: f64, cells: [usize; D], ppc: usize, margin: usize) -> Body<D> {
    let origin = Vector::<D>::from_element(-(margin as f64) * h);
    let total = cells.map(|c| c + 2 * margin);
    let grid = Grid::new(origin, h, total).unwrap();
    let hi = Vector::<D>::from_fn(|d, _| cells[d] as f64 * h);
    let points = Points::seed(Vector::<D>::zeros(), hi, origin, h, ppc, RHO, |x| {
        (0..D).all(|d| x[d] > 0.0 && x[d] < hi[d])
    });
    Body { grid, points, law }
}

/// Solves f(a) = 0 on [lo, hi] by bisection (f changes sign there), to round-off.
fn bisect(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    let flo = f(lo);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if (f(mid) > 0.0) == (flo > 0.0) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Closed-form plane-strain (D = 2) or 3-D uniaxial-stress compression between frictionless plates
/// to the axial stretch s: lateral stretch a (σ_lateral = 0) and axial first Piola–Kirchhoff P.
fn uniaxial_stress(law: &Law, d: usize, s: f64) -> (f64, f64) {
    let (l, m) = law.lame();
    let nl = (d - 1) as f64; // number of lateral axes
    match law {
        // P = μ(F − F⁻ᵀ) + λ ln J F⁻ᵀ, J = a^{D−1} s: lateral μ(a − 1/a) + λ ln J / a = 0.
        Law::NeoHookean(_) => {
            let a = bisect(|a| m * (a * a - 1.0) + l * (a.powf(nl) * s).ln(), 0.5, 2.0);
            let j = a.powf(nl) * s;
            (a, m * (s - 1.0 / s) + l * j.ln() / s)
        }
        // S = λ tr γ I + 2μ γ: lateral λ(nl γ_a + γ_s) + 2μ γ_a = 0.
        Law::SaintVenantKirchhoff(_) => {
            let gs = 0.5 * (s * s - 1.0);
            let ga = -l * gs / (nl * l + 2.0 * m);
            let syy = l * (nl * ga + gs) + 2.0 * m * gs;
            ((1.0 + 2.0 * ga).sqrt(), s * syy)
        }
        Law::Hooke(_) => unreachable!(),
    }
}

fn compress_block<const D: usize>(
    law: Law,
    strain: f64,
    steps: usize,
    locking: Locking,
    walls_on: WallsOn,
) -> (Body<D>, f64, f64, usize) {
    let h = 1e-3;
    let n = 4;
    // Block [−2h, 2h]^{D−1} × [0, 4h], centred so that the free lateral faces expand symmetrically;
    // the rigid lateral translation is held by the inertia term alone.
    let mut body = block::<D>(law, h, [n; D], 2, 3);
    for x in body.points.x.iter_mut() {
        for d in 0..D - 1 {
            x[d] -= 0.5 * n as f64 * h;
        }
    }
    for d in 0..D - 1 {
        body.grid.origin[d] -= 0.5 * n as f64 * h;
    }
    let top = n as f64 * h;
    // Quasi-static: the inertia forces M u/Δt² against the stress forces are ρ L/(E Δt²) ~ 1e-11
    // at Δt = 10 s in one step (L = 4 mm, E ≥ 3.8 MPa).
    let dt = 10.0 / steps as f64;
    let v = -strain * top / (dt * steps as f64);
    let mut walls = vec![
        Wall { axis: D - 1, side: 1.0, position: 0.0, velocity: 0.0 },
        Wall { axis: D - 1, side: -1.0, position: top, velocity: v },
    ];
    let opt = StepOptions { dt, gravity: [0.0; 3], newton: Newton::default(), flip: 1.0, locking, walls_on };
    let mut ws = Workspace::default();
    let mut load = 0.0;
    let mut iterations = 0;
    for k in 0..steps {
        let rep = step(&mut body, &walls, &[], &opt, k, &mut ws).unwrap();
        load = rep.wall_load[1];
        iterations += rep.iterations;
        for w in walls.iter_mut() {
            w.position += w.velocity * dt;
        }
    }
    let area = (n as f64 * h).powi(D as i32 - 1);
    (body, load, area, iterations)
}

/// Both formulations: J is uniform in a homogeneous deformation, so F̄ = F and F-bar is exact too.
fn check_block<const D: usize>(law: Law, strain: f64) {
    for locking in [Locking::None, Locking::FBar] {
        check_block_with::<D>(law, strain, locking, WallsOn::Nodes);
    }
}

fn check_block_with<const D: usize>(law: Law, strain: f64, locking: Locking, walls_on: WallsOn) {
    let s = 1.0 - strain;
    let (body, load, area, iterations) = compress_block::<D>(law, strain, 1, locking, walls_on);
    let (a, p_axial) = uniaxial_stress(&law, D, s);
    // The solution is homogeneous and the 2-per-cell points integrate ∫∇N exactly, so the MPM
    // reproduces it up to the Newton tolerance and the inertia term (~1e-8): 1e-6 relative.
    let err = (load + p_axial * area).abs() / (p_axial * area).abs();
    eprintln!(
        "block D={D} {law:?} {locking:?} {walls_on:?} strain {strain}: plate load rel. error {err:.2e}, {iterations} Newton iterations"
    );
    assert!(
        err < 1e-6,
        "D={D} {law:?}: plate load {load} against closed form {} (rel {err:.2e})",
        -p_axial * area
    );
    for f in &body.points.f {
        for d in 0..D {
            let want = if d + 1 == D { s } else { a };
            // Same bound on F (the inertia perturbs it at ~1e-8).
            assert!((f[(d, d)] - want).abs() < 1e-6 * want, "F_{d}{d} = {} against {want}", f[(d, d)]);
        }
    }
}

#[test]
fn homogeneous_block_between_plates_matches_closed_forms_2d() {
    // One quasi-static step from the undeformed block to the final strain: the plates' strain is
    // reached by Newton within one step, so the grid is the initial one and the solution stays
    // exactly homogeneous (see docs/mpm.md for what the grid reset of later steps does).
    for strain in [0.05, 0.2] {
        for lambda in [0.0, 3e6, LAMBDA] {
            check_block::<2>(Law::NeoHookean(NeoHookean::new(lambda, MU).unwrap()), strain);
        }
    }
    // Saint-Venant–Kirchhoff softens in compression (non-convex energy); a single Newton solve
    // from the undeformed state converges to 10 %.
    for strain in [0.05, 0.1] {
        for lambda in [3e6, LAMBDA] {
            check_block::<2>(
                Law::SaintVenantKirchhoff(SaintVenantKirchhoff::new(lambda, MU).unwrap()),
                strain,
            );
        }
    }
}

#[test]
fn homogeneous_block_between_plates_matches_closed_forms_3d() {
    check_block::<3>(Law::NeoHookean(NeoHookean::new(3e6, MU).unwrap()), 0.2);
    check_block::<3>(Law::SaintVenantKirchhoff(SaintVenantKirchhoff::new(3e6, MU).unwrap()), 0.1);
}

/// The same block with the walls on the material points (`"walls_on": "points"`): the block's
/// material edges start at the plates, and no point's domain may cross them. The domains' corners
/// facing a plate are mapped by each point's F, which is exact for a homogeneous deformation, so
/// the plate load must be the closed form again. Tolerance 1e-6 as for the nodes: the multiplier
/// updates stop at a gap of 1e-9 h, which moves the strain of the 4-cell block by 2.5e-10 and the
/// load by less than 1e-8 relative at 5 % strain.
#[test]
fn homogeneous_block_between_plates_on_points_matches_closed_forms() {
    for strain in [0.05, 0.2] {
        for lambda in [0.0, 3e6, LAMBDA] {
            let law = Law::NeoHookean(NeoHookean::new(lambda, MU).unwrap());
            // λ = 100 MPa at 20 % in one step is left out: from u = 0 the plates' whole travel
            // starts as a penalty violation (the nodes' projection instead puts the top nodes on
            // the plate at once), and Newton does not converge in the default 40 iterations
            // (plain: C1 = 2.6e-4; F-bar, non-convex, ends on another equilibrium 34 % off when
            // allowed 200). Both pass at 5 %, where the path is short.
            if lambda == LAMBDA && strain > 0.1 {
                continue;
            }
            for locking in [Locking::None, Locking::FBar] {
                check_block_with::<2>(law, strain, locking, WallsOn::Points);
            }
        }
    }
    for strain in [0.05, 0.1] {
        for lambda in [3e6, LAMBDA] {
            let law = Law::SaintVenantKirchhoff(SaintVenantKirchhoff::new(lambda, MU).unwrap());
            check_block_with::<2>(law, strain, Locking::None, WallsOn::Points);
        }
    }
    check_block_with::<3>(
        Law::NeoHookean(NeoHookean::new(3e6, MU).unwrap()),
        0.2,
        Locking::None,
        WallsOn::Points,
    );
}

/// Patch test: the outer nodes of a block get the displacement of a homogeneous finite deformation
/// F̂ (stretch, shear and rotation); the free interior must reproduce it, every point ending with
/// F = F̂ and the stress P(F̂).
#[test]
fn patch_test_reproduces_a_homogeneous_deformation() {
    for locking in [Locking::None, Locking::FBar] {
        patch_test_with(locking);
    }
}

fn patch_test_with(locking: Locking) {
    let law = Law::NeoHookean(NeoHookean::new(3e6, MU).unwrap());
    let h = 1e-3;
    let n = 4;
    let mut body = block::<2>(law, h, [n, n], 2, 1);
    let th = 0.3f64;
    let rot = Mat::<2>::new(th.cos(), -th.sin(), th.sin(), th.cos());
    let fhat = rot * Mat::<2>::new(1.15, 0.1, -0.05, 0.9);
    let grid = body.grid.clone();
    let mut fixed = Vec::new();
    for node in 0..grid.n_nodes() {
        let x = grid.node_position(node);
        let on_edge = (0..2).any(|d| x[d].abs() < 1e-12 || (x[d] - n as f64 * h).abs() < 1e-12);
        let inside = (0..2).all(|d| x[d] > -1e-12 && x[d] < n as f64 * h + 1e-12);
        if on_edge && inside {
            let u = (fhat - Mat::<2>::identity()) * x;
            fixed.extend((0..2).map(|comp| Fixed { node, comp, u: u[comp] }));
        }
    }
    // One quasi-static step (inertia ρL²/(EΔt²) ~ 1e-12 relative).
    let opt = StepOptions {
        dt: 10.0,
        gravity: [0.0; 3],
        newton: Newton::default(),
        flip: 1.0,
        locking,
        walls_on: WallsOn::Nodes,
    };
    let x0 = body.points.x.clone();
    step(&mut body, &[], &fixed, &opt, 0, &mut Workspace::default()).unwrap();
    let p_hat = <Law as Constitutive<2>>::pk1(&law, &fhat).unwrap();
    for (p, x0p) in x0.iter().enumerate() {
        let f = body.points.f[p];
        assert!((f - fhat).norm() < 1e-9, "point {p}: F = {f} against {fhat}");
        let x_want = fhat * x0p;
        assert!((body.points.x[p] - x_want).norm() < 1e-9 * h, "point {p} position");
        let sigma_want = p_hat * fhat.transpose() / fhat.determinant();
        assert!((body.points.sigma[p] - sigma_want).norm() < 1e-8 * sigma_want.norm(), "point {p} stress");
    }
}

/// Free elastic disc with a velocity field (translation, rotation, stretching): total momentum is
/// conserved to round-off; the total energy never grows and the backward-Euler loss is first order
/// in Δt (halving Δt halves it).
#[test]
fn free_body_conserves_momentum_and_loses_energy_at_first_order() {
    let run = |dt: f64, steps: usize| -> (f64, f64, f64, f64) {
        let law = Law::NeoHookean(NeoHookean::new(3e6, MU).unwrap());
        let h = 1e-3;
        let r = 4e-3;
        let grid = Grid::new(Vector::<2>::new(-10e-3, -10e-3), h, [20, 20]).unwrap();
        let mut points =
            Points::seed(Vector::<2>::new(-r, -r), Vector::<2>::new(r, r), grid.origin, h, 2, RHO, |x| {
                x.norm() < r
            });
        for (x, v) in points.x.iter().zip(points.v.iter_mut()) {
            // 1 m/s translation, 200 rad/s spin, stretching rate 100 /s.
            *v = Vector::<2>::new(1.0 - 200.0 * x[1] + 100.0 * x[0], 0.5 + 200.0 * x[0] - 100.0 * x[1]);
        }
        let mut body = Body { grid, points, law };
        let energy = |b: &Body<2>| b.energy().unwrap();
        let p0 = body.points.momentum();
        let e0 = energy(&body);
        // Plain formulation: the energy summed below is W at the points' own F.
        let locking = Locking::None;
        let opt = StepOptions {
            dt,
            gravity: [0.0; 3],
            newton: Newton::default(),
            flip: 1.0,
            locking,
            walls_on: WallsOn::Nodes,
        };
        let mut ws = Workspace::default();
        let mut e_prev = e0;
        let mut max_rise: f64 = 0.0;
        for k in 0..steps {
            step(&mut body, &[], &[], &opt, k, &mut ws).unwrap();
            let e = energy(&body);
            max_rise = max_rise.max((e - e_prev) / e0);
            e_prev = e;
        }
        let dp = (body.points.momentum() - p0).norm() / p0.norm();
        (dp, (e0 - e_prev) / e0, max_rise, e0)
    };
    let (dp1, loss1, rise1, _) = run(2e-6, 20);
    let (dp2, loss2, rise2, _) = run(1e-6, 40);
    // Σ_I f_int,I = 0 by the partition of unity and the FLIP update carries the nodal momentum
    // to the points exactly: only summation round-off (~1e-16 per term, 10³ terms) remains.
    assert!(dp1 < 1e-12 && dp2 < 1e-12, "momentum drift {dp1:.2e}, {dp2:.2e}");
    assert!(rise1 < 1e-12 && rise2 < 1e-12, "energy grew: {rise1:.2e}, {rise2:.2e}");
    let ratio = loss1 / loss2;
    eprintln!("energy loss over 40 µs: {loss1:.4e} (Δt = 2 µs), {loss2:.4e} (Δt = 1 µs), ratio {ratio:.3}");
    assert!(loss2 > 0.0 && (1.6..2.4).contains(&ratio), "loss ratio {ratio} not first order");
}

/// Bad scenes stop with a message naming the cause.
#[test]
fn bad_scenes_name_their_problem() {
    use mcdem::mpm::scene::Scene;
    let scene = |material: &str, walls: &str| {
        format!(
            r#"{{"dimension": 2, "material": {material},
                "body": {{"shape": "disc", "center": [0.0, 0.01], "radius": 0.01}},
                "grid": {{"h": 1e-3, "points_per_cell": 2}}, "walls": [{walls}], "dt": 1e-4, "steps": 1}}"#
        )
    };
    let good = r#"{"law": "neohookean", "lambda": 3e6, "mu": 1.5e6, "density": 990}"#;
    let err = |text: String| Scene::from_json(&text).and_then(|s| s.setup::<2>().map(|_| ())).unwrap_err();
    let e = err(scene(r#"{"law": "neohookean", "lambda": 3e6, "mu": -1.5e6, "density": 990}"#, ""));
    assert!(e.contains("μ must be positive"), "{e}");
    let e = err(scene(r#"{"law": "rubber", "lambda": 3e6, "mu": 1.5e6, "density": 990}"#, ""));
    assert!(e.contains("unknown law"), "{e}");
    // A wall through the disc: points start on its wrong side.
    let e = err(scene(good, r#"{"axis": 1, "side": 1, "position": 0.005}"#));
    assert!(e.contains("wrong side") && e.contains("wall 0"), "{e}");
    let e = err(scene(good, r#"{"axis": 2, "side": 1, "position": 0.0}"#));
    assert!(e.contains("axis"), "{e}");
    assert!(Scene::from_json(&scene(good, r#"{"axis": 1, "side": 1, "position": 0.0}"#))
        .unwrap()
        .setup::<2>()
        .is_ok());
    // The plain formulation unless the scene asks for F-bar; an unknown remedy is named.
    let with_locking = |v: &str| scene(good, "").replacen("\"dt\"", &format!("\"locking\": {v}, \"dt\""), 1);
    let opts = |text: String| Scene::from_json(&text).unwrap().setup::<2>().unwrap().options.locking;
    assert_eq!(opts(scene(good, "")), Locking::None);
    assert_eq!(opts(with_locking("\"fbar\"")), Locking::FBar);
    let e = err(with_locking("\"bbar\""));
    assert!(e.contains("locking") && e.contains("bbar"), "{e}");
    // A point outside the grid is reported with its step.
    let mut setup = Scene::from_json(&scene(good, "")).unwrap().setup::<2>().unwrap();
    setup.bodies[0].points.x[0][0] = 1.0;
    let e = step(&mut setup.bodies[0], &[], &[], &setup.options, 7, &mut Workspace::default()).unwrap_err();
    assert!(e.contains("step 7") && e.contains("outside the grid"), "{e}");
    // Newton capped at one iteration cannot meet Eq. 16 on a loaded step: the criteria are named.
    let mut setup =
        Scene::from_json(&scene(good, r#"{"axis": 1, "side": -1, "position": 0.02, "velocity": -0.5}"#))
            .unwrap()
            .setup::<2>()
            .unwrap();
    setup.options.newton.max_iter = 1;
    let e = step(&mut setup.bodies[0], &setup.walls, &[], &setup.options, 3, &mut Workspace::default())
        .unwrap_err();
    assert!(e.contains("step 3") && e.contains("C1") && e.contains("Eq. 16"), "{e}");
}

/// Volumetric locking: a plane-strain cantilever [0, L] × [0, H], L = 8H, clamped at x = 0 (every
/// node on that line fixed), sagging under its own weight, λ/μ = 1000 (ν = 0.4995). One
/// quasi-static step (inertia ρh²/(μΔt²) ~ 1e-9 relative) with a small load (deflection ~1e-3 L,
/// the linear regime). The mass-weighted mean deflection is compared with Timoshenko beam theory,
/// ∫w dx / L = qL⁴/(20 E'I) + qL²/(3κGA) (q = ρgH, E' = 4μ(λ+μ)/(λ+2μ), I = H³/12, κ = 5/6,
/// G = μ, A = H), which is within a few per cent of the plane-strain elasticity answer at L/H = 8.
/// The plain formulation locks: the 2×2 points per cell each enforce J ≈ 1 and the beam is far
/// too stiff at every h. F-bar keeps one volume constraint per cell and recovers the deflection.
#[test]
fn fbar_removes_volumetric_locking_of_a_nearly_incompressible_cantilever() {
    let (mu, lambda, rho, g): (f64, f64, f64, f64) = (1.0, 1000.0, 1.0, -2e-6);
    let (len, hgt): (f64, f64) = (8.0, 1.0);
    let ep = 4.0 * mu * (lambda + mu) / (lambda + 2.0 * mu);
    let q = rho * g.abs() * hgt;
    let inertia = hgt.powi(3) / 12.0;
    let theory = q * len.powi(4) / (20.0 * ep * inertia) + q * len * len / (3.0 * (5.0 / 6.0) * mu * hgt);
    let run = |nt: usize, locking: Locking| -> f64 {
        let h = hgt / nt as f64;
        let law = Law::NeoHookean(NeoHookean::new(lambda, mu).unwrap());
        let margin = 2;
        let nx = (len / h).round() as usize;
        let grid = Grid::new(Vector::<2>::new(0.0, -(margin as f64) * h), h, [nx + margin, nt + 2 * margin])
            .unwrap();
        let points =
            Points::seed(Vector::<2>::zeros(), Vector::<2>::new(len, hgt), grid.origin, h, 2, rho, |x| {
                x[0] > 0.0 && x[0] < len && x[1] > 0.0 && x[1] < hgt
            });
        let fixed: Vec<Fixed> = (0..grid.n_nodes())
            .filter(|&i| grid.node_position(i)[0].abs() < 1e-12 * h)
            .flat_map(|node| (0..2).map(move |comp| Fixed { node, comp, u: 0.0 }))
            .collect();
        let mut body = Body { grid, points, law };
        let y0: Vec<f64> = body.points.x.iter().map(|x| x[1]).collect();
        let opt = StepOptions {
            dt: 1e3,
            gravity: [0.0, g, 0.0],
            newton: Newton::default(),
            flip: 1.0,
            locking,
            walls_on: WallsOn::Nodes,
        };
        step(&mut body, &[], &fixed, &opt, 0, &mut Workspace::default()).unwrap();
        let m: f64 = body.points.mass.iter().sum();
        let w: f64 =
            body.points.x.iter().zip(&y0).zip(&body.points.mass).map(|((x, y), m)| (x[1] - y) * m).sum();
        -w / m
    };
    for nt in [2, 4, 8, 16] {
        let plain = run(nt, Locking::None) / theory;
        let fbar = run(nt, Locking::FBar) / theory;
        eprintln!("cantilever H/h = {nt}: deflection / Timoshenko: plain {plain:.4}, F-bar {fbar:.4}");
        // Locked: the plain beam is far too stiff at every h (measured 0.05, 0.10, 0.24, 0.53 for
        // H/h = 2 … 16): its error stays ≥ 40 %, eight times F-bar's bound below.
        assert!(plain < 0.6, "H/h = {nt}: the plain formulation no longer locks ({plain:.4})");
        // F-bar: within the beam theory's own error against 2-D elasticity (a few per cent: the
        // fully clamped root and the κ of the shear term) once the thickness has 4 cells or more;
        // 2 cells through the thickness carry an O(h) discretisation error on top (measured +11 %).
        let tol = if nt >= 4 { 0.05 } else { 0.15 };
        assert!((fbar - 1.0).abs() < tol, "H/h = {nt}: F-bar deflection / theory = {fbar:.4}");
    }
}
