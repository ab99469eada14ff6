//! mcdem run vs stock LIGGGHTS on the same decks: step-by-step dumps of the small decks in
//! `liggghts_inputs/`, and the piston force of the hydrogel example (NRMSE per stroke).
//! A machine without `liggghts` (or without the `liggghts-doc` examples) fails these tests, unless
//! `MCDEM_NO_LIGGGHTS=1` says on purpose that it has none (README); tests/run.sh installs both.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{frames, present};

const HYDROGEL: &str = "/usr/share/doc/liggghts/examples/LIGGGHTS/Tutorials_public/hydrogel_multicontact";

pub(crate) fn have_liggghts() -> bool {
    // `liggghts -h` exits with status 1 after printing its help: only "could it start" matters.
    present(Command::new("liggghts").arg("-h").output().is_ok(), "the liggghts binary")
}

/// Are the Debian hydrogel example's files there (package liggghts-doc)?
fn have_hydrogel() -> bool {
    have_liggghts() && present(Path::new(HYDROGEL).exists(), HYDROGEL)
}

pub(crate) fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs a deck with both engines in two fresh directories (with `extra` copied in); returns them.
pub(crate) fn run_both(
    deck: &Path,
    extra: &[&Path],
    vars: &[(&str, &str)],
) -> (tempfile::TempDir, tempfile::TempDir) {
    let ours = tempfile::tempdir().unwrap();
    let theirs = tempfile::tempdir().unwrap();
    for d in [&ours, &theirs] {
        std::fs::create_dir_all(d.path().join("post")).unwrap();
        for e in extra {
            copy_dir(e, &d.path().join(e.file_name().unwrap()));
        }
    }
    let mut c = Command::new("liggghts");
    c.current_dir(theirs.path()).arg("-in").arg(deck).arg("-log").arg("log.liggghts");
    for (k, v) in vars {
        c.arg("-var").arg(k).arg(v);
    }
    let o = c.output().unwrap();
    assert!(o.status.success(), "liggghts failed: {}", String::from_utf8_lossy(&o.stdout));
    let mut c = Command::new(env!("CARGO_BIN_EXE_mcdem"));
    c.current_dir(ours.path()).arg("run").arg(deck).arg("-log").arg("none");
    for (k, v) in vars {
        c.arg("-var").arg(k).arg(v);
    }
    let o = c.output().unwrap();
    assert!(
        o.status.success(),
        "mcdem failed: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    (ours, theirs)
}

fn copy_dir(from: &Path, to: &Path) {
    if from.is_dir() {
        std::fs::create_dir_all(to).unwrap();
        for e in std::fs::read_dir(from).unwrap() {
            let e = e.unwrap();
            copy_dir(&e.path(), &to.join(e.file_name()));
        }
    } else {
        std::fs::copy(from, to).unwrap();
    }
}

/// Every quantity of the two dumps within `tol` of its largest magnitude over the run (read with
/// polars; frames by step, atoms by id).
/// Every dumped quantity of every frame (written with 15 significant digits) to `tol` of its range.
///
/// The tolerances at the call sites are 10–30 times the measured differences: a few-particle
/// run differs from LIGGGHTS only by the order of floating-point sums (measured ≤ 6.6e-14 of the
/// range, so the bound is 1e-12); in a dense packing that round-off grows through many contacts
/// (256 spheres over 30 steps: measured 6.6e-14, bound 1e-11; the die decks over their whole run:
/// measured 5.6e-11, bound 1e-9). A lost contact or a wrong force term shows
/// at 1e-4 or more.
pub(crate) fn assert_dumps_agree(ours: &Path, theirs: &Path, tol: f64) {
    for (q, e) in frames::trajectory_difference(ours, theirs) {
        println!("{q:>8}: {e:.3e}");
        assert!(e <= tol, "{q}: relative difference {e:e} > {tol:e}");
    }
}

#[test]
fn two_particle_collision_matches_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/two_particle_collision.in");
    for tangential in ["history", "no_history"] {
        let (o, t) = run_both(&deck, &[], &[("tangential", tangential)]);
        let f = "post/two_particle.dump";
        println!("tangential {tangential}");
        assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
        // compute pair/gran/local + dump local: every column of every contact entry, to the
        // dump's 6 printed digits.
        let f = "post/two_particle_contacts.dump";
        let read = |d: &tempfile::TempDir| mcdem::outputs::read_dump(&d.path().join(f)).unwrap();
        let (a, b) = (read(&o), read(&t));
        assert_eq!(a.len(), b.len());
        assert!(b.iter().filter(|fr| !fr.rows.is_empty()).count() >= 10, "too few frames with a contact");
        let width = b[0].columns.len();
        assert_eq!(width, 29);
        let d = frames::frame_difference(&a, &b, &(0..width).collect::<Vec<_>>());
        assert!(d <= 1e-5, "dump local: max relative difference {d:e}");
    }
}

