//! Contact Dynamics between MPM bodies (Nezamabadi et al. 2019, Section 2.2): momentum exchange at
//! common-lattice nodes, and scene validation.

use mcdem::mpm::contact::{step_bodies, ContactWorkspace};
use mcdem::mpm::scene::Scene;

fn two_discs(extra: &str) -> String {
    format!(
        r#"{{"dimension": 2, "material": {{"law": "neohookean", "lambda": 3e6, "mu": 1.5e6, "density": 990}},
            "bodies": [
              {{"shape": "disc", "center": [-0.00425, 0.0], "radius": 0.004, "velocity": [1.0, 0.0]}},
              {{"shape": "disc", "center": [0.00425, 0.0], "radius": 0.004, "velocity": [-1.0, 0.0]}}],
            "grid": {{"h": 1e-3, "points_per_cell": 2}}, {extra} "dt": 1e-5, "steps": 30}}"#
    )
}

/// Two equal Neo-Hookean discs (R = 4 mm, h = 1 mm, Δt = 10 µs, c_p Δt = 0.78 mm < h) approaching
/// at ±1 m/s: over the first 30 steps of the contact the nodal forces are equal and opposite, so
/// the total momentum stays zero to round-off (1e-12 of one disc's momentum: Newton residuals at
/// convergence are ~1e-9 of the force scale, times Δt, well below), the contact pushes (normal
/// force > 0) and it slows the approach.
#[test]
fn head_on_contact_conserves_momentum_and_slows_the_approach() {
    let mut s = Scene::from_json(&two_discs("")).unwrap().setup::<2>().unwrap();
    let p_ref = s.bodies[0].points.momentum().norm();
    let mut ws = ContactWorkspace::default();
    let mut pushed = 0;
    for k in 0..30 {
        let r = step_bodies(&mut s.bodies, &[], &s.options, &s.contact, k, &mut ws).unwrap();
        if r.contact_normal_force > 0.0 {
            pushed += 1;
        }
        let p = s.bodies[0].points.momentum() + s.bodies[1].points.momentum();
        assert!(p.norm() < 1e-12 * p_ref, "step {k}: total momentum {p:?} against {p_ref}");
    }
    assert!(pushed > 20, "the contact pushed in only {pushed} of 30 steps");
    let v = |b: usize| s.bodies[b].points.momentum()[0] / s.bodies[b].points.mass.iter().sum::<f64>();
    // Approach speed 2 m/s at start; after 0.3 ms of contact it must have dropped.
    let approach = v(0) - v(1);
    assert!(approach < 1.5, "approach speed {approach} m/s after 30 steps (2 m/s at start)");
}

/// Runs the head-on collision until the discs have separated for 5 steps; returns the
/// coefficient of restitution (separation over approach speed of the centres of mass), the steps in
/// contact, the largest rise of the total energy between steps (relative to the initial kinetic
/// energy) and the energy lost, and the largest momentum drift.
fn collide(dt: f64, h: f64) -> (f64, usize, f64, f64, f64, usize) {
    let text = two_discs("")
        .replace("\"dt\": 1e-5", &format!("\"dt\": {dt:e}"))
        .replace("\"h\": 1e-3", &format!("\"h\": {h:e}"));
    let mut s = Scene::from_json(&text).unwrap().setup::<2>().unwrap();
    let mut ws = ContactWorkspace::default();
    let v = |s: &mcdem::mpm::scene::Setup<2>, b: usize| {
        s.bodies[b].points.momentum()[0] / s.bodies[b].points.mass.iter().sum::<f64>()
    };
    let energy = |s: &mcdem::mpm::scene::Setup<2>| s.bodies.iter().map(|b| b.energy().unwrap()).sum::<f64>();
    let approach = v(&s, 0) - v(&s, 1);
    let e0 = energy(&s);
    let p_ref = s.bodies[0].points.momentum().norm();
    let (mut in_contact, mut open_after, mut touched, mut rise, mut e_prev, mut drift) =
        (0, 0, false, 0.0f64, e0, 0.0f64);
    let mut sliver = 0;
    for k in 0..(2e-3 / dt) as usize {
        let r = step_bodies(&mut s.bodies, &[], &s.options, &s.contact, k, &mut ws).unwrap();
        sliver += r.sliver_sides;
        let e = energy(&s);
        rise = rise.max((e - e_prev) / e0);
        e_prev = e;
        let p = s.bodies[0].points.momentum() + s.bodies[1].points.momentum();
        drift = drift.max(p.norm() / p_ref);
        if r.contact_normal_force > 0.0 {
            in_contact += 1;
            touched = true;
            open_after = 0;
        } else if touched {
            open_after += 1;
            if open_after == 5 {
                break;
            }
        }
    }
    assert_eq!(open_after, 5, "the discs did not separate within 2 ms");
    ((v(&s, 1) - v(&s, 0)) / approach, in_contact, rise, (e0 - e_prev) / e0, drift, sliver)
}

