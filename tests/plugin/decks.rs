//! End-to-end tests of the LIGGGHTS plugin: the decks in `liggghts_inputs/` run by
//! `mcdem-liggghts` in temporary directories, their `dump custom` and `fix ave/time` output parsed
//! and compared between contact laws.
//!
//! - MPR = 0 reproduces the stock `hertz` (pairs, primitive and mesh walls) to print precision;
//! - MPR huge reproduces the stock `surface multicontact` + `fix multicontact/halfspace` (same γ);
//! - bad decks stop with one `ERROR:` line that names the cause;
//! - the hydrogel packing: piston force of mc_advanced (cap never tripping) vs stock multicontact,
//!   and its independence of the neighbour skin.
//!
//! (The `library.h` bindings are tested in `liggghts_library.rs`, a process of their own.)
//!
//! Dumps are compared with polars (tests/common/frames.rs).
#![cfg(feature = "liggghts")]

use std::path::{Path, PathBuf};
use std::process::Output;

use assert_cmd::Command;
use tempfile::TempDir;

use crate::common::frames;

fn decks() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("liggghts_inputs")
}

/// Runs `deck` in `dir` with `-var` pairs; the log goes to `run.log` (OpenMPI may lose stdout on
/// an error exit, the log file keeps the `ERROR:` line). Returns the output and the log text.
fn run(dir: &Path, deck: &str, vars: &[(&str, &str)]) -> (Output, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mcdem-liggghts"));
    cmd.current_dir(dir).arg("-in").arg(decks().join(deck)).arg("-log").arg("run.log");
    cmd.arg("-var").arg("dir").arg(decks());
    for (k, v) in vars {
        cmd.arg("-var").arg(k).arg(v);
    }
    let out = cmd.output().expect("start mcdem-liggghts");
    let log = std::fs::read_to_string(dir.join("run.log")).unwrap_or_default();
    (out, log)
}

fn run_ok(dir: &Path, deck: &str, vars: &[(&str, &str)]) -> String {
    let (out, log) = run(dir, deck, vars);
    assert!(
        out.status.success(),
        "{deck} {vars:?} failed ({}):\n{}\n{}",
        out.status,
        log.lines().rev().take(15).collect::<Vec<_>>().join("\n"),
        String::from_utf8_lossy(&out.stderr)
    );
    log
}

use mcdem::outputs::Frame;

fn read_dump(path: &Path) -> Vec<Frame> {
    mcdem::outputs::read_dump(path).unwrap()
}

fn read_ave_time(path: &Path) -> Vec<Vec<f64>> {
    mcdem::outputs::read_ave_time(path).unwrap()
}

/// Print precision of the decks' dumps: `%.10g`.
const PRINT_PRECISION: f64 = 1e-9;

fn compare_laws(deck: &str, mc: &[(&str, &str)], stock: &[(&str, &str)]) -> f64 {
    let tmp = TempDir::new().unwrap();
    let mut a = mc.to_vec();
    a.extend([("law", "0"), ("dump", "mc.dump"), ("out", "mc.txt")]);
    let mut b = stock.to_vec();
    b.extend([("dump", "stock.dump"), ("out", "stock.txt")]);
    run_ok(tmp.path(), deck, &a);
    run_ok(tmp.path(), deck, &b);
    assert!(read_dump(&tmp.path().join("mc.dump")).len() > 10, "too few frames in the dump");
    let d = frames::trajectory_difference(&tmp.path().join("mc.dump"), &tmp.path().join("stock.dump"));
    eprintln!("  {deck}: {d:?}");
    d.iter().map(|(_, e)| *e).fold(0.0, f64::max)
}

#[test]
fn mpr_zero_is_stock_hertz_two_particles_and_plate() {
    // Same contact distance factor for both runs: it sets the neighbour lists and so the order in
    // which forces are summed.
    let d =
        compare_laws("two_particles.in", &[("mpr", "0"), ("cdf", "1.2")], &[("law", "1"), ("cdf", "1.2")]);
    assert!(d <= PRINT_PRECISION, "max relative difference {d:e}");
}

