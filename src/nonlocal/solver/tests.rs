use super::*;
use crate::nonlocal::kernel::KernelKind;
use crate::physics::material::PairCoeffs;

/// A small compressed cluster in a box with pair and wall contacts.
fn cluster(kind: KernelKind) -> Nonlocal {
    let m = Material::hertz(1e4, 0.35).unwrap();
    let wm = Material::hertz(1e7, 0.3).unwrap();
    let pts = [
        [0.95, 1.0, 0.9],
        [2.75, 1.1, 1.0],
        [1.9, 2.6, 1.05],
        [1.85, 1.5, 2.55],
        [0.9, 2.8, 2.7],
        [2.9, 2.9, 2.8],
    ];
    let spheres: Vec<Sphere> = pts
        .iter()
        .enumerate()
        .map(|(k, p)| Sphere {
            id: k as u64 + 1,
            x: Vec3::from(*p),
            radius: 1.0 + 0.05 * k as f64,
            material: m,
        })
        .collect();
    let walls = vec![
        Wall { name: "a".into(), point: Vec3::zeros(), normal: Vec3::x() },
        Wall { name: "b".into(), point: Vec3::zeros(), normal: Vec3::z() },
        Wall { name: "c".into(), point: Vec3::new(3.8, 0.0, 0.0), normal: -Vec3::x() },
    ];
    let mut s =
        Nonlocal::new(&spheres, &walls, wm, Kernel::new(kind, 1.0).unwrap(), Settings::default()).unwrap();
    s.update_active_set();
    for (k, c) in s.contacts.iter_mut().enumerate() {
        c.delta = c.delta * 0.7 + 1e-3 * k as f64;
    }
    s
}

#[test]
fn jacobian_matches_finite_differences() {
    jacobian_check(KernelKind::Boussinesq);
}

#[test]
fn jacobian_matches_finite_differences_with_the_sphere_kernel() {
    jacobian_check(KernelKind::Sphere);
}

fn jacobian_check(kind: KernelKind) {
    let s = cluster(kind);
    let nc = s.contacts.len();
    assert!(nc >= 8, "cluster has only {nc} contacts");
    let n = s.x.len();
    let dim = 3 * n + nc;
    let adj = s.adjacency();
    let delta: Vec<f64> = s.contacts.iter().map(|c| c.delta).collect();
    let ev = s.evaluate(&s.x, &delta, &adj, true, 0.0);
    let mut dense = vec![vec![0.0; dim]; dim];
    for t in &ev.trip {
        dense[t.row][t.col] += t.val;
    }
    let h = 1e-7;
    for col in 0..dim {
        let (mut xp, mut xm) = (s.x.clone(), s.x.clone());
        let (mut dp, mut dm) = (delta.clone(), delta.clone());
        if col < 3 * n {
            xp[col / 3][col % 3] += h;
            xm[col / 3][col % 3] -= h;
        } else {
            dp[col - 3 * n] += h;
            dm[col - 3 * n] -= h;
        }
        let rp = s.evaluate(&xp, &dp, &adj, false, 0.0).res;
        let rm = s.evaluate(&xm, &dm, &adj, false, 0.0).res;
        for row in 0..dim {
            let fd = (rp[row] - rm[row]) / (2.0 * h);
            let an = dense[row][col];
            // The tether −ε·k_ref on the position diagonal is deliberately not in the residual.
            let tether = if row == col && row < 3 * n { 1e-6 } else { 0.0 };
            let tol = 1e-6 * (1.0 + fd.abs()) + tether;
            if (an - fd).abs() > tol {
                panic!("J[{row}][{col}] = {an}, finite difference {fd}");
            }
        }
    }
}