/// The whole collision to separation (Neo-Hookean discs R = 4 mm, 2 m/s approach). Measured at
/// h = 1 mm: restitution 0.7912, 0.8499, 0.8796 at Δt = 10, 5, 2.5 µs (1 − e falls by 0.0587 then
/// 0.0297: first order in Δt, the backward-Euler loss, towards ≈ 0.91, the loss of the nodes'
/// perfectly inelastic impact at this h), 0.8778 at h = 0.5 mm, Δt = 5 µs; contact 350 µs at every
/// Δt (360 µs at h/2); the total energy never rises between steps (largest rise exactly 0) and the
/// momentum stays zero to 2e-15. Asserted: separation, no energy rise beyond round-off (1e-12),
/// momentum to 1e-12 (as above), first order of the loss in Δt (ratio in [1.6, 2.4], as for the free
/// body in tests/mpm/closed_forms.rs), restitution rising under both refinements, and the contact duration
/// converged in Δt (within two steps of the coarsest run).
#[test]
fn head_on_discs_separate_after_the_collision() {
    let runs: Vec<_> = [(1e-5, 1e-3), (5e-6, 1e-3), (2.5e-6, 1e-3), (5e-6, 5e-4)]
        .iter()
        .map(|&(dt, h)| {
            let (e, n, rise, loss, drift, sliver) = collide(dt, h);
            eprintln!(
                "Δt {dt:e} s, h {h:e} m: restitution {e:.6}, contact {:.1} µs, energy lost {loss:.4}, largest rise {rise:.2e}, momentum drift {drift:.2e}, sliver contact sides {sliver}",
                n as f64 * dt * 1e6
            );
            assert!(rise < 1e-12 && drift < 1e-12, "Δt {dt:e}, h {h:e}: energy rise {rise:.2e}, momentum drift {drift:.2e}");
            (e, n as f64 * dt)
        })
        .collect();
    let ratio = (runs[1].0 - runs[0].0) / (runs[2].0 - runs[1].0);
    assert!((1.6..2.4).contains(&ratio), "restitution gain ratio {ratio} not first order in Δt");
    assert!(runs[0].0 > 0.5 && runs[0].0 < runs[1].0 && runs[1].0 < runs[2].0 && runs[2].0 < 1.0, "{runs:?}");
    assert!(runs[3].0 > runs[1].0, "restitution must rise with h refinement: {runs:?}");
    for r in &runs[1..3] {
        assert!((r.1 - runs[0].1).abs() <= 2e-5, "contact duration {} s against {} s", r.1, runs[0].1);
    }
}

