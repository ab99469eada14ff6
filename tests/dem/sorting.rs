//! Spatial sorting (`World::sort_every`, LAMMPS `atom_modify sort`) reorders particles in memory;
//! it must not change the physics. A sheared, frictional, multi-contact bed between two plane
//! walls is run with sorting at every neighbour build and without: per particle id, positions and
//! velocities agree to round-off, although the particles were renumbered many times (pair
//! history turned round, wall contacts and kept influence matrices remapped).

use mcdem::engine::{Closure, Domain, PlaneWall, WallFix, WallGeom, World};
use mcdem::physics::ghods2022::MprTest;
use mcdem::physics::hertz::Tangential;
use mcdem::physics::{Material, Vec3};

const D: f64 = 1e-3;

/// 6 × 6 × 5 jittered simple cubic bed at spacing 0.95 d (every particle touches its lattice
/// neighbours), periodic in x and y with Lees–Edwards shear, plane walls at both z ends.
fn bed(sort_every: u64, tolerance: f64) -> World {
    let (nx, nz) = (6, 5);
    let a = 0.95 * D;
    let (l, lz) = (nx as f64 * a, nz as f64 * a);
    let mut w = World::new();
    let mut dom = Domain::new(Vec3::zeros(), Vec3::new(l, l, lz), [true, true, false]);
    let gdot = 60.0;
    dom.le_vjump = gdot * l;
    w.domain = Some(dom);
    let m = Material::new(1e6, 0.4, 0.81, Some((0.11, MprTest::Abs))).unwrap();
    w.set_materials(vec![m], &[0.7], &[0.5], Tangential::History).unwrap();
    w.closure = Some(Closure::MultiContact);
    w.mc_range = 1.25;
    w.mc_geometry_tolerance = tolerance;
    w.sort_every = sort_every;
    w.skin = 0.1 * D;
    w.integrate = true;
    w.dt = 4e-6;
    for (axis_pos, name) in [(0.0, "bottom"), (lz, "top")] {
        w.walls.push(WallFix {
            name: name.into(),
            geom: WallGeom::Plane(PlaneWall { axis: 2, pos: axis_pos, wall_type: 0 }),
        });
    }
    // Created with x slowest: the sort (x fastest) has to renumber nearly every particle.
    let mut id = 1;
    for i in 0..nx {
        for j in 0..nx {
            for k in 0..nz {
                let jit = 0.02 * a * (((id * 7919) % 13) as f64 - 6.0) / 6.0;
                let x =
                    Vec3::new((i as f64 + 0.5) * a + jit, (j as f64 + 0.5) * a - jit, (k as f64 + 0.5) * a);
                w.p.push(id, 0, x, D, 1000.0);
                let n = w.p.len() - 1;
                w.p.v[n].x = dom.streaming_vx(x.y);
                w.p.v[n].z = 0.01 * (((id * 104729) % 17) as f64 - 8.0) / 8.0;
                id += 1;
            }
        }
    }
    w.setup().unwrap();
    w
}

/// Positions and velocities by id after `steps` steps.
fn run(mut w: World, steps: usize) -> (World, Vec<(i64, Vec3, Vec3)>) {
    for _ in 0..steps {
        w.step().unwrap();
    }
    let mut s: Vec<(i64, Vec3, Vec3)> = (0..w.p.len()).map(|i| (w.p.id[i], w.p.x[i], w.p.v[i])).collect();
    s.sort_by_key(|r| r.0);
    (w, s)
}

fn worst(a: &[(i64, Vec3, Vec3)], b: &[(i64, Vec3, Vec3)], vscale: f64) -> (f64, f64) {
    assert_eq!(a.len(), b.len());
    let mut ex: f64 = 0.0;
    let mut ev: f64 = 0.0;
    for (p, q) in a.iter().zip(b) {
        assert_eq!(p.0, q.0);
        ex = ex.max((p.1 - q.1).norm() / D);
        ev = ev.max((p.2 - q.2).norm() / vscale);
    }
    (ex, ev)
}

#[test]
fn sorting_does_not_change_a_sheared_multicontact_bed_with_walls() {
    let steps = 1500;
    let (plain, a) = run(bed(0, 0.0), steps);
    let (sorted, b) = run(bed(1, 0.0), steps);
    assert_eq!(plain.sorts, 0);
    // The comparison means something only if the particles were really renumbered, many times.
    assert!(sorted.sorts >= 5, "only {} sorts", sorted.sorts);
    let moved = (0..sorted.p.len()).filter(|&i| sorted.p.id[i] != i as i64 + 1).count();
    assert!(moved > sorted.p.len() / 2, "{moved} of {} particles renumbered", sorted.p.len());
    // The bed is really multi-contact, sheared and touching both walls.
    assert!(sorted.mc_kernel_contacts > 0);
    let vscale = 60.0 * 6.0 * 0.95 * D;
    let (ex, ev) = worst(&a, &b, vscale);
    eprintln!("{} sorts, max |dx|/d = {ex:e}, max |dv|/(gdot L) = {ev:e}", sorted.sorts);
    // Only summation orders differ: round-off (1e-16) grown over the run, far below any physical
    // difference (a pair's history used with the wrong sign moves particles by ~1e-3 d here).
    assert!(ex < 1e-9 && ev < 1e-7, "sorted run differs: dx/d {ex:e}, dv {ev:e}");
}

#[test]
fn sorting_keeps_the_geometry_tolerance_cache_consistent() {
    // Under a geometry tolerance the kept influence matrices follow the renumbering; a particle
    // whose contacts come in another order after a sort recomputes its matrix (exact again). So
    // the sorted run is no further from the exact run than the unsorted one, and it does not
    // recompute every matrix at every step.
    let steps = 1500;
    let (_, exact) = run(bed(0, 0.0), steps);
    let (plain, a) = run(bed(0, 1e-3), steps);
    let (sorted, b) = run(bed(1, 1e-3), steps);
    assert!(sorted.sorts >= 5);
    let vscale = 60.0 * 6.0 * 0.95 * D;
    let (ea, _) = worst(&exact, &a, vscale);
    let (eb, _) = worst(&exact, &b, vscale);
    let (ua, ub) = (plain.mc_influence_updates(), sorted.mc_influence_updates());
    let calls = sorted.p.len() as u64 * steps as u64;
    eprintln!("tolerance 1e-3 vs exact: unsorted {ea:e} d ({ua} matrices), sorted {eb:e} d ({ub} matrices), {calls} particle-steps");
    assert!(ea > 0.0 && ea < 1e-3, "unsorted tolerance error {ea:e}");
    assert!(eb < 2.0 * ea, "sorted tolerance error {eb:e} vs unsorted {ea:e}");
    assert!(ub < calls / 2, "sorted run recomputed {ub} of {calls} matrices");
}
