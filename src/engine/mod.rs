//! The standalone DEM engine: particle state as a struct of arrays, cell-list neighbours with a
//! skin, contact history keyed by particle ids, walls (primitive planes and STL meshes), periodic
//! boundaries and velocity Verlet with rotation (LIGGGHTS `fix nve/sphere`).
//!
//! Contact forces come only from [`crate::physics`]: this module does geometry bookkeeping and
//! integration, never a contact formula of its own.
//!
//! One step follows the LAMMPS/LIGGGHTS Verlet order, so both engines agree step by step:
//! first half kick + drift (and mesh motion), neighbour check, forces (multi-contact radius
//! changes, pairs, gravity, walls), second half kick.

pub mod mesh;
pub mod neighbor;
mod probe;
mod wall_contacts;

use std::cell::RefCell;
use std::fmt;
use std::ops::Range;
use std::sync::Mutex;

use crate::physics::contact_set::{
    loaded_threshold, radius_changes, ContactLoad, InfluenceCache, KeptInfluence, McParams,
};
use crate::physics::hertz::Tangential;
use crate::physics::pair::{
    particle_particle, particle_wall, Body, ContactError, PairLanes, WallLanes, WallPoint, LANES,
};
use crate::physics::{Material, PairCoeffs, Vec3};

use crate::team::{share, SplitMut, Team};
pub use mesh::Mesh;
use neighbor::CellList;
use probe::ThreadProbe;

/// Moment of inertia prefactor of a solid sphere, I = 0.4 m r² (as LIGGGHTS `nve/sphere`).
const INERTIA: f64 = 0.4;

/// Simulation box: bounds and which axes are periodic.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Domain {
    pub lo: Vec3,
    pub hi: Vec3,
    pub periodic: [bool; 3],
    /// Lees–Edwards shear (x sheared along y): x offset of the image above the box (accumulated
    /// strain × L_y, kept in [0, L_x)) and its x velocity jump γ̇ L_y. Both zero without shear.
    pub le_offset: f64,
    pub le_vjump: f64,
}

impl Domain {
    /// Box with no Lees–Edwards shear.
    pub fn new(lo: Vec3, hi: Vec3, periodic: [bool; 3]) -> Self {
        Domain { lo, hi, periodic, le_offset: 0.0, le_vjump: 0.0 }
    }

    /// Shortest periodic image of a separation vector.
    #[inline]
    pub fn minimum_image(&self, d: &mut Vec3) {
        self.minimum_image_k(d);
    }

    /// Shortest image of d = x_i − x_j; returns k, the number of box heights the image of j was
    /// moved up along y. With Lees–Edwards that image also sits k·offset further in x and moves
    /// k·γ̇L_y faster in x, so the caller adds k·le_vjump to v_j.x.
    #[inline]
    pub fn minimum_image_k(&self, d: &mut Vec3) -> f64 {
        let mut k = 0.0;
        if self.periodic[1] {
            let l = self.hi.y - self.lo.y;
            if d.y.abs() > 0.5 * l {
                k = (d.y / l).round();
                d.y -= k * l;
                d.x -= k * self.le_offset;
            }
        }
        for a in [0, 2] {
            if self.periodic[a] {
                let l = self.hi[a] - self.lo[a];
                if d[a].abs() > 0.5 * l {
                    d[a] -= l * (d[a] / l).round();
                }
            }
        }
        k
    }

    /// Advances the Lees–Edwards offset by the velocity jump over dt, kept in [0, L_x).
    pub fn advance_shear(&mut self, dt: f64) {
        if self.le_vjump != 0.0 {
            let lx = self.hi.x - self.lo.x;
            self.le_offset = (self.le_offset + self.le_vjump * dt).rem_euclid(lx);
        }
    }

    /// Streaming velocity u_x = γ̇ (y − y_mid) of the Lees–Edwards shear (zero without shear).
    #[inline]
    pub fn streaming_vx(&self, y: f64) -> f64 {
        let ly = self.hi.y - self.lo.y;
        self.le_vjump / ly * (y - 0.5 * (self.lo.y + self.hi.y))
    }

    pub fn volume(&self) -> f64 {
        let l = self.hi - self.lo;
        l.x * l.y * l.z
    }
}

/// Per-particle state, struct of arrays. Indices change only when [`World::sort_every`] asks for
/// spatial sorting (then at neighbour builds); everything keyed by index is remapped with them,
/// and ids never change.
#[derive(Debug, Clone, Default)]
pub struct Particles {
    pub id: Vec<i64>,
    /// Atom type, 0-based.
    pub typ: Vec<usize>,
    pub x: Vec<Vec3>,
    pub v: Vec<Vec3>,
    pub omega: Vec<Vec3>,
    pub f: Vec<Vec3>,
    pub torque: Vec<Vec3>,
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    pub density: Vec<f64>,
    /// Periodic image counts (LAMMPS ix iy iz).
    pub image: Vec<[i32; 3]>,
}

impl Particles {
    pub fn len(&self) -> usize {
        self.x.len()
    }

    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Adds a sphere; mass from the density as LIGGGHTS `atom_style sphere` does.
    pub fn push(&mut self, id: i64, typ: usize, x: Vec3, diameter: f64, density: f64) {
        let r = 0.5 * diameter;
        self.id.push(id);
        self.typ.push(typ);
        self.x.push(x);
        self.v.push(Vec3::zeros());
        self.omega.push(Vec3::zeros());
        self.f.push(Vec3::zeros());
        self.torque.push(Vec3::zeros());
        self.radius.push(r);
        self.mass.push(sphere_mass(r, density));
        self.density.push(density);
        self.image.push([0; 3]);
    }

    /// Recomputes the mass of particle `i` after a diameter or density change.
    pub fn set_size(&mut self, i: usize, diameter: Option<f64>, density: Option<f64>) {
        if let Some(d) = diameter {
            self.radius[i] = 0.5 * d;
        }
        if let Some(rho) = density {
            self.density[i] = rho;
        }
        self.mass[i] = sphere_mass(self.radius[i], self.density[i]);
    }
}

impl Particles {
    /// Reorders every array: the particle at old index `old_of_new[k]` moves to index k.
    fn permute(&mut self, old_of_new: &[u32]) {
        fn gather<T: Copy>(v: &mut Vec<T>, old_of_new: &[u32]) {
            // One fresh array per field and sort: sorts are rare (every `sort_every` steps at a
            // neighbour build), so this stays out of the step loop's cost.
            let out: Vec<T> = old_of_new.iter().map(|&o| v[o as usize]).collect();
            *v = out;
        }
        gather(&mut self.id, old_of_new);
        gather(&mut self.typ, old_of_new);
        gather(&mut self.x, old_of_new);
        gather(&mut self.v, old_of_new);
        gather(&mut self.omega, old_of_new);
        gather(&mut self.f, old_of_new);
        gather(&mut self.torque, old_of_new);
        gather(&mut self.radius, old_of_new);
        gather(&mut self.mass, old_of_new);
        gather(&mut self.density, old_of_new);
        gather(&mut self.image, old_of_new);
    }
}

fn sphere_mass(r: f64, density: f64) -> f64 {
    if r == 0.0 {
        density
    } else {
        4.0 * std::f64::consts::PI / 3.0 * r * r * r * density
    }
}

/// A primitive plane wall `xplane|yplane|zplane POS`; particles on either side touch it.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneWall {
    pub axis: usize,
    pub pos: f64,
    pub wall_type: usize,
}

/// A `fix wall/gran`: one plane, or the meshes it uses (indices into [`World::meshes`]).
#[derive(Debug, Clone, PartialEq)]
pub enum WallGeom {
    Plane(PlaneWall),
    Meshes(Vec<usize>),
}

#[derive(Debug, Clone, PartialEq)]
pub struct WallFix {
    pub name: String,
    pub geom: WallGeom,
}

/// Candidate pair with its tangential history ξ: what every step reads and writes per pair, 32
/// bytes, two to a cache line. What only the multi-contact closure needs lives beside it in
/// [`PairHist`], and per-step transients (this step's radius changes, the recorded force) in their
/// own arrays: at large N the pairs no longer fit in cache and stream from memory every step, so a
/// Hertz pass moves half the bytes it would if the closure's state rode along.
#[derive(Debug, Clone, Copy)]
#[repr(align(32))]
struct Pair {
    i: u32,
    j: u32,
    shear: Vec3,
}

/// What the multi-contact pass reads of a pair, written by the pair pass before it (kept, one per
/// pair, only under the closure).
#[derive(Debug, Clone, Copy)]
struct PairHist {
    /// |F·n| of the previous step (Eq. 2 is lagged one step).
    fn_prev: f64,
    /// Modified radii r + Δ used at the previous step (contact point of the next step, as LIGGGHTS).
    ri_prev: f64,
    rj_prev: f64,
    /// Centres closer than (1 + RECEIVER_GAP)(r_i + r_j) at the last evaluation: the pair may
    /// receive multi-contact terms (growth could make it touch). True for a new pair.
    near: bool,
}

impl PairHist {
    /// A pair just found by the neighbour search. LIGGGHTS starts a pair's history at zero radii:
    /// the contact point sits at the centre and receives no multi-contact term until the pair is
    /// evaluated.
    const NEW: PairHist = PairHist { fn_prev: 0.0, ri_prev: 0.0, rj_prev: 0.0, near: true };
}

/// This step's multi-contact radius changes of a pair: [Δ of i at this contact, Δ of j].
type PairDr = [f64; 2];

/// A pair's contact as the multi-contact kernel sees it: the contact points relative to i and to
/// j, and the previous step's normal force.
#[derive(Debug, Clone, Copy, Default)]
struct PairLoad {
    points: [Vec3; 2],
    force: f64,
}

/// One touching particle pair as output sees it (indices into the particle arrays).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairContact {
    pub i: usize,
    pub j: usize,
    /// x_i − x_j, minimum image.
    pub branch: Vec3,
    /// The pair touches across a periodic boundary.
    pub periodic: bool,
    /// Contact force on i [N].
    pub force: Vec3,
    /// Contact torque on i [N m].
    pub torque: Vec3,
}

/// A particle and a wall element (plane, or one triangle of a mesh) that may come within reach
/// before the wall candidates are rebuilt.
#[derive(Debug, Clone, Copy)]
struct WallCandidate {
    p: u32,
    wall: u32,
    mesh: u32,
    tri: u32,
}

/// A particle close to a wall element (plane, or one triangle of a mesh) with its history.
#[derive(Debug, Clone, Copy)]
struct WallContact {
    p: u32,
    wall: u32,
    mesh: u32,
    tri: u32,
    point: Vec3,
    velocity: Vec3,
    shear: Vec3,
    fn_prev: f64,
    /// Contact point relative to the centre at the previous step (LIGGGHTS `surfPos`): the
    /// multi-contact pass reads it, as LIGGGHTS does; zero for a contact seen for the first time.
    rel_prev: Vec3,
    dr: f64,
}

impl WallContact {
    /// A contact seen for the first time: no tangential history, no previous force or surface point.
    fn fresh(p: usize, wall: usize, mesh: usize, tri: usize, point: Vec3, velocity: Vec3) -> Self {
        WallContact {
            p: p as u32,
            wall: wall as u32,
            mesh: mesh as u32,
            tri: tri as u32,
            point,
            velocity,
            shear: Vec3::zeros(),
            fn_prev: 0.0,
            rel_prev: Vec3::zeros(),
            dr: 0.0,
        }
    }

    #[inline]
    fn key(&self) -> (u32, u32, u32, u32) {
        (self.p, self.wall, self.mesh, self.tri)
    }
}

/// Which multi-contact closure the contacts use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Closure {
    /// Plain Hertz: no radius changes.
    Hertz,
    /// Eq. 2 (standard MC), with the Eq. 3 cap where a type's material carries one.
    MultiContact,
}

/// Why a run stopped: the particle, the step and the cause.
#[derive(Debug, Clone, PartialEq)]
pub struct StepError {
    pub step: u64,
    pub particle: i64,
    pub cause: String,
}

impl fmt::Display for StepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "step {}: particle {}: {}", self.step, self.particle, self.cause)
    }
}

impl std::error::Error for StepError {}

/// Per-type MC kernel parameters without the radius (filled in per particle).
#[derive(Debug, Clone, Copy)]
struct McType {
    material: Material,
}

/// Indirection from a particle to one of its contacts, for the multi-contact pass.
#[derive(Debug, Clone, Copy)]
enum Slot {
    PairI(u32),
    PairJ(u32),
    Wall(u32),
}