/// `model hooke tangential history` (two atom types, gravity): a head-on and an oblique
/// collision between spheres and a spinning sphere hitting a primitive `zplane` wall, every
/// quantity every step, with LIGGGHTS' default options and with all three options switched
/// (`tangential_damping off limitForce on ktToKnUser on`). Tolerance 1e-12 of each quantity's
/// range, as for the Hertz collision: the same law evaluated in the same operation order differs
/// only by the order of the few force sums (measured ≤ 5.1e-15).
#[test]
fn hooke_collisions_and_wall_match_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/two_particles_hooke.in");
    let defaults: &[(&str, &str)] = &[];
    let switched: &[(&str, &str)] = &[("td", "off"), ("lf", "on"), ("kt", "on")];
    for vars in [defaults, switched] {
        let (o, t) = run_both(&deck, &[], vars);
        let f = "post/two_particles_hooke.dump";
        println!("options {vars:?}");
        assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
        // The scene has contacts: every particle feels a horizontal force at some step.
        let read = mcdem::outputs::read_dump(&t.path().join(f)).unwrap();
        for id in 1..=5 {
            let touched = read.iter().any(|fr| {
                fr.rows.iter().any(|r| r[0] as i64 == id && (r[7].abs() > 1e-9 || r[8].abs() > 1e-9))
            });
            assert!(touched, "particle {id} never touched anything");
        }
    }
}

