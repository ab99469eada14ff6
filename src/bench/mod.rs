//! `mcdem bench`: the same scenes with every engine and model available, measured side by side in
//! one invocation so that every ratio compares runs that saw the same machine. Absolute rates on a
//! shared machine mean little; the ratios are the result.
//!
//! Rows: the 514-particle hydrogel deck with LIGGGHTS (stock `hertz`, stock `surface multicontact`,
//! the `mc_advanced` plugin) and the Rust DEM (same three laws, 1 and 2 threads); a dense periodic
//! packing (φ = 0.8) at growing N for the Rust DEM, in process (with its memory) and as a deck run by
//! both engines (LIGGGHTS on 1 and 2 MPI ranks, the Rust DEM on 1 and 2 threads); the contact-set
//! kernel at 2, 6 and 12 contacts.
//!
//! With `--rounds R` every selected group runs R times, one whole pass after another, so that each
//! row is sampled at R moments of the machine's load. A ratio is formed within each round (its two
//! rows ran minutes apart at most) and the report gives the median over the rounds with the range;
//! a row's rate is its median. The targets of the bench are checked on these medians.

mod budget;
mod budget_scenes;
mod hydrogel;
mod kernel;
mod nonlocal;
pub mod packing;

use std::collections::BTreeMap;

use serde::Serialize;

use crate::harness::progress::Progress;
use crate::physics::model_kind::{ModelKind, ModelLabel};

/// One measurement.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// `rust` or `liggghts`.
    pub engine: &'static str,
    /// `hertz`, `standard_mc` (γ only), `mc_advanced` (γ and MPR), or a variant's own label (an
    /// approximation, a kernel variant).
    pub model: ModelLabel,
    pub scene: String,
    /// Particles in the scene (contacts per particle for kernel rows).
    pub n: usize,
    pub threads: usize,
    /// Particle-steps per second (kernel rows: particles, i.e. kernel calls, per second).
    pub particle_steps_per_s: f64,
    pub wall_time_s: f64,
    /// Resident memory added by the scene, per particle (dense packing rows).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub memory_bytes_per_particle: Option<f64>,
    /// The rate of each round, in round order, when the bench ran more than one (the row's
    /// `particle_steps_per_s` is their median).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub rounds_particle_steps_per_s: Vec<f64>,
}

/// What `mcdem bench` prints and writes.
#[derive(Debug, Default, Serialize)]
pub struct Report {
    pub rows: Vec<Row>,
    /// Rounds the bench ran (each selected group once per round).
    pub rounds: usize,
    /// Named ratios of rows of this run (costs: > 1 means slower); with several rounds the median
    /// of the ratios formed within each round.
    pub ratios: BTreeMap<String, f64>,
    /// With several rounds: the smallest and largest per-round value of each ratio.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub ratio_ranges: BTreeMap<String, [f64; 2]>,
    /// Which row groups ran, and why others did not.
    pub notes: Vec<String>,
    /// Accuracy paid for speed: named errors of approximate rows against their exact run.
    pub errors: BTreeMap<String, f64>,
    /// The bench's speed targets, checked on the (median) ratios and rows above.
    pub targets: Vec<Target>,
    /// The accuracy budget's speed–error fronts, one per scene (`--scene budget`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub budget: Vec<budget::Front>,
}

/// One speed target and whether this run meets it.
#[derive(Debug, Clone, Serialize)]
pub struct Target {
    /// What is compared, e.g. `hydrogel hertz: speed-up rust 2 threads / liggghts 1 rank`.
    pub name: String,
    pub value: f64,
    /// `<=` or `>=`: how `value` must stand to `bound`.
    pub relation: &'static str,
    pub bound: f64,
    pub met: bool,
}

#[derive(Debug, Clone)]
pub struct Options {
    /// CI size: shorter strokes, smaller packings, fewer steps.
    pub quick: bool,
    /// Scene groups to run (names from [`SCENES`]); empty = all.
    pub scenes: Vec<String>,
    /// Passes over the selected groups (≥ 1). The first runs every row, later ones the rows the
    /// targets read (the stock LIGGGHTS `surface multicontact` row alone takes longer than all
    /// of those together). The `budget` group runs in the first pass only, its settings
    /// interleaved this many times within it.
    pub rounds: usize,
    /// Directory of the budget group's PNGs (one per scene).
    pub plots: std::path::PathBuf,
}

