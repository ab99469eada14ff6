//! Lees–Edwards simple shear (`fix deform … xy erate … remap v`) and the stress/coordination
//! computes: hand-computable static lattice, streaming profile, momentum.

use std::process::Command;

fn run(dir: &std::path::Path, deck: &str) -> String {
    std::fs::write(dir.join("in.t"), deck).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .current_dir(dir)
        .args(["run", "in.t", "-log", "none", "--no-progress"])
        .output()
        .unwrap();
    let s = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{s}");
    s
}

/// Simple cubic lattice of n³ spheres of diameter d, spacing a, in a periodic cube of side n a.
fn lattice(dir: &std::path::Path, n: usize, a: f64, d: f64, jitter: f64) {
    let mut s = format!(
        "lattice\n\n{} atoms\n1 atom types\n0 {l} xlo xhi\n0 {l} ylo yhi\n0 {l} zlo zhi\n\nAtoms\n\n",
        n * n * n,
        l = n as f64 * a
    );
    let mut id = 1;
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                // Small deterministic jitter off the grid keeps a sheared lattice from locking.
                let jit = if jitter > 0.0 { 1e-3 } else { 0.0 } * a * (((id * 7919) % 13) as f64 - 6.0) / 6.0;
                s += &format!(
                    "{id} 1 {d} 1000 {} {} {}\n",
                    (i as f64 + 0.5) * a + jit,
                    (j as f64 + 0.5) * a,
                    (k as f64 + 0.5) * a - jit
                );
                id += 1;
            }
        }
    }
    // Pseudo-random vy, vz of amplitude `jitter` m/s with zero mean: collisions between the
    // sliding lattice rows (vx comes from the velocity ramp).
    let nat = n * n * n;
    let mut rng = mcdem::rng::Lcg64(12345);
    let mut rnd = || rng.uniform() - 0.5;
    let v: Vec<(f64, f64)> = (0..nat).map(|_| (rnd() * jitter, rnd() * jitter)).collect();
    let (my, mz) = v.iter().fold((0.0, 0.0), |a, b| (a.0 + b.0 / nat as f64, a.1 + b.1 / nat as f64));
    s += "\nVelocities\n\n";
    for (i, (vy, vz)) in v.iter().enumerate() {
        s += &format!("{} 0 {} {} 0 0 0\n", i + 1, vy - my, vz - mz);
    }
    std::fs::write(dir.join("data.lat"), s).unwrap();
}

const HEAD: &str = "units si
atom_style sphere
boundary p p p
read_data data.lat
neighbor 0.0002 bin
fix m1 all property/global youngsModulus peratomtype 1e7
fix m2 all property/global poissonsRatio peratomtype 0.3
fix m3 all property/global coefficientRestitution peratomtypepair 1 E
fix m4 all property/global coefficientFriction peratomtypepair 1 MU
pair_style gran model hertz tangential history
pair_coeff * *
timestep 1e-6
fix integr all nve/sphere
compute s all stress/mcdem
compute z all coord/mcdem
";

fn last_thermo(out: &str, ncol: usize) -> Vec<f64> {
    out.lines()
        .rev()
        .find_map(|l| {
            let v: Vec<f64> = l.split_whitespace().filter_map(|t| t.parse().ok()).collect();
            (v.len() == ncol && l.split_whitespace().count() == ncol).then_some(v)
        })
        .expect("thermo line")
}

#[test]
fn compressed_cubic_lattice_pressure_and_coordination() {
    let dir = tempfile::tempdir().unwrap();
    let (n, d, a) = (4, 0.002, 0.002 * 0.99);
    lattice(dir.path(), n, a, d, 0.0);
    let deck = HEAD.replace("E\n", "0.9\n").replace("MU\n", "0.0\n")
        + "thermo_style custom step c_z c_s c_s[11] c_s[12] c_s[2] c_s[4]\nthermo 1\nrun 0\n";
    let out = run(dir.path(), &deck);
    let v = last_thermo(&out, 7);
    // Hertz by hand: E* = E / (2 (1 − ν²)), R = d/4, δ = d − a, F = 4/3 E* √(R δ) δ, p = F / a².
    let es = 1e7 / (2.0 * (1.0 - 0.09));
    let delta = d - a;
    let f = 4.0 / 3.0 * es * (d / 4.0 * delta).sqrt() * delta;
    let p = f / (a * a);
    assert!((v[1] - 6.0).abs() < 1e-12, "Z = {}", v[1]);
    assert!(((v[3] - p) / p).abs() < 1e-3, "contact p {} vs {p}", v[3]);
    assert!(v[5].abs() < 1e-9 * p && v[6].abs() < 1e-9 * p, "off-diagonal {} {}", v[5], v[6]);
}

