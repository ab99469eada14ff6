//! The sphere problems on one octant: a sphere of radius r between two frictionless rigid plates
//! (Hertz check) or in the rigid cubic die of side 2r (paper App. B single particle), loaded by
//! moving the plates together quasi-statically.
//!
//! Symmetry: with frictionless walls and the sphere centre mid-way between the plates, the solution
//! is symmetric about the three planes through the centre, so one octant with u_x = 0 on x = 0,
//! u_y = 0 on y = 0 and u_z = 0 on z = 0 is the whole problem. Δ is the plates' total approach
//! (the die's top-plate travel with the bottom plate fixed); each contact is compressed by Δ/2,
//! so the octant's plate sits at z = r − Δ/2 and, in the die, the side walls at x = r and y = r.
//! Forces: the octant carries a quarter of each contact patch, so a wall force is four times the
//! octant's reaction; stresses are wall force / (2r)², the die's convention (`validate::die`).

use super::element::{Law, Volumetric};
use super::material::Lame;
use super::mesh::{sphere_octant, Mesh};
use super::solver::{Equilibrium, Plane, Problem, Settings, Solver, State};

/// Which walls surround the sphere.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Walls {
    /// Two plates only (Hertz).
    Plates,
    /// Two plates and the four side walls of the die of side 2r.
    Die,
}

/// Specification of one sphere run.
#[derive(Clone, Debug)]
pub struct SphereRun {
    pub radius: f64,
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    pub law: Law,
    pub vol: Volumetric,
    /// Intervals per octant block edge (mesh level ℓ has `intervals(ℓ)` = 4·2^{ℓ−1}).
    pub intervals: usize,
    pub walls: Walls,
    /// Plate approach Δ/r at which the forces are reported, increasing.
    pub delta_over_r: Vec<f64>,
}

/// One reported point.
#[derive(Clone, Copy, Debug)]
pub struct Point {
    pub delta_over_r: f64,
    /// Plate force [N] (whole sphere) and side-wall force on one wall [N] (0 for `Plates`).
    pub plate_force: f64,
    pub side_force: f64,
    /// Stresses force / (2r)² [Pa].
    pub plate_stress: f64,
    pub side_stress: f64,
    /// Number of octant nodes on the plate and on the x side wall.
    pub plate_nodes: usize,
    pub side_nodes: usize,
}

/// Largest plate approach the octant meshes are built for: beyond it the graded contact zone has
/// spread past the refined part of the blocks (the contact radius reaches ~0.6 r at Δ/r = 0.5).
pub const MAX_DELTA_OVER_R: f64 = 0.5;

/// Fewest and most intervals per block edge: below 2 the graded contact zone has no interior
/// node row; 128 is mesh level 6, beyond which the direct solve outgrows memory.
pub const MIN_INTERVALS: usize = 2;
pub const MAX_INTERVALS: usize = 128;

/// Intervals per block edge at mesh level ℓ.
pub fn intervals(level: u32) -> usize {
    4usize << (level.saturating_sub(1))
}

impl SphereRun {
    /// Checks the inputs; every message names the offending field.
    pub fn check(&self) -> Result<(), String> {
        if !(self.radius > 0.0 && self.radius.is_finite()) {
            return Err(format!("radius must be positive, got {}", self.radius));
        }
        if !(self.youngs_modulus > 0.0 && self.youngs_modulus.is_finite()) {
            return Err(format!("youngs_modulus must be positive, got {}", self.youngs_modulus));
        }
        if !(self.poisson_ratio > -1.0 && self.poisson_ratio < 0.5) {
            return Err(format!(
                "poisson_ratio must lie in (-1, 0.5), got {} (the incompressible limit is reached by extrapolation, see docs/validation.md)",
                self.poisson_ratio
            ));
        }
        if !(MIN_INTERVALS..=MAX_INTERVALS).contains(&self.intervals) {
            return Err(format!(
                "mesh intervals per block edge must be {MIN_INTERVALS} to {MAX_INTERVALS} (mesh_level 1 to 6), got {}",
                self.intervals
            ));
        }
        if self.delta_over_r.is_empty() {
            return Err("delta_over_r: no load steps".into());
        }
        let mut prev = 0.0;
        for &d in &self.delta_over_r {
            if d.is_nan() || d <= prev {
                return Err(format!("delta_over_r must be positive and increasing, got {d} after {prev}"));
            }
            if d > MAX_DELTA_OVER_R {
                return Err(format!(
                    "delta_over_r = {d} is beyond what the octant mesh is built for ({MAX_DELTA_OVER_R})"
                ));
            }
            prev = d;
        }
        Ok(())
    }