/// The plugin evaluates pairs in its own loop (native/pair_loop.cpp, `mc_pair_loop`): what the
/// library's loop hands to its outputs must come out the same. With MPR = 0, `compute
/// pair/gran/local` (dump local: positions, IDs, force, contact area, overlap of every contact) and
/// `compute stress/atom` (the virial tallied per pair) equal stock Hertz's to print precision.
#[test]
fn mpr_zero_is_stock_hertz_in_contact_and_stress_output() {
    let tmp = TempDir::new().unwrap();
    // The deck with the pair virial per atom added to its dump (the Rust engine, which also runs
    // the deck, has no `compute stress/atom`).
    let text = std::fs::read_to_string(decks().join("two_particles.in")).unwrap();
    let dump = "omegax omegay omegaz radius";
    assert!(text.contains(dump));
    let text = text
        .replace("dump            d ", "compute         st all stress/atom pair\ndump            d ")
        .replace(dump, &format!("{dump} c_st[1] c_st[2] c_st[3] c_st[4] c_st[5] c_st[6]"))
        .replace("%.10g\"\n", &format!("%.10g{}\"\n", " %.10g".repeat(6)));
    let deck = tmp.path().join("two_particles_stress.in");
    std::fs::write(&deck, text).unwrap();
    let deck = deck.to_str().unwrap();
    let common = [("mpr", "0"), ("cdf", "1.2")];
    run_ok(tmp.path(), deck, &[&common[..], &[("dump", "mc.dump"), ("contacts", "mc_c.dump")]].concat());
    run_ok(
        tmp.path(),
        deck,
        &[&common[..], &[("law", "1"), ("dump", "stock.dump"), ("contacts", "stock_c.dump")]].concat(),
    );
    let (a, b) = (read_dump(&tmp.path().join("mc_c.dump")), read_dump(&tmp.path().join("stock_c.dump")));
    assert!(b.iter().filter(|f| !f.rows.is_empty()).count() >= 5, "too few frames with a contact");
    assert_eq!(b[0].columns.len(), 14);
    // Dump local prints 6 digits; every column, the force's x and z components among them.
    for c in [9, 11] {
        assert!(b.iter().any(|f| f.rows.iter().any(|r| r[c] != 0.0)), "no contact force in the dump");
    }
    let d_local = frames::frame_difference(&a, &b, &(0..14).collect::<Vec<_>>());
    eprintln!("contacts: max relative difference {d_local:e}");
    assert!(d_local <= 1e-5, "dump local: max relative difference {d_local:e}");
    let (a, b) = (read_dump(&tmp.path().join("mc.dump")), read_dump(&tmp.path().join("stock.dump")));
    let stress: Vec<usize> = ["c_st[1]", "c_st[3]", "c_st[5]"]
        .iter()
        .map(|n| b[0].columns.iter().position(|c| c == n).expect("stress column"))
        .collect();
    for &c in &stress {
        assert!(
            b.iter().any(|f| f.rows.iter().any(|r| r[c] != 0.0)),
            "{} is zero throughout",
            b[0].columns[c]
        );
    }
    let d_stress = frames::frame_difference(&a, &b, &stress);
    eprintln!("per-atom stress: max relative difference {d_stress:e}");
    assert!(d_stress <= PRINT_PRECISION, "stress/atom: max relative difference {d_stress:e}");
}

#[test]
fn mpr_zero_is_stock_hertz_with_primitive_and_mesh_walls() {
    for deck in ["single_particle_plates.in", "bcc_box.in"] {
        let d = compare_laws(deck, &[("mpr", "0"), ("cdf", "1.2")], &[("law", "1"), ("cdf", "1.2")]);
        eprintln!("{deck}: mc_advanced MPR = 0 vs hertz, max relative difference {d:e}");
        assert!(d <= PRINT_PRECISION, "{deck}: max relative difference {d:e}");
    }
}

