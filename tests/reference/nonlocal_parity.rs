//! Parity of two independent codes (docs/spec.md §4, consequence b): standard MC with prefactor γ, relaxed
//! to rest by the Rust DEM with strong damping and no friction, is a lagged fixed-point iteration
//! of the nonlocal relation with kernel γ·G (boussinesq), so at rest the two must agree up to the
//! second-order differences of docs/spec.md §2 (MC evaluates R_eff with the modified radii and the
//! half-space term at the current contact points). Scene: the 9-particle bcc cell in the die of
//! `liggghts_inputs/bcc_box.in`, top plate lowered by 0.3 r; and 50 polydisperse spheres compressed
//! in a box past jamming, whose DEM rest state is handed to the nonlocal solver at the same wall
//! positions. Tolerance 2 % of each wall force.
//!
//! Measured: bcc 0.68 %; packing at φ = 0.52 (wall forces ~1e-3 N, Hertz overlaps ~15 % of r)
//! 0.45 %. With γ = 0 the packing agrees to 1e-6. The difference grows with the deformation
//! (φ = 0.55: 1.8 %, 0.58: 2.8 %, 0.62: 6 %, 0.66: 8.4 %): when the radius changes reach tens of
//! per cent of r, MC's modified radii in R_eff and its contact points inside the sphere are no
//! longer second order.

use std::path::Path;
use std::process::Command;

use mcdem::nonlocal::{Kernel, KernelKind, Nonlocal, Settings, Sphere, Wall};
use mcdem::physics::material::Material;
use mcdem::physics::Vec3;

const R: f64 = 1e-3;
const GAMMA: f64 = 0.82;

/// The bcc deck with restitution 0.05 and no friction, the plate stopped at 0.3 r and held for
/// 20000 steps; returns the (plate, side-wall) forces at rest [N].
fn dem_at_rest() -> (f64, f64) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("liggghts_inputs");
    let dir = tempfile::tempdir().unwrap();
    let decks = dir.path().join("decks");
    std::fs::create_dir_all(decks.join("meshes")).unwrap();
    for f in ["bcc_box.in", "die_common.inc", "die_run.inc", "select_law.inc", "meshes/die_face.stl"] {
        std::fs::copy(src.join(f), decks.join(f)).unwrap();
    }
    let mut run = std::fs::read_to_string(decks.join("die_run.inc")).unwrap();
    run.push_str("unfix pmove\nrun 20000\n");
    std::fs::write(decks.join("die_run.inc"), run).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .current_dir(dir.path())
        .arg("run")
        .arg(decks.join("bcc_box.in"))
        .args(["-log", "none", "-var", "law", "0", "-var", "mpr", "1e9", "-var", "gamma", &GAMMA.to_string()])
        .args(["-var", "e", "0.05", "-var", "mu", "0"])
        .args(["-var", "every", "100", "-var", "dir"])
        .arg(&decks)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let rows = mcdem::outputs::read_ave_time(&dir.path().join("bcc_box.txt")).unwrap();
    let (last, before) = (&rows[rows.len() - 1], &rows[rows.len() - 11]);
    // At rest: the forces no longer change over the last 1000 steps.
    assert!((last[2] - before[2]).abs() <= 1e-6 * last[2], "plate force still moving: {before:?} {last:?}");
    (last[2], -last[3])
}

fn nonlocal_at(delta: f64) -> (f64, f64) {
    let a = 2.0 * R * (1.0 + 2.0 / 3.0_f64.sqrt());
    let m = Material::hertz(23.3e3, 0.5).unwrap();
    let mut spheres = Vec::new();
    for (k, c) in [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1), (1, 1, 1)]
        .iter()
        .enumerate()
    {
        let p = |i: i32| if i == 0 { R } else { a - R };
        spheres.push(Sphere {
            id: k as u64 + 1,
            x: Vec3::new(p(c.0), p(c.1), p(c.2)),
            radius: R,
            material: m,
        });
    }
    spheres.push(Sphere { id: 9, x: Vec3::repeat(a / 2.0), radius: R, material: m });
    let walls = Wall::rigid_box(a, a, a, "top");
    let kernel = Kernel::new(KernelKind::Boussinesq, GAMMA).unwrap();
    let mut s =
        Nonlocal::new(&spheres, &walls, Material::hertz(50e6, 0.5).unwrap(), kernel, Settings::default())
            .unwrap();
    let steps = 12;
    let path = |t: f64| {
        let points = walls
            .iter()
            .enumerate()
            .map(|(k, wall)| if k == 5 { wall.point - Vec3::z() * (t * delta) } else { wall.point })
            .collect();
        (points, 0.0)
    };
    for k in 1..=steps {
        let st = s.advance(&path, (k - 1) as f64 / steps as f64, k as f64 / steps as f64).unwrap();
        assert!(st.residual <= 1e-9, "step {k}: residual {}", st.residual);
    }
    let f = s.wall_forces();
    (-f[5].dot(&walls[5].normal), -f[0].dot(&walls[0].normal))
}

