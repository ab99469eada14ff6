//! The `mcdem` command line.

use std::io::Read;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

#[derive(Parser)]
#[command(name = "mcdem", version, about = "Advanced multi-contact DEM for strongly deformed soft particles")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Evaluate the multi-contact kernel for one particle described in JSON (FILE or - for stdin)
    Contacts {
        /// JSON file, or - for standard input
        file: String,
    },
    /// Run a LIGGGHTS deck with the standalone engine: `mcdem run DECK [-var NAME VALUE]... [-log FILE]`
    Run {
        /// The input deck
        deck: PathBuf,
        /// Define an index variable before the deck is read (LIGGGHTS -var)
        #[arg(long = "var", short_alias = 'v', num_args = 2, value_names = ["NAME", "VALUE"], action = clap::ArgAction::Append, allow_hyphen_values = true)]
        var: Vec<String>,
        /// Log file (default log.liggghts; `none` for no log)
        #[arg(long = "log")]
        log: Option<PathBuf>,
        #[command(flatten)]
        flags: RunFlags,
    },
    /// Nonlocal quasi-static reference (Gonzalez & Cuitiño 2012): solve a JSON scene along its loading path
    Nonlocal {
        /// Scene file (JSON, see docs/nonlocal.md)
        scene: PathBuf,
        /// Per-step CSV output (default: standard output)
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Also write every contact force, one CSV per step, into this directory
        #[arg(long)]
        contacts: Option<PathBuf>,
    },
    /// Piston compression of a packing by the nonlocal solver (the 514-particle hydrogel box by default)
    Uniaxial {
        /// Start state: LIGGGHTS/mcdem `dump custom` file with id radius x y z (last frame)
        start: PathBuf,
        /// Particle Poisson ratio (E = 23.3 kPa, walls 50 MPa / 0.5)
        #[arg(long, default_value_t = 0.5)]
        nu: f64,
        /// Kernel: boussinesq | none | sphere
        #[arg(long, default_value = "boussinesq")]
        kernel: String,
        /// Load steps from the start height to the end height
        #[arg(long, default_value_t = 40)]
        steps: usize,
        /// Piston start height [m]
        #[arg(long, default_value_t = mcdem::nonlocal::uniaxial::HYDROGEL_Z_START)]
        z_start: f64,
        /// Piston end height [m] (0.11578: φ = 0.85)
        #[arg(long, default_value_t = 0.11578)]
        z_end: f64,
        /// Solid volume for φ [m³] (default: the hydrogel packing's 2.695884e-3; `spheres`: sum of
        /// the sphere volumes of the start file)
        #[arg(long)]
        solid_volume: Option<String>,
        /// Per-step CSV output (default: standard output)
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
    /// Speed of every engine and model on the same scenes, measured side by side (ratios)
    Bench {
        /// CI size: short strokes, smaller packings
        #[arg(long)]
        quick: bool,
        /// Also write the rows and ratios as JSON
        #[arg(long)]
        json: Option<PathBuf>,
        /// Run only this scene group (repeatable; default: all)
        #[arg(long = "scene", value_parser = clap::builder::PossibleValuesParser::new(mcdem::bench::SCENES))]
        scenes: Vec<String>,
        /// Passes over the selected groups; rates and ratios are the medians over the passes
        #[arg(long, default_value_t = 1)]
        rounds: usize,
        /// Directory of the PNGs of `--scene budget` (one speed–error front per scene)
        #[arg(long, default_value = ".")]
        plots: PathBuf,
        /// Only write the dense packing with 4 K³ spheres as a data file for
        /// liggghts_inputs/dense_packing.in (prints the time step it was built for), then stop
        #[arg(long, num_args = 2, value_names = ["K", "FILE"], allow_negative_numbers = true)]
        write_packing: Option<Vec<String>>,
    },
    /// Fit advanced MC (γ, MPR, and E where ν > 0.3) per Poisson ratio against the nonlocal reference (Fig. 5)
    Calibrate {
        /// CI size: 4× piston speed, ν = 0.5 only unless --nu is given, shorter searches
        #[arg(long)]
        quick: bool,
        /// Poisson ratios (comma-separated); default 0.25,0.3,0.35,0.4,0.45,0.5
        #[arg(long, value_delimiter = ',')]
        nu: Vec<f64>,
        /// Output directory (calibration.csv, .json, .md, .png; with --heldout heldout.csv, .json, .md)
        #[arg(long, default_value = "validation/report")]
        out: PathBuf,
        /// Instead of fitting: measure the recorded calibration on curves it was not fitted on
        /// (decompression, first compression, another packing, bcc and single-sphere dies)
        #[arg(long)]
        heldout: bool,
        /// With --heldout: the calibration to check (a calibration.csv); default the built-in one
        #[arg(long, value_name = "FILE")]
        calibration: Option<PathBuf>,
        /// With --heldout: leave out the other packing (the `uniaxial` case run on it measures it)
        #[arg(long)]
        skip_other_packing: bool,
        /// With --heldout: read the fitted curve's nonlocal reference from a `validate` uniaxial.csv
        #[arg(long, value_name = "FILE")]
        fit_reference: Option<PathBuf>,
    },
    /// Parameter studies with the standalone engine
    Study {
        #[command(subcommand)]
        study: Study,
    },
    /// Implicit finite-strain MPM of one soft particle between walls (JSON scene, see docs/mpm.md)
    Mpm {
        /// Scene file (JSON)
        scene: PathBuf,
        /// Output directory (history.csv, points.csv, PNG charts)
        #[arg(long, default_value = "mpm_out")]
        out: PathBuf,
        /// Write VTK snapshots of the points and walls every N steps into OUT/vtk (ParaView: open
        /// vtk/points.vtk.series)
        #[arg(long, value_name = "N")]
        vtk_every: Option<usize>,
    },
    /// Fits the compaction laws of Nezamabadi et al. (2019), Eqs. 21–23, to `mcdem mpm` packing runs
    /// (one output directory per λ) and draws Figs. 11–15 (see docs/mpm.md)
    MpmFit {
        /// Output directories of `mcdem mpm` runs (packing.csv, scene.json)
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// Where fit.md and the charts go
        #[arg(long, default_value = "mpm_fit")]
        out: PathBuf,
        /// Jamming point Φ₀ (default: from the data, where the runs' ε(Φ) part; needs two runs)
        #[arg(long)]
        phi0: Option<f64>,
    },
    /// Finite-element continuum reference: one sphere between rigid frictionless walls (JSON scene, see src/fem/scene.rs)
    Continuum {
        /// Scene file (JSON)
        scene: PathBuf,
        /// Output directory (continuum.csv, continuum.png)
        #[arg(long, default_value = "continuum_out")]
        out: PathBuf,
    },
    /// Compare two LIGGGHTS-format outputs (dump custom, fix ave/time or fix print tables) column by column
    Compare(mcdem::compare::Args),
    /// Make a packing of the project's own: `hydrogel` is the 514-sphere packing of the uniaxial
    /// case (validation/cases/uniaxial/README.md); `--describe FILE` prints the statistics of a
    /// LIGGGHTS data file of that box instead (e.g. the Debian example's, to compare)
    Packing {
        /// Which packing (hydrogel)
        #[arg(value_parser = ["hydrogel"])]
        kind: String,
        /// Seed of the random placement
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Data file to write
        #[arg(long, required_unless_present = "describe")]
        out: Option<PathBuf>,
        /// Describe this data file instead of making one
        #[arg(long, value_name = "FILE")]
        describe: Option<PathBuf>,
    },
    /// Run the validation suite and write the report
    Validate {
        /// Quick subset (CI)
        #[arg(long)]
        quick: bool,
        /// Run only this case (repeatable); default: all
        #[arg(long = "case", value_name = "NAME")]
        cases: Vec<String>,
        /// Output directory
        #[arg(long, default_value = "validation/report")]
        out: PathBuf,
    },
}