/// The whole simulated system.
#[derive(Debug, Default)]
pub struct World {
    pub domain: Option<Domain>,
    pub p: Particles,
    pub ntypes: usize,
    /// Per type (0-based): material.
    pub materials: Vec<Material>,
    /// ntypes × ntypes pair coefficients, row-major.
    pub coeffs: Vec<PairCoeffs>,
    pub closure: Option<Closure>,
    pub dt: f64,
    pub step: u64,
    pub gravity: Option<Vec3>,
    pub walls: Vec<WallFix>,
    pub meshes: Vec<Mesh>,
    pub skin: f64,
    /// Multi-contact range factor: wall contacts are sought out to this multiple of the radius;
    /// pair lists out to it as well, but never beyond what a pair can use ([`World::pair_reach`]).
    pub mc_range: f64,
    /// Is each particle integrated (`fix nve/sphere` present)?
    pub integrate: bool,
    /// Number of neighbour-list builds so far.
    pub builds: u64,
    /// LIGGGHTS 3.8 `surface multicontact` radius convention in pairs: the first particle of a
    /// pair keeps its original radius in R_eff and lever arm (only its overlap sees Δ). Set for
    /// decks that ask for LIGGGHTS' standard MC, so both engines give the same forces; the
    /// `mc_advanced` model uses the modified radii of both particles (SPEC §2).
    pub liggghts_radii: bool,
    /// Multi-contact kernel counters since they were last zeroed (diagnostics): contacts the kernel
    /// saw (particles with two or more contacts, touching or within the MC range) and those the
    /// Eq. 3 cap switched back to Hertz.
    pub mc_kernel_contacts: u64,
    pub mc_kernel_fallbacks: u64,
    /// Geometry tolerance of the multi-contact pass, as a fraction of the particle radius. 0 (the
    /// default): Eq. 2 is evaluated from this step's contact points for every particle. > 0: each
    /// particle keeps its influence matrix (Eq. 2 without the forces) and recomputes it only when
    /// one of its contact points has moved more than this fraction of its radius since, or its
    /// number of contacts changed: an approximation whose error `mcdem bench` reports next to its speed.
    pub mc_geometry_tolerance: f64,
    /// Multi-contact update interval K [steps]. 0 or 1 (the default): the radius changes are
    /// recomputed every step, as Eq. 2 prescribes (from the previous step's forces). K > 1: they are
    /// recomputed every K steps and at every neighbour-list build, and kept in between (walls
    /// by contact), like a slow force in multiple time stepping: the multi-contact pass then costs
    /// 1/K of its exact cost and the radius changes lag the forces by up to K steps. Contacts
    /// appearing in between get their change at the next update. An approximation whose
    /// error `mcdem bench` reports next to its speed.
    pub mc_every: u64,
    /// Full multi-contact passes so far.
    pub mc_updates: u64,
    /// Step of the next full multi-contact pass under `mc_every`.
    mc_due: u64,
    /// Neighbour builds at the last full multi-contact pass (a build renumbers the pairs).
    mc_builds: u64,
    /// Spatial sorting (LAMMPS `atom_modify sort`): at the first neighbour build at least this
    /// many steps after the last sort, particles are renumbered bin by bin in row-major order, so
    /// that particles close in space are close in memory and the pair loop stays in cache as N
    /// grows. 0 (the default of the library API, which keeps indices stable): never. Decks get
    /// LAMMPS' 1000.
    pub sort_every: u64,
    /// Number of spatial sorts so far.
    pub sorts: u64,
    next_sort: u64,

    cells: CellList,
    cand: Vec<(u32, u32)>,
    pairs: Vec<Pair>,
    pairs_old: Vec<Pair>,
    /// Per pair, under the multi-contact closure: what its next pass reads (empty under Hertz).
    pair_hist: Vec<PairHist>,
    pair_hist_old: Vec<PairHist>,
    wc: Vec<WallContact>,
    wc_old: Vec<WallContact>,
    wc_scratch: wall_contacts::GroupScratch,
    /// Wall elements that may touch a particle before the next candidate build, in the wall scan's
    /// order (`update_wall_contacts`); built at every neighbour build (`wall_cand_builds`) and when
    /// the meshes have moved half a skin since (`wall_travel`).
    wall_cand: Vec<WallCandidate>,
    wall_cand_builds: Option<u64>,
    /// Upper bound on how far any mesh moved since the wall candidates were built [m].
    wall_travel: f64,
    x_build: Vec<Vec3>,
    need_build: bool,
    /// Lees–Edwards offset travelled since the last neighbour build (not wrapped) [m].
    le_travel: f64,
    /// Interaction cutoff without skin, 2 r_max × pair_reach, at the last build [m].
    cut_build: f64,
    mc_types: Vec<McType>,
    // multi-contact scratch (kept between steps: no allocation in the loop)
    slot_start: Vec<u32>,
    slots: Vec<Slot>,
    slot_fill: Vec<u32>,
    /// Radius change per slot, from this step's kernel pass.
    slot_dr: Vec<f64>,
    /// Per particle, its pairs (see `build_incidence`), as compressed rows.
    inc_start: Vec<u32>,
    inc: Vec<u32>,
    /// Threaded pair pass: per particle, the block of pairs that writes its sums directly (the
    /// first block, in pair order, with a pair on it; see [`World::assign_owners`]).
    owner: Vec<u16>,
    /// (pairs, blocks, particles) the owners were computed for; None after a neighbour build.
    owner_key: Option<(usize, usize, usize)>,
    /// Where the blocks of the owning threaded pass start in the pair list (and the end): equal
    /// runs after each assignment, then moved by [`World::balance_blocks`] to even out the
    /// members' measured times.
    pair_cuts: Vec<usize>,
    /// Per block, nanoseconds spent in the threaded pair pass since the last balancing, and the
    /// passes counted.
    block_ns: Vec<u64>,
    block_passes: u32,
    /// Few enough pair ends fall on particles another block owns for the blocks to pay (else the
    /// threaded pass keeps every pair's result and sums per particle afterwards).
    owned_blocks_pay: bool,
    /// Threaded pair passes so far: (by owned blocks, keeping every pair's result).
    threaded_passes: (u64, u64),
    /// Threaded pair pass: per block, its contributions to particles another block owns, in pair
    /// order (kept between steps: no allocation in the loop once grown).
    deferred: Vec<Vec<Deferred>>,
    /// The slot lists no longer match the pairs and wall contacts (neighbour build, a wall
    /// contact appeared or left, a pair entered or left the multi-contact set).
    slots_stale: bool,
    /// Per pair: what this step's multi-contact pass reads (filled for pairs taking part).
    pair_loads: Vec<PairLoad>,
    /// Geometry tolerance: the kept influence matrices, one per particle.
    mc_cache: Option<InfluenceCache>,
    pair_out: Vec<PairOut>,
    /// Per pair, under the multi-contact closure: this step's radius changes (a Hertz pass reads none).
    pair_dr: Vec<PairDr>,
    /// Per pair: the total contact force on i from j at the last force pass (zero when apart),
    /// for the stress and coordination outputs.
    pair_force: Vec<Vec3>,
    pair_mc: Vec<bool>,
    /// Per wall contact: its force on the particle at the last force pass (for the mesh sums).
    wall_force: Vec<Vec3>,
    f_buf: Vec<Vec3>,
    t_buf: Vec<Vec3>,
    parallel: bool,
    /// When `PairThreads::Auto` times steps with and without threads, and what it measured.
    probe: ThreadProbe,
    /// Whether a step's force passes (pairs, walls, multi-contact kernel) and half-kicks run on
    /// the threads' team (default: decided by the timing probe).
    pub pair_threads: PairThreads,
    /// The threads of the threaded passes (`rayon::current_num_threads()` members, started at
    /// the first threaded step and kept for the run).
    team: Option<Team>,
    /// Per member of the threaded wall pass: its first wall contact and first particle (and
    /// after the last member, the ends).
    wall_cuts: Vec<[usize; 2]>,
}

/// Whether the force passes of a step (pairs, wall contacts, the multi-contact kernel) run on the
/// threads' team ([`Team`], as many members as the rayon pool the step runs in has threads).
/// The results are bit-identical either way (every sum is taken in the serial order),
/// so this only decides speed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PairThreads {
    /// Time windows of steps with and without threads (alternating in slices) and keep the
    /// faster: every 5 000 steps, sooner after a choice of one core (`probe.rs`).
    #[default]
    Auto,
    Serial,
    Parallel,
}

impl World {
    pub fn new() -> Self {
        World { mc_range: 1.0, ..Default::default() }
    }

    /// Checks that the world is complete and consistent, and builds the neighbour list: called by
    /// every `run` before the first step (LAMMPS `setup`).
    pub fn setup(&mut self) -> Result<Vec<String>, String> {
        let mut warnings = Vec::new();
        let domain = self.domain.ok_or("no simulation box (create_box or read_data) before run")?;
        if self.dt <= 0.0 {
            return Err("timestep must be > 0".into());
        }
        if self.closure.is_none() {
            return Err("no pair_style gran defined before run".into());
        }
        if self.coeffs.len() != self.ntypes * self.ntypes {
            return Err("material properties missing (fix property/global youngsModulus, poissonsRatio, coefficientRestitution, coefficientFriction)".into());
        }
        let n = self.p.len();
        for i in 0..n {
            if !(self.p.radius[i] > 0.0 && self.p.mass[i] > 0.0) {
                return Err(format!("particle {}: radius and mass must be > 0", self.p.id[i]));
            }
        }
        // Rayleigh time step (LIGGGHTS checks the same): above it the explicit scheme is unstable.
        let mut worst: Option<(f64, usize)> = None;
        for i in 0..n {
            let m = &self.materials[self.p.typ[i]];
            let nu = m.poisson_ratio;
            let g = m.youngs_modulus / (2.0 * (1.0 + nu));
            let t_r = std::f64::consts::PI * self.p.radius[i] * (self.p.density[i] / g).sqrt()
                / (0.1631 * nu + 0.8766);
            if worst.is_none_or(|(t, _)| t_r < t) {
                worst = Some((t_r, i));
            }
        }
        if let Some((t_r, i)) = worst {
            if self.dt > t_r {
                return Err(format!(
                    "step {}: particle {}: time step {:e} s is above the Rayleigh time {:e} s: the run would be unstable",
                    self.step, self.p.id[i], self.dt, t_r
                ));
            }
            if self.dt > 0.2 * t_r {
                warnings.push(format!(
                    "time step {:e} s is {:.0} % of the Rayleigh time {:e} s (particle {}); keep it below 20 %",
                    self.dt,
                    100.0 * self.dt / t_r,
                    t_r,
                    self.p.id[i]
                ));
            }
        }
        let rmax = self.p.radius.iter().copied().fold(0.0, f64::max);
        for a in 0..3 {
            let l = domain.hi[a] - domain.lo[a];
            if domain.periodic[a] && l < 2.0 * (2.0 * rmax * self.pair_reach() + self.skin) {
                return Err(format!(
                    "periodic box length {l:e} m along axis {a} is shorter than twice the neighbour cutoff"
                ));
            }
        }
        self.mc_types = self.materials.iter().map(|m| McType { material: *m }).collect();
        let tol = self.mc_geometry_tolerance;
        if tol == 0.0 {
            self.mc_cache = None;
        } else if self.mc_cache.as_ref().is_none_or(|c| c.tolerance() != tol) {
            self.mc_cache = Some(InfluenceCache::new(tol).map_err(|e| e.to_string())?);
        }
        self.need_build = true;
        self.mc_due = 0;
        self.neighbor_check().map_err(|e| e.to_string())?;
        // LIGGGHTS zeroes mesh node velocities at set-up (fix move/mesh sets them again in the
        // first step), so the set-up forces see resting meshes.
        // The threads' team is started here rather than inside the timing probe's first window.
        if self.pair_threads != PairThreads::Serial {
            self.start_team();
        }
        let vel: Vec<Vec3> = self.meshes.iter().map(|m| m.velocity).collect();
        self.meshes.iter_mut().for_each(|m| m.velocity = Vec3::zeros());
        let r = self.compute_forces(false).map_err(|e| e.to_string());
        self.meshes.iter_mut().zip(vel).for_each(|(m, v)| m.velocity = v);
        r?;
        Ok(warnings)
    }

    /// One velocity-Verlet step.
    pub fn step(&mut self) -> Result<(), StepError> {
        self.step += 1;
        let dt = self.dt;
        // Threads pay only when the cores are free: the probe (`probe.rs`) times windows of whole
        // steps with and without them and keeps the faster. Whole steps, so that what threading
        // changes outside the threaded passes counts too, but without the neighbour check: a
        // list build costs the same in both modes and would weigh on whichever slice it falls in.
        let plan = match self.pair_threads {
            PairThreads::Auto => self.probe.plan(self.step),
            fixed => {
                self.parallel = fixed == PairThreads::Parallel;
                None
            }
        };
        if let Some(s) = plan {
            self.parallel = s.threads;
        }
        let t0 = plan.filter(|s| s.timed).map(|_| std::time::Instant::now());
        if self.integrate {
            self.initial_integrate();
        }
        if let Some(d) = self.domain.as_mut() {
            d.advance_shear(dt);
            self.le_travel += d.le_vjump * dt;
        }
        let mut travel: f64 = 0.0;
        for m in &mut self.meshes {
            if m.velocity != Vec3::zeros() {
                let d = m.velocity * dt;
                m.translate(&d);
                travel = travel.max(d.norm());
            }
        }
        self.wall_travel += travel;
        let t_check = t0.is_some().then(std::time::Instant::now);
        self.neighbor_check()?;
        let check = t_check.map_or(std::time::Duration::ZERO, |t| t.elapsed());
        self.compute_forces(true)?;
        if self.integrate {
            self.final_integrate()?;
        }
        if let Some(t0) = t0 {
            let ns = t0.elapsed().saturating_sub(check).as_nanos() as u64;
            if let Some(threads) = self.probe.record(self.step, ns) {
                self.parallel = threads;
            }
        }
        Ok(())
    }

    /// The team of the threaded passes when this step uses threads and there are several to use
    /// (as many members as the rayon pool the step runs in has threads), started on first use.
    fn threads(&mut self) -> Option<&Team> {
        if !self.parallel {
            return None;
        }
        self.start_team()
    }

    /// The team, started if there is none of the pool's size yet; none on a one-thread pool.
    fn start_team(&mut self) -> Option<&Team> {
        let size = rayon::current_num_threads();
        if size < 2 {
            return None;
        }
        if self.team.as_ref().is_none_or(|t| t.size() != size) {
            self.team = Some(Team::new(size));
        }
        self.team.as_ref()
    }