#[test]
fn lees_edwards_streaming_profile_and_momentum() {
    let dir = tempfile::tempdir().unwrap();
    // 343 spheres, φ ≈ 0.39 (gas-like), γ̇ = 50 /s.
    let (n, d, a) = (7, 0.002, 0.0022);
    lattice(dir.path(), n, a, d, 0.5);
    let l = n as f64 * a;
    let rate = 50.0;
    let deck = HEAD.replace("E\n", "0.7\n").replace("MU\n", "0.5\n")
        + &format!(
            "velocity all ramp vx {} {} y 0 {l} units box\n\
             fix sh all deform 1 xy erate {rate} remap v\n\
             thermo_style custom step c_z c_s[2] c_s[4] c_s[10]\nthermo 5000\n\
             run 40000\n\
             dump d all custom 40000 dump.sh id x y z vx vy vz\n\
             dump_modify d format \"%d %.15g %.15g %.15g %.15g %.15g %.15g\"\n\
             run 0\n",
            -0.5 * rate * l,
            0.5 * rate * l
        );
    let _ = run(dir.path(), &deck);
    let rows = mcdem::outputs::read_dump(&dir.path().join("dump.sh")).unwrap().pop().unwrap().rows;
    assert_eq!(rows.len(), n * n * n);
    // Momentum: the peculiar momentum Σ m (v − u(y)) is what Lees–Edwards conserves (a particle
    // crossing the sheared boundary changes v_x and u_x by the same jump); it starts at zero.
    // Positions are not yet wrapped between rebuilds, so y and v_x stay consistent.
    let ymid = 0.5 * l;
    let vscale = rate * l;
    let m: Vec<f64> = (4..7)
        .map(|c| {
            let u = |r: &Vec<f64>| if c == 4 { rate * (r[2] - ymid) } else { 0.0 };
            rows.iter().map(|r| r[c] - u(r)).sum::<f64>() / rows.len() as f64
        })
        .collect();
    eprintln!("mean peculiar velocity {m:?} (scale {vscale})");
    assert!(m.iter().all(|x| x.abs() < 1e-10 * vscale), "mean peculiar velocity {m:?}");
    // Streaming profile: least-squares slope of vx(y) ≈ γ̇.
    let pts: Vec<(f64, f64)> = rows.iter().map(|r| (r[2], r[4])).collect();
    let nn = pts.len() as f64;
    let (my, mv) = (pts.iter().map(|p| p.0).sum::<f64>() / nn, pts.iter().map(|p| p.1).sum::<f64>() / nn);
    let sxy: f64 = pts.iter().map(|p| (p.0 - my) * (p.1 - mv)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - my).powi(2)).sum();
    let slope = sxy / sxx;
    // The fit's standard error from the scatter of the peculiar velocities (collisional heating):
    // the bound is 4 standard errors (a correct code fails it with probability ~6e-5 on a
    // different trajectory, e.g. another vector path), and the scatter must stay small enough for
    // that bound to catch a wrong streaming term (SE below 2 % of γ̇; measured slope 50.10 /s,
    // i.e. 0.2 % off).
    let ss: f64 = pts.iter().map(|p| (p.1 - mv - slope * (p.0 - my)).powi(2)).sum();
    let se = (ss / (nn - 2.0) / sxx).sqrt();
    eprintln!("slope {slope} ± {se} vs {rate}");
    assert!(se < 0.02 * rate, "the profile's scatter is too large for the test: SE {se}");
    assert!((slope - rate).abs() < 4.0 * se, "profile slope {slope} ± {se} vs γ̇ = {rate}");
}

