//! Mesh walls against independent references: a primitive plane at the same place, or another
//! triangulation of the same surface. Every contact of a sphere with a mesh must count exactly
//! once wherever its closest point lies: inside a triangle, on an edge or corner shared by
//! coplanar triangles (up to six here), on the mesh boundary, on a convex ridge or in a concave
//! fold; and a sphere sliding across a seam keeps its tangential history.
//!
//! Tolerances: a face contact of a horizontal mesh and the plane give the same contact point up to
//! the round-off of the barycentric arithmetic (1e-16 relative), so whole trajectories agree to
//! 1e-12 of the largest value over the run (measured: below 1e-13); a lost or doubled contact, or a
//! tangential spring restarted at a seam, moves them by 1e-3 or more.

use mcdem::engine::{Closure, Domain, Mesh, PairThreads, PlaneWall, WallFix, WallGeom, World};
use mcdem::physics::hertz::Tangential;
use mcdem::physics::{Material, Vec3};

const R: f64 = 1e-3;
const L: f64 = 10e-3;

enum Wall {
    Plane(usize, f64),
    Mesh(Vec<[Vec3; 3]>),
}

fn world(walls: Vec<Wall>, spheres: &[(Vec3, Vec3)], friction: f64) -> World {
    let mut w = World::new();
    w.domain = Some(Domain::new(Vec3::repeat(-0.02), Vec3::repeat(0.02), [false; 3]));
    w.set_materials(vec![Material::hertz(1e6, 0.4).unwrap()], &[0.7], &[friction], Tangential::History)
        .unwrap();
    w.closure = Some(Closure::Hertz);
    w.skin = 1e-4;
    w.dt = 1e-6;
    w.integrate = true;
    for (k, (x, v)) in spheres.iter().enumerate() {
        w.p.push(k as i64 + 1, 0, *x, 2.0 * R, 1000.0);
        w.p.v[k] = *v;
    }
    for (k, wall) in walls.into_iter().enumerate() {
        let geom = match wall {
            Wall::Plane(axis, pos) => WallGeom::Plane(PlaneWall { axis, pos, wall_type: 0 }),
            Wall::Mesh(raw) => {
                w.meshes.push(Mesh::new(&format!("mesh{k}"), 0, raw).unwrap());
                WallGeom::Meshes(vec![w.meshes.len() - 1])
            }
        };
        w.walls.push(WallFix { name: format!("wall{k}"), geom });
    }
    w.setup().unwrap();
    w
}

/// The square [-L/2, L/2]² at height z as an n × n grid of squares, each split along its
/// (−,−)–(+,+) diagonal, or along the other one with `flip` (so an interior vertex is shared by
/// six triangles).
fn plate(z: f64, n: usize, flip: bool) -> Vec<[Vec3; 3]> {
    let h = L / n as f64;
    let p = |i: usize, j: usize| Vec3::new(-0.5 * L + h * i as f64, -0.5 * L + h * j as f64, z);
    let mut tris = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            if flip {
                tris.push([a, b, d]);
                tris.push([b, c, d]);
            } else {
                tris.push([a, b, c]);
                tris.push([a, c, d]);
            }
        }
    }
    tris
}

/// Steps both worlds together; returns the largest difference of positions, velocities, angular
/// velocities and forces, each relative to its largest magnitude over the run (positions: the
/// largest coordinate), and the largest force seen.
fn run_pair(a: &mut World, b: &mut World, steps: usize) -> (f64, f64) {
    let mut worst = [0.0_f64; 4];
    let mut scale = [0.0_f64; 4];
    for _ in 0..steps {
        a.step().unwrap();
        b.step().unwrap();
        for i in 0..a.p.len() {
            let q = [
                (a.p.x[i], b.p.x[i]),
                (a.p.v[i], b.p.v[i]),
                (a.p.omega[i], b.p.omega[i]),
                (a.p.f[i], b.p.f[i]),
            ];
            for (k, (u, v)) in q.iter().enumerate() {
                worst[k] = worst[k].max((u - v).amax());
                scale[k] = scale[k].max(u.amax()).max(v.amax());
            }
        }
    }
    // A spin that the reference lacks altogether (round-off of a contact point's in-plane
    // coordinates) is measured against the spin the largest velocity would give when rolling.
    scale[2] = scale[2].max(scale[1] / R);
    let rel = (0..4).map(|k| if scale[k] > 0.0 { worst[k] / scale[k] } else { worst[k] }).fold(0.0, f64::max);
    (rel, scale[3])
}

