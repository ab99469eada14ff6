//! The scenes of the accuracy-budget front (`mcdem bench --scene budget`) and one run of a setting
//! on each: the hydrogel deck as a child process (its piston force), and in process the dense
//! periodic packing of the packing group, a Lees–Edwards shear at φ = 0.8 (the study's protocol)
//! and a pour onto a floor (each with its contact pressure). A run returns the CPU time of the
//! measured steps, the force measure's samples and the budget's own account.

use std::path::Path;
use std::process::Command;

use crate::engine::{Closure, Domain, PlaneWall, WallFix, WallGeom, World};
use crate::outputs::read_ave_time;
use crate::physics::ghods2022::MprTest;
use crate::physics::hertz::Tangential;
use crate::physics::{Material, Vec3};

/// One contact-law setting of the front.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Setting {
    Hertz,
    /// `mc_advanced`, Eq. 2 every step for every particle.
    Exact,
    /// The exact run with one particle moved by 1e-12 of a diameter: how far a round-off-size
    /// change carries the force measure over the run (the floor below which no setting's error
    /// means anything in a chaotic flow).
    Perturbed,
    /// `mcAccuracy EPS`.
    Budget(f64),
    /// `geometryTolerance TOL updateEvery K` (K = 1: the tolerance alone).
    Fixed(f64, u64),
}

impl Setting {
    pub fn label(&self) -> String {
        match *self {
            Setting::Hertz => "hertz".into(),
            Setting::Exact => "exact".into(),
            Setting::Perturbed => "exact, 1e-12 d moved".into(),
            Setting::Budget(e) => format!("mcAccuracy {e:e}"),
            Setting::Fixed(t, 1) => format!("geometryTolerance {t:e}"),
            Setting::Fixed(t, k) => format!("geometryTolerance {t:e} updateEvery {k}"),
        }
    }

    /// Puts the setting on a world built for multi-contact (Hertz worlds are built as such).
    fn apply(&self, w: &mut World) {
        w.mc_accuracy = 0.0;
        w.mc_geometry_tolerance = 0.0;
        w.mc_every = 1;
        match *self {
            Setting::Budget(e) => w.mc_accuracy = e,
            Setting::Fixed(t, k) => {
                w.mc_geometry_tolerance = t;
                w.mc_every = k;
            }
            _ => {}
        }
    }
}

/// Shadow-check interval of the untimed check runs [steps] (the deck's `mcAccuracyCheck yes`).
pub const CHECK_EVERY: u64 = crate::engine::DEFAULT_CHECK_EVERY;

/// What one run gave.
#[derive(Debug, Clone, Default)]
pub struct Outcome {
    /// CPU time of the measured steps [s].
    pub cpu_s: f64,
    /// The force measure, one sample per output interval.
    pub samples: Vec<f64>,
    /// Fraction of the particle-steps with two or more contacts whose Eq. 2 was recomputed.
    pub recomputed: Option<f64>,
    /// Shadow check: largest measured radius-change error and largest bound, both relative to the
    /// particle's scale.
    pub checked: Option<(f64, f64)>,
    /// Share of the exact evaluations by reason (`engine::BUDGET_WHY` names), budget settings.
    pub why: Vec<(String, f64)>,
}

/// The scenes, in the order they run.
pub const SCENES: [&str; 4] = ["hydrogel", "packing", "shear", "pour"];

/// (particles, measured steps, output interval) of a scene.
pub fn size(scene: &str, quick: bool) -> (usize, u64, u64) {
    match (scene, quick) {
        ("hydrogel", true) => (514, 1500, 10),
        ("hydrogel", false) => (514, 60000, 100),
        ("packing", true) => (256, 200, 5),
        ("packing", false) => (2048, 1500, 25),
        ("shear", true) => (128, 400, 5),
        ("shear", false) => (500, 3000, 25),
        ("pour", true) => (100, 800, 10),
        _ => (384, 2500, 25),
    }
}

/// What the force measure of a scene is.
pub fn measure(scene: &str) -> &'static str {
    if scene == "hydrogel" {
        "piston force: max |F - F_exact| / range of F_exact"
    } else {
        "contact pressure (Eq. 4 virial): max |p - p_exact| / max |p_exact|"
    }
}