#[test]
fn huge_mpr_is_stock_multicontact_same_gamma() {
    // Stock multicontact registers a contact distance factor of 2; use it for both. With
    // `pairRadii stock` mc_advanced uses LIGGGHTS's pair convention (the first partner's original
    // radius in R_eff, lever arm and contact point) and is the stock model to round-off, except
    // where the stock bookkeeping depends on the neighbour-list history and mc_advanced does not
    // (docs/liggghts.md, "Neighbour lists"): in bcc_box the atoms are sorted at step 1000, the
    // next list build names some pairs the other way round, and stock then hands each partner the
    // other's radius for one step. That step is the whole difference (measured 1.6e-5 of the force
    // range; with atom sorting switched off in the deck, 5e-11), hence 1e-4 for bcc_box. With the
    // default `pairRadii modified` (docs/spec.md §2: both partners' modified radii, so a pair does not
    // depend on the neighbour-list order) pairs differ at second order; walls are unaffected.
    for (deck, tol_stock, tol) in [
        ("single_particle_plates.in", 1e-6, 1e-6),
        ("two_particles.in", 1e-6, 0.03),
        ("bcc_box.in", 1e-4, 0.03),
    ] {
        let stock = [("law", "2"), ("cdf", "2.0")];
        let d = compare_laws(deck, &[("mpr", "1e9"), ("cdf", "2.0"), ("pairradii", "stock")], &stock);
        eprintln!("{deck}: mc_advanced MPR = 1e9, pairRadii stock vs stock multicontact: {d:e}");
        assert!(d <= tol_stock, "{deck}: pairRadii stock, max relative difference {d:e}");
        let d = compare_laws(deck, &[("mpr", "1e9"), ("cdf", "2.0")], &stock);
        eprintln!("{deck}: mc_advanced MPR = 1e9, pairRadii modified vs stock multicontact: {d:e}");
        assert!(d <= tol, "{deck}: pairRadii modified, max relative difference {d:e}");
    }
}

#[test]
fn cap_moves_the_response_between_hertz_and_standard_mc() {
    // Single particle in the die at Δ/r = 0.3: the neighbour terms reach ~0.01 r, so MPR = 0.01
    // trips the cap for part of the loading; the plate force must differ from both limits and
    // stay finite (no abort), which shows the cap is wired in.
    let tmp = TempDir::new().unwrap();
    let deck = "single_particle_plates.in";
    run_ok(tmp.path(), deck, &[("law", "0"), ("mpr", "0.01"), ("out", "adv.txt"), ("dump", "adv.dump")]);
    run_ok(tmp.path(), deck, &[("law", "1"), ("out", "hz.txt"), ("dump", "hz.dump")]);
    run_ok(tmp.path(), deck, &[("law", "0"), ("mpr", "1e9"), ("out", "mc.txt"), ("dump", "mc.dump")]);
    let last = |f: &str| read_ave_time(&tmp.path().join(f)).last().expect("rows")[2];
    let (adv, hz, mc) = (last("adv.txt"), last("hz.txt"), last("mc.txt"));
    assert!(adv.is_finite() && hz > 0.0 && mc > 1.2 * hz, "adv {adv}, hertz {hz}, standard MC {mc}");
    assert!(
        (adv - mc).abs() > 1e-3 * mc && (adv - hz).abs() > 1e-3 * hz,
        "adv {adv}, hertz {hz}, standard MC {mc}"
    );
}

/// Runs `deck` with mcdem's own engine (`mcdem run`) in `dir`.
fn run_engine(dir: &Path, deck: &str, vars: &[(&str, &str)]) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mcdem"));
    cmd.current_dir(dir)
        .arg("run")
        .arg(decks().join(deck))
        .args(["-log", "none", "-var", "dir"])
        .arg(decks());
    for (k, v) in vars {
        cmd.arg("-var").arg(k).arg(v);
    }
    let out = cmd.output().expect("start mcdem");
    assert!(out.status.success(), "mcdem run {deck} {vars:?}: {}", String::from_utf8_lossy(&out.stderr));
}