/// The scene groups, in the order they run.
pub const SCENES: [&str; 5] = ["kernel", "packing", "hydrogel", "nonlocal", "budget"];

/// Groups that run only when named with `--scene` (the budget front runs every scene under seven
/// settings: minutes even in its quick form, too long for the default quick bench).
const ON_REQUEST: [&str; 1] = ["budget"];

impl Options {
    fn runs(&self, scene: &str) -> bool {
        if self.scenes.is_empty() {
            return !ON_REQUEST.contains(&scene);
        }
        self.scenes.iter().any(|s| s == scene)
    }
}

/// Runs every available row group `opts.rounds` times; `say` receives progress lines.
pub fn run(opts: Options, say: &mut dyn FnMut(&str)) -> Result<Report, String> {
    if let Some(bad) = opts.scenes.iter().find(|s| !SCENES.contains(&s.as_str())) {
        return Err(format!("ERROR: unknown bench scene '{bad}' (expected one of {})", SCENES.join(", ")));
    }
    if opts.rounds == 0 {
        return Err("ERROR: --rounds must be at least 1".into());
    }
    let mut rounds = Vec::with_capacity(opts.rounds);
    // One progress item per scene group and round; the lines of `say` go above the bar.
    let groups: Vec<&str> = SCENES.iter().copied().filter(|g| opts.runs(g)).collect();
    let progress = Progress::new("bench", groups.len() * opts.rounds);
    let mut say_above = |l: &str| progress.suspend(|| say(l));
    let say: &mut dyn FnMut(&str) = &mut say_above;
    for round in 0..opts.rounds {
        if opts.rounds > 1 {
            say(&format!("round {} of {}", round + 1, opts.rounds));
        }
        let mut report = Report::default();
        for &group in &groups {
            let item =
                if opts.rounds > 1 { format!("{group} (round {})", round + 1) } else { group.to_string() };
            progress.start(&item);
            let t = std::time::Instant::now();
            let done = match group {
                "kernel" => {
                    kernel::rows(&opts, &mut report, say);
                    Ok(())
                }
                "packing" => packing::rows(&opts, round, &mut report, say),
                "hydrogel" => hydrogel::rows(&opts, round, &mut report, say),
                "budget" if round == 0 => budget::rows(&opts, &mut report, say),
                "budget" => Ok(()),
                // "nonlocal", the last of SCENES.
                _ => nonlocal::rows(&opts, &mut report, say),
            };
            progress.finish(&item);
            // Groups differ by orders of magnitude in time: a later round's estimate of a group is
            // this round's time of it, not the mean over groups.
            if round + 1 < opts.rounds {
                progress.expect(&format!("{group} (round {})", round + 2), t.elapsed().as_secs_f64());
            }
            done?;
        }
        ratios(&mut report);
        rounds.push(report);
    }
    drop(progress);
    let mut report = merge(rounds);
    report.targets = targets(&report);
    Ok(report)
}

/// Median of a non-empty list (mean of the middle two for an even count).
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