/// Bad scenes stop with a message naming the problem.
#[test]
fn bad_contact_scenes_name_their_problem() {
    let err = |text: String| Scene::from_json(&text).and_then(|s| s.setup::<2>().map(|_| ())).unwrap_err();
    let e = err(two_discs(r#""contact": {"wall_friction": -0.3},"#));
    assert!(e.contains("wall_friction") && e.contains("≥ 0"), "{e}");
    let e = err(two_discs(r#""contact": {"body_friction": -1},"#));
    assert!(e.contains("body_friction"), "{e}");
    let e = err(two_discs("").replace("[0.00425, 0.0]", "[0.002, 0.0]"));
    assert!(e.contains("overlap at start") && e.contains("bodies"), "{e}");
    let e = err(two_discs("").replace(
        "\"bodies\"",
        "\"body\": {\"shape\": \"disc\", \"center\": [0, 0], \"radius\": 1}, \"bodies\"",
    ));
    assert!(e.contains("not both"), "{e}");
    assert!(Scene::from_json(&two_discs("")).unwrap().setup::<2>().is_ok());
}

/// The disc between plates (scene 1, h = 1 mm, Δt = 100 µs, 10 steps to d = 0.25 mm): the contact
/// driver with μ = 0 gives the plate loads of the frictionless one-body step bit for bit (no
/// friction force is ever set, one contact iteration per step).
#[test]
fn plates_with_zero_friction_reproduce_the_frictionless_step() {
    use mcdem::mpm::implicit::{step, Workspace};
    let scene = |mu: f64| {
        format!(
            r#"{{"dimension": 2, "material": {{"law": "hooke", "lambda": 100e6, "mu": 1.5e6, "density": 990}},
                "body": {{"shape": "disc", "center": [0.0, 0.01], "radius": 0.01}},
                "grid": {{"h": 1e-3, "points_per_cell": 2}},
                "walls": [{{"axis": 1, "side": 1, "position": 0.0}}, {{"axis": 1, "side": -1, "position": 0.02, "velocity": -0.5}}],
                "contact": {{"wall_friction": {mu}}}, "dt": 1e-4, "steps": 10}}"#
        )
    };
    let run = |mu: f64, driver: bool| {
        let mut s = Scene::from_json(&scene(mu)).unwrap().setup::<2>().unwrap();
        let (mut ws, mut cws) = (Workspace::default(), ContactWorkspace::default());
        let mut loads = Vec::new();
        for k in 0..10 {
            let l = if driver {
                step_bodies(&mut s.bodies, &s.walls, &s.options, &s.contact, k, &mut cws).unwrap().wall_load
            } else {
                step(&mut s.bodies[0], &s.walls, &[], &s.options, k, &mut ws).unwrap().wall_load
            };
            loads.push(l[1]);
            for w in s.walls.iter_mut() {
                w.position += w.velocity * s.options.dt;
            }
        }
        loads
    };
    let plain = run(0.0, false);
    assert_eq!(run(0.0, true), plain);
    assert!(plain[9] > 0.0, "the top plate must load the disc: {plain:?}");
    // With μ = 0.5 the symmetric disc still loads symmetrically: the friction of each plate sums
    // to zero over its nodes (x → −x), to the contact tolerance (1e-7 h per step) times the
    // stiffness, i.e. below 1e-6 of the load; sticking contacts stiffen the disc (the plate load is
    // not below the frictionless one).
    let mut s = Scene::from_json(&scene(0.5)).unwrap().setup::<2>().unwrap();
    let mut cws = ContactWorkspace::default();
    for (k, &plain_load) in plain.iter().enumerate() {
        let r = step_bodies(&mut s.bodies, &s.walls, &s.options, &s.contact, k, &mut cws).unwrap();
        for w in 0..2 {
            assert!(r.wall_friction[w][0].abs() < 1e-6 * r.wall_load[w].abs().max(1e-3), "step {k}: {r:?}");
        }
        assert!(r.wall_load[1] >= plain_load * (1.0 - 1e-9), "step {k}: {} < {plain_load}", r.wall_load[1]);
        for w in s.walls.iter_mut() {
            w.position += w.velocity * s.options.dt;
        }
    }
}

/// A block on a frictional floor under tilted gravity (an incline of angle θ): Coulomb's threshold
/// tan θ = μ separates sticking (the centre of mass stays at rest but for the elastic settling) from
/// sliding at the acceleration g (sin θ − μ cos θ) of a rigid block.
fn incline(tan_theta: f64, mu: f64) -> (f64, f64) {
    let g = 9.81;
    let (sin, cos) =
        (tan_theta / (1.0 + tan_theta * tan_theta).sqrt(), 1.0 / (1.0 + tan_theta * tan_theta).sqrt());
    let text = format!(
        r#"{{"dimension": 2, "material": {{"law": "neohookean", "lambda": 2e6, "mu": 1e6, "density": 1000}},
            "body": {{"shape": "block", "lo": [0.0, 0.0], "hi": [0.004, 0.002]}},
            "grid": {{"h": 5e-4, "points_per_cell": 2, "margin": 4}},
            "walls": [{{"axis": 1, "side": 1, "position": 0.0}}],
            "gravity": [{gx}, {gy}],
            "contact": {{"wall_friction": {mu}}}, "dt": 5e-4, "steps": 40}}"#,
        gx = g * sin,
        gy = -g * cos
    );
    let mut s = Scene::from_json(&text).unwrap().setup::<2>().unwrap();
    let mut cws = ContactWorkspace::default();
    let v = |s: &mcdem::mpm::scene::Setup<2>| {
        s.bodies[0].points.momentum()[0] / s.bodies[0].points.mass.iter().sum::<f64>()
    };
    let (mut v10, mut v40) = (0.0, 0.0);
    for k in 0..40 {
        let r = step_bodies(&mut s.bodies, &s.walls, &s.options, &s.contact, k, &mut cws).unwrap();
        // Sliding (from the first step on): the friction is μ times the normal load (the reported
        // sums), opposing the slip. Sticking: the friction balances g sin θ (checked through `a`).
        if tan_theta > mu {
            let ratio = -r.wall_friction[0][0] / r.wall_load[0];
            assert!((ratio - mu).abs() < 1e-6, "step {k}: friction/load {ratio} while sliding (μ = {mu})");
        }
        if k == 9 {
            v10 = v(&s);
        }
        v40 = v(&s);
    }
    // Mean tangential acceleration over steps 10–40 (15 ms), and the rigid-block prediction.
    ((v40 - v10) / (30.0 * 5e-4), g * (sin - mu * cos).max(0.0))
}

