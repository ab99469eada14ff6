//! The AVX2 code paths chosen at run time (the batched pair forces, the multi-contact chords) give
//! the baseline x86-64 paths' results bit for bit: a dense, frictional, periodic packing is run
//! both ways in one process (the switch is one-way, so the AVX2 runs come first) and every
//! position, velocity and angular velocity must be identical, for Hertz and for advanced MC. On a
//! CPU without AVX2 both runs take the baseline paths.

use mcdem::engine::{Closure, Domain, World};
use mcdem::physics::ghods2022::MprTest;
use mcdem::physics::hertz::Tangential;
use mcdem::physics::{Material, Vec3};

/// 256 spheres (diameter 1 mm ± 5 %) on a compressed fcc lattice (φ = 0.8), random velocities,
/// μ = 0.5, triply periodic: every sphere has about 12 overlapping neighbours.
fn packing(advanced: bool) -> World {
    let (d, k) = (1e-3, 4);
    let phi_fcc = std::f64::consts::PI / (3.0 * 2f64.sqrt());
    let a = 2f64.sqrt() * d * (phi_fcc / 0.8).cbrt();
    let mut w = World::new();
    w.domain = Some(Domain::new(Vec3::zeros(), Vec3::repeat(a * k as f64), [true; 3]));
    let m = if advanced {
        Material::new(1e6, 0.4, 0.81, Some((0.11, MprTest::Abs))).unwrap()
    } else {
        Material::hertz(1e6, 0.4).unwrap()
    };
    w.set_materials(vec![m], &[0.7], &[0.5], Tangential::History).unwrap();
    w.closure = Some(if advanced { Closure::MultiContact } else { Closure::Hertz });
    w.skin = 0.05 * d;
    w.integrate = true;
    let mut seed = 0x2545f4914f6cdd1du64;
    let mut rnd = move || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let basis = [[0.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.5, 0.0, 0.5], [0.0, 0.5, 0.5]];
    let mut id = 1;
    for i in 0..k {
        for j in 0..k {
            for l in 0..k {
                for b in basis {
                    let x =
                        Vec3::new(i as f64 + b[0] + 0.25, j as f64 + b[1] + 0.25, l as f64 + b[2] + 0.25) * a;
                    w.p.push(id, 0, x, d * (1.0 + 0.05 * rnd()), 1000.0);
                    let n = w.p.len() - 1;
                    w.p.v[n] = Vec3::new(rnd(), rnd(), rnd()) * 1e-2;
                    id += 1;
                }
            }
        }
    }
    w.dt = 2e-6;
    w
}

/// Positions, velocities and angular velocities after 400 steps, as bits.
fn state(advanced: bool) -> Vec<u64> {
    let mut w = packing(advanced);
    w.setup().unwrap();
    for _ in 0..400 {
        w.step().unwrap();
    }
    assert!(w.contact_counts().0 > 1000, "the packing must be dense");
    let p = &w.p;
    p.x.iter()
        .chain(&p.v)
        .chain(&p.omega)
        .flat_map(|v| v.iter().map(|c| c.to_bits()).collect::<Vec<_>>())
        .collect()
}

#[test]
fn avx2_paths_give_the_baseline_result_bit_for_bit() {
    let fast = [state(false), state(true)];
    mcdem::physics::use_portable_code();
    assert!(!mcdem::physics::avx2());
    for (advanced, fast) in [false, true].into_iter().zip(fast) {
        assert!(fast == state(advanced), "advanced MC {advanced}: the AVX2 paths changed the trajectory");
    }
}
