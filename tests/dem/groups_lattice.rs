//! Integration of part of the particles (`fix nve/sphere` of a group), `fix momentum`, and
//! `region mesh/tet` + `lattice` + `create_atoms … region`: each against stock LIGGGHTS on a small
//! deck of `liggghts_inputs/`, and the bad inputs each stops on.

use std::path::Path;

use crate::against_liggghts::{assert_dumps_agree, have_liggghts, repo, run_both};

/// Rows of a dump frame by particle id.
fn by_id(f: &mcdem::outputs::Frame) -> Vec<&Vec<f64>> {
    let mut rows: Vec<&Vec<f64>> = f.rows.iter().collect();
    rows.sort_by(|a, b| a[0].total_cmp(&b[0]));
    rows
}

/// Particle 2 (group `movers`) hits particle 1 (not integrated) and bounces off. Particle 1 keeps
/// its position and velocity at every step in both engines, though forces act on it; particle 2
/// bounces. Every quantity every step to 1e-12 of its range: as for the other few-particle decks
/// the only difference is the order of the few force sums.
#[test]
fn integrating_one_group_of_two_particles_matches_liggghts_step_by_step() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/group_integration.in");
    let (o, t) = run_both(&deck, &[], &[]);
    let f = "post/group_integration.dump";
    assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
    let frames = mcdem::outputs::read_dump(&o.path().join(f)).unwrap();
    let (mut touched, first) = (false, by_id(&frames[0])[1][4]);
    for fr in &frames {
        let r = by_id(fr);
        // id x y z vx: the fixed particle never moves and keeps vx = 0.3.
        assert_eq!((r[0][1], r[0][2], r[0][3], r[0][4]), (0.0, 0.0, 0.005, 0.3), "step {}", fr.step);
        touched |= r[0][7] != 0.0;
    }
    let last = by_id(frames.last().unwrap())[1][4];
    assert!(touched, "particle 1 never felt a contact");
    assert!(first < 0.0 && last > 0.0, "particle 2 did not bounce back: vx {first} -> {last}");
}

/// `fix momentum 1 linear 1 1 0` over a periodic bed: the same trajectories as LIGGGHTS to 1e-12
/// of each range (few particles: only the order of sums differs); after every step the total
/// momentum in x and y is zero to round-off (1e-12 of Σ m|v|) while z is not held.
#[test]
fn fix_momentum_zeroes_x_and_y_and_matches_liggghts() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/momentum_periodic.in");
    let (o, t) = run_both(&deck, &[], &[]);
    let f = "post/momentum_periodic.dump";
    assert_dumps_agree(&o.path().join(f), &t.path().join(f), 1e-12);
    let frames = mcdem::outputs::read_dump(&o.path().join(f)).unwrap();
    let mut pz_seen = Vec::new();
    for fr in frames.iter().skip(1) {
        // id mass x y z vx vy vz …
        let (mut p, mut scale) = ([0.0; 3], 0.0);
        for r in &fr.rows {
            for c in 0..3 {
                p[c] += r[1] * r[5 + c];
                scale += r[1] * r[5 + c].abs();
            }
        }
        assert!(p[0].abs() <= 1e-12 * scale && p[1].abs() <= 1e-12 * scale, "step {}: p = {p:?}", fr.step);
        pz_seen.push(p[2]);
    }
    let spread = pz_seen.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
        - pz_seen.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    assert!(spread > 1e-6, "z momentum did not change (gravity, floor): spread {spread:e}");
}