#[derive(Subcommand)]
enum Study {
    /// Lees–Edwards simple shear over (φ, μ, ν, γ̂) with the advanced MC law; Eq. 8 response surface
    /// next to the paper's Tables D.1/D.2 (docs/shear.md). Resumable: finished runs are skipped.
    Shear {
        /// quick (a few minutes on two cores) or full (the paper's grid)
        #[arg(long, value_parser = ["quick", "full"])]
        grid: String,
        /// Output directory (default validation/shear_<grid>)
        #[arg(long)]
        out: Option<PathBuf>,
        /// Particles per run (default: 250 quick, 2000 full)
        #[arg(long)]
        n: Option<usize>,
        /// Geometric prefactor γ of Eq. 2 for every ν (default: per ν from the recorded calibration)
        #[arg(long)]
        gamma: Option<f64>,
        /// Maximum penetration ratio of Eq. 3 for every ν (default: per ν from the recorded calibration)
        #[arg(long)]
        mpr: Option<f64>,
        /// Friction coefficients to run, comma-separated (default: the grid's); a sub-grid's
        /// finished runs count for a later call on the whole grid in the same directory
        #[arg(long, value_delimiter = ',')]
        mu: Vec<f64>,
        /// Poisson ratios to run, comma-separated (default: the grid's)
        #[arg(long, value_delimiter = ',')]
        nu: Vec<f64>,
        /// Runs side by side, one thread each (default 2)
        #[arg(long, default_value_t = 2)]
        threads: usize,
        /// Skip the cost-vs-N measurement
        #[arg(long)]
        no_cost: bool,
        /// Only the cost-vs-N measurement (no grid run is started; finished runs are still reported)
        #[arg(long, conflicts_with = "no_cost")]
        cost_only: bool,
        /// Rewrite runs.csv, response_surface.csv, the plots and report.md from the finished runs in
        /// DIR/runs and the cached cost rows only: nothing is run or measured
        #[arg(long, conflicts_with = "cost_only")]
        report_only: bool,
        /// Iterate Eq. 2 to its fixed point within each step instead of lagging it one step (the
        /// paper's and LIGGGHTS' scheme, the default); 11–18 force passes per step where measured
        #[arg(long)]
        eq2_fixed_point: bool,
    },
}