    /// First half of velocity Verlet: half-kick, drift, rotational half-kick. On the team's
    /// threads each member moves its own range of particles (the range it will also finish and,
    /// roughly, the particles of its pair block): a particle's state then stays in one core's
    /// cache from step to step instead of travelling between them.
    fn initial_integrate(&mut self) {
        let (dtf, dtv) = (0.5 * self.dt, self.dt);
        let dtfrot = dtf / INERTIA;
        let n = self.p.len();
        let p = &mut self.p;
        let (f, torque, mass, radius) = (&p.f, &p.torque, &p.mass, &p.radius);
        let kick = |r: Range<usize>, x: &mut [Vec3], v: &mut [Vec3], omega: &mut [Vec3]| {
            for (i, ((x, v), omega)) in r.zip(x.iter_mut().zip(v.iter_mut()).zip(omega.iter_mut())) {
                let dtfm = dtf / mass[i];
                *v += dtfm * f[i];
                *x += dtv * *v;
                let dtirot = dtfrot / (radius[i] * radius[i] * mass[i]);
                *omega += dtirot * torque[i];
            }
        };
        match self.team.as_ref().filter(|_| self.parallel) {
            Some(team) => {
                let (xs, vs, os) =
                    (SplitMut::new(&mut p.x), SplitMut::new(&mut p.v), SplitMut::new(&mut p.omega));
                team.for_shares(n, |_, r| {
                    // SAFETY: the members' shares are disjoint ranges of particles.
                    let (x, v, o) =
                        unsafe { (xs.range(r.clone()), vs.range(r.clone()), os.range(r.clone())) };
                    kick(r, x, v, o);
                });
            }
            None => kick(0..n, &mut p.x, &mut p.v, &mut p.omega),
        }
    }

    /// Second half-kick of velocity Verlet (on the team's threads as [`World::initial_integrate`]);
    /// stops at the first particle (lowest index) whose position or velocity is not finite.
    fn final_integrate(&mut self) -> Result<(), StepError> {
        let dtf = 0.5 * self.dt;
        let dtfrot = dtf / INERTIA;
        let (n, step) = (self.p.len(), self.step);
        let p = &mut self.p;
        let (f, torque, mass, radius, x, id) = (&p.f, &p.torque, &p.mass, &p.radius, &p.x, &p.id);
        let kick = |r: Range<usize>, v: &mut [Vec3], omega: &mut [Vec3]| {
            for (i, (v, omega)) in r.zip(v.iter_mut().zip(omega.iter_mut())) {
                let dtfm = dtf / mass[i];
                *v += dtfm * f[i];
                let dtirot = dtfrot / (radius[i] * radius[i] * mass[i]);
                *omega += dtirot * torque[i];
                if !(x[i].iter().all(|c| c.is_finite()) && v.iter().all(|c| c.is_finite())) {
                    return Err(StepError {
                        step,
                        particle: id[i],
                        cause: "position or velocity is not finite".into(),
                    });
                }
            }
            Ok(())
        };
        match self.team.as_ref().filter(|_| self.parallel) {
            Some(team) => {
                let (vs, os) = (SplitMut::new(&mut p.v), SplitMut::new(&mut p.omega));
                team.run_shares(n, |_, r| {
                    // SAFETY: the members' shares are disjoint ranges of particles.
                    let (v, o) = unsafe { (vs.range(r.clone()), os.range(r.clone())) };
                    kick(r, v, o)
                })
            }
            None => kick(0..n, &mut p.v, &mut p.omega),
        }
    }

    /// Rebuilds the neighbour list when a pair could have closed the skin since the last build
    /// (or on request). Without shear that is LAMMPS' test, some particle moved more than skin/2.
    /// Under Lees–Edwards shear each particle's displacement is split into the affine streaming
    /// part at its build position, γ (y_build − y_mid) x̂ for the strain γ since the build, and
    /// the rest (the fluctuation, largest m). Two particles that can touch now are less than the
    /// cutoff r_c + 2m apart in y, so their separation changed by at most 2m + γ (r_c + 2m); the
    /// image across the sheared boundary moves with the offset, which cancels the streaming jump
    /// there. Rebuilding when that bound reaches the skin keeps the list complete, and the
    /// interval no longer shrinks with the box size: the lab displacement of particles near the
    /// boundary grows with L_y, the relative motion of neighbours does not.
    fn neighbor_check(&mut self) -> Result<(), StepError> {
        if !self.need_build {
            let Some(domain) = self.domain else { return Ok(()) };
            // Lees–Edwards strain since the build (0 without shear).
            let strain =
                if self.le_travel == 0.0 { 0.0 } else { self.le_travel / (domain.hi.y - domain.lo.y) };
            let moved = if strain == 0.0 {
                let lim = 0.25 * self.skin * self.skin;
                self.p.x.iter().zip(&self.x_build).any(|(x, x0)| (x - x0).norm_squared() > lim)
            } else {
                let ymid = 0.5 * (domain.lo.y + domain.hi.y);
                let m2 = self
                    .p
                    .x
                    .iter()
                    .zip(&self.x_build)
                    .map(|(x, x0)| {
                        let mut d = x - x0;
                        d.x -= strain * (x0.y - ymid);
                        d.norm_squared()
                    })
                    .fold(0.0, f64::max);
                let m = m2.sqrt();
                2.0 * m + strain.abs() * (self.cut_build + 2.0 * m) > self.skin
            };
            if !moved {
                return Ok(());
            }
        }
        self.need_build = false;
        self.builds += 1;
        let domain = self.domain.expect("domain checked in setup");
        // Periodic wrap and lost-particle check happen at rebuilds, as in LAMMPS. y first: a
        // Lees–Edwards crossing shifts x, which is then wrapped too.
        for i in 0..self.p.len() {
            for a in [1, 0, 2] {
                let (lo, hi) = (domain.lo[a], domain.hi[a]);
                let xi = &mut self.p.x[i];
                let x = &mut xi[a];
                if domain.periodic[a] {
                    let l = hi - lo;
                    let mut crossed = 0.0;
                    while *x >= hi {
                        *x -= l;
                        self.p.image[i][a] += 1;
                        crossed -= 1.0;
                    }
                    while *x < lo {
                        *x += l;
                        self.p.image[i][a] -= 1;
                        crossed += 1.0;
                    }
                    if a == 1 && crossed != 0.0 {
                        // Leaving through the top of a sheared box: back in at the bottom,
                        // shifted and slowed by the image's offset and velocity jump.
                        xi.x += crossed * domain.le_offset;
                        self.p.v[i].x += crossed * domain.le_vjump;
                    }
                } else if !(*x >= lo && *x <= hi) {
                    return Err(StepError {
                        step: self.step,
                        particle: self.p.id[i],
                        cause: format!(
                            "left the box along {} (coordinate {:e} m outside [{:e}, {:e}]): lost particle",
                            ["x", "y", "z"][a],
                            *x,
                            lo,
                            hi
                        ),
                    });
                }
            }
        }
        // The pair cutoff without skin, read by the sort's bins and by the next rebuild test.
        self.cut_build = 2.0 * self.p.radius.iter().copied().fold(0.0, f64::max) * self.pair_reach();
        if self.sort_every > 0 && self.step >= self.next_sort {
            self.sort_spatially(&domain);
            self.next_sort = self.step + self.sort_every;
        }
        self.cells.build(&domain, &self.p.x, &self.p.radius, self.skin, self.pair_reach(), &mut self.cand);
        // Carry the history over: both lists are sorted by (i, j). The closure's state rides
        // along when it is kept (a closure that starts later finds every pair new).
        std::mem::swap(&mut self.pairs, &mut self.pairs_old);
        std::mem::swap(&mut self.pair_hist, &mut self.pair_hist_old);
        self.pairs.clear();
        self.pair_hist.clear();
        let keep_hist = self.closure == Some(Closure::MultiContact);
        let old_hist = self.pair_hist_old.len() == self.pairs_old.len();
        let mut k = 0;
        for &(i, j) in &self.cand {
            while k < self.pairs_old.len() && (self.pairs_old[k].i, self.pairs_old[k].j) < (i, j) {
                k += 1;
            }
            let old = self.pairs_old.get(k).filter(|o| o.i == i && o.j == j);
            self.pairs.push(old.copied().unwrap_or(Pair { i, j, shear: Vec3::zeros() }));
            if keep_hist {
                let h = old.filter(|_| old_hist).map(|_| self.pair_hist_old[k]);
                self.pair_hist.push(h.unwrap_or(PairHist::NEW));
            }
        }
        self.slots_stale = true;
        self.owner_key = None;
        // The incidence rows are built when the threaded pass first needs them.
        self.inc.clear();
        self.x_build.clear();
        self.x_build.extend_from_slice(&self.p.x);
        self.le_travel = 0.0;
        Ok(())
    }

    /// Threaded pair passes so far: (by blocks that own their particles, keeping every pair's
    /// result and summing per particle afterwards). Both give the serial sums bit for bit; which
    /// one runs depends on how many pair ends the blocks share (`assign_owners`).
    pub fn threaded_passes(&self) -> (u64, u64) {
        self.threaded_passes
    }

    /// Splits the pairs into `blocks` equal runs ([`share`]) and gives each particle to the
    /// first block (in pair order) with a pair on it ([`World::own_blocks`]).
    fn assign_owners(&mut self, blocks: usize) {
        let np = self.pairs.len();
        self.pair_cuts.clear();
        self.pair_cuts.extend((0..blocks).map(|b| share(np, blocks, b).start));
        self.pair_cuts.push(np);
        self.block_ns.clear();
        self.block_ns.resize(blocks, 0);
        self.block_passes = 0;
        self.own_blocks();
    }

    /// Moves the block boundaries so that each member's share of the pairs is proportional to
    /// the rate at which it evaluated them over the last [`BALANCE_PASSES`] passes (equal runs of
    /// pairs need not cost the same: touching pairs cost more than those apart, and the data a
    /// member reads may sit in the other core's cache), and reassigns the owners if a boundary
    /// moved by more than 1 % of the pairs. Where the boundaries lie changes nothing in the
    /// results: every particle still receives its terms in pair order.
    fn balance_blocks(&mut self) {
        let np = self.pairs.len();
        let blocks = self.pair_cuts.len() - 1;
        let rate = |b: usize| {
            let len = (self.pair_cuts[b + 1] - self.pair_cuts[b]) as f64;
            len / (self.block_ns[b].max(1) as f64)
        };
        let total: f64 = (0..blocks).map(rate).sum();
        if !(total.is_finite() && total > 0.0) {
            return;
        }
        // Half-way to the balanced boundaries each time: the times are noisy. On the stack: at
        // most MAX_PAIR_BLOCKS + 1 boundaries.
        let mut buf = [0usize; MAX_PAIR_BLOCKS + 1];
        let cuts = &mut buf[..=blocks];
        cuts.copy_from_slice(&self.pair_cuts);
        let mut acc = 0.0;
        for b in 1..blocks {
            acc += rate(b - 1) / total;
            let target = 0.5 * (self.pair_cuts[b] as f64 + acc * np as f64);
            cuts[b] = (target.round() as usize).clamp(cuts[b - 1], np);
        }
        self.block_ns.iter_mut().for_each(|t| *t = 0);
        self.block_passes = 0;
        if cuts.iter().zip(&self.pair_cuts).any(|(a, b)| a.abs_diff(*b) * 100 > np) {
            self.pair_cuts.copy_from_slice(cuts);
            self.own_blocks();
        }
    }

    /// Gives each particle to the first block (in pair order, blocks as in `pair_cuts`) with a
    /// pair on it; particles on no pair get `u16::MAX` (nobody writes them).
    /// Every contribution a particle receives from its owner comes before any from later blocks,
    /// so the owner may add straight into the sums while later blocks defer theirs: the threaded
    /// pass then adds in exactly the serial order. With the particles sorted in space, only a
    /// thin layer at each block boundary is shared.
    fn own_blocks(&mut self) {
        let (n, np, blocks) = (self.p.len(), self.pairs.len(), self.pair_cuts.len() - 1);
        self.owner.clear();
        self.owner.resize(n, u16::MAX);
        self.deferred.resize_with(blocks, Vec::new);
        let mut shared = 0;
        for b in 0..blocks {
            let block = &self.pairs[self.pair_cuts[b]..self.pair_cuts[b + 1]];
            let before = shared;
            for pr in block {
                for a in [pr.i as usize, pr.j as usize] {
                    if self.owner[a] == u16::MAX {
                        self.owner[a] = b as u16;
                    }
                    shared += usize::from(self.owner[a] != b as u16);
                }
            }
            // Room for every deferral the block can make, so the pair loop never grows the list.
            let d = &mut self.deferred[b];
            d.clear();
            d.reserve(shared - before);
        }
        // Deferred ends cost a serial pass after the blocks, one addition each; keeping every
        // pair's result instead costs two more passes over all pairs and a second threaded
        // section. With the particles sorted, a particle's partners j > i lie up to about two
        // layers of bins ahead in index order, so few ends are shared: with two blocks 2.3 % at
        // 97 556 spheres in the dense packing, 4 % at 19 652, 9 % at 2 048, 12 % in the
        // 514-particle hydrogel deck (there the blocks take 2.1-2.3 s per stroke against
        // 3.2-3.3 s keeping every result, serial 2.8 s). Unsorted numberings share about half.
        self.owned_blocks_pay = shared * 4 <= 2 * np;
        self.owner_key = Some((np, blocks, n));
    }