/// `lattice sc|bcc|fcc` + `create_atoms 1 region` in a `mesh/tet` cube of six tetrahedra: the same
/// number of atoms as LIGGGHTS (sites on the faces, inner ones included, are outside), the same ids
/// at the same positions, mass and radius to the printed 15 digits (the sites are computed with
/// LIGGGHTS' arithmetic, so identical).
#[test]
fn lattice_sites_in_a_tet_mesh_are_liggghts_atoms() {
    if !have_liggghts() {
        return;
    }
    let deck = repo().join("liggghts_inputs/lattice_tet.in");
    let meshes = repo().join("liggghts_inputs/meshes");
    for (style, n) in [("sc", 504), ("bcc", 1224), ("fcc", 2934)] {
        let (o, t) = run_both(&deck, &[meshes.as_path()], &[("style", style)]);
        let read = |d: &Path| mcdem::outputs::read_dump(&d.join("post/lattice_tet.dump")).unwrap();
        let (a, b) = (read(o.path()), read(t.path()));
        // LIGGGHTS writes its memory order (sorted in space at set-up), mcdem id order.
        let (a, b) = (by_id(&a[0]), by_id(&b[0]));
        assert_eq!(b.len(), n, "{style}: LIGGGHTS count");
        assert_eq!(a.len(), n, "{style}: mcdem count");
        let first_diff = a.iter().zip(&b).position(|(p, q)| p != q);
        assert!(first_diff.is_none(), "{style}: row {first_diff:?} differs (id type mass radius x y z)");
    }
}

fn run_deck(text: &str, files: &[(&str, &str)]) -> (bool, String) {
    let (ok, out, _) = super::deck::run_in("in.test", text, &[], files);
    (ok, out)
}

const BASE: &str = "units si
atom_style sphere
boundary f f f
region box block -1 1 -1 1 -1 1 units box
create_box 1 box
";

const CUBE: &str = "# vtk DataFile Version 2.0
cube
ASCII
DATASET UNSTRUCTURED_GRID
POINTS 4 double
0 0 0
1 0 0
0 1 0
0 0 1
CELLS 1 5
4 0 1 2 3
CELL_TYPES 1
10
";

/// A deck, the files it reads (name, text), and what its error must say.
type Case<'a> = (String, Vec<(&'a str, &'a str)>, &'a str);

