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

/// The whole collision to separation: stops in the line search when the discs unload (step 33).
#[test]
#[ignore = "measured: Newton stalls at step 33 when the discs unload (line search accepts alpha ~1e-7, |R| stays 8.7e-5 N/m against a force scale of 97 N/m); restitution not measured yet"]
fn head_on_discs_separate_after_the_collision() {
    let mut s = Scene::from_json(&two_discs("")).unwrap().setup::<2>().unwrap();
    let mut ws = ContactWorkspace::default();
    for k in 0..120 {
        step_bodies(&mut s.bodies, &[], &s.options, &s.contact, k, &mut ws).unwrap();
    }
    let v = |b: usize| s.bodies[b].points.momentum()[0] / s.bodies[b].points.mass.iter().sum::<f64>();
    assert!(v(0) < 0.0 && v(1) > 0.0);
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
    // With μ = 0.5 at this quasi-static step (K ≫ M/Δt²) the contact iterations converge too
    // slowly (measured: a force update still moves a node by 1.0e-6 m after 500 iterations against
    // the 1e-10 m criterion): the run must stop with that message, not return a wrong answer.
    let mut s = Scene::from_json(&scene(0.5)).unwrap().setup::<2>().unwrap();
    let e = step_bodies(&mut s.bodies, &s.walls, &s.options, &s.contact, 0, &mut ContactWorkspace::default())
        .unwrap_err();
    assert!(e.contains("contact iterations did not converge") && e.contains("reduce Δt"), "{e}");
}