    /// Per particle, its pairs in pair order (index × 2 + side, side 1 when it is the pair's j),
    /// as compressed rows: the threaded force pass sums each particle's pair results from these,
    /// in the order the serial pass adds them.
    fn build_incidence(&mut self) {
        let n = self.p.len();
        self.inc_start.clear();
        self.inc_start.resize(n + 1, 0);
        for pr in &self.pairs {
            self.inc_start[pr.i as usize + 1] += 1;
            self.inc_start[pr.j as usize + 1] += 1;
        }
        for i in 0..n {
            self.inc_start[i + 1] += self.inc_start[i];
        }
        self.inc.resize(2 * self.pairs.len(), 0);
        self.slot_fill.clear();
        self.slot_fill.extend_from_slice(&self.inc_start[..n]);
        for (k, pr) in self.pairs.iter().enumerate() {
            for (a, side) in [(pr.i, 0), (pr.j, 1)] {
                let at = &mut self.slot_fill[a as usize];
                self.inc[*at as usize] = 2 * k as u32 + side;
                *at += 1;
            }
        }
    }

    /// Renumbers the particles bin by bin in row-major order (x fastest, as LAMMPS' `atom_modify
    /// sort`), bins half a neighbour cutoff wide, and remaps everything keyed by particle index:
    /// pair history (a pair whose indices change order is turned round), wall contacts and kept
    /// influence matrices. Positions must be inside the box (called after the periodic wrap) and
    /// `cut_build` current. The physics is unchanged; only summation orders, hence round-off,
    /// differ from an unsorted run.
    ///
    /// Why row-major and not a space-filling curve: the pair loop walks particle i in index order
    /// and touches each partner j > i. In row-major order every partner lies at most about one
    /// xy-layer of bins ahead (N^(2/3) particles), and the partners' indices rise steadily with i,
    /// so the hardware prefetcher follows them. A Morton order keeps most partners closer but
    /// sends a fraction across its coarse blocks, up to N/2 ahead, and each of those loads misses
    /// the cache: on the 97 556-particle packing it measured 20-25 % slower per particle-step.
    fn sort_spatially(&mut self, domain: &Domain) {
        let n = self.p.len();
        if n < 2 {
            return;
        }
        let bin = 0.5 * (self.cut_build + self.skin);
        let len = domain.hi - domain.lo;
        // Bins per axis; coarser bins only for absurdly large boxes (the key must fit 64 bits).
        let bins = |a: usize| ((len[a] / bin).ceil().clamp(1.0, (1u64 << 21) as f64)) as u64;
        let nb = [bins(0), bins(1), bins(2)];
        let mut keys: Vec<(u64, u32)> = (0..n)
            .map(|i| {
                let x = self.p.x[i];
                let b = |a: usize| {
                    let s = ((x[a] - domain.lo[a]) / len[a]).clamp(0.0, 1.0);
                    ((s * nb[a] as f64) as u64).min(nb[a] - 1)
                };
                ((b(2) * nb[1] + b(1)) * nb[0] + b(0), i as u32)
            })
            .collect();
        keys.sort_unstable();
        if keys.iter().enumerate().all(|(k, &(_, o))| k == o as usize) {
            return;
        }
        let old_of_new: Vec<u32> = keys.iter().map(|&(_, o)| o).collect();
        let mut new_of_old = vec![0u32; n];
        for (k, &o) in old_of_new.iter().enumerate() {
            new_of_old[o as usize] = k as u32;
        }
        self.p.permute(&old_of_new);
        for (k, pr) in self.pairs.iter_mut().enumerate() {
            let (a, b) = (new_of_old[pr.i as usize], new_of_old[pr.j as usize]);
            if a < b {
                (pr.i, pr.j) = (a, b);
            } else {
                // The same contact seen from the other particle: the history is i's tangential
                // displacement relative to j, so it changes sign; the radii trade places.
                (pr.i, pr.j) = (b, a);
                pr.shear = -pr.shear;
                if let Some(h) = self.pair_hist.get_mut(k) {
                    std::mem::swap(&mut h.ri_prev, &mut h.rj_prev);
                }
            }
        }
        if self.pair_hist.len() == self.pairs.len() {
            // One permutation for both lists.
            let mut order: Vec<u32> = (0..self.pairs.len() as u32).collect();
            order.sort_unstable_by_key(|&k| (self.pairs[k as usize].i, self.pairs[k as usize].j));
            self.pairs = order.iter().map(|&k| self.pairs[k as usize]).collect();
            self.pair_hist = order.iter().map(|&k| self.pair_hist[k as usize]).collect();
        } else {
            self.pair_hist.clear();
            self.pairs.sort_unstable_by_key(|pr| (pr.i, pr.j));
        }
        for c in &mut self.wc {
            c.p = new_of_old[c.p as usize];
        }
        self.wc.sort_unstable_by_key(|c| c.key());
        if let Some(cache) = self.mc_cache.as_mut() {
            cache.reorder(&old_of_new);
        }
        self.slots_stale = true;
        self.sorts += 1;
    }

    /// Centre distance, as a multiple of r_i + r_j, out to which a pair can matter: touching
    /// (Hertz), or receiving multi-contact radius changes (within RECEIVER_GAP; a pair further
    /// apart gets none and cannot touch). The neighbour list needs no more, whatever `mc_range`
    /// asks for: wider lists only cost memory traffic.
    fn pair_reach(&self) -> f64 {
        match self.closure {
            Some(Closure::MultiContact) => self.mc_range.min(1.0 + RECEIVER_GAP),
            _ => 1.0,
        }
    }

    /// Finds the wall elements each particle is close to and carries their history over.
    fn update_wall_contacts(&mut self) {
        // A particle moves at most half a skin from where it was at the last neighbour build
        // (`neighbor_check`), so two particle positions between builds are at most a skin apart;
        // candidates found within reach + 1.5 skin stay a superset of the contacts while the
        // meshes move less than half a skin more. The exact test below then finds the same
        // contacts, in the same order, as a scan of every particle against every wall element.
        let margin = 1.5 * self.skin;
        if self.wall_cand_builds != Some(self.builds) || self.wall_travel > 0.5 * self.skin {
            self.build_wall_candidates(margin);
        }
        std::mem::swap(&mut self.wc, &mut self.wc_old);
        // Taken out for the search (no allocation: the vectors move back with their capacity).
        let (mut wc, mut scratch) = (std::mem::take(&mut self.wc), std::mem::take(&mut self.wc_scratch));
        wall_contacts::collect(
            &wall_contacts::Scene::of(self),
            &self.wall_cand,
            &self.wc_old,
            &mut wc,
            &mut scratch,
        );
        (self.wc, self.wc_scratch) = (wc, scratch);
        if self.wc.len() != self.wc_old.len()
            || self.wc.iter().zip(&self.wc_old).any(|(a, b)| a.key() != b.key())
        {
            self.slots_stale = true;
        }
    }

    /// Every particle against every wall element, in particle, wall, mesh, triangle order:
    /// the elements within reach + `margin` (by their distance whatever the element's active
    /// edges, so that the list holds every contact the exact test can find).
    fn build_wall_candidates(&mut self, margin: f64) {
        self.wall_cand.clear();
        self.wall_cand_builds = Some(self.builds);
        self.wall_travel = 0.0;
        let p = &self.p;
        for i in 0..p.len() {
            let x = p.x[i];
            let reach = p.radius[i] * self.mc_range + margin;
            for (w, wall) in self.walls.iter().enumerate() {
                let cand = |mesh: usize, tri: usize| WallCandidate {
                    p: i as u32,
                    wall: w as u32,
                    mesh: mesh as u32,
                    tri: tri as u32,
                };
                match &wall.geom {
                    WallGeom::Plane(pl) => {
                        if (x[pl.axis] - pl.pos).abs() < reach {
                            self.wall_cand.push(cand(0, 0));
                        }
                    }
                    WallGeom::Meshes(list) => {
                        for &mi in list {
                            let m = &self.meshes[mi];
                            if m.far(&x, reach) {
                                continue;
                            }
                            for (t, tri) in m.tris.iter().enumerate() {
                                if mesh::distance_squared(tri, &x) < reach * reach {
                                    self.wall_cand.push(cand(mi, t));
                                }
                            }
                        }
                    }
                }
            }
        }
    }

    /// Per particle, the list of its multi-contact slots (pairs in pair order, then wall
    /// contacts), as compressed rows. Rebuilt only when the pairs or wall contacts changed.
    fn build_slots(&mut self) {
        let n = self.p.len();
        self.slot_start.clear();
        self.slot_start.resize(n + 1, 0);
        for (pr, _) in self.pairs.iter().zip(&self.pair_mc).filter(|(_, m)| **m) {
            self.slot_start[pr.i as usize + 1] += 1;
            self.slot_start[pr.j as usize + 1] += 1;
        }
        for c in &self.wc {
            self.slot_start[c.p as usize + 1] += 1;
        }
        for i in 0..n {
            self.slot_start[i + 1] += self.slot_start[i];
        }
        let total = self.slot_start[n] as usize;
        self.slots.clear();
        self.slots.resize(total, Slot::Wall(0));
        self.slot_fill.clear();
        self.slot_fill.extend_from_slice(&self.slot_start[..n]);
        for (k, pr) in self.pairs.iter().enumerate() {
            if !self.pair_mc[k] {
                continue;
            }
            let (i, j) = (pr.i as usize, pr.j as usize);
            self.slots[self.slot_fill[i] as usize] = Slot::PairI(k as u32);
            self.slot_fill[i] += 1;
            self.slots[self.slot_fill[j] as usize] = Slot::PairJ(k as u32);
            self.slot_fill[j] += 1;
        }
        for (k, c) in self.wc.iter().enumerate() {
            let i = c.p as usize;
            self.slots[self.slot_fill[i] as usize] = Slot::Wall(k as u32);
            self.slot_fill[i] += 1;
        }
        self.slots_stale = false;
    }

    /// Multi-contact pass (LIGGGHTS `fix multicontact/halfspace` pre_force): radius change of
    /// every particle at every one of its contacts from the previous step's normal forces.
    fn multicontact(&mut self) -> Result<(), StepError> {
        // Between updates under `mc_every` the radius changes of the last pass stand: pairs keep
        // theirs by index (valid until the next neighbour build) and wall contacts by key
        // (`wall_contacts::collect`).
        if self.mc_every > 1
            && self.step < self.mc_due
            && self.builds == self.mc_builds
            && self.pair_dr.len() == self.pairs.len()
        {
            return Ok(());
        }
        self.mc_due = self.step.saturating_add(self.mc_every.max(1));
        self.mc_builds = self.builds;
        self.mc_updates += 1;
        let n = self.p.len();
        let domain = self.domain.expect("domain checked in setup");
        for c in &mut self.wc {
            c.dr = 0.0;
        }
        if self.pair_mc.len() != self.pairs.len() {
            self.pair_mc.clear();
            self.pair_mc.resize(self.pairs.len(), false);
            self.slots_stale = true;
        }
        if self.pair_hist.len() != self.pairs.len() {
            // The closure started since the last neighbour build: every pair is new to it.
            self.pair_hist.clear();
            self.pair_hist.resize(self.pairs.len(), PairHist::NEW);
        }
        self.pair_loads.resize(self.pairs.len(), PairLoad::default());
        // Pairs outside the multi-contact set get no slot, hence no change.
        self.pair_dr.clear();
        self.pair_dr.resize(self.pairs.len(), [0.0; 2]);
        let (p, types) = (&self.p, &self.mc_types);
        // The kernel's loaded threshold of particle a (LIGGGHTS switches the point on the same).
        let eps = |a: usize| loaded_threshold(types[p.typ[a]].material.youngs_modulus, p.radius[a]);
        // One pass over the pairs (at large N they no longer fit in cache): reset the radius
        // changes, decide who takes part, and give the kernel each taking part pair's contact
        // points and previous force in a compact array, so its gather does not touch the pairs.
        // A pair takes part if loaded, or close enough that radius growth could make it touch
        // (gap below RECEIVER_GAP of the radii at the last evaluation; a pair moves far less than
        // that in a step): far candidates would only cost kernel time. Contact points once per
        // pair, both sides from one centre distance; as LIGGGHTS: the midpoint of the modified
        // spheres' surfaces along the centre line when loaded, else each particle's own surface
        // point.
        let mut stale = false;
        let taking_part = self.pair_mc.iter_mut().zip(self.pair_loads.iter_mut());
        for ((pr, h), (m, load)) in self.pairs.iter().zip(&self.pair_hist).zip(taking_part) {
            let now = h.fn_prev > 0.0 || h.near;
            if *m != now {
                *m = now;
                stale = true;
            }
            if !now {
                continue;
            }
            let (a, b) = (pr.i as usize, pr.j as usize);
            let mut xab = p.x[b] - p.x[a];
            domain.minimum_image(&mut xab);
            let len = xab.norm().max(1e-300);
            load.points = if h.fn_prev > eps(a) {
                let tmp = xab * ((h.ri_prev - h.rj_prev) * 0.5 / len);
                [tmp + 0.5 * xab, tmp - 0.5 * xab]
            } else {
                [xab * (h.ri_prev / len), -xab * (h.rj_prev / len)]
            };
            load.force = h.fn_prev;
        }
        if stale || self.slots_stale {
            self.build_slots();
        }
        // The kernel particle by particle into one Δ per slot (threads on disjoint particle
        // ranges when they pay), then Δ to the pairs and wall contacts.
        self.slot_dr.resize(self.slots.len(), 0.0);
        let threaded = n >= 2 * MC_GRAIN && self.threads().is_some();
        let ctx = McCtx {
            p: &self.p,
            mc_types: &self.mc_types,
            slot_start: &self.slot_start,
            slots: &self.slots,
            pair_loads: &self.pair_loads,
            wc: &self.wc,
            step: self.step,
        };
        let (tolerance, kept) = match self.mc_cache.as_mut() {
            Some(c) => {
                let (t, k) = c.slots_mut(n);
                (t, Some(k))
            }
            None => (0.0, None),
        };
        let counts = match self.team.as_ref().filter(|_| threaded) {
            Some(team) => ctx.kernel_on(team, &mut self.slot_dr, kept, tolerance)?,
            None => ctx.kernel(0, n, &mut self.slot_dr, kept, tolerance)?,
        };
        self.mc_kernel_contacts += counts.contacts;
        self.mc_kernel_fallbacks += counts.fallbacks;
        if let Some(c) = self.mc_cache.as_mut() {
            c.recomputed += counts.recomputed;
        }
        for (s, &d) in self.slots.iter().zip(&self.slot_dr) {
            match *s {
                Slot::PairI(k) => self.pair_dr[k as usize][0] = d,
                Slot::PairJ(k) => self.pair_dr[k as usize][1] = d,
                Slot::Wall(k) => self.wc[k as usize].dr = d,
            }
        }
        Ok(())
    }

