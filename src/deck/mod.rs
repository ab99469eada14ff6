//! LIGGGHTS deck reader: variables, commands → engine setup, `run`, and LIGGGHTS-format output.
//!
//! The accepted subset is documented in `docs/dem.md`. Output-only commands without effect here
//! (`compute_modify`) are skipped with a one-line warning; every other unknown command or keyword
//! stops with `ERROR: FILE:LINE: unsupported …`,
//! because a silently ignored setting would give a different simulation.

mod atom_vars;
mod atoms;
mod budget_report;
mod commands;
pub mod data_file;
mod dumps;
pub mod expr;
mod fixes;
pub mod format;
mod groups;
mod lattice;
mod lexer;
mod local;
pub mod output;
mod pair;
mod regions;
mod restart;
mod run;
mod scope;
mod tet_mesh;
mod thermo;
mod variables;
mod vtk;

use std::collections::HashMap;
use std::fmt;
use std::fs::File;
use std::io::{BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::engine::{
    Closure, CylinderWall, Domain, Mesh, PlaneWall, StepError, WallFix, WallGeom, World, GROUP_ALL,
};
use crate::physics::hertz::Tangential;
use crate::physics::{Material, MprTest, Vec3};
use lexer::strip_comment;
use output::{AveTime, Col, Dump};
use pair::GranModel;
pub use pair::MAX_UPDATE_EVERY;

/// Command-line options of `mcdem run`.
#[derive(Debug, Default, Clone)]
pub struct Options {
    /// `-var NAME VALUE` pairs (index-style variables, defined before the deck is read).
    pub vars: Vec<(String, String)>,
    /// `-log FILE` (default `log.liggghts`, as LIGGGHTS); `none` disables it.
    pub log: Option<PathBuf>,
    /// Allow a progress bar (only shown when standard output is a terminal).
    pub progress: bool,
    /// Nothing on standard output (the log file, if any, still gets everything): for decks run
    /// in-process by `mcdem validate`.
    pub quiet: bool,
    /// Thread use of the pair loop (default: timing probe); results do not depend on it.
    pub pair_threads: crate::engine::PairThreads,
    /// Multi-contact geometry tolerance ([`crate::engine::World::mc_geometry_tolerance`]; 0 = exact).
    pub mc_geometry_tolerance: f64,
    /// Multi-contact update interval ([`crate::engine::World::mc_every`]; 0 = the deck's, else 1).
    pub mc_every: u64,
    /// Multi-contact accuracy budget ([`crate::engine::World::mc_accuracy`]; `None`: the deck's).
    pub mc_accuracy: Option<f64>,
    /// Shadow check interval of the budget ([`crate::engine::World::mc_accuracy_check`]; `None`: the deck's).
    pub mc_accuracy_check: Option<u64>,
}

/// Runs a deck file. Errors come back as `FILE:LINE: message`.
pub fn run_file(path: &Path, opts: &Options) -> Result<RunSummary, String> {
    run_file_checked(path, opts).map_err(String::from)
}

/// Why a deck run failed: the message (`FILE:LINE: …`) and, when the engine stopped on an
/// instability (overlap beyond a radius, a non-finite value, a lost particle), that stop. Callers
/// that search parameters (`mcdem calibrate`, the standard-MC γ ladder) tell an unstable law,
/// which is a result, from a broken deck or file, which is not.
#[derive(Debug, Clone)]
pub struct DeckFailure {
    pub message: String,
    pub instability: Option<StepError>,
}

impl DeckFailure {
    /// A failure that is not an engine stop.
    pub fn other(message: String) -> Self {
        DeckFailure { message, instability: None }
    }

    /// The same failure with `prefix: ` before its message.
    pub fn context(self, prefix: &str) -> Self {
        DeckFailure { message: format!("{prefix}: {}", self.message), ..self }
    }
}

impl fmt::Display for DeckFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl From<DeckFailure> for String {
    fn from(e: DeckFailure) -> String {
        e.message
    }
}

/// [`run_file`], with an engine stop kept apart from other failures.
pub fn run_file_checked(path: &Path, opts: &Options) -> Result<RunSummary, DeckFailure> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| DeckFailure::other(format!("cannot read deck {}: {e}", path.display())))?;
    let mut deck = Deck::new(path, opts).map_err(DeckFailure::other)?;
    let r = deck.execute(&text, path);
    if let Err(message) = r {
        return Err(DeckFailure { message, instability: deck.instability.take() });
    }
    deck.finish();
    Ok(deck.summary)
}

/// Totals of a deck run (for benchmarks and tests).
#[derive(Debug, Default, Clone, Copy)]
pub struct RunSummary {
    pub steps: u64,
    pub particle_steps: f64,
    pub loop_seconds: f64,
    pub neighbor_builds: u64,
    /// The multi-contact accuracy budget over the run (all zero without `mcAccuracy`).
    pub mc_budget: crate::engine::BudgetStats,
}

