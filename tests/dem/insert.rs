//! `fix particletemplate/sphere` + `fix particledistribution/discrete` + `fix insert/pack`:
//! the inserted count and mass meet the target, no two particles overlap, every particle lies in
//! the region, the same seed gives the same packing on one or two threads, and bad values stop
//! with `ERROR: FILE:LINE` naming the command.

use std::f64::consts::PI;
use std::process::Command;

/// Runs a deck in a fresh directory; returns success, stdout+stderr and the dump text (if any).
fn run_deck(text: &str, extra: &[&str]) -> (bool, String, String) {
    let (ok, all, dir) = super::deck::run_in("in.test", text, extra, &[]);
    let dump = std::fs::read_to_string(dir.path().join("out.dump")).unwrap_or_default();
    (ok, all, dump)
}

/// Rows `x y z radius mass` of the last frame of the dump, read by the project's dump parser and
/// picked by column name.
fn atoms(dump: &str) -> Vec<[f64; 5]> {
    let frames = mcdem::outputs::parse_dump(dump, "out.dump").expect("a readable dump");
    let last = frames.last().expect("a dump frame");
    let col = |n: &str| last.column(n).unwrap_or_else(|| panic!("dump has no column {n}"));
    let c = [col("x"), col("y"), col("z"), col("radius"), col("mass")];
    last.rows.iter().map(|r| c.map(|k| r[k])).collect()
}

const BASE: &str = "units si
atom_style granular
boundary f f f
region box block -0.01 0.01 -0.01 0.01 -0.01 0.01 units box
create_box 1 box
neighbor 0.0002 bin
fix m1 all property/global youngsModulus peratomtype 5e6
fix m2 all property/global poissonsRatio peratomtype 0.3
fix m3 all property/global coefficientRestitution peratomtypepair 1 0.8
fix m4 all property/global coefficientFriction peratomtypepair 1 0.3
pair_style gran model hertz tangential history
pair_coeff * *
timestep 1e-6
";

/// Two templates (constant 0.5 mm and gaussian 0.8 ± 0.05 mm radius, 1000 kg/m³), 30/70 by mass,
/// packed into `region` with `target`; dumped at the start of a zero-step run.
fn deck(region: &str, target: &str, seed: u64) -> String {
    format!(
        "{BASE}region ins {region} units box
fix pts1 all particletemplate/sphere 15485863 atom_type 1 density constant 1000 radius constant 0.0005
fix pts2 all particletemplate/sphere 15485867 atom_type 1 density constant 1000 radius gaussian 0.0008 0.00005
fix pdd all particledistribution/discrete 32452843 2 pts1 0.3 pts2 0.7
fix ins all insert/pack seed {seed} distributiontemplate pdd maxattempt 200 insert_every once overlapcheck yes all_in yes region ins {target}
fix integr all nve/sphere
dump d all custom 1 out.dump id x y z radius mass
run 0
"
    )
}

const BLOCK: &str = "block -0.008 0.008 -0.008 0.008 -0.008 0.008";

fn check_packing(p: &[[f64; 5]], inside: impl Fn(&[f64; 5]) -> bool) {
    for (i, a) in p.iter().enumerate() {
        assert!(inside(a), "particle {i} at {:?} not wholly inside the region", &a[..3]);
        for b in &p[i + 1..] {
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            // The dump prints 6 significant digits: allow that rounding (1e-5 relative).
            assert!(d >= (a[3] + b[3]) * (1.0 - 1e-5), "overlap: distance {d:e} m < {:e} m", a[3] + b[3]);
        }
    }
}