/// A sphere pressed against the plate by 0.1 r (centre 0.9 r below it), at rest, against the
/// same sphere under a primitive plane.
fn against_plane(mesh: Vec<[Vec3; 3]>, xy: &[(f64, f64)], what: &str) {
    let h = 5e-3;
    let spheres: Vec<(Vec3, Vec3)> =
        xy.iter().map(|&(x, y)| (Vec3::new(x, y, h - 0.9 * R), Vec3::zeros())).collect();
    let mut a = world(vec![Wall::Mesh(mesh)], &spheres, 0.5);
    let mut b = world(vec![Wall::Plane(2, h)], &spheres, 0.5);
    let (rel, fmax) = run_pair(&mut a, &mut b, 50);
    println!("{what}: relative difference {rel:.2e}, largest force {fmax:.3e} N");
    assert!(fmax > 1e-3, "{what}: no contact force ({fmax:e} N)");
    assert!(rel <= 1e-12, "{what}: mesh and plane differ by {rel:e} of the range");
}

#[test]
fn a_sphere_over_the_diagonal_of_a_split_plate_feels_it_like_a_plane() {
    // The cases of the report: centred, and two more points exactly on the diagonal.
    for xy in [(0.0, 0.0), (0.001, 0.001), (-0.002, -0.002)] {
        against_plane(plate(5e-3, 1, false), &[xy], &format!("two triangles, sphere at {xy:?}"));
    }
}

#[test]
fn spheres_on_every_vertex_and_seam_of_a_32_triangle_plate_feel_it_like_a_plane() {
    let h = L / 4.0;
    // All 25 grid vertices (the 9 interior ones shared by six triangles, the corners by one or
    // two), then the midpoints of every edge and diagonal, in sets 2.5 mm apart (no pair contact).
    let vertices: Vec<(f64, f64)> =
        (0..25).map(|k| (-0.5 * L + h * (k % 5) as f64, -0.5 * L + h * (k / 5) as f64)).collect();
    for flip in [false, true] {
        against_plane(plate(5e-3, 4, flip), &vertices, &format!("grid vertices, flip {flip}"));
        for (dx, dy) in [(0.5, 0.0), (0.0, 0.5), (0.5, 0.5)] {
            let mids: Vec<(f64, f64)> = vertices
                .iter()
                .map(|&(x, y)| (x + dx * h, y + dy * h))
                .filter(|&(x, y)| x <= 0.5 * L && y <= 0.5 * L)
                .collect();
            against_plane(plate(5e-3, 4, flip), &mids, &format!("midpoints ({dx}, {dy}) h, flip {flip}"));
        }
    }
}

#[test]
fn randomly_placed_spheres_feel_a_meshed_plate_like_a_plane() {
    // The crate's seeded generator: four rounds of four spheres, each anywhere in its own 5 mm
    // quarter of the plate at least 1.05 r from the quarter's sides (so no two touch).
    let mut rng = mcdem::rng::SplitMix64(12345);
    let mut next = || rng.uniform();
    let h = 0.5 * L;
    for round in 0..4 {
        let xy: Vec<(f64, f64)> = (0..4)
            .map(|k| {
                let (i, j) = ((k % 2) as f64, (k / 2) as f64);
                let u = |c: f64, r: f64| -0.5 * L + h * c + 1.05 * R + (h - 2.1 * R) * r;
                (u(i, next()), u(j, next()))
            })
            .collect();
        against_plane(plate(5e-3, 4, false), &xy, &format!("random positions, round {round}"));
    }
}

