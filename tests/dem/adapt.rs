//! `fix adapt ... atom diameter` with atom-style variables and `compute property/atom`: the radius
//! and mass after k calls against the closed form, a contact that growth alone creates between
//! particles at rest (the neighbour list must be rebuilt for it), and bad input named with
//! FILE:LINE. The step-by-step comparison with LIGGGHTS is in `against_liggghts.rs`.

use std::path::Path;

/// Runs a deck in a fresh directory (with a `post/` folder); returns success, the output and the
/// directory.
fn run_deck(text: &str) -> (bool, String, tempfile::TempDir) {
    super::deck::run_in("in.adapt", text, &[], &[("post/", "")])
}

/// Two spheres (d = 2 mm, 2500 and 1000 kg/m³) `gap` apart along x, at rest, no gravity, no walls.
fn base(gap: f64, skin: f64) -> String {
    let x2 = 0.002 + gap;
    format!(
        "units si
atom_style sphere
boundary f f f
region box block -0.01 0.01 -0.01 0.01 -0.01 0.01 units box
create_box 1 box
neighbor {skin} bin
neigh_modify delay 0
fix m1 all property/global youngsModulus peratomtype 5e6
fix m2 all property/global poissonsRatio peratomtype 0.3
fix m3 all property/global coefficientRestitution peratomtypepair 1 0.8
fix m4 all property/global coefficientFriction peratomtypepair 1 0.3
pair_style gran model hertz tangential history
pair_coeff * *
timestep 1e-6
create_atoms 1 single 0 0 0 units box
create_atoms 1 single {x2} 0 0 units box
set atom 1 diameter 0.002 density 2500
set atom 2 diameter 0.002 density 1000
fix integr all nve/sphere
"
    )
}

/// Rows of the dump frame at `step`, by id: (radius, mass, fx).
fn frame(dir: &Path, step: u64) -> Vec<(f64, f64, f64)> {
    let frames = mcdem::outputs::read_dump(&dir.join("post/a.dump")).unwrap();
    let f = frames.iter().find(|f| f.step == step).unwrap_or_else(|| panic!("no frame at step {step}"));
    let c = |n: &str| f.column(n).unwrap();
    let mut rows: Vec<&Vec<f64>> = f.rows.iter().collect();
    rows.sort_by(|a, b| a[c("id")].total_cmp(&b[c("id")]));
    rows.iter().map(|r| (r[c("radius")], r[c("mass")], r[c("fx")])).collect()
}

/// r_k = r_0 q^k after k calls, mass 4/3 π r_k³ ρ (density kept): one call at the run's set-up and
/// one at every step that is a multiple of N (LIGGGHTS 3.8 `fix_adapt.cpp`); none after `unfix`.
/// Relative tolerance 1e-13: k ≤ 12 products of doubles.
#[test]
fn radius_and_mass_follow_the_closed_form() {
    let deck = base(0.004, 0.0002)
        + "compute rad all property/atom radius
variable q equal 1.05
variable d atom v_q*2*c_rad
fix grow all adapt 10 atom diameter v_d
dump a all custom 5 post/a.dump id radius mass fx
dump_modify a format \"%d %.17g %.17g %.17g\"
run 95
run 20
unfix grow
run 10
";
    let (ok, out, dir) = run_deck(&deck);
    assert!(ok, "{out}");
    let rho = [2500.0, 1000.0];
    let check = |step: u64, k: i32| {
        for (p, &(r, m, _)) in frame(dir.path(), step).iter().enumerate() {
            let re = 0.001 * 1.05f64.powi(k);
            let me = 4.0 / 3.0 * std::f64::consts::PI * re.powi(3) * rho[p];
            assert!((r / re - 1.0).abs() < 1e-13, "step {step} particle {}: r {r} vs {re}", p + 1);
            assert!((m / me - 1.0).abs() < 1e-13, "step {step} particle {}: m {m} vs {me}", p + 1);
        }
    };
    check(0, 1); // set-up of the first run
    check(5, 1);
    check(10, 2);
    check(95, 10);
    check(100, 12); // set-up of the second run (step 95), then step 100
    check(115, 13);
    check(125, 13); // after unfix: unchanged, and no set-up call
}