#[test]
fn count_target_is_met_without_overlap_inside_the_region() {
    let (ok, out, dump) = run_deck(&deck(BLOCK, "particles_in_region 300", 32452867), &[]);
    assert!(ok, "{out}");
    assert!(out.contains("inserted 300 particles"), "{out}");
    let p = atoms(&dump);
    assert_eq!(p.len(), 300);
    let h = 0.008;
    check_packing(&p, |a| (0..3).all(|k| a[k].abs() + a[3] <= h * (1.0 + 1e-5)));
    // Exact split by mass 30/70 through the templates' mean masses (constant: 0.5 mm; gaussian:
    // ⟨r³⟩ = μ³ + 3μσ²): number fractions 0.3/m1 : 0.7/m2, largest remainder rounding.
    let small = p.iter().filter(|a| (a[3] - 0.0005).abs() < 1e-9).count();
    let (m1, m2) = (0.0005f64.powi(3), 0.0008f64.powi(3) + 3.0 * 0.0008 * 0.00005f64.powi(2));
    let f1 = (0.3 / m1) / (0.3 / m1 + 0.7 / m2);
    assert!((small as f64 - 300.0 * f1).abs() <= 1.0, "small particles {small}, expected {:.1}", 300.0 * f1);
    // Mass column = ρ 4/3 π r³ for every particle (1e-5 relative: 6 printed digits).
    for a in &p {
        let m = 1000.0 * 4.0 / 3.0 * PI * a[3].powi(3);
        assert!((a[4] - m).abs() <= 1e-5 * m, "mass {} vs {m}", a[4]);
    }
}

#[test]
fn volume_fraction_and_mass_targets_in_cylinder_and_sphere() {
    // Volume fraction 0.2 of a cylinder r = 8 mm, 16 mm tall: the count is the target volume over
    // the mean particle volume, so the inserted volume matches within the spread of the gaussian
    // draws (σ/μ = 1/16 on r, so ≈ 3·6 % / √n on the volume: 5 % is ample for n ≈ 200).
    let cyl = "cylinder z 0 0 0.008 -0.008 0.008";
    let (ok, out, dump) = run_deck(&deck(cyl, "volumefraction_region 0.2", 7), &[]);
    assert!(ok, "{out}");
    let p = atoms(&dump);
    let vol: f64 = p.iter().map(|a| 4.0 / 3.0 * PI * a[3].powi(3)).sum();
    let target = 0.2 * PI * 0.008f64.powi(2) * 0.016;
    assert!((vol / target - 1.0).abs() < 0.05, "inserted volume {vol:e} m³ vs target {target:e} m³");
    check_packing(&p, |a| {
        (a[0] * a[0] + a[1] * a[1]).sqrt() + a[3] <= 0.008 * (1.0 + 1e-5)
            && a[2].abs() + a[3] <= 0.008 * (1.0 + 1e-5)
    });
    // Mass 0.3 g (volume fraction 0.14) into a sphere of r = 8 mm: same reasoning, 5 %.
    let (ok, out, dump) = run_deck(&deck("sphere 0 0 0 0.008", "mass_in_region 0.0003", 11), &[]);
    assert!(ok, "{out}");
    let p = atoms(&dump);
    let mass: f64 = p.iter().map(|a| a[4]).sum();
    assert!((mass / 0.0003 - 1.0).abs() < 0.05, "inserted mass {mass:e} kg vs 3e-4 kg");
    check_packing(&p, |a| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt() + a[3] <= 0.008 * (1.0 + 1e-5));
}

#[test]
fn same_seed_same_packing_on_one_or_two_threads_and_another_seed_differs() {
    let d = deck(BLOCK, "particles_in_region 200", 32452867);
    let (ok1, o1, a) = run_deck(&d, &["--threads-mode", "serial"]);
    let (ok2, o2, b) = run_deck(&d, &["--threads-mode", "parallel"]);
    let (ok3, o3, c) = run_deck(&d, &[]);
    assert!(ok1 && ok2 && ok3, "{o1}{o2}{o3}");
    assert_eq!(a, b, "serial and parallel runs differ");
    assert_eq!(a, c, "two runs with the same seed differ");
    let (ok, o, e) = run_deck(&deck(BLOCK, "particles_in_region 200", 49979687), &[]);
    assert!(ok, "{o}");
    assert_ne!(a, e, "another seed gave the same packing: the seed is not used");
}