/// `compute pair/gran/local … history`: under `hertz tangential history` LIGGGHTS lists the
/// pair's tangential spring (3 columns); the same deck with that compute, to the 6 printed digits.
/// Twice: with the keywords listed out of LIGGGHTS's column order (`delta history id`: LIGGGHTS
/// writes id, history, delta, 7 columns, whatever the order in the deck) and with no keyword
/// (LIGGGHTS's default set, pos vel id force torque history contactArea: 25 columns).
#[test]
fn pair_gran_local_history_and_default_set_match_liggghts() {
    if !have_liggghts() {
        return;
    }
    let text = std::fs::read_to_string(repo().join("liggghts_inputs/two_particle_collision.in")).unwrap();
    let keys = "pos vel id force force_normal force_tangential torque contactArea delta";
    assert!(text.contains(keys));
    for (listed, width, spring) in [(" delta history id", 7, 3), ("", 25, 21)] {
        let cols: String = (1..=width).map(|k| format!(" c_fc[{k}]")).collect();
        let text: String = text
            .replace(&format!(" {keys}"), listed)
            .lines()
            .map(|l| {
                if l.starts_with("dump\t\tdl ") {
                    format!("dump\t\tdl all local 10 post/two_particle_contacts.dump{cols}")
                } else {
                    l.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        let dir = tempfile::tempdir().unwrap();
        let deck = dir.path().join("history.in");
        std::fs::write(&deck, text).unwrap();
        let (o, t) = run_both(&deck, &[], &[]);
        let f = "post/two_particle_contacts.dump";
        let read = |d: &tempfile::TempDir| mcdem::outputs::read_dump(&d.path().join(f)).unwrap();
        let (a, b) = (read(&o), read(&t));
        assert_eq!(a.len(), b.len());
        assert!(b.iter().filter(|fr| !fr.rows.is_empty()).count() >= 10, "too few frames with a contact");
        assert_eq!(b[0].columns.len(), width, "keywords '{listed}'");
        // The spring is not zero (the collision is oblique and spinning), so the columns carry it.
        assert!(b.iter().flat_map(|fr| &fr.rows).any(|r| r[spring].abs() > 1e-7), "keywords '{listed}'");
        let d = frames::frame_difference(&a, &b, &(0..width).collect::<Vec<_>>());
        assert!(d <= 1e-5, "dump local, keywords '{listed}': max relative difference {d:e}");
    }
}

/// Primitive `zcylinder` walls: three spheres pressed, rolling and sliding on the inside of an
/// off-centre cylinder and one thrown against its outside, every quantity every 10 steps.
#[test]
fn spheres_on_a_primitive_cylinder_wall_match_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/spheres_in_cylinder.in");
    let (o, t) = run_both(&deck, &[], &[]);
    let f = "post/cylinder.dump";
    assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
}

#[test]
fn particle_between_moving_plates_matches_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/particle_between_plates.in");
    let meshes = repo().join("liggghts_inputs/meshes");
    let (o, t) = run_both(&deck, &[&meshes], &[]);
    let f = "post/plates.dump";
    assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
    assert_plate_forces_agree(o.path(), t.path());
}

/// The mesh/surface/stress force f_plate[3] written by fix ave/time (read with polars; LIGGGHTS
/// prints 6 digits): the same rows and values to 1e-5 of the largest. Returns that largest [N].
fn assert_plate_forces_agree(ours: &Path, theirs: &Path) -> f64 {
    let read = |d: &Path| frames::ave_time(&d.join("post/plates_force.txt"));
    let (a, b) = (read(ours), read(theirs));
    assert_eq!(frames::values(&a, "TimeStep"), frames::values(&b, "TimeStep"));
    let name = b.get_column_names()[3].to_string();
    let (fa, fb) = (frames::values(&a, &name), frames::values(&b, &name));
    let scale = fb.iter().map(|v| v.abs()).fold(0.0, f64::max);
    for (k, (x, y)) in fa.iter().zip(&fb).enumerate() {
        assert!((x - y).abs() <= 1e-5 * scale, "row {k}: plate force {x} vs {y}");
    }
    scale
}

/// The plate deck with the sphere exactly over the diagonal x = y along which the plate's two
/// triangles meet (no sliding, no spin, so it stays there): the sphere feels the plate as LIGGGHTS
/// makes it (a face contact of one triangle). Before the mesh contact rule was fixed it got no
/// plate contact at all there and was pushed through the plate's plane. Measured difference:
/// below 1e-13 of each quantity's range; 1e-12 leaves room for the summation order only.
#[test]
fn a_sphere_over_the_shared_edge_of_a_plate_matches_liggghts() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/particle_between_plates.in");
    let meshes = repo().join("liggghts_inputs/meshes");
    for (px, py) in [("0.0", "0.0"), ("0.001", "0.001"), ("-0.002", "-0.002")] {
        let vars = [("px", px), ("py", py), ("vx", "0"), ("wy", "0"), ("wz", "0")];
        let (o, t) = run_both(&deck, &[&meshes], &vars);
        println!("sphere at ({px}, {py})");
        let f = "post/plates.dump";
        assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
        // The plate force: the same rows, and not zero.
        let scale = assert_plate_forces_agree(o.path(), t.path());
        assert!(scale > 1e-3, "no plate force in LIGGGHTS ({scale:e} N)");
    }
}

/// The same deck with the sphere sliding and spinning across the diagonal (friction 0.4): its
/// tangential history moves to the second triangle, as LIGGGHTS' coplanar neighbour rule does.
#[test]
fn a_sphere_sliding_across_the_shared_edge_of_a_plate_matches_liggghts() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/particle_between_plates.in");
    let meshes = repo().join("liggghts_inputs/meshes");
    // From x = -0.4 mm on the line y = 0 at 0.15 m/s: the plate touches from step 1100, the sphere
    // crosses x = y = 0 near step 1450 and stays beyond it, sticking and slipping.
    let vars = [("px", "-0.0004"), ("py", "0.0"), ("vx", "0.15"), ("wy", "5"), ("wz", "20")];
    let (o, t) = run_both(&deck, &[&meshes], &vars);
    let f = "post/plates.dump";
    let d = frames::dump(&t.path().join(f));
    let (step, x) = (frames::values(&d, "step"), frames::values(&d, "x"));
    let at = |s: f64| x[step.iter().position(|&v| v == s).unwrap()];
    assert!(
        at(1100.0) < -5e-5 && at(5000.0) > 5e-6,
        "the sphere crossed under the plate: {} -> {}",
        at(1100.0),
        at(5000.0)
    );
    assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
}