#[test]
fn beyond_the_boundary_every_triangulation_gives_the_same_contact() {
    // Level with the plate, beside an outer corner (shared by two triangles in one split, one in
    // the other) and beside an outer edge: the contact is the corner or edge point, once.
    let z = 5e-3;
    let spheres = [
        (Vec3::new(0.5 * L + 0.4 * R, 0.5 * L + 0.3 * R, z - 0.5 * R), Vec3::zeros()),
        (Vec3::new(-0.5 * L - 0.4 * R, -0.5 * L - 0.3 * R, z + 0.5 * R), Vec3::zeros()),
        (Vec3::new(0.5 * L + 0.6 * R, 0.0, z + 0.2 * R), Vec3::zeros()),
    ];
    let meshes = [plate(z, 1, false), plate(z, 1, true), plate(z, 4, false), plate(z, 4, true)];
    for m in &meshes[1..] {
        let mut a = world(vec![Wall::Mesh(meshes[0].clone())], &spheres, 0.5);
        let mut b = world(vec![Wall::Mesh(m.clone())], &spheres, 0.5);
        let (rel, fmax) = run_pair(&mut a, &mut b, 50);
        println!("boundary, {} triangles: relative difference {rel:.2e}, force {fmax:.3e} N", m.len());
        assert!(fmax > 1e-3 && rel <= 1e-12, "{rel:e} {fmax:e}");
    }
}

#[test]
fn the_triangle_order_of_the_mesh_file_does_not_matter() {
    let h = L / 4.0;
    let xy: Vec<(f64, f64)> =
        (0..25).map(|k| (-0.5 * L + h * (k % 5) as f64, -0.5 * L + h * (k / 5) as f64)).collect();
    let spheres: Vec<(Vec3, Vec3)> =
        xy.iter().map(|&(x, y)| (Vec3::new(x, y, 5e-3 - 0.9 * R), Vec3::zeros())).collect();
    let ordered = plate(5e-3, 4, false);
    // Reversed order, and each triangle's vertices rotated by one.
    let shuffled: Vec<[Vec3; 3]> = ordered.iter().rev().map(|t| [t[1], t[2], t[0]]).collect();
    let mut a = world(vec![Wall::Mesh(ordered)], &spheres, 0.5);
    let mut b = world(vec![Wall::Mesh(shuffled)], &spheres, 0.5);
    let (rel, _) = run_pair(&mut a, &mut b, 50);
    assert!(rel <= 1e-12, "{rel:e}");
}

/// A heavy sphere (gravity 1000 m/s²) rolling with a slight slip (spin 0.1 % short of rolling)
/// over a floor split along its diagonal, across the diagonal: its tangential spring stays below
/// the Coulomb limit (stick), so restarting it on the second triangle would change the friction
/// force at the crossing. The same trajectory as on a primitive plane.
#[test]
fn a_sphere_rolling_across_a_seam_keeps_its_friction_history() {
    let v = Vec3::new(1.0, 0.2, 0.0);
    let start = [(Vec3::new(-1e-3, -0.2e-3, R - 1.9e-5), v)];
    let spin = 0.999 * Vec3::new(-v.y / R, v.x / R, 0.0);
    let mut a = world(vec![Wall::Mesh(plate(0.0, 1, false))], &start, 0.5);
    let mut b = world(vec![Wall::Plane(2, 0.0)], &start, 0.5);
    for w in [&mut a, &mut b] {
        w.gravity = Some(Vec3::new(0.0, 0.0, -1000.0));
        w.p.omega[0] = spin;
    }
    let (rel, fmax) = run_pair(&mut a, &mut b, 2500);
    let x = a.p.x[0];
    println!("rolling across the seam: relative difference {rel:.2e}, force {fmax:.3e} N, end at {x:?}");
    assert!(x.x > x.y + 5e-4, "the sphere crossed the diagonal: {x:?}");
    assert!(rel <= 1e-12, "{rel:e}");
}

