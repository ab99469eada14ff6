//! The whole simulated system and its step as the list of the stages.

use std::fmt;

use crate::physics::contact_set::InfluenceCache;
use crate::physics::hertz::Tangential;
use crate::physics::pair::ContactError;
use crate::physics::{Hysteresis, Material, PairCoeffs, Vec3};
use crate::team::Team;

use super::blocks::{Blocks, PairThreads, StepTimer};
use super::contacts::Contacts;
use super::mc_fixed_point::{FixedPoint, FixedPointStats, FpScratch};
use super::multicontact::{McState, McType};
use super::neighbor_list::NeighborList;
use super::pair_pass::PairScratch;
use super::wall_pass::WallSearch;
use super::{Domain, Mesh, Particles, WallFix};

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
    /// The cause in words (the text of [`StepError::contact`] when it is set, with the partner).
    pub cause: String,
    /// The contact law's own error when a contact stopped the run (overlap beyond a radius,
    /// coincident centres, a non-finite force); `None` for the other stops (a lost particle, a
    /// non-finite position, the multi-contact kernel). Callers that act on the cause read this,
    /// not the text.
    pub contact: Option<ContactError>,
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
    /// The box as outputs report it (dump headers, `vol`), where the deck's shrink-wrapped box
    /// (LIGGGHTS' `boundary m`/`s`: the particle centres' extent) differs from `domain`, which
    /// keeps a radius and a skin of margin so that no particle is ever outside it.
    pub reported_box: Option<(Vec3, Vec3)>,
    pub p: Particles,
    pub ntypes: usize,
    /// Per type (0-based): material.
    pub materials: Vec<Material>,
    /// ntypes × ntypes pair coefficients, row-major.
    pub coeffs: Vec<PairCoeffs>,
    /// ntypes × ntypes particle–wall coefficients (row: particle type, column: wall type) when
    /// the walls' model differs from the pairs' (LIGGGHTS lets `fix wall/gran` drop the pair
    /// style's cohesion or run `hooke` beside `hooke/hysteresis` pairs); `None`: [`World::coeffs`].
    pub wall_coeffs: Option<Vec<PairCoeffs>>,
    pub closure: Option<Closure>,
    pub dt: f64,
    pub step: u64,
    pub gravity: Option<Vec3>,
    pub walls: Vec<WallFix>,
    pub meshes: Vec<Mesh>,
    pub skin: f64,
    /// `neigh_modify check no`: rebuild the neighbour list every step instead of when the skin
    /// test fires (LAMMPS' `every 1 check no`); the reference the skin test is checked against.
    pub rebuild_every_step: bool,
    /// Multi-contact range factor: wall contacts are sought out to this multiple of the radius;
    /// pair lists out to it as well, but never beyond what a pair can use ([`World::pair_reach`]).
    pub mc_range: f64,
    /// Is each particle integrated (`fix nve/sphere` present)?
    pub integrate: bool,
    /// `fix nve/sphere` of a group that may not hold every particle: only particles with this
    /// mask bit move (LAMMPS: the others keep position and velocity, forces act on them but are
    /// not integrated). `None`: every particle, the plain loop.
    pub integrate_group: Option<u32>,
    /// Number of neighbour-list builds so far.
    pub builds: u64,
    /// LIGGGHTS 3.8 `surface multicontact` radius convention in pairs: the first particle of a
    /// pair keeps its original radius in R_eff and lever arm (only its overlap sees Δ). Set for
    /// decks that ask for LIGGGHTS' standard MC, so both engines give the same forces; the
    /// `mc_advanced` model uses the modified radii of both particles (docs/spec.md §2).
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
    /// Accuracy budget EPS of the multi-contact pass (`mcAccuracy`). 0 (the default): exact, the
    /// plain pass. > 0: each particle reuses the radius changes of its last exact Eq. 2 evaluation
    /// while a bound on their error stays below EPS × its scale (docs/dem.md "Accuracy budget").
    pub mc_accuracy: f64,
    /// Shadow check interval [steps] of the accuracy budget (`mcAccuracyCheck`; 0: none).
    pub mc_accuracy_check: u64,
    /// Full multi-contact passes so far.
    pub mc_updates: u64,
    /// Eq. 2 iterated to self-consistency within each step (`mc_fixed_point`); `None` (the
    /// default): the paper's one-step lag, one force pass per step.
    pub mc_fixed_point: Option<FixedPoint>,
    /// What that iteration did since the counters were last zeroed.
    pub mc_fp_stats: FixedPointStats,
    /// Spatial sorting (LAMMPS `atom_modify sort`): at the first neighbour build at least this
    /// many steps after the last sort, particles are renumbered bin by bin in row-major order, so
    /// that particles close in space are close in memory and the pair loop stays in cache as N
    /// grows. 0 (the default of the library API, which keeps indices stable): never. Decks get
    /// LAMMPS' 1000.
    pub sort_every: u64,
    /// Number of spatial sorts so far.
    pub sorts: u64,
    /// Whether a step's force passes (pairs, walls, multi-contact kernel) and half-kicks run on
    /// the threads' team (default: decided by the timing probe).
    pub pair_threads: PairThreads,

    // The stages' own state.
    pub(super) contacts: Contacts,
    pub(super) wall_search: WallSearch,
    pub(super) multi: McState,
    pub(super) lists: NeighborList,
    pub(super) blocks: Blocks,
    pub(super) pair_scratch: PairScratch,
    pub(super) fp_scratch: FpScratch,
    /// The timer of a step split at its pre-force point ([`World::step_to_pre_force`]).
    pub(super) step_timer: Option<StepTimer>,
}