/// The die decks of the validation cases (single particle, 9-particle bcc cell; primitive and mesh
/// walls) with stock Hertz. (`mc_advanced` is compared with the plugin in tests/plugin/decks.rs.)
#[test]
fn die_decks_hertz_match_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let dir = repo().join("liggghts_inputs");
    let d = dir.to_str().unwrap();
    for deck in ["single_particle_plates.in", "bcc_box.in"] {
        let vars = [("law", "1"), ("dir", d), ("every", "10"), ("dump", "run.dump"), ("out", "run.txt")];
        let (o, t) = run_both(&dir.join(deck), &[], &vars);
        println!("{deck}");
        assert_dumps_agree(&o.path().join("run.dump"), &t.path().join("run.dump"), 1e-9);
    }
}

/// The bench's dense packing as a deck (`dense_packing.in`): 256 polydisperse spheres (d = 1 mm
/// ± 5 %, ν = 0.4, μ = 0.5) squeezed to φ = 0.8, triply periodic, every sphere with about twelve
/// overlapping neighbours, many across the boundaries, released with random velocities. The data
/// file comes from `mcdem bench --write-packing`, so both engines start from the same bits.
/// Thirty steps: the packing spins up fast (ω to ~50 rad/s), and over longer runs the two
/// summation orders' round-off grows as in any dense packing.
#[test]
fn dense_periodic_packing_matches_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let work = tempfile::tempdir().unwrap();
    let data = work.path().join("packing.data");
    let out = Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .args(["bench", "--write-packing", "4"])
        .arg(&data)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success() && said.starts_with("256 spheres"), "{said}");
    let dt = said.rsplit("-var dt ").next().unwrap().trim().to_string();
    let dir = repo().join("liggghts_inputs");
    let (d, data) = (dir.display().to_string(), data.display().to_string());
    let vars = [("data", data.as_str()), ("dt", &dt), ("steps", "30"), ("dumpevery", "1"), ("dir", &d)];
    let (o, t) = run_both(&dir.join("dense_packing.in"), &[], &vars);
    let f = "dense_packing.dump";
    assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-11);
}

/// Standard multi-contact (LIGGGHTS `surface multicontact`): identical within one run; LIGGGHTS
/// drops the wall multi-contact data at a run boundary, so only the first run is compared tightly.
#[test]
fn particle_between_plates_standard_mc_matches_liggghts_within_a_run() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/particle_between_plates_mc.in");
    let meshes = repo().join("liggghts_inputs/meshes");
    let (o, t) = run_both(&deck, &[&meshes], &[]);
    // The first run's frames only (up to step 3000).
    let f = "post/plates.dump";
    for d in [&o, &t] {
        let text = std::fs::read_to_string(d.path().join(f)).unwrap();
        let cut = text.find("ITEM: TIMESTEP\n3001\n").unwrap_or(text.len());
        std::fs::write(d.path().join("first_run.dump"), &text[..cut]).unwrap();
    }
    assert_dumps_agree(&o.path().join("first_run.dump"), &t.path().join("first_run.dump"), 1e-12);
}

/// NRMSE of the piston force (the third value of the ave/time file) per stroke of `stroke_steps`,
/// both files read with polars and cut into strokes by their `TimeStep` column.
fn nrmse_per_stroke(ours: &Path, theirs: &Path, stroke_steps: u64) -> Vec<f64> {
    let (a, b) = (frames::ave_time(ours), frames::ave_time(theirs));
    let force = b.get_column_names()[3].to_string();
    let last = frames::values(&b, "TimeStep").into_iter().fold(0.0, f64::max) as u64;
    (0..last.div_ceil(stroke_steps))
        .map(|k| {
            let (lo, hi) = ((k * stroke_steps) as f64, ((k + 1) * stroke_steps) as f64);
            let (sa, sb) =
                (frames::rows_between(&a, "TimeStep", lo, hi), frames::rows_between(&b, "TimeStep", lo, hi));
            assert_eq!(frames::values(&sa, "TimeStep"), frames::values(&sb, "TimeStep"), "stroke {k}: steps");
            mcdem::outputs::nrmse(&frames::values(&sa, &force), &frames::values(&sb, &force))
        })
        .collect()
}