/// The same deck run by the plugin and by mcdem's own engine: both evaluate the one Rust core, so
/// the trajectories agree step by step. Tolerance 1e-6 of each quantity's largest magnitude in the
/// run: the engines sum forces in different orders, and the multi-contact feedback amplifies
/// those ulps, but any modelling difference (a radius convention, a lag, a missed contact) shows
/// up at 1e-4 or more within a few hundred steps.
#[test]
fn engine_matches_plugin_step_by_step() {
    let laws: [&[(&str, &str)]; 5] = [
        &[("law", "0")],
        &[("law", "0"), ("mpr", "0.01")],
        &[("law", "0"), ("mpr", "1e9")],
        &[("law", "1")],
        // The update interval too: both engines recompute on the same steps (every K, and at
        // neighbour builds, which follow the same rule in both).
        &[("law", "0"), ("mcevery", "5")],
    ];
    for deck in ["two_particles.in", "single_particle_plates.in", "bcc_box.in"] {
        for law in laws {
            // Only two_particles.in takes the interval (through select_law.inc).
            if law.contains(&("mcevery", "5")) && deck != "two_particles.in" {
                continue;
            }
            let tmp = TempDir::new().unwrap();
            let mut vars = law.to_vec();
            vars.extend([("every", "10"), ("dump", "run.dump"), ("out", "run.txt")]);
            run_ok(tmp.path(), deck, &vars);
            std::fs::rename(tmp.path().join("run.dump"), tmp.path().join("plugin.dump")).unwrap();
            run_engine(tmp.path(), deck, &vars);
            assert!(read_dump(&tmp.path().join("run.dump")).len() >= 40, "{deck}: too few frames");
            let (a, b) = (tmp.path().join("run.dump"), tmp.path().join("plugin.dump"));
            for (q, d) in frames::trajectory_difference(&a, &b) {
                eprintln!("{deck} {law:?}: {q} {d:.2e}");
                assert!(d <= 1e-6, "{deck} {law:?}: {q} differs by {d:e} of its range");
            }
        }
    }
}

/// docs/spec.md §6 hard case: a dropped three-sphere column. Stock `surface multicontact` aborts with
/// "sidata.deltan < 0!" when a radius change leaves a touching pair with no effective overlap;
/// `mc_advanced` treats that contact as open and runs to the end with finite values, the same
/// trajectory in the plugin and in the engine.
#[test]
fn three_sphere_stack_runs_where_stock_multicontact_aborts() {
    let tmp = TempDir::new().unwrap();
    let deck = "three_sphere_stack.in";
    let (out, _) = run(tmp.path(), deck, &[("law", "2"), ("dump", "stock.dump")]);
    assert!(!out.status.success(), "stock multicontact was expected to abort on this deck");
    for mpr in ["1e9", "0.11"] {
        let vars = [("law", "0"), ("mpr", mpr), ("dump", "run.dump")];
        run_ok(tmp.path(), deck, &vars);
        let frames = read_dump(&tmp.path().join("run.dump"));
        assert_eq!(frames.last().map(|f| f.step), Some(20000));
        assert!(frames.iter().all(|f| f.rows.iter().flatten().all(|v| v.is_finite())));
        std::fs::rename(tmp.path().join("run.dump"), tmp.path().join("plugin.dump")).unwrap();
        run_engine(tmp.path(), deck, &vars);
        let (a, b) = (tmp.path().join("run.dump"), tmp.path().join("plugin.dump"));
        for (q, d) in frames::trajectory_difference(&a, &b) {
            assert!(d <= 1e-6, "MPR {mpr}: {q} differs by {d:e} between engine and plugin");
        }
    }
}

/// A run driven beyond the contact law's range (the hydrogel piston at 10 m/s, 100 times the
/// example's speed: particles are pushed through each other within 200 steps) stops at the first
/// overlap that reaches a particle radius, with one ERROR line naming both particles and the step,
/// in the batched pair path (default) and in the one-contact path (`pairRadii stock`) alike; it
/// never runs on with interpenetrating particles or NaN.
#[test]
fn overlap_beyond_the_radius_stops_the_run_naming_the_particles() {
    let tmp = TempDir::new().unwrap();
    for radii in ["modified", "stock"] {
        let vars = vec![("stroke", "300"), ("strokes", "1"), ("pairradii", radii)];
        expect_error(
            ("hydrogel.in", vars),
            tmp.path(),
            &["model mc_advanced: particles ", " and ", "step ", "reached the particle radius"],
        );
    }
}

