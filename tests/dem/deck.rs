//! Deck reader behaviour: unknown input stops with FILE:LINE, VTK dumps are written, -var overrides
//! index variables, bad values are named.

use std::path::Path;
use std::process::Command;

/// Runs `mcdem run` on `text`, written to `name` in a fresh directory beside `files` (name and
/// contents; a name ending in `/` is a folder), with the `extra` arguments. Returns whether it
/// succeeded, its stdout and stderr, and the directory (for the files the deck wrote).
pub(crate) fn run_in(
    name: &str,
    text: &str,
    extra: &[&str],
    files: &[(&str, &str)],
) -> (bool, String, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    for (file, body) in files {
        match file.strip_suffix('/') {
            Some(folder) => std::fs::create_dir_all(dir.path().join(folder)).unwrap(),
            None => std::fs::write(dir.path().join(file), body).unwrap(),
        }
    }
    let deck = dir.path().join(name);
    std::fs::write(&deck, text).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .current_dir(dir.path())
        .arg("run")
        .arg(&deck)
        .args(extra)
        .args(["-log", "none"])
        .output()
        .unwrap();
    let all = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    (o.status.success(), all, dir)
}

pub(crate) fn run_deck(text: &str, extra: &[&str]) -> (bool, String) {
    let (ok, out, _) = run_in("in.test", text, extra, &[]);
    (ok, out)
}

pub(crate) const BASE: &str = "units si
atom_style sphere
boundary f f f
region box block -0.01 0.01 -0.01 0.01 -0.01 0.01 units box
create_box 1 box
neighbor 0.0002 bin
fix m1 all property/global youngsModulus peratomtype 5e6
fix m2 all property/global poissonsRatio peratomtype 0.3
fix m3 all property/global coefficientRestitution peratomtypepair 1 0.8
fix m4 all property/global coefficientFriction peratomtypepair 1 0.3
pair_style gran model hertz tangential history
pair_coeff * *
timestep 1e-6
create_atoms 1 single 0 0 0 units box
set atom 1 diameter 0.002 density 1000
fix integr all nve/sphere
";

#[test]
fn unknown_command_names_file_and_line() {
    let (ok, out) = run_deck(&format!("{BASE}fix x all wiggle/foo 1\nrun 10\n"), &[]);
    assert!(!ok);
    assert!(out.contains("ERROR: ") && out.contains("in.test:17: unsupported fix style wiggle/foo"), "{out}");
    let (ok, out) = run_deck(&format!("{BASE}frobnicate\n"), &[]);
    assert!(!ok && out.contains("in.test:17: unsupported command frobnicate"), "{out}");
}

#[test]
fn vtk_dumps_are_written_and_unsupported_forms_stop() {
    // The files themselves are checked in tests/cli/compare_vtk.rs.
    let (ok, out) = run_deck(&format!("{BASE}dump d all custom/vtk 10 post/x*.vtk id x\nrun 10\n"), &[]);
    assert!(ok && !out.contains("WARNING"), "{out}");
    let (ok, out) = run_deck(&format!("{BASE}dump d all custom/vtk 10 post/x*.vtu id x\nrun 10\n"), &[]);
    assert!(!ok && out.contains("in.test:17: unsupported dump custom/vtk to post/x*.vtu"), "{out}");
}

#[test]
fn var_on_the_command_line_overrides_index_variables() {
    let text = format!("{BASE}variable n index 5\nprint \"steps ${{n}}\"\nrun ${{n}}\n");
    let (ok, out) = run_deck(&text, &["-var", "n", "7"]);
    assert!(ok, "{out}");
    assert!(out.contains("steps 7") && out.contains("for 7 steps"), "{out}");
}