/// Single hydrogel sphere (docs/spec.md §4 die: E = 23.3 kPa, ν = 0.5, r = 1 mm, walls 50 MPa) in a
/// rigid cubic die of side 2r, top plate pushed down by Δ in steps of 0.05 r. Returns, per step,
/// (Δ/r, P_v, P_h, P_v Hertz) and checks convergence and the die's symmetry.
fn die(kind: KernelKind) -> Vec<(f64, f64, f64, f64)> {
    let (e, nu, r) = (23.3e3, 0.5, 1e-3);
    let m = Material::hertz(e, nu).unwrap();
    let wm = Material::hertz(50e6, 0.5).unwrap();
    let l = 2.0 * r;
    let walls = Wall::rigid_box(l, l, l, "top");
    let sphere = Sphere { id: 1, x: Vec3::new(r, r, r), radius: r, material: m };
    let mut s =
        Nonlocal::new(&[sphere], &walls, wm, Kernel::new(kind, 1.0).unwrap(), Settings::default()).unwrap();
    let e_star = PairCoeffs::new(&m, &wm, 1.0, 0.0).unwrap().e_star;
    let steps = 6;
    let disp = 0.3 * r;
    let top0 = walls[5].point;
    let path = |t: f64| {
        let points = walls
            .iter()
            .enumerate()
            .map(|(k, wall)| if k == 5 { top0 - Vec3::z() * (t * disp) } else { wall.point })
            .collect();
        (points, 0.0)
    };
    let mut out = Vec::new();
    for k in 1..=steps {
        let st = s.advance(&path, (k - 1) as f64 / steps as f64, k as f64 / steps as f64).unwrap();
        assert!(st.residual <= 1e-9, "{kind} step {k}: residual {}", st.residual);
        let f: Vec<f64> = s.wall_forces().iter().zip(&walls).map(|(f, w)| -f.dot(&w.normal)).collect();
        let (pv, ph) = (f[5], f[0]);
        assert!(pv.is_finite() && ph.is_finite());
        assert!((f[4] - pv).abs() <= 1e-9 * pv, "{kind}: bottom {} top {pv}", f[4]);
        for fw in &f[1..4] {
            assert!((fw - ph).abs() <= 1e-9 * pv, "{kind}: side {fw} vs {ph}");
        }
        let dr = disp / r * k as f64 / steps as f64;
        let hertz = crate::physics::hertz::hertz_force(e_star, r, 0.5 * dr * r);
        // Independent reduced solve by symmetry (unknowns P_v, P_h), with the kernel's G at 90°
        // and 180°: P_v: Δ/2 = H(P_v) + G180 P_v + 4 G90 P_h; P_h: 0 = H(P_h) + 2 G90 P_v + (G180 + 2 G90) P_h.
        let kern = Kernel::new(kind, 1.0).unwrap();
        let (g90, g180) = (kern.compliance(0.0, e, nu, r).0, kern.compliance(-1.0, e, nu, r).0);
        let h = |p: f64| (3.0 * p.max(0.0) / (4.0 * e_star * r.sqrt())).powf(2.0 / 3.0);
        let res = |pv: f64, ph: f64| {
            (
                0.5 * dr * r - h(pv) - g180 * pv - 4.0 * g90 * ph,
                -h(ph) - 2.0 * g90 * pv - (g180 + 2.0 * g90) * ph,
            )
        };
        let (mut qv, mut qh) = (pv * 1.01, ph * 1.01 + 1e-9 * pv);
        for _ in 0..60 {
            let (f1, f2) = res(qv, qh);
            let (e1, e2) = (1e-7 * qv, 1e-7 * qv);
            let (a11, a21) = ((res(qv + e1, qh).0 - f1) / e1, (res(qv + e1, qh).1 - f2) / e1);
            let (a12, a22) = ((res(qv, qh + e2).0 - f1) / e2, (res(qv, qh + e2).1 - f2) / e2);
            let det = a11 * a22 - a12 * a21;
            qv -= (a22 * f1 - a12 * f2) / det;
            qh -= (-a21 * f1 + a11 * f2) / det;
        }
        assert!((pv - qv).abs() <= 1e-6 * qv, "{kind} dr {dr}: P_v {pv} vs reduced {qv}");
        assert!(
            (ph - qh).abs() <= 1e-6 * qh.abs().max(1e-3 * qv),
            "{kind} dr {dr}: P_h {ph} vs reduced {qh}"
        );
        out.push((dr, pv, ph, hertz));
    }
    out
}