#[test]
fn standard_mc_at_rest_is_the_nonlocal_solution_with_gamma_g() {
    let (plate_dem, side_dem) = dem_at_rest();
    let (plate_nl, side_nl) = nonlocal_at(0.3 * R);
    let (ep, es) = ((plate_dem / plate_nl - 1.0).abs(), (side_dem / side_nl - 1.0).abs());
    eprintln!("bcc, γ = {GAMMA}, Δ = 0.3 r: plate DEM {plate_dem:.5e} N vs nonlocal {plate_nl:.5e} N ({:.2} %), side {side_dem:.5e} vs {side_nl:.5e} ({:.2} %)", 100.0 * ep, 100.0 * es);
    assert!(ep <= 0.02 && es <= 0.02, "plate {ep:e}, side {es:e}");
}

/// 50 spheres (r = 1 mm ± 10 %) on a jittered 3×3×6 grid in a 6.6 mm square box, compressed by the
/// top plate to φ ≈ 0.52 and held until rest (forces steady to 1e-4 over the last 1000 steps) (DEM, standard MC γ, no friction, restitution 0.05).
/// Returns the spheres at rest, the plate height and the (top, bottom, x = 0) wall forces.
fn random_packing_at_rest(dir: &Path) -> (Vec<(Vec3, f64)>, f64, [f64; 3]) {
    let (l, h0) = (6.6e-3, 13.2e-3);
    let mut rng = mcdem::rng::Lcg64(7);
    let mut rnd = move || rng.symmetric();
    let mut atoms = String::new();
    let mut vol = 0.0;
    let mut id = 0;
    for k in 0..6 {
        for j in 0..3 {
            for i in 0..3 {
                if id == 50 {
                    continue; // the top layer keeps 5 of its 9 sites
                }
                id += 1;
                let r = R * (1.0 + 0.1 * rnd());
                vol += 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
                let mut c = |n: usize| (n as f64 + 0.5) * 2.2e-3 + 0.05e-3 * rnd();
                let (x, y, z) = (c(i), c(j), c(k));
                atoms.push_str(&format!("{id} 1 {} 1000 {x} {y} {z}\n", 2.0 * r));
            }
        }
    }
    assert_eq!(id, 50);
    let h = vol / (0.52 * l * l);
    let data = format!(
        "packing\n\n50 atoms\n2 atom types\n\n-0.001 {} xlo xhi\n-0.001 {} ylo yhi\n-0.001 {} zlo zhi\n\nAtoms\n\n{atoms}",
        l + 1e-3,
        l + 1e-3,
        h0 + 2e-3
    );
    std::fs::write(dir.join("packing.data"), data).unwrap();
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("liggghts_inputs/meshes/die_face.stl");
    let steps = ((h0 - h) / 0.05 / 1e-5).round();
    let deck = format!(
        "atom_style sphere\natom_modify map array\nboundary f f f\nnewton off\ncommunicate single vel yes\nunits si\n\
         read_data packing.data\nneighbor 0.0002 bin\nneigh_modify delay 0\n\
         fix m1 all property/global youngsModulus peratomtype 23.3e3 5e7\n\
         fix m2 all property/global poissonsRatio peratomtype 0.5 0.5\n\
         fix m3 all property/global coefficientRestitution peratomtypepair 2 0.05 0.05 0.05 0.05\n\
         fix m4 all property/global coefficientFriction peratomtypepair 2 0 0 0 0\n\
         fix m5 all property/global geometricPrefactor peratomtype {GAMMA} {GAMMA}\n\
         fix m6 all property/global maxPenetrationRatio peratomtype 1e9 1e9\n\
         pair_style gran model mc_advanced tangential history\npair_coeff * *\ntimestep 1e-5\n\
         fix xhi all wall/gran model mc_advanced tangential history primitive type 2 xplane {l}\n\
         fix ylo all wall/gran model mc_advanced tangential history primitive type 2 yplane 0.0\n\
         fix yhi all wall/gran model mc_advanced tangential history primitive type 2 yplane {l}\n\
         fix bot_m all mesh/surface/stress file {m} type 2 scale {l}\n\
         fix side_m all mesh/surface/stress file {m} type 2 rotate axis 0 1 0 angle -90 scale {h0}\n\
         fix top_m all mesh/surface/stress file {m} type 2 scale {l} move 0.0 0.0 {h0}\n\
         fix meshes all wall/gran model mc_advanced tangential history mesh n_meshes 3 meshes bot_m side_m top_m\n\
         fix integr all nve/sphere\n\
         fix out all ave/time 1 100 100 f_top_m[3] f_bot_m[3] f_side_m[1] file forces.txt\n\
         fix pmove all move/mesh mesh top_m linear 0.0 0.0 -0.05\nrun {steps}\nunfix pmove\nrun 80000\n\
         dump d all custom 1 rest.dump id x y z radius\nrun 0\n",
        m = mesh.display()
    );
    std::fs::write(dir.join("packing.in"), deck).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .current_dir(dir)
        .args(["run", "packing.in", "-log", "none"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let rows = mcdem::outputs::read_ave_time(&dir.join("forces.txt")).unwrap();
    let (last, before) = (&rows[rows.len() - 1], &rows[rows.len() - 11]);
    assert!((last[1] - before[1]).abs() <= 1e-4 * last[1].abs(), "not at rest: {before:?} {last:?}");
    let frame = mcdem::outputs::read_dump(&dir.join("rest.dump")).unwrap().pop().unwrap();
    let spheres = frame.rows.iter().map(|r| (Vec3::new(r[1], r[2], r[3]), r[4])).collect();
    (spheres, h0 - 0.05 * 1e-5 * steps, [last[1], -last[2], -last[3]])
}

#[test]
fn random_packing_rest_state_is_a_nonlocal_equilibrium() {
    let dir = tempfile::tempdir().unwrap();
    let (spheres, top, dem) = random_packing_at_rest(dir.path());
    let l = 6.6e-3;
    let m = Material::hertz(23.3e3, 0.5).unwrap();
    let spheres: Vec<Sphere> = spheres
        .iter()
        .enumerate()
        .map(|(k, (x, r))| Sphere { id: k as u64 + 1, x: *x, radius: *r, material: m })
        .collect();
    let walls = Wall::rigid_box(l, l, top, "top");
    let kernel = Kernel::new(KernelKind::Boussinesq, GAMMA).unwrap();
    let mut s =
        Nonlocal::new(&spheres, &walls, Material::hertz(50e6, 0.5).unwrap(), kernel, Settings::default())
            .unwrap();
    let fixed = |_: f64| (walls.iter().map(|w| w.point).collect(), 0.0);
    let st = s.advance(&fixed, 0.0, 1.0).unwrap();
    assert!(st.residual <= 1e-9, "residual {}", st.residual);
    let f = s.wall_forces();
    let nl = [-f[5].dot(&walls[5].normal), -f[4].dot(&walls[4].normal), -f[0].dot(&walls[0].normal)];
    let mut errors = Vec::new();
    for (k, name) in ["top", "bottom", "x = 0"].iter().enumerate() {
        let e = (dem[k] / nl[k] - 1.0).abs();
        eprintln!(
            "50 spheres, γ = {GAMMA}: {name} wall DEM {:.5e} N vs nonlocal {:.5e} N ({:.2} %)",
            dem[k],
            nl[k],
            100.0 * e
        );
        errors.push((name, dem[k], e));
    }
    for (name, f, e) in errors {
        assert!(f > 0.0 && e <= 0.02, "{name}: DEM force {f} N, relative difference {e}");
    }
}