impl World {
    pub fn new() -> Self {
        World { mc_range: 1.0, ..Default::default() }
    }

    /// Checks that the world is complete and consistent, and builds the neighbour list: called by
    /// every `run` before the first step (LAMMPS `setup`).
    /// The box the outputs report: [`World::reported_box`] if set, else the domain's.
    pub fn output_box(&self) -> Option<(Vec3, Vec3)> {
        self.reported_box.or(self.domain.map(|d| (d.lo, d.hi)))
    }

    pub fn setup(&mut self) -> Result<Vec<String>, String> {
        let mut warnings = Vec::new();
        let domain = self.domain.ok_or("no simulation box (create_box or read_data) before run")?;
        if self.dt <= 0.0 {
            return Err("timestep must be > 0".into());
        }
        if self.closure.is_none() {
            return Err("no pair_style gran defined before run".into());
        }
        if self.mc_fixed_point.is_some()
            && (self.mc_every > 1 || self.mc_accuracy > 0.0 || self.mc_geometry_tolerance > 0.0)
        {
            return Err("the Eq. 2 fixed point evaluates the multi-contact pass exactly at every pass: \
                        it does not combine with an update interval, an accuracy budget or a geometry tolerance"
                .into());
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
        if let Some((t_r, i)) = self.rayleigh_worst() {
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
        self.multi.mc_types = self.materials.iter().map(|m| McType { material: *m }).collect();
        let tol = self.mc_geometry_tolerance;
        if tol == 0.0 {
            self.multi.mc_cache = None;
        } else if self.multi.mc_cache.as_ref().is_none_or(|c| c.tolerance() != tol) {
            self.multi.mc_cache = Some(InfluenceCache::new(tol).map_err(|e| e.to_string())?);
        }
        self.lists.need_build = true;
        self.multi.mc_due = 0;
        self.neighbor_check().map_err(|e| e.to_string())?;
        // LIGGGHTS zeroes mesh node velocities at set-up (fix move/mesh sets them again in the
        // first step), so the set-up forces see resting meshes.
        // The threads' team is started here rather than inside the timing probe's first window.
        if self.pair_threads != PairThreads::Serial {
            self.start_team();
        }
        // The conveyor velocity of `surface_vel` is set once and stays.
        let vel: Vec<(Vec3, Vec3)> = self.meshes.iter().map(|m| (m.velocity, m.omega)).collect();
        self.meshes.iter_mut().for_each(|m| (m.velocity, m.omega) = (Vec3::zeros(), Vec3::zeros()));
        let r = self.compute_forces(false).map_err(|e| e.to_string());
        self.meshes.iter_mut().zip(vel).for_each(|(m, v)| (m.velocity, m.omega) = v);
        r?;
        Ok(warnings)
    }

    /// The smallest Rayleigh time of the particles and the particle that has it (LIGGGHTS checks
    /// the same): above it the explicit scheme is unstable.
    pub(super) fn rayleigh_worst(&self) -> Option<(f64, usize)> {
        let mut worst: Option<(f64, usize)> = None;
        for i in 0..self.p.len() {
            let m = &self.materials[self.p.typ[i]];
            let t_r = crate::physics::timestep::rayleigh_time(
                self.p.radius[i],
                self.p.density[i],
                m.youngs_modulus,
                m.poisson_ratio,
            );
            if worst.is_none_or(|(t, _)| t_r < t) {
                worst = Some((t_r, i));
            }
        }
        worst
    }

    /// One velocity-Verlet step, stage by stage in the LAMMPS `Verlet` order.
    pub fn step(&mut self) -> Result<(), StepError> {
        self.step_to_pre_force()?;
        self.step_from_pre_force()
    }

    /// The first half of [`World::step`]: the step counter, first half kick and drift, boundary
    /// motion and the neighbour check. What a deck changes "before the forces" (LAMMPS
    /// `pre_force`, e.g. `fix adapt`) goes between this and [`World::step_from_pre_force`].
    pub fn step_to_pre_force(&mut self) -> Result<(), StepError> {
        self.step += 1;
        // Threads pay only when the cores are free: the probe (`probe.rs`) times windows of whole
        // steps with and without them and keeps the faster. Whole steps, so that what threading
        // changes outside the threaded passes counts too, but without the neighbour check: a
        // list build costs the same in both modes and would weigh on whichever slice it falls in.
        let mut timer = self.blocks.begin_step(self.pair_threads, self.step);
        if self.integrate {
            self.initial_integrate();
        }
        self.move_boundaries();
        timer.leave_out(|| self.neighbor_check())?;
        self.step_timer = Some(timer);
        Ok(())
    }

    /// The second half of [`World::step`]: forces and the second half kick.
    pub fn step_from_pre_force(&mut self) -> Result<(), StepError> {
        let timer = self.step_timer.take().expect("step_to_pre_force runs first");
        self.compute_forces(true)?;
        if self.integrate {
            self.final_integrate()?;
        }
        self.blocks.end_step(self.step, timer);
        Ok(())
    }

    /// `reset_timestep`: the step counter becomes `step`; the next spatial sort stays as many
    /// steps ahead.
    pub fn reset_step(&mut self, step: u64) {
        self.lists.next_sort = (self.lists.next_sort + step).saturating_sub(self.step);
        self.step = step;
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
        let threads = self.threads().map_or(1, Team::size);
        let batched = self.batched();
        if let Some(fp) = self.mc_fixed_point.filter(|_| mc && update) {
            return self.fixed_point_passes(fp, threads, batched);
        }
        if mc {
            self.multicontact()?;
        }
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
        let coeffs = crate::physics::material::pair_table(&materials, restitution, friction)?
            .into_iter()
            .map(|c| PairCoeffs { tangential, ..c })
            .collect();
        self.ntypes = nt;
        self.materials = materials;
        self.coeffs = coeffs;
        Ok(())
    }

    /// Switches every type pair set by [`World::set_materials`] to LIGGGHTS' `model hooke` with
    /// characteristic velocity `char_vel` [m/s]; `restitution` is the same table as there,
    /// `options` (tangential_damping, limitForce, ktToKnUser).
    pub fn use_hooke(
        &mut self,
        char_vel: f64,
        restitution: &[f64],
        options: (bool, bool, bool),
    ) -> Result<(), String> {
        if restitution.len() != self.coeffs.len() {
            return Err(format!("peratomtypepair tables must have {0}×{0} entries", self.ntypes));
        }
        for (c, &e) in self.coeffs.iter_mut().zip(restitution) {
            *c = c.with_hooke(char_vel, e, options).map_err(|e| e.to_string())?;
        }
        Ok(())
    }

    /// The particle–wall coefficient table (see [`World::wall_coeffs`]).
    pub fn wall_coeffs(&self) -> &[PairCoeffs] {
        self.wall_coeffs.as_deref().unwrap_or(&self.coeffs)
    }

    /// Switches every type pair of `model hooke` (after [`World::use_hooke`]) to LIGGGHTS'
    /// `model hooke/hysteresis` with the per-type-pair tables `max_stiffness`
    /// (coefficientMaxElasticStiffness), `adhesion` (coefficientAdhesionStiffness) and `depth`
    /// (coefficientPlasticityDepth), each ntypes × ntypes.
    pub fn use_hysteresis(
        &mut self,
        max_stiffness: &[f64],
        adhesion: &[f64],
        depth: &[f64],
    ) -> Result<(), String> {
        let n = self.coeffs.len();
        if [max_stiffness.len(), adhesion.len(), depth.len()].iter().any(|&l| l != n) {
            return Err(format!("peratomtypepair tables must have {0}×{0} entries", self.ntypes));
        }
        let nt = self.ntypes;
        for (k, c) in self.coeffs.iter_mut().enumerate() {
            let hy = Hysteresis::new(max_stiffness[k], adhesion[k], depth[k])
                .and_then(|hy| c.with_hysteresis(hy))
                .map_err(|e| format!("types {} and {}: {e}", k / nt + 1, k % nt + 1))?;
            *c = hy;
        }
        Ok(())
    }

    /// Adds LIGGGHTS' `cohesion sjkr` with the ntypes × ntypes `cohesionEnergyDensity` table to
    /// `table` (the pair or the wall coefficients); `tangential_reduce` as in [`PairCoeffs`].
    /// Adds `rolling_friction cdt` with the per-type-pair coefficients `mu_r` to `table`.
    pub fn add_rolling_friction(table: &mut [PairCoeffs], nt: usize, mu_r: &[f64]) -> Result<(), String> {
        if mu_r.len() != table.len() {
            return Err(format!("peratomtypepair tables must have {nt}×{nt} entries"));
        }
        for (k, c) in table.iter_mut().enumerate() {
            *c = c
                .with_rolling_friction(mu_r[k])
                .map_err(|e| format!("types {} and {}: {e}", k / nt + 1, k % nt + 1))?;
        }
        Ok(())
    }

    /// Adds `rolling_friction epsd` (with the per-type-pair `coefficientRollingViscousDamping`
    /// `damping`) or `epsd2` (`damping` None) with the per-type-pair coefficients `mu_r` to `table`.
    pub fn add_rolling_spring(
        table: &mut [PairCoeffs],
        nt: usize,
        mu_r: &[f64],
        damping: Option<&[f64]>,
    ) -> Result<(), String> {
        if mu_r.len() != table.len() || damping.is_some_and(|d| d.len() != table.len()) {
            return Err(format!("peratomtypepair tables must have {nt}×{nt} entries"));
        }
        for (k, c) in table.iter_mut().enumerate() {
            *c = c
                .with_rolling_spring(mu_r[k], damping.map(|d| d[k]))
                .map_err(|e| format!("types {} and {}: {e}", k / nt + 1, k % nt + 1))?;
        }
        Ok(())
    }

    pub fn add_cohesion(
        table: &mut [PairCoeffs],
        nt: usize,
        energy_density: &[f64],
        tangential_reduce: bool,
    ) -> Result<(), String> {
        if energy_density.len() != table.len() {
            return Err(format!("peratomtypepair tables must have {nt}×{nt} entries"));
        }
        for (k, c) in table.iter_mut().enumerate() {
            *c = c
                .with_cohesion(energy_density[k], tangential_reduce)
                .map_err(|e| format!("types {} and {}: {e}", k / nt + 1, k % nt + 1))?;
        }
        Ok(())
    }
}