/// FCC start of 4·nc³ spheres at packing fraction phi in a periodic cube, with zero-mean
/// pseudo-random velocities of 0.1 m/s; returns the box side.
fn fcc(dir: &std::path::Path, nc: usize, phi: f64, d: f64) -> f64 {
    let n = 4 * nc * nc * nc;
    let l = (n as f64 * std::f64::consts::PI * d.powi(3) / 6.0 / phi).cbrt();
    let a = l / nc as f64;
    let mut rng = mcdem::rng::Lcg64(99);
    let mut rnd = || 0.2 * (rng.uniform() - 0.5);
    let mut s =
        format!("fcc\n\n{n} atoms\n1 atom types\n0 {l} xlo xhi\n0 {l} ylo yhi\n0 {l} zlo zhi\n\nAtoms\n\n");
    let mut id = 1;
    for x in 0..nc {
        for y in 0..nc {
            for z in 0..nc {
                for b in [[0.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.5, 0.0, 0.5], [0.0, 0.5, 0.5]] {
                    let p = [x as f64 + b[0] + 0.25, y as f64 + b[1] + 0.25, z as f64 + b[2] + 0.25];
                    s += &format!("{id} 1 {d} 1000 {} {} {}\n", p[0] * a, p[1] * a, p[2] * a);
                    id += 1;
                }
            }
        }
    }
    let v: Vec<[f64; 3]> = (0..n).map(|_| [rnd(), rnd(), rnd()]).collect();
    let m: Vec<f64> = (0..3).map(|k| v.iter().map(|w| w[k]).sum::<f64>() / n as f64).collect();
    s += "\nVelocities\n\n";
    for (i, w) in v.iter().enumerate() {
        s += &format!("{} {} {} {} 0 0 0\n", i + 1, w[0] - m[0], w[1] - m[1], w[2] - m[2]);
    }
    std::fs::write(dir.join("data.lat"), s).unwrap();
    l
}

/// Steady shear of 256 frictionless spheres at φ = 0.5 (below jamming): time averages of
/// Z, p, σ_xy, σ_yx over the second half of 40 000 steps of 2 µs (strain 0.8 per half at γ̇ = 20 /s).
fn sheared_gas(rate: f64) -> Vec<f64> {
    let dir = tempfile::tempdir().unwrap();
    let l = fcc(dir.path(), 4, 0.5, 0.002);
    let deck =
        HEAD.replace("E\n", "0.7\n").replace("MU\n", "0.0\n").replace("timestep 1e-6", "timestep 2e-6")
            + &format!(
                "velocity all ramp vx {} {} y 0 {l} sum yes units box\n\
             fix sh all deform 1 xy erate {rate} remap v\n\
             thermo 0\nrun 20000\n\
             fix av all ave/time 10 2000 20000 c_z c_s c_s[2] c_s[4] file ave.txt\n\
             run 20000\n",
                -0.5 * rate * l,
                0.5 * rate * l
            );
    let _ = run(dir.path(), &deck);
    let text = std::fs::read_to_string(dir.path().join("ave.txt")).unwrap();
    let last = text.lines().next_back().unwrap();
    last.split_whitespace().skip(1).map(|t| t.parse().unwrap()).collect()
}

#[test]
fn kinetic_regime_pressure_scales_with_rate_squared_and_stress_is_symmetric() {
    let slow = sheared_gas(20.0);
    let fast = sheared_gas(80.0);
    eprintln!("γ̇ = 20: {slow:?}\nγ̇ = 80: {fast:?}");
    for s in [&slow, &fast] {
        // μ = 0: every contact force is parallel to its branch vector, σ_xy = σ_yx.
        assert!((s[2] - s[3]).abs() <= 1e-9 * s[1], "σ_xy {} σ_yx {}", s[2], s[3]);
        // Shear resists the motion: σ_xy < 0 with compression positive.
        assert!(s[2] < 0.0 && s[1] > 0.0);
    }
    // Bagnold scaling p ∝ γ̇²: ×4 in rate ⇒ ×16 in pressure (measured 16.4 with 256 spheres).
    let ratio = fast[1] / slow[1];
    assert!((11.0..24.0).contains(&ratio), "p ratio {ratio} for a rate ratio 4");
}

#[test]
fn bad_shear_input_is_named() {
    let dir = tempfile::tempdir().unwrap();
    lattice(dir.path(), 3, 0.0022, 0.002, 0.0);
    let cases = [
        ("boundary p p p", "fix sh all deform 1 xz erate 5 remap v", "unsupported fix deform form"),
        ("boundary p f p", "fix sh all deform 1 xy erate 5 remap v", "needs periodic x and y"),
        ("boundary p p p", "velocity all ramp vx 0 1 y 1 0", "must exceed YLO"),
        ("boundary p p p", "thermo_style custom step c_s[13]\nrun 1", "out of range 1..12"),
    ];
    for (bnd, line, msg) in cases {
        let deck = HEAD.replace("E\n", "0.7\n").replace("MU\n", "0.0\n").replace("boundary p p p", bnd)
            + line
            + "\n";
        std::fs::write(dir.path().join("in.t"), deck).unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_mcdem"))
            .current_dir(dir.path())
            .args(["run", "in.t", "-log", "none", "--no-progress"])
            .output()
            .unwrap();
        let s = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
        assert!(!o.status.success() && s.contains("ERROR") && s.contains(msg), "{line}: {s}");
    }
}

