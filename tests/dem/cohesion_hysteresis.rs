//! LIGGGHTS' `cohesion sjkr` and `model hooke/hysteresis` in `mcdem run`: step by step against
//! stock LIGGGHTS on the small decks `liggghts_inputs/two_particles_sjkr.in` and
//! `two_particles_hysteresis.in`, and the errors of bad input. (The closed forms — the SJKR
//! contact area, the hysteresis loop's dissipated energy — are unit tests of `physics::sjkr` and
//! `physics::hooke_hysteresis`.)

use std::path::Path;

use crate::against_liggghts::{assert_dumps_agree, have_liggghts, repo, run_both};
use crate::deck::{run_deck, BASE};

/// Rows of the dump by step: id → [x y z vx vy vz fx fy fz ωx ωy ωz].
fn trajectory(path: &Path) -> Vec<std::collections::HashMap<i64, Vec<f64>>> {
    mcdem::outputs::read_dump(path)
        .unwrap()
        .iter()
        .map(|fr| fr.rows.iter().map(|r| (r[0] as i64, r[1..].to_vec())).collect())
        .collect()
}

/// Overlap r_i + r_j − |x_i − x_j| of particles `i`, `j` (radii as the decks set them) at every step.
fn overlaps(tr: &[std::collections::HashMap<i64, Vec<f64>>], i: i64, j: i64) -> Vec<f64> {
    let radius = |id: i64| [0.001, 0.0009, 0.001, 0.0009, 0.0008][id as usize - 1];
    tr.iter()
        .map(|fr| {
            let (a, b) = (&fr[&i], &fr[&j]);
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            radius(i) + radius(j) - d
        })
        .collect()
}

/// `hertz tangential history cohesion sjkr` on pairs and on a primitive wall, with
/// `tangential_reduce off` (LIGGGHTS' default) and `on`: every quantity every step to 1e-12 of
/// its range, as for the other small decks (the same law in the same operation order; measured
/// ≤ 4.1e-15). The scene must show the feature: the slow pair sticks (still overlapping at the
/// end), the weakly cohesive fast pair rebounds, the sphere stays on the wall, and
/// `tangential_reduce` changes the motion.
#[test]
fn sjkr_collisions_and_wall_match_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/two_particles_sjkr.in");
    let f = "post/two_particles_sjkr.dump";
    let mut ours = Vec::new();
    for tr in ["off", "on"] {
        let (o, t) = run_both(&deck, &[], &[("tr", tr)]);
        println!("tangential_reduce {tr}");
        assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
        let tr = trajectory(&o.path().join(f));
        let stick = overlaps(&tr, 1, 2);
        assert!(stick.iter().take(1000).all(|&d| d < 0.0), "pair 1-2 starts apart");
        assert!(*stick.last().unwrap() > 1e-4, "pair 1-2 did not stick: {}", stick.last().unwrap());
        let rebound = overlaps(&tr, 3, 4);
        assert!(
            rebound.iter().any(|&d| d > 0.0) && *rebound.last().unwrap() < 0.0,
            "pair 3-4 did not rebound"
        );
        // Sphere 5 (radius 0.8 mm) rests on the cohesive floor, pulled into it.
        assert!(tr.last().unwrap()[&5][2] < 0.0007);
        ours.push(tr);
    }
    let (a, b) = (ours[0].last().unwrap(), ours[1].last().unwrap());
    let moved = (1..=5).map(|id| (a[&id][0] - b[&id][0]).abs()).fold(0.0, f64::max);
    assert!(moved > 1e-7, "tangential_reduce changed nothing: {moved:e}");
}

/// `hooke/hysteresis tangential history` pairs beside a `model hooke` wall, with
/// `tangential_damping on` and `off`: every quantity every step to 1e-12 of its range (measured
/// ≤ 8.2e-15). Pair 1-2 (type pair 1-2, plasticity depth 0.002) loads beyond δ_lim = 2.8 µm,
/// pair 3-4 (type pair 1-1, δ_lim = 100 µm) stays below it; both unload through the adhesive
/// branch and part.
#[test]
fn hysteresis_collisions_match_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/two_particles_hysteresis.in");
    let f = "post/two_particles_hysteresis.dump";
    for td in ["on", "off"] {
        let (o, t) = run_both(&deck, &[], &[("td", td)]);
        println!("tangential_damping {td}");
        assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
        let tr = trajectory(&o.path().join(f));
        for (i, j, lo, hi) in [(1, 2, 2.8e-6, 1.0), (3, 4, 0.0, 1e-4)] {
            let d = overlaps(&tr, i, j);
            let max = d.iter().cloned().fold(f64::MIN, f64::max);
            assert!(max > lo && max < hi, "pair {i}-{j}: largest overlap {max:e}");
            assert!(*d.last().unwrap() < 0.0, "pair {i}-{j} did not part");
        }
    }
}

