//! The AVX2 code paths chosen at run time (the batched pair forces, the multi-contact kernel) give
//! the baseline x86-64 paths' results bit for bit: a dense, frictional, periodic packing is run
//! both ways in one process (the switch is one-way, so the AVX2 runs come first) and every
//! position, velocity and angular velocity must be identical, for Hertz and for advanced MC. On a
//! CPU without AVX2 both runs take the baseline paths.

/// The bench's dense periodic packing (φ = 0.8, μ = 0.5, 256 spheres of diameter 1 mm ± 5 %,
/// about 12 overlapping neighbours each), Hertz or advanced MC.
fn packing(advanced: bool) -> mcdem::engine::World {
    mcdem::bench::packing::scene(4, advanced).unwrap()
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

/// The multi-contact kernel alone on contact sets of 0 … 23 contacts (every offset of the AVX2
/// kernel's four-pair chunks), with coincident, antipodal and centred points and unloaded
/// contacts among them: radius changes, fallback flags and influence matrices, as bits, and the
/// radius changes from the influence matrix.
fn kernel_bits() -> Vec<u64> {
    use mcdem::physics::contact_set::{
        influence, radius_changes, radius_changes_with, ContactLoad, McParams,
    };
    use mcdem::physics::ghods2022::{Cap, MprTest};
    use mcdem::physics::Vec3;
    let mut rng = mcdem::rng::Lcg64(0x6d63_6465_6d00);
    let mut next = move || rng.uniform();
    let mut out = Vec::new();
    for round in 0..400 {
        let n = round % 24;
        let r = 1e-3;
        let mut cs: Vec<ContactLoad> = (0..n)
            .map(|_| {
                let v = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
                ContactLoad {
                    point: v * r * (0.7 + 0.3 * next()),
                    force: if next() < 0.2 { 0.0 } else { 1e-3 * next() },
                }
            })
            .collect();
        if n > 3 {
            cs[1].point = cs[0].point; // coincident
            cs[2].point = -cs[0].point; // antipodal
            cs[3].point = cs[0].point * 0.5; // on the load line (a guard of Eq. 2's third term)
        }
        if n > 5 && round % 3 == 0 {
            cs[5].point = Vec3::zeros(); // at the centre: no normal
        }
        let nu = [0.5, 0.0, 0.3, 0.45][round % 4];
        let cap = [
            None,
            Some(Cap { mpr: 0.05, test: MprTest::Abs }),
            Some(Cap { mpr: 0.02, test: MprTest::Signed }),
        ][round % 3];
        let p = McParams { radius: r, youngs_modulus: 23.3e3, poisson_ratio: nu, gamma: 1.0, cap };
        let (mut d, mut fb) = (vec![0.0; n], vec![false; n]);
        radius_changes(&p, &cs, &mut d, &mut fb).unwrap();
        let mut g = vec![0.0; n * n];
        influence(&p, &cs, &mut g).unwrap();
        out.extend(d.iter().chain(&g).map(|v| v.to_bits()));
        out.extend(fb.iter().map(|&f| u64::from(f)));
        // The same radius changes from the matrix: exactly n² values (one lane at a time), and
        // with four values after it (the kept matrices' layout: four lanes when the CPU has AVX2).
        let (mut dw, mut fbw) = (vec![0.0; n], vec![false; n]);
        radius_changes_with(&p, &g, &cs, &mut dw, &mut fbw).unwrap();
        g.extend([0.0; 4]);
        let (mut dp, mut fbp) = (vec![0.0; n], vec![false; n]);
        radius_changes_with(&p, &g, &cs, &mut dp, &mut fbp).unwrap();
        assert!(dw.iter().zip(&dp).all(|(a, b)| a.to_bits() == b.to_bits()), "padded matrix: other bits");
        assert_eq!(fbw, fbp);
        out.extend(dw.iter().map(|v| v.to_bits()));
        out.extend(fbw.iter().map(|&f| u64::from(f)));
    }
    out
}

#[test]
fn avx2_paths_give_the_baseline_result_bit_for_bit() {
    // Without AVX2 both runs would take the baseline paths and the test would compare them with
    // themselves: such a machine fails here unless MCDEM_NO_AVX2=1 says it on purpose.
    if !mcdem::physics::avx2() {
        let told = std::env::var("MCDEM_NO_AVX2").is_ok_and(|v| v == "1");
        assert!(told, "the AVX2 paths are not active on this CPU (MCDEM_NO_AVX2=1 to run the baseline only)");
        eprintln!("MCDEM_NO_AVX2=1: no AVX2 on this CPU, the comparison checks the baseline paths only");
    }
    let fast = [state(false), state(true)];
    let fast_kernel = kernel_bits();
    mcdem::physics::use_portable_code();
    assert!(!mcdem::physics::avx2());
    assert!(fast_kernel == kernel_bits(), "the AVX2 multi-contact kernel differs from the baseline one");
    for (advanced, fast) in [false, true].into_iter().zip(fast) {
        assert!(fast == state(advanced), "advanced MC {advanced}: the AVX2 paths changed the trajectory");
    }
}
