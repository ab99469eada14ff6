//! Conservation checks of the engine: energy without damping and friction (e = 1, μ = 0) and
//! momentum with periodic boundaries; plus the instability stop.

use mcdem::engine::{Closure, Domain, World};
use mcdem::physics::hertz::Tangential;
use mcdem::physics::{Material, Vec3};

/// A dilute periodic gas of spheres on a jittered lattice with deterministic pseudo-random
/// velocities and spins.
fn gas(restitution: f64, friction: f64, dt: f64) -> World {
    let mut w = World::new();
    let l = 0.012;
    w.domain = Some(Domain::new(Vec3::zeros(), Vec3::repeat(l), [true; 3]));
    w.set_materials(
        vec![Material::hertz(1e6, 0.3).unwrap()],
        &[restitution],
        &[friction],
        Tangential::History,
    )
    .unwrap();
    w.closure = Some(Closure::Hertz);
    w.dt = dt;
    w.skin = 2e-4;
    w.integrate = true;
    let mut rng = mcdem::rng::Lcg64(12345);
    let mut rnd = move || rng.symmetric();
    let mut id = 1;
    for a in 0..2 {
        for b in 0..2 {
            for c in 0..2 {
                let x = Vec3::new(a as f64 + 0.5, b as f64 + 0.5, c as f64 + 0.5) * (l / 2.0);
                w.p.push(id, 0, x + Vec3::new(rnd(), rnd(), rnd()) * 1e-3, 0.002 + 2e-4 * rnd(), 1000.0);
                let i = w.p.len() - 1;
                w.p.v[i] = Vec3::new(rnd(), rnd(), rnd());
                w.p.omega[i] = Vec3::new(rnd(), rnd(), rnd()) * 100.0;
                id += 1;
            }
        }
    }
    w
}

fn energy(w: &World) -> f64 {
    w.kinetic_energy() + w.rotational_energy() + w.elastic_energy()
}

fn momentum(w: &World) -> Vec3 {
    w.p.v.iter().zip(&w.p.mass).map(|(v, m)| v * *m).sum()
}

#[test]
fn energy_is_conserved_without_damping_and_friction() {
    energy_conserved(gas(1.0, 0.0, 1e-7));
}

/// The same gas under `model hooke` (e = 1: no damping; the stored energy is ½ k_n δ²).
#[test]
fn energy_is_conserved_under_hooke_without_damping_and_friction() {
    let mut w = gas(1.0, 0.0, 1e-7);
    w.use_hooke(1.0, &[1.0], (true, false, false)).unwrap();
    energy_conserved(w);
}

fn energy_conserved(mut w: World) {
    w.setup().unwrap();
    let e0 = energy(&w);
    let mut worst = 0.0_f64;
    let mut contacts_seen = 0;
    for _ in 0..100_000 {
        w.step().unwrap();
        let (pp, _) = w.contact_counts();
        contacts_seen += pp;
        worst = worst.max((energy(&w) - e0).abs() / e0);
    }
    println!("max relative energy error over 1e5 steps: {worst:.3e}; contact-steps {contacts_seen}");
    assert!(contacts_seen > 1000, "the gas must actually collide ({contacts_seen} contact-steps)");
    assert!(worst <= 1e-6, "energy drift {worst:e}");
}

#[test]
fn momentum_is_conserved_with_periodic_boundaries() {
    let mut w = gas(0.7, 0.5, 2e-7);
    w.setup().unwrap();
    let p0 = momentum(&w);
    let scale: f64 = w.p.v.iter().zip(&w.p.mass).map(|(v, m)| v.norm() * m).sum();
    let mut contacts_seen = 0;
    for _ in 0..50_000 {
        w.step().unwrap();
        contacts_seen += w.contact_counts().0;
    }
    let err = (momentum(&w) - p0).norm() / scale;
    println!("relative momentum error: {err:.3e}; contact-steps {contacts_seen}; builds {}", w.builds);
    assert!(contacts_seen > 500);
    assert!(w.p.image.iter().any(|im| im.iter().any(|&k| k != 0)), "particles must cross the boundary");
    assert!(err <= 1e-13, "momentum error {err:e}");
}

#[test]
fn too_large_time_step_stops_with_particle_and_step() {
    let mut w = gas(1.0, 0.0, 1e-2);
    let e = w.setup().unwrap_err();
    assert!(e.contains("Rayleigh") && e.contains("particle"), "{e}");
}

/// Two Hertz spheres of diameter 2 mm, ids `ids`, centres at ∓`half_gap` on x, in a closed box,
/// integrating at Δt = 1 µs.
fn two_spheres(ids: [i64; 2], half_gap: f64) -> World {
    let mut w = World::new();
    w.domain = Some(Domain::new(Vec3::repeat(-0.01), Vec3::repeat(0.01), [false; 3]));
    w.set_materials(vec![Material::hertz(1e3, 0.3).unwrap()], &[1.0], &[0.0], Tangential::History).unwrap();
    w.closure = Some(Closure::Hertz);
    w.dt = 1e-6;
    w.skin = 1e-3;
    w.integrate = true;
    w.p.push(ids[0], 0, Vec3::new(-half_gap, 0.0, 0.0), 0.002, 1000.0);
    w.p.push(ids[1], 0, Vec3::new(half_gap, 0.0, 0.0), 0.002, 1000.0);
    w
}

#[test]
fn runaway_overlap_stops_with_particle_and_step() {
    // Two spheres driven into each other far faster than the contact can resist.
    let mut w = two_spheres([1, 2], 0.0012);
    w.p.v[0] = Vec3::new(50.0, 0.0, 0.0);
    w.p.v[1] = Vec3::new(-50.0, 0.0, 0.0);
    w.setup().unwrap();
    let mut err = None;
    for _ in 0..10_000 {
        if let Err(e) = w.step() {
            err = Some(e);
            break;
        }
    }
    let e = err.expect("the run must stop");
    let msg = e.to_string();
    assert!(msg.contains("particle 1") && msg.contains("step") && msg.contains("overlap"), "{msg}");
}

/// A state that is no longer finite (here a velocity set to NaN mid-run, as a broken force or fix
/// would leave it) stops the step naming the particle, the step and the cause; it never runs on
/// with NaN positions. Checked to fail: with the finiteness check removed from the kick, the run
/// goes on and `step()` returns Ok with a NaN position.
#[test]
fn non_finite_state_stops_naming_the_particle() {
    let mut w = two_spheres([1, 7], 0.003);
    w.setup().unwrap();
    for _ in 0..10 {
        w.step().unwrap();
    }
    w.p.v[1] = Vec3::new(f64::NAN, 0.0, 0.0);
    let e = w.step().expect_err("a NaN velocity must stop the step");
    let msg = e.to_string();
    assert!(msg.contains("particle 7") && msg.contains("not finite") && msg.contains("step"), "{msg}");
    assert!(w.p.x[0].iter().all(|c| c.is_finite()), "the other particle stays finite");
}
