//! Moving and conveying meshes (`fix move/mesh` rotate/riggle/wiggle, `fix mesh/surface …
//! surface_vel`): step by step against stock LIGGGHTS on the small decks `conveyor_belt.in` and
//! `moving_plate.in`, the plate written by `dump mesh/stl` against LIGGGHTS' files, a sphere
//! brought up to a belt's speed against the friction law's prediction, and the errors of bad
//! input.

use std::path::Path;
use std::process::Command;

use crate::against_liggghts::{assert_dumps_agree, have_liggghts, repo, run_both};
use crate::common::frames;

/// Tolerance: a few-sphere run on a mesh differs from LIGGGHTS only by the order of the force
/// sums and of the node arithmetic. Measured: belt and turntable below 5e-14 of each quantity's
/// range; the tilting and rocking plates up to 3.4e-12 (f), because mcdem turns the plate from
/// its start pose by the summed angle while LIGGGHTS turns it step by step (its quaternion's
/// round-off, `engine::mesh_motion`). 1e-11 holds with room; a missing or wrong wall velocity
/// shows at 1e-3 or more.
const TOL: f64 = 1e-11;

#[test]
fn spheres_on_a_conveyor_belt_match_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/conveyor_belt.in");
    let meshes = repo().join("liggghts_inputs/meshes");
    for tilt in ["0", "10"] {
        let (o, t) = run_both(&deck, &[&meshes], &[("tilt", tilt)]);
        println!("tilt {tilt}");
        let f = "post/belt.dump";
        assert_dumps_agree(&o.path().join(f), &t.path().join(f), TOL);
    }
}

#[test]
fn a_sphere_on_a_moving_plate_matches_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/moving_plate.in");
    let meshes = repo().join("liggghts_inputs/meshes");
    let cases: [&[(&str, &str)]; 4] = [
        // A turntable: the plate drags the sphere round (friction), ω × r in the tangential force.
        &[("form", "1")],
        // Tilting about y under a sphere at x < 0: the plate lifts it (ω × r along the normal).
        &[("form", "1"), ("ax", "0"), ("ay", "1"), ("az", "0"), ("period", "0.4"), ("px", "-0.003")],
        // Rocking ±20° about x, 125 rad/s: the sphere stays on the plate, sliding and rolling.
        &[("form", "2"), ("ax", "1"), ("ay", "0"), ("az", "0"), ("period", "0.05")],
        // Shaking at 3 g: the sphere bounces on the plate.
        &[("form", "3"), ("period", "0.02")],
    ];
    for vars in cases {
        let (o, t) = run_both(&deck, &[&meshes], vars);
        println!("{vars:?}");
        let f = "post/plate.dump";
        assert_dumps_agree(&o.path().join(f), &t.path().join(f), TOL);
        for step in ["0", "1000", "2000", "3000", "4000"] {
            let f = format!("post/plate_{step}.stl");
            stl_files_agree(&o.path().join(&f), &t.path().join(&f));
        }
    }
}

/// Two `dump mesh/stl` files: the same lines, every number equal to LIGGGHTS' printing
/// precision (`%g`, 6 digits: 1e-5 relative, and 1e-9 m absolute for coordinates that are
/// round-off around zero).
fn stl_files_agree(ours: &Path, theirs: &Path) {
    let read = |p: &Path| std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let (a, b) = (read(ours), read(theirs));
    let (la, lb): (Vec<&str>, Vec<&str>) = (a.lines().collect(), b.lines().collect());
    assert_eq!(la.len(), lb.len(), "{}", theirs.display());
    assert!(lb.len() > 10, "{}: no triangles", theirs.display());
    for (x, y) in la.iter().zip(&lb) {
        let (wx, wy): (Vec<&str>, Vec<&str>) =
            (x.split_whitespace().collect(), y.split_whitespace().collect());
        assert_eq!(wx.len(), wy.len(), "{x} vs {y}");
        for (p, q) in wx.iter().zip(&wy) {
            match (p.parse::<f64>(), q.parse::<f64>()) {
                (Ok(u), Ok(v)) => assert!((u - v).abs() <= 1e-5 * v.abs() + 1e-9, "{x} vs {y}"),
                _ => assert_eq!(p, q, "{x} vs {y}"),
            }
        }
    }
}

/// Runs mcdem on `deck` (a file of liggghts_inputs/) in a fresh directory with the meshes, after
/// replacing the line starting with `line` by `by` (when given); returns (success, output, dir).
fn run_ours(
    deck: &str,
    vars: &[(&str, &str)],
    edit: Option<(&str, &str)>,
) -> (bool, String, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("post")).unwrap();
    std::fs::create_dir_all(dir.path().join("meshes")).unwrap();
    let meshes = repo().join("liggghts_inputs/meshes");
    for e in std::fs::read_dir(&meshes).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), dir.path().join("meshes").join(e.file_name())).unwrap();
    }
    let mut text = std::fs::read_to_string(repo().join("liggghts_inputs").join(deck)).unwrap();
    if let Some((line, by)) = edit {
        let start = text.find(line).unwrap_or_else(|| panic!("no line {line}"));
        let end = start + text[start..].find('\n').unwrap();
        text.replace_range(start..end, by);
    }
    let path = dir.path().join(deck);
    std::fs::write(&path, text).unwrap();
    let mut c = Command::new(env!("CARGO_BIN_EXE_mcdem"));
    c.current_dir(dir.path()).arg("run").arg(&path).args(["-log", "none"]);
    for (k, v) in vars {
        c.arg("-var").arg(k).arg(v);
    }
    let o = c.output().unwrap();
    let all = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    (o.status.success(), all, dir)
}