/// A contact across the sheared boundary sees the image of the lower particle shifted and moving
/// with γ̇ L_y: the same forces (normal, damping, tangential history) as a plain pair placed at the
/// image position with that velocity in an unsheared box.
#[test]
fn contact_across_sheared_boundary_equals_plain_pair() {
    let dir = tempfile::tempdir().unwrap();
    let (l, r, rate) = (0.01, 0.001, 20.0);
    let common = "units si
atom_style sphere
neighbor 0.0002 bin
fix m1 all property/global youngsModulus peratomtype 1e7
fix m2 all property/global poissonsRatio peratomtype 0.3
fix m3 all property/global coefficientRestitution peratomtypepair 1 0.7
fix m4 all property/global coefficientFriction peratomtypepair 1 0.5
pair_style gran model hertz tangential history
pair_coeff * *
timestep 1e-6
fix integr all nve/sphere
";
    let y1 = l - 0.99 * r;
    let y2 = 0.99 * r - 0.00003; // image at y2 + l: centre distance 1.98r − 3e-5 m < 2r
    let tail = "dump d all custom 20 dump.t id x y z vx vy vz fx fy fz\n\
                dump_modify d format \"%d %.15g %.15g %.15g %.15g %.15g %.15g %.15g %.15g %.15g\" sort id\n\
                run 20\n";
    let le = format!(
        "{common}boundary p p p\nregion b block 0 {l} 0 {l} 0 {l} units box\ncreate_box 1 b\n\
         create_atoms 1 single 0.005 {y1} 0.005 units box\ncreate_atoms 1 single 0.0052 {y2} 0.005 units box\n\
         set atom * diameter {d} density 1000\nfix sh all deform 1 xy erate {rate} remap v\n{tail}",
        d = 2.0 * r
    );
    let plain = format!(
        "{common}boundary f f f\nregion b block -0.01 0.02 -0.01 0.03 -0.01 0.02 units box\ncreate_box 1 b\n\
         create_atoms 1 single 0.005 {y1} 0.005 units box\ncreate_atoms 1 single 0.0052 {y2l} 0.005 units box\n\
         set atom * diameter {d} density 1000\nset atom 2 vx {vj}\n{tail}",
        y2l = y2 + l,
        d = 2.0 * r,
        vj = rate * l
    );
    let frame = |deck: &str| -> Vec<Vec<f64>> {
        let _ = run(dir.path(), deck);
        let text = std::fs::read_to_string(dir.path().join("dump.t")).unwrap();
        let mut last: Vec<&str> = text.lines().collect();
        last = last.split_off(last.len() - 2);
        last.iter().map(|l| l.split_whitespace().map(|t| t.parse().unwrap()).collect()).collect()
    };
    let a = frame(&le);
    let b = frame(&plain);
    // Forces on particle 1 (entirely from the contact) and on 2; the tangential part must be
    // there (x component from the velocity jump).
    let fscale = b[0][7..10].iter().map(|f| f * f).sum::<f64>().sqrt();
    assert!(b[0][7].abs() > 1e-3 * fscale, "no tangential force in the plain pair: {:?}", b[0]);
    for p in 0..2 {
        for c in 7..10 {
            assert!(
                (a[p][c] - b[p][c]).abs() <= 1e-9 * fscale,
                "particle {} col {c}: {} vs {}",
                p + 1,
                a[p][c],
                b[p][c]
            );
        }
    }
    // Particle 1's trajectory is the same; particle 2's x velocity differs by the jump.
    assert!((a[0][4] - b[0][4]).abs() < 1e-12 && (a[1][4] + rate * l - b[1][4]).abs() < 1e-9);
}