/// Coulomb stick/slip threshold of the wall friction (μ = 0.5, threshold tan θ = 0.5): at
/// tan θ = 0.4 and 0.45 the block sticks, at 0.55, 0.8 and 1 it slides at the rigid-block
/// acceleration, and with μ = 0 it slides at g sin θ. Measured: the sliding accelerations match
/// g (sin θ − μ cos θ) to 1e-6 relative (the friction is μ times the wall reaction at every sliding
/// node and the reaction sums to m g cos θ once the elastic settling, of order ρ g H²/E = 1e-11 m,
/// has decayed); the sticking ones are 3e-10 and 1.1e-8 m/s² (the elastic creep of the first
/// steps decaying), asserted below 1e-6 m/s². Tolerance 1e-4 g: the settling transient
/// and the contact tolerance (1e-7 h per step) are orders below it, a wrong friction law (μ times
/// the wrong normal force, or friction on nodes that left the wall) is orders above it.
#[test]
fn block_on_an_incline_sticks_below_and_slides_above_the_coulomb_angle() {
    for (tan, mu) in [(0.4, 0.5), (0.45, 0.5), (0.55, 0.5), (0.8, 0.5), (1.0, 0.5), (0.6, 0.0)] {
        let (a, pred) = incline(tan, mu);
        eprintln!("tan θ = {tan}, μ = {mu}: mean acceleration {a:.6e} m/s², rigid block {pred:.6e} m/s²");
        assert!((a - pred).abs() < 1e-4 * 9.81, "tan θ = {tan}, μ = {mu}: {a} m/s² against {pred} m/s²");
        if tan < mu {
            assert!(a.abs() < 1e-6, "tan θ = {tan} below μ = {mu} must stick: {a} m/s²");
        }
    }
}