fn study(s: Study) -> Result<(), String> {
    match s {
        Study::Shear {
            grid,
            out,
            n,
            gamma,
            mpr,
            mu,
            nu,
            threads,
            no_cost,
            cost_only,
            report_only,
            eq2_fixed_point,
        } => {
            use mcdem::study::shear;
            let mut g = if grid == "full" { shear::Grid::full() } else { shear::Grid::quick() };
            if let Some(n) = n {
                g.n = n;
            }
            use mcdem::physics::material::{check_friction, check_poisson_ratio};
            if let Some(m) = mu.iter().find(|m| check_friction(**m).is_err()) {
                return Err(format!("--mu {m}: a friction coefficient must be finite and >= 0"));
            }
            if let Some(v) = nu.iter().find(|v| check_poisson_ratio(**v).is_err()) {
                return Err(format!("--nu {v}: a Poisson ratio must lie in [0, 0.5]"));
            }
            if !mu.is_empty() {
                g.mus = mu;
            }
            if !nu.is_empty() {
                g.nus = nu;
            }
            g.gamma_mc = gamma;
            g.mpr = mpr;
            g.eq2_fixed_point = eq2_fixed_point;
            if no_cost {
                g.cost_sizes.clear();
            }
            let out = out.unwrap_or_else(|| PathBuf::from(format!("validation/shear_{grid}")));
            let opts = shear::Options { grid: g, out: out.clone(), threads, cost_only, report_only };
            let sum = shear::run(&opts, &|l| eprintln!("{l}"))?;
            for (mu, (pc, lo)) in &sum.phi_c {
                println!("mu {mu}: phi_c {pc:.4} (free fit, searched from {lo})");
            }
            for j in &sum.jamming {
                if let Some((pc, err, src)) = j.data {
                    println!("mu {}: phi_c {pc:.4} +- {err:.4} from the rate data ({src})", j.mu);
                }
            }
            // A (μ, ν) without quasi-static points has no fit (all of them in a cost-only call).
            for r in sum.surface.iter().filter(|r| r.points > 0) {
                println!(
                    "mu {} nu {}: alpha {:.4} (paper {:.4}) beta {:.4} (paper {:.4}) from {} points",
                    r.mu, r.nu, r.alpha, r.alpha_paper, r.beta, r.beta_paper, r.points
                );
            }
            println!("{} runs done now, {} skipped (already finished)", sum.ran, sum.skipped);
            println!("report: {}", out.join("report.md").display());
            // A run whose stop converged in Δt met the contact law's limit: a result about the
            // model (listed in the report), not a failure of the command.
            let (range, other): (Vec<_>, Vec<_>) =
                sum.failed.iter().partition(|(_, e)| e.starts_with(shear::OUT_OF_RANGE));
            if !range.is_empty() {
                println!(
                    "{} run(s) out of the model's range (the stop converges in the time step or persists down to a quarter of it; listed in the report and stops.csv)",
                    range.len()
                );
            }
            if other.is_empty() {
                Ok(())
            } else if report_only {
                // Rewriting the report does not settle the stops: say so, but the report is written.
                eprintln!(
                    "note: {} run(s) stopped for another cause or are unclassified (listed in the report)",
                    other.len()
                );
                Ok(())
            } else {
                Err(format!(
                    "{} run(s) stopped for another cause than the contact law's range or are unclassified (a \
                     .failed file the study cannot classify: delete it to rerun): {}",
                    other.len(),
                    other.iter().map(|(k, e)| format!("{k}: {e}")).collect::<Vec<_>>().join("; ")
                ))
            }
        }
    }
}