/// Dense frictional `mc_advanced` Lees–Edwards shear: 4 nc³ spheres at φ = 0.8 (fcc, overlaps of
/// 2.6 % of d), μ = 0.5, γ̇ = 100 /s for 3000 steps of 0.5 µs (strain 0.15), skin 0.05 mm (a
/// rebuild every ~0.02 strain), final positions and velocities to 17 digits. `extra` goes before
/// the run, `pool` sets the thread-pool size, `mode` is `--threads-mode`.
fn dense_shear(nc: usize, steps: u64, extra: &str, mode: &str, pool: &str) -> (Vec<Vec<f64>>, String) {
    let dir = tempfile::tempdir().unwrap();
    let l = fcc(dir.path(), nc, 0.8, 0.002);
    let rate = 100.0;
    let deck = HEAD
        .replace("E\n", "0.7\n")
        .replace("MU\n", "0.5\n")
        .replace("timestep 1e-6", "timestep 5e-7")
        .replace("neighbor 0.0002 bin", "neighbor 0.00005 bin")
        .replace("model hertz", "model mc_advanced")
        .replace(
            "pair_coeff * *",
            "fix m5 all property/global geometricPrefactor peratomtype 0.702\n\
             fix m6 all property/global maxPenetrationRatio peratomtype 0.109\npair_coeff * *",
        )
        + &format!(
            "{extra}\nvelocity all ramp vx {} {} y 0 {l} sum yes units box\n\
             fix sh all deform 1 xy erate {rate} remap v\n\
             thermo_style custom step c_z\nthermo 10\nrun {steps}\n\
             dump d all custom 1 dump.sh id x y z vx vy vz\n\
             dump_modify d format \"%d %.17g %.17g %.17g %.17g %.17g %.17g\"\n\
             run 0\n",
            -0.5 * rate * l,
            0.5 * rate * l
        );
    std::fs::write(dir.path().join("in.t"), deck).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mcdem"))
        .current_dir(dir.path())
        .env("RAYON_NUM_THREADS", pool)
        .args(["run", "in.t", "-log", "none", "--no-progress", "--threads-mode", mode])
        .output()
        .unwrap();
    let out = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{out}");
    let mut rows = mcdem::outputs::read_dump(&dir.path().join("dump.sh")).unwrap().pop().unwrap().rows;
    rows.sort_by(|a, b| a[0].total_cmp(&b[0]));
    assert_eq!(rows.len(), 4 * nc * nc * nc);
    (rows, out)
}

/// The (step, Z) thermo rows of a run.
fn coordination(out: &str) -> Vec<(u64, f64)> {
    out.lines()
        .filter_map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            (w.len() == 2).then(|| Some((w[0].parse().ok()?, w[1].parse().ok()?))).flatten()
        })
        .collect()
}

/// Neighbour builds of a run's `Loop time` lines.
fn builds(out: &str) -> u64 {
    mcdem::outputs::loop_details(out).unwrap().iter().map(|d| d.neighbour_builds).sum()
}

/// The Lees–Edwards skin test (rebuild when relative motion plus the sheared-image drift could
/// close the skin) against the reference that rebuilds every step (`neigh_modify every 1 check
/// no`), over strain 0.5. A list that misses a pair loses that contact at once: the coordination
/// number Z, printed every 10 steps, must be the same number at every print (contact counts do
/// not feel round-off unless an overlap sits within ~1e-16 m of zero). The positions then agree
/// to round-off amplified by the dense packing's chaos (measured 1.0e-13 m = 5e-11 d with 166
/// builds against 10 000; bound 1e-9 d). Checked to fail: a list never rebuilt stops the run
/// at step 10 000 (overlap 1.26 mm > radius across the sheared boundary). Dropping only the
/// strain term of the test is *not* caught in this dense scene: the non-affine motion fires the
/// skin test first (36–143 builds, Z identical, positions within 6e-13 m), so that term is
/// pinned by the affine-only case in `lees_edwards_skin_includes_the_image_drift` instead.
#[test]
fn lees_edwards_skin_test_matches_rebuilding_every_step() {
    let (skin, out_skin) = dense_shear(3, 10000, "", "serial", "1");
    let (every, out_every) = dense_shear(3, 10000, "neigh_modify every 1 check no", "serial", "1");
    let (b_skin, b_every) = (builds(&out_skin), builds(&out_every));
    eprintln!("neighbour builds: skin test {b_skin}, every step {b_every}");
    assert!(b_every >= 10000, "check no rebuilt only {b_every} times");
    assert!((3..2000).contains(&b_skin), "the skin test rebuilt {b_skin} times: not a test of the skin");
    let (z_skin, z_every) = (coordination(&out_skin), coordination(&out_every));
    assert!(z_skin.len() >= 1000, "{} thermo rows", z_skin.len());
    if let Some((a, b)) = z_skin.iter().zip(&z_every).find(|(a, b)| a != b) {
        panic!("coordination differs: skin test {a:?}, rebuild every step {b:?}");
    }
    let mut worst = 0.0f64;
    for (a, b) in skin.iter().zip(&every) {
        assert_eq!(a[0], b[0]);
        for k in 1..4 {
            worst = worst.max((a[k] - b[k]).abs());
        }
    }
    eprintln!("max position difference {worst:e} m");
    assert!(worst < 1e-9 * 0.002, "skin-test run off the rebuild-every-step run by {worst:e} m");
}