#[test]
fn a_sphere_in_a_concave_fold_touches_both_sides_like_two_planes() {
    let n = 4;
    let floor: Vec<[Vec3; 3]> =
        plate(0.0, n, false).into_iter().map(|t| t.map(|v| Vec3::new(v.x + 0.5 * L, v.y, v.z))).collect();
    // The wall x = 0 (z from 0 to L): the floor turned about the y axis.
    let wall: Vec<[Vec3; 3]> = floor.iter().map(|t| t.map(|v| Vec3::new(0.0, v.y, v.x))).collect();
    let folded: Vec<[Vec3; 3]> = floor.iter().chain(&wall).copied().collect();
    let spheres = [(Vec3::new(0.9 * R, 0.0, 0.9 * R), Vec3::new(0.0, 0.1, 0.0))];
    let planes = || vec![Wall::Plane(2, 0.0), Wall::Plane(0, 0.0)];
    for (what, walls) in [
        ("one folded mesh", vec![Wall::Mesh(folded.clone())]),
        ("two meshes", vec![Wall::Mesh(floor.clone()), Wall::Mesh(wall.clone())]),
    ] {
        let mut a = world(walls, &spheres, 0.5);
        let mut b = world(planes(), &spheres, 0.5);
        let (rel, fmax) = run_pair(&mut a, &mut b, 200);
        println!("{what}: relative difference {rel:.2e}, force {fmax:.3e} N");
        assert!(fmax > 1e-3 && rel <= 1e-12, "{what}: {rel:e}");
    }
}

#[test]
fn a_sphere_on_a_convex_ridge_touches_it_once() {
    // A roof of two 30° slopes meeting at the ridge y = 0, z = 0; the sphere straight above the
    // ridge, pressed on it by 0.1 r. The same contact as with one slope alone, whose boundary edge
    // is the ridge: a double count would give twice the force.
    let s = 30.0_f64.to_radians().tan();
    let left: Vec<[Vec3; 3]> = vec![
        [Vec3::new(-L, 0.0, 0.0), Vec3::new(L, 0.0, 0.0), Vec3::new(-L, -L, -L * s)],
        [Vec3::new(L, 0.0, 0.0), Vec3::new(L, -L, -L * s), Vec3::new(-L, -L, -L * s)],
    ];
    let right: Vec<[Vec3; 3]> = left.iter().map(|t| t.map(|v| Vec3::new(v.x, -v.y, v.z))).collect();
    let roof: Vec<[Vec3; 3]> = left.iter().chain(&right).copied().collect();
    let spheres = [(Vec3::new(0.0, 0.0, 0.9 * R), Vec3::zeros())];
    let mut a = world(vec![Wall::Mesh(roof)], &spheres, 0.5);
    let mut b = world(vec![Wall::Mesh(left)], &spheres, 0.5);
    let (rel, fmax) = run_pair(&mut a, &mut b, 1);
    println!("ridge: relative difference {rel:.2e}, force {fmax:.3e} N");
    assert!(fmax > 1e-3 && rel <= 1e-12, "{rel:e}");
}

#[test]
fn a_plate_larger_than_the_box_still_holds_the_spheres() {
    // The plate reaches 5 mm beyond the domain (±0.02 m here: a 50 mm plate); spheres near the
    // domain's edge.
    let big: Vec<[Vec3; 3]> =
        plate(5e-3, 2, false).into_iter().map(|t| t.map(|v| Vec3::new(5.0 * v.x, 5.0 * v.y, v.z))).collect();
    let xy = [(0.019, 0.019), (-0.019, 0.0), (0.0, -0.0195)];
    against_plane(big, &xy, "plate beyond the box");
}

#[test]
fn mesh_contacts_are_the_same_on_one_and_two_threads() {
    let h = L / 4.0;
    let spheres: Vec<(Vec3, Vec3)> = (0..25)
        .map(|k| {
            (
                Vec3::new(-0.5 * L + h * (k % 5) as f64, -0.5 * L + h * (k / 5) as f64, 5e-3 - 0.9 * R),
                Vec3::new(0.3, 0.1, 0.0),
            )
        })
        .collect();
    let mut a = world(vec![Wall::Plane(2, 5e-3 - 1.8 * R), Wall::Mesh(plate(5e-3, 4, true))], &spheres, 0.5);
    let mut b = world(vec![Wall::Plane(2, 5e-3 - 1.8 * R), Wall::Mesh(plate(5e-3, 4, true))], &spheres, 0.5);
    a.pair_threads = PairThreads::Serial;
    b.pair_threads = PairThreads::Parallel;
    let (rel, fmax) = run_pair(&mut a, &mut b, 300);
    assert!(fmax > 1e-3);
    assert_eq!(rel, 0.0, "one and two threads differ by {rel:e}");
}