fn read_input(file: &str) -> Result<String, String> {
    if file == "-" {
        let mut s = String::new();
        std::io::stdin().read_to_string(&mut s).map_err(|e| format!("cannot read standard input: {e}"))?;
        Ok(s)
    } else {
        std::fs::read_to_string(file).map_err(|e| format!("cannot read {file}: {e}"))
    }
}

fn contacts(file: &str) -> Result<(), String> {
    let out = mcdem::contacts_cli::evaluate(&read_input(file)?)?;
    println!("{}", serde_json::to_string(&out).map_err(|e| e.to_string())?);
    Ok(())
}

fn packing(seed: u64, out: Option<PathBuf>, describe: Option<PathBuf>) -> Result<(), String> {
    use mcdem::validate::packing;
    let s = match (describe, out) {
        (Some(file), _) => {
            let m = mcdem::physics::Material::hertz(23.3e3, 0.5).map_err(|e| e.to_string())?;
            let (spheres, _) = mcdem::nonlocal::scene::read_liggghts_data(&file, m)?;
            let list: Vec<_> = spheres.iter().map(|s| (s.id as i64, 2.0 * s.radius, s.x)).collect();
            let v = vec![mcdem::physics::Vec3::zeros(); list.len()];
            packing::stats(&list, &v)
        }
        (None, Some(out)) => {
            let s = packing::make(seed, &out)?;
            println!("wrote {}", out.display());
            s
        }
        (None, None) => return Err("packing: give --out FILE or --describe FILE".into()),
    };
    println!(
        "diameter mean {:.5} m, SD {:.5} m, range {:.5} .. {:.5} m; top {:.4} m, phi below the top {:.4}; \
         {:.2} contacts per sphere (neighbours and walls); kinetic energy {:.2e} J",
        s.diameter_mean,
        s.diameter_sd,
        s.diameter_min,
        s.diameter_max,
        s.top,
        s.phi_below_top,
        s.contacts_per_sphere,
        s.kinetic_energy
    );
    Ok(())
}

fn validate(quick: bool, cases: Vec<String>, out: PathBuf) -> Result<(), String> {
    let opts = mcdem::validate::Options { quick, out: out.clone(), progress: None };
    let results = mcdem::validate::run(&opts, &cases)?;
    let failed: Vec<_> = results.iter().filter(|r| !r.passed).map(|r| r.name).collect();
    let targets: Vec<_> = results.iter().flat_map(|r| &r.targets).collect();
    println!(
        "{} passed, {} failed; paper targets met: {}/{}",
        results.len() - failed.len(),
        failed.len(),
        targets.iter().filter(|t| t.met).count(),
        targets.len()
    );
    println!("report: {}", out.join("report.md").display());
    if failed.is_empty() {
        Ok(())
    } else {
        Err(format!("validation case(s) failed: {}", failed.join(", ")))
    }
}

