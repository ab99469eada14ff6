//! Eq. 2 iterated to its fixed point within the step (`World::mc_fixed_point`) against the lagged
//! scheme it replaces, on a held cluster where both are the same map.
//!
//! Scene: a centre sphere pressed by five held neighbours at unequal overlaps and directions,
//! standard MC (no Eq. 3 cap), everything at rest (no damping, no tangential motion). The
//! neighbours have one contact each, so only the centre's radii change; with the positions held,
//! the lagged scheme applies the map F ↦ F(δ + Δ(F)) once per step, so its forces converge over
//! the steps to the map's fixed point, and the ratio of successive changes tends to the map's
//! dominant eigenvalue (the loop gain). The fixed-point option applies the same map within one
//! step. Contacts at 90° and more from each other grow the centre's radius (docs/spec.md §2,
//! B(s) < 0), so the loop has positive feedback: the lag is not the fixed point.

use mcdem::engine::{Closure, Domain, FixedPoint, World};
use mcdem::physics::hertz::Tangential;
use mcdem::physics::{Material, Vec3};

const R: f64 = 1e-3;
/// γ of Eq. 2: large enough that the loop gain is well above round-off over the passes (≈ 0.7).
const GAMMA: f64 = 8.0;

fn cluster(fixed_point: Option<FixedPoint>) -> World {
    let mut w = World::new();
    w.domain = Some(Domain::new(Vec3::repeat(-0.01), Vec3::repeat(0.01), [false; 3]));
    let m = Material::new(1e5, 0.3, GAMMA, None).unwrap();
    w.set_materials(vec![m], &[0.5], &[0.5], Tangential::History).unwrap();
    w.closure = Some(Closure::MultiContact);
    w.mc_range = 1.25;
    w.dt = 1e-6;
    w.skin = 0.1 * R;
    w.integrate = false;
    w.mc_fixed_point = fixed_point;
    w.p.push(1, 0, Vec3::zeros(), 2.0 * R, 1000.0);
    let dirs = [
        (Vec3::new(1.0, 0.0, 0.0), 0.06),
        (Vec3::new(-1.0, 0.1, 0.0), 0.05),
        (Vec3::new(0.0, 1.0, 0.2), 0.07),
        (Vec3::new(0.1, -1.0, 0.0), 0.04),
        (Vec3::new(0.0, 0.2, 1.0), 0.05),
    ];
    for (k, (d, overlap)) in dirs.iter().enumerate() {
        let x = d.normalize() * (2.0 * R - overlap * R);
        w.p.push(k as i64 + 2, 0, x, 2.0 * R, 1000.0);
    }
    w.setup().unwrap();
    w
}

fn forces(w: &World) -> Vec<f64> {
    (1..w.p.len()).map(|i| w.p.f[i].norm()).collect()
}

fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().copied().fold(0.0, f64::max);
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max) / scale
}

/// One iterated step reaches the limit of the lagged steps, and its loop gain is the lagged
/// sequence's ratio of successive changes. Fails if the iteration stopped early, read the wrong
/// forces, advanced the histories per pass, or if the gain estimate were not the map's.
#[test]
fn one_iterated_step_is_the_limit_of_the_lagged_steps() {
    let mut lag = cluster(None);
    let mut seq = Vec::new();
    for _ in 0..200 {
        lag.step().unwrap();
        seq.push(forces(&lag));
    }
    let limit = seq.last().unwrap().clone();
    // The lagged forces change: the loop is there to be closed (step 1 is Hertz, see mpr_test).
    assert!(rel_diff(&seq[0], &limit) > 0.01, "{:?} {:?}", seq[0], limit);
    assert!(rel_diff(&seq[198], &limit) < 1e-12, "the lagged steps converged");
    // The ratio of successive changes, as the iteration measures it (Euclidean norms).
    let change = |k: usize| seq[k + 1].iter().zip(&seq[k]).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
    let lag_gain = change(8) / change(7);
    let mut fp = cluster(Some(FixedPoint::new(100, 1e-10, 1.0).unwrap()));
    fp.step().unwrap();
    let st = fp.mc_fp_stats;
    println!("lagged gain {lag_gain:.6}, iterated: {} passes, gain {:.6}", st.passes, st.gain_max);
    assert!(rel_diff(&forces(&fp), &limit) < 1e-9, "{:?} {:?}", forces(&fp), limit);
    assert_eq!(st.unconverged, 0);
    assert!(st.passes >= 5 && (st.gain_max - lag_gain).abs() < 0.02 * lag_gain.abs(), "{st:?} {lag_gain}");
    assert!(lag_gain > 0.05, "positive feedback expected, gain {lag_gain}");
}

/// One pass per step is the lagged scheme bit for bit; under-relaxation reaches the same fixed point.
#[test]
fn one_pass_is_the_lag_and_relaxation_reaches_the_same_state() {
    let mut lag = cluster(None);
    let mut one = cluster(Some(FixedPoint::new(1, 1e-10, 1.0).unwrap()));
    for _ in 0..5 {
        lag.step().unwrap();
        one.step().unwrap();
        assert_eq!(forces(&lag), forces(&one));
    }
    let mut full = cluster(Some(FixedPoint::new(100, 1e-10, 1.0).unwrap()));
    let mut relaxed = cluster(Some(FixedPoint::new(200, 1e-10, 0.5).unwrap()));
    full.step().unwrap();
    relaxed.step().unwrap();
    assert!(rel_diff(&forces(&relaxed), &forces(&full)) < 1e-8);
    // ω = 1/2 turns the gain g into (1 + g)/2: more passes for a positive g.
    assert!(relaxed.mc_fp_stats.passes > full.mc_fp_stats.passes);
}

/// The iteration does not combine with the approximations that skip exact passes.
#[test]
fn fixed_point_refuses_the_skipping_approximations() {
    let mut w = cluster(None);
    w.mc_fixed_point = Some(FixedPoint::new(10, 1e-6, 1.0).unwrap());
    w.mc_every = 5;
    let e = w.setup().unwrap_err();
    assert!(e.contains("fixed point") && e.contains("update interval"), "{e}");
}
