//! LIGGGHTS deck reader: variables, commands → engine setup, `run`, and LIGGGHTS-format output.
//!
//! The accepted subset is documented in `docs/dem.md`. Output-only commands without effect here
//! (`compute_modify`) are skipped with a one-line warning; every other unknown command or keyword
//! stops with `ERROR: FILE:LINE: unsupported …`,
//! because a silently ignored setting would give a different simulation.

pub mod expr;
pub mod format;
mod local;
pub mod output;
mod vtk;

use std::collections::HashMap;
use std::fmt;
use std::fs::File;
use std::io::{BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::engine::{Closure, Domain, Mesh, PlaneWall, StepError, WallFix, WallGeom, World};
use crate::physics::hertz::Tangential;
use crate::physics::{Material, MprTest, Vec3};
use output::{AveTime, Col, Dump};

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
}

#[derive(Debug, Clone)]
enum Var {
    Index(String),
    Equal(String),
    /// `variable NAME loop N1 N2`: the current value, advanced by `next` up to `last`.
    Loop {
        value: i64,
        last: i64,
    },
}

#[derive(Debug, Clone, PartialEq)]
struct GranModel {
    model: String,
    tangential: String,
    surface_mc: bool,
    mpr_test: MprTest,
    /// `pairRadii stock`: pairs with LIGGGHTS's radius convention (see docs/dem.md).
    stock_pair_radii: bool,
    /// `geometryTolerance TOL` (mc_advanced): see `World::mc_geometry_tolerance`.
    geometry_tolerance: Option<f64>,
    /// `updateEvery K` (mc_advanced): see `World::mc_every`.
    update_every: Option<u64>,
}

impl GranModel {
    /// One model setting `key value` of a `pair_style gran` or `fix wall/gran` line; false if `key`
    /// is not a model setting (the caller decides what else it may be).
    fn setting(&mut self, key: &str, v: Option<&str>) -> R<bool> {
        match (key, v) {
            ("mprTest", Some(x)) => self.mpr_test = x.parse()?,
            ("geometryTolerance", Some(x)) => self.geometry_tolerance = Some(geometry_tolerance(x)?),
            ("updateEvery", Some(x)) => self.update_every = Some(update_every(x)?),
            ("pairRadii", Some("modified")) => self.stock_pair_radii = false,
            ("pairRadii", Some("stock")) => self.stock_pair_radii = true,
            ("pairRadii", Some(x)) => {
                return Err(format!("pairRadii must be 'modified' or 'stock', got '{x}'"))
            }
            // LIGGGHTS' default for hertz; the core always applies tangential damping.
            ("tangential_damping", Some("on")) => {}
            _ => return Ok(false),
        }
        Ok(true)
    }

    /// The combination is one the engines run, and every setting belongs to the chosen model.
    fn check(&self) -> R<()> {
        if !matches!(self.model.as_str(), "hertz" | "mc_advanced") {
            return Err(unsupported(&format!("granular model '{}' (hertz or mc_advanced)", self.model)));
        }
        if !matches!(self.tangential.as_str(), "history" | "no_history") {
            return Err(unsupported(&format!(
                "tangential model '{}' (history or no_history)",
                self.tangential
            )));
        }
        if self.stock_pair_radii && self.model != "mc_advanced" {
            return Err("pairRadii is a setting of model mc_advanced".into());
        }
        if self.geometry_tolerance.is_some() && self.model != "mc_advanced" {
            return Err("geometryTolerance is a setting of model mc_advanced".into());
        }
        if self.update_every.is_some() && self.model != "mc_advanced" {
            return Err("updateEvery is a setting of model mc_advanced".into());
        }
        if self.model == "mc_advanced" && self.surface_mc {
            return Err("mc_advanced is itself a multi-contact model: drop 'surface multicontact'".into());
        }
        Ok(())
    }
}

/// `geometryTolerance` value: a finite number ≥ 0 (a fraction of the particle radius).
fn geometry_tolerance(x: &str) -> R<f64> {
    match x.parse::<f64>() {
        Ok(t) if t.is_finite() && t >= 0.0 => Ok(t),
        _ => Err(format!(
            "geometryTolerance must be a finite number >= 0 (a fraction of the particle radius), got '{x}'"
        )),
    }
}

/// Largest `updateEvery` (both engines; the plugin keeps it in an `int`).
pub const MAX_UPDATE_EVERY: u64 = 1_000_000_000;

/// `updateEvery` value: a whole number of steps from 1 to [`MAX_UPDATE_EVERY`].
fn update_every(x: &str) -> R<u64> {
    match x.parse::<u64>() {
        Ok(k) if (1..=MAX_UPDATE_EVERY).contains(&k) => Ok(k),
        _ => Err(format!(
            "updateEvery must be a whole number of steps from 1 to {MAX_UPDATE_EVERY}, got '{x}'"
        )),
    }
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
    mc_gamma: Option<f64>,
    fixes: Vec<(String, FixKind)>,
    computes: HashMap<String, ComputeKind>,
    regions: HashMap<String, [f64; 6]>,
    periodic: [bool; 3],
    ntypes: usize,
    thermo_every: u64,
    thermo_cols: Vec<String>,
    thermo_float: Option<format::Spec>,
    dumps: Vec<Dump>,
    local_dumps: Vec<local::LocalDump>,
    vtk_dumps: Vec<vtk::VtkDump>,
    pair_locals: HashMap<String, local::PairLocal>,
    aves: Vec<Option<AveTime>>,
    progress: bool,
    quiet: bool,
    /// Multi-contact approximations given on the command line (they override the deck's; 0: none).
    cli_geometry_tolerance: f64,
    cli_mc_every: u64,
    summary: RunSummary,
    line_no: usize,
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

fn num(s: &str) -> R<f64> {
    s.parse::<f64>().map_err(|_| format!("expected a number, got \"{s}\""))
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

/// Splits a command line into words; a quoted string ("…" or '…') is one word (quotes removed).
fn words(line: &str) -> R<Vec<String>> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quotes = Quotes::default();
    let mut had = false;
    for c in line.chars() {
        if quotes.mark(c) {
            had = true;
        } else if !quotes.open() && c.is_whitespace() {
            if had || !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
                had = false;
            }
        } else {
            cur.push(c);
        }
    }
    if let Some(q) = quotes.0 {
        return Err(format!("unterminated quote {q}"));
    }
    if had || !cur.is_empty() {
        out.push(cur);
    }
    Ok(out)
}

/// Strips a `#` comment that is not inside quotes.
fn strip_comment(line: &str) -> &str {
    let mut quotes = Quotes::default();
    for (k, c) in line.char_indices() {
        if !quotes.mark(c) && !quotes.open() && c == '#' {
            return &line[..k];
        }
    }
    line
}

/// LAMMPS quoting: "…" or '…' enclose text; inside one kind, the other is a plain character.
#[derive(Default)]
struct Quotes(Option<char>);

impl Quotes {
    /// Feeds one character; true if it is a quote mark that opened or closed a quote.
    fn mark(&mut self, c: char) -> bool {
        match self.0 {
            Some(q) if c == q => self.0 = None,
            None if c == '"' || c == '\'' => self.0 = Some(c),
            _ => return false,
        }
        true
    }

    fn open(&self) -> bool {
        self.0.is_some()
    }
}

struct Resolver<'a> {
    deck: &'a Deck,
    depth: usize,
}