/// A copy of the two-particle deck edited by `edit`, written into `dir`.
fn edited_deck(dir: &Path, edit: impl Fn(&str) -> String) -> String {
    let text = std::fs::read_to_string(decks().join("two_particles.in")).unwrap();
    let name = "edited.in";
    std::fs::write(dir.join(name), edit(&text)).unwrap();
    dir.join(name).to_string_lossy().into_owned()
}

fn expect_error(deck_vars: (&str, Vec<(&str, &str)>), dir: &Path, needles: &[&str]) {
    let (deck, mut vars) = deck_vars;
    vars.push(("steps", "10"));
    let (out, log) = run(dir, deck, &vars);
    assert!(!out.status.success(), "{deck} {vars:?} should fail");
    // OpenMPI's abort path can lose either the log file's buffer or stdout: take the ERROR
    // lines from whichever kept them.
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let error_lines =
        |t: &str| t.lines().filter(|l| l.starts_with("ERROR")).map(str::to_owned).collect::<Vec<_>>();
    let errors = if log.contains("ERROR") { error_lines(&log) } else { error_lines(&stdout) };
    assert_eq!(errors.len(), 1, "{deck} {vars:?}: expected one ERROR line, got {errors:?}; stdout {stdout}");
    for n in needles {
        assert!(errors[0].contains(n), "{:?} does not name {n:?}", errors[0]);
    }
}

#[test]
fn bad_decks_stop_with_one_error_line_naming_the_cause() {
    let tmp = TempDir::new().unwrap();
    let d = tmp.path();
    let two = "two_particles.in";
    // Negative values go through deck edits: the command line reads "-0.5" as a new switch.
    let deck = edited_deck(d, |t| {
        t.replace(
            "geometricPrefactor peratomtype ${gamma} ${gamma}",
            "geometricPrefactor peratomtype -0.5 0.81",
        )
    });
    expect_error((&deck, vec![]), d, &["geometricPrefactor", "-0.5"]);
    let deck = edited_deck(d, |t| {
        t.replace("maxPenetrationRatio peratomtype ${mpr} ${mpr}", "maxPenetrationRatio peratomtype 0.1 -1")
    });
    expect_error((&deck, vec![]), d, &["maxPenetrationRatio", "-1", "type 2"]);
    expect_error((two, vec![("mprtest", "sometimes")]), d, &["mprTest", "sometimes"]);
    expect_error((two, vec![("pairradii", "both")]), d, &["pairRadii", "both"]);
    expect_error((two, vec![("geomtol", "small")]), d, &["geometryTolerance", "small"]);
    let deck = edited_deck(d, |t| t.replace("${mkey3} ${mval3}", "geometryTolerance -1e-3"));
    expect_error((&deck, vec![]), d, &["geometryTolerance", "-1e-3"]);
    // A wall's multi-contact settings would be ignored (the pair style's pass serves it): another
    // value than the pair style's stops the deck, the same value is accepted.
    // (`slot` is the wall line's `${mkeyN} ${mvalN}` pair to replace: the deck gives every setting
    // once, and the last value given wins.)
    let wall_setting = |slot: &str, setting: &str| {
        edited_deck(d, |t| {
            t.lines()
                .map(|l| if l.contains("wall/gran") { l.replace(slot, setting) } else { l.into() })
                .collect::<Vec<_>>()
                .join("\n")
        })
    };
    let tol = wall_setting("${mkey3} ${mval3}", "geometryTolerance 1e-3");
    expect_error((&tol, vec![]), d, &["geometryTolerance 0.001", "pair style's geometryTolerance 0"]);
    run_ok(d, &tol, &[("geomtol", "1e-3"), ("steps", "10")]);
    let every = wall_setting("${mkey4} ${mval4}", "updateEvery 4");
    expect_error((&every, vec![]), d, &["updateEvery 4", "pair style's updateEvery 1"]);
    let signed = wall_setting("${mkey} ${mval}", "mprTest signed");
    expect_error((&signed, vec![]), d, &["mprTest signed", "pair style's mprTest abs"]);
    expect_error((two, vec![("mcevery", "0")]), d, &["updateEvery", "'0'"]);
    expect_error((two, vec![("mcevery", "2.5")]), d, &["updateEvery", "2.5"]);

    let deck = edited_deck(d, |t| {
        t.replace("poissonsRatio peratomtype 0.5 0.5", "poissonsRatio peratomtype 0.6 0.5")
    });
    expect_error((&deck, vec![]), d, &["poissonsRatio", "0.6"]);
    let deck = edited_deck(d, |t| {
        t.replace("poissonsRatio peratomtype 0.5 0.5", "poissonsRatio peratomtype -0.1 0.5")
    });
    expect_error((&deck, vec![]), d, &["poissonsRatio", "-0.1"]);
    for prop in ["geometricPrefactor", "maxPenetrationRatio", "youngsModulus", "coefficientRestitution"] {
        let deck = edited_deck(d, |t| t.lines().filter(|l| !l.contains(prop)).collect::<Vec<_>>().join("\n"));
        expect_error((&deck, vec![]), d, &[prop]);
    }
}