#[test]
fn nested_loops_with_label_next_and_jump() {
    // LAMMPS semantics: an exhausted `next` deletes the variable and skips the following jump,
    // so the inner loop restarts for every outer value.
    let text = "variable i loop 2\nlabel outer\nvariable j loop 3\nlabel inner\n\
                print \"cell $(10*v_i+v_j)\"\nnext j\njump SELF inner\nnext i\njump SELF outer\n\
                print done\n";
    let (ok, out) = run_deck(&format!("{BASE}{text}"), &[]);
    assert!(ok, "{out}");
    let cells: Vec<&str> = out.lines().filter(|l| l.starts_with("cell")).collect();
    assert_eq!(cells, ["cell 11", "cell 12", "cell 13", "cell 21", "cell 22", "cell 23"], "{out}");
    assert!(out.contains("done"));
    let (ok, out) = run_deck(&format!("{BASE}jump SELF nowhere\n"), &[]);
    assert!(!ok && out.contains("no label nowhere"), "{out}");
}

#[test]
fn pair_local_output_errors_name_the_problem() {
    // No keyword: LIGGGHTS's default set, pos vel id force torque history contactArea = 25 columns.
    let default = |k: usize| {
        format!("{BASE}compute fc all pair/gran/local\ndump dl all local 1 c.dump c_fc[{k}]\nrun 1\n")
    };
    let (ok, out) = run_deck(&default(25), &[]);
    assert!(ok, "{out}");
    let (ok, out) = run_deck(&default(26), &[]);
    assert!(!ok && out.contains("c_fc[26] beyond its 25 columns"), "{out}");
    let (ok, out) = run_deck(&format!("{BASE}compute fc all pair/gran/local pos heatFlux\nrun 1\n"), &[]);
    assert!(!ok && out.contains("heatFlux: out of scope: heat transfer"), "{out}");
    let (ok, out) = run_deck(&format!("{BASE}compute fc all pair/gran/local contactPoint\nrun 1\n"), &[]);
    assert!(!ok && out.contains("contactPoint is not one of LIGGGHTS 3.8"), "{out}");
    let (ok, out) = run_deck(&format!("{BASE}compute fc all pair/gran/local forces\nrun 1\n"), &[]);
    assert!(!ok && out.contains("unsupported compute pair/gran/local keyword forces"), "{out}");
    let (ok, out) = run_deck(&format!("{BASE}dump dl all local 1 c.dump c_nope[1]\nrun 1\n"), &[]);
    assert!(!ok && out.contains("no compute pair/gran/local nope"), "{out}");
    let text =
        format!("{BASE}compute fc all pair/gran/local delta\ndump dl all local 1 c.dump c_fc[2]\nrun 1\n");
    let (ok, out) = run_deck(&text, &[]);
    assert!(!ok && out.contains("c_fc[2] beyond its 1 columns"), "{out}");
    // `history` has 3 columns under tangential history and none under no_history.
    let text =
        format!("{BASE}compute fc all pair/gran/local history\ndump dl all local 1 c.dump c_fc[3]\nrun 1\n");
    let (ok, out) = run_deck(&text, &[]);
    assert!(ok, "{out}");
    let no_history = text.replace("tangential history", "tangential no_history");
    let (ok, out) = run_deck(&no_history, &[]);
    assert!(!ok && out.contains("c_fc[3] beyond its 0 columns"), "{out}");
}

#[test]
fn bad_material_value_is_named() {
    let text = BASE.replace("poissonsRatio peratomtype 0.3", "poissonsRatio peratomtype 0.7") + "run 1\n";
    let (ok, out) = run_deck(&text, &[]);
    assert!(!ok && out.contains("poisson_ratio") && out.contains("0.7"), "{out}");
}