/// The hydrogel example with strokes of `ts` steps instead of 30000 (same piston travel), cut
/// after `strokes` strokes; the piston force's NRMSE against LIGGGHTS must stay within `tol` in
/// every stroke.
fn hydrogel(deck: &str, ts: u64, out: &str, strokes: usize, tol: f64) {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(Path::new(HYDROGEL).join(deck)).unwrap();
    let text = text.replace("variable ts_move   equal 30000", &format!("variable ts_move   equal {ts}"));
    let mut cut = String::new();
    let mut runs = 0;
    for l in text.lines() {
        if runs > strokes {
            break;
        }
        if l.starts_with("run") {
            runs += 1;
        }
        cut.push_str(l);
        cut.push('\n');
    }
    let text = cut;
    let path = dir.path().join(deck);
    std::fs::write(&path, text).unwrap();
    copy_dir(&Path::new(HYDROGEL).join("data"), &dir.path().join("data"));
    copy_dir(&Path::new(HYDROGEL).join("meshes"), &dir.path().join("meshes"));
    let (o, t) = run_both(&path, &[&dir.path().join("data"), &dir.path().join("meshes")], &[]);
    let f = format!("post/{out}");
    let e = nrmse_per_stroke(&o.path().join(&f), &t.path().join(&f), ts);
    println!("{deck} ({ts} steps per stroke): NRMSE per stroke {e:?}");
    assert_eq!(e.len(), strokes);
    for (k, v) in e.iter().enumerate() {
        assert!(*v <= tol, "stroke {}: NRMSE {v:e} > {tol:e}", k + 1);
    }
}

#[test]
fn hydrogel_default_short_strokes_piston_force_nrmse() {
    if !have_hydrogel() {
        return;
    }
    // Measured per stroke: 1.7e-6, 2.4e-6, 1.9e-5, 9.0e-5 (round-off of two summation orders grows
    // as the packing rearranges); a lost or doubled mesh contact moves it by 1e-2.
    hydrogel("in.hydrogel_default", 3000, "piston_force_default.txt", 4, 1e-3);
}

/// Standard multi-contact, two fast strokes (about a minute of LIGGGHTS time: its multi-contact
/// path is slow). Later fast strokes are too chaotic for a 3 % bound; the full deck has it.
#[test]
fn hydrogel_multicontact_short_strokes_piston_force_nrmse() {
    if !have_hydrogel() {
        return;
    }
    // Measured 3.8e-3 and 9.1e-3: LIGGGHTS's standard MC drops its wall multi-contact data at
    // each run boundary and keys it by triangle (docs/dem.md), which the engine does not copy.
    hydrogel("in.hydrogel_multicontact", 3000, "piston_force_multicontact.txt", 2, 0.02);
}

#[test]
#[ignore = "full example: about a minute for Hertz with both engines"]
fn hydrogel_default_full_piston_force_nrmse() {
    if !have_hydrogel() {
        return;
    }
    hydrogel("in.hydrogel_default", 30000, "piston_force_default.txt", 4, 1e-3);
}

#[test]
#[ignore = "full example with LIGGGHTS standard multi-contact: about 25 minutes"]
fn hydrogel_multicontact_full_piston_force_nrmse() {
    if !have_hydrogel() {
        return;
    }
    hydrogel("in.hydrogel_multicontact", 30000, "piston_force_multicontact.txt", 4, 0.03);
}