/// The accuracy budget (`mcAccuracy`, docs/dem.md) runs in `mcdem run` only: the plugin stops
/// naming the keyword and the library's reason rather than run without it, for every keyword of
/// the library's engine-only list (`physics::mc_settings::ENGINE_ONLY`).
#[test]
fn accuracy_budget_is_refused_by_the_plugin() {
    use mcdem::physics::mc_settings::{ENGINE_ONLY, ENGINE_ONLY_WHY};
    let tmp = TempDir::new().unwrap();
    let d = tmp.path();
    let why = ENGINE_ONLY_WHY.to_str().unwrap();
    let keys: Vec<&str> = ENGINE_ONLY.iter().map(|k| k.to_str().unwrap()).collect();
    assert_eq!(keys, ["mcAccuracy", "mcAccuracyCheck"], "the budget's keywords (docs/dem.md)");
    for (key, value) in keys.iter().zip(["1e-3", "yes"]) {
        let deck = edited_deck(d, |t| t.replace("${mkey3} ${mval3}", &format!("{key} {value}")));
        expect_error((&deck, vec![]), d, &[key, "is not implemented in the LIGGGHTS plugin", why]);
    }
}

use mcdem::outputs::nrmse;

#[test]
fn hydrogel_piston_force_matches_stock_multicontact_when_cap_never_trips() {
    // Shortened for test time: one compression stroke in 3000 steps (ten times the example's
    // piston speed), the same for both laws; γ = 1.125 as in the Debian example.
    let tmp = TempDir::new().unwrap();
    let common = [("stroke", "3000"), ("strokes", "1"), ("every", "100"), ("cdf", "2.0")];
    let mut mc = common.to_vec();
    mc.extend([("law", "0"), ("mpr", "1e9"), ("pairradii", "stock"), ("out", "mc.txt")]);
    let mut st = common.to_vec();
    st.extend([("law", "2"), ("out", "stock.txt")]);
    run_ok(tmp.path(), "hydrogel.in", &mc);
    run_ok(tmp.path(), "hydrogel.in", &st);
    let fz = |f: &str| read_ave_time(&tmp.path().join(f)).iter().map(|r| r[3]).collect::<Vec<f64>>();
    let (a, b) = (fz("mc.txt"), fz("stock.txt"));
    assert_eq!(a.len(), 30);
    let e = nrmse(&a, &b);
    eprintln!(
        "hydrogel, one fast stroke: piston F_z NRMSE mc_advanced (MPR 1e9) vs stock multicontact = {e:.3e}"
    );
    assert!(e <= 0.02, "NRMSE {e}");
}