/// Reads legacy VTK files with VTK's own Python reader (an independent reader, as in
/// tests/cli/compare_vtk.rs) and returns, per file, its points, cell count and point/cell arrays.
fn read_vtk(files: &[std::path::PathBuf]) -> Vec<serde_json::Value> {
    let script = r#"
import json, sys, vtk
from vtk.util.numpy_support import vtk_to_numpy
out = []
for f in sys.argv[1:]:
    r = vtk.vtkPolyDataReader()
    r.SetFileName(f)
    r.ReadAllFieldsOn()
    r.Update()
    if r.GetErrorCode() != 0:
        sys.exit("read error %d in %s" % (r.GetErrorCode(), f))
    d = r.GetOutput()
    def arrays(a):
        return {a.GetArrayName(k): vtk_to_numpy(a.GetArray(k)).tolist() for k in range(a.GetNumberOfArrays())}
    out.append({
        "points": vtk_to_numpy(d.GetPoints().GetData()).tolist() if d.GetPoints() else [],
        "cells": d.GetNumberOfCells(),
        "point_data": arrays(d.GetPointData()),
        "cell_data": arrays(d.GetCellData()),
    })
print(json.dumps(out))
"#;
    let o = std::process::Command::new("python3")
        .arg("-c")
        .arg(script)
        .args(files)
        .output()
        .expect("python3 starts");
    assert!(
        o.status.success(),
        "python vtk could not read the snapshots: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).unwrap()
}

/// A named point array of a snapshot read by [`read_vtk`], as numbers.
fn point_array(snapshot: &serde_json::Value, name: &str) -> Vec<f64> {
    let pd = &snapshot["point_data"];
    pd[name]
        .as_array()
        .unwrap_or_else(|| panic!("array {name} missing: {pd}"))
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// The rows of a run's `points.csv` (body,x,y,z,J,sigma_xx,sigma_yy,sigma_xy,volume), as numbers.
fn points_csv_rows(csv: &str) -> Vec<Vec<f64>> {
    csv.lines().skip(1).map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect()).collect()
}

/// `mcdem mpm --vtk-every 10` on the head-on discs between a fixed and a descending plate (25
/// steps): snapshots at steps 0, 10, 20 and 25, listed with their times t = step·Δt in the
/// ParaView series files; read back by VTK's reader, the last one has every material point of
/// points.csv with its body, J, volume and σ_xx to the printed digits, the walls sit where they
/// moved to, and the material has deformed between the first and the last snapshot. Without the
/// option no snapshot is written; `--vtk-every 0` is refused with a message naming it.
#[test]
fn vtk_snapshots_read_back_by_python_vtk_match_points_csv() {
    let d = tempfile::tempdir().unwrap();
    let walls = r#""walls": [{"axis": 1, "side": 1, "position": -0.0045},
                             {"axis": 1, "side": -1, "position": 0.0045, "velocity": -0.5}],"#;
    let scene = d.path().join("discs.json");
    std::fs::write(&scene, two_discs(walls).replace("\"steps\": 30", "\"steps\": 25")).unwrap();
    let mpm = |out: &str, extra: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_mcdem"))
            .current_dir(d.path())
            .args(["mpm", "discs.json", "--out", out])
            .args(extra)
            .output()
            .expect("mcdem starts")
    };
    let o = mpm("out", &["--vtk-every", "10"]);
    assert!(o.status.success(), "mcdem mpm failed: {}", String::from_utf8_lossy(&o.stderr));
    let vtk = d.path().join("out/vtk");

    // The series files: every snapshot, in order, with increasing real times.
    let steps = [0usize, 10, 20, 25];
    for part in ["points", "walls"] {
        let text = std::fs::read_to_string(vtk.join(format!("{part}.vtk.series"))).unwrap();
        let series: serde_json::Value = serde_json::from_str(&text).expect("series file is JSON");
        assert_eq!(series["file-series-version"], "1.0");
        let files = series["files"].as_array().unwrap();
        let names: Vec<&str> = files.iter().map(|f| f["name"].as_str().unwrap()).collect();
        let want: Vec<String> = steps.iter().map(|s| format!("{part}_{s}.vtk")).collect();
        assert_eq!(names, want, "{part}.vtk.series");
        for (f, s) in files.iter().zip(steps) {
            let t = f["time"].as_f64().unwrap();
            assert!((t - s as f64 * 1e-5).abs() < 1e-15, "{part} step {s}: time {t}");
            assert!(vtk.join(f["name"].as_str().unwrap()).is_file());
        }
    }
    let mut entries: Vec<String> =
        std::fs::read_dir(&vtk).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    entries.sort();
    assert_eq!(entries.len(), 2 * steps.len() + 2, "only the requested steps are written: {entries:?}");

    // points.csv: body,x,y,z,J,sigma_xx,sigma_yy,sigma_xy,volume.
    let csv = std::fs::read_to_string(d.path().join("out/points.csv")).unwrap();
    assert_eq!(csv.lines().next().unwrap(), "body,x,y,z,J,sigma_xx,sigma_yy,sigma_xy,volume");
    let rows = points_csv_rows(&csv);
    assert!(rows.len() > 100, "{} points", rows.len());

    let files: Vec<_> = ["points_0.vtk", "points_25.vtk", "walls_0.vtk", "walls_25.vtk"]
        .iter()
        .map(|f| vtk.join(f))
        .collect();
    let v = read_vtk(&files);
    let (first, last, walls0, walls) = (&v[0], &v[1], &v[2], &v[3]);
    let pts = last["points"].as_array().unwrap();
    assert_eq!(pts.len(), rows.len(), "point count");
    assert_eq!(last["cells"].as_u64().unwrap() as usize, rows.len(), "one vertex per point");
    let pd = &last["point_data"];
    let col = |name: &str| point_array(last, name);
    // points.csv prints 10 significant digits, the VTK file 11: equal to 1e-9 relative.
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-30);
    let (body, j, vol, sxx, sxy) = (col("body"), col("J"), col("volume"), col("sigma_xx"), col("sigma_xy"));
    let vel = pd["velocity"].as_array().expect("vector array velocity");
    let mut bodies_seen = [0usize; 2];
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(body[k], r[0], "body of point {k}");
        bodies_seen[r[0] as usize] += 1;
        assert!(close(j[k], r[4]), "J of point {k}: {} vs {}", j[k], r[4]);
        assert!(close(vol[k], r[8]), "volume of point {k}: {} vs {}", vol[k], r[8]);
        assert!(close(sxx[k], r[5]), "sigma_xx of point {k}: {} vs {}", sxx[k], r[5]);
        assert!(close(sxy[k], r[7]), "sigma_xy of point {k}: {} vs {}", sxy[k], r[7]);
        // Positions are VTK floats (six digits); z = 0 in 2-D.
        for a in 0..2 {
            let p = pts[k][a].as_f64().unwrap();
            assert!((p - r[1 + a]).abs() <= 5e-6 * r[1 + a].abs(), "point {k} axis {a}: {p} vs {}", r[1 + a]);
        }
        assert_eq!(pts[k][2].as_f64().unwrap(), 0.0);
        assert_eq!(vel[k].as_array().unwrap().len(), 3);
        assert_eq!(vel[k][2].as_f64().unwrap(), 0.0);
    }
    assert!(bodies_seen[0] > 0 && bodies_seen[0] == bodies_seen[1], "points per body {bodies_seen:?}");
    for name in ["gamma_eq", "sigma_yy"] {
        assert_eq!(col(name).len(), rows.len(), "{name}");
    }
    // The discs have been compressed by the collision: J and γ_eq moved away from their values at
    // step 0 (J = 1, γ_eq = 0 everywhere), and the left disc moved right.
    let j0 = point_array(first, "J");
    assert!(j0.iter().all(|&x| x == 1.0), "J at step 0");
    assert!(j.iter().any(|&x| (x - 1.0).abs() > 1e-4), "J unchanged after the collision");
    assert!(col("gamma_eq").iter().any(|&g| g > 1e-4), "no strain after the collision");
    let v0 = first["point_data"]["velocity"][0][0].as_f64().unwrap();
    assert!((v0 - 1.0).abs() < 1e-12, "left disc's speed at start {v0}");
    // Walls: two segments; the top plate has moved by −0.5 m/s × 25 × 10 µs.
    for (w, y_top) in [(walls0, 0.0045), (walls, 0.0045 - 0.5 * 25.0 * 1e-5)] {
        assert_eq!(w["cells"].as_u64(), Some(2));
        let p = w["points"].as_array().unwrap();
        assert_eq!(p.len(), 4);
        let y = |k: usize| p[k][1].as_f64().unwrap();
        assert!((y(0) + 0.0045).abs() < 1e-9 && (y(1) + 0.0045).abs() < 1e-9, "bottom wall {p:?}");
        assert!((y(2) - y_top).abs() < 1e-8 && (y(3) - y_top).abs() < 1e-8, "top wall {p:?}, want {y_top}");
        assert_eq!(w["cell_data"]["wall"], serde_json::json!([0, 1]));
        assert_eq!(w["cell_data"]["velocity"][1], serde_json::json!([0.0, -0.5, 0.0]));
    }

    // Off by default; a zero interval is refused by name.
    let o = mpm("plain", &[]);
    assert!(o.status.success());
    assert!(!d.path().join("plain/vtk").exists(), "snapshots written without --vtk-every");
    let o = mpm("zero", &["--vtk-every", "0"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("--vtk-every must be at least 1") && !e.contains("panicked"), "{e}");
}

