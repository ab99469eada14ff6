//! LIGGGHTS' `rolling_friction cdt` in `mcdem run`: step by step against stock LIGGGHTS on
//! `liggghts_inputs/rolling_friction.in` (primitive floor, and the same scene on a mesh floor),
//! the constant deceleration of a sphere rolling on a floor, and the errors of bad input.

use std::path::Path;
use std::process::Command;

use crate::against_liggghts::{assert_dumps_agree, have_liggghts, repo, run_both};
use crate::deck::{run_deck, BASE};

/// Spheres spinning and rolling on a primitive floor, and a pair pressed together with opposite
/// spins, under `cdt` and with `rolling_friction off`: every quantity every step to 1e-12 of its
/// range (measured ≤ 4e-15 for cdt, as for the other laws the difference is the order of the
/// force sums). The torque changes the run: with cdt particle 1's spin at the end is 145.9 rad/s,
/// without 159.8 rad/s (checked so the comparison cannot pass with the torque missing in both).
#[test]
fn rolling_friction_matches_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/rolling_friction.in");
    let f = "post/rolling_friction.dump";
    let mut last_spin = vec![];
    for rf in ["cdt", "off"] {
        let (o, t) = run_both(&deck, &[], &[("rf", rf)]);
        println!("rolling_friction {rf}");
        assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
        let frames = mcdem::outputs::read_dump(&o.path().join(f)).unwrap();
        let fr = frames.last().unwrap();
        let row = fr.rows.iter().find(|r| r[0] as i64 == 1).unwrap();
        last_spin.push(row[10]);
    }
    assert!((last_spin[0] - 145.933).abs() < 0.01 && (last_spin[1] - 159.792).abs() < 0.01, "{last_spin:?}");
}

/// The same scene on a `mesh/surface` floor (the 10 mm plate scaled to 40 mm): LIGGGHTS' mesh
/// walls give the same rolling torque as its primitive walls (lever: the particle radius).
/// Tolerance 1e-12 of the range (measured ≤ 1.4e-14).
#[test]
fn rolling_friction_on_a_mesh_floor_matches_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let text = std::fs::read_to_string(repo().join("liggghts_inputs/rolling_friction.in")).unwrap();
    let floor = "fix\t\tfloor all wall/gran model hertz tangential history rolling_friction ${rf} primitive type 1 zplane 0.0";
    assert!(text.contains(floor));
    let mesh = "fix\t\tplate all mesh/surface file meshes/plate_10mm.stl type 1 scale 4\n\
                fix\t\tfloor all wall/gran model hertz tangential history rolling_friction ${rf} mesh n_meshes 1 meshes plate";
    let dir = tempfile::tempdir().unwrap();
    let deck = dir.path().join("rolling_friction_mesh.in");
    std::fs::write(&deck, text.replace(floor, mesh)).unwrap();
    let meshes = repo().join("liggghts_inputs/meshes");
    let (o, t) = run_both(&deck, &[meshes.as_path()], &[]);
    let f = "post/rolling_friction.dump";
    assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
}

/// A solid sphere rolling without slip on a floor under a rolling torque μ_r F_n R: about the
/// contact point, I_c α = −μ_r F_n R with I_c = (7/5) m R² and a = α R, F_n = m g, so the centre
/// decelerates at a = −(5/7) μ_r g, whatever the sphere's size and mass. (LIGGGHTS' cdt uses the
/// elastic normal force k_n δ, which averages to m g once the bounce has died out.) Measured
/// between 0.01 s and 0.09 s (measured −0.700853 m/s² against −0.700714, 0.02 %; tolerance
/// 0.5 %: the contact point sits δ ≈ 0.9 µm below the centre's radius and the bounce decays).
/// The rolling stays without slip: ω (R − δ/2) = v, so ω R exceeds v by δ/(2R) ≈ 4.6e-4 (bound 1e-3).
/// `epsd` and `epsd2` reach their cap μ_r R |F_n| within the first microseconds (their springs
/// are stiff: k_r ω Δt per step against a cap of 1e-8 N m) and then decelerate the same way
/// (epsd's dashpot is off at the cap).
#[test]
fn a_sphere_rolling_on_a_floor_decelerates_at_five_sevenths_mu_r_g() {
    for model in ["cdt", "epsd", "epsd2"] {
        println!("rolling_friction {model}");
        rolling_sphere_decelerates(model);
    }
}