    /// Force and torque on every particle and force on every mesh. `update` = false is the
    /// set-up pass of a run: the contact history is not advanced (LIGGGHTS `shearupdate` off).
    fn compute_forces(&mut self, update: bool) -> Result<(), StepError> {
        let n = self.p.len();
        let domain = self.domain.expect("domain checked in setup");
        // Every pass below writes the per-particle sums from zero (the pair pass into spare
        // buffers, swapped in): no clearing here.
        // LIGGGHTS does not clear the mesh force before the set-up pass, so the first thermo line
        // of a run shows the previous step's force plus the set-up force; do the same so the
        // outputs match line by line (the dynamics never read this sum).
        if update {
            for m in &mut self.meshes {
                m.force = Vec3::zeros();
            }
        }
        self.update_wall_contacts();
        let mc = self.closure == Some(Closure::MultiContact);
        if mc {
            self.multicontact()?;
        }
        let dt = if update { self.dt } else { 0.0 };
        let nt = self.ntypes;
        // Threads, when the timing probe says they pay: one block of pairs each (more blocks
        // share more particles, whose sums are deferred), none below two blocks' worth of pairs.
        let threads = self.threads().map_or(1, Team::size);
        let blocks = threads.min(self.pairs.len() / MIN_BLOCK_PAIRS).min(MAX_PAIR_BLOCKS);
        let threaded = threads > 1 && blocks > 1;
        if threaded && self.owner_key != Some((self.pairs.len(), blocks, n)) {
            self.assign_owners(blocks);
        }
        if threaded
            && !self.owned_blocks_pay
            && (self.inc_start.len() != n + 1 || self.inc.len() != 2 * self.pairs.len())
        {
            // After every neighbour build, and when particles were added since.
            self.build_incidence();
        }
        // Pairs: in pair order, or in blocks on the threads that add in that same order
        // (`assign_owners`), so the sums are bit-identical whatever the number of threads.
        let ctx = PairCtx {
            p: &self.p,
            coeffs: &self.coeffs,
            nt,
            domain,
            dt,
            update,
            step: self.step,
            liggghts_radii: self.liggghts_radii,
        };
        // The vectorised batches evaluate `tangential history` with the radii of SPEC §2; the
        // LIGGGHTS `surface multicontact` radii and `no_history` take the pair-by-pair path.
        let batched = !self.liggghts_radii
            && self.coeffs.iter().all(|c| c.tangential == Tangential::History)
            && PairLanes::vectorised();
        let np = self.pairs.len();
        if !mc {
            // Hertz keeps no closure state: a closure that starts later finds every pair new.
            self.pair_hist.clear();
        }
        // Every entry is overwritten below: only the length has to match (no per-step fill).
        if self.pair_force.len() != np {
            self.pair_force.resize(np, Vec3::zeros());
        }
        if threaded && self.owned_blocks_pay {
            self.threaded_passes.0 += 1;
            let team = self.team.as_ref().expect("threads() started the team");
            let (f, torque) = (&mut self.f_buf, &mut self.t_buf);
            f.resize(n, Vec3::zeros());
            torque.resize(n, Vec3::zeros());
            {
                // Cleared by the members, each its own particles: the lines then sit in the
                // cache of the core that adds into most of them next.
                let (fs, ts) = (SplitMut::new(f), SplitMut::new(torque));
                team.for_shares(n, |_, r| {
                    // SAFETY: the members' shares are disjoint ranges of particles.
                    unsafe { (fs.range(r.clone()).fill(Vec3::zeros()), ts.range(r).fill(Vec3::zeros())) };
                });
            }
            let sums = SharedSums { f: f.as_mut_ptr(), torque: torque.as_mut_ptr(), n };
            // Every list emptied first: a block without pairs (fewer runs than blocks) adds none.
            self.deferred.iter_mut().for_each(Vec::clear);
            // Member b takes block b: its pairs, radius changes, recorded forces and deferrals,
            // and times itself for `balance_blocks`.
            let (owner, cuts) = (&self.owner, &self.pair_cuts);
            let (pairs, forces) = (SplitMut::new(&mut self.pairs), SplitMut::new(&mut self.pair_force));
            let deferred = SplitMut::new(&mut self.deferred[..blocks]);
            let block_ns = SplitMut::new(&mut self.block_ns[..blocks]);
            let (drs, hists) = (&self.pair_dr, SplitMut::new(&mut self.pair_hist));
            team.run(|b| {
                if b >= blocks {
                    return Ok(());
                }
                let t0 = std::time::Instant::now();
                let r = cuts[b]..cuts[b + 1];
                // SAFETY: the cuts do not decrease, so each member has its own range of pairs,
                // and its own block.
                let (prs, force, deferred, ns) = unsafe {
                    let d = &mut deferred.range(b..b + 1)[0];
                    (pairs.range(r.clone()), forces.range(r.clone()), d, &mut block_ns.range(b..b + 1)[0])
                };
                // SAFETY: as the pairs.
                let closure = mc.then(|| (&drs[r.clone()], unsafe { hists.range(r) }));
                let mut sink = OwnedSums { sums, owner, block: b as u16, deferred, force };
                let res = ctx.pass(prs, closure, batched, &mut sink);
                *ns += t0.elapsed().as_nanos() as u64;
                res
            })
            .map_err(|e| *e)?;
            // Later blocks' contributions to shared particles, in block then pair order: the
            // serial pass's order.
            for d in self.deferred.iter().flatten() {
                self.f_buf[d.p as usize] += d.f;
                self.t_buf[d.p as usize] += d.torque;
            }
            std::mem::swap(&mut self.p.f, &mut self.f_buf);
            std::mem::swap(&mut self.p.torque, &mut self.t_buf);
            // After the deferred ends are added: a new assignment clears their lists.
            self.block_passes += 1;
            if self.block_passes >= BALANCE_PASSES {
                self.balance_blocks();
            }
        } else if threaded {
            self.threaded_passes.1 += 1;
            if self.pair_out.len() != np {
                self.pair_out.resize(np, PairOut::default());
            }
            let team = self.team.as_ref().expect("threads() started the team");
            {
                let (pairs, outs) = (SplitMut::new(&mut self.pairs), SplitMut::new(&mut self.pair_out));
                let forces = SplitMut::new(&mut self.pair_force);
                let (drs, hists) = (&self.pair_dr, SplitMut::new(&mut self.pair_hist));
                team.run_shares(np, |_, r| {
                    // SAFETY: the members' shares are disjoint ranges of pairs.
                    let (prs, outs, force, closure) = unsafe {
                        let closure = mc.then(|| (&drs[r.clone()], hists.range(r.clone())));
                        (pairs.range(r.clone()), outs.range(r.clone()), forces.range(r), closure)
                    };
                    ctx.pass(prs, closure, batched, &mut Keep { outs, force })
                })
                .map_err(|e| *e)?;
            }
            // Each particle sums its own pairs' results in pair order, as the serial pass adds
            // them (from zero: the sums were cleared above): no write is shared between threads.
            let (start, inc, outs) = (&self.inc_start, &self.inc, &self.pair_out);
            let (fs, ts) = (SplitMut::new(&mut self.p.f), SplitMut::new(&mut self.p.torque));
            team.for_shares(n, |_, r| {
                // SAFETY: the members' shares are disjoint ranges of particles.
                let (fs, ts) = unsafe { (fs.range(r.clone()), ts.range(r.clone())) };
                for (i, (f, t)) in r.zip(fs.iter_mut().zip(ts.iter_mut())) {
                    let (mut fa, mut ta) = (Vec3::zeros(), Vec3::zeros());
                    for &e in &inc[start[i] as usize..start[i + 1] as usize] {
                        let out = &outs[(e >> 1) as usize];
                        if out.touching {
                            if e & 1 == 0 {
                                fa += out.force;
                                ta += out.torque_i;
                            } else {
                                fa -= out.force;
                                ta += out.torque_j;
                            }
                        }
                    }
                    (*f, *t) = (fa, ta);
                }
            });
        } else {
            // The threaded passes add in this order too: identical sums.
            let (f, torque) = (&mut self.f_buf, &mut self.t_buf);
            f.clear();
            f.resize(n, Vec3::zeros());
            torque.clear();
            torque.resize(n, Vec3::zeros());
            let mut sums = SumInto { f, torque, force: &mut self.pair_force };
            let closure = mc.then_some((&self.pair_dr[..], &mut self.pair_hist[..]));
            ctx.pass(&mut self.pairs, closure, batched, &mut sums).map_err(|e| *e)?;
            std::mem::swap(&mut self.p.f, &mut self.f_buf);
            std::mem::swap(&mut self.p.torque, &mut self.t_buf);
        }
        // Body forces come next, then the walls (the order of the example decks' fixes); with
        // threads, each member adds both to its own particles (below).
        let walls_threaded = threads > 1 && self.wc.len() >= MIN_THREADED_WALL_CONTACTS;
        if let Some(g) = self.gravity.filter(|_| !walls_threaded) {
            for i in 0..n {
                self.p.f[i] += self.p.mass[i] * g;
            }
        }
        // Walls, in wall-contact order, which is particle order. With threads the list splits at
        // a particle boundary and each half adds into its own particles' sums: every particle
        // gets its terms in the serial order. A mesh's total force is summed afterwards, in
        // contact order, from each contact's force.
        let ctx = WallCtx {
            walls: &self.walls,
            meshes: &self.meshes,
            coeffs: &self.coeffs,
            nt,
            typ: &self.p.typ,
            x: &self.p.x,
            v: &self.p.v,
            omega: &self.p.omega,
            radius: &self.p.radius,
            mass: &self.p.mass,
            id: &self.p.id,
            dt,
            update,
            step: self.step,
            batched,
        };
        if self.wall_force.len() != self.wc.len() {
            self.wall_force.resize(self.wc.len(), Vec3::zeros());
        }
        if walls_threaded {
            // Member k's contacts start at its equal share's start moved back to the first
            // contact of that particle, its particles at that contact's (0 for the first member,
            // n after the last): non-decreasing in k, since the contacts are in particle order.
            let (wc, cuts) = (&self.wc, &mut self.wall_cuts);
            cuts.clear();
            cuts.extend((0..threads).map(|k| {
                let mut c = share(wc.len(), threads, k).start;
                while c > 0 && c < wc.len() && wc[c - 1].p == wc[c].p {
                    c -= 1;
                }
                [c, if k == 0 { 0 } else { wc.get(c).map_or(n, |w| w.p as usize) }]
            }));
            cuts.push([wc.len(), n]);
        }
        match self.team.as_ref().filter(|_| walls_threaded) {
            Some(team) => {
                let (cuts, gravity, mass) = (&self.wall_cuts, self.gravity, &self.p.mass);
                let (cs, wf) = (SplitMut::new(&mut self.wc), SplitMut::new(&mut self.wall_force));
                let (fs, ts) = (SplitMut::new(&mut self.p.f), SplitMut::new(&mut self.p.torque));
                team.run(|k| {
                    let ([c0, p0], [c1, p1]) = (cuts[k], cuts[k + 1]);
                    // SAFETY: the cuts do not decrease with k, so the members' ranges of
                    // contacts and of particles are disjoint.
                    let (c, w, f, t) =
                        unsafe { (cs.range(c0..c1), wf.range(c0..c1), fs.range(p0..p1), ts.range(p0..p1)) };
                    if let Some(g) = gravity {
                        for (fi, m) in f.iter_mut().zip(&mass[p0..p1]) {
                            *fi += *m * g;
                        }
                    }
                    ctx.forces(c, w, f, t, p0)
                })?;
            }
            None => ctx.forces(&mut self.wc, &mut self.wall_force, &mut self.p.f, &mut self.p.torque, 0)?,
        }
        for (c, wf) in self.wc.iter().zip(&self.wall_force) {
            if let WallGeom::Meshes(_) = self.walls[c.wall as usize].geom {
                self.meshes[c.mesh as usize].force -= *wf;
            }
        }
        Ok(())
    }

    /// Force the particles exerted on each triangle of mesh `mesh` in the last force pass (the
    /// per-face share of `Mesh::force`, for `dump mesh/vtk`'s stresses).
    pub fn mesh_face_forces(&self, mesh: usize) -> Vec<Vec3> {
        let mut f = vec![Vec3::zeros(); self.meshes[mesh].tris.len()];
        for (c, wf) in self.wc.iter().zip(&self.wall_force) {
            if c.mesh as usize == mesh && matches!(self.walls[c.wall as usize].geom, WallGeom::Meshes(_)) {
                f[c.tri as usize] -= *wf;
            }
        }
        f
    }