/// One report from the rounds: each row's median rate (and wall time, memory), each ratio's
/// median over the rounds that formed it, with its range; errors are the largest seen (they are
/// deterministic, so the rounds agree); the notes of the first round.
fn merge(rounds: Vec<Report>) -> Report {
    let n = rounds.len();
    let mut it = rounds.into_iter();
    let mut out = it.next().unwrap_or_default();
    out.rounds = n;
    if n == 1 {
        return out;
    }
    let later: Vec<Report> = it.collect();
    let same = |a: &Row, b: &Row| {
        a.engine == b.engine
            && a.model == b.model
            && a.scene == b.scene
            && a.n == b.n
            && a.threads == b.threads
    };
    for row in &mut out.rows {
        let matches: Vec<&Row> = std::iter::once(&*row)
            .chain(later.iter().flat_map(|r| r.rows.iter().filter(|x| same(row, x))))
            .collect();
        let mut rates: Vec<f64> = matches.iter().map(|x| x.particle_steps_per_s).collect();
        let mut walls: Vec<f64> = matches.iter().map(|x| x.wall_time_s).collect();
        let mut mem: Vec<f64> = matches.iter().filter_map(|x| x.memory_bytes_per_particle).collect();
        row.rounds_particle_steps_per_s = rates.clone();
        row.particle_steps_per_s = median(&mut rates);
        row.wall_time_s = median(&mut walls);
        if !mem.is_empty() {
            row.memory_bytes_per_particle = Some(median(&mut mem));
        }
    }
    let mut ratios = BTreeMap::new();
    for (k, &v) in &out.ratios {
        let mut all: Vec<f64> =
            std::iter::once(v).chain(later.iter().filter_map(|r| r.ratios.get(k).copied())).collect();
        if all.len() > 1 {
            let lo = all.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = all.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            out.ratio_ranges.insert(k.clone(), [lo, hi]);
        }
        ratios.insert(k.clone(), median(&mut all));
    }
    out.ratios = ratios;
    for r in &later {
        for (k, &e) in &r.errors {
            let v = out.errors.entry(k.clone()).or_insert(e);
            *v = v.max(e);
        }
    }
    out.notes.push(format!(
        "{n} rounds: the first ran every row, later ones the rows the targets read; a row's rate is the median of its rounds, a ratio the median of the ratios formed within each round ([min, max] beside it when more than one)"
    ));
    out
}

/// The targets of the bench (docs/bench.md, "Targets"), where this run has their rows.
/// Ratios are costs; speed-ups are their inverses.
fn targets(r: &Report) -> Vec<Target> {
    let mut t = Vec::new();
    let mut push = |name: String, value: f64, relation: &'static str, bound: f64| {
        let met = if relation == "<=" { value <= bound } else { value >= bound };
        t.push(Target { name, value, relation, bound, met });
    };
    let (tol, every) = hydrogel::TARGET_APPROXIMATION;
    let fast = hydrogel::approximate_model(tol, every);
    for (label, engine) in [("rust 1 thread", "rust"), ("liggghts", "liggghts")] {
        for m in [ModelKind::McAdvanced.name(), fast.as_str()] {
            if let Some(&v) = r.ratios.get(&format!("{label}: {m} / hertz")) {
                push(format!("hydrogel, {engine}: cost {m} / hertz"), v, "<=", 1.3);
            }
        }
    }
    // The exact-MC speed issue's targets (docs/bench.md): exact `mc_advanced` within 2.5× Hertz on
    // one thread, and the 514-particle deck 1.6× faster on two threads than on one.
    if let Some(&v) = r.ratios.get("rust 1 thread: mc_advanced / hertz") {
        push("hydrogel, rust 1 thread: cost exact mc_advanced / hertz".into(), v, "<=", 2.5);
    }
    for m in [ModelKind::Hertz.name(), ModelKind::McAdvanced.name()] {
        if let Some(&v) = r.ratios.get(&format!("rust: {m} 2 threads / 1 thread")) {
            push(format!("hydrogel, rust {m}: speed-up 2 threads / 1 thread"), 1.0 / v, ">=", 1.6);
        }
    }
    if let Some(&v) = r.ratios.get("hertz: rust 1 thread / liggghts") {
        push("hydrogel hertz: speed-up rust 1 thread / liggghts 1 rank".into(), 1.0 / v, ">=", 1.5);
    }
    if let Some(&v) = r.ratios.get("hertz: rust 2 threads / liggghts") {
        push("hydrogel hertz: speed-up rust 2 threads / liggghts 1 rank".into(), 1.0 / v, ">=", 2.5);
    }
    for (k, &v) in &r.ratios {
        if let Some(n) = k.strip_prefix("hertz packing deck N=") {
            let n = n.split(':').next().unwrap_or_default();
            if k.ends_with("rust 1 thread / liggghts 1 rank") {
                push(
                    format!("packing deck N={n} hertz: speed-up rust 1 thread / liggghts 1 rank"),
                    1.0 / v,
                    ">=",
                    1.5,
                );
            } else if k.ends_with("rust 2 threads / liggghts 1 rank") {
                push(
                    format!("packing deck N={n} hertz: speed-up rust 2 threads / liggghts 1 rank"),
                    1.0 / v,
                    ">=",
                    2.5,
                );
            }
        } else if k.starts_with("packing hertz 1 thread: cost per particle-step") {
            push(k.clone(), v, "<=", 1.3);
        }
    }
    for x in r.rows.iter().filter(|x| x.scene == nonlocal::SCENE) {
        push(format!("{}: seconds to phi = 0.85", x.model), x.wall_time_s, "<=", 60.0);
    }
    budget::targets(&r.budget, &mut t);
    t
}