#[test]
fn bad_values_name_the_command_and_line() {
    // Fractions not summing to 1.
    let bad = deck(BLOCK, "particles_in_region 10", 1).replace("pts1 0.3 pts2 0.7", "pts1 0.3 pts2 0.6");
    let (ok, out, _) = run_deck(&bad, &[]);
    assert!(
        !ok && out.contains("in.test:17: fix pdd particledistribution/discrete: the weights sum to 0.89"),
        "{out}"
    );
    // Radius ≤ 0.
    let bad = deck(BLOCK, "particles_in_region 10", 1).replace("radius constant 0.0005", "radius constant 0");
    let (ok, out, _) = run_deck(&bad, &[]);
    assert!(!ok && out.contains("in.test:15: fix pts1 particletemplate/sphere: radius must be > 0"), "{out}");
    // An insertion seed equal to its distribution's or a template's seed (LIGGGHTS stops at it).
    for (seed, who) in [(32452843, "distribution pdd"), (15485867, "template pts2 of distribution pdd")] {
        let (ok, out, _) = run_deck(&deck(BLOCK, "particles_in_region 10", seed), &[]);
        let needle = format!("in.test:18: fix ins insert/pack: seed {seed} is also the seed of {who}");
        assert!(!ok && out.contains(&needle), "{out}");
    }
}

/// A region that cannot hold its target: as LIGGGHTS (FixInsert::pre_exchange), a warning naming
/// the run that inserts (`Less insertions than requested`) and a short insertion, then the run goes
/// on. Until now mcdem stopped there; LIGGGHTS does not (in.movingMeshGran of the Debian tutorials
/// places 767 of 1500 and runs). The budget is LIGGGHTS' n × maxattempt tries for the whole
/// insertion, so the placed spheres still do not overlap.
#[test]
fn a_region_too_small_warns_and_inserts_what_fits() {
    // 1000 particles of ~0.7 mm in a 4 mm cube cannot fit.
    let (ok, out, dump) =
        run_deck(&deck("block 0 0.004 0 0.004 0 0.004", "particles_in_region 1000", 1), &[]);
    assert!(ok, "{out}");
    assert!(
        out.contains("WARNING: ")
            && out.contains("in.test:21: fix ins insert/pack (line 18) at step 1: Particle insertion: Less insertions than requested: placed "),
        "{out}"
    );
    let p = atoms(&dump);
    // The largest spheres go first; the budget is spent on the first that finds no room (4 here).
    assert!(!p.is_empty() && p.len() < 1000, "{} placed: {out}", p.len());
    assert!(out.contains(&format!("placed {} of 1000", p.len())), "{out}");
    check_packing(&p, |a| (0..3).all(|k| a[k] - a[3] >= -1e-8 && a[k] + a[3] <= 0.004 + 1e-8));
}

#[test]
fn shrink_wrapped_box_follows_particles_that_a_fixed_box_loses() {
    // Particles inserted moving down at 5 m/s travel 10 mm in 2000 steps of 1 µs: they leave the
    // box (z ≥ −10 mm) from a region starting at z = −8 mm. `f` loses them; `m` grows the box.
    let d = deck(BLOCK, "particles_in_region 50", 3)
        .replace("all_in yes", "all_in yes vel constant 0 0 -5")
        .replace("run 0", "run 2000");
    let (ok, out, _) = run_deck(&d, &[]);
    assert!(!ok && out.contains("lost particle"), "{out}");
    let (ok, out, dump) = run_deck(&d.replace("boundary f f f", "boundary m m m"), &[]);
    assert!(ok, "{out}");
    let p = atoms(&dump);
    assert_eq!(p.len(), 50);
    assert!(p.iter().all(|a| a[2] < -0.01 + 0.008), "the particles moved 10 mm down");
}

/// The deck of the LIGGGHTS tutorials' pattern: a group over the box, an insertion fix of that
/// group refilling a 4 mm slab every 500 steps (particles leave it at 10 m/s, 5 mm per period),
/// `fix nve/sphere` of the group; thermo every 100 steps.
fn refill_deck() -> String {
    format!(
        "{BASE}region slab block -0.008 0.008 -0.008 0.008 0.004 0.008 units box
group g region box
fix pts1 all particletemplate/sphere 15485863 atom_type 1 density constant 1000 radius constant 0.0005
fix pdd all particledistribution/discrete 32452843 1 pts1 1.0
fix ins g insert/pack seed 32452867 distributiontemplate pdd insert_every 500 overlapcheck yes all_in yes vel constant 0 0 -10 region slab particles_in_region 20
fix integr g nve/sphere
thermo_style custom step atoms vol
thermo 100
thermo_modify lost ignore norm no
run 1600
unfix ins
run 1000
"
    )
    .replace("boundary f f f", "boundary m m m")
}