    /// Kernel calls that (re)computed an influence matrix under the geometry tolerance.
    pub fn mc_influence_updates(&self) -> u64 {
        self.mc_cache.as_ref().map_or(0, |c| c.recomputed)
    }

    /// Translational kinetic energy ½ Σ m v² [J] (thermo `ke`).
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.p.v.iter().zip(&self.p.mass).map(|(v, m)| v.norm_squared() * m).sum::<f64>()
    }

    /// Rotational kinetic energy ½ Σ I ω² [J] (`compute erotate/sphere`).
    pub fn rotational_energy(&self) -> f64 {
        0.5 * INERTIA
            * (0..self.p.len())
                .map(|i| {
                    self.p.omega[i].norm_squared() * self.p.radius[i] * self.p.radius[i] * self.p.mass[i]
                })
                .sum::<f64>()
    }

    /// Elastic energy stored in the contacts, Σ (2/5) k_n δ² (Hertz potential, undamped part).
    /// Used by the energy-conservation checks; exact for Hertz without multi-contact.
    pub fn elastic_energy(&self) -> f64 {
        let domain = match self.domain {
            Some(d) => d,
            None => return 0.0,
        };
        let mut e = 0.0;
        let nt = self.ntypes;
        for pr in &self.pairs {
            let (i, j) = (pr.i as usize, pr.j as usize);
            let mut d = self.p.x[i] - self.p.x[j];
            domain.minimum_image(&mut d);
            let (ri, rj) = (self.p.radius[i], self.p.radius[j]);
            let delta = ri + rj - d.norm();
            if delta > 0.0 {
                let c = &self.coeffs[self.p.typ[i] * nt + self.p.typ[j]];
                let reff = ri * rj / (ri + rj);
                e += 0.4 * crate::physics::hertz::hertz_force(c.e_star, reff, delta) * delta;
            }
        }
        for c in &self.wc {
            let i = c.p as usize;
            let delta = self.p.radius[i] - (self.p.x[i] - c.point).norm();
            if delta > 0.0 {
                let wt = match &self.walls[c.wall as usize].geom {
                    WallGeom::Plane(pl) => pl.wall_type,
                    WallGeom::Meshes(_) => self.meshes[c.mesh as usize].wall_type,
                };
                let co = &self.coeffs[self.p.typ[i] * nt + wt];
                e += 0.4 * crate::physics::hertz::hertz_force(co.e_star, self.p.radius[i], delta) * delta;
            }
        }
        e
    }

    /// Number of touching contacts: particle pairs and particle–wall.
    /// Eq. 4 stress tensor (compression positive), row-major, as (contact, kinetic) parts:
    /// contact Σ_pairs r_ij ⊗ F_ij / V (= Σ_i Σ_j ½ r_ij F_ij / V), kinetic Σ m v'⊗v' / V with v'
    /// the velocity about the Lees–Edwards streaming profile u_x = γ̇ (y − y_mid).
    pub fn stress_parts(&self) -> ([[f64; 3]; 3], [[f64; 3]; 3]) {
        let mut sc = [[0.0; 3]; 3];
        let mut sk = [[0.0; 3]; 3];
        let Some(domain) = self.domain else { return (sc, sk) };
        let vol = domain.volume();
        for (pr, force) in self.pairs.iter().zip(&self.pair_force) {
            if *force == Vec3::zeros() {
                continue;
            }
            let mut d = self.p.x[pr.i as usize] - self.p.x[pr.j as usize];
            domain.minimum_image(&mut d);
            add_outer(&mut sc, &d, &(force / vol));
        }
        for i in 0..self.p.len() {
            let mut v = self.p.v[i];
            v.x -= domain.streaming_vx(self.p.x[i].y);
            add_outer(&mut sk, &v, &(v * (self.p.mass[i] / vol)));
        }
        (sc, sk)
    }

    /// Every touching particle–particle contact with what `compute pair/gran/local` reports.
    /// Re-evaluates every pair at the current positions and velocities without advancing contact
    /// histories or touching particle forces: per-contact output at the end of a step sees the
    /// full-step velocities, as LIGGGHTS's `compute pair/gran/local` (which calls the pair style
    /// again with history updates off) does.
    pub fn touching_pairs(&mut self) -> Result<Vec<PairContact>, StepError> {
        let Some(domain) = self.domain else { return Ok(Vec::new()) };
        let ctx = PairCtx {
            p: &self.p,
            coeffs: &self.coeffs,
            nt: self.ntypes,
            domain,
            dt: 0.0,
            update: false,
            step: self.step,
            liggghts_radii: self.liggghts_radii,
        };
        let np = self.pairs.len();
        let mc = self.closure == Some(Closure::MultiContact)
            && self.pair_hist.len() == np
            && self.pair_dr.len() == np;
        let closure = mc.then_some((&self.pair_dr[..], &mut self.pair_hist[..]));
        let mut touching = Touching { x: &self.p.x, domain, out: Vec::new() };
        ctx.pass(&mut self.pairs, closure, false, &mut touching).map_err(|e| *e)?;
        Ok(touching.out)
    }

    /// Particle–particle contacts carrying a force at the last force pass (set-up pass included).
    pub fn pair_contacts(&self) -> usize {
        self.pair_force.iter().filter(|f| **f != Vec3::zeros()).count()
    }

    /// Contacts carrying a normal force at the last force pass: (particle pairs, particle–wall).
    /// Under Hertz, which keeps no normal force per pair, the pairs carrying a force.
    pub fn contact_counts(&self) -> (usize, usize) {
        let pp = if self.pair_hist.len() == self.pairs.len() {
            self.pair_hist.iter().filter(|h| h.fn_prev > 0.0).count()
        } else {
            self.pair_contacts()
        };
        let pw = self.wc.iter().filter(|c| c.fn_prev > 0.0).count();
        (pp, pw)
    }

    /// Registers a per-type material table and the pair restitution/friction matrices.
    pub fn set_materials(
        &mut self,
        materials: Vec<Material>,
        restitution: &[f64],
        friction: &[f64],
        tangential: Tangential,
    ) -> Result<(), String> {
        let nt = materials.len();
        if restitution.len() != nt * nt || friction.len() != nt * nt {
            return Err(format!("peratomtypepair tables must have {nt}×{nt} entries"));
        }
        let mut coeffs = Vec::with_capacity(nt * nt);
        for a in 0..nt {
            for b in 0..nt {
                coeffs.push(
                    PairCoeffs::new(
                        &materials[a],
                        &materials[b],
                        restitution[a * nt + b],
                        friction[a * nt + b],
                    )
                    .map(|c| PairCoeffs { tangential, ..c })
                    .map_err(|e| format!("types {} and {}: {e}", a + 1, b + 1))?,
                );
            }
        }
        self.ntypes = nt;
        self.materials = materials;
        self.coeffs = coeffs;
        Ok(())
    }
}

/// Relative gap (fraction of r_i + r_j) within which an unloaded pair still receives a
/// multi-contact radius change: growth beyond 10 % of both radii together is outside the
/// model's range (Eq. 3 caps each neighbour term at MPR r, about 0.1 r).
const RECEIVER_GAP: f64 = 0.1;

/// Steps after which the first serial-vs-threads probe has decided (benchmarks warm up this long).
pub const THREAD_PROBE_STEPS: u64 = 2 * probe::WINDOW;

/// Fewest pairs in a block of the threaded pair pass, and most blocks (block indices are kept
/// in a `u16` per particle).
const MIN_BLOCK_PAIRS: usize = 512;
const MAX_PAIR_BLOCKS: usize = 64;

/// Owning threaded pair passes between two rebalancings of their blocks ([`World::balance_blocks`]).
const BALANCE_PASSES: u32 = 200;

/// Fewest wall contacts worth a threaded wall pass.
const MIN_THREADED_WALL_CONTACTS: usize = 64;

/// Read-only view of the state that one pair evaluation needs (shared between threads).
struct PairCtx<'a> {
    p: &'a Particles,
    coeffs: &'a [PairCoeffs],
    nt: usize,
    domain: Domain,
    dt: f64,
    update: bool,
    step: u64,
    liggghts_radii: bool,
}

/// One pair's contribution: force on i, torques on i and j, when touching. Written in place by
/// [`PairCtx::eval`] (a returned tuple travels through memory on every pair, and reading it back
/// stalled the serial loop).
#[derive(Debug, Clone, Copy, Default)]
struct PairOut {
    touching: bool,
    force: Vec3,
    torque_i: Vec3,
    torque_j: Vec3,
}

impl PairCtx<'_> {
    /// Force on i and torques on i and j of one pair into `out` (`touching` false when apart);
    /// updates the pair's history when `update`.
    #[inline]
    fn eval(
        &self,
        pr: &mut Pair,
        k: usize,
        state: &mut impl PairState,
        out: &mut PairOut,
    ) -> Result<(), Box<StepError>> {
        let dr = state.dr(k);
        let Some((d, kimg)) = self.approach(pr, k, dr, state) else {
            *out = PairOut::default();
            return Ok(());
        };
        let p = self.p;
        let (i, j) = (pr.i as usize, pr.j as usize);
        let (ri, rj) = (p.radius[i] + dr[0], p.radius[j] + dr[1]);
        let bi = Body { x: p.x[i], v: p.v[i], omega: p.omega[i], radius: p.radius[i], mass: p.mass[i] };
        // The image of j across a sheared boundary carries the Lees–Edwards velocity jump.
        let mut vj = p.v[j];
        vj.x += kimg * self.domain.le_vjump;
        let mut bj = Body { x: p.x[i] - d, v: vj, omega: p.omega[j], radius: p.radius[j], mass: p.mass[j] };
        let mut dri = dr[0];
        let mut ri_stored = ri;
        if self.liggghts_radii && dr[0] != 0.0 {
            // LIGGGHTS 3.8 `surface multicontact` keeps particle i's original radius in R_eff and
            // in its lever arm (only the overlap sees r_i + Δ). Same effect through the physics
            // core: original r_i, and j moved Δ_i closer along the normal.
            let r = d.norm();
            if r > dr[0] {
                bj.x = p.x[i] - d * ((r - dr[0]) / r);
                dri = 0.0;
                ri_stored = p.radius[i];
            }
        }
        let c = &self.coeffs[p.typ[i] * self.nt + p.typ[j]];
        let mut shear = pr.shear;
        let r = particle_particle(c, &bi, &bj, dri, dr[1], self.dt, &mut shear)
            .map_err(|e| Box::new(contact_error(self.step, p.id[i], Some(p.id[j]), e)))?;
        let fnorm = match r {
            Some(cf) => {
                *out = PairOut {
                    touching: true,
                    force: cf.force_i,
                    torque_i: cf.torque_i,
                    torque_j: cf.torque_j,
                };
                cf.force_i.dot(&cf.en).abs()
            }
            None => {
                *out = PairOut::default();
                0.0
            }
        };
        if self.update {
            pr.shear = shear;
            state.keep(k, fnorm, ri_stored, rj);
        }
        Ok(())
    }

    /// What both pair passes do first: the centre difference d = x_i − x_j (minimum image) and
    /// the image count across a sheared boundary, and the `near` flag. A pair whose modified
    /// spheres are apart gets its history reset, and `None`.
    #[inline(always)]
    fn approach(
        &self,
        pr: &mut Pair,
        k: usize,
        dr: PairDr,
        state: &mut impl PairState,
    ) -> Option<(Vec3, f64)> {
        let p = self.p;
        let (i, j) = (pr.i as usize, pr.j as usize);
        let mut d = p.x[i] - p.x[j];
        let kimg = self.domain.minimum_image_k(&mut d);
        let (ri, rj) = (p.radius[i] + dr[0], p.radius[j] + dr[1]);
        let radsum = ri + rj;
        let d2 = d.norm_squared();
        let reach = (1.0 + RECEIVER_GAP) * (p.radius[i] + p.radius[j]);
        state.near(k, d2 < reach * reach);
        if d2 >= radsum * radsum {
            if self.update {
                pr.shear = Vec3::zeros();
                state.keep(k, 0.0, ri, rj);
            }
            return None;
        }
        Some((d, kimg))
    }
}

/// Where [`PairCtx::eval_batched`] puts each pair's result. A trait rather than a closure so the
/// call is inlined into the batch loop (a closure stayed an out-of-line call: 15 % of a Hertz step).
trait PairSink {
    fn put(&mut self, k: usize, i: usize, j: usize, o: &PairOut);
}

/// Serial pass: forces and torques straight into the per-particle sums; each pair's force
/// recorded for the outputs.
struct SumInto<'a> {
    f: &'a mut [Vec3],
    torque: &'a mut [Vec3],
    force: &'a mut [Vec3],
}

impl PairSink for SumInto<'_> {
    #[inline(always)]
    fn put(&mut self, k: usize, i: usize, j: usize, o: &PairOut) {
        self.force[k] = o.force;
        if o.touching {
            self.f[i] += o.force;
            self.f[j] -= o.force;
            self.torque[i] += o.torque_i;
            self.torque[j] += o.torque_j;
        }
    }
}

/// Threaded pass: each pair's result kept for the ordered sum afterwards, and its force recorded
/// for the outputs.
struct Keep<'a> {
    outs: &'a mut [PairOut],
    force: &'a mut [Vec3],
}

impl PairSink for Keep<'_> {
    #[inline(always)]
    fn put(&mut self, k: usize, _i: usize, _j: usize, o: &PairOut) {
        self.outs[k] = *o;
        self.force[k] = o.force;
    }
}

