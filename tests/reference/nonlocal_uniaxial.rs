//! Reduced versions of the 514-particle uniaxial compression by the nonlocal solver
//! (`nonlocal::uniaxial`, docs/nonlocal.md "514-particle compression"): the first load steps of the
//! full packing from the DEM state at the start of the second compression, and a loose
//! sub-packing that carries no load. Physics checked: force balance at every step,
//! piston force = bottom force (gravity is off), σ non-decreasing in φ once loaded.

use std::path::Path;

use mcdem::nonlocal::scene::read_liggghts_dump;
use mcdem::nonlocal::uniaxial::{compress, Uniaxial, UniaxialPoint};
use mcdem::nonlocal::{Kernel, KernelKind, Sphere};

const START: &str = "validation/cases/nonlocal/hydrogel_start_2nd_compression.dump";

fn start(u: &Uniaxial) -> Vec<Sphere> {
    read_liggghts_dump(&Path::new(env!("CARGO_MANIFEST_DIR")).join(START), u.particle).unwrap()
}

fn check(points: &[UniaxialPoint], steps: usize) {
    assert_eq!(points.len(), steps + 1, "the curve must not be truncated");
    let mut loaded = false;
    for w in points.windows(2) {
        assert!(w[1].phi > w[0].phi);
        if loaded {
            assert!(
                w[1].sigma_piston >= w[0].sigma_piston,
                "sigma decreased from {} to {} between steps {} and {}",
                w[0].sigma_piston,
                w[1].sigma_piston,
                w[0].step,
                w[1].step
            );
        }
        // Below 1 µPa (1e-9 of the final stress) a state is force-free up to the solver's floor.
        loaded |= w[1].sigma_piston > 1e-6;
    }
    for p in points {
        assert!(p.residual <= 1e-9, "step {}: residual {}", p.step, p.residual);
        // Relative, with an absolute floor for force-free states (forces at the solver's
        // round-off floor, ~1e-17 Pa here).
        assert!(
            (p.sigma_piston - p.sigma_bottom).abs() <= 1e-6 * p.sigma_piston.abs() + 1e-12,
            "step {}: piston {} vs bottom {}",
            p.step,
            p.sigma_piston,
            p.sigma_bottom
        );
        assert!(p.sigma_piston >= 0.0 && p.sigma_side >= 0.0);
    }
}

#[test]
fn first_steps_of_the_hydrogel_compression() {
    // The first 3 of the 40 steps to φ = 0.85 (φ 0.587 → 0.601), boussinesq, ν = 0.5.
    let full = Uniaxial::hydrogel(0.5, 40).unwrap();
    let u = Uniaxial { z_end: full.z_at(3), steps: 3, ..full };
    let spheres = start(&u);
    assert_eq!(spheres.len(), 514);
    let kernel = Kernel::new(KernelKind::Boussinesq, 1.0).unwrap();
    let points = compress(&spheres, &u, kernel).unwrap();
    check(&points, u.steps);
    // The DEM state at the start of the second compression is (barely) jammed at the start height.
    assert!(points[0].sigma_piston > 0.0);
    // The load grows several-fold over these steps (≈ 3.7 Pa → 13 Pa).
    assert!(points[3].sigma_piston > 2.0 * points[0].sigma_piston, "{points:?}");
}

#[test]
fn loose_sub_packing_is_force_free_above_its_top() {
    // The 167 spheres below z = 0.06 m with the piston from 0.065 m down to 0.062 m: above them,
    // so once the overlaps that gravity caused in the DEM state have opened (gravity is off) the
    // equilibrium carries no load at all. Every step must still be solved and reported.
    let full = Uniaxial::hydrogel(0.5, 3).unwrap();
    let spheres: Vec<Sphere> = start(&full).into_iter().filter(|s| s.x.z + s.radius < 0.06).collect();
    assert_eq!(spheres.len(), 167);
    let vs: f64 = spheres.iter().map(|s| 4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3)).sum();
    let u = Uniaxial { z_start: 0.065, z_end: 0.062, solid_volume: vs, ..full };
    for kind in [KernelKind::None, KernelKind::Boussinesq] {
        let points = compress(&spheres, &u, Kernel::new(kind, 1.0).unwrap()).unwrap();
        check(&points, u.steps);
        for p in &points {
            // No load: with Hertz every overlap has opened (all forces exactly zero); with the
            // lagged nonlocal FIRE a pair may keep a force at the solver's floor (≈ 1e-19 Pa).
            if kind == KernelKind::None {
                assert_eq!(p.contacts + p.wall_contacts, 0, "{kind}: {p:?}");
                assert_eq!(p.residual, 0.0, "{kind}: {p:?}");
            }
            assert!(p.sigma_piston.abs() < 1e-9 && p.sigma_bottom.abs() < 1e-9, "{kind}: {p:?}");
            assert!(p.sigma_side.abs() < 1e-9, "{kind}: {p:?}");
        }
    }
}