/// Runs `setting` on `scene`; `check`: with the shadow check every [`CHECK_EVERY`] steps (budget
/// settings only).
pub fn run(scene: &str, quick: bool, setting: Setting, check: bool) -> Result<Outcome, String> {
    if scene == "hydrogel" {
        return hydrogel(quick, setting, check);
    }
    let (_, steps, every) = size(scene, quick);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().map_err(|e| e.to_string())?;
    pool.install(|| -> Result<Outcome, String> {
        let hertz = setting == Setting::Hertz;
        let mut w = match scene {
            "packing" => packing(quick, hertz)?,
            "shear" => shear(quick, hertz)?,
            _ => pour(quick, hertz)?,
        };
        if setting == Setting::Perturbed {
            w.p.x[0].x += 1e-12 * 2.0 * w.p.radius[0];
        }
        setting.apply(&mut w);
        w.mc_accuracy_check = if check && w.mc_accuracy > 0.0 { CHECK_EVERY } else { 0 };
        w.setup()?;
        w.take_budget_stats();
        let mut samples = Vec::with_capacity((steps / every) as usize);
        let t0 = thread_cpu_s();
        for s in 1..=steps {
            w.step().map_err(|e| format!("{scene}, {}: {e}", setting.label()))?;
            if s % every == 0 {
                samples.push(contact_pressure(&w));
            }
        }
        let cpu_s = thread_cpu_s() - t0;
        let st = w.take_budget_stats();
        let exact: u64 = st.why.iter().sum();
        let why = crate::engine::BUDGET_WHY
            .iter()
            .zip(st.why)
            .filter(|(_, c)| *c > 0)
            .map(|(name, c)| (name.to_string(), c as f64 / exact as f64))
            .collect();
        Ok(Outcome {
            cpu_s,
            samples,
            recomputed: (w.mc_accuracy > 0.0).then(|| st.recomputed as f64 / (st.multi as f64).max(1.0)),
            checked: (st.checks > 0).then_some((st.worst_measured, st.worst_checked_bound)),
            why,
        })
    })
}

/// Contact part of the Eq. 4 pressure [Pa] (trace / 3 of `World::stress_parts`' contact tensor).
fn contact_pressure(w: &World) -> f64 {
    let (sc, _) = w.stress_parts();
    (sc[0][0] + sc[1][1] + sc[2][2]) / 3.0
}

/// On-CPU time of the calling thread [s] (Linux `/proc/thread-self/schedstat`, nanoseconds):
/// the cost of an in-process run, unaffected by the time other processes hold the core.
fn thread_cpu_s() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or_else(wall_s, |ns| ns * 1e-9)
}

/// Fallback clock where /proc is missing (not Linux): wall time since the first call.
fn wall_s() -> f64 {
    static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
    START.get_or_init(std::time::Instant::now).elapsed().as_secs_f64()
}

/// CPU time (user + system) of the waited-for children of this process [s], from fields 16 and 17
/// of /proc/self/stat, in the kernel's fixed USER_HZ of 100 ticks per second (an ABI constant of
/// /proc, independent of the kernel's own tick rate). None where /proc is missing.
fn children_cpu_s() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (in parentheses, which may hold spaces): field 3 onwards.
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let (cu, cs): (f64, f64) = (f.get(13)?.parse().ok()?, f.get(14)?.parse().ok()?);
    Some((cu + cs) / 100.0)
}

/// The hydrogel deck (`liggghts_inputs/hydrogel.in`) as a child `mcdem run` on one thread: quick,
/// one stroke of 1500 steps; full, compression and release at the example's speed (2 strokes of
/// 30000 steps, the deck of validation/recorded/accuracy_budget/).
fn hydrogel(quick: bool, setting: Setting, check: bool) -> Result<Outcome, String> {
    let decks = Path::new(env!("CARGO_MANIFEST_DIR")).join("liggghts_inputs");
    let (stroke, strokes) = if quick { ("1500", "1") } else { ("30000", "2") };
    let every = size("hydrogel", quick).2.to_string();
    let work = std::env::temp_dir().join(format!("mcdem-bench-budget-{}", std::process::id()));
    std::fs::create_dir_all(&work).map_err(|e| format!("{}: {e}", work.display()))?;
    let me = std::env::current_exe().map_err(|e| e.to_string())?;
    let mut c = Command::new(me);
    c.current_dir(&work).env("RAYON_NUM_THREADS", "1").arg("run").arg(decks.join("hydrogel.in"));
    let law = if setting == Setting::Hertz { "1" } else { "0" };
    for (k, v) in [("law", law), ("stroke", stroke), ("strokes", strokes), ("every", every.as_str())] {
        c.args(["-var", k, v]);
    }
    c.arg("-var").arg("dir").arg(&decks);
    c.args(["-log", "none", "--no-progress", "--threads-mode", "serial"]);
    match setting {
        Setting::Budget(e) => {
            c.arg(format!("--mc-accuracy={e}"));
            if check {
                c.arg(format!("--mc-accuracy-check={CHECK_EVERY}"));
            }
        }
        Setting::Fixed(t, k) => {
            c.arg(format!("--mc-geometry-tolerance={t}")).arg(format!("--mc-update-every={k}"));
        }
        Setting::Perturbed => {
            return Err("hydrogel: no perturbed run (a deck cannot move one particle)".into())
        }
        _ => {}
    }
    let before = children_cpu_s();
    let out = c.output().map_err(|e| format!("hydrogel, {}: cannot start: {e}", setting.label()));
    let after = children_cpu_s();
    let table = read_ave_time(&work.join("piston_force.txt"));
    let _ = std::fs::remove_dir_all(&work);
    let out = out?;
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    if !out.status.success() {
        let tail: Vec<&str> = text.lines().rev().take(5).collect();
        return Err(format!("hydrogel, {} failed: {}", setting.label(), tail.join(" | ")));
    }
    let samples = table?
        .iter()
        .map(|r| r.get(3).copied().ok_or("hydrogel: piston_force.txt has no 4th column".to_string()))
        .collect::<Result<Vec<f64>, String>>()?;
    let cpu_s = match (before, after) {
        (Some(b), Some(a)) => a - b,
        _ => crate::outputs::loop_totals(&text).ok_or("hydrogel: no 'Loop time' line")?.seconds,
    };
    Ok(Outcome {
        cpu_s,
        samples,
        recomputed: budget_recomputed(&text),
        checked: budget_checked(&text),
        why: budget_why(&text),
    })
}