/// [`World::touching_pairs`]: every pair carrying a force, with its branch vector.
struct Touching<'a> {
    x: &'a [Vec3],
    domain: Domain,
    out: Vec<PairContact>,
}

impl PairSink for Touching<'_> {
    fn put(&mut self, _k: usize, i: usize, j: usize, o: &PairOut) {
        if o.force == Vec3::zeros() {
            return;
        }
        let raw = self.x[i] - self.x[j];
        let mut branch = raw;
        self.domain.minimum_image(&mut branch);
        self.out.push(PairContact {
            i,
            j,
            branch,
            periodic: branch != raw,
            force: o.force,
            torque: o.torque_i,
        });
    }
}

/// The per-particle sums of the threaded pass, written by several threads at once.
#[derive(Clone, Copy)]
struct SharedSums {
    f: *mut Vec3,
    torque: *mut Vec3,
    n: usize,
}

// SAFETY: the threads write disjoint entries: particle p only from the block that owns it
// (`World::assign_owners`), and the buffers outlive the parallel pass that uses them.
unsafe impl Send for SharedSums {}
unsafe impl Sync for SharedSums {}

/// A contribution to a particle that another block owns, added after the blocks finish.
#[derive(Debug, Clone, Copy)]
struct Deferred {
    p: u32,
    f: Vec3,
    torque: Vec3,
}

/// Threaded pass, one block of pairs: forces and torques straight into the sums of the particles
/// this block owns, deferred for the others; each pair's force recorded for the outputs.
struct OwnedSums<'a> {
    sums: SharedSums,
    owner: &'a [u16],
    block: u16,
    deferred: &'a mut Vec<Deferred>,
    force: &'a mut [Vec3],
}

impl OwnedSums<'_> {
    #[inline(always)]
    fn add(&mut self, p: usize, f: Vec3, torque: Vec3) {
        if self.owner[p] == self.block {
            assert!(p < self.sums.n);
            // SAFETY: in bounds (checked), and only this block writes particle p (its owner).
            unsafe {
                *self.sums.f.add(p) += f;
                *self.sums.torque.add(p) += torque;
            }
        } else {
            self.deferred.push(Deferred { p: p as u32, f, torque });
        }
    }
}

impl PairSink for OwnedSums<'_> {
    #[inline(always)]
    fn put(&mut self, k: usize, i: usize, j: usize, o: &PairOut) {
        self.force[k] = o.force;
        if o.touching {
            // −F added is F subtracted, bit for bit (IEEE a − b = a + (−b)): the serial sums.
            self.add(i, o.force, o.torque_i);
            self.add(j, -o.force, o.torque_j);
        }
    }
}

impl PairCtx<'_> {
    /// Evaluates `pairs` in order as [`PairCtx::eval`] does, overlapping pairs in vectorised
    /// batches of [`LANES`]; hands each pair's result to `sink.put(k, i, j, out)` (k: index in
    /// `pairs`). Touching pairs reach the sink in pair order; pairs apart may come earlier.
    fn eval_batched(
        &self,
        pairs: &mut [Pair],
        state: &mut impl PairState,
        sink: &mut impl PairSink,
    ) -> Result<(), Box<StepError>> {
        let p = self.p;
        let mut lanes = PairLanes::default();
        let mut slot = [0usize; LANES];
        let mut n = 0;
        for k in 0..pairs.len() {
            let (pr, dr) = (&mut pairs[k], state.dr(k));
            let (i, j) = (pr.i as usize, pr.j as usize);
            let Some((d, kimg)) = self.approach(pr, k, dr, state) else {
                sink.put(k, i, j, &PairOut::default());
                continue;
            };
            // The image of j across a sheared boundary carries the Lees–Edwards velocity jump.
            let mut vj = p.v[j];
            vj.x += kimg * self.domain.le_vjump;
            let c = &self.coeffs[p.typ[i] * self.nt + p.typ[j]];
            let l = n;
            for a in 0..3 {
                lanes.d[a][l] = d[a];
                lanes.vr[a][l] = p.v[i][a] - vj[a];
                lanes.omega_i[a][l] = p.omega[i][a];
                lanes.omega_j[a][l] = p.omega[j][a];
                lanes.shear[a][l] = pr.shear[a];
            }
            lanes.radius_i[l] = p.radius[i];
            lanes.radius_j[l] = p.radius[j];
            lanes.dri[l] = dr[0];
            lanes.drj[l] = dr[1];
            lanes.mass_i[l] = p.mass[i];
            lanes.mass_j[l] = p.mass[j];
            lanes.coeffs.set(l, c);
            slot[n] = k;
            n += 1;
            if n == LANES {
                self.flush(&mut lanes, &slot[..n], pairs, state, sink)?;
                n = 0;
            }
        }
        if n > 0 {
            lanes.pad_from_first(n);
            self.flush(&mut lanes, &slot[..n], pairs, state, sink)?;
        }
        Ok(())
    }

    /// Evaluates a filled batch and writes each used lane back to its pair and to the sink.
    fn flush(
        &self,
        lanes: &mut PairLanes,
        slot: &[usize],
        pairs: &mut [Pair],
        state: &mut impl PairState,
        sink: &mut impl PairSink,
    ) -> Result<(), Box<StepError>> {
        lanes.evaluate(self.dt);
        for (l, &k) in slot.iter().enumerate() {
            let pr = &mut pairs[k];
            if !lanes.ok[l] {
                // The pair-by-pair path names the cause (its history is still the step's input).
                let mut o = PairOut::default();
                self.eval(pr, k, state, &mut o)?;
                let (i, j) = (pr.i as usize, pr.j as usize);
                return Err(Box::new(contact_error(
                    self.step,
                    self.p.id[i],
                    Some(self.p.id[j]),
                    ContactError::NonFinite,
                )));
            }
            let lane = |a: &[[f64; LANES]; 3]| Vec3::new(a[0][l], a[1][l], a[2][l]);
            let o = PairOut {
                touching: true,
                force: lane(&lanes.force),
                torque_i: lane(&lanes.torque_i),
                torque_j: lane(&lanes.torque_j),
            };
            if self.update {
                pr.shear = lane(&lanes.shear);
                let (ri, rj) = (lanes.radius_i[l] + lanes.dri[l], lanes.radius_j[l] + lanes.drj[l]);
                state.keep(k, lanes.fnorm[l], ri, rj);
            }
            sink.put(k, pr.i as usize, pr.j as usize, &o);
        }
        Ok(())
    }
}

impl PairCtx<'_> {
    /// Evaluates `pairs` in order into `sink` (vectorised batches when `batched`), with their
    /// radius changes and closure state when the multi-contact closure is on (`closure`, one
    /// entry per pair each).
    fn pass(
        &self,
        pairs: &mut [Pair],
        closure: Option<(&[PairDr], &mut [PairHist])>,
        batched: bool,
        sink: &mut impl PairSink,
    ) -> Result<(), Box<StepError>> {
        match closure {
            None => self.pass_with(pairs, &mut NoClosure, batched, sink),
            Some((dr, hist)) => {
                let n = pairs.len();
                let mut state = ClosureState { dr: &dr[..n], hist: &mut hist[..n] };
                self.pass_with(pairs, &mut state, batched, sink)
            }
        }
    }

    fn pass_with(
        &self,
        pairs: &mut [Pair],
        state: &mut impl PairState,
        batched: bool,
        sink: &mut impl PairSink,
    ) -> Result<(), Box<StepError>> {
        if batched {
            return self.eval_batched(pairs, state, sink);
        }
        let mut o = PairOut::default();
        for (k, pr) in pairs.iter_mut().enumerate() {
            self.eval(pr, k, state, &mut o)?;
            sink.put(k, pr.i as usize, pr.j as usize, &o);
        }
        Ok(())
    }
}

/// What a pair pass reads and keeps of the multi-contact closure, pair k of the pass: a trait so
/// that each pass is compiled for one case, and a Hertz pass neither loads radius changes that
/// are all zero nor stores a state nobody reads (at large N both would stream from memory).
trait PairState {
    /// This step's radius changes of pair k.
    fn dr(&self, k: usize) -> PairDr;
    /// Whether pair k is near enough to receive multi-contact terms.
    fn near(&mut self, k: usize, near: bool);
    /// What the next multi-contact pass reads of pair k: |F·n| and the modified radii.
    fn keep(&mut self, k: usize, fnorm: f64, ri: f64, rj: f64);
}

/// Hertz: no radius changes, nothing kept.
struct NoClosure;

impl PairState for NoClosure {
    #[inline(always)]
    fn dr(&self, _: usize) -> PairDr {
        [0.0; 2]
    }
    #[inline(always)]
    fn near(&mut self, _: usize, _: bool) {}
    #[inline(always)]
    fn keep(&mut self, _: usize, _: f64, _: f64, _: f64) {}
}

/// The multi-contact closure: this step's radius changes in, the pairs' state out.
struct ClosureState<'a> {
    dr: &'a [PairDr],
    hist: &'a mut [PairHist],
}

impl PairState for ClosureState<'_> {
    #[inline(always)]
    fn dr(&self, k: usize) -> PairDr {
        self.dr[k]
    }
    #[inline(always)]
    fn near(&mut self, k: usize, near: bool) {
        self.hist[k].near = near;
    }
    #[inline(always)]
    fn keep(&mut self, k: usize, fnorm: f64, ri: f64, rj: f64) {
        let h = &mut self.hist[k];
        (h.fn_prev, h.ri_prev, h.rj_prev) = (fnorm, ri, rj);
    }
}

/// Particles per leaf of the threaded multi-contact pass.
const MC_GRAIN: usize = 64;

/// Kernel calls, fallbacks to Hertz and influence-matrix recomputations of a multi-contact pass.
#[derive(Debug, Clone, Copy, Default)]
struct McCounts {
    contacts: u64,
    fallbacks: u64,
    recomputed: u64,
}

/// A wall contact's result: (force, torque on the particle, |F·n|) when it touches.
type WallOut = Option<(Vec3, Vec3, f64)>;

/// Read-only view of what the wall-contact forces need (shared between threads).
struct WallCtx<'a> {
    walls: &'a [WallFix],
    meshes: &'a [Mesh],
    coeffs: &'a [PairCoeffs],
    nt: usize,
    typ: &'a [usize],
    x: &'a [Vec3],
    v: &'a [Vec3],
    omega: &'a [Vec3],
    radius: &'a [f64],
    mass: &'a [f64],
    id: &'a [i64],
    dt: f64,
    update: bool,
    step: u64,
    /// Evaluate the contacts that reach their wall in vectorised batches ([`WallLanes`]).
    batched: bool,
}