    /// The boundary-value problem at zero load.
    pub fn problem(&self) -> Problem {
        let mesh: Mesh = sphere_octant(self.radius, self.intervals);
        let tol = 1e-9 * self.radius;
        let mut fixed = Vec::new();
        for (i, x) in mesh.x.iter().enumerate() {
            for a in 0..3 {
                if x[a].abs() < tol {
                    fixed.push((3 * i + a, 0.0));
                }
            }
        }
        let mut planes = vec![Plane { axis: 2, pos: self.radius, upper: true }];
        if self.walls == Walls::Die {
            planes.push(Plane { axis: 0, pos: self.radius, upper: true });
            planes.push(Plane { axis: 1, pos: self.radius, upper: true });
        }
        Problem {
            mesh,
            law: self.law,
            lame: Lame::from_e_nu(self.youngs_modulus, self.poisson_ratio),
            vol: self.vol,
            fixed,
            planes,
            pairs: Vec::new(),
        }
    }

    /// Runs the load path (`load_path`); `progress` sees every reported point.
    pub fn run(&self, mut progress: impl FnMut(&Point)) -> Result<Vec<Point>, String> {
        self.check()?;
        let mut p = self.problem();
        let area = 4.0 * self.radius * self.radius;
        let mut out = Vec::new();
        let what =
            format!("{} intervals per edge, {:?}, nu = {}", self.intervals, self.law, self.poisson_ratio);
        load_path(
            &mut p,
            &Settings::default(),
            &self.delta_over_r,
            &what,
            |p, next| p.planes[0].pos = self.radius * (1.0 - 0.5 * next),
            |eq, target| {
                let side = if self.walls == Walls::Die { 4.0 * eq.plane_force[1] } else { 0.0 };
                let pt = Point {
                    delta_over_r: target,
                    plate_force: 4.0 * eq.plane_force[0],
                    side_force: side,
                    plate_stress: 4.0 * eq.plane_force[0] / area,
                    side_stress: side / area,
                    plate_nodes: eq.contact_nodes[0],
                    side_nodes: if self.walls == Walls::Die { eq.contact_nodes[1] } else { 0 },
                };
                progress(&pt);
                out.push(pt);
            },
        )?;
        Ok(out)
    }
}

/// Quasi-static load path through the plate approaches Δ/r `targets` (increasing):
/// `apply(problem, Δ/r)` sets one, `report(equilibrium, target)` sees the equilibrium at each target. Each interval
/// between targets is one load step, halved on non-convergence down to 1/256 of it; `what` names
/// the run in the error.
pub fn load_path(
    p: &mut Problem,
    set: &Settings,
    targets: &[f64],
    what: &str,
    mut apply: impl FnMut(&mut Problem, f64),
    mut report: impl FnMut(&Equilibrium, f64),
) -> Result<(), String> {
    let mut solver = Solver::new(p)?;
    let mut state: State = solver.rest(p);
    let mut at = 0.0;
    let mut last: Option<(Vec<f64>, f64)> = None;
    for &target in targets {
        let mut step = target - at;
        let min_step = step / 256.0;
        while at < target - 1e-12 {
            let next = (at + step).min(target);
            let saved = state.clone();
            // Secant predictor: continue the last increment's displacement field, which keeps
            // the thin graded surface layer from being crushed by the contact nodes alone;
            // dropped if it would invert an element.
            if let Some((u_prev, d_prev)) = &last {
                let ratio = (next - at) / d_prev;
                let trial: Vec<f64> = state.u.iter().zip(u_prev).map(|(u, v)| u + ratio * (u - v)).collect();
                if solver.energy(p, &trial, &state.multiplier).is_some() {
                    state.u = trial;
                }
            }
            apply(p, next);
            match solver.solve(p, &mut state, set) {
                Ok(eq) => {
                    last = Some((saved.u, next - at));
                    at = next;
                    if (at - target).abs() < 1e-12 {
                        report(&eq, target);
                    }
                }
                Err(e) => {
                    state = saved;
                    step *= 0.5;
                    if step < min_step {
                        return Err(format!(
                            "no equilibrium between delta/r = {at:.5} and {target:.5} even with 1/256 of the step ({what}): {e}"
                        ));
                    }
                }
            }
        }
    }
    Ok(())
}