/// `statestroke N` writes the state after stroke N (the nonlocal compression starts from it): the
/// write is a zero-step run inside an `if`, which LIGGGHTS runs only when spelled out there (it
/// refuses `include` inside `if`).
#[test]
fn hydrogel_deck_writes_the_state_after_a_stroke() {
    let tmp = TempDir::new().unwrap();
    let vars = [("stroke", "3000"), ("strokes", "1"), ("statestroke", "1"), ("statefile", "state.dump")];
    run_ok(tmp.path(), "hydrogel.in", &vars);
    let frames = read_dump(&tmp.path().join("state.dump"));
    assert_eq!(frames.len(), 1);
    let f = &frames[0];
    let id = f.column("id").unwrap();
    let mut ids: Vec<i64> = f.rows.iter().map(|r| r[id] as i64).collect();
    ids.sort_unstable();
    assert_eq!(ids, (1..=514).collect::<Vec<_>>());
    for c in ["radius", "x", "y", "z", "vx", "vy", "vz"] {
        let k = f.column(c).unwrap_or_else(|| panic!("no column {c}"));
        assert!(f.rows.iter().all(|r| r[k].is_finite()), "{c}");
    }
}

#[test]
fn hydrogel_approximations_bound_the_piston_force_error_in_the_plugin() {
    // The two approximations of the multi-contact pass (docs/dem.md), on two 3000-step strokes:
    // - `geometryTolerance` keeps each particle's Eq. 2 geometry until a contact point moved that
    //   fraction of its radius: 6e-4 of the force range measured on the full-speed deck at 1e-3,
    //   the same as the Rust engine's;
    // - `updateEvery K` recomputes the radius changes every K steps and at neighbour builds: the
    //   radius changes lag by up to K steps, so the error grows with K (bounds as in the Rust
    //   engine's test, tests/dem/mc_approximations.rs: this piston is ten times faster).
    // Each error must shrink with its setting, and `updateEvery 1` is the exact run.
    let tmp = TempDir::new().unwrap();
    let run_with = |tol: &str, every: &str| {
        let out = format!("tol{tol}_every{every}.txt");
        let vars = [
            ("stroke", "3000"),
            ("strokes", "2"),
            ("every", "10"),
            ("geomtol", tol),
            ("mcevery", every),
            ("out", &out),
        ];
        run_ok(tmp.path(), "hydrogel.in", &vars);
        read_ave_time(&tmp.path().join(&out)).iter().map(|r| r[3]).collect::<Vec<f64>>()
    };
    let exact = run_with("0", "1");
    let range =
        exact.iter().cloned().fold(f64::MIN, f64::max) - exact.iter().cloned().fold(f64::MAX, f64::min);
    let worst = |f: Vec<f64>| {
        assert_eq!(f.len(), exact.len());
        f.iter().zip(&exact).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / range
    };
    let (e4, e3) = (worst(run_with("1e-4", "1")), worst(run_with("1e-3", "1")));
    eprintln!("hydrogel plugin, geometry tolerance: max |dF|/range {e4:.2e} (1e-4), {e3:.2e} (1e-3)");
    assert!(e4 < 2e-4 && e3 < 2e-3 && e4 < e3, "{e4:e} (1e-4), {e3:e} (1e-3)");
    let (k2, k5) = (worst(run_with("0", "2")), worst(run_with("0", "5")));
    eprintln!("hydrogel plugin, update interval: max |dF|/range {k2:.2e} (every 2), {k5:.2e} (every 5)");
    assert!(k2 > 0.0 && k2 < 1e-2 && k5 < 4e-2 && k2 < k5, "{k2:e} (every 2), {k5:e} (every 5)");
}

#[test]
fn hydrogel_piston_force_does_not_depend_on_the_neighbour_skin() {
    // Changing the skin changes only when the neighbour lists are rebuilt (and the order of the
    // force sums). Shortened: one compression cycle of 3000-step strokes. Three pieces of
    // LIGGGHTS's multi-contact bookkeeping made the result depend on the list history
    // (docs/liggghts.md, "Neighbour lists"); with the other two handled, each of them alone gave
    // these NRMSEs between skins 0.004 and 0.0041 on this run: pair records in list order 6.7e-5,
    // mesh rows filed under the wrong triangle 3.6e-3, primitive-wall rows shared between
    // particles 1.2e-3. Now the runs agree at the print precision of `fix ave/time` (6 digits).
    let tmp = TempDir::new().unwrap();
    let skins = ["0.004", "0.0041", "0.006"];
    for (k, skin) in skins.iter().enumerate() {
        let out = format!("skin{k}.txt");
        let vars = [("stroke", "3000"), ("strokes", "2"), ("every", "50"), ("skin", skin), ("out", &out)];
        run_ok(tmp.path(), "hydrogel.in", &vars);
    }
    let fz =
        |k: usize| read_ave_time(&tmp.path().join(format!("skin{k}.txt"))).iter().map(|r| r[3]).collect();
    let reference: Vec<f64> = fz(0);
    assert_eq!(reference.len(), 120);
    for (k, skin) in skins.iter().enumerate().skip(1) {
        let e = nrmse(&fz(k), &reference);
        eprintln!("hydrogel, one cycle: piston F_z NRMSE skin {skin} vs {} = {e:.3e}", skins[0]);
        assert!(e <= 1e-5, "skin {skin} vs {}: NRMSE {e:e}", skins[0]);
    }
}