/// (step, atoms, volume) of every thermo line.
fn thermo_rows(out: &str) -> Vec<(u64, usize, f64)> {
    out.lines()
        .filter_map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            match w.as_slice() {
                [s, n, v] => Some((s.parse().ok()?, n.parse().ok()?, v.parse().ok()?)),
                _ => None,
            }
        })
        .collect()
}

#[test]
fn periodic_insertion_refills_its_region_into_its_group_until_unfixed() {
    let (ok, out, _) = run_deck(&refill_deck(), &[]);
    assert!(ok, "{out}");
    let rows = thermo_rows(&out);
    let at =
        |step: u64| rows.iter().rev().find(|r| r.0 == step).unwrap_or_else(|| panic!("step {step}: {out}"));
    // As LIGGGHTS: the first insertion on the step after the definition, then every 500 steps
    // (1, 501, 1001, 1501), each filling the emptied slab back to 20.
    for (step, n) in [(0, 20), (500, 20), (600, 40), (1000, 40), (1100, 60), (1500, 60), (1600, 80)] {
        assert_eq!(at(step).1, n, "atoms at step {step}:\n{out}");
    }
    assert_eq!(out.matches("inserted 20 particles").count(), 4, "{out}");
    // After `unfix ins` nothing more comes.
    assert_eq!(at(2600).1, 80, "{out}");
    // The reported box is LIGGGHTS': the created box while every centre is inside it (m keeps it
    // as the minimum), growing once particles fall below z = -10 mm (10 m/s for 2.6 ms).
    assert_eq!(at(0).2, 8e-6, "{out}");
    assert!(at(2600).2 > 8.5e-6, "{out}");
}

#[test]
fn a_group_that_misses_particles_is_integrated_alone_and_refused_elsewhere() {
    // Particles inserted into `all` are not in `g`: nve/sphere of `g` leaves them where they were
    // inserted (as LIGGGHTS), so none falls out of the created box, and the refills find the slab
    // full.
    let d = refill_deck().replace("fix ins g insert/pack", "fix ins all insert/pack");
    let (ok, out, _) = run_deck(&d, &[]);
    assert!(ok, "{out}");
    let rows = thermo_rows(&out);
    let last = rows.last().unwrap();
    assert_eq!((last.0, last.1, last.2), (2600, 20, 8e-6), "{out}");
    // A compute acts on every particle: of `g`, it is refused.
    let d = d.replace("fix integr g nve/sphere", "fix integr g nve/sphere\ncompute k g ke");
    let (ok, out, _) = run_deck(&d, &[]);
    assert!(!ok && out.contains("compute k ke on group g, which does not hold every particle"), "{out}");
    assert!(out.contains("in.test:"), "file and line: {out}");
    // A particle added after a compute acts on `g`, outside it.
    let d = refill_deck()
        .replace("fix integr g nve/sphere", "fix integr g nve/sphere\ncompute k g ke")
        .replace("run 1600", "create_atoms 1 single 0 0 0 units box\nrun 1600");
    let (ok, out, _) = run_deck(&d, &[]);
    assert!(!ok && out.contains("compute k ke acts on group g"), "{out}");
    // Group styles other than region, and unknown groups.
    for (from, to, says) in [
        ("group g region box", "group g type 1", "group style type"),
        ("group g region box", "group g region nowhere", "unknown region nowhere"),
        ("fix integr g nve/sphere", "fix integr h nve/sphere", "no group h"),
    ] {
        let (ok, out, _) = run_deck(&refill_deck().replace(from, to), &[]);
        assert!(!ok && out.contains(says), "{to}: {out}");
    }
}