/// A solid sphere set down at rest on a belt moving at u (friction μ): while it slips, friction
/// μ m g accelerates its centre (v = μ g t) and spins it backwards (I = 2/5 m R², so
/// dω/dt = 5 μ g / (2 R)); the contact point's slip u − v − R|ω| closes at 7/2 μ g, so slipping
/// ends at t* = 2 u / (7 μ g) and the sphere then rolls without slip at v = 2/7 u (the no-slip
/// condition with the angular momentum about the contact point conserved from then on).
/// Here u = 0.05 m/s, μ = 0.4: t* = 3.64 ms (1820 steps), v = 0.01429 m/s. Tolerances: the
/// sphere is set down just touching, so its normal force builds up over the first ~200 steps
/// and rings a little (the friction lags the ideal μ m g at first), and the elastic tangential
/// spring lets the contact creep around t*: bounds 5 % on t* and 1 % on the final speed
/// (measured: slipping ends at 3.626 ms, 0.4 % early; final speed 0.07 % above 2/7 u).
#[test]
fn a_sphere_on_a_belt_reaches_two_sevenths_of_its_speed_when_friction_says() {
    let (ok, out, dir) = run_ours("conveyor_belt.in", &[("steps", "6000")], None);
    assert!(ok, "{out}");
    let d = frames::dump(&dir.path().join("post/belt.dump"));
    let (id, step) = (frames::values(&d, "id"), frames::values(&d, "step"));
    let (vx, wy) = (frames::values(&d, "vx"), frames::values(&d, "omegay"));
    let (u, mu, g, r, dt) = (0.05, 0.4, 9.81, 0.001, 2e-6);
    let rows: Vec<usize> = (0..id.len()).filter(|&k| id[k] == 1.0).collect();
    // Slip of the contact point against the belt: the bottom point moves at v + ω × (−R ẑ),
    // whose x part is v − R ω_y (friction along +x spins the sphere to ω_y < 0).
    let slip = |k: usize| u - (vx[k] - r * wy[k]);
    let t_star = 2.0 * u / (7.0 * mu * g);
    let end = rows.iter().find(|&&k| slip(k) < 0.01 * u).map(|&k| step[k] * dt).expect("never rolls");
    println!("slipping ends at {end:e} s, predicted {t_star:e} s");
    assert!((end - t_star).abs() < 0.05 * t_star, "slipping ends at {end} s, predicted {t_star} s");
    let at = |s: f64| rows.iter().copied().find(|&k| step[k] == s).unwrap();
    let v_end = 2.0 / 7.0 * u;
    let last = at(6000.0);
    println!("v = {:e}, 2/7 u = {v_end:e}", vx[last]);
    assert!((vx[last] - v_end).abs() < 0.01 * v_end, "v = {} vs 2/7 u = {v_end}", vx[last]);
}

/// Bad `move/mesh` and `surface_vel` input stops with the deck's file and line and the problem.
#[test]
fn bad_moving_mesh_input_is_named() {
    let cases = [
        ("if \"${form} == 1\"", "fix mv all move/mesh mesh plate spin 1 2 3", "unsupported fix move/mesh form spin"),
        (
            "if \"${form} == 1\"",
            "fix mv all move/mesh mesh plate rotate origin 0 0 0 axis 0 0 0 period 1",
            "fix move/mesh rotate: the axis must not be zero",
        ),
        (
            "if \"${form} == 1\"",
            "fix mv all move/mesh mesh plate rotate origin 0 0 0 axis 0 0 1 period 0",
            "fix move/mesh rotate: period must be > 0, got 0",
        ),
        (
            "if \"${form} == 1\"",
            "fix mv all move/mesh mesh plate rotate origin 0 0 0 axes 0 0 1 period 1",
            "fix move/mesh rotate: expected 'axis' at \"axes\"",
        ),
        (
            "if \"${form} == 1\"",
            "fix mv all move/mesh mesh plate riggle origin 0 0 0 axis 0 0 1 period 1",
            "fix move/mesh riggle: expected",
        ),
        (
            "fix\t\tplate all mesh/surface",
            "fix plate all mesh/surface file meshes/plate_10mm.stl type 2 surface_ang_vel origin 0 0 0 axis 0 0 1 omega 1",
            "unsupported fix mesh/surface keyword surface_ang_vel",
        ),
        (
            "fix\t\tplate all mesh/surface",
            "fix plate all mesh/surface file meshes/plate_10mm.stl type 2 surface_vel 1 0",
            "mesh surface_vel: 3 values",
        ),
        (
            "fix\t\tplate all mesh/surface",
            "fix plate all mesh/surface file meshes/plate_10mm.stl type 2 surface_vel 1 0 0",
            "fix move/mesh: mesh plate has a surface_vel; LIGGGHTS refuses to move such a mesh",
        ),
    ];
    for (line, by, want) in cases {
        let (ok, out, _dir) = run_ours("moving_plate.in", &[], Some((line, by)));
        assert!(!ok, "{by}: ran");
        assert!(
            out.contains("ERROR: ") && out.contains("moving_plate.in:") && out.contains(want),
            "{by}: {out}"
        );
    }
}
