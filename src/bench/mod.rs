//! `mcdem bench`: the same scenes with every engine and model available, measured side by side in
//! one invocation so that every ratio compares runs that saw the same machine. Absolute rates on a
//! shared machine mean little; the ratios are the result.
//!
//! Rows: the 514-particle hydrogel deck with LIGGGHTS (stock `hertz`, stock `surface multicontact`,
//! the `mc_advanced` plugin) and the Rust DEM (same three laws, 1 and 2 threads); a dense periodic
//! packing (φ = 0.8) at growing N for the Rust DEM, in process (with its memory) and as a deck run by
//! both engines (LIGGGHTS on 1 and 2 MPI ranks, the Rust DEM on 1 and 2 threads); the contact-set
//! kernel at 2, 6 and 12 contacts.

mod hydrogel;
mod kernel;
mod nonlocal;
pub mod packing;

use std::collections::BTreeMap;

use serde::Serialize;

/// One measurement.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// `rust` or `liggghts`.
    pub engine: &'static str,
    /// `hertz`, `standard_mc` (γ only), `mc_advanced` (γ and MPR), or a kernel variant.
    pub model: String,
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
}

/// What `mcdem bench` prints and writes.
#[derive(Debug, Default, Serialize)]
pub struct Report {
    pub rows: Vec<Row>,
    /// Named ratios of rows of this run (costs: > 1 means slower).
    pub ratios: BTreeMap<String, f64>,
    /// Which row groups ran, and why others did not.
    pub notes: Vec<String>,
    /// Accuracy paid for speed: named errors of approximate rows against their exact run.
    pub errors: BTreeMap<String, f64>,
}

#[derive(Debug, Clone)]
pub struct Options {
    /// CI size: shorter strokes, smaller packings, fewer steps.
    pub quick: bool,
    /// Scene groups to run (names from [`SCENES`]); empty = all.
    pub scenes: Vec<String>,
}

/// The scene groups, in the order they run.
pub const SCENES: [&str; 4] = ["kernel", "packing", "hydrogel", "nonlocal"];

impl Options {
    fn runs(&self, scene: &str) -> bool {
        self.scenes.is_empty() || self.scenes.iter().any(|s| s == scene)
    }
}

/// Runs every available row group; `say` receives progress lines.
pub fn run(opts: Options, say: &mut dyn FnMut(&str)) -> Result<Report, String> {
    let mut report = Report::default();
    if let Some(bad) = opts.scenes.iter().find(|s| !SCENES.contains(&s.as_str())) {
        return Err(format!("ERROR: unknown bench scene '{bad}' (expected one of {})", SCENES.join(", ")));
    }
    if opts.runs("kernel") {
        kernel::rows(&opts, &mut report, say);
    }
    if opts.runs("packing") {
        packing::rows(&opts, &mut report, say)?;
    }
    if opts.runs("hydrogel") {
        hydrogel::rows(&opts, &mut report, say)?;
    }
    if opts.runs("nonlocal") {
        nonlocal::rows(&opts, &mut report, say)?;
    }
    ratios(&mut report);
    Ok(report)
}

fn find<'a>(r: &'a Report, engine: &str, model: &str, scene: &str, threads: usize) -> Option<&'a Row> {
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
    let pairs = [
        ("liggghts: mc_advanced / hertz", ("liggghts", "mc_advanced", 1), ("liggghts", "hertz", 1)),
        ("liggghts: standard_mc / hertz", ("liggghts", "standard_mc", 1), ("liggghts", "hertz", 1)),
        ("rust 1 thread: mc_advanced / hertz", ("rust", "mc_advanced", 1), ("rust", "hertz", 1)),
        ("rust 1 thread: standard_mc / hertz", ("rust", "standard_mc", 1), ("rust", "hertz", 1)),
        ("hertz: rust 1 thread / liggghts", ("rust", "hertz", 1), ("liggghts", "hertz", 1)),
        ("hertz: rust 2 threads / liggghts", ("rust", "hertz", 2), ("liggghts", "hertz", 1)),
        ("hertz: rust 2 threads / liggghts 2 ranks", ("rust", "hertz", 2), ("liggghts", "hertz", 2)),
        ("liggghts: hertz 2 ranks / 1 rank", ("liggghts", "hertz", 2), ("liggghts", "hertz", 1)),
        ("rust: hertz 2 threads / 1 thread", ("rust", "hertz", 2), ("rust", "hertz", 1)),
        ("mc_advanced: rust 1 thread / liggghts", ("rust", "mc_advanced", 1), ("liggghts", "mc_advanced", 1)),
    ];
    for (name, (e1, m1, t1), (e2, m2, t2)) in pairs {
        if let Some(v) = cost(find(r, e1, m1, h, t1), find(r, e2, m2, h, t2)) {
            out.insert(name.to_string(), v);
        }
    }
    for (tol, every, _) in hydrogel::APPROXIMATIONS {
        let m = hydrogel::approximate_model(tol, every);
        for (engine, label) in [("rust", "rust 1 thread"), ("liggghts", "liggghts")] {
            if let Some(v) = cost(find(r, engine, &m, h, 1), find(r, engine, "hertz", h, 1)) {
                out.insert(format!("{label}: {m} / hertz"), v);
            }
        }
        if let Some(v) = cost(find(r, "liggghts", &m, h, 2), find(r, "liggghts", "hertz", h, 2)) {
            out.insert(format!("liggghts 2 ranks: {m} / hertz"), v);
        }
    }
    // Cost per particle-step across packing sizes, relative to the smallest (1 thread).
    let sizes: Vec<&Row> = r
        .rows
        .iter()
        .filter(|x| x.scene.starts_with(packing::SCENE) && x.threads == 1 && x.model == "hertz")
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
        let row = |e: &str, t: usize| find(r, e, "hertz", &scene, t);
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
        s.push_str(&format!("  {k:<60} {v:.2}\n"));
    }
    if !r.errors.is_empty() {
        s.push_str("\nerrors of approximate rows:\n");
        for (k, v) in &r.errors {
            s.push_str(&format!("  {k:<60} {v:.2e}\n"));
        }
    }
    for n in &r.notes {
        s.push_str(&format!("note: {n}\n"));
    }
    s
}