/// LIGGGHTS 3.8 cannot run the Lees–Edwards shear study in its own idiom (triclinic box + `fix
/// deform … remap v`): a triclinic box gets no periodic ghost atoms, so contacts across periodic
/// boundaries vanish without an error (docs/shear.md). If a LIGGGHTS version fixes this, this test
/// fails and the shear cross-check becomes possible.
#[test]
fn triclinic_boxes_lose_periodic_ghosts_in_liggghts() {
    let stat = |log: &str, key: &str| -> f64 {
        log.lines()
            .find_map(|l| l.strip_prefix(key))
            .and_then(|r| r.split_whitespace().next().and_then(|v| v.parse().ok()))
            .unwrap_or_else(|| panic!("no '{key}' line in the log"))
    };
    let dir = tempfile::tempdir().unwrap();
    let ortho = run_ok(dir.path(), "triclinic_ghost_probe.in", &[("tri", "0")]);
    let tri = run_ok(dir.path(), "triclinic_ghost_probe.in", &[("tri", "1")]);
    let (g0, g1) = (stat(&ortho, "Nghost:"), stat(&tri, "Nghost:"));
    let (n0, n1) = (stat(&ortho, "Total # of neighbors ="), stat(&tri, "Total # of neighbors ="));
    eprintln!("orthogonal: {g0} ghosts, {n0} neighbours; triclinic: {g1} ghosts, {n1} neighbours");
    assert!(g0 > 0.0 && n0 > 0.0, "the orthogonal periodic box must have ghosts");
    assert_eq!(g1, 0.0, "triclinic box now has ghosts: add the LIGGGHTS shear cross-check");
    assert!(n1 < n0);
}

/// `liggghts_inputs/soft_packing.in`, the soft-particle example deck (polydisperse `insert/pack`,
/// then a mesh piston under `mc_advanced`), on its first 2000 steps in both engines: both insert
/// the same number of spheres (insert/pack fills a volume fraction, so the count does not depend on
/// the random stream, which differs between the engines) and write the same piston table rows
/// (step, piston height). The full stroke and its piston curves against LIGGGHTS with two seeds
/// are recorded in validation/recorded/soft_packing/.
#[test]
fn soft_packing_example_runs_in_both_engines() {
    let dir = TempDir::new().unwrap();
    std::fs::create_dir_all(dir.path().join("post")).unwrap();
    let log = run_ok(dir.path(), "soft_packing.in", &[("steps", "2000"), ("out", "post/liggghts.txt")]);
    assert!(log.contains("inserted 452 particle templates"), "{log}");
    let out = Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .current_dir(dir.path())
        .arg("run")
        .arg(decks().join("soft_packing.in"))
        .args(["-log", "none", "--no-progress", "-var", "steps", "2000", "-var", "out", "post/mcdem.txt"])
        .args(["-var", "dir"])
        .arg(decks())
        .output()
        .expect("start mcdem");
    let text = String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("inserted 452 particles"), "{text}");
    let (a, b) = (
        read_ave_time(&dir.path().join("post/mcdem.txt")),
        read_ave_time(&dir.path().join("post/liggghts.txt")),
    );
    assert_eq!(a.len(), 4);
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x[0], y[0]);
        assert!((x[1] - y[1]).abs() < 1e-12, "piston height {} against {}", x[1], y[1]);
    }
}