const COHESIVE: &str = "fix m5 all property/global cohesionEnergyDensity peratomtypepair 1 3e5\n";
const HYSTERESIS: &str = "fix m5 all property/global characteristicVelocity scalar 2\n\
fix m6 all property/global coefficientMaxElasticStiffness peratomtypepair 1 2\n\
fix m7 all property/global coefficientAdhesionStiffness peratomtypepair 1 0.2\n\
fix m8 all property/global coefficientPlasticityDepth peratomtypepair 1 0.05\n";

/// BASE with `pair_style` replaced by `style` and `props` added before it; then `tail`.
fn deck(props: &str, style: &str, tail: &str) -> String {
    BASE.replace(
        "pair_style gran model hertz tangential history\n",
        &format!("{props}pair_style gran {style}\n"),
    ) + tail
}

#[test]
fn cohesion_and_hysteresis_bad_input_stops_with_file_and_line() {
    let run = "run 1\n";
    let cases: &[(String, &str)] = &[
        // BASE has 10 lines before pair_style and 16 in all: without properties `run` is line 17.
        (
            deck("", "model hertz tangential history cohesion sjkr", run),
            "in.test:17: fix property/global cohesionEnergyDensity is missing",
        ),
        (
            deck(
                &COHESIVE.replace("1 3e5", "1 -3e5"),
                "model hertz tangential history cohesion sjkr",
                run,
            ),
            "in.test:18: types 1 and 1: invalid cohesionEnergyDensity = -300000: must be finite and >= 0",
        ),
        (
            deck(COHESIVE, "model hertz tangential history cohesion washino", run),
            "in.test:12: unsupported cohesion model 'washino' (sjkr or off)",
        ),
        (
            deck(COHESIVE, "model hertz tangential history tangential_reduce on", run),
            "in.test:12: tangential_reduce is a setting of cohesion sjkr",
        ),
        (
            deck(&HYSTERESIS.replace("fix m8 all property/global coefficientPlasticityDepth peratomtypepair 1 0.05\n", ""), "model hooke/hysteresis tangential history", run),
            "in.test:20: fix property/global coefficientPlasticityDepth is missing",
        ),
        (
            deck(&HYSTERESIS.replace("peratomtypepair 1 0.2", "peratomtypepair 1 -0.2"), "model hooke/hysteresis tangential history", run),
            "in.test:21: types 1 and 1: invalid coefficientAdhesionStiffness = -0.2: must be finite and >= 0",
        ),
        (
            deck(&HYSTERESIS.replace("peratomtypepair 1 2\n", "peratomtypepair 1 0.5\n"), "model hooke/hysteresis tangential history", run),
            "in.test:21: types 1 and 1: invalid coefficientMaxElasticStiffness = 0.5: must be finite and > 1",
        ),
        (
            deck(HYSTERESIS, "model hooke/hysteresis tangential history limitForce on", run),
            "in.test:15: limitForce on has no effect in LIGGGHTS 3.8's model hooke/hysteresis",
        ),
        (
            deck(
                HYSTERESIS,
                "model hooke/hysteresis tangential history",
                "fix w all wall/gran model hooke/hysteresis tangential history primitive type 1 zplane -0.005\nrun 1\n",
            ),
            "in.test:21: unsupported fix wall/gran model hooke/hysteresis",
        ),
        (
            deck(
                HYSTERESIS,
                "model hooke/hysteresis tangential history",
                "fix w all wall/gran model hertz tangential history primitive type 1 zplane -0.005\nrun 1\n",
            ),
            "in.test:21: unsupported a wall model different from the pair model",
        ),
        (
            // Restarts have no field for the largest overlap: a pair in the neighbour list stops it.
            deck(
                HYSTERESIS,
                "model hooke/hysteresis tangential history",
                "create_atoms 1 single 0.0021 0 0 units box\nset atom 2 diameter 0.002 density 1000\nrun 10\nwrite_restart r.restart\n",
            ),
            "in.test:24: write_restart: the contact history of model hooke/hysteresis",
        ),
    ];
    for (text, want) in cases {
        let (ok, out) = run_deck(text, &[]);
        assert!(!ok && out.contains("ERROR: ") && out.contains(want), "want '{want}' in:\n{out}");
    }
    // The good forms run: cohesion on the pairs only, and hooke walls beside hysteresis pairs.
    for text in [
        deck(
            COHESIVE,
            "model hertz tangential history cohesion sjkr",
            "fix w all wall/gran model hertz tangential history primitive type 1 zplane -0.005\nrun 10\n",
        ),
        deck(
            HYSTERESIS,
            "model hooke/hysteresis tangential history",
            "fix w all wall/gran model hooke tangential history primitive type 1 zplane -0.005\nrun 10\n",
        ),
    ] {
        let (ok, out) = run_deck(&text, &[]);
        assert!(ok, "{out}");
    }
}
