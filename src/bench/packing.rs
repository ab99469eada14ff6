//! Dense periodic packing for the Rust DEM: N spheres (diameter 1 mm ± 5 %) on a face-centred
//! cubic lattice squeezed to a solid fraction of 0.8 (about 12 overlapping neighbours each, several
//! per cent overlap), small random velocities, triply periodic. Cost per particle-step at growing
//! N shows whether neighbour search and memory layout scale; resident memory per particle is read
//! from /proc while the scene is alive.

use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

use super::hydrogel::{mpirun_available, on_path, on_two_ranks, sibling};
use super::{Options, Report, Row};
use crate::engine::{Closure, Domain, World};
use crate::outputs::loop_totals;
use crate::physics::ghods2022::MprTest;
use crate::physics::hertz::Tangential;
use crate::physics::model_kind::ModelKind;
use crate::physics::{Material, Vec3};

pub const SCENE: &str = "packing_phi0.8";

/// Lattice cells per side for the sizes measured (4 k³ particles).
pub fn cells(quick: bool) -> &'static [usize] {
    if quick {
        &[8, 17]
    } else {
        &[8, 17, 29]
    }
}

/// Resident set size of this process [bytes] (Linux; None elsewhere).
fn rss_bytes() -> Option<f64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: f64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096.0)
}

/// The packing with 4 k³ spheres, Hertz or advanced MC (γ = 0.81, MPR = 0.11), ready for `setup`.
pub fn scene(k: usize, advanced: bool) -> Result<World, String> {
    let d = 1e-3;
    // fcc at contact: a = √2 d, φ = π/(3√2) ≈ 0.7405; shrink the lattice to reach φ = 0.8.
    let phi_fcc = std::f64::consts::PI / (3.0 * 2f64.sqrt());
    let a = 2f64.sqrt() * d * (phi_fcc / 0.8).cbrt();
    let l = a * k as f64;
    let mut w = World::new();
    // Spatial sorting as in a deck (LAMMPS' default period): keeps the pair loop in cache at large N.
    w.sort_every = 1000;
    w.domain = Some(Domain::new(Vec3::zeros(), Vec3::repeat(l), [true; 3]));
    let m = if advanced {
        Material::new(1e6, 0.4, 0.81, Some((0.11, MprTest::Abs))).map_err(|e| e.to_string())?
    } else {
        Material::hertz(1e6, 0.4).map_err(|e| e.to_string())?
    };
    w.set_materials(vec![m], &[0.7], &[0.5], Tangential::History)?;
    w.closure = Some(if advanced { Closure::MultiContact } else { Closure::Hertz });
    if advanced {
        w.mc_range = 1.25;
    }
    w.skin = 0.05 * d;
    w.integrate = true;
    let mut rng = crate::rng::Lcg64(0x9e3779b97f4a7c15);
    let mut rnd = move || rng.symmetric();
    let basis = [[0.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.5, 0.0, 0.5], [0.0, 0.5, 0.5]];
    let mut id = 1;
    for i in 0..k {
        for j in 0..k {
            for kk in 0..k {
                for b in basis {
                    let x =
                        Vec3::new(i as f64 + b[0] + 0.25, j as f64 + b[1] + 0.25, kk as f64 + b[2] + 0.25)
                            * a;
                    w.p.push(id, 0, x, d * (1.0 + 0.05 * rnd()), 1000.0);
                    let n = w.p.len() - 1;
                    w.p.v[n] = Vec3::new(rnd(), rnd(), rnd()) * 1e-3;
                    id += 1;
                }
            }
        }
    }
    // A tenth of the Rayleigh time of the smallest sphere (G = E/2(1+ν)).
    let g: f64 = 1e6 / (2.0 * 1.4);
    w.dt = 0.1 * std::f64::consts::PI * 0.475 * d * (1000.0 / g).sqrt() / (0.1631 * 0.4 + 0.8766);
    Ok(w)
}