/// Mean over the deck's runs (strokes of equal length) of each reason's share in "exact
/// evaluations by reason: NAME X %, …" (a run without a reason counts 0 for it).
fn budget_why(text: &str) -> Vec<(String, f64)> {
    let lines: Vec<&str> = text
        .lines()
        .filter_map(|l| l.split("exact evaluations by reason: ").nth(1)?.split(')').next())
        .collect();
    crate::engine::BUDGET_WHY
        .iter()
        .filter_map(|name| {
            let sum: f64 = lines
                .iter()
                .filter_map(|l| {
                    l.split(", ").find_map(|p| {
                        p.strip_prefix(name)?.trim().strip_suffix('%')?.trim().parse::<f64>().ok()
                    })
                })
                .sum::<f64>();
            (sum > 0.0).then(|| (name.to_string(), sum / lines.len() as f64 / 100.0))
        })
        .collect()
}

/// Mean over the deck's runs of "recomputed in X %" (the runs are strokes of equal length).
fn budget_recomputed(text: &str) -> Option<f64> {
    let v: Vec<f64> = text
        .lines()
        .filter_map(|l| l.split("recomputed in ").nth(1)?.split(' ').next()?.parse::<f64>().ok())
        .collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64 / 100.0)
}

/// Largest "measured error A, bound B" over the deck's runs.
fn budget_checked(text: &str) -> Option<(f64, f64)> {
    let mut out: Option<(f64, f64)> = None;
    for l in text.lines() {
        let Some(rest) = l.split("measured error ").nth(1) else { continue };
        let mut w = rest.split([',', ' ']).filter(|s| !s.is_empty());
        let m: Option<f64> = w.next().and_then(|s| s.parse().ok());
        let b: Option<f64> = w.nth(1).and_then(|s| s.parse().ok());
        if let (Some(m), Some(b)) = (m, b) {
            let (m0, b0) = out.unwrap_or((0.0, 0.0));
            out = Some((m0.max(m), b0.max(b)));
        }
    }
    out
}

/// The packing group's dense periodic packing (φ = 0.8, `packing::scene`), 4 k³ spheres with
/// k = 4 (quick) or 8, set up.
fn packing(quick: bool, hertz: bool) -> Result<World, String> {
    let mut w = super::packing::scene(if quick { 4 } else { 8 }, !hertz)?;
    w.setup()?;
    Ok(w)
}

/// The shear study's run at φ = 0.8, μ = 0.5, ν = 0.4, γ̂ = 1e-2 (γ = 0.81, MPR = 0.11 as the
/// packing), compressed from φ = 0.3 under exact `mc_advanced` and set shearing; the Hertz row
/// switches the law after the compression, so that every setting starts from the same packing.
fn shear(quick: bool, hertz: bool) -> Result<World, String> {
    use crate::study::shear::{sheared_start, RunSpec, RESTITUTION};
    let spec = RunSpec {
        phi: 0.8,
        mu: 0.5,
        nu: 0.4,
        gamma_hat: 1e-2,
        n: size("shear", quick).0,
        gamma_mc: 0.81,
        mpr: 0.11,
        restitution: RESTITUTION,
        seed: 1,
        eq2_fixed_point: false,
    };
    let mut w = sheared_start(&spec, if quick { 1000 } else { 2000 })?;
    if hertz {
        w.closure = Some(Closure::Hertz);
        w.mc_range = 1.0;
    }
    w.setup()?;
    Ok(w)
}

