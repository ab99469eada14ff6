//! Moving and conveying meshes (`fix move/mesh` rotate/riggle/wiggle, `fix mesh/surface …
//! surface_vel`): step by step against stock LIGGGHTS on the small decks `conveyor_belt.in` and
//! `moving_plate.in`, the plate written by `dump mesh/stl` against LIGGGHTS' files, a sphere
//! brought up to a belt's speed against the friction law's prediction, and the errors of bad
//! input.

use std::path::Path;

use crate::against_liggghts::{assert_dumps_agree, have_liggghts, repo, run_both};

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