/// A 10 mm square insertion face (two triangles) at z = 10 mm, normal +z by its vertex order.
const FACE_STL: &str = "solid face
facet normal 0 0 1
 outer loop
  vertex -0.005 -0.005 0.01
  vertex 0.005 -0.005 0.01
  vertex 0.005 0.005 0.01
 endloop
endfacet
facet normal 0 0 1
 outer loop
  vertex -0.005 -0.005 0.01
  vertex 0.005 0.005 0.01
  vertex -0.005 0.005 0.01
 endloop
endfacet
endsolid face
";

/// `insert/stream` of 0.3 mm spheres (1000 kg/m³) through the face, vel (0.5, 0, -1) m/s,
/// extruded 2 mm: K = 2 mm / (1 m/s · 10 µs) = 200 steps. No gravity: after release every
/// particle keeps its velocity.
fn stream_deck(rate: &str, total: &str, steps: u64, dump_every: u64) -> String {
    format!(
        "units si
atom_style granular
boundary f f f
region box block -0.02 0.02 -0.01 0.01 -0.03 0.02 units box
create_box 1 box
neighbor 0.0002 bin
fix m1 all property/global youngsModulus peratomtype 5e6
fix m2 all property/global poissonsRatio peratomtype 0.3
fix m3 all property/global coefficientRestitution peratomtypepair 1 0.8
fix m4 all property/global coefficientFriction peratomtypepair 1 0.3
pair_style gran model hertz tangential history
pair_coeff * *
timestep 1e-5
fix face all mesh/surface file face.stl type 1
fix pts1 all particletemplate/sphere 15485863 atom_type 1 density constant 1000 radius constant 0.0003
fix pdd all particledistribution/discrete 32452843 1 pts1 1.0
fix ins all insert/stream seed 32452867 distributiontemplate pdd {total} {rate} overlapcheck yes all_in no vel constant 0.5 0 -1 insertion_face face extrude_length 0.002
fix integr all nve/sphere
dump d all custom {dump_every} out.dump id x y z vx vy vz radius mass
run {steps}
"
    )
}

/// Runs a stream deck with the face mesh beside it; success, output and the dump frames.
fn run_stream(text: &str) -> (bool, String, Vec<mcdem::outputs::Frame>) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("face.stl"), FACE_STL).unwrap();
    std::fs::write(dir.path().join("in.test"), text).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .current_dir(dir.path())
        .args(["run", "in.test", "-log", "none"])
        .output()
        .unwrap();
    let all = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    let dump = std::fs::read_to_string(dir.path().join("out.dump")).unwrap_or_default();
    let frames =
        if dump.is_empty() { Vec::new() } else { mcdem::outputs::parse_dump(&dump, "out.dump").unwrap() };
    (o.status.success(), all, frames)
}

const SPHERE_MASS: f64 = 1000.0 * 4.0 / 3.0 * PI * 0.0003 * 0.0003 * 0.0003;

