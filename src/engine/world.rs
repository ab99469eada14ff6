//! The whole simulated system and its step as the list of the stages.

use std::fmt;

use crate::physics::contact_set::InfluenceCache;
use crate::physics::hertz::Tangential;
use crate::physics::{Material, PairCoeffs, Vec3};
use crate::team::Team;

use super::blocks::PairThreads;
use super::contacts::{Pair, PairDr, PairHist, PairLoad, WallCandidate, WallContact};
use super::multicontact::{McType, Slot};
use super::neighbor::CellList;
use super::pair_eval::PairOut;
use super::probe::ThreadProbe;
use super::sinks::Deferred;
use super::{wall_contacts, Domain, Mesh, Particles, WallFix};

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
    pub(super) mc_due: u64,
    /// Neighbour builds at the last full multi-contact pass (a build renumbers the pairs).
    pub(super) mc_builds: u64,
    /// Spatial sorting (LAMMPS `atom_modify sort`): at the first neighbour build at least this
    /// many steps after the last sort, particles are renumbered bin by bin in row-major order, so
    /// that particles close in space are close in memory and the pair loop stays in cache as N
    /// grows. 0 (the default of the library API, which keeps indices stable): never. Decks get
    /// LAMMPS' 1000.
    pub sort_every: u64,
    /// Number of spatial sorts so far.
    pub sorts: u64,
    pub(super) next_sort: u64,

    pub(super) cells: CellList,
    pub(super) cand: Vec<(u32, u32)>,
    pub(super) pairs: Vec<Pair>,
    pub(super) pairs_old: Vec<Pair>,
    /// Per pair, under the multi-contact closure: what its next pass reads (empty under Hertz).
    pub(super) pair_hist: Vec<PairHist>,
    pub(super) pair_hist_old: Vec<PairHist>,
    pub(super) wc: Vec<WallContact>,
    pub(super) wc_old: Vec<WallContact>,
    pub(super) wc_scratch: wall_contacts::GroupScratch,
    /// Wall elements that may touch a particle before the next candidate build, in the wall scan's
    /// order (`update_wall_contacts`); built at every neighbour build (`wall_cand_builds`) and when
    /// the meshes have moved half a skin since (`wall_travel`).
    pub(super) wall_cand: Vec<WallCandidate>,
    pub(super) wall_cand_builds: Option<u64>,
    /// Upper bound on how far any mesh moved since the wall candidates were built [m].
    pub(super) wall_travel: f64,
    pub(super) x_build: Vec<Vec3>,
    pub(super) need_build: bool,
    /// Lees–Edwards offset travelled since the last neighbour build (not wrapped) [m].
    pub(super) le_travel: f64,
    /// Interaction cutoff without skin, 2 r_max × pair_reach, at the last build [m].
    pub(super) cut_build: f64,
    pub(super) mc_types: Vec<McType>,
    // multi-contact scratch (kept between steps: no allocation in the loop)
    pub(super) slot_start: Vec<u32>,
    pub(super) slots: Vec<Slot>,
    pub(super) slot_fill: Vec<u32>,
    /// Radius change per slot, from this step's kernel pass.
    pub(super) slot_dr: Vec<f64>,
    /// Per particle, its pairs (see `build_incidence`), as compressed rows.
    pub(super) inc_start: Vec<u32>,
    pub(super) inc: Vec<u32>,
    /// Threaded pair pass: per particle, the block of pairs that writes its sums directly (the
    /// first block, in pair order, with a pair on it; see [`World::assign_owners`]).
    pub(super) owner: Vec<u16>,
    /// (pairs, blocks, particles) the owners were computed for; None after a neighbour build.
    pub(super) owner_key: Option<(usize, usize, usize)>,
    /// Where the blocks of the owning threaded pass start in the pair list (and the end): equal
    /// runs after each assignment, then moved by [`World::balance_blocks`] to even out the
    /// members' measured times.
    pub(super) pair_cuts: Vec<usize>,
    /// Per block, nanoseconds spent in the threaded pair pass since the last balancing, and the
    /// passes counted.
    pub(super) block_ns: Vec<u64>,
    pub(super) block_passes: u32,
    /// Few enough pair ends fall on particles another block owns for the blocks to pay (else the
    /// threaded pass keeps every pair's result and sums per particle afterwards).
    pub(super) owned_blocks_pay: bool,
    /// Threaded pair passes so far: (by owned blocks, keeping every pair's result).
    pub(super) threaded_passes: (u64, u64),
    /// Threaded pair pass: per block, its contributions to particles another block owns, in pair
    /// order (kept between steps: no allocation in the loop once grown).
    pub(super) deferred: Vec<Vec<Deferred>>,
    /// The slot lists no longer match the pairs and wall contacts (neighbour build, a wall
    /// contact appeared or left, a pair entered or left the multi-contact set).
    pub(super) slots_stale: bool,
    /// Per pair: what this step's multi-contact pass reads (filled for pairs taking part).
    pub(super) pair_loads: Vec<PairLoad>,
    /// Geometry tolerance: the kept influence matrices, one per particle.
    pub(super) mc_cache: Option<InfluenceCache>,
    pub(super) pair_out: Vec<PairOut>,
    /// Per pair, under the multi-contact closure: this step's radius changes (a Hertz pass reads none).
    pub(super) pair_dr: Vec<PairDr>,
    /// Per pair: the total contact force on i from j at the last force pass (zero when apart),
    /// for the stress and coordination outputs.
    pub(super) pair_force: Vec<Vec3>,
    pub(super) pair_mc: Vec<bool>,
    /// Per wall contact: its force on the particle at the last force pass (for the mesh sums).
    pub(super) wall_force: Vec<Vec3>,
    pub(super) f_buf: Vec<Vec3>,
    pub(super) t_buf: Vec<Vec3>,
    pub(super) parallel: bool,
    /// When `PairThreads::Auto` times steps with and without threads, and what it measured.
    pub(super) probe: ThreadProbe,
    /// Whether a step's force passes (pairs, walls, multi-contact kernel) and half-kicks run on
    /// the threads' team (default: decided by the timing probe).
    pub pair_threads: PairThreads,
    /// The threads of the threaded passes (`rayon::current_num_threads()` members, started at
    /// the first threaded step and kept for the run).
    pub(super) team: Option<Team>,
    /// Per member of the threaded wall pass: its first wall contact and first particle (and
    /// after the last member, the ends).
    pub(super) wall_cuts: Vec<[usize; 2]>,
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

    /// Force and torque on every particle and force on every mesh, stage by stage: wall contacts
    /// found, multi-contact radius changes, pairs, body forces and walls. `update` = false is the
    /// set-up pass of a run: the contact history is not advanced (LIGGGHTS `shearupdate` off).
    /// Every pass writes the per-particle sums from zero (the pair pass into spare buffers,
    /// swapped in): no clearing here.
    pub(super) fn compute_forces(&mut self, update: bool) -> Result<(), StepError> {
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
        let threads = self.threads().map_or(1, Team::size);
        let batched = self.batched();
        self.pair_pass(update, mc, threads, batched)?;
        self.wall_pass(update, threads, batched)
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