/// A pour: spheres of diameter 1 cm ± 5 % (E = 100 kPa, ν = 0.4, 1000 kg/m³, e = 0.5, μ = 0.5) on
/// a loose cubic lattice (spacing 1.3 d, 5×5×4 or 8×8×6 of them) falling under gravity with small
/// random velocities onto a floor (a `zplane` wall), periodic in x and y: the first half of the
/// run is free fall and impacts (few contacts, loads changing fast), the rest a settling bed.
fn pour(quick: bool, hertz: bool) -> Result<World, String> {
    let d = 1e-2;
    let (nx, nz) = if quick { (5, 4) } else { (8, 6) };
    let a = 1.3 * d;
    let l = nx as f64 * a;
    let h = 4.0 * d + nz as f64 * a;
    let mut w = World::new();
    w.domain = Some(Domain::new(Vec3::zeros(), Vec3::new(l, l, h), [true, true, false]));
    let (e, nu) = (1e5, 0.4);
    let m = if hertz {
        Material::hertz(e, nu).map_err(|e| e.to_string())?
    } else {
        Material::new(e, nu, 0.81, Some((0.11, MprTest::Abs))).map_err(|e| e.to_string())?
    };
    w.set_materials(vec![m], &[0.5], &[0.5], Tangential::History)?;
    w.closure = Some(if hertz { Closure::Hertz } else { Closure::MultiContact });
    if !hertz {
        w.mc_range = 1.25;
    }
    w.gravity = Some(Vec3::new(0.0, 0.0, -9.81));
    w.walls.push(WallFix {
        name: "floor".into(),
        geom: WallGeom::Plane(PlaneWall { axis: 2, pos: 0.0, wall_type: 0 }),
    });
    w.skin = 0.1 * d;
    w.integrate = true;
    let mut rng = crate::rng::Lcg64(0x2545f4914f6cdd1d);
    let mut rnd = move || rng.symmetric();
    let mut id = 1;
    for k in 0..nz {
        for j in 0..nx {
            for i in 0..nx {
                let x = Vec3::new((i as f64 + 0.5) * a, (j as f64 + 0.5) * a, 2.0 * d + k as f64 * a);
                w.p.push(id, 0, x, d * (1.0 + 0.05 * rnd()), 1000.0);
                let n = w.p.len() - 1;
                w.p.v[n] = Vec3::new(rnd(), rnd(), rnd()) * 0.05;
                id += 1;
            }
        }
    }
    // A tenth of the Rayleigh time of the smallest sphere (G = E/2(1+ν)), as the packing.
    let g = e / (2.0 * (1.0 + nu));
    w.dt = 0.1 * std::f64::consts::PI * 0.475 * d * (1000.0 / g).sqrt() / (0.1631 * nu + 0.8766);
    w.setup()?;
    Ok(w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_deck_summary_clauses_are_read() {
        let text = "Loop time of 1 on 1 procs for 10 steps with 5 atoms, multi-contact accuracy 1e-2: recomputed in 20.00 % of the particle-steps with two or more contacts (10.00 % of all), largest estimated error 0.900 of the budget, accuracy check (1 checks, every 10 steps): measured error 1.000e-3, bound 4.000e-3 (of the particle's scale)\n\
Loop time of 1 on 1 procs for 10 steps with 5 atoms, multi-contact accuracy 1e-2: recomputed in 40.00 % of the particle-steps with two or more contacts (20.00 % of all), largest estimated error 0.900 of the budget, accuracy check (1 checks, every 10 steps): measured error 2.000e-3, bound 3.000e-3 (of the particle's scale)\n";
        assert!((budget_recomputed(text).unwrap() - 0.3).abs() < 1e-12);
        assert_eq!(budget_checked(text), Some((2e-3, 4e-3)));
        assert_eq!(budget_checked("Loop time of 1"), None);
        let why = "x, largest estimated error 0.9 of the budget (exact evaluations by reason: no reference 10.0 %, back-off 90.0 %), accuracy\n\
y (exact evaluations by reason: no reference 30.0 %, contact set changed 70.0 %)\n";
        let got = budget_why(why);
        let share = |n: &str| got.iter().find(|(k, _)| k == n).map(|x| x.1);
        assert!((share("no reference").unwrap() - 0.2).abs() < 1e-12, "{got:?}");
        assert!((share("back-off").unwrap() - 0.45).abs() < 1e-12, "{got:?}");
        assert!((share("contact set changed").unwrap() - 0.35).abs() < 1e-12, "{got:?}");
        assert_eq!(share("Eq. 3 cap"), None);
    }
}