/// A step that does not converge is taken again in halves (`step_bodies_cut`): the disc between
/// plates with Newton capped at `max_iter` iterations, where the full step's increment needs more
/// than the cap and half a step's fewer.
fn plates_with_newton_cap(max_iter: usize, dt: f64, steps: usize) -> String {
    format!(
        r#"{{"dimension": 2, "material": {{"law": "neohookean", "lambda": 3e6, "mu": 1.5e6, "density": 990}},
            "body": {{"shape": "disc", "center": [0.0, 0.01], "radius": 0.01}},
            "grid": {{"h": 1e-3, "points_per_cell": 2}},
            "walls": [{{"axis": 1, "side": 1, "position": 0.0}}, {{"axis": 1, "side": -1, "position": 0.0199, "velocity": -2.0}}],
            "newton": {{"eps1": 1e-8, "eps2": 1e-8, "max_iter": {max_iter}}},
            "dt": {dt:e}, "steps": {steps}}}"#
    )
}

/// Runs the capped plates scene for `steps` steps of Δt with at most `cuts` halvings; returns the
/// top plate's load after each step, the sub-steps of each step and the final points and walls.
/// Top plate load per step, sub-steps per step, final point coordinates, final top wall position.
type CutRun = (Vec<f64>, Vec<usize>, Vec<f64>, f64);

fn run_cut(cap: usize, dt: f64, steps: usize, cuts: u32) -> Result<CutRun, String> {
    use mcdem::mpm::contact::step_bodies_cut;
    let mut s = Scene::from_json(&plates_with_newton_cap(cap, dt, steps)).unwrap().setup::<2>().unwrap();
    let mut cws = ContactWorkspace::default();
    let (mut loads, mut subs) = (Vec::new(), Vec::new());
    for k in 0..steps {
        let (r, n) = step_bodies_cut(&mut s.bodies, &mut s.walls, &s.options, &s.contact, k, &mut cws, cuts)?;
        loads.push(r.wall_load[1]);
        subs.push(n);
    }
    let xs = s.bodies[0].points.x.iter().flat_map(|x| [x[0], x[1]]).collect();
    Ok((loads, subs, xs, s.walls[1].position))
}