impl expr::Resolve for Resolver<'_> {
    fn resolve(&self, name: &str) -> R<f64> {
        self.deck.value_of(name, self.depth)
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
            mc_gamma: None,
            fixes: Vec::new(),
            computes: HashMap::new(),
            regions: HashMap::new(),
            periodic: [false; 3],
            ntypes: 0,
            thermo_every: 0,
            thermo_cols: vec!["step".into(), "atoms".into(), "ke".into()],
            thermo_float: None,
            dumps: Vec::new(),
            local_dumps: Vec::new(),
            vtk_dumps: Vec::new(),
            pair_locals: HashMap::new(),
            aves: Vec::new(),
            progress: opts.progress,
            quiet: opts.quiet,
            cli_geometry_tolerance: opts.mc_geometry_tolerance,
            cli_mc_every: opts.mc_every,
            summary: RunSummary::default(),
            line_no: 0,
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

    fn execute(&mut self, text: &str, path: &Path) -> R<()> {
        let fname = path.display().to_string();
        let lines: Vec<&str> = text.lines().collect();
        let mut k = 0;
        while k < lines.len() {
            let start = k;
            let mut line = String::new();
            // '&' at the end of a line continues the command on the next line.
            loop {
                let l = lines[k].trim_end();
                k += 1;
                if let Some(stripped) = l.strip_suffix('&') {
                    line.push_str(stripped);
                    line.push(' ');
                    if k < lines.len() {
                        continue;
                    }
                } else {
                    line.push_str(l);
                }
                break;
            }
            self.line_no = start + 1;
            let cmd = strip_comment(&line).trim().to_string();
            self.logln(&line);
            if cmd.is_empty() {
                continue;
            }
            self.command(&cmd).map_err(|e| format!("{fname}:{}: {e}", start + 1))?;
            if let Some(label) = self.pending_jump.take() {
                // LAMMPS rereads the file from its start up to the label (none: from the start).
                k = if label.is_empty() {
                    0
                } else {
                    let at = lines.iter().position(|l| {
                        let w: Vec<&str> = strip_comment(l).split_whitespace().collect();
                        w.len() == 2 && w[0] == "label" && w[1] == label
                    });
                    at.ok_or_else(|| format!("{fname}:{}: jump: no label {label} in this file", start + 1))?
                        + 1
                };
            }
        }
        Ok(())
    }

    /// `${name}` / `$x` substitution, done on the whole line before parsing (LAMMPS semantics).
    fn substitute(&self, line: &str) -> R<String> {
        let mut out = String::with_capacity(line.len());
        let b: Vec<char> = line.chars().collect();
        let mut i = 0;
        while i < b.len() {
            if b[i] == '$' && i + 1 < b.len() && b[i + 1] == '(' {
                // `$(expression)`: evaluated immediately (LAMMPS), printed with enough digits to
                // give back the same double.
                let mut depth = 0usize;
                let mut end = None;
                for (k, &c) in b.iter().enumerate().skip(i + 1) {
                    match c {
                        '(' => depth += 1,
                        ')' => {
                            depth -= 1;
                            if depth == 0 {
                                end = Some(k);
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                let end = end.ok_or("missing ')' after '$('")?;
                let expr: String = b[i + 2..end].iter().collect();
                out.push_str(&format::g(self.eval_formula(&expr, 0)?, 17));
                i = end + 1;
            } else if b[i] == '$' && i + 1 < b.len() {
                let (name, next) = if b[i + 1] == '{' {
                    let end = b[i + 2..].iter().position(|&c| c == '}').ok_or("missing '}' after '${'")?;
                    (b[i + 2..i + 2 + end].iter().collect::<String>(), i + 3 + end)
                } else {
                    (b[i + 1].to_string(), i + 2)
                };
                let v = match self.vars.get(&name) {
                    Some(Var::Index(s)) => s.clone(),
                    Some(Var::Equal(f)) => format::g(self.eval_formula(f, 0)?, 15),
                    Some(Var::Loop { value, .. }) => value.to_string(),
                    None => return Err(format!("substitution for undefined variable {name}")),
                };
                out.push_str(&v);
                i = next;
            } else {
                out.push(b[i]);
                i += 1;
            }
        }
        Ok(out)
    }

    fn eval_formula(&self, f: &str, depth: usize) -> R<f64> {
        if depth > 50 {
            return Err("variable definitions refer to each other in a loop".into());
        }
        expr::eval(f, &Resolver { deck: self, depth: depth + 1 })
    }

    /// Value of a name inside a formula or a thermo column.
    fn value_of(&self, name: &str, depth: usize) -> R<f64> {
        let w = &self.world;
        if let Some(v) = name.strip_prefix("v_") {
            return match self.vars.get(v) {
                Some(Var::Equal(f)) => self.eval_formula(f, depth),
                Some(Var::Index(s)) => num(s).map_err(|_| format!("variable {v} is not numeric")),
                Some(Var::Loop { value, .. }) => Ok(*value as f64),
                None => Err(format!("unknown variable {v}")),
            };
        }
        if let Some(c) = name.strip_prefix("c_") {
            let (id, idx) = split_index(c)?;
            return match (self.computes.get(id), idx) {
                (Some(ComputeKind::ERotate), None) => Ok(w.rotational_energy()),
                (Some(ComputeKind::Ke), None) => Ok(w.kinetic_energy()),
                (Some(ComputeKind::Coord), None) => {
                    let n = w.p.len().max(1) as f64;
                    Ok(2.0 * w.pair_contacts() as f64 / n)
                }
                (Some(ComputeKind::Stress), k) => {
                    let (sc, sk) = w.stress_parts();
                    let tr = |s: &[[f64; 3]; 3]| (s[0][0] + s[1][1] + s[2][2]) / 3.0;
                    match k.unwrap_or(10) {
                        k @ 1..=9 => Ok(sc[(k - 1) / 3][(k - 1) % 3] + sk[(k - 1) / 3][(k - 1) % 3]),
                        10 => Ok(tr(&sc) + tr(&sk)),
                        11 => Ok(tr(&sc)),
                        12 => Ok(tr(&sk)),
                        k => Err(format!("compute {id} (stress/mcdem): index {k} out of range 1..12")),
                    }
                }
                (Some(_), Some(k)) => Err(format!("compute {id} is a scalar: no index [{k}]")),
                (None, _) => Err(format!("unknown compute {id}")),
            };
        }
        if let Some(f) = name.strip_prefix("f_") {
            let (id, idx) = split_index(f)?;
            let kind = self.fixes.iter().find(|(n, _)| n == id).map(|(_, k)| k.clone());
            return match (kind, idx) {
                (Some(FixKind::MeshSurface(m)), Some(k @ 1..=3)) => {
                    if !w.meshes[m].stress {
                        return Err(format!(
                            "fix {id} is mesh/surface without stress: use mesh/surface/stress"
                        ));
                    }
                    Ok(w.meshes[m].force[k - 1])
                }
                (Some(FixKind::AveTime(a)), Some(k)) => self.aves[a]
                    .as_ref()
                    .and_then(|a| a.last.get(k - 1).copied())
                    .ok_or_else(|| format!("fix {id} has no value {k}")),
                (Some(_), _) => Err(unsupported(&format!("fix reference f_{f}"))),
                (None, _) => Err(format!("unknown fix {id}")),
            };
        }
        if let (base, Some(k)) = split_index(name)? {
            let i =
                w.p.id.iter().position(|&x| x == k as i64).ok_or_else(|| format!("no atom with id {k}"))?;
            let p = &w.p;
            return Ok(match base {
                "x" => p.x[i].x,
                "y" => p.x[i].y,
                "z" => p.x[i].z,
                "vx" => p.v[i].x,
                "vy" => p.v[i].y,
                "vz" => p.v[i].z,
                "fx" => p.f[i].x,
                "fy" => p.f[i].y,
                "fz" => p.f[i].z,
                "omegax" => p.omega[i].x,
                "omegay" => p.omega[i].y,
                "omegaz" => p.omega[i].z,
                "radius" => p.radius[i],
                "mass" => p.mass[i],
                _ => return Err(unsupported(&format!("atom value {name}"))),
            });
        }
        let d = w.domain;
        let len = |a: usize| d.map(|d| d.hi[a] - d.lo[a]).unwrap_or(0.0);
        Ok(match name {
            "step" => w.step as f64,
            "atoms" => w.p.len() as f64,
            "dt" => w.dt,
            "time" => w.step as f64 * w.dt,
            "ke" => w.kinetic_energy(),
            "pe" => 0.0,
            "etotal" => w.kinetic_energy(),
            "vol" => d.map(|d| d.volume()).unwrap_or(0.0),
            "lx" => len(0),
            "ly" => len(1),
            "lz" => len(2),
            _ => return Err(unsupported(&format!("keyword {name}"))),
        })
    }

    fn command(&mut self, raw: &str) -> R<()> {
        let line = self.substitute(raw)?;
        if line != raw {
            self.logln(&line);
        }
        let w = words(&line)?;
        let a: Vec<&str> = w.iter().map(String::as_str).collect();
        let need = |n: usize| -> R<()> {
            if a.len() < n {
                Err(format!("{}: expected at least {} arguments", a[0], n - 1))
            } else {
                Ok(())
            }
        };
        match a[0] {
            "units" => {
                need(2)?;
                if a[1] != "si" {
                    return Err(unsupported(&format!("units {} (only si)", a[1])));
                }
            }
            "atom_style" => {
                need(2)?;
                if !matches!(a[1], "sphere" | "granular") {
                    return Err(unsupported(&format!("atom_style {}", a[1])));
                }
            }
            "atom_modify" => {
                // `map array|hash` only changes LIGGGHTS' memory layout; `sort Nfreq binsize`
                // sets how often particles are reordered in space (0 = never; the bin size is
                // the engine's own, half the neighbour cutoff).
                let mut k = 1;
                while k < a.len() {
                    match a[k] {
                        "map" => k += 2,
                        "sort" => {
                            let every = a.get(k + 1).ok_or("atom_modify sort: expected Nfreq binsize")?;
                            let bin = a.get(k + 2).ok_or("atom_modify sort: expected Nfreq binsize")?;
                            self.world.sort_every = every.parse::<u64>().map_err(|_| {
                                format!("atom_modify sort: Nfreq '{every}' is not an integer >= 0")
                            })?;
                            if !bin.parse::<f64>().is_ok_and(|b| b >= 0.0) {
                                return Err(format!(
                                    "atom_modify sort: binsize '{bin}' is not a number >= 0"
                                ));
                            }
                            k += 3;
                        }
                        other => return Err(unsupported(&format!("atom_modify keyword {other}"))),
                    }
                }
            }
            "boundary" => {
                need(4)?;
                for d in 0..3 {
                    self.periodic[d] = match a[1 + d] {
                        "p" => true,
                        "f" => false,
                        other => return Err(unsupported(&format!("boundary style {other} (f or p)"))),
                    };
                }
            }
            // Parallel-layout and bookkeeping switches with no effect on a serial engine.
            "newton" | "communicate" | "processors" | "echo" => {}
            "soft_particles" => {}
            "region" => {
                need(9)?;
                if a[2] != "block" {
                    return Err(unsupported(&format!("region style {}", a[2])));
                }
                let mut b = [0.0; 6];
                for (k, v) in b.iter_mut().enumerate() {
                    *v = num(a[3 + k])?;
                }
                let mut k = 9;
                while k < a.len() {
                    match (a[k], a.get(k + 1)) {
                        ("units", Some(&"box")) => k += 2,
                        _ => return Err(unsupported(&format!("region keyword {}", a[k]))),
                    }
                }
                self.regions.insert(a[1].into(), b);
            }
            "create_box" => {
                need(3)?;
                let b = *self.regions.get(a[2]).ok_or_else(|| format!("unknown region {}", a[2]))?;
                self.ntypes = int(a[1])? as usize;
                self.set_box(b)?;
            }
            "read_data" => {
                need(2)?;
                if a.len() > 2 {
                    return Err(unsupported("read_data keywords"));
                }
                self.read_data(a[1])?;
            }
            "create_atoms" => self.create_atoms(&a)?,
            "set" => self.set(&a)?,
            "velocity" => self.velocity(&a)?,
            "neighbor" => {
                need(3)?;
                self.world.skin = num(a[1])?;
                if a[2] != "bin" {
                    return Err(unsupported(&format!("neighbor style {}", a[2])));
                }
            }
            "neigh_modify" => {
                let mut k = 1;
                while k < a.len() {
                    match a[k] {
                        "delay" | "every" => {
                            if int(a.get(k + 1).ok_or("neigh_modify: missing value")?)? > 1 && a[k] == "every"
                            {
                                return Err(unsupported(
                                    "neigh_modify every > 1 (rebuilds are displacement-triggered)",
                                ));
                            }
                            k += 2
                        }
                        "check" => k += 2,
                        "contact_distance_factor" => {
                            // LIGGGHTS widens the neighbour search for contacts that may appear
                            // through multi-contact radius growth; the engine's detection reach is
                            // the same knob (never below what the contact law needs, see pair_style).
                            let f = num(a.get(k + 1).ok_or("neigh_modify: missing value")?)?;
                            if !(f.is_finite() && f >= 1.0) {
                                return Err(format!(
                                    "neigh_modify contact_distance_factor {f}: must be >= 1"
                                ));
                            }
                            self.world.mc_range = f;
                            k += 2
                        }
                        other => return Err(unsupported(&format!("neigh_modify keyword {other}"))),
                    }
                }
            }
            "pair_style" => self.pair_style(&a)?,
            "pair_coeff" => {
                if a.len() != 3 || a[1] != "*" || a[2] != "*" {
                    return Err(unsupported(
                        "pair_coeff other than '* *' (granular coefficients come from fix property/global)",
                    ));
                }
            }
            "timestep" => {
                need(2)?;
                self.world.dt = num(a[1])?;
                if !(self.world.dt > 0.0 && self.world.dt.is_finite()) {
                    return Err(format!("timestep must be finite and > 0, got {}", a[1]));
                }
            }
            "fix" => self.fix(&a)?,
            "unfix" => self.unfix(&a)?,
            "compute" => {
                need(4)?;
                if a[3] == "pair/gran/local" {
                    if a[2] != "all" {
                        return Err(unsupported(&format!("compute group '{}' (all)", a[2])));
                    }
                    self.pair_locals.insert(a[1].into(), local::PairLocal::parse(&a[4..])?);
                    return Ok(());
                }
                let kind = match a[3] {
                    "erotate/sphere" => ComputeKind::ERotate,
                    "ke" => ComputeKind::Ke,
                    "stress/mcdem" => ComputeKind::Stress,
                    "coord/mcdem" => ComputeKind::Coord,
                    other => return Err(unsupported(&format!("compute style {other}"))),
                };
                if a.len() > 4 {
                    return Err(unsupported(&format!("compute {} arguments", a[3])));
                }
                self.computes.insert(a[1].into(), kind);
            }
            "compute_modify" => self.warn("compute_modify is output-only here: skipped"),
            "thermo" => {
                need(2)?;
                self.thermo_every = int(a[1])?.max(0) as u64;
            }
            "thermo_style" => {
                need(2)?;
                if a[1] != "custom" {
                    return Err(unsupported(&format!("thermo_style {}", a[1])));
                }
                self.thermo_cols = a[2..].iter().map(|s| s.to_string()).collect();
            }
            "thermo_modify" => {
                let mut k = 1;
                while k < a.len() {
                    match a[k] {
                        "format" if a.get(k + 1) == Some(&"float") => {
                            let f = a.get(k + 2).ok_or("thermo_modify format float: missing format")?;
                            match format::parse(f)?.as_slice() {
                                [format::Piece::Conv(s)] => self.thermo_float = Some(s.clone()),
                                _ => {
                                    return Err(format!(
                                        "thermo_modify format float: one conversion expected in \"{f}\""
                                    ))
                                }
                            }
                            k += 3;
                        }
                        "norm" if a.get(k + 1) == Some(&"no") => k += 2,
                        "lost" if a.get(k + 1) == Some(&"error") => k += 2,
                        // Already so: stdout is line-buffered and the log is flushed when the
                        // deck ends, after an error too.
                        "flush" if matches!(a.get(k + 1), Some(&"yes") | Some(&"no")) => k += 2,
                        other => return Err(unsupported(&format!("thermo_modify keyword {other}"))),
                    }
                }
            }
            "dump" => self.dump(&a)?,
            "dump_modify" => self.dump_modify(&a)?,
            "undump" => {
                need(2)?;
                self.dumps.retain(|d| d.name != a[1]);
                self.local_dumps.retain(|d| d.name != a[1]);
                self.vtk_dumps.retain(|d| d.name != a[1]);
            }
            "variable" => self.variable(&a)?,
            "label" => need(2)?,
            "next" => {
                need(2)?;
                for v in &a[1..] {
                    match self.vars.get_mut(*v) {
                        Some(Var::Loop { value, last }) if *value < *last => *value += 1,
                        Some(Var::Loop { .. }) | Some(Var::Index(_)) => {
                            // Exhausted: deleted, and the jump that closes the loop is skipped.
                            self.vars.remove(*v);
                            self.skip_jump = true;
                        }
                        Some(Var::Equal(_)) => return Err(format!("next: variable {v} is not a loop")),
                        None => return Err(format!("next: unknown variable {v}")),
                    }
                }
            }
            "jump" => {
                need(2)?;
                if a[1] != "SELF" {
                    return Err(unsupported("jump to another file (use jump SELF LABEL)"));
                }
                if std::mem::take(&mut self.skip_jump) {
                    return Ok(());
                }
                self.pending_jump = Some(a.get(2).map_or(String::new(), |l| l.to_string()));
            }
            "include" => {
                need(2)?;
                let path = self.input_path(a[1]);
                let text = std::fs::read_to_string(&path)
                    .map_err(|e| format!("include: cannot read {}: {e}", path.display()))?;
                self.execute(&text, &path)?;
            }
            "if" => self.if_command(&a)?,
            "print" => {
                let text = a[1..].join(" ");
                self.say(&text);
            }
            "run" => self.run(&a)?,
            other => return Err(unsupported(&format!("command {other}"))),
        }
        Ok(())
    }

    fn set_box(&mut self, b: [f64; 6]) -> R<()> {
        if self.world.domain.is_some() {
            return Err("the simulation box already exists".into());
        }
        let lo = Vec3::new(b[0], b[2], b[4]);
        let hi = Vec3::new(b[1], b[3], b[5]);
        if (0..3).any(|k| hi[k].partial_cmp(&lo[k]) != Some(std::cmp::Ordering::Greater)) {
            return Err("box bounds must have hi > lo".into());
        }
        self.world.domain = Some(Domain::new(lo, hi, self.periodic));
        Ok(())
    }

    fn read_data(&mut self, file: &str) -> R<()> {
        let path = self.input_path(file);
        let text = std::fs::read_to_string(&path)
            .map_err(|e| format!("cannot read data file {}: {e}", path.display()))?;
        let mut b = [0.0; 6];
        let mut natoms = 0usize;
        let lines = text.lines().skip(1);
        let mut section = "";
        let mut vel_seen = false;
        // Velocities name atoms by id: one map for the section (a search per line is quadratic).
        let mut by_id = std::collections::HashMap::new();
        for l in lines {
            let l = strip_comment(l).trim();
            if l.is_empty() {
                continue;
            }
            let t: Vec<&str> = l.split_whitespace().collect();
            match t.as_slice() {
                [n, "atoms"] => natoms = int(n)? as usize,
                [n, "atom", "types"] => self.ntypes = int(n)? as usize,
                [lo, hi, "xlo", "xhi"] => (b[0], b[1]) = (num(lo)?, num(hi)?),
                [lo, hi, "ylo", "yhi"] => (b[2], b[3]) = (num(lo)?, num(hi)?),
                [lo, hi, "zlo", "zhi"] => (b[4], b[5]) = (num(lo)?, num(hi)?),
                ["Atoms", ..] => {
                    self.set_box(b)?;
                    section = "Atoms";
                }
                ["Velocities"] => {
                    section = "Velocities";
                    vel_seen = true;
                    by_id = self.world.p.id.iter().enumerate().map(|(i, &id)| (id, i)).collect();
                }
                [word, ..] if word.chars().next().is_some_and(|c| c.is_ascii_alphabetic()) => {
                    return Err(unsupported(&format!(
                        "data file section or header \"{l}\" in {}",
                        path.display()
                    )));
                }
                _ => match section {
                    "Atoms" => {
                        if t.len() < 7 {
                            return Err(format!(
                                "{}: Atoms line needs id type diameter density x y z: \"{l}\"",
                                path.display()
                            ));
                        }
                        let id = int(t[0])?;
                        let typ = int(t[1])? as usize;
                        if typ < 1 || typ > self.ntypes {
                            return Err(format!(
                                "{}: atom {id} has type {typ} outside 1..{}",
                                path.display(),
                                self.ntypes
                            ));
                        }
                        let x = Vec3::new(num(t[4])?, num(t[5])?, num(t[6])?);
                        self.world.p.push(id, typ - 1, x, num(t[2])?, num(t[3])?);
                        if t.len() >= 10 {
                            let i = self.world.p.len() - 1;
                            self.world.p.image[i] = [int(t[7])? as i32, int(t[8])? as i32, int(t[9])? as i32];
                        }
                    }
                    "Velocities" => {
                        if t.len() < 7 {
                            return Err(format!(
                                "{}: Velocities line needs id vx vy vz wx wy wz",
                                path.display()
                            ));
                        }
                        let id = int(t[0])?;
                        let i = *by_id.get(&id).ok_or_else(|| format!("no atom with id {id}"))?;
                        self.world.p.v[i] = Vec3::new(num(t[1])?, num(t[2])?, num(t[3])?);
                        self.world.p.omega[i] = Vec3::new(num(t[4])?, num(t[5])?, num(t[6])?);
                    }
                    _ => return Err(format!("{}: data line outside a section: \"{l}\"", path.display())),
                },
            }
        }
        if self.world.p.len() != natoms {
            return Err(format!(
                "{}: header says {natoms} atoms, found {}",
                path.display(),
                self.world.p.len()
            ));
        }
        self.say(&format!("  {} atoms{}", natoms, if vel_seen { ", velocities read" } else { "" }));
        Ok(())
    }

    fn index_of(&self, id: i64) -> R<usize> {
        self.world.p.id.iter().position(|&x| x == id).ok_or_else(|| format!("no atom with id {id}"))
    }

    fn create_atoms(&mut self, a: &[&str]) -> R<()> {
        if a.len() < 6 || a[2] != "single" {
            return Err(unsupported(
                "create_atoms style (only 'create_atoms TYPE single x y z [units box]')",
            ));
        }
        if a.len() > 6 && !(a.len() == 8 && a[6] == "units" && a[7] == "box") {
            return Err(unsupported("create_atoms keyword"));
        }
        let typ = int(a[1])? as usize;
        if typ < 1 || typ > self.ntypes {
            return Err(format!("atom type {typ} outside 1..{}", self.ntypes));
        }
        let x = Vec3::new(num(a[3])?, num(a[4])?, num(a[5])?);
        let id = self.world.p.id.iter().copied().max().unwrap_or(0) + 1;
        // LIGGGHTS default for a new sphere: diameter 1, density 1 (set changes it).
        self.world.p.push(id, typ - 1, x, 1.0, 1.0);
        Ok(())
    }

    fn set(&mut self, a: &[&str]) -> R<()> {
        if a.len() < 5 {
            return Err("set: expected 'set atom|type ID keyword value …'".into());
        }
        let sel: Vec<usize> = match a[1] {
            "atom" if a[2] == "*" => (0..self.world.p.len()).collect(),
            "atom" => vec![self.index_of(int(a[2])?)?],
            "type" => {
                let t = int(a[2])? as usize;
                (0..self.world.p.len()).filter(|&i| self.world.p.typ[i] + 1 == t).collect()
            }
            other => return Err(unsupported(&format!("set style {other}"))),
        };
        let mut k = 3;
        while k + 1 < a.len() + 1 && k < a.len() {
            let v = num(a.get(k + 1).ok_or("set: missing value")?)?;
            for &i in &sel {
                match a[k] {
                    "diameter" => self.world.p.set_size(i, Some(v), None),
                    "density" => self.world.p.set_size(i, None, Some(v)),
                    "vx" => self.world.p.v[i].x = v,
                    "vy" => self.world.p.v[i].y = v,
                    "vz" => self.world.p.v[i].z = v,
                    "omegax" => self.world.p.omega[i].x = v,
                    "omegay" => self.world.p.omega[i].y = v,
                    "omegaz" => self.world.p.omega[i].z = v,
                    other => return Err(unsupported(&format!("set keyword {other}"))),
                }
            }
            k += 2;
        }
        Ok(())
    }

    fn velocity(&mut self, a: &[&str]) -> R<()> {
        if a.get(2) == Some(&"ramp") {
            // `velocity all ramp vx VLO VHI y YLO YHI [sum yes|no] [units box]` (LAMMPS): the
            // streaming profile of a Lees–Edwards shear.
            if a.len() < 9 || a[1] != "all" || a[3] != "vx" || a[6] != "y" {
                return Err(unsupported(
                    "velocity ramp form (only 'velocity all ramp vx VLO VHI y YLO YHI')",
                ));
            }
            let (vlo, vhi, ylo, yhi) = (num(a[4])?, num(a[5])?, num(a[7])?, num(a[8])?);
            if yhi <= ylo || !(yhi - ylo).is_finite() {
                return Err(format!("velocity ramp: YHI ({yhi}) must exceed YLO ({ylo})"));
            }
            let mut sum = false;
            let mut k = 9;
            while k < a.len() {
                match (a[k], a.get(k + 1).copied()) {
                    ("sum", Some(v @ ("yes" | "no"))) => sum = v == "yes",
                    ("units", Some("box")) => {}
                    _ => return Err(unsupported(&format!("velocity ramp keyword {}", a[k]))),
                }
                k += 2;
            }
            let p = &mut self.world.p;
            for i in 0..p.len() {
                let s = ((p.x[i].y - ylo) / (yhi - ylo)).clamp(0.0, 1.0);
                let v = vlo + s * (vhi - vlo);
                p.v[i].x = if sum { p.v[i].x + v } else { v };
            }
            return Ok(());
        }
        if a.len() < 6 || a[1] != "all" || a[2] != "set" {
            return Err(unsupported("velocity form (only 'velocity all set vx vy vz [units box]')"));
        }
        if a.len() > 6 && !(a.len() == 8 && a[6] == "units" && a[7] == "box") {
            return Err(unsupported("velocity keyword"));
        }
        let v = Vec3::new(num(a[3])?, num(a[4])?, num(a[5])?);
        self.world.p.v.iter_mut().for_each(|x| *x = v);
        Ok(())
    }

    fn gran_model(a: &[&str], start: usize) -> R<(GranModel, usize)> {
        let mut m = GranModel {
            model: String::new(),
            tangential: "history".into(),
            surface_mc: false,
            mpr_test: MprTest::Abs,
            stock_pair_radii: false,
            geometry_tolerance: None,
            update_every: None,
        };
        let mut k = start;
        while k < a.len() {
            let v = a.get(k + 1).copied();
            match (a[k], v) {
                ("model", Some(x)) => m.model = x.into(),
                ("tangential", Some(x)) => m.tangential = x.into(),
                ("cohesion", Some("off")) | ("rolling_friction", Some("off")) => {}
                ("surface", Some("default")) => m.surface_mc = false,
                ("surface", Some("multicontact")) => m.surface_mc = true,
                (key, v) => {
                    if !m.setting(key, v)? {
                        break;
                    }
                }
            }
            k += 2;
        }
        m.check()?;
        Ok((m, k))
    }

    fn pair_style(&mut self, a: &[&str]) -> R<()> {
        if a.get(1) != Some(&"gran") {
            return Err(unsupported(&format!("pair_style {}", a.get(1).unwrap_or(&""))));
        }
        let (m, k) = Self::gran_model(a, 2)?;
        if k != a.len() {
            return Err(unsupported(&format!("pair_style gran keyword {}", a[k])));
        }
        // The command-line options, when given, take precedence over the deck's settings; they
        // approximate the multi-contact pass of mc_advanced and of nothing else.
        let (cli_tol, cli_every) = (self.cli_geometry_tolerance, self.cli_mc_every);
        if m.model != "mc_advanced" && (cli_tol > 0.0 || cli_every > 1) {
            return Err(format!(
                "--mc-geometry-tolerance and --mc-update-every apply to model mc_advanced only; this pair style is model {}",
                m.model
            ));
        }
        // A pair style defined again starts from the defaults, as in LIGGGHTS.
        self.world.mc_geometry_tolerance =
            if cli_tol > 0.0 { cli_tol } else { m.geometry_tolerance.unwrap_or(0.0) };
        self.world.mc_every = if cli_every > 0 { cli_every } else { m.update_every.unwrap_or(1) };
        self.pair = Some(m);
        Ok(())
    }

    fn fix(&mut self, a: &[&str]) -> R<()> {
        if a.len() < 4 {
            return Err("fix: expected 'fix ID group style …'".into());
        }
        let (id, group, style) = (a[1], a[2], a[3]);
        if group != "all" {
            return Err(unsupported(&format!("fix group '{group}' (all)")));
        }
        if self.fixes.iter().any(|(n, _)| n == id) {
            // LIGGGHTS replaces a fix redefined with the same ID; only the stateless ones here.
            if style != "property/global" {
                return Err(unsupported(&format!("redefining fix {id} without unfix")));
            }
            self.fixes.retain(|(n, _)| n != id);
        }
        let kind = match style {
            "property/global" => {
                if a.len() < 6 {
                    return Err("fix property/global: expected NAME STYLE values".into());
                }
                let vals = a[6..].iter().map(|s| num(s)).collect::<R<Vec<f64>>>()?;
                self.props.insert(a[4].into(), (a[5].into(), vals));
                FixKind::Property
            }
            "gravity" => {
                if a.len() != 9 || a[5] != "vector" {
                    return Err(unsupported("fix gravity form (only 'gravity MAG vector x y z')"));
                }
                let g = num(a[4])?;
                let dir = Vec3::new(num(a[6])?, num(a[7])?, num(a[8])?);
                let l = dir.norm();
                if l == 0.0 {
                    return Err("fix gravity: zero direction vector".into());
                }
                self.world.gravity = Some(dir / l * g);
                FixKind::Gravity
            }
            "nve/sphere" => {
                if a.len() > 4 {
                    return Err(unsupported("fix nve/sphere keywords"));
                }
                self.world.integrate = true;
                FixKind::Nve
            }
            "deform" => {
                // Lees–Edwards simple shear: `fix ID all deform N xy erate RATE remap v`.
                if a.len() != 10 || a[5] != "xy" || a[6] != "erate" || a[8] != "remap" || a[9] != "v" {
                    return Err(unsupported("fix deform form (only 'deform N xy erate RATE remap v')"));
                }
                int(a[4])?;
                let rate = num(a[7])?;
                if !rate.is_finite() {
                    return Err(format!("fix deform: shear rate must be finite, got {}", a[7]));
                }
                if !(self.periodic[0] && self.periodic[1]) {
                    return Err("fix deform xy (Lees–Edwards shear) needs periodic x and y boundaries".into());
                }
                let d = self.world.domain.as_mut().ok_or("fix deform before the simulation box")?;
                d.le_vjump = rate * (d.hi.y - d.lo.y);
                FixKind::Deform
            }
            "multicontact/halfspace" => {
                if a.len() != 6 || a[4] != "geometric_prefactor" {
                    return Err(unsupported("fix multicontact/halfspace form (geometric_prefactor G)"));
                }
                let g = num(a[5])?;
                if g <= 0.0 {
                    return Err("fix multicontact/halfspace: geometric_prefactor > 0 required".into());
                }
                self.mc_gamma = Some(g);
                FixKind::MultiContact
            }
            "wall/gran" => self.wall_gran(a)?,
            "mesh/surface" | "mesh/surface/stress" => self.mesh_surface(a)?,
            "move/mesh" => {
                if a.len() != 10 || a[4] != "mesh" || a[6] != "linear" {
                    return Err(unsupported("fix move/mesh form (only 'mesh ID linear vx vy vz')"));
                }
                let m = self.mesh_index(a[5])?;
                if self.fixes.iter().any(|(_, k)| matches!(k, FixKind::MoveMesh(x) if *x == m)) {
                    return Err(unsupported("two move/mesh fixes on one mesh"));
                }
                self.world.meshes[m].velocity = Vec3::new(num(a[7])?, num(a[8])?, num(a[9])?);
                FixKind::MoveMesh(m)
            }
            "ave/time" => self.ave_time(a)?,
            other => return Err(unsupported(&format!("fix style {other}"))),
        };
        self.fixes.push((id.into(), kind));
        Ok(())
    }

    fn mesh_index(&self, fix_id: &str) -> R<usize> {
        match self.fixes.iter().find(|(n, _)| n == fix_id) {
            Some((_, FixKind::MeshSurface(m))) => Ok(*m),
            _ => Err(format!("{fix_id} is not a mesh/surface fix")),
        }
    }

    fn mesh_surface(&mut self, a: &[&str]) -> R<FixKind> {
        let mut file = None;
        let mut wall_type = None;
        let mut ops: Vec<(&str, Vec<f64>)> = Vec::new();
        let mut k = 4;
        while k < a.len() {
            match a[k] {
                "file" => {
                    file = Some(a.get(k + 1).ok_or("mesh: missing file name")?.to_string());
                    k += 2;
                }
                "type" => {
                    wall_type = Some(int(a.get(k + 1).ok_or("mesh: missing type")?)? as usize);
                    k += 2;
                }
                "move" => {
                    let v =
                        (1..=3).map(|d| num(a.get(k + d).ok_or("mesh move: 3 values")?)).collect::<R<_>>()?;
                    ops.push(("move", v));
                    k += 4;
                }
                "rotate" => {
                    if a.get(k + 1) != Some(&"axis") || a.get(k + 5) != Some(&"angle") {
                        return Err("mesh rotate: expected 'rotate axis X Y Z angle DEGREES'".into());
                    }
                    let v = [2, 3, 4, 6]
                        .iter()
                        .map(|d| num(a.get(k + d).ok_or("mesh rotate: 4 values")?))
                        .collect::<R<_>>()?;
                    ops.push(("rotate", v));
                    k += 7;
                }
                "scale" => {
                    ops.push(("scale", vec![num(a.get(k + 1).ok_or("mesh scale: value")?)?]));
                    k += 2;
                }
                "stress" if matches!(a.get(k + 1), Some(&"on") | Some(&"off")) => k += 2,
                "verbose" | "heal" if a.get(k + 1).is_some() => k += 2,
                other => return Err(unsupported(&format!("fix {} keyword {other}", a[3]))),
            }
        }
        let file = file.ok_or("mesh/surface: 'file' is required")?;
        let t = wall_type.ok_or("mesh/surface: 'type' is required")?;
        if t < 1 || (self.ntypes > 0 && t > self.ntypes) {
            return Err(format!("mesh/surface: type {t} outside 1..{}", self.ntypes));
        }
        let raw = mesh::read(&self.input_path(&file))?;
        let mut m = Mesh::new(a[1], t - 1, raw)?;
        for (op, v) in ops {
            match op {
                "move" => m.translate(&Vec3::new(v[0], v[1], v[2])),
                "rotate" => m.rotate(&Vec3::new(v[0], v[1], v[2]), v[3])?,
                _ => m.scale(v[0]),
            }
        }
        m.stress = a[3] == "mesh/surface/stress";
        self.world.meshes.push(m);
        Ok(FixKind::MeshSurface(self.world.meshes.len() - 1))
    }

    fn wall_gran(&mut self, a: &[&str]) -> R<FixKind> {
        let (mut m, mut k) = Self::gran_model(a, 4)?;
        let geom = match a.get(k) {
            Some(&"primitive") => {
                if a.len() < k + 5 || a[k + 1] != "type" {
                    return Err("wall/gran primitive: expected 'type T xplane|yplane|zplane POS'".into());
                }
                let t = int(a[k + 2])? as usize;
                let axis = match a[k + 3] {
                    "xplane" => 0,
                    "yplane" => 1,
                    "zplane" => 2,
                    other => return Err(unsupported(&format!("primitive wall {other}"))),
                };
                let pos = num(a[k + 4])?;
                k += 5;
                if t < 1 || (self.ntypes > 0 && t > self.ntypes) {
                    return Err(format!("wall type {t} outside 1..{}", self.ntypes));
                }
                WallGeom::Plane(PlaneWall { axis, pos, wall_type: t - 1 })
            }
            Some(&"mesh") => {
                if a.get(k + 1) != Some(&"n_meshes") || a.get(k + 3) != Some(&"meshes") {
                    return Err("wall/gran mesh: expected 'n_meshes N meshes ID…'".into());
                }
                let n = int(a.get(k + 2).ok_or("n_meshes value")?)? as usize;
                let mut list = Vec::new();
                for j in 0..n {
                    list.push(
                        self.mesh_index(a.get(k + 4 + j).ok_or("wall/gran: fewer mesh IDs than n_meshes")?)?,
                    );
                }
                k += 4 + n;
                WallGeom::Meshes(list)
            }
            _ => return Err("wall/gran: expected 'primitive' or 'mesh'".into()),
        };
        // Model settings may also follow the geometry (LIGGGHTS accepts them at the end of the line).
        while k < a.len() {
            if !m.setting(a[k], a.get(k + 1).copied())? {
                return Err(unsupported(&format!("wall/gran keyword {}", a[k])));
            }
            k += 2;
        }
        m.check()?;
        // The wall runs the pair style's model: the same law and sub-models. The pair style's
        // multi-contact pass serves the walls too, so a wall may repeat its mprTest,
        // geometryTolerance and updateEvery but not give other values (they would be ignored);
        // pairRadii concerns pairs only.
        let Some(p) = &self.pair else { return Err("fix wall/gran before pair_style gran".into()) };
        if (&p.model, &p.tangential, p.surface_mc) != (&m.model, &m.tangential, m.surface_mc) {
            return Err(unsupported("a wall model different from the pair model"));
        }
        let given = |key: &str| a.iter().rposition(|w| *w == key).and_then(|i| a.get(i + 1));
        let agrees = [
            ("mprTest", p.mpr_test == m.mpr_test),
            ("geometryTolerance", p.geometry_tolerance.unwrap_or(0.0) == m.geometry_tolerance.unwrap_or(0.0)),
            ("updateEvery", p.update_every.unwrap_or(1) == m.update_every.unwrap_or(1)),
        ];
        for (key, same) in agrees {
            if let (Some(x), false) = (given(key), same) {
                return Err(format!("wall/gran {key} {x} differs from the pair style's"));
            }
        }
        self.world.walls.push(WallFix { name: a[1].into(), geom });
        Ok(FixKind::Wall(self.world.walls.len() - 1))
    }

    fn ave_time(&mut self, a: &[&str]) -> R<FixKind> {
        if a.len() < 8 {
            return Err("fix ave/time: expected Nevery Nrepeat Nfreq values…".into());
        }
        let (ne, nr, nf) = (int(a[4])? as u64, int(a[5])? as u64, int(a[6])? as u64);
        if ne == 0 || nr == 0 || nf == 0 || nf % ne != 0 || nr * ne > nf {
            return Err("fix ave/time: need Nfreq a multiple of Nevery and Nrepeat*Nevery <= Nfreq".into());
        }
        let mut values = Vec::new();
        let mut file = None;
        let mut k = 7;
        while k < a.len() {
            match a[k] {
                "file" => {
                    file = Some(a.get(k + 1).ok_or("ave/time file: missing name")?.to_string());
                    k += 2;
                }
                v if v.starts_with("c_") || v.starts_with("f_") || v.starts_with("v_") => {
                    values.push(v.to_string());
                    k += 1;
                }
                other => return Err(unsupported(&format!("fix ave/time keyword {other}"))),
            }
        }
        for v in &values {
            self.value_of(v, 0).map_err(|e| format!("fix ave/time value {v}: {e}"))?;
        }
        let out = match file {
            Some(f) => {
                let mut o = output::create(Path::new(&f))?;
                writeln!(o, "# Time-averaged data for fix {}\n# TimeStep {}", a[1], values.join(" "))
                    .map_err(|e| e.to_string())?;
                Some(o)
            }
            None => None,
        };
        let mut at = AveTime {
            name: a[1].into(),
            nevery: ne,
            nrepeat: nr,
            nfreq: nf,
            sum: vec![0.0; values.len()],
            last: vec![0.0; values.len()],
            values,
            irepeat: 0,
            nvalid: 0,
            out,
        };
        at.nvalid = at.next_valid(self.world.step);
        self.aves.push(Some(at));
        Ok(FixKind::AveTime(self.aves.len() - 1))
    }

    fn unfix(&mut self, a: &[&str]) -> R<()> {
        let id = *a.get(1).ok_or("unfix: missing ID")?;
        let pos =
            self.fixes.iter().position(|(n, _)| n == id).ok_or_else(|| format!("unfix: no fix {id}"))?;
        let (_, kind) = self.fixes.remove(pos);
        match kind {
            FixKind::Property => {}
            FixKind::Gravity => self.world.gravity = None,
            FixKind::Nve => self.world.integrate = false,
            FixKind::MoveMesh(m) => self.world.meshes[m].velocity = Vec3::zeros(),
            // An inactive wall keeps its slot so wall-contact keys stay valid.
            FixKind::Wall(w) => self.world.walls[w].geom = WallGeom::Meshes(Vec::new()),
            FixKind::AveTime(k) => {
                if let Some(mut at) = self.aves[k].take() {
                    if let Some(o) = at.out.as_mut() {
                        let _ = o.flush();
                    }
                }
            }
            FixKind::MultiContact => self.mc_gamma = None,
            FixKind::Deform => {
                if let Some(d) = self.world.domain.as_mut() {
                    d.le_vjump = 0.0;
                }
            }
            FixKind::MeshSurface(_) => return Err(unsupported("unfix of a mesh/surface fix")),
        }
        Ok(())
    }

    fn dump(&mut self, a: &[&str]) -> R<()> {
        if a.len() < 4 {
            return Err("dump: expected 'dump ID group style N file …'".into());
        }
        match a[3] {
            "custom/vtk" | "mesh/vtk" => return self.dump_vtk(a),
            "custom" => {}
            "local" => {
                if a[2] != "all" {
                    return Err(unsupported(&format!("dump group '{}' (all)", a[2])));
                }
                self.local_dumps.push(local::LocalDump::parse(a[1], &a[4..])?);
                return Ok(());
            }
            other => return Err(unsupported(&format!("dump style {other}"))),
        }
        if a.len() < 7 {
            return Err("dump custom: expected N file columns…".into());
        }
        if a[2] != "all" {
            return Err(unsupported(&format!("dump group '{}' (all)", a[2])));
        }
        let every = int(a[4])?;
        if every <= 0 {
            return Err("dump: N must be > 0".into());
        }
        let mut cols = Vec::new();
        for c in &a[6..] {
            cols.push(Col::parse(c).ok_or_else(|| unsupported(&format!("dump custom column {c}")))?);
        }
        self.dumps.push(Dump::new(
            a[1],
            every as u64,
            PathBuf::from(a[5]),
            a[6..].iter().map(|s| s.to_string()).collect(),
            cols,
        ));
        Ok(())
    }

    /// `dump ID group custom/vtk|mesh/vtk N FILE …` (see `vtk.rs`).
    fn dump_vtk(&mut self, a: &[&str]) -> R<()> {
        if a.len() < 7 {
            return Err(format!("dump {}: expected N file and at least one column or keyword", a[3]));
        }
        if a[2] != "all" {
            return Err(unsupported(&format!("dump group '{}' (all)", a[2])));
        }
        let every = int(a[4])?;
        if every <= 0 {
            return Err("dump: N must be > 0".into());
        }
        let d = if a[3] == "custom/vtk" {
            vtk::VtkDump::particles(a[1], every as u64, a[5], &a[6..])?
        } else {
            let all = self.world.meshes.len();
            vtk::VtkDump::mesh(a[1], every as u64, a[5], &a[6..], |f| self.mesh_index(f), all)?
        };
        self.vtk_dumps.push(d);
        Ok(())
    }

    fn dump_modify(&mut self, a: &[&str]) -> R<()> {
        let id = *a.get(1).ok_or("dump_modify: missing ID")?;
        let Some(d) = self.dumps.iter_mut().find(|d| d.name == id) else {
            if self.vtk_dumps.iter().any(|d| d.name == id) {
                return Err(unsupported(&format!("dump_modify of the VTK dump {id}")));
            }
            return Err(format!("dump_modify: no dump {id}"));
        };
        let mut k = 2;
        while k < a.len() {
            match a[k] {
                "format" => {
                    let f = a.get(k + 1).ok_or("dump_modify format: missing string")?;
                    d.format = Some(format::parse(f)?);
                    k += 2;
                }
                "sort" if a.get(k + 1) == Some(&"id") => k += 2,
                other => return Err(unsupported(&format!("dump_modify keyword {other}"))),
            }
        }
        Ok(())
    }

    /// `if "cond" then "cmd" ... [elif "cond" "cmd" ...]... [else "cmd" ...]` (LAMMPS): the first
    /// true branch's commands run in order, each as if it were a deck line.
    fn if_command(&mut self, a: &[&str]) -> R<()> {
        let mut k = 1;
        let mut cond = a.get(k).ok_or("if: expected a condition")?.to_string();
        k += 1;
        if a.get(k) != Some(&"then") {
            return Err("if: expected 'then' after the condition".into());
        }
        k += 1;
        loop {
            let start = k;
            while k < a.len() && a[k] != "elif" && a[k] != "else" {
                k += 1;
            }
            let commands: Vec<String> = a[start..k].iter().map(|c| c.to_string()).collect();
            if self.eval_formula(&cond, 0)? != 0.0 {
                for c in commands {
                    self.command(&c)?;
                }
                return Ok(());
            }
            match a.get(k) {
                None => return Ok(()),
                Some(&"elif") => {
                    cond = a.get(k + 1).ok_or("if: expected a condition after 'elif'")?.to_string();
                    k += 2;
                }
                Some(_) => {
                    // else: everything after it runs.
                    for c in &a[k + 1..] {
                        self.command(c)?;
                    }
                    return Ok(());
                }
            }
        }
    }

    fn variable(&mut self, a: &[&str]) -> R<()> {
        if a.len() < 4 {
            return Err("variable: expected 'variable NAME style args'".into());
        }
        let name = a[1].to_string();
        match a[2] {
            "index" | "string" => {
                // LAMMPS: an index variable that exists (e.g. from -var) is not redefined.
                if !self.vars.contains_key(&name) || a[2] == "string" {
                    self.vars.insert(name, Var::Index(a[3].into()));
                }
            }
            "equal" => {
                let f = a[3..].join(" ");
                self.vars.insert(name, Var::Equal(f));
            }
            "loop" => {
                let (first, last) = match a.len() {
                    4 => (1, int(a[3])?),
                    5 if a[4] == "pad" => (1, int(a[3])?),
                    5 | 6 => (int(a[3])?, int(a[4])?),
                    _ => return Err("variable loop: expected N or N1 N2".into()),
                };
                if a.get(5).is_some_and(|w| *w != "pad") {
                    return Err(unsupported(&format!("variable loop keyword {}", a[5])));
                }
                if first > last {
                    return Err(format!("variable {name}: loop from {first} to {last} is empty"));
                }
                // LAMMPS: an existing loop variable is not redefined (the loop is running).
                self.vars.entry(name).or_insert(Var::Loop { value: first, last });
            }
            other => return Err(unsupported(&format!("variable style {other}"))),
        }
        Ok(())
    }

    /// Builds the materials and the contact closure from the deck's properties.
    fn prepare(&mut self) -> R<()> {
        let pair = self.pair.clone().ok_or("run before pair_style gran")?;
        let nt = self.ntypes;
        if nt == 0 {
            return Err("run before the box and atom types exist".into());
        }
        let per_type = |s: &Self, name: &str| -> R<Vec<f64>> {
            let (style, v) =
                s.props.get(name).ok_or_else(|| format!("fix property/global {name} is missing"))?;
            if style != "peratomtype" {
                return Err(format!("property {name} must be peratomtype"));
            }
            if v.len() != nt {
                return Err(format!("property {name}: {} values for {nt} atom types", v.len()));
            }
            Ok(v.clone())
        };
        let per_pair = |s: &Self, name: &str| -> R<Vec<f64>> {
            let (style, v) =
                s.props.get(name).ok_or_else(|| format!("fix property/global {name} is missing"))?;
            if style != "peratomtypepair" {
                return Err(format!("property {name} must be peratomtypepair"));
            }
            if v.first().map(|n| *n as usize) != Some(nt) || v.len() != 1 + nt * nt {
                return Err(format!("property {name}: expected {nt} followed by {} values", nt * nt));
            }
            Ok(v[1..].to_vec())
        };
        let e = per_type(self, "youngsModulus")?;
        let nu = per_type(self, "poissonsRatio")?;
        let rest = per_pair(self, "coefficientRestitution")?;
        let fric = per_pair(self, "coefficientFriction")?;
        let (closure, gammas, mprs): (Closure, Vec<f64>, Option<Vec<f64>>) = if pair.model == "mc_advanced" {
            (
                Closure::MultiContact,
                per_type(self, "geometricPrefactor")?,
                Some(per_type(self, "maxPenetrationRatio")?),
            )
        } else if pair.surface_mc {
            let g = self.mc_gamma.ok_or("surface multicontact needs fix multicontact/halfspace")?;
            (Closure::MultiContact, vec![g; nt], None)
        } else {
            if self.mc_gamma.is_some() {
                return Err("fix multicontact/halfspace needs 'surface multicontact' in pair_style".into());
            }
            (Closure::Hertz, vec![0.0; nt], None)
        };
        let mut mats = Vec::with_capacity(nt);
        for t in 0..nt {
            let cap = mprs.as_ref().map(|m| (m[t], pair.mpr_test));
            mats.push(
                Material::new(e[t], nu[t], gammas[t], cap)
                    .map_err(|e| format!("atom type {}: {e}", t + 1))?,
            );
        }
        let tangential =
            if pair.tangential == "no_history" { Tangential::NoHistory } else { Tangential::History };
        self.world.set_materials(mats, &rest, &fric, tangential)?;
        self.world.closure = Some(closure);
        self.world.liggghts_radii = pair.surface_mc || pair.stock_pair_radii;
        self.world.mc_range =
            self.world.mc_range.max(if closure == Closure::MultiContact { 1.25 } else { 1.0 });
        Ok(())
    }

    fn thermo_header(&self) -> String {
        let mut s = String::new();
        for c in &self.thermo_cols {
            let (name, is_int) = match c.as_str() {
                "step" => ("Step".to_string(), true),
                "atoms" => ("Atoms".to_string(), true),
                "ke" => ("KinEng".to_string(), false),
                "pe" => ("PotEng".to_string(), false),
                "etotal" => ("TotEng".to_string(), false),
                "vol" => ("Volume".to_string(), false),
                "time" => ("Time".to_string(), false),
                "dt" => ("Dt".to_string(), false),
                "lx" => ("Lx".to_string(), false),
                "ly" => ("Ly".to_string(), false),
                "lz" => ("Lz".to_string(), false),
                other => (other.get(2..).unwrap_or(other).to_string(), false),
            };
            if is_int {
                s.push_str(&format!("{name:>8} "));
            } else {
                s.push_str(&format!("{name:>14} "));
            }
        }
        s
    }

    fn thermo_line(&self) -> R<String> {
        let mut s = String::new();
        for c in &self.thermo_cols {
            let v = self.value_of(c, 0)?;
            if matches!(c.as_str(), "step" | "atoms") {
                s.push_str(&format!("{:>8} ", v as i64));
            } else {
                match &self.thermo_float {
                    Some(spec) => s.push_str(&format::number(spec, v)),
                    None => s.push_str(&format::gw(v, 14, 8)),
                }
                s.push(' ');
            }
        }
        Ok(s)
    }

    fn end_of_step_outputs(&mut self, last: bool) -> R<Option<String>> {
        let step = self.world.step;
        self.sample_ave_times()?;
        self.write_dumps()?;
        let thermo_due = last || (self.thermo_every > 0 && step % self.thermo_every == 0);
        if thermo_due {
            return Ok(Some(self.thermo_line()?));
        }
        Ok(None)
    }

    /// Every dump due at the current step writes its frame (once per step).
    fn write_dumps(&mut self) -> R<()> {
        let step = self.world.step;
        for d in &mut self.dumps {
            if step % d.every == 0 && d.last != Some(step) {
                d.write(&self.world)?;
            }
        }
        for d in &mut self.local_dumps {
            if step % d.every == 0 && d.last != Some(step) {
                d.write(&mut self.world, &self.pair_locals)?;
            }
        }
        let vtk_due = |d: &vtk::VtkDump| step % d.every == 0 && d.last != Some(step);
        if self.vtk_dumps.iter().any(vtk_due) {
            // Meshes under a `fix move/mesh` carry a velocity LIGGGHTS writes; others have none.
            let mut moving = vec![false; self.world.meshes.len()];
            for (_, k) in &self.fixes {
                if let FixKind::MoveMesh(m) = k {
                    moving[*m] = true;
                }
            }
            for d in self.vtk_dumps.iter_mut().filter(|d| vtk_due(d)) {
                d.write(&self.world, &moving)?;
            }
        }
        Ok(())
    }

    /// Every `fix ave/time` due at the current step samples (and writes, at the end of its window).
    fn sample_ave_times(&mut self) -> R<()> {
        let step = self.world.step;
        for k in 0..self.aves.len() {
            let Some(at) = self.aves[k].as_ref() else { continue };
            if at.nvalid != step {
                continue;
            }
            // Reused buffer: sampling happens every step in typical decks.
            let mut vals = std::mem::take(&mut self.scratch);
            vals.clear();
            for v in &at.values {
                vals.push(self.value_of(v, 0)?);
            }
            if let Some(at) = self.aves[k].as_mut() {
                at.sample(step, &vals)?;
            }
            self.scratch = vals;
        }
        Ok(())
    }

    fn run(&mut self, a: &[&str]) -> R<()> {
        if a.len() < 2 {
            return Err("run: missing N".into());
        }
        let n = int(a[1])?;
        let upto = match a.get(2) {
            None => false,
            Some(&"upto") if a.len() == 3 => true,
            Some(other) => return Err(unsupported(&format!("run keyword {other}"))),
        };
        if n < 0 {
            return Err("run: N must be >= 0".into());
        }
        let nsteps = if upto {
            (n as u64).checked_sub(self.world.step).ok_or("run upto: target step already passed")?
        } else {
            n as u64
        };
        self.prepare()?;
        let warnings = self.world.setup()?;
        for wmsg in warnings {
            self.warn(&wmsg);
        }
        // As in LIGGGHTS, the setup of a run is an end of step for the averaging fixes.
        self.sample_ave_times()?;
        self.say("Setting up run ...");
        let header = self.thermo_header();
        self.say(&header);
        for d in &self.local_dumps {
            d.check(&self.pair_locals)?;
        }
        self.write_dumps()?;
        let first = self.thermo_line()?;
        self.say(&first);
        let bar = if self.progress && !self.quiet && std::io::stdout().is_terminal() && nsteps >= 1000 {
            let pb = indicatif::ProgressBar::new(nsteps);
            pb.set_style(
                indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} steps {per_sec} eta {eta}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            Some(pb)
        } else {
            None
        };
        let t0 = Instant::now();
        let end = self.world.step + nsteps;
        let builds0 = self.world.builds;
        let updates0 = self.world.mc_influence_updates();
        let passes0 = self.world.mc_updates;
        let threaded0 = self.world.threaded_passes();
        let kernel0 = (self.world.mc_kernel_contacts, self.world.mc_kernel_fallbacks);
        while self.world.step < end {
            self.world.step().map_err(|e| {
                let m = e.to_string();
                self.instability = Some(e);
                m
            })?;
            let last = self.world.step == end;
            if let Some(line) = self.end_of_step_outputs(last)? {
                match &bar {
                    Some(pb) => pb.println(&line),
                    None if self.quiet => {}
                    None => println!("{line}"),
                }
                self.logln(&line);
            }
            if let Some(pb) = &bar {
                if self.world.step % 100 == 0 {
                    pb.set_position(nsteps - (end - self.world.step));
                }
            }
        }
        if let Some(pb) = bar {
            pb.finish_and_clear();
        }
        let secs = t0.elapsed().as_secs_f64();
        let np = self.world.p.len();
        self.summary.steps += nsteps;
        self.summary.particle_steps += (nsteps as f64) * np as f64;
        self.summary.loop_seconds += secs;
        self.summary.neighbor_builds += self.world.builds - builds0;
        let rate = if secs > 0.0 { nsteps as f64 * np as f64 / secs } else { 0.0 };
        // What the multi-contact approximations did: how often a particle's Eq. 2 geometry was
        // recomputed, and in how many steps the full pass ran.
        let mut approx = String::new();
        if self.world.mc_geometry_tolerance > 0.0 {
            let updates = self.world.mc_influence_updates() - updates0;
            approx += &format!(
                ", multi-contact geometry tolerance {:e}: recomputed in {:.2} % of particle-steps",
                self.world.mc_geometry_tolerance,
                100.0 * updates as f64 / (nsteps as f64 * np as f64).max(1.0)
            );
        }
        if self.world.mc_every > 1 {
            approx += &format!(
                ", multi-contact update every {} steps: full pass in {} of {nsteps} steps",
                self.world.mc_every,
                self.world.mc_updates - passes0
            );
        }
        // The engine times steps with and without its threads and keeps the faster (results
        // are the same bits either way): say how often the threads were used.
        let threads = rayon::current_num_threads();
        let used = if threads > 1 {
            let (a, b) = self.world.threaded_passes();
            let passes = (a + b) - (threaded0.0 + threaded0.1);
            // (The run's set-up pass counts too: at most 100 %.)
            let pct = (100.0 * passes as f64 / (nsteps as f64).max(1.0)).min(100.0);
            format!(" (threaded in {pct:.0} % of steps)")
        } else {
            String::new()
        };
        self.say(&format!(
            "Loop time of {secs:.6} on 1 procs for {nsteps} steps with {np} atoms ({rate:.4e} particle-steps/s, {threads} threads{used}, {} neighbour builds{approx})\n",
            self.world.builds - builds0
        ));
        // Whether the Eq. 3 cap acted: contacts the multi-contact kernel evaluated, and how many of
        // them it switched back to Hertz because a penetration ratio exceeded MPR.
        let contacts = self.world.mc_kernel_contacts - kernel0.0;
        if contacts > 0 {
            let capped = self.world.mc_kernel_fallbacks - kernel0.1;
            self.say(&format!(
                "Multi-contact kernel: {contacts} contact evaluations, {capped} capped to Hertz by the maximum penetration ratio\n"
            ));
        }
        Ok(())
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

mod mesh {
    pub use crate::engine::mesh::read_stl as read;
}

#[cfg(test)]
mod tests {
    use super::{strip_comment, words};

    /// LAMMPS quoting: double or single quotes make one word, the other kind is plain inside,
    /// and `#` inside quotes is not a comment.
    #[test]
    fn quotes_of_either_kind_make_one_word() {
        let w = words(r#"if "${a} > 0" then "dump_modify d format '%d %g'" 'x "y"'"#).unwrap();
        assert_eq!(w, ["if", "${a} > 0", "then", "dump_modify d format '%d %g'", "x \"y\""]);
        assert_eq!(words("print ''").unwrap(), ["print", ""]);
        assert!(words("print 'open").unwrap_err().contains("unterminated quote '"));
        assert_eq!(strip_comment("print '# not a comment' # a comment"), "print '# not a comment' ");
        assert_eq!(strip_comment(r#"print "it's" # c"#), r#"print "it's" "#);
    }
}