#[test]
fn update_every_is_checked_and_belongs_to_mc_advanced() {
    let mc = |setting: &str| {
        BASE.replace(
            "pair_style gran model hertz tangential history",
            &format!(
                "fix m5 all property/global geometricPrefactor peratomtype 0.81\n\
                 fix m6 all property/global maxPenetrationRatio peratomtype 0.11\n\
                 pair_style gran model mc_advanced tangential history {setting}"
            ),
        ) + "run 1\n"
    };
    let (ok, out) = run_deck(&mc("updateEvery 10"), &[]);
    assert!(ok && out.contains("multi-contact update every 10 steps"), "{out}");
    for bad in ["0", "2.5", "-3", "often", "1000000001"] {
        let (ok, out) = run_deck(&mc(&format!("updateEvery {bad}")), &[]);
        let named = format!("updateEvery must be a whole number of steps from 1 to 1000000000, got '{bad}'");
        assert!(!ok && out.contains(&named), "{out}");
    }
    // Walls share the pair style's pass: a different value is a contradiction, not a setting.
    let wall = "fix w all wall/gran model mc_advanced tangential history primitive type 1 zplane -0.01 updateEvery 5";
    let with_wall = |wall: &str| mc("updateEvery 10").replace("run 1\n", &format!("{wall}\nrun 1\n"));
    let (ok, out) = run_deck(&with_wall(wall), &[]);
    assert!(
        !ok && out.contains(
            "wall/gran with model mc_advanced: updateEvery 5 differs from the pair style's updateEvery 10"
        ),
        "{out}"
    );
    let tol = wall.replace("updateEvery 5", "geometryTolerance 1e-3");
    let (ok, out) = run_deck(&with_wall(&tol), &[]);
    assert!(!ok && out.contains("wall/gran with model mc_advanced: geometryTolerance 0.001 differs from the pair style's geometryTolerance 0"), "{out}");
    // Settings before the geometry count the same.
    let before = wall
        .replace("history primitive", "history geometryTolerance 1e-3 primitive")
        .replace(" updateEvery 5", "");
    let (ok, out) = run_deck(&with_wall(&before), &[]);
    assert!(!ok && out.contains("wall/gran with model mc_advanced: geometryTolerance 0.001 differs from the pair style's geometryTolerance 0"), "{out}");
    // Repeating the pair style's values is fine.
    let same = wall.replace("updateEvery 5", "updateEvery 10 geometryTolerance 0");
    let (ok, out) = run_deck(&with_wall(&same), &[]);
    assert!(ok, "{out}");
    // The command-line approximations belong to mc_advanced as well.
    let (ok, out) = run_deck(&format!("{BASE}run 1\n"), &["--mc-update-every", "5"]);
    assert!(!ok && out.contains("apply to model mc_advanced only; this pair style is model hertz"), "{out}");
    let text = BASE.replace("tangential history", "tangential history updateEvery 10") + "run 1\n";
    let (ok, out) = run_deck(&text, &[]);
    assert!(!ok && out.contains("updateEvery is a setting of model mc_advanced"), "{out}");
}

#[test]
fn atom_modify_sort_values_are_checked() {
    // Accepted: LAMMPS' form, and 0 to switch spatial sorting off.
    for ok_line in ["atom_modify map array sort 1000 0.0", "atom_modify sort 0 0"] {
        let (ok, out) = run_deck(&format!("{ok_line}\n{BASE}run 1\n"), &[]);
        assert!(ok, "{ok_line}: {out}");
    }
    for (line, named) in [
        ("atom_modify sort -5 0.0", "Nfreq '-5' is not an integer >= 0"),
        ("atom_modify sort 1000 -1", "binsize '-1' is not a number >= 0"),
        ("atom_modify sort 1000", "expected Nfreq binsize"),
    ] {
        let (ok, out) = run_deck(&format!("{line}\n{BASE}run 1\n"), &[]);
        assert!(!ok && out.contains(named), "{line}: {out}");
    }
}

#[test]
fn include_if_and_immediate_expressions() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("part.inc"), "variable from_include equal 2*${half}\n").unwrap();
    let deck = format!(
        "variable half equal 0.5\ninclude {}/part.inc\n\
         if \"${{from_include}} == 1\" then \"print 'took then $(v_from_include*3)'\" else \"print took-else\"\n\
         if \"${{from_include}} > 5\" then \"print wrong\" elif \"1 < 2\" \"print took-elif\"\n{BASE}run 1\n",
        dir.path().display()
    );
    let (ok, out) = run_deck(&deck, &[]);
    assert!(ok, "{out}");
    assert!(out.contains("took then 3"), "{out}");
    assert!(out.contains("took-elif") && !out.contains("wrong") && !out.contains("took-else"), "{out}");
    let (ok, out) = run_deck("include /nonexistent/part.inc\n", &[]);
    assert!(!ok && out.contains("include: cannot read /nonexistent/part.inc"), "{out}");
    let (ok, out) = run_deck("if \"1 == 1\" \"print x\"\n", &[]);
    assert!(!ok && out.contains("expected 'then'"), "{out}");
}