/// `mcdem run`'s thread use of the force passes ([`mcdem::engine::PairThreads`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ThreadsMode {
    Auto,
    Serial,
    Parallel,
}

/// `mcdem run`'s flags beyond the deck, its variables and the log.
#[derive(Debug, clap::Args)]
struct RunFlags {
    /// No progress bar even on a terminal
    #[arg(long)]
    no_progress: bool,
    /// Multi-contact geometry tolerance, as a fraction of the particle radius: keep each
    /// particle's Eq. 2 geometry until a contact point moved this far (0 = exact, the default;
    /// an approximation that trades accuracy for speed, see docs/dem.md)
    #[arg(long, default_value_t = 0.0)]
    mc_geometry_tolerance: f64,
    /// Multi-contact update interval in steps: recompute the radius changes every K steps and
    /// at neighbour-list builds, keep them in between (default: the deck's `updateEvery`, else
    /// 1 = every step, exact; an approximation that trades accuracy for speed, see docs/dem.md)
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=mcdem::deck::MAX_UPDATE_EVERY))]
    mc_update_every: Option<u64>,
    /// Multi-contact accuracy budget EPS (overrides the deck's `mcAccuracy`): each particle
    /// reuses its last exact Eq. 2 radius changes while a bound on their error stays below
    /// EPS times their size (0 = exact; see docs/dem.md "Accuracy budget")
    #[arg(long)]
    mc_accuracy: Option<f64>,
    /// Every K steps, compute the exact radius changes as a shadow (not used for the forces)
    /// and report the measured error next to the bound (overrides `mcAccuracyCheck`)
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    mc_accuracy_check: Option<u64>,
    /// Whether a step's force passes use both threads of the pool: `auto` (default) times
    /// windows of steps each way every 5000 steps (sooner after it chose one core) and keeps
    /// the faster; `serial` and `parallel` fix the choice. Results are bit-identical in all
    /// three; only speed differs.
    #[arg(long, value_enum, default_value_t = ThreadsMode::Auto)]
    threads_mode: ThreadsMode,
}

fn run(deck: PathBuf, var: Vec<String>, log: Option<PathBuf>, flags: RunFlags) -> Result<(), String> {
    let RunFlags {
        no_progress,
        mc_geometry_tolerance,
        mc_update_every,
        mc_accuracy,
        mc_accuracy_check,
        threads_mode,
    } = flags;
    if !(mc_geometry_tolerance.is_finite() && mc_geometry_tolerance >= 0.0) {
        return Err(format!(
            "ERROR: --mc-geometry-tolerance must be a finite number >= 0 (a fraction of the particle radius), got {mc_geometry_tolerance}"
        ));
    }
    if let Some(eps) = mc_accuracy {
        if !(eps.is_finite() && eps >= 0.0) {
            return Err(format!(
                "ERROR: --mc-accuracy must be a finite number >= 0 (the relative error budget of the multi-contact corrections; 0 = exact), got {eps}"
            ));
        }
        if eps > 0.0 && (mc_geometry_tolerance > 0.0 || mc_update_every.is_some_and(|k| k > 1)) {
            return Err("ERROR: --mc-accuracy cannot be combined with --mc-geometry-tolerance or --mc-update-every: the accuracy budget decides per particle and step when Eq. 2 is recomputed".into());
        }
    }
    let vars = var.chunks(2).map(|c| (c[0].clone(), c[1].clone())).collect();
    let opts = mcdem::deck::Options {
        vars,
        log,
        progress: !no_progress,
        quiet: false,
        mc_geometry_tolerance,
        mc_every: mc_update_every.unwrap_or(0),
        mc_accuracy,
        mc_accuracy_check,
        pair_threads: match threads_mode {
            ThreadsMode::Auto => mcdem::engine::PairThreads::Auto,
            ThreadsMode::Serial => mcdem::engine::PairThreads::Serial,
            ThreadsMode::Parallel => mcdem::engine::PairThreads::Parallel,
        },
    };
    mcdem::deck::run_file(&deck, &opts).map(|_| ()).map_err(|e| format!("ERROR: {e}"))
}