fn find<'a>(
    r: &'a Report,
    engine: &str,
    model: impl Into<ModelLabel>,
    scene: &str,
    threads: usize,
) -> Option<&'a Row> {
    let model = model.into();
    r.rows.iter().find(|x| x.engine == engine && x.model == model && x.scene == scene && x.threads == threads)
}

/// Cost ratios (time per particle-step of the first row over the second).
fn ratios(r: &mut Report) {
    let mut out = BTreeMap::new();
    let h = hydrogel::SCENE;
    let cost = |a: Option<&Row>, b: Option<&Row>| match (a, b) {
        (Some(a), Some(b)) => Some(b.particle_steps_per_s / a.particle_steps_per_s),
        _ => None,
    };
    let (hertz, standard, advanced) = (ModelKind::Hertz, ModelKind::StandardMc, ModelKind::McAdvanced);
    let pairs = [
        ("liggghts: mc_advanced / hertz", ("liggghts", advanced, 1), ("liggghts", hertz, 1)),
        ("liggghts: standard_mc / hertz", ("liggghts", standard, 1), ("liggghts", hertz, 1)),
        ("rust 1 thread: mc_advanced / hertz", ("rust", advanced, 1), ("rust", hertz, 1)),
        ("rust 1 thread: standard_mc / hertz", ("rust", standard, 1), ("rust", hertz, 1)),
        ("hertz: rust 1 thread / liggghts", ("rust", hertz, 1), ("liggghts", hertz, 1)),
        ("hertz: rust 2 threads / liggghts", ("rust", hertz, 2), ("liggghts", hertz, 1)),
        ("hertz: rust 2 threads / liggghts 2 ranks", ("rust", hertz, 2), ("liggghts", hertz, 2)),
        ("liggghts: hertz 2 ranks / 1 rank", ("liggghts", hertz, 2), ("liggghts", hertz, 1)),
        ("rust: hertz 2 threads / 1 thread", ("rust", hertz, 2), ("rust", hertz, 1)),
        ("rust: mc_advanced 2 threads / 1 thread", ("rust", advanced, 2), ("rust", advanced, 1)),
        ("mc_advanced: rust 1 thread / liggghts", ("rust", advanced, 1), ("liggghts", advanced, 1)),
    ];
    for (name, (e1, m1, t1), (e2, m2, t2)) in pairs {
        if let Some(v) = cost(find(r, e1, m1, h, t1), find(r, e2, m2, h, t2)) {
            out.insert(name.to_string(), v);
        }
    }
    for (tol, every, _) in hydrogel::APPROXIMATIONS {
        let m = hydrogel::approximate_model(tol, every);
        for (engine, label) in [("rust", "rust 1 thread"), ("liggghts", "liggghts")] {
            if let Some(v) = cost(find(r, engine, m.as_str(), h, 1), find(r, engine, ModelKind::Hertz, h, 1))
            {
                out.insert(format!("{label}: {m} / hertz"), v);
            }
        }
        if let Some(v) =
            cost(find(r, "liggghts", m.as_str(), h, 2), find(r, "liggghts", ModelKind::Hertz, h, 2))
        {
            out.insert(format!("liggghts 2 ranks: {m} / hertz"), v);
        }
    }
    // Cost per particle-step across packing sizes, relative to the smallest (1 thread).
    let sizes: Vec<&Row> = r
        .rows
        .iter()
        .filter(|x| x.scene.starts_with(packing::SCENE) && x.threads == 1 && x.model == ModelKind::Hertz)
        .collect();
    if let (Some(first), Some(last)) = (sizes.first(), sizes.last()) {
        if first.n != last.n {
            let name = format!("packing hertz 1 thread: cost per particle-step N={} / N={}", last.n, first.n);
            out.insert(name, first.particle_steps_per_s / last.particle_steps_per_s);
        }
    }
    // The packing deck, same data file in both engines: Rust against LIGGGHTS per N, on one core
    // each and with both cores (Rust threads, LIGGGHTS MPI ranks).
    let deck: Vec<usize> = {
        let mut n: Vec<usize> =
            r.rows.iter().filter(|x| x.scene.starts_with(packing::DECK_SCENE)).map(|x| x.n).collect();
        n.dedup();
        n
    };
    for n in deck {
        let scene = format!("{}_N{n}", packing::DECK_SCENE);
        let row = |e: &str, t: usize| find(r, e, ModelKind::Hertz, &scene, t);
        for (name, a, b) in [
            ("rust 1 thread / liggghts 1 rank", row("rust", 1), row("liggghts", 1)),
            ("rust 2 threads / liggghts 1 rank", row("rust", 2), row("liggghts", 1)),
            ("rust 2 threads / liggghts 2 ranks", row("rust", 2), row("liggghts", 2)),
        ] {
            if let Some(v) = cost(a, b) {
                out.insert(format!("hertz packing deck N={n}: {name}"), v);
            }
        }
    }
    r.ratios = out;
}