#[test]
fn stream_inserts_the_rate_into_the_extruded_face_and_releases_at_the_face() {
    // particlerate 10 000/s × 200 steps × 10 µs = 20 per insertion (a whole number: no random
    // rounding), at steps 1, 201, 401, 601 until nparticles 70: 20, 20, 20, 10.
    let (ok, out, frames) = run_stream(&stream_deck("particlerate 10000", "nparticles 70", 700, 1));
    assert!(ok, "{out}");
    let count = |s: u64| frames.iter().find(|f| f.step == s).map(|f| f.rows.len()).unwrap();
    assert_eq!(
        [count(1), count(200), count(201), count(401), count(601), count(700)],
        [20, 20, 40, 60, 70, 70]
    );
    let mut seen = std::collections::HashMap::new();
    let (r, dt) = (0.0003, 1e-5);
    for f in &frames {
        let c = |n: &str| f.column(n).unwrap();
        let (id, x, y, z, vx, vy, vz, rad, mass) =
            (c("id"), c("x"), c("y"), c("z"), c("vx"), c("vy"), c("vz"), c("radius"), c("mass"));
        for row in &f.rows {
            assert!((row[mass] - SPHERE_MASS).abs() < 1e-5 * SPHERE_MASS && (row[rad] - r).abs() < 1e-9);
            let v = [row[vx], row[vy], row[vz]];
            if seen.insert(row[id] as i64, f.step).is_none() {
                // First seen: at its insertion step (the first comes with the run's set-up, step
                // 0, as insert/pack), in the face's square, r … L + r above it, flying at the
                // velocity's normal part (0, 0, -1).
                assert!(f.step % 200 == 1 || f.step == 0, "particle {} appeared at step {}", row[id], f.step);
                assert!(row[x].abs() <= 0.005 + 1e-9 && row[y].abs() <= 0.005 + 1e-9, "{row:?}");
                assert!(row[z] >= 0.01 + r - 1e-9 && row[z] <= 0.01 + 0.002 + r + 1e-9, "{row:?}");
                assert_eq!(v, [0.0, 0.0, -1.0], "{row:?}");
            } else if row[z] > 0.01 + dt + 1e-9 {
                // Still behind the face (released within the last step's travel before it, on
                // step ⌊depth / (|v_n| Δt)⌋ after insertion): straight on at (0, 0, -1).
                assert_eq!(v, [0.0, 0.0, -1.0], "step {}: {row:?}", f.step);
            } else if row[z] < 0.01 - 1e-9 {
                // Through the face: released at the insertion velocity.
                assert!((v[0] - 0.5).abs() < 1e-9 && v[1] == 0.0 && (v[2] + 1.0).abs() < 1e-9, "{row:?}");
            }
        }
        // No two particles overlap (the dump prints 6 digits: 1e-5 relative).
        let p: Vec<[f64; 5]> = f.rows.iter().map(|w| [w[x], w[y], w[z], w[rad], w[mass]]).collect();
        check_packing(&p, |_| true);
    }
    assert_eq!(seen.len(), 70);
    assert!(
        out.contains("inserted 20 particles at step 601")
            || out.contains("inserted 10 particles at step 601"),
        "{out}"
    );
}

#[test]
fn stream_massrate_gives_the_mean_count_per_insertion() {
    // massrate = 12.5 particles per insertion: ⌊12.5 + u⌋ is 12 or 13, mean 12.5; ten insertions
    // (steps 1, 201, …, 1801) hold 125 ± 5 (the standard deviation of the sum is √10/2 ≈ 1.6).
    let rate = 12.5 / (200.0 * 1e-5) * SPHERE_MASS;
    let (ok, out, frames) =
        run_stream(&stream_deck(&format!("massrate {rate:e}"), "nparticles INF", 2000, 200));
    assert!(ok, "{out}");
    let counts: Vec<usize> = frames.iter().map(|f| f.rows.len()).collect();
    assert_eq!(counts.len(), 11, "frames at 0, 200, …, 2000");
    for w in counts.windows(2).skip(1) {
        assert!(w[1] - w[0] == 12 || w[1] - w[0] == 13, "{counts:?}");
    }
    let n = counts[10] as f64;
    assert!((n - 125.0).abs() <= 5.0, "{counts:?}");
    let m: f64 = frames[10].rows.iter().map(|r| r[frames[10].column("mass").unwrap()]).sum();
    assert!((m - n * SPHERE_MASS).abs() < 1e-5 * m, "mass {m:e} for {n} particles");
}

#[test]
fn stream_bad_keywords_stop_with_file_and_line() {
    let good = stream_deck("particlerate 10000", "nparticles 70", 10, 10);
    for (from, to, says) in [
        ("all_in no", "all_in no bogus 3", "keyword bogus"),
        ("all_in no", "all_in yes", "all_in yes"),
        ("extrude_length 0.002", "extrude_length 0.002 insert_every 100", "exclude each other"),
        ("extrude_length 0.002", "extrude_length 0.0005", "below 3 particle radii"),
        ("insertion_face face", "insertion_face nothere", "nothere is not a mesh/surface fix"),
        ("vel constant 0.5 0 -1", "vel constant 1 0 0", "projected on the face normal"),
    ] {
        let (ok, out, _) = run_stream(&good.replace(from, to));
        assert!(!ok && out.contains("ERROR: in.test:17:") && out.contains(says), "{to}: {out}");
    }
}

