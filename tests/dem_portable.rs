//! The AVX2 code paths chosen at run time (the batched pair forces, the multi-contact chords) give
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

#[test]
fn avx2_paths_give_the_baseline_result_bit_for_bit() {
    let fast = [state(false), state(true)];
    mcdem::physics::use_portable_code();
    assert!(!mcdem::physics::avx2());
    for (advanced, fast) in [false, true].into_iter().zip(fast) {
        assert!(fast == state(advanced), "advanced MC {advanced}: the AVX2 paths changed the trajectory");
    }
}