/// LIGGGHTS spells its options with one dash (`-var`, `-log`); accept both spellings.
fn liggghts_args() -> Vec<String> {
    std::env::args()
        .map(|a| match a.as_str() {
            "-var" => "--var".to_string(),
            "-log" => "--log".to_string(),
            _ => a,
        })
        .collect()
}

fn nonlocal(scene: PathBuf, out: Option<PathBuf>, contacts: Option<PathBuf>) -> Result<(), String> {
    let mut scene = mcdem::nonlocal::scene::Scene::load(&scene)?;
    let mut sink: Box<dyn std::io::Write> = match &out {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).map_err(|e| format!("cannot create {}: {e}", p.display()))?,
        )),
        None => Box::new(std::io::stdout().lock()),
    };
    let summary = scene.run(&mut *sink, contacts.as_deref(), &mut |line| eprintln!("{line}"))?;
    sink.flush().map_err(|e| format!("cannot write output: {e}"))?;
    eprintln!("done: {} load steps in {:.2} s", summary.steps, summary.wall_seconds);
    Ok(())
}

fn heldout(opts: mcdem::validate::heldout::Options) -> Result<(), String> {
    let out = opts.out.clone();
    let r = mcdem::validate::heldout::run(&opts)?;
    for e in r.entries.iter().filter(|e| e.model == "mc_advanced_calibrated") {
        println!(
            "nu {:.2}: {:<18} NRMSE {:.2} %{}",
            e.nu,
            e.curve,
            100.0 * e.nrmse,
            if e.fitted { " (fitted)" } else { "" }
        );
    }
    println!("report: {}", out.join("heldout.md").display());
    Ok(())
}

fn calibrate(quick: bool, nus: Vec<f64>, out: PathBuf) -> Result<(), String> {
    let fits = mcdem::validate::calibrate::run(&mcdem::validate::calibrate::Options {
        quick,
        nus,
        out: out.clone(),
    })?;
    for f in &fits {
        println!(
            "nu {:.2}: gamma {:.3} MPR {:.3} E {:.4e} Pa NRMSE {:.2} % (Hertz {:.2} %)",
            f.nu,
            f.gamma,
            f.mpr,
            f.youngs_modulus_pa,
            100.0 * f.nrmse,
            100.0 * f.hertz_nrmse
        );
    }
    println!("report: {}", out.join("calibration.md").display());
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn uniaxial(
    start: PathBuf,
    nu: f64,
    kernel: String,
    steps: usize,
    z_start: f64,
    z_end: f64,
    solid_volume: Option<String>,
    out: Option<PathBuf>,
) -> Result<(), String> {
    use mcdem::nonlocal::uniaxial::{self, Uniaxial};
    let mut u = Uniaxial::hydrogel(nu, steps)?;
    u.z_start = z_start;
    u.z_end = z_end;
    let spheres = mcdem::nonlocal::scene::read_liggghts_dump(&start, u.particle)?;
    match solid_volume.as_deref() {
        None => {}
        Some("spheres") => {
            u.solid_volume =
                spheres.iter().map(|s| 4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3)).sum();
        }
        Some(v) => {
            u.solid_volume = v
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v > 0.0)
                .ok_or_else(|| format!("--solid-volume {v}: expected a volume > 0 or 'spheres'"))?;
        }
    }
    let kernel = mcdem::nonlocal::Kernel::new(kernel.parse()?, 1.0)?;
    let clock = std::time::Instant::now();
    let points = uniaxial::compress_with(&spheres, &u, kernel, &mut |p| {
        eprintln!(
            "step {}/{}: phi {:.4} sigma {:.4e} Pa Z {:.3} newton {} fire {} halvings {} residual {:.2e} ({:.2} s)",
            p.step,
            u.steps,
            p.phi,
            p.sigma_piston,
            2.0 * p.contacts as f64 / spheres.len() as f64,
            p.iterations,
            p.fire_steps,
            p.subdivisions,
            p.residual,
            p.seconds
        )
    })
    .map_err(|e| e.to_string())?;
    let secs = clock.elapsed().as_secs_f64();
    let mut sink: Box<dyn std::io::Write> = match &out {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).map_err(|e| format!("cannot create {}: {e}", p.display()))?,
        )),
        None => Box::new(std::io::stdout().lock()),
    };
    uniaxial::write_csv(&mut *sink, &points, kernel, &u, &start.display().to_string())
        .and_then(|_| sink.flush())
        .map_err(|e| format!("cannot write output: {e}"))?;
    let iters: usize = points.iter().map(|p| p.iterations).sum();
    eprintln!("done: {} load steps, {iters} Newton iterations in {secs:.2} s", u.steps);
    for (phi, z) in uniaxial::HYDROGEL_Z_PHI {
        if let Some(s) = uniaxial::sigma_at_z(&points, z) {
            eprintln!("sigma(phi = {phi:.2}, z = {z}) = {s:.4e} Pa");
        }
    }
    Ok(())
}