/// The cut step written out independently: each attempt on a copy of the bodies (kept only if it
/// converges), halves by recursion, walls moved to where an uncut step puts them.
fn replay<const D: usize>(
    bodies: &mut Vec<mcdem::mpm::implicit::Body<D>>,
    walls: &mut [mcdem::mpm::implicit::Wall],
    opt: &mcdem::mpm::implicit::StepOptions,
    copt: &mcdem::mpm::contact::ContactOptions,
    k: usize,
    cuts: u32,
) -> f64 {
    let mut trial = bodies.clone();
    let mut cws = ContactWorkspace::default();
    match step_bodies(&mut trial, walls, opt, copt, k, &mut cws) {
        Ok(r) => {
            *bodies = trial;
            for w in walls.iter_mut() {
                w.position += w.velocity * opt.dt;
            }
            r.wall_load[1]
        }
        Err(e) => {
            assert!(cuts > 0, "{e}");
            let start: Vec<f64> = walls.iter().map(|w| w.position).collect();
            let half = mcdem::mpm::implicit::StepOptions { dt: opt.dt / 2.0, ..*opt };
            replay(bodies, walls, &half, copt, k, cuts - 1);
            let load = replay(bodies, walls, &half, copt, k, cuts - 1);
            for (w, s) in walls.iter_mut().zip(start) {
                w.position = s + w.velocity * opt.dt;
            }
            load
        }
    }
}

/// Newton capped at 6 iterations on a Neo-Hookean disc squeezed at 2 m/s with Δt = 0.2 ms: the
/// first step needs 7 (it fails without cuts, naming Newton and Eq. 16), and with cuts several
/// steps are taken in 2–4 sub-steps and the run completes. Checked bit for bit against the same
/// cuts written out independently on copies of the bodies (a failed attempt must leave no trace in
/// the points, the grids or the workspace), and a step that converges is the plain step followed
/// by the wall motion, bit for bit (with a cap of 40 no step is cut and points, loads and walls
/// equal the uncut driver's).
#[test]
fn a_step_that_does_not_converge_is_cut_into_halves() {
    let (dt, steps) = (2e-4, 10);
    let err = run_cut(6, dt, steps, 0).unwrap_err();
    assert!(err.starts_with("step 0: Newton did not converge in 6 iterations"), "{err}");
    assert!(!err.contains("sub-step"), "no cut was allowed: {err}");
    let (cut_loads, subs, x_cut, cut_wall) = run_cut(6, dt, steps, 4).unwrap();
    assert!(subs[0] > 1 && subs.iter().filter(|&&n| n > 1).count() >= 2, "sub-steps per step: {subs:?}");
    // Allowed cuts exhausted: the error names the sub-step's Δt.
    let err = run_cut(2, dt, steps, 2).unwrap_err();
    assert!(err.contains("in a sub-step of Δt = 5.000e-5 s, the step cut in halves 2 times"), "{err}");

    // Uncut references with a cap that never binds.
    let (full, subs_full, x_full, wall_full) = run_cut(40, dt, steps, 4).unwrap();
    assert!(subs_full.iter().all(|&n| n == 1), "{subs_full:?}");
    // Bit for bit the driver without cuts.
    let mut s = Scene::from_json(&plates_with_newton_cap(40, dt, steps)).unwrap().setup::<2>().unwrap();
    let mut cws = ContactWorkspace::default();
    for (k, &load) in full.iter().enumerate() {
        let r = step_bodies(&mut s.bodies, &s.walls, &s.options, &s.contact, k, &mut cws).unwrap();
        assert_eq!(r.wall_load[1], load, "step {k}");
        for w in s.walls.iter_mut() {
            w.position += w.velocity * s.options.dt;
        }
    }
    let x_plain: Vec<f64> = s.bodies[0].points.x.iter().flat_map(|x| [x[0], x[1]]).collect();
    assert_eq!(x_plain, x_full);
    assert_eq!(s.walls[1].position, wall_full);
    assert_eq!(cut_wall, wall_full, "the walls end where uncut steps put them");
    let mut s = Scene::from_json(&plates_with_newton_cap(6, dt, steps)).unwrap().setup::<2>().unwrap();
    for (k, &load) in cut_loads.iter().enumerate() {
        assert_eq!(replay(&mut s.bodies, &mut s.walls, &s.options, &s.contact, k, 4), load, "step {k}");
    }
    let x_replay: Vec<f64> = s.bodies[0].points.x.iter().flat_map(|x| [x[0], x[1]]).collect();
    assert_eq!(x_replay, x_cut);
}