/// Shear on two threads gives the one-thread result bit for bit (Lees–Edwards images, tangential
/// history and the multi-contact radius changes all split across the blocks); 500 spheres so
/// that the pair pass is split into blocks at all.
#[test]
fn dense_shear_on_two_threads_is_bit_identical() {
    let (one, _) = dense_shear(5, 3000, "", "serial", "2");
    let (two, out) = dense_shear(5, 3000, "", "parallel", "2");
    assert!(out.contains("2 threads, threaded in 100 % of steps"), "{out}");
    assert!(one == two, "two threads changed the sheared packing");
}

/// The image-drift term of the Lees–Edwards skin test, alone: two spheres (d = 2 mm) on either
/// side of the sheared y boundary of a 12 mm box (γ̇ = 100 /s), 1.8 mm apart in y through the
/// boundary, each moving exactly with the affine flow v_x = γ̇ (y − y_mid) (∓0.51 m/s), so that
/// their displacement from the affine field stays zero and only the strain term of the skin test
/// can trigger a rebuild. Across the boundary the image of A streams past B at γ̇ · 1.8 mm =
/// 0.18 m/s. The x gap starts at 1.412 mm (centre distance 2.288 mm, outside the 2.2 mm list
/// cutoff, so the first list does not hold the pair) and contact needs √(d² − 1.8²) = 0.872 mm,
/// reached at t = 3.0 ms (step 3000). A skin test that forgets the strain never rebuilds and the
/// contact never forms (checked by removing the term); the test asserts the onset at step
/// 3000 ± 10 (the thermo interval), at least one rebuild, and that Z agrees, print by print,
/// with a list rebuilt every step.
#[test]
fn lees_edwards_skin_includes_the_image_drift() {
    let run = |extra: &str| {
        let dir = tempfile::tempdir().unwrap();
        let data = "pair\n\n2 atoms\n1 atom types\n0 0.012 xlo xhi\n0 0.012 ylo yhi\n0 0.012 zlo zhi\n\n\
                    Atoms\n\n1 1 0.002 1000 0.004 0.0009 0.006\n2 1 0.002 1000 0.005412 0.0111 0.006\n\n\
                    Velocities\n\n1 -0.51 0 0 0 0 0\n2 0.51 0 0 0 0 0\n";
        std::fs::write(dir.path().join("data.lat"), data).unwrap();
        let deck = HEAD.replace("E\n", "0.7\n").replace("MU\n", "0.5\n")
            + &format!(
                "{extra}\nfix sh all deform 1 xy erate 100 remap v\n\
                 thermo_style custom step c_z\nthermo 10\nrun 4000\n"
            );
        std::fs::write(dir.path().join("in.t"), deck).unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_mcdem"))
            .current_dir(dir.path())
            .args(["run", "in.t", "-log", "none", "--no-progress"])
            .output()
            .unwrap();
        let out = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
        assert!(o.status.success(), "{out}");
        (coordination(&out), builds(&out))
    };
    let (z_skin, b_skin) = run("");
    let (z_every, _) = run("neigh_modify every 1 check no");
    eprintln!("skin test: {b_skin} builds");
    assert_eq!(z_skin.len(), 401);
    assert!(b_skin >= 1, "the skin test never rebuilt the list");
    let onset = z_every.iter().find(|(_, z)| *z > 0.0).map(|(s, _)| *s);
    assert!(onset.is_some_and(|s| s.abs_diff(3000) <= 10), "contact onset at {onset:?}, expected step 3000");
    assert_eq!(z_skin, z_every, "the skin test missed the contact across the sheared boundary");
}