/// The keywords both insertion fixes read through one parser (`src/deck/fixes/insert_common.rs`)
/// stop each fix with the same message, naming the deck line and the fix.
#[test]
fn common_insertion_keywords_stop_both_fixes_alike() {
    let pack = deck(BLOCK, "particles_in_region 10", 1);
    let stream = stream_deck("particlerate 10000", "nparticles 70", 10, 10);
    let pack_seed = "seed 1 distributiontemplate pdd";
    let stream_seed = "seed 32452867 distributiontemplate pdd";
    for (to, says) in [
        ("seed -3 distributiontemplate pdd", "seed must be a whole number >= 0, got '-3'"),
        ("seed 7 distributiontemplate nope", "nope is not a particledistribution/discrete fix"),
        (
            "seed 7 distributiontemplate pdd random_distribute sometimes",
            "random_distribute must be exact or uncorrelated, got 'sometimes'",
        ),
        ("seed 7 distributiontemplate pdd vel constant 1 x 0", "expected a number, got \"x\""),
    ] {
        let (ok, out, _) = run_deck(&pack.replace(pack_seed, to), &[]);
        let needle = if says.starts_with("expected") {
            format!("in.test:18: {says}")
        } else {
            format!("in.test:18: fix ins insert/pack: {says}")
        };
        assert!(!ok && out.contains(&needle), "pack, {to}: {out}");
        let (ok, out, _) = run_stream(&stream.replace(stream_seed, to));
        let needle = needle.replace("in.test:18: fix ins insert/pack", "in.test:17: fix ins insert/stream");
        let needle = needle.replace("in.test:18: expected", "in.test:17: expected");
        assert!(!ok && out.contains(&needle), "stream, {to}: {out}");
    }
}

#[test]
fn dump_mesh_stl_writes_the_moved_mesh_read_back() {
    // The face mesh moved up at 0.1 m/s: 50 steps of 10 µs lift it by 50 µm per frame.
    let deck = stream_deck("particlerate 10000", "nparticles 70", 100, 50)
        .replace("fix ins all insert/stream", "#")
        .replace(
            "run 100",
            "fix mv all move/mesh mesh face linear 0 0 0.1\ndump st all mesh/stl 50 post*.stl face\nrun 100",
        );
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("face.stl"), FACE_STL).unwrap();
    std::fs::write(dir.path().join("in.test"), &deck).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .current_dir(dir.path())
        .args(["run", "in.test", "-log", "none"])
        .output()
        .unwrap();
    let out = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{out}");
    let face = mcdem::engine::mesh::read_stl(&dir.path().join("face.stl")).unwrap();
    for step in [0u32, 50, 100] {
        let path = dir.path().join(format!("post{step}.stl"));
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.starts_with("solid LIGGGHTS_STL_EXPORT\n")
                && text.ends_with("endsolid LIGGGHTS_STL_EXPORT\n")
        );
        assert_eq!(text.matches("facet normal 0 0 1\n").count(), 2, "{text}");
        let tris = mcdem::engine::mesh::read_stl(&path).unwrap();
        assert_eq!(tris.len(), face.len());
        let dz = 0.1 * 1e-5 * step as f64;
        for (t, f) in tris.iter().zip(&face) {
            for (a, b) in t.iter().zip(f) {
                // %g: 6 significant digits.
                assert!((a.x - b.x).abs() < 1e-8 && (a.y - b.y).abs() < 1e-8, "{a:?} {b:?}");
                assert!((a.z - b.z - dz).abs() < 1e-7, "step {step}: z {} vs {}", a.z, b.z + dz);
            }
        }
    }
    // A moving insertion face is refused, as LIGGGHTS does.
    let moving = stream_deck("particlerate 10000", "nparticles 70", 10, 10)
        .replace("fix integr", "fix mv all move/mesh mesh face linear 0 0 0.1\nfix integr");
    let (ok, out, _) = run_stream(&moving);
    assert!(!ok && out.contains("move/mesh") && out.contains("in.test:"), "{out}");
}