#[test]
fn bad_lattice_tet_group_and_momentum_input_stops_with_the_reason() {
    let tet = "region t mesh/tet file m.vtk scale 1 move 0 0 0 rotate 0 0 0 units box\n";
    let cases: Vec<Case> = vec![
        (format!("{BASE}{tet}"), vec![("m.vtk", "# vtk DataFile Version 2.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n0 0 0\n1 0 q\n")], "in.test:6: m.vtk:7: point coordinate: expected a finite number, got 'q'"),
        (format!("{BASE}{tet}"), vec![], "cannot read tet mesh file m.vtk"),
        (format!("{BASE}region t mesh/tet file m.vtk scale 1 move 0 0 0 rotate 0 0 0\n"), vec![("m.vtk", CUBE)], "needs 'units box'"),
        (format!("{BASE}region t mesh/tet file m.vtk scale 1 shift 0 0 0 rotate 0 0 0 units box\n"), vec![("m.vtk", CUBE)], "expected keyword 'move', got 'shift'"),
        (format!("{BASE}region t mesh/tet file m.vtk scale 3 move 0 0 0 rotate 0 0 0 units box\n"), vec![("m.vtk", CUBE)], "vertices outside the simulation box"),
        (format!("{BASE}{tet}lattice hcp 0.1\n"), vec![("m.vtk", CUBE)], "in.test:7: unsupported lattice style hcp"),
        (format!("{BASE}{tet}lattice sc 0.1 origin 0.5 0.5 0.5\n"), vec![("m.vtk", CUBE)], "unsupported lattice keyword origin"),
        (format!("{BASE}{tet}lattice sc -0.1\n"), vec![("m.vtk", CUBE)], "scale must be > 0"),
        (format!("{BASE}{tet}create_atoms 1 region t\n"), vec![("m.vtk", CUBE)], "no lattice defined"),
        (format!("{BASE}{tet}lattice sc 0.1\ncreate_atoms 1 region nope\n"), vec![("m.vtk", CUBE)], "unknown region nope"),
        (format!("{BASE}{tet}lattice sc 0.1\ncreate_atoms 1 region t basis 1 1\n"), vec![("m.vtk", CUBE)], "unsupported create_atoms keyword basis"),
        (format!("{BASE}set group nope density 1 diameter 1\n"), vec![], "set group: no group nope"),
        (format!("{BASE}create_atoms 1 single 0 0 0\nfix mo all momentum 0 linear 1 1 0\n"), vec![], "N must be an integer > 0"),
        (format!("{BASE}create_atoms 1 single 0 0 0\nfix mo all momentum 1 linear 1 2 0\n"), vec![], "linear flag must be 0 or 1, got '2'"),
        (format!("{BASE}create_atoms 1 single 0 0 0\nfix mo all momentum 1 angular\n"), vec![], "unsupported fix mo momentum keyword angular"),
        (format!("{BASE}create_atoms 1 single 0 0 0\nfix mo all momentum 1 linear 1 1 0 rescale\n"), vec![], "keyword rescale"),
        (format!("{BASE}fix mo all momentum 1 linear 1 1 0\n"), vec![], "group all has no atoms"),
        (format!("{BASE}fix i nope nve/sphere\n"), vec![], "fix i nve/sphere: no group nope"),
        (format!("{BASE}fix i all nve/sphere\nfix j all nve/sphere\n"), vec![], "a second integration fix"),
        ("units si\nregion box block -1 1 -1 1 -1 1 units box\ngroup g region box\n".to_string(), vec![], "in.test:3: group g: before the simulation box exists"),
        (format!("{BASE}reset_timestep -5\n"), vec![], "in.test:6: reset_timestep: N must be >= 0"),
        (format!("{BASE}reset_timestep 5 every 2\n"), vec![], "expected 'reset_timestep N'"),
        (format!("{BASE}dump d all custom 1 x.dump id x\nreset_timestep 5\n"), vec![], "unsupported reset_timestep after a dump"),
    ];
    for (deck, files, want) in cases {
        let (ok, out) = run_deck(&deck, &files);
        assert!(!ok && out.contains("ERROR") && out.contains(want), "wanted '{want}':\n{out}");
    }
}

/// `reset_timestep` twice in a row (as in `in.insert_stream_reset_timestep`): an `insert_every 500`
/// insertion defined at step 0 is due on step 1; after `reset_timestep 0` and `reset_timestep
/// 5000` it comes on step 5001, then every 500 steps, and the thermo steps count from 5000.
#[test]
fn reset_timestep_moves_the_step_and_the_insertion_schedule() {
    let deck = format!(
        "{BASE}fix m1 all property/global youngsModulus peratomtype 5e6
fix m2 all property/global poissonsRatio peratomtype 0.3
fix m3 all property/global coefficientRestitution peratomtypepair 1 0.8
fix m4 all property/global coefficientFriction peratomtypepair 1 0.3
pair_style gran model hertz tangential history
pair_coeff * *
timestep 1e-6
neighbor 0.0002 bin
region slab block -0.5 0.5 -0.5 0.5 0.5 0.9 units box
fix pts1 all particletemplate/sphere 15485863 atom_type 1 density constant 1000 radius constant 0.01
fix pdd all particledistribution/discrete 32452843 1 pts1 1.0
fix ins all insert/pack seed 32452867 distributiontemplate pdd insert_every 500 overlapcheck yes all_in yes region slab particles_in_region 5
fix integr all nve/sphere
thermo_style custom step atoms
thermo 250
reset_timestep 0
reset_timestep 5000
run 600
"
    );
    let (ok, out) = run_deck(&deck, &[]);
    assert!(ok, "{out}");
    assert!(out.contains("inserted 5 particles at step 5001"), "{out}");
    assert!(out.contains("inserted 0 particles at step 5501") || out.contains("at step 5501"), "{out}");
    assert!(out.lines().any(|l| l.split_whitespace().collect::<Vec<_>>() == ["5600", "5"]), "{out}");
}