#[test]
fn die_decks_of_the_plugin_run_in_the_engine() {
    // The single-particle die deck (include, if, $(...), rotated mesh, wall model settings) runs
    // unmodified with Hertz and its plate force grows with the plate travel.
    let decks = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("liggghts_inputs");
    let dir = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .current_dir(dir.path())
        .arg("run")
        .arg(decks.join("single_particle_plates.in"))
        .args(["-var", "law", "1", "-var", "dir"])
        .arg(&decks)
        .args(["-var", "out", "f.txt", "-log", "none"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = mcdem::outputs::read_ave_time(&dir.path().join("f.txt")).unwrap();
    assert_eq!(rows.len(), 30);
    let fz: Vec<f64> = rows.iter().map(|r| r[2]).collect();
    assert!(fz.windows(2).all(|w| w[1] > w[0]) && fz[0] > 0.0, "{fz:?}");
    // Hertz closed form: the plate travel (column 1, averaged over the output window like the
    // force) is shared by the top and bottom contacts of the centred sphere, R = r = 1 mm.
    let e_star = 1.0 / ((1.0 - 0.25) / 23.3e3 + (1.0 - 0.25) / 5e7);
    let expected = 4.0 / 3.0 * e_star * 1e-3f64.sqrt() * (rows[29][1] / 2.0).powf(1.5);
    assert!((fz[29] - expected).abs() < 2e-3 * expected, "{} vs {expected}", fz[29]);
}

/// The library entry point keeps an engine stop apart from a broken deck: parameter searches
/// (`mcdem calibrate`, the standard-MC γ ladder of `validate uniaxial`) score the first as an
/// unstable law and abort on the second.
#[test]
fn deck_failures_say_whether_the_engine_stopped() {
    use mcdem::deck::{run_file_checked, Options};
    let dir = tempfile::tempdir().unwrap();
    let opts = Options { log: Some("none".into()), progress: false, quiet: true, ..Default::default() };
    // Two spheres driven into each other at 200 m/s: the overlap passes a radius within a step.
    let crash = format!(
        "{BASE}create_atoms 1 single 0.0015 0 0 units box\nset atom 2 diameter 0.002 density 1000\n\
         set atom 1 vx 100\nset atom 2 vx -100\nrun 100\n"
    );
    let deck = dir.path().join("in.crash");
    std::fs::write(&deck, crash).unwrap();
    let e = run_file_checked(&deck, &opts).unwrap_err();
    let stop = e.instability.clone().expect("an engine stop");
    assert!(stop.particle == 1 || stop.particle == 2, "{e}");
    assert!(stop.cause.contains("overlap"), "{e}");
    // A deck error is not an engine stop, and names file and line.
    let broken = dir.path().join("in.broken");
    std::fs::write(&broken, format!("{BASE}frobnicate all\nrun 10\n")).unwrap();
    let e = run_file_checked(&broken, &opts).unwrap_err();
    assert!(e.instability.is_none(), "{e}");
    assert!(e.message.contains("in.broken:") && e.message.contains("frobnicate"), "{e}");
}

/// `--threads-mode` fixes the choice the timing probe otherwise makes; a bad value is refused by
/// name, and on the hydrogel deck (514 spheres, walls and a mesh piston: every threaded pass runs)
/// the piston force on two forced threads is the serial one, byte for byte, and the `Loop time`
/// lines say how many steps were threaded (none, all).
#[test]
fn threads_mode_is_checked_and_changes_no_result() {
    let (ok, out) = run_deck(&format!("{BASE}run 1\n"), &["--threads-mode", "sometimes"]);
    assert!(!ok && out.contains("invalid value 'sometimes' for '--threads-mode"), "{out}");
    let (ok, out) = run_deck(&format!("{BASE}run 1\n"), &["--threads-mode", "parallel"]);
    assert!(ok, "{out}");
    // The project's own 514-sphere packing (the Debian example's needs liggghts-doc).
    let data = mcdem::validate::packing::shipped();
    let dir = tempfile::tempdir().unwrap();
    let decks = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("liggghts_inputs");
    let piston = |mode: &str| {
        let out = dir.path().join(format!("piston_{mode}.txt"));
        let o = Command::new(env!("CARGO_BIN_EXE_mcdem"))
            .env("RAYON_NUM_THREADS", "2")
            .args([
                "run",
                decks.join("hydrogel.in").to_str().unwrap(),
                "--threads-mode",
                mode,
                "-log",
                "none",
            ])
            .args(["-var", "stroke", "1000", "-var", "strokes", "2", "-var", "every", "10"])
            .args(["-var", "dir", decks.to_str().unwrap(), "-var", "out", out.to_str().unwrap()])
            .args(["-var", "data", data.to_str().unwrap()])
            .output()
            .unwrap();
        assert!(o.status.success(), "{mode}: {}", String::from_utf8_lossy(&o.stderr));
        // The share of threaded steps, from every `Loop time` line of the run.
        let log = String::from_utf8_lossy(&o.stdout).into_owned();
        let shares: Vec<f64> = mcdem::outputs::loop_details(&log)
            .unwrap()
            .iter()
            .map(|d| {
                // Serial mode names one thread whatever the pool size (the pool is never used).
                if mode == "serial" {
                    assert!(d.threads == 1 && d.threaded_percent.is_none(), "{mode}: {d:?}");
                    return 0.0;
                }
                assert_eq!(d.threads, 2, "{mode}: {d:?}");
                d.threaded_percent.unwrap_or_else(|| panic!("{mode}: {d:?}"))
            })
            .collect();
        assert!(!shares.is_empty(), "{mode}: no Loop time line in\n{log}");
        (std::fs::read(out).unwrap(), shares)
    };
    let (serial, shares) = piston("serial");
    assert!(serial.len() > 1000, "piston output too short");
    assert!(shares.iter().all(|&s| s == 0.0), "serial mode says it threaded: {shares:?}");
    let (parallel, shares) = piston("parallel");
    assert!(parallel == serial, "two forced threads changed the piston force");
    // Forced threads run every step's pair pass on them (the deck has ~2 000 pairs: two blocks).
    assert!(shares.iter().all(|&s| s == 100.0), "parallel mode left steps serial: {shares:?}");
}

/// A sphere flying out of a fixed box stops the run naming it and the box side (LAMMPS: "Lost
/// atoms"), at the neighbour check that finds it; it never runs on with a particle outside.
#[test]
fn a_particle_leaving_a_fixed_box_stops_the_run() {
    let (ok, out) = run_deck(&format!("{BASE}set atom 1 vx 50\nrun 1000\n"), &[]);
    assert!(!ok, "{out}");
    assert!(
        out.contains("particle 1") && out.contains("left the box along x") && out.contains("lost particle"),
        "{out}"
    );
}

/// `run N upto` runs to step N (LAMMPS), not N more steps; a step already passed is an error.
/// Measured through `compute ke` and thermo: a sphere at 1 m/s keeps ke = ½ m v² (no contacts).
#[test]
fn run_upto_and_compute_ke() {
    let deck = format!(
        "{BASE}set atom 1 vx 1\ncompute k all ke\nthermo_style custom step c_k\nthermo 100\nrun 300\nrun 500 upto\n"
    );
    let (ok, out) = run_deck(&deck, &[]);
    assert!(ok, "{out}");
    let rows: Vec<(u64, f64)> = out
        .lines()
        .filter_map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            (w.len() == 2).then(|| Some((w[0].parse().ok()?, w[1].parse().ok()?))).flatten()
        })
        .collect();
    let last = rows.last().unwrap();
    assert_eq!(last.0, 500, "{out}");
    // m = 4/3 π (1e-3)³ · 1000 kg/m³; ke = ½ m (1 m/s)².
    let ke = 0.5 * 4.0 / 3.0 * std::f64::consts::PI * 1e-9 * 1000.0;
    assert!(rows.iter().all(|r| (r.1 - ke).abs() <= 1e-6 * ke), "{rows:?} vs {ke}");
    let (ok, out) = run_deck(&format!("{BASE}run 300\nrun 200 upto\n"), &[]);
    assert!(!ok && out.contains("run upto: target step already passed"), "{out}");
}