/// Two spheres at rest 0.5 mm apart (2.5 skins) grow by 2 % in diameter every step: nothing moves,
/// so only the growth can make the neighbour list rebuild. They touch at the first step s with
/// 2 r_0 q^(s+1) > 3 mm (the set-up call counts once); the contact force must appear at exactly
/// that step (it would never appear with a list built once for the initial radii).
#[test]
fn growth_alone_brings_a_contact_into_the_neighbour_list() {
    let q: f64 = 1.02;
    let deck = base(0.001, 0.0004)
        + &format!(
            "compute rad all property/atom radius
variable d atom {q}*2*c_rad
fix grow all adapt 1 atom diameter v_d
dump a all custom 1 post/a.dump id radius mass fx
dump_modify a format \"%d %.17g %.17g %.17g\"
run 30
"
        );
    let (ok, out, dir) = run_deck(&deck);
    assert!(ok, "{out}");
    let s = (1u64..).find(|&s| 2.0 * 0.001 * q.powi(s as i32 + 1) > 0.003).unwrap();
    assert!(s < 30);
    let before = frame(dir.path(), s - 1);
    let at = frame(dir.path(), s);
    assert_eq!((before[0].2, before[1].2), (0.0, 0.0), "force before contact at step {}", s - 1);
    assert!(at[0].2 < 0.0 && at[1].2 > 0.0, "no repulsion at step {s}: {at:?}");
    assert!(out.contains("neighbour builds"), "{out}");
}

/// Bad `fix adapt` input stops with FILE:LINE and names the problem.
#[test]
fn bad_adapt_input_is_named() {
    let b = base(0.004, 0.0002) + "compute rad all property/atom radius\n";
    // Line numbers: `base` has 19 lines, the compute is line 20; `tail` starts at line 21.
    let cases: &[(&str, &str)] = &[
        (
            "fix grow all adapt 10 atom diameter v_nope\nrun 10\n",
            "in.adapt:22: fix grow adapt: variable nope does not exist",
        ),
        (
            "variable s string 0.002\nfix grow all adapt 10 atom diameter v_s\nrun 10\n",
            "in.adapt:23: fix grow adapt: variable s is neither atom-style nor equal-style",
        ),
        (
            "variable d atom 2*c_rad-0.003\nfix grow all adapt 10 atom diameter v_d\nrun 10\n",
            "in.adapt:23: fix grow adapt: variable d gives diameter -0.001 for particle 1 at step 0: it must be finite and > 0",
        ),
        ("fix grow all adapt 10 atom diameter d\n", "in.adapt:21: fix grow adapt: expected v_NAME after 'atom diameter', got d"),
        ("fix grow all adapt 10 atom charge v_d\n", "in.adapt:21: unsupported fix grow adapt atom charge"),
        ("fix grow all adapt 10 pair gran x 1 1 v_d\n", "in.adapt:21: unsupported fix grow adapt pair"),
        ("fix grow all adapt -1 atom diameter v_d\n", "in.adapt:21: fix grow adapt: N must be >= 0"),
        ("fix grow all adapt 10 atom diameter v_d reset maybe\n", "in.adapt:21: fix grow adapt reset: expected yes or no"),
        ("fix grow all adapt 10 atom diameter v_d frob 1\n", "in.adapt:21: fix grow adapt: unknown keyword frob"),
        ("variable d atom 2*c_rad\nprint \"${d}\"\n", "in.adapt:22: variable d is atom-style"),
        ("thermo_style custom step c_rad\nrun 1\n", "compute rad is per-atom (property/atom)"),
        ("compute p all property/atom radius foo\n", "in.adapt:21: unsupported compute p property/atom attribute foo"),
    ];
    for (tail, want) in cases {
        let (ok, out, _dir) = run_deck(&format!("{b}{tail}"));
        assert!(
            !ok && out.contains("ERROR: ") && out.contains(want),
            "{tail}: expected \"{want}\" in\n{out}"
        );
    }
}