/// A plain-text table of the report.
pub fn table(r: &Report) -> String {
    let mut s = format!(
        "{:<9} {:<30} {:<28} {:>7} {:>3} {:>14} {:>10}\n",
        "engine", "model", "scene", "n", "thr", "particle-st/s", "wall [s]"
    );
    for x in &r.rows {
        s.push_str(&format!(
            "{:<9} {:<30} {:<28} {:>7} {:>3} {:>14.4e} {:>10.2}{}\n",
            x.engine,
            x.model,
            x.scene,
            x.n,
            x.threads,
            x.particle_steps_per_s,
            x.wall_time_s,
            x.memory_bytes_per_particle.map_or(String::new(), |m| format!("  {m:.0} B/particle"))
        ));
    }
    s.push_str("\nratios (cost, > 1 = slower):\n");
    for (k, v) in &r.ratios {
        let range = r.ratio_ranges.get(k).map_or(String::new(), |[lo, hi]| format!("  [{lo:.2}, {hi:.2}]"));
        s.push_str(&format!("  {k:<60} {v:.2}{range}\n"));
    }
    if !r.errors.is_empty() {
        s.push_str("\nerrors of approximate rows:\n");
        for (k, v) in &r.errors {
            s.push_str(&format!("  {k:<60} {v:.2e}\n"));
        }
    }
    s.push_str(&budget::table(&r.budget));
    if !r.targets.is_empty() {
        s.push_str("\ntargets:\n");
        for x in &r.targets {
            let mark = if x.met { "met    " } else { "not met" };
            s.push_str(&format!("  {mark} {:<66} {:.2} {} {}\n", x.name, x.value, x.relation, x.bound));
        }
    }
    for n in &r.notes {
        s.push_str(&format!("note: {n}\n"));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(engine: &'static str, threads: usize, rate: f64) -> Row {
        Row {
            engine,
            model: ModelKind::Hertz.into(),
            scene: hydrogel::SCENE.into(),
            n: 514,
            threads,
            particle_steps_per_s: rate,
            wall_time_s: 514.0 / rate,
            memory_bytes_per_particle: None,
            rounds_particle_steps_per_s: Vec::new(),
        }
    }

    /// One round: LIGGGHTS at `l` and the Rust DEM at `r1` (1 thread), `r2` (2 threads).
    fn round(l: f64, r1: f64, r2: f64) -> Report {
        let mut r = Report {
            rows: vec![row("liggghts", 1, l), row("rust", 1, r1), row("rust", 2, r2)],
            ..Default::default()
        };
        ratios(&mut r);
        r
    }

    #[test]
    fn rounds_give_median_rows_and_median_ratios_formed_within_each_round() {
        // The machine slows down by half in round 2: the rows' rates move, their ratio does not.
        let merged = merge(vec![round(4.0, 8.0, 12.0), round(2.0, 4.0, 6.0), round(4.0, 6.0, 8.0)]);
        assert_eq!(merged.rounds, 3);
        let rust1 = find(&merged, "rust", ModelKind::Hertz, hydrogel::SCENE, 1).unwrap();
        assert_eq!(rust1.particle_steps_per_s, 6.0);
        assert_eq!(rust1.rounds_particle_steps_per_s, vec![8.0, 4.0, 6.0]);
        // Costs rust / liggghts per round: 0.5, 0.5, 2/3; median 0.5 (the medians of the rows
        // would give 4/6).
        assert_eq!(merged.ratios["hertz: rust 1 thread / liggghts"], 0.5);
        assert_eq!(merged.ratio_ranges["hertz: rust 1 thread / liggghts"], [0.5, 4.0 / 6.0]);
        let t = targets(&merged);
        let speedup = |name: &str| t.iter().find(|x| x.name.contains(name)).unwrap();
        let one = speedup("rust 1 thread / liggghts 1 rank");
        assert_eq!((one.value, one.met), (2.0, true));
        // 2 threads: speed-ups 3, 3, 2 → median 3 ≥ 2.5.
        let two = speedup("rust 2 threads / liggghts 1 rank");
        assert_eq!((two.value, two.met), (3.0, true));
        let slow = targets(&merge(vec![round(4.0, 5.0, 8.0)]));
        assert!(!slow.iter().find(|x| x.name.contains("rust 1 thread")).unwrap().met, "1.25 < 1.5");
    }

    /// The exact-MC issue's rows: cost of exact `mc_advanced` against Hertz on one thread (≤ 2.5)
    /// and each law's speed-up on two threads (≥ 1.6), both at their bounds and beside them.
    #[test]
    fn exact_mc_cost_and_two_thread_speed_up_targets() {
        let rate = |model: ModelKind, threads: usize, rate: f64| Row {
            model: model.into(),
            ..row("rust", threads, rate)
        };
        let (h, mc) = (ModelKind::Hertz, ModelKind::McAdvanced);
        let mut r = Report {
            rows: vec![rate(h, 1, 10.0), rate(mc, 1, 4.0), rate(h, 2, 15.0), rate(mc, 2, 6.4)],
            ..Default::default()
        };
        ratios(&mut r);
        let t = targets(&r);
        let get = |name: &str| t.iter().find(|x| x.name == name).unwrap_or_else(|| panic!("{name}: {t:?}"));
        let cost = get("hydrogel, rust 1 thread: cost exact mc_advanced / hertz");
        assert_eq!((cost.value, cost.relation, cost.bound, cost.met), (2.5, "<=", 2.5, true));
        let hertz = get("hydrogel, rust hertz: speed-up 2 threads / 1 thread");
        // Speed-ups are inverses of cost ratios: equal to 1.5 and 1.6 to rounding.
        assert!((hertz.value - 1.5).abs() < 1e-12 && (hertz.bound, hertz.met) == (1.6, false), "{hertz:?}");
        let advanced = get("hydrogel, rust mc_advanced: speed-up 2 threads / 1 thread");
        assert!((advanced.value - 1.6).abs() < 1e-12 && advanced.relation == ">=", "{advanced:?}");
        r.rows[1].particle_steps_per_s = 3.9;
        ratios(&mut r);
        assert!(!targets(&r).iter().find(|x| x.name.contains("cost exact")).unwrap().met, "2.56 > 2.5");
    }

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
    }

    #[test]
    fn zero_rounds_are_refused() {
        let e = run(
            Options { quick: true, scenes: vec!["kernel".into()], rounds: 0, plots: ".".into() },
            &mut |_| {},
        )
        .unwrap_err();
        assert!(e.contains("--rounds"), "{e}");
    }
}