#[test]
fn die_with_the_sphere_kernel() {
    let sphere = die(KernelKind::Sphere);
    let bous = die(KernelKind::Boussinesq);
    println!("dr    P_v Hertz   P_v sphere  P_h sphere  P_v bouss.  P_h bouss.");
    for (a, b) in sphere.iter().zip(&bous) {
        println!("{:.2}  {:.4e}  {:.4e}  {:.3e}  {:.4e}  {:.3e}", a.0, a.3, a.1, a.2, b.1, b.2);
        // Converged, finite, stiffer than Hertz (the outward bulge at the far contacts), and a
        // side-wall force builds up.
        assert!(a.1 > a.3 && a.2 > 0.0, "dr {}: P_v {} Hertz {} P_h {}", a.0, a.1, a.3, a.2);
    }
}

/// FIRE's parallel force evaluation gives the serial pass's bits: a 6 × 6 × 6 packing (216
/// particles, more than one block of kernel sums and of contacts) pressed in a box of walls,
/// relaxed with the lagged nonlocal law on one and on two threads.
#[test]
fn fire_relaxation_does_not_depend_on_the_thread_count() {
    let m = Material::hertz(1e4, 0.5).unwrap();
    let wm = Material::hertz(1e7, 0.3).unwrap();
    let packing = || {
        let mut spheres = Vec::new();
        for k in 0..216usize {
            let (a, b, c) = ((k % 6) as f64, ((k / 6) % 6) as f64, (k / 36) as f64);
            // Spacing below the diameter, and an irregular offset so no contact is symmetric.
            let wobble = 0.04 * ((k * 7919) % 13) as f64 / 13.0;
            spheres.push(Sphere {
                id: k as u64 + 1,
                x: Vec3::new(1.0 + 1.9 * a + wobble, 1.0 + 1.9 * b - wobble, 1.0 + 1.9 * c + 0.5 * wobble),
                radius: 1.0 + 0.02 * ((k * 31) % 5) as f64,
                material: m,
            });
        }
        spheres
    };
    let relaxed = |threads: usize| {
        let spheres = packing();
        let walls = vec![
            Wall { name: "x0".into(), point: Vec3::new(0.05, 0.0, 0.0), normal: Vec3::x() },
            Wall { name: "x1".into(), point: Vec3::new(11.3, 0.0, 0.0), normal: -Vec3::x() },
            Wall { name: "y0".into(), point: Vec3::new(0.0, 0.05, 0.0), normal: Vec3::y() },
            Wall { name: "y1".into(), point: Vec3::new(0.0, 11.3, 0.0), normal: -Vec3::y() },
            Wall { name: "z0".into(), point: Vec3::new(0.0, 0.0, 0.05), normal: Vec3::z() },
            Wall { name: "z1".into(), point: Vec3::new(0.0, 0.0, 11.3), normal: -Vec3::z() },
        ];
        let mut s = Nonlocal::new(
            &spheres,
            &walls,
            wm,
            Kernel::new(KernelKind::Sphere, 1.0).unwrap(),
            Settings::default(),
        )
        .unwrap();
        s.update_active_set();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let (steps, rel) = pool.install(|| s.relax(400, 1e-12, true));
        (s.positions(), steps, rel, s.contacts.len())
    };
    let (x1, steps1, rel1, c1) = relaxed(1);
    let (x2, steps2, rel2, c2) = relaxed(2);
    assert!(c1 > 216, "the packing must be loaded: {c1} contacts");
    assert_eq!((steps1, rel1.to_bits(), c1), (steps2, rel2.to_bits(), c2));
    for (a, b) in x1.iter().zip(&x2) {
        for k in 0..3 {
            assert_eq!(a[k].to_bits(), b[k].to_bits());
        }
    }
    // The relaxation moved the particles (a run that did nothing would compare equal trivially).
    let moved = x1.iter().zip(packing()).map(|(a, b)| (a - b.x).norm()).fold(0.0, f64::max);
    assert!(moved > 1e-6, "largest move {moved}");
}