/// `fix adapt ... atom diameter` driven by an atom-style variable reading `compute property/atom
/// radius` (`liggghts_inputs/adapt_growth.in`): four spheres on a wall grow by 0.1 % in diameter
/// every 4 steps for 600 steps (two pairs come into contact through growth alone), then relax for
/// 200 steps after `unfix`. Positions, velocities, forces and spins to 1e-12 of their range (the
/// same bound and reason as the Hertz collision: only the order of force sums differs, measured
/// ≤ 5.6e-14); radius and mass, which both engines compute by the same few operations from the
/// same inputs, to 1e-15 (measured: identical).
#[test]
fn adapt_growth_matches_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/adapt_growth.in");
    let (o, t) = run_both(&deck, &[], &[]);
    let f = "post/adapt_growth.dump";
    assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
    let read = |d: &tempfile::TempDir| {
        let mut fr = mcdem::outputs::read_dump(&d.path().join(f)).unwrap();
        for x in &mut fr {
            x.rows.sort_by(|a, b| a[0].total_cmp(&b[0]));
        }
        fr
    };
    let (a, b) = (read(&o), read(&t));
    assert_eq!(a.len(), 801);
    let cols = [a[0].column("radius").unwrap(), a[0].column("mass").unwrap()];
    let d = frames::frame_difference(&a, &b, &cols);
    assert!(d <= 1e-15, "radius and mass: max relative difference {d:e}");
    // The growth happened: 151 calls (run set-up and every 4th step of 600) of 1.001.
    let r = |fr: &mcdem::outputs::Frame| fr.rows[0][cols[0]];
    let grown = r(&a[800]) / 0.001;
    assert!((grown - 1.001f64.powi(151)).abs() < 1e-12, "radius grew by {grown}");
}

/// `rolling_friction epsd` and `epsd2` (liggghts_inputs/rolling_friction_epsd.in): spheres on a
/// primitive floor with fast spins (the rolling spring at its cap from the start), slow spins (it
/// loads past the cap, unloads and swings back; or stays below it and rocks) and a pair pressed
/// together with opposite spins, 6000 steps. Every quantity every step to 1e-12 of its range
/// (measured ≤ 1.8e-15 for both: the same operations in the same order, the difference is the
/// order of the force sums). The torque changes the run: particle 1's spin at the end is
/// 137.32 rad/s under epsd, 140.81 under epsd2 and 155.53 without rolling friction (checked, so
/// that the comparison cannot pass with the model missing in both engines).
#[test]
fn rolling_friction_epsd_matches_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/rolling_friction_epsd.in");
    let f = "post/rolling_friction.dump";
    for (rf, spin) in [("epsd", 137.32), ("epsd2", 140.81), ("off", 155.53)] {
        let (o, t) = run_both(&deck, &[], &[("rf", rf)]);
        println!("rolling_friction {rf}");
        assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
        let frames = mcdem::outputs::read_dump(&o.path().join(f)).unwrap();
        let row = frames.last().unwrap().rows.iter().find(|r| r[0] as i64 == 1).unwrap().clone();
        assert!((row[10] - spin).abs() < 0.01, "{rf}: particle 1 spins at {} rad/s", row[10]);
    }
}

/// The `epsd` / `epsd2` scene on a `mesh/surface` floor (the 10 mm plate scaled to 40 mm):
/// LIGGGHTS' mesh walls run the same rolling model as its primitive walls, with the same rolling
/// velocity `wr` and lever. Tolerance 1e-12 of the range, as on the primitive floor (measured
/// ≤ 2.1e-14).
#[test]
fn rolling_friction_epsd_on_a_mesh_floor_matches_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let text = std::fs::read_to_string(repo().join("liggghts_inputs/rolling_friction_epsd.in")).unwrap();
    let floor = "fix\t\tfloor all wall/gran model hertz tangential history rolling_friction ${rf} primitive type 1 zplane 0.0";
    assert!(text.contains(floor));
    let mesh = "fix\t\tplate all mesh/surface file meshes/plate_10mm.stl type 1 scale 4\n\
                fix\t\tfloor all wall/gran model hertz tangential history rolling_friction ${rf} mesh n_meshes 1 meshes plate";
    let dir = tempfile::tempdir().unwrap();
    let deck = dir.path().join("rolling_friction_epsd_mesh.in");
    std::fs::write(&deck, text.replace(floor, mesh)).unwrap();
    let meshes = repo().join("liggghts_inputs/meshes");
    for rf in ["epsd", "epsd2"] {
        let (o, t) = run_both(&deck, &[meshes.as_path()], &[("rf", rf)]);
        let f = "post/rolling_friction.dump";
        println!("rolling_friction {rf} on a mesh floor");
        assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
    }
}