/// Writes `w` as a LIGGGHTS data file (`atom_style sphere`: `id type diameter density x y z`, then
/// `Velocities`), the input of `liggghts_inputs/dense_packing.in`. Numbers are written in their
/// shortest exact form, so both engines start from bit-identical positions and velocities.
pub fn write_data(w: &World, path: &Path) -> Result<(), String> {
    let d = w.domain.ok_or("write_data: the scene has no box")?;
    let p = &w.p;
    let mut s = String::with_capacity(160 * p.len());
    let _ = writeln!(s, "dense periodic packing, solid fraction 0.8 (mcdem bench)\n");
    let _ = writeln!(s, "{} atoms\n{} atom types\n", p.len(), w.ntypes.max(1));
    for (a, name) in ["x", "y", "z"].iter().enumerate() {
        let _ = writeln!(s, "{:?} {:?} {name}lo {name}hi", d.lo[a], d.hi[a]);
    }
    s.push_str("\nAtoms\n\n");
    for i in 0..p.len() {
        let (x, r) = (p.x[i], p.radius[i]);
        let _ = writeln!(
            s,
            "{} {} {:?} {:?} {:?} {:?} {:?}",
            p.id[i],
            p.typ[i] + 1,
            2.0 * r,
            p.density[i],
            x.x,
            x.y,
            x.z
        );
    }
    s.push_str("\nVelocities\n\n");
    for i in 0..p.len() {
        let (v, o) = (p.v[i], p.omega[i]);
        let _ = writeln!(s, "{} {:?} {:?} {:?} {:?} {:?} {:?}", p.id[i], v.x, v.y, v.z, o.x, o.y, o.z);
    }
    std::fs::write(path, s).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Steps measured for a packing of `n` particles: at least ~4e6 particle-steps per row (the
/// small packing's steps are short: timing noise).
fn steps_for(quick: bool, n: usize) -> usize {
    if quick {
        40
    } else {
        (4_000_000 / n).max(200)
    }
}

/// The packing as a deck (`liggghts_inputs/dense_packing.in`, Hertz): the same data file run by
/// LIGGGHTS on one and two MPI ranks and by the Rust DEM on one and two threads, each a child
/// process timed by its own "Loop time" line. This is where the two engines' Hertz rates compare
/// at growing N; the in-process rows above measure the Rust DEM alone (and its memory).
fn deck_rows(opts: &Options, report: &mut Report, say: &mut dyn FnMut(&str)) -> Result<(), String> {
    let decks = Path::new(env!("CARGO_MANIFEST_DIR")).join("liggghts_inputs");
    let exe = if on_path("liggghts") { Some("liggghts".into()) } else { sibling("mcdem-liggghts") };
    let Some(liggghts) = exe else {
        report.notes.push("packing deck rows skipped: neither liggghts nor mcdem-liggghts found".into());
        return Ok(());
    };
    let mpi = mpirun_available();
    let me = std::env::current_exe().map_err(|e| e.to_string())?;
    let work = std::env::temp_dir().join(format!("mcdem-bench-packing-{}", std::process::id()));
    std::fs::create_dir_all(&work).map_err(|e| e.to_string())?;
    let result = (|| -> Result<(), String> {
        for &k in cells(opts.quick) {
            let w = scene(k, false)?;
            let n = w.p.len();
            let data = work.join(format!("packing_{n}.data"));
            write_data(&w, &data)?;
            // Longer than the in-process rows: these include the engine's thread probe (the
            // first 100 steps), which must not decide the row.
            let steps = if opts.quick { 40 } else { (20_000_000 / n).max(1000) };
            let vars = [
                ("data", data.display().to_string()),
                ("dt", format!("{:?}", w.dt)),
                ("steps", steps.to_string()),
                ("every", steps.to_string()),
                ("dir", decks.display().to_string()),
            ];
            let var_args: Vec<&str> = vars.iter().flat_map(|(k, v)| ["-var", k, v.as_str()]).collect();
            let deck_args = |c: &mut Command| {
                c.arg("-in").arg(decks.join("dense_packing.in")).args(&var_args);
                c.args(["-log", "none"]).current_dir(&work);
            };
            let mut runs: Vec<(&'static str, usize, Command)> = Vec::new();
            let mut c = Command::new(&liggghts);
            deck_args(&mut c);
            runs.push(("liggghts", 1, c));
            if mpi {
                let mut c = on_two_ranks(&liggghts);
                deck_args(&mut c);
                runs.push(("liggghts", 2, c));
            }
            for threads in [1usize, 2] {
                let mut c = Command::new(&me);
                c.arg("run").arg(decks.join("dense_packing.in")).args(&var_args);
                c.args(["-log", "none", "--no-progress"]).current_dir(&work);
                c.env("RAYON_NUM_THREADS", threads.to_string());
                runs.push(("rust", threads, c));
            }
            for (engine, threads, mut c) in runs {
                let what = format!("packing deck N = {n}, {engine} hertz, {threads} core(s)");
                let out = c.output().map_err(|e| format!("{what}: cannot start: {e}"))?;
                let text = String::from_utf8_lossy(&out.stdout);
                if !out.status.success() {
                    let tail: Vec<&str> = text.lines().rev().take(5).collect();
                    return Err(format!("{what} failed: {}", tail.join(" | ")));
                }
                let lt = loop_totals(&text).ok_or_else(|| format!("{what}: no 'Loop time' line"))?;
                let (secs, rate) = (lt.seconds, lt.rate());
                say(&format!("{what}: {rate:.3e} particle-steps/s"));
                report.rows.push(Row {
                    engine,
                    model: ModelKind::Hertz.into(),
                    scene: format!("{DECK_SCENE}_N{n}"),
                    n,
                    threads,
                    particle_steps_per_s: rate,
                    wall_time_s: secs,
                    memory_bytes_per_particle: None,
                    rounds_particle_steps_per_s: Vec::new(),
                });
            }
        }
        Ok(())
    })();
    let _ = std::fs::remove_dir_all(&work);
    result?;
    report.notes.push(format!(
        "packing deck: liggghts_inputs/dense_packing.in (hertz), {} steps, one process per row; threads = MPI ranks for liggghts{}",
        if opts.quick { "40" } else { "max(1000, 2e7/N)" },
        if mpi { "" } else { " (mpirun not found: 1 rank only)" }
    ));
    Ok(())
}

/// Scene name of the deck rows.
pub const DECK_SCENE: &str = "packing_deck_phi0.8";

/// The rows of one round (`round` from 0). Later rounds repeat the rows the targets read: the
/// in-process Hertz rows on one thread (cost per particle-step against N) and every deck row.
pub fn rows(
    opts: &Options,
    round: usize,
    report: &mut Report,
    say: &mut dyn FnMut(&str),
) -> Result<(), String> {
    // At least ~4e6 particle-steps per row (the small packing's steps are short: timing noise),
    // after a warm-up that covers the engine's first serial-vs-threads probe.
    let steps_for = |n: usize| steps_for(opts.quick, n);
    let warmup = 5 + crate::engine::THREAD_PROBE_STEPS;
    let base = rss_bytes();
    for &k in cells(opts.quick) {
        for (model, advanced) in [(ModelKind::Hertz, false), (ModelKind::McAdvanced, true)] {
            for threads in [1, 2] {
                if round > 0 && (advanced || threads > 1) {
                    continue;
                }
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .map_err(|e| e.to_string())?;
                let (n, secs, mem) = pool.install(|| -> Result<(usize, f64, Option<f64>), String> {
                    let mut w = scene(k, advanced)?;
                    w.setup()?;
                    // Warm-up: the neighbour list, contact histories and the thread-use probe.
                    for _ in 0..warmup {
                        w.step().map_err(|e| e.to_string())?;
                    }
                    let n = w.p.len();
                    let mem = match (base, rss_bytes()) {
                        (Some(b), Some(now)) => Some((now - b).max(0.0) / n as f64),
                        _ => None,
                    };
                    let t0 = Instant::now();
                    for _ in 0..steps_for(n) {
                        w.step().map_err(|e| e.to_string())?;
                    }
                    Ok((n, t0.elapsed().as_secs_f64(), mem))
                })?;
                let steps = steps_for(n);
                report.rows.push(Row {
                    engine: "rust",
                    model: model.into(),
                    scene: format!("{SCENE}_N{n}"),
                    n,
                    threads,
                    particle_steps_per_s: (n * steps) as f64 / secs,
                    wall_time_s: secs,
                    memory_bytes_per_particle: mem,
                    rounds_particle_steps_per_s: Vec::new(),
                });
                say(&format!(
                    "packing N = {n}, {model}, {threads} thread(s): {:.3e} particle-steps/s",
                    (n * steps) as f64 / secs
                ));
            }
        }
    }
    report.notes.push(format!(
        "packing: {} after {warmup} warm-up steps (the engine's first thread probe included); memory = resident-set growth over the start of the bench while the scene is alive",
        if opts.quick { "40 steps" } else { "max(200, 4e6/N) steps" }
    ));
    deck_rows(opts, report, say)
}