/// The 3-D snapshot path: a Neo-Hookean cube (2 mm, 4 cells a side) squeezed along z between a
/// fixed and a descending frictionless plate for 10 steps. Read back by VTK's reader, the last
/// snapshot has every point of points.csv at its x, y, z (VTK floats), the three extra stress
/// components of 3-D (`sigma_zz`, `sigma_xz`, `sigma_yz`) and a three-component velocity; the
/// compression shows where it must (σ_zz < 0 and J < 1 at every point, the top plate's points
/// moving down), the shear components are orders below σ_zz (frictionless plates: a homogeneous
/// uniaxial state but for the grid's edges), and the walls are two rectangles (4 corners each)
/// at their current positions.
#[test]
fn vtk_snapshots_of_a_3d_scene_carry_the_third_axis() {
    let d = tempfile::tempdir().unwrap();
    let (v, dt, steps) = (-0.5, 1e-5, 10);
    let scene = format!(
        r#"{{"dimension": 3, "material": {{"law": "neohookean", "lambda": 3e6, "mu": 1.5e6, "density": 990}},
            "body": {{"shape": "block", "lo": [0.0, 0.0, 0.0], "hi": [0.002, 0.002, 0.002]}},
            "grid": {{"h": 5e-4, "points_per_cell": 2, "margin": 2}},
            "walls": [{{"axis": 2, "side": 1, "position": 0.0}},
                      {{"axis": 2, "side": -1, "position": 0.002, "velocity": {v}}}],
            "dt": {dt}, "steps": {steps}}}"#
    );
    std::fs::write(d.path().join("cube.json"), scene).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .current_dir(d.path())
        .args(["mpm", "cube.json", "--out", "out", "--vtk-every", "5"])
        .output()
        .expect("mcdem starts");
    assert!(o.status.success(), "mcdem mpm failed: {}", String::from_utf8_lossy(&o.stderr));
    let vtk = d.path().join("out/vtk");
    let csv = std::fs::read_to_string(d.path().join("out/points.csv")).unwrap();
    let rows = points_csv_rows(&csv);
    assert_eq!(rows.len(), 8 * 8 * 8, "4 cells a side, 2 points per cell and axis");
    let v3 = read_vtk(&[vtk.join(format!("points_{steps}.vtk")), vtk.join(format!("walls_{steps}.vtk"))]);
    let (last, walls) = (&v3[0], &v3[1]);
    let pts = last["points"].as_array().unwrap();
    assert_eq!(pts.len(), rows.len());
    let pd = &last["point_data"];
    let col = |name: &str| point_array(last, name);
    let (j, szz, sxz, syz) = (col("J"), col("sigma_zz"), col("sigma_xz"), col("sigma_yz"));
    let vel = pd["velocity"].as_array().unwrap();
    let szz_max = szz.iter().fold(0.0f64, |m, s| m.max(s.abs()));
    for (k, r) in rows.iter().enumerate() {
        for a in 0..3 {
            let p = pts[k][a].as_f64().unwrap();
            assert!(
                (p - r[1 + a]).abs() <= 5e-6 * r[1 + a].abs().max(1e-4),
                "point {k} axis {a}: {p} vs {}",
                r[1 + a]
            );
        }
        assert!(szz[k] < 0.0 && j[k] < 1.0, "point {k}: sigma_zz {} J {}", szz[k], j[k]);
        assert!(
            sxz[k].abs() < 1e-2 * szz_max && syz[k].abs() < 1e-2 * szz_max,
            "point {k}: shear {} {}",
            sxz[k],
            syz[k]
        );
        assert_eq!(vel[k].as_array().unwrap().len(), 3);
    }
    // The points near the top plate move down with it; those on the floor stay.
    let top = (0..rows.len()).max_by(|&a, &b| rows[a][3].total_cmp(&rows[b][3])).unwrap();
    assert!(vel[top][2].as_f64().unwrap() < 0.1 * v, "top point's vz {}", vel[top][2]);
    // Walls: two rectangles, the top one at its moved position.
    assert_eq!(walls["cells"].as_u64(), Some(2));
    let wp = walls["points"].as_array().unwrap();
    assert_eq!(wp.len(), 8);
    let z_top = 0.002 + v * dt * steps as f64;
    for k in 0..4 {
        assert!(wp[k][2].as_f64().unwrap().abs() < 1e-12, "floor corner {k}: {:?}", wp[k]);
        assert!(
            (wp[4 + k][2].as_f64().unwrap() - z_top).abs() < 1e-8,
            "top corner {k}: {:?}, want {z_top}",
            wp[4 + k]
        );
    }
}