impl WallCtx<'_> {
    /// Forces of the wall contacts `wc`, whose particles are `base..base + f.len()`, added into
    /// those particles' sums `f`, `torque` in contact order; each contact's force on the particle
    /// into `force` (for the mesh sums), and, on a time step, its history updated.
    fn forces(
        &self,
        wc: &mut [WallContact],
        force: &mut [Vec3],
        f: &mut [Vec3],
        torque: &mut [Vec3],
        base: usize,
    ) -> Result<(), StepError> {
        if self.batched {
            return self.forces_batched(wc, force, f, torque, base);
        }
        for (c, fc) in wc.iter_mut().zip(force) {
            let (out, shear) = self.one(c)?;
            self.finish(c, fc, shear, out, f, torque, base);
        }
        Ok(())
    }

    /// One contact by [`particle_wall`]: (force, torque, |F·n|) if it touches, and its new
    /// tangential history; a contact that cannot be integrated stops the step, naming the particle.
    fn one(&self, c: &WallContact) -> Result<(WallOut, Vec3), StepError> {
        let i = c.p as usize;
        let mut shear = c.shear;
        let r = particle_wall(self.coeff(c), &self.body(i), &self.wall_point(c), c.dr, self.dt, &mut shear)
            .map_err(|e| contact_error(self.step, self.id[i], None, e))?;
        Ok((r.map(|cf| (cf.force_i, cf.torque_i, cf.force_i.dot(&cf.en).abs())), shear))
    }

    /// [`WallCtx::forces`] with the contacts that reach their wall evaluated in batches of
    /// [`LANES`] ([`WallLanes`], vectorised) and the results added in contact order afterwards:
    /// the same sums. A contact that does not reach its wall adds nothing, so settling it at
    /// once, ahead of the batch still open, changes no sum.
    fn forces_batched(
        &self,
        wc: &mut [WallContact],
        force: &mut [Vec3],
        f: &mut [Vec3],
        torque: &mut [Vec3],
        base: usize,
    ) -> Result<(), StepError> {
        let mut lanes = WallLanes::default();
        let mut slot = [0usize; LANES];
        let mut n = 0;
        for k in 0..wc.len() {
            let c = &wc[k];
            let i = c.p as usize;
            let ri = self.radius[i] + c.dr;
            let d = self.x[i] - c.point;
            if d.norm_squared() >= ri * ri {
                self.finish(&mut wc[k], &mut force[k], Vec3::zeros(), None, f, torque, base);
                continue;
            }
            let cf = self.coeff(c);
            let (l, v) = (n, self.v[i] - c.velocity);
            for a in 0..3 {
                lanes.d[a][l] = d[a];
                lanes.vr[a][l] = v[a];
                lanes.omega[a][l] = self.omega[i][a];
                lanes.shear[a][l] = c.shear[a];
            }
            (lanes.radius[l], lanes.dr[l], lanes.mass[l]) = (self.radius[i], c.dr, self.mass[i]);
            lanes.coeffs.set(l, cf);
            slot[n] = k;
            n += 1;
            if n == LANES {
                self.flush(&mut lanes, &slot, wc, force, f, torque, base)?;
                n = 0;
            }
        }
        if n > 0 {
            lanes.pad_from_first(n);
            self.flush(&mut lanes, &slot[..n], wc, force, f, torque, base)?;
        }
        Ok(())
    }

    /// Evaluates a batch and settles its contacts `slot` in order. A lane that cannot be
    /// integrated is evaluated again by [`WallCtx::one`] for the error it reports.
    #[allow(clippy::too_many_arguments)]
    fn flush(
        &self,
        lanes: &mut WallLanes,
        slot: &[usize],
        wc: &mut [WallContact],
        force: &mut [Vec3],
        f: &mut [Vec3],
        torque: &mut [Vec3],
        base: usize,
    ) -> Result<(), StepError> {
        lanes.evaluate(self.dt);
        for (l, &k) in slot.iter().enumerate() {
            let c = &mut wc[k];
            if !lanes.ok[l] {
                self.one(c)?;
            }
            let lane = |a: &[[f64; LANES]; 3]| Vec3::new(a[0][l], a[1][l], a[2][l]);
            let out = Some((lane(&lanes.force), lane(&lanes.torque), lanes.fnorm[l]));
            self.finish(c, &mut force[k], lane(&lanes.shear), out, f, torque, base);
        }
        Ok(())
    }

    /// Settles one contact: its force and torque (if it touches) into the particle's sums, its
    /// force recorded for the mesh sums, and on a time step its history.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn finish(
        &self,
        c: &mut WallContact,
        fc: &mut Vec3,
        shear: Vec3,
        out: WallOut,
        f: &mut [Vec3],
        torque: &mut [Vec3],
        base: usize,
    ) {
        let i = c.p as usize;
        let fnorm = match out {
            Some((force, tq, fnorm)) => {
                f[i - base] += force;
                torque[i - base] += tq;
                *fc = force;
                fnorm
            }
            None => {
                *fc = Vec3::zeros();
                0.0
            }
        };
        if self.update {
            c.shear = shear;
            c.fn_prev = fnorm;
            let rel = c.point - self.x[i];
            c.rel_prev = if fnorm > 0.0 {
                rel
            } else {
                let l = rel.norm();
                if l > 0.0 {
                    rel * ((self.radius[i] + c.dr) / l)
                } else {
                    Vec3::zeros()
                }
            };
        }
    }

    fn coeff(&self, c: &WallContact) -> &PairCoeffs {
        let wall_type = match &self.walls[c.wall as usize].geom {
            WallGeom::Plane(pl) => pl.wall_type,
            WallGeom::Meshes(_) => self.meshes[c.mesh as usize].wall_type,
        };
        &self.coeffs[self.typ[c.p as usize] * self.nt + wall_type]
    }

    fn body(&self, i: usize) -> Body {
        Body { x: self.x[i], v: self.v[i], omega: self.omega[i], radius: self.radius[i], mass: self.mass[i] }
    }

    fn wall_point(&self, c: &WallContact) -> WallPoint {
        WallPoint { point: c.point, velocity: c.velocity }
    }
}

thread_local! {
    /// One particle's contact loads and fallback flags: per thread, grown to the largest contact
    /// set seen and reused (no allocation in the step loop).
    static MC_SCRATCH: RefCell<(Vec<ContactLoad>, Vec<bool>)> = RefCell::default();
}

/// Read-only view of what the multi-contact kernel pass needs (shared between threads).
struct McCtx<'a> {
    p: &'a Particles,
    mc_types: &'a [McType],
    slot_start: &'a [u32],
    slots: &'a [Slot],
    pair_loads: &'a [PairLoad],
    wc: &'a [WallContact],
    step: u64,
}

impl McCtx<'_> {
    /// [`McCtx::kernel`] of all particles on the members of `team`, each on a consecutive range
    /// of particles with about equal numbers of contacts (the kernel's cost grows with them).
    /// Every particle's result is the one of a serial pass, and of several failures the lowest
    /// particle's is reported (the lowest member's, whose range comes first).
    fn kernel_on(
        &self,
        team: &Team,
        dr: &mut [f64],
        kept: Option<&mut [KeptInfluence]>,
        tolerance: f64,
    ) -> Result<McCounts, StepError> {
        let n = self.slot_start.len() - 1;
        let (size, total) = (team.size(), self.slot_start[n] as usize);
        debug_assert_eq!(self.slot_start[0], 0);
        let cut = |k: usize| {
            if k >= size {
                n
            } else {
                self.slot_start[..n].partition_point(|&s| (s as usize) * size < k * total)
            }
        };
        let (dr, kept) = (SplitMut::new(dr), kept.map(SplitMut::new));
        let counts = Mutex::new(McCounts::default());
        team.run(|k| {
            let (lo, hi) = (cut(k), cut(k + 1));
            let slots = self.slot_start[lo] as usize..self.slot_start[hi] as usize;
            // SAFETY: `cut` does not decrease with k, so the members' particle ranges lo..hi are
            // disjoint, and with them their slots and kept matrices.
            let (d, kp) = unsafe { (dr.range(slots), kept.as_ref().map(|v| v.range(lo..hi))) };
            let c = self.kernel(lo, hi, d, kp, tolerance)?;
            let mut sum = counts.lock().unwrap_or_else(|p| p.into_inner());
            sum.contacts += c.contacts;
            sum.fallbacks += c.fallbacks;
            sum.recomputed += c.recomputed;
            Ok(())
        })?;
        Ok(counts.into_inner().unwrap_or_else(|p| p.into_inner()))
    }

    /// Radius changes of particles lo..hi into `dr` (exactly their slots), kept matrices in
    /// `kept` (exactly those particles) under a geometry tolerance; of several failures the
    /// lowest particle's is reported.
    fn kernel(
        &self,
        lo: usize,
        hi: usize,
        dr: &mut [f64],
        kept: Option<&mut [KeptInfluence]>,
        tolerance: f64,
    ) -> Result<McCounts, StepError> {
        MC_SCRATCH.with(|buf| {
            let (loads, fb_buf) = &mut *buf.borrow_mut();
            let mut counts = McCounts::default();
            let mut kept = kept;
            let base = self.slot_start[lo] as usize;
            for i in lo..hi {
                let (s0, s1) = (self.slot_start[i] as usize, self.slot_start[i + 1] as usize);
                let out = &mut dr[s0 - base..s1 - base];
                if s1 - s0 < 2 {
                    out.fill(0.0);
                    continue;
                }
                loads.clear();
                loads.extend(self.slots[s0..s1].iter().map(|s| {
                    let (point, force) = match *s {
                        Slot::PairI(k) => {
                            let l = &self.pair_loads[k as usize];
                            (l.points[0], l.force)
                        }
                        Slot::PairJ(k) => {
                            let l = &self.pair_loads[k as usize];
                            (l.points[1], l.force)
                        }
                        Slot::Wall(k) => {
                            let c = &self.wc[k as usize];
                            (c.rel_prev, c.fn_prev)
                        }
                    };
                    ContactLoad { point, force }
                }));
                let m = self.mc_types[self.p.typ[i]].material;
                let params = McParams {
                    radius: self.p.radius[i],
                    youngs_modulus: m.youngs_modulus,
                    poisson_ratio: m.poisson_ratio,
                    gamma: m.gamma,
                    cap: m.cap,
                };
                let nl = loads.len();
                if fb_buf.len() < nl {
                    fb_buf.resize(nl, false);
                }
                // The particle's slots are its contacts in order: Δ goes straight into them.
                let fb = &mut fb_buf[..nl];
                let res = match kept.as_deref_mut() {
                    Some(k) => {
                        if let Some(next) = k.get(i - lo + 1) {
                            next.prefetch();
                        }
                        k[i - lo].radius_changes(tolerance, &params, loads, out, fb)
                    }
                    None => radius_changes(&params, loads, out, fb).map(|s| (s, false)),
                };
                let (summary, recomputed) = res.map_err(|e| StepError {
                    step: self.step,
                    particle: self.p.id[i],
                    cause: format!("multi-contact kernel: {e}"),
                })?;
                counts.contacts += nl as u64;
                counts.fallbacks += summary.fallbacks as u64;
                counts.recomputed += u64::from(recomputed);
            }
            Ok(counts)
        })
    }
}

/// s += u ⊗ w.
fn add_outer(s: &mut [[f64; 3]; 3], u: &Vec3, w: &Vec3) {
    for (row, ua) in s.iter_mut().zip(u.iter()) {
        for (sab, wb) in row.iter_mut().zip(w.iter()) {
            *sab += ua * wb;
        }
    }
}

// Cold: keeps the error formatting out of the contact loops.
#[cold]
#[inline(never)]
fn contact_error(step: u64, particle: i64, other: Option<i64>, e: ContactError) -> StepError {
    let with = match other {
        Some(j) => format!("contact with particle {j}"),
        None => "wall contact".to_string(),
    };
    StepError { step, particle, cause: format!("{with}: {e}") }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The wall contacts a scan of every particle against every wall element finds (what the
    /// candidate list must reproduce), as keys in scan order, from the same last-step contacts.
    fn scanned_keys(w: &World) -> Vec<(u32, u32, u32, u32)> {
        let mut all = Vec::new();
        for i in 0..w.p.len() as u32 {
            for (wi, wall) in w.walls.iter().enumerate() {
                let cand = |mesh: usize, tri: usize| WallCandidate {
                    p: i,
                    wall: wi as u32,
                    mesh: mesh as u32,
                    tri: tri as u32,
                };
                match &wall.geom {
                    WallGeom::Plane(_) => all.push(cand(0, 0)),
                    WallGeom::Meshes(list) => {
                        for &mi in list {
                            all.extend((0..w.meshes[mi].tris.len()).map(|t| cand(mi, t)));
                        }
                    }
                }
            }
        }
        let scene = wall_contacts::Scene::of(w);
        let (mut out, mut scratch) = (Vec::new(), Vec::new());
        wall_contacts::collect(&scene, &all, &w.wc_old, &mut out, &mut scratch);
        out.iter().map(WallContact::key).collect()
    }

    /// A piston of two tilted triangles oscillating onto two layers of resting spheres (no
    /// integration, so that no neighbour build happens and only the mesh's travel rebuilds the
    /// candidates) at a fifth of the skin per step: every step the contacts equal the full scan's.
    #[test]
    fn wall_candidates_find_every_contact_of_a_moving_mesh() {
        let (r, l) = (1e-3, 1e-2);
        let mut w = World::new();
        w.domain = Some(Domain::new(Vec3::zeros(), Vec3::repeat(l), [false; 3]));
        w.set_materials(vec![Material::hertz(1e6, 0.4).unwrap()], &[0.7], &[0.5], Tangential::History)
            .unwrap();
        w.closure = Some(Closure::Hertz);
        w.skin = 1e-4;
        w.dt = 1e-5;
        let lattice = (0..4).flat_map(|i| (0..4).flat_map(move |j| (0..2).map(move |k| (i, j, k))));
        for (id, (i, j, k)) in (1..).zip(lattice) {
            // Heights staggered by up to 0.9 r, so contacts start at many different steps.
            let dz = 1e-4 * ((7 * i + 3 * j + 5 * k) % 10) as f64;
            let x = Vec3::new(
                1.3e-3 + 2.5e-3 * i as f64,
                1.3e-3 + 2.5e-3 * j as f64,
                1.5e-3 + 2.5e-3 * k as f64 + dz,
            );
            w.p.push(id, 0, x, 2.0 * r, 1000.0);
        }
        for (axis, pos) in [(0, 0.0), (0, l), (1, 0.0), (1, l), (2, 0.0)] {
            let geom = WallGeom::Plane(PlaneWall { axis, pos, wall_type: 0 });
            w.walls.push(WallFix { name: format!("plane{axis}"), geom });
        }
        let (z0, z1) = (6.0e-3, 6.3e-3);
        let raw = vec![
            [Vec3::new(0.0, 0.0, z0), Vec3::new(l, 0.0, z0), Vec3::new(l, l, z1)],
            [Vec3::new(0.0, 0.0, z0), Vec3::new(l, l, z1), Vec3::new(0.0, l, z1)],
        ];
        w.meshes.push(Mesh::new("piston", 0, raw).unwrap());
        w.walls.push(WallFix { name: "piston".into(), geom: WallGeom::Meshes(vec![0]) });
        w.setup().unwrap();
        let keys = |w: &World| w.wc.iter().map(WallContact::key).collect::<Vec<_>>();
        assert_eq!(keys(&w), scanned_keys(&w));
        let (mut travel_builds, mut onsets, mut before) = (0, 0, 0);
        for s in 0..240 {
            // Down and up by 8e-4 m at 2 m/s: 2e-5 m per step.
            w.meshes[0].velocity = Vec3::new(0.0, 0.0, if (s / 40) % 2 == 0 { -2.0 } else { 2.0 });
            let travel = w.wall_travel;
            w.step().unwrap();
            travel_builds += usize::from(w.wall_travel < travel);
            let scan = scanned_keys(&w);
            let on_piston = scan.iter().filter(|k| k.1 == 5).count();
            onsets += on_piston.saturating_sub(before);
            before = on_piston;
            assert_eq!(keys(&w), scan, "step {s}");
        }
        assert_eq!(w.builds, 1, "no neighbour build after set-up");
        assert!(travel_builds > 50, "the mesh's travel rebuilt the candidates {travel_builds} times");
        assert!(onsets >= 20, "{onsets} piston contacts began");
    }
}