/// `dump custom` every N steps across three runs with an atom added between the first two: a frame
/// at every multiple of N (step 0 included), none at a run's start off the grid (step 250), no
/// second frame when a run starts on a step already written (500), and each frame holding the atoms
/// present then. The same deck through LIGGGHTS writes the same frames.
#[test]
fn custom_dump_frames_follow_the_interval_and_the_atom_count() {
    // LIGGGHTS's granular pair style needs newton off (before the box), ghost velocities and no
    // neighbour delay; the engine reads the same lines.
    let base = BASE.replace("atom_style sphere\n", "atom_style sphere\nnewton off\n");
    let deck = format!(
        "{base}communicate single vel yes\nneigh_modify delay 0\n\
         dump d all custom 100 out.dump id type x y z vx\nrun 250\n\
         create_atoms 1 single 0.005 0 0 units box\nset atom 2 diameter 0.002 density 1000\n\
         run 250\nrun 100\n"
    );
    let want: Vec<(u64, usize)> = vec![(0, 1), (100, 1), (200, 1), (300, 2), (400, 2), (500, 2), (600, 2)];
    let frames = |dir: &Path| -> Vec<(u64, usize)> {
        let fr = mcdem::outputs::read_dump(&dir.join("out.dump")).unwrap();
        // Every row carries the six columns asked for, ids 1..=n in order.
        for f in &fr {
            assert_eq!(f.columns, ["id", "type", "x", "y", "z", "vx"], "step {}", f.step);
            let ids: Vec<f64> = f.rows.iter().map(|r| r[0]).collect();
            assert_eq!(ids, (1..=f.rows.len()).map(|k| k as f64).collect::<Vec<_>>(), "step {}", f.step);
        }
        fr.iter().map(|f| (f.step, f.rows.len())).collect()
    };
    let ours = tempfile::tempdir().unwrap();
    std::fs::write(ours.path().join("in.test"), &deck).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .current_dir(ours.path())
        .args(["run", "in.test", "-log", "none"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(frames(ours.path()), want);
    if crate::common::present(Command::new("liggghts").arg("-h").output().is_ok(), "the liggghts binary") {
        let theirs = tempfile::tempdir().unwrap();
        std::fs::write(theirs.path().join("in.test"), &deck).unwrap();
        let o = Command::new("liggghts")
            .current_dir(theirs.path())
            .args(["-in", "in.test", "-log", "none"])
            .output()
            .unwrap();
        assert!(o.status.success(), "liggghts: {}", String::from_utf8_lossy(&o.stdout));
        assert_eq!(frames(theirs.path()), want, "LIGGGHTS");
    }
}

/// A value that parses as a float but is not finite (`nan`, `inf`: Rust's parser takes both) is bad
/// input, named with file and line, not a state that runs on as NaN. Checked to fail: with the
/// finiteness test removed from the deck's number reader, `set ... vx nan` is accepted.
#[test]
fn non_finite_values_are_refused_with_file_and_line() {
    for bad in ["nan", "inf", "-infinity"] {
        let (ok, out) = run_deck(&format!("{BASE}set atom 1 vx {bad}\nrun 10\n"), &[]);
        assert!(!ok, "{bad}: {out}");
        assert!(out.contains("in.test:17") && out.contains("expected a finite number"), "{bad}: {out}");
    }
}

#[test]
fn out_of_scope_features_stop_before_the_first_line_naming_theirs() {
    // Checked before anything runs: nothing of the deck's mechanical part is written.
    for (line, says) in [
        (
            "pair_style gran/hertz/history 266000.0 NULL 500.0 NULL 0.5 1",
            "the LIGGGHTS 2.x pair_style gran/hertz/history, which LIGGGHTS 3.8 rejects too",
        ),
        ("fix heat all heat/gran initial_temperature 300", "heat transfer (fix heat/gran)"),
        ("fix w all mesh/surface/stress file a.stl type 1 wear finnie", "wear of mesh walls"),
    ] {
        let (ok, out) = run_deck(&BASE.replace("pair_style gran model hertz tangential history", line), &[]);
        assert!(!ok && out.contains(&format!("in.test:11: out of scope: {says}")), "{line}: {out}");
    }
}

#[test]
fn contact_model_keywords_name_the_bad_value() {
    let pair = "pair_style gran model hertz tangential history";
    for (to, says) in [
        (
            "pair_style gran tangential history",
            "in.test:11: pair_style gran: 'model hertz', 'model hooke', 'model hooke/hysteresis' or 'model mc_advanced' is required",
        ),
        (
            "pair_style gran model hooke/stiff tangential history",
            "in.test:11: unsupported granular model 'hooke/stiff' (hertz, hooke, hooke/hysteresis or mc_advanced)",
        ),
        (
            // As in LIGGGHTS, the missing property is found when the run starts.
            "pair_style gran model hooke tangential history",
            "in.test:17: fix property/global characteristicVelocity is missing (model hooke needs",
        ),
        (
            "pair_style gran model hooke tangential history surface multicontact",
            "in.test:11: model hooke has no multi-contact form",
        ),
        ("pair_style gran model hooke tangential history viscous on", "in.test:11: unsupported viscous on"),
        (
            "pair_style gran model hertz tangential history limitForce on",
            "in.test:11: unsupported limitForce on with model hertz (model hooke only)",
        ),
        (
            "pair_style gran model hertz tangential spring",
            "in.test:11: unsupported tangential model 'spring' (history or no_history)",
        ),
        (
            "pair_style gran model hertz tangential history geometryTolerance 0.1",
            "in.test:11: geometryTolerance is a setting of model mc_advanced",
        ),
    ] {
        let (ok, out) = run_deck(&format!("{}run 1\n", BASE.replace(pair, to)), &[]);
        assert!(!ok && out.contains(says), "{to}: {out}");
    }
}

/// `fix check/timestep/gran`: one sphere (r = 1 mm, ρ = 1000 kg/m³, E = 5 MPa, ν = 0.3) moving
/// force-free at 1 m/s, Δt = 1 µs, skin 0.2 mm. By hand: t_R = π r √(ρ/G) / (0.1631 ν + 0.8766)
/// = 7.7404e-5 s (Δt/t_R = 0.0129193); t_H = 2.87 (m² / (r/2 · E_eff² · 2v))^(1/5) with
/// E_eff = E / (2(1 − ν²)) = 2.1437e-4 s (Δt/t_H = 0.0046649); v_max Δt / skin = 2 m/s · 1 µs /
/// 0.2 mm = 0.01. The vector is 0 before the first check (step 0), the warnings come when Δt passes
/// the fractions and not with `warn no`, and a bad keyword names the line.
#[test]
fn check_timestep_gran_reports_rayleigh_and_hertz_fractions() {
    let deck = |args: &str| {
        format!(
            "{BASE}set atom 1 vx 1\nfix ts all check/timestep/gran 100 {args}\nthermo_style custom step f_ts[1] f_ts[2] f_ts[3]\nthermo_modify format float %.10g\nthermo 100\nrun 200\n"
        )
    };
    let (ok, out) = run_deck(&deck("0.1 0.1"), &[]);
    assert!(ok, "{out}");
    let rows: Vec<Vec<f64>> = out
        .lines()
        .filter_map(|l| l.split_whitespace().map(|w| w.parse::<f64>().ok()).collect::<Option<Vec<f64>>>())
        .filter(|r| r.len() == 4)
        .collect();
    assert_eq!(rows.len(), 3, "{out}");
    assert_eq!(rows[0], [0.0, 0.0, 0.0, 0.0], "nothing before the first check: {out}");
    for r in &rows[1..] {
        assert!((r[1] / 0.012919299 - 1.0).abs() < 1e-7, "Rayleigh fraction {r:?}");
        assert!((r[2] / 0.0046648975 - 1.0).abs() < 1e-7, "Hertz fraction {r:?}");
        assert!((r[3] / 0.01 - 1.0).abs() < 1e-8, "skin fraction {r:?}");
    }
    assert!(!out.contains("WARNING: time-step"), "below the fractions: {out}");
    let (ok, out) = run_deck(&deck("0.01 0.001"), &[]);
    assert!(ok, "{out}");
    assert_eq!(out.matches("WARNING: time-step is 1.291930 % of rayleigh time").count(), 2, "{out}");
    assert_eq!(out.matches("WARNING: time-step is 0.466490 % of hertz time").count(), 2, "{out}");
    let (ok, out) = run_deck(&deck("0.01 0.001 warn no"), &[]);
    assert!(ok && !out.contains("WARNING: time-step"), "{out}");
    let (ok, out) = run_deck(&deck("0.01 0.001 warm no"), &[]);
    assert!(
        !ok && out.contains("in.test:18: fix ts check/timestep/gran: expected 'warn yes' or 'warn no'"),
        "{out}"
    );
}

/// `read_data` through the one data-file reader (`src/deck/data_file.rs`): a good file gives its
/// atoms and velocities; a count that does not match the header and an unknown section stop with
/// the deck's file:line and the data file named.
#[test]
fn read_data_reads_atoms_and_velocities_and_names_bad_files() {
    let data = "title\n\n2 atoms\n1 atom types\n0 1 xlo xhi\n0 1 ylo yhi\n0 1 zlo zhi\n\nAtoms\n\n\
                1 1 0.1 1000 0.25 0.5 0.5\n2 1 0.1 1000 0.75 0.5 0.5\n\nVelocities\n\n2 0.5 0 0 0 0 0\n";
    let deck = "units si\natom_style sphere\nboundary f f f\nread_data f.data\n\
                fix m1 all property/global youngsModulus peratomtype 5e6\n\
                fix m2 all property/global poissonsRatio peratomtype 0.3\n\
                fix m3 all property/global coefficientRestitution peratomtypepair 1 0.8\n\
                fix m4 all property/global coefficientFriction peratomtypepair 1 0.3\n\
                pair_style gran model hertz tangential history\npair_coeff * *\ntimestep 1e-6\n\
                dump d all custom 1 out.dump id x vx radius\nrun 0\n";
    let (ok, out, dir) = run_in("in.test", deck, &[], &[("f.data", data)]);
    assert!(ok && out.contains("2 atoms, velocities read"), "{out}");
    let rows = mcdem::outputs::read_dump(&dir.path().join("out.dump")).unwrap().pop().unwrap().rows;
    assert_eq!(rows, vec![vec![1.0, 0.25, 0.0, 0.05], vec![2.0, 0.75, 0.5, 0.05]]);
    for (from, to, says) in [
        ("2 atoms", "3 atoms", "f.data: header says 3 atoms, found 2"),
        ("1 atom types", "Masses", "unsupported data file section or header \"Masses\" in "),
    ] {
        let (ok, out, _) = run_in("in.test", deck, &[], &[("f.data", &data.replace(from, to))]);
        let line = out.lines().find(|l| l.starts_with("ERROR:")).unwrap_or_default();
        assert!(!ok && line.contains("in.test:4: ") && line.contains(says), "{to}: {out}");
    }
}