#[derive(Debug, Clone)]
enum Var {
    Index(String),
    /// `index` or `universe` with several values: the current one is `values[at]`.
    List {
        values: Vec<String>,
        at: usize,
    },
    Equal(String),
    /// `variable NAME atom EXPR`: one value per particle (see `atom_vars.rs`).
    Atom(String),
    /// `variable NAME loop N1 N2`: the current value, advanced by `next` up to `last`.
    Loop {
        value: i64,
        last: i64,
    },
}

#[derive(Debug, Clone)]
enum FixKind {
    Property,
    Gravity,
    Wall(usize),
    MeshSurface(usize),
    MoveMesh(usize),
    Nve,
    AveTime(usize),
    MultiContact,
    Deform,
    /// `insert/pack`: `unfix` drops its insertions not yet done.
    Insert,
    /// `check/timestep/gran`: index into `Deck::checks`.
    CheckTimestep(usize),
    /// `momentum`: its entry in `Deck::momenta` (by fix ID).
    Momentum,
    /// `adapt N atom diameter v_NAME`: every `every` steps (and at each run's set-up) the
    /// diameters become the variable's values (`fixes/adapt.rs`).
    Adapt {
        every: u64,
        var: String,
    },
}

#[derive(Debug, Clone)]
enum ComputeKind {
    ERotate,
    Ke,
    /// Eq. 4 stress: scalar p; vector [1..9] σ row-major (xx xy xz yx yy yz zx zy zz),
    /// [10] p, [11] contact p, [12] kinetic p.
    Stress,
    /// Coordination number Z = 2 N_c / N (particle–particle contacts).
    Coord,
    /// `property/atom`: per-particle columns, read by atom-style variables (`atom_vars.rs`).
    PropertyAtom(Vec<Col>),
}

struct Deck {
    world: World,
    /// The engine stop that ended the run, if one did (see [`DeckFailure`]).
    instability: Option<StepError>,
    vars: HashMap<String, Var>,
    deck_dir: PathBuf,
    log: Option<BufWriter<File>>,
    props: HashMap<String, (String, Vec<f64>)>,
    pair: Option<GranModel>,
    /// The model of the `fix wall/gran` walls (all walls run one model; it may drop the pair
    /// style's cohesion, or be `hooke` beside `hooke/hysteresis` pairs).
    wall_model: Option<GranModel>,
    mc_gamma: Option<f64>,
    fixes: Vec<(String, FixKind)>,
    computes: HashMap<String, ComputeKind>,
    regions: HashMap<String, regions::Region>,
    /// `lattice`: the sites `create_atoms … region` fills.
    lattice: Option<lattice::Lattice>,
    groups: groups::Groups,
    /// `thermo_modify lost`: error (the default), ignore or warn.
    lost_policy: String,
    /// `fix particletemplate/sphere` and `fix particledistribution/discrete` definitions, and the
    /// `fix insert/pack` insertions waiting for the next run.
    insertion: fixes::insert::Insertion,
    periodic: [bool; 3],
    /// Shrink-wrapped axes (`boundary m` or `s`): the box follows the particles.
    shrink: [bool; 3],
    /// `boundary m` (true) or `s` on a shrink-wrapped axis.
    shrink_min: [bool; 3],
    /// The box as created, the minimum of a `boundary m` axis.
    box0: Option<(Vec3, Vec3)>,
    ntypes: usize,
    thermo_every: u64,
    thermo_cols: Vec<String>,
    thermo_float: Option<format::Spec>,
    dumps: Vec<Dump>,
    local_dumps: Vec<local::LocalDump>,
    vtk_dumps: Vec<vtk::VtkDump>,
    pair_locals: HashMap<String, local::PairLocal>,
    aves: Vec<Option<AveTime>>,
    /// `fix check/timestep/gran` (`None` after `unfix`).
    checks: Vec<Option<fixes::check_timestep::CheckTimestep>>,
    /// `fix momentum`, in definition order.
    momenta: Vec<fixes::momentum::Momentum>,
    progress: bool,
    quiet: bool,
    /// Multi-contact approximations given on the command line (they override the deck's; 0: none).
    cli_geometry_tolerance: f64,
    cli_mc_every: u64,
    cli_mc_accuracy: Option<f64>,
    cli_mc_accuracy_check: Option<u64>,
    summary: RunSummary,
    line_no: usize,
    /// The deck file being read (for `FILE:LINE` in warnings).
    file: String,
    scratch: Vec<f64>,
    /// Label a `jump SELF LABEL` asked for: the running file continues after it.
    pending_jump: Option<String>,
    /// Set when `next` exhausts a variable: the following `jump` is skipped (ends the loop).
    skip_jump: bool,
}

