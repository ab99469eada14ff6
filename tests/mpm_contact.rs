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
/// body in tests/mpm.rs), restitution rising under both refinements, and the contact duration
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