fn rolling_sphere_decelerates(model: &str) {
    let (mu_r, g, r) = (0.1, 9.81, 0.001);
    let deck = format!(
        "units si
atom_style sphere
boundary f f f
region box block -0.05 0.05 -0.01 0.01 -0.001 0.01 units box
create_box 1 box
neighbor 0.0002 bin
fix m1 all property/global youngsModulus peratomtype 5e6
fix m2 all property/global poissonsRatio peratomtype 0.3
fix m3 all property/global coefficientRestitution peratomtypepair 1 0.5
fix m4 all property/global coefficientFriction peratomtypepair 1 0.5
fix m5 all property/global coefficientRollingFriction peratomtypepair 1 {mu_r}
fix m6 all property/global coefficientRollingViscousDamping peratomtypepair 1 0.3
pair_style gran model hertz tangential history rolling_friction {model}
pair_coeff * *
fix floor all wall/gran model hertz tangential history rolling_friction {model} primitive type 1 zplane 0.0
fix gravi all gravity {g} vector 0.0 0.0 -1.0
timestep 1e-6
create_atoms 1 single -0.04 0 0.000999078 units box
set atom 1 diameter {d} density 2500
set atom 1 vx 0.1 omegay 100
fix integr all nve/sphere
dump d all custom 10000 post/roll.dump id x z vx omegay
run 90000
",
        d = 2.0 * r
    );
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("post")).unwrap();
    std::fs::write(dir.path().join("in.roll"), deck).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .current_dir(dir.path())
        .args(["run", "in.roll", "-log", "none", "--no-progress"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let frames = mcdem::outputs::read_dump(&Path::new(dir.path()).join("post/roll.dump")).unwrap();
    let at = |step: u64| {
        let fr = frames.iter().find(|f| f.step == step).unwrap();
        (fr.rows[0][3], fr.rows[0][4])
    };
    let ((v1, _), (v9, w9)) = (at(10_000), at(90_000));
    let a = (v9 - v1) / 0.08;
    let expected = -5.0 / 7.0 * mu_r * g;
    println!("a = {a:.6} m/s², −(5/7) μ_r g = {expected:.6}");
    assert!(((a - expected) / expected).abs() < 5e-3, "a = {a}, expected {expected}");
    assert!((w9 * r - v9).abs() < 1e-3 * v9, "slipping: ω R = {}, v = {v9}", w9 * r);
}

pub(crate) const ROLLING: &str =
    "fix m5 all property/global coefficientRollingFriction peratomtypepair 1 0.1\n";

/// BASE with `pair_style` replaced by `style` and `props` added before it; then `run 1`.
pub(crate) fn deck(props: &str, style: &str) -> String {
    BASE.replace(
        "pair_style gran model hertz tangential history\n",
        &format!("{props}pair_style gran {style}\n"),
    ) + "run 1\n"
}

#[test]
fn rolling_friction_bad_input_stops_with_file_and_line() {
    let cdt = "model hertz tangential history rolling_friction cdt";
    // BASE has 10 lines before pair_style and 16 in all: without properties `run` is line 17.
    let cases: &[(String, &str)] = &[
        (deck("", cdt), "in.test:17: fix property/global coefficientRollingFriction is missing"),
        (
            deck(&ROLLING.replace("1 0.1", "1 -0.1"), cdt),
            "in.test:18: types 1 and 1: invalid coefficientRollingFriction = -0.1: must be finite and >= 0",
        ),
        (
            deck(ROLLING, "model hertz tangential history rolling_friction sds"),
            "in.test:12: unsupported rolling model 'sds' (cdt, epsd, epsd2 or off)",
        ),
        (
            deck(ROLLING, "model hertz tangential history rolling_friction epsd3"),
            "in.test:12: unsupported rolling_friction epsd3",
        ),
        (
            deck(ROLLING, "model hertz tangential history rolling_friction"),
            "in.test:12: unsupported pair_style gran keyword rolling_friction",
        ),
        (
            deck(ROLLING, "model mc_advanced tangential history rolling_friction cdt"),
            "in.test:12: unsupported rolling_friction cdt with a multi-contact model",
        ),
    ];
    for (text, want) in cases {
        let (ok, out) = run_deck(text, &[]);
        assert!(!ok && out.contains("ERROR: ") && out.contains(want), "want '{want}', got:\n{out}");
    }
}