type R<T> = Result<T, String>;

fn unsupported(what: &str) -> String {
    format!("unsupported {what}")
}

/// A finite number: Rust also parses "inf" and "NaN", which no deck value may be (a NaN would run
/// on silently; LAMMPS's own infinite bounds, `INF`/`EDGE`, are read by the region code).
fn num(s: &str) -> R<f64> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("expected a finite number, got \"{s}\"")),
        Err(_) => Err(format!("expected a number, got \"{s}\"")),
    }
}

fn int(s: &str) -> R<i64> {
    if let Ok(v) = s.parse::<i64>() {
        return Ok(v);
    }
    let f = num(s)?;
    if f.fract() == 0.0 && f.abs() < 9e15 {
        Ok(f as i64)
    } else {
        Err(format!("expected an integer, got \"{s}\""))
    }
}

impl Deck {
    fn new(path: &Path, opts: &Options) -> R<Self> {
        let log_path = opts.log.clone().unwrap_or_else(|| PathBuf::from("log.liggghts"));
        let log = if log_path.as_os_str() == "none" { None } else { Some(output::create(&log_path)?) };
        let mut vars = HashMap::new();
        for (k, v) in &opts.vars {
            vars.insert(k.clone(), Var::Index(v.clone()));
        }
        let mut world = World::new();
        world.skin = 0.0;
        world.pair_threads = opts.pair_threads;
        // LAMMPS sorts atoms spatially every 1000 steps unless `atom_modify sort` says otherwise.
        world.sort_every = 1000;
        Ok(Deck {
            instability: None,
            world,
            vars,
            deck_dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
            log,
            props: HashMap::new(),
            pair: None,
            wall_model: None,
            mc_gamma: None,
            fixes: Vec::new(),
            computes: HashMap::new(),
            regions: HashMap::new(),
            lattice: None,
            groups: Default::default(),
            lost_policy: "error".into(),
            insertion: Default::default(),
            periodic: [false; 3],
            shrink: [false; 3],
            shrink_min: [false; 3],
            box0: None,
            ntypes: 0,
            thermo_every: 0,
            thermo_cols: vec!["step".into(), "atoms".into(), "ke".into()],
            thermo_float: None,
            dumps: Vec::new(),
            local_dumps: Vec::new(),
            vtk_dumps: Vec::new(),
            pair_locals: HashMap::new(),
            aves: Vec::new(),
            checks: Vec::new(),
            momenta: Vec::new(),
            progress: opts.progress,
            quiet: opts.quiet,
            cli_geometry_tolerance: opts.mc_geometry_tolerance,
            cli_mc_every: opts.mc_every,
            cli_mc_accuracy: opts.mc_accuracy,
            cli_mc_accuracy_check: opts.mc_accuracy_check,
            summary: RunSummary::default(),
            line_no: 0,
            file: String::new(),
            scratch: Vec::new(),
            pending_jump: None,
            skip_jump: false,
        })
    }

    fn logln(&mut self, s: &str) {
        if let Some(l) = self.log.as_mut() {
            let _ = writeln!(l, "{s}");
        }
    }

    fn say(&mut self, s: &str) {
        if !self.quiet {
            println!("{s}");
        }
        self.logln(s);
    }

    fn warn(&mut self, s: &str) {
        let m = format!("WARNING: {s}");
        if !self.quiet {
            println!("{m}");
        }
        self.logln(&m);
    }

    /// A warning about the command being run, as `WARNING: FILE:LINE: message`.
    fn warn_here(&mut self, s: &str) {
        let m = format!("{}:{}: {s}", self.file, self.line_no);
        self.warn(&m);
    }

    fn finish(&mut self) {
        if let Some(l) = self.log.as_mut() {
            let _ = l.flush();
        }
    }

    /// An input file: relative to the working directory as in LIGGGHTS, else next to the deck.
    fn input_path(&self, p: &str) -> PathBuf {
        let direct = PathBuf::from(p);
        if direct.exists() || direct.is_absolute() {
            return direct;
        }
        let beside = self.deck_dir.join(p);
        if beside.exists() {
            beside
        } else {
            direct
        }
    }
}

/// `name[3]` → ("name", Some(3)); `name` → ("name", None).
fn split_index(s: &str) -> R<(&str, Option<usize>)> {
    match s.find('[') {
        Some(b) if s.ends_with(']') => {
            let k = s[b + 1..s.len() - 1].parse::<usize>().map_err(|_| format!("bad index in {s}"))?;
            if k == 0 {
                return Err(format!("index in {s} starts at 1"));
            }
            Ok((&s[..b], Some(k)))
        }
        _ => Ok((s, None)),
    }
}