fn bench(
    quick: bool,
    json: Option<PathBuf>,
    scenes: Vec<String>,
    rounds: usize,
    plots: PathBuf,
    write: Option<Vec<String>>,
) -> Result<(), String> {
    if let Some(w) = write {
        let k: usize =
            w[0].parse().ok().filter(|k| (1..=200).contains(k)).ok_or_else(|| {
                format!("ERROR: --write-packing K: '{}' is not a cell count in 1..200", w[0])
            })?;
        let world = mcdem::bench::packing::scene(k, false)?;
        mcdem::bench::packing::write_data(&world, std::path::Path::new(&w[1]))?;
        println!("{} spheres written to {}; run it with -var dt {:?}", world.p.len(), w[1], world.dt);
        return Ok(());
    }
    let report =
        mcdem::bench::run(mcdem::bench::Options { quick, scenes, rounds, plots }, &mut |l| eprintln!("{l}"))?;
    print!("{}", mcdem::bench::table(&report));
    if let Some(p) = json {
        let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        std::fs::write(&p, text).map_err(|e| format!("cannot write {}: {e}", p.display()))?;
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse_from(liggghts_args());
    let result = match cli.command {
        Command::Contacts { file } => contacts(&file),
        Command::Validate { quick, cases, out } => validate(quick, cases, out),
        Command::Packing { kind: _, seed, out, describe } => packing(seed, out, describe),
        // The time loop runs on a worker of the thread pool, whose size (RAYON_NUM_THREADS, else
        // the cores) sets the members of the engine's team of threads.
        Command::Run { deck, var, log, flags } => rayon::scope(|_| run(deck, var, log, flags)),
        Command::Nonlocal { scene, out, contacts } => nonlocal(scene, out, contacts),
        Command::Bench { quick, json, scenes, rounds, plots, write_packing } => {
            bench(quick, json, scenes, rounds, plots, write_packing)
        }
        Command::Calibrate {
            quick,
            nu,
            out,
            heldout: true,
            calibration,
            skip_other_packing,
            fit_reference,
        } => heldout(mcdem::validate::heldout::Options {
            quick,
            nus: nu,
            out,
            calibration,
            other_packing: !skip_other_packing,
            fit_reference,
        }),
        Command::Calibrate { calibration, skip_other_packing, fit_reference, .. }
            if calibration.is_some() || skip_other_packing || fit_reference.is_some() =>
        {
            Err("--calibration, --skip-other-packing and --fit-reference go with --heldout".into())
        }
        Command::Calibrate { quick, nu, out, .. } => calibrate(quick, nu, out),
        Command::Uniaxial { start, nu, kernel, steps, z_start, z_end, solid_volume, out } => {
            uniaxial(start, nu, kernel, steps, z_start, z_end, solid_volume, out)
        }
        Command::Study { study: s } => study(s),
        Command::Mpm { scene, out, vtk_every } => mcdem::mpm::cli::run(&scene, &out, vtk_every),
        Command::MpmFit { runs, out, phi0 } => mcdem::mpm::cli::fit(&runs, &out, phi0),
        Command::Continuum { scene, out } => mcdem::fem::scene::run(&scene, &out),
        // Its own exit statuses (0 agree, 1 differ, 2 unreadable input): see docs/compare.md.
        Command::Compare(args) => return mcdem::compare::cli(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.starts_with("ERROR: ") => {
            eprintln!("{e}");
            ExitCode::from(1)
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
