//! Uniaxial (piston) compression of a packing in a rigid rectangular box by the nonlocal solver:
//! the reference curve σ(φ) of the 514-particle hydrogel case (docs/spec.md §5.2, docs/nonlocal.md
//! "514-particle compression").
//!
//! Walls: four frictionless side planes x = 0, L_x, y = 0, L_y, the bottom z = 0 and the piston plane
//! z = z_piston, moved linearly from `z_start` to `z_end` in `steps` equal load steps. Gravity is
//! off. φ = V_s / (L_x L_y z_piston), σ = piston force / (L_x L_y).
//!
//! Treatment of a loose start (docs/nonlocal.md): every increment starts from the affine prediction
//! of the previous equilibrium, is relaxed by FIRE with the lagged nonlocal relation (the
//! rearrangements of a frictionless, barely jammed packing are a minimisation problem), and is then
//! solved exactly by Newton with the active set; a failing increment is halved. A force-free state
//! (the piston not yet carrying load) is an exact equilibrium with every contact force zero. Every
//! returned point satisfies the solver's force-balance tolerance; an increment that cannot be solved
//! is an error naming the step, never a shortened curve.

use std::time::Instant;

use super::kernel::Kernel;
use super::solver::{Nonlocal, Other, Settings, SolveError, Sphere, Wall};
use crate::physics::material::Material;
use crate::physics::Vec3;

/// Box side L_x of the hydrogel packing (LIGGGHTS example `hydrogel_multicontact`) [m].
pub const HYDROGEL_LX: f64 = 0.165190844117647;
/// Box side L_y [m].
pub const HYDROGEL_LY: f64 = 0.165833589215686;
/// Solid volume of the 514 spheres [m³] (docs/spec.md §5.2).
pub const HYDROGEL_SOLID_VOLUME: f64 = 2.695884e-3;
/// Piston height at the start of every compression stroke of the example deck [m].
pub const HYDROGEL_Z_START: f64 = 0.1676430125;
/// Piston heights for φ = 0.66, 0.70, 0.75, 0.80, 0.85 (docs/spec.md §5.2) [m].
pub const HYDROGEL_Z_PHI: [(f64, f64); 5] =
    [(0.66, 0.14911), (0.70, 0.14059), (0.75, 0.13121), (0.80, 0.12301), (0.85, 0.11578)];

/// The compression to run.
#[derive(Debug, Clone, Copy)]
pub struct Uniaxial {
    pub lx: f64,
    pub ly: f64,
    /// Piston height of the start state [m].
    pub z_start: f64,
    /// Piston height of the last load step [m].
    pub z_end: f64,
    /// Number of equal load steps (step 0, the equilibrium at `z_start`, is returned as well).
    pub steps: usize,
    /// Material of every particle (replaces the spheres' own).
    pub particle: Material,
    pub wall: Material,
    /// V_s for φ [m³].
    pub solid_volume: f64,
}

impl Uniaxial {
    /// The hydrogel case (Table 1 of Ghods et al. 2022: E = 23.3 kPa, walls 50 MPa, ν_w = 0.5)
    /// with particle Poisson ratio `nu`, from the start height to φ = 0.85 in `steps` steps.
    pub fn hydrogel(nu: f64, steps: usize) -> Result<Self, String> {
        Ok(Self {
            lx: HYDROGEL_LX,
            ly: HYDROGEL_LY,
            z_start: HYDROGEL_Z_START,
            z_end: HYDROGEL_Z_PHI[4].1,
            steps,
            particle: Material::hertz(23.3e3, nu).map_err(|e| e.to_string())?,
            wall: Material::hertz(50e6, 0.5).map_err(|e| e.to_string())?,
            solid_volume: HYDROGEL_SOLID_VOLUME,
        })
    }

    /// Piston height after load step `k`.
    pub fn z_at(&self, k: usize) -> f64 {
        self.z_start + (self.z_end - self.z_start) * k as f64 / self.steps as f64
    }

    pub fn phi_at(&self, z: f64) -> f64 {
        self.solid_volume / (self.lx * self.ly * z)
    }
}

/// One converged load step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UniaxialPoint {
    pub step: usize,
    /// Piston height [m].
    pub z: f64,
    pub phi: f64,
    /// Piston force / (L_x L_y) [Pa].
    pub sigma_piston: f64,
    /// Bottom force / (L_x L_y) [Pa]; equal to `sigma_piston` up to the force-balance residual.
    pub sigma_bottom: f64,
    /// Mean normal stress on the four side walls [Pa] (force / (L_y z) or (L_x z)).
    pub sigma_side: f64,
    /// Loaded particle–particle and particle–wall contacts.
    pub contacts: usize,
    pub wall_contacts: usize,
    /// Newton iterations, FIRE steps and halvings spent on this step.
    pub iterations: usize,
    pub fire_steps: usize,
    pub subdivisions: usize,
    /// Force-balance residual (max |net force| / mean contact force) of the converged state.
    pub residual: f64,
    /// Wall time of the step [s].
    pub seconds: f64,
}

/// Compresses `start` (centres and radii; materials are replaced by `u.particle`) with the given
/// kernel; `progress` sees every converged point as soon as it exists.
pub fn compress_with(
    start: &[Sphere],
    u: &Uniaxial,
    kernel: Kernel,
    progress: &mut dyn FnMut(&UniaxialPoint),
) -> Result<Vec<UniaxialPoint>, SolveError> {
    let bad = |m: String| SolveError { message: m, residual: f64::NAN, worst_particle: None };
    if u.steps == 0 || !(u.z_start > 0.0 && u.z_end > 0.0 && u.lx > 0.0 && u.ly > 0.0) {
        return Err(bad("uniaxial: steps >= 1 and positive box dimensions are required".into()));
    }
    let spheres: Vec<Sphere> = start.iter().map(|s| Sphere { material: u.particle, ..*s }).collect();
    let walls = Wall::rigid_box(u.lx, u.ly, u.z_start, "piston");
    let settings = Settings { affine_predictor: true, fire_first: true, ..Settings::default() };
    let mut solver = Nonlocal::new(&spheres, &walls, u.wall, kernel, settings).map_err(bad)?;
    let points0: Vec<Vec3> = walls.iter().map(|w| w.point).collect();
    let load_at = |t: f64| {
        let mut p = points0.clone();
        p[5] = Vec3::new(0.0, 0.0, u.z_start + (u.z_end - u.z_start) * t);
        (p, 0.0)
    };
    let area = u.lx * u.ly;
    let mut out = Vec::with_capacity(u.steps + 1);
    for k in 0..=u.steps {
        let t1 = k as f64 / u.steps as f64;
        let t0 = if k == 0 { 0.0 } else { (k - 1) as f64 / u.steps as f64 };
        let clock = Instant::now();
        let st = solver.advance(&load_at, t0, t1).map_err(|e| SolveError {
            message: format!("uniaxial load step {k} (piston z = {:.6} m): {}", u.z_at(k), e.message),
            ..e
        })?;
        let f = solver.wall_forces();
        let ws = solver.walls();
        // (+ 0.0 turns the −0 of a force-free wall into 0.)
        let normal = |w: usize| -f[w].dot(&ws[w].normal) + 0.0;
        let z = u.z_at(k);
        let (mut pp, mut pw) = (0, 0);
        for c in solver.contacts() {
            if c.force > 0.0 {
                match c.other {
                    Other::Particle(_) => pp += 1,
                    Other::Wall(_) => pw += 1,
                }
            }
        }
        let p = UniaxialPoint {
            step: k,
            z,
            phi: u.phi_at(z),
            sigma_piston: normal(5) / area,
            sigma_bottom: normal(4) / area,
            sigma_side: 0.25 * ((normal(0) + normal(1)) / (u.ly * z) + (normal(2) + normal(3)) / (u.lx * z)),
            contacts: pp,
            wall_contacts: pw,
            iterations: st.newton_iterations,
            fire_steps: st.fire_steps,
            subdivisions: st.subdivisions,
            residual: st.residual,
            seconds: clock.elapsed().as_secs_f64(),
        };
        progress(&p);
        out.push(p);
    }
    Ok(out)
}

/// [`compress_with`] without progress reports.
pub fn compress(start: &[Sphere], u: &Uniaxial, kernel: Kernel) -> Result<Vec<UniaxialPoint>, SolveError> {
    compress_with(start, u, kernel, &mut |_| {})
}

/// σ at the given piston heights, linearly interpolated between load steps (for the φ table of
/// docs/nonlocal.md and the validation). `None` outside the computed range.
pub fn sigma_at_z(points: &[UniaxialPoint], z: f64) -> Option<f64> {
    points.windows(2).find_map(|w| {
        let (a, b) = (&w[0], &w[1]);
        let (lo, hi) = if a.z < b.z { (a, b) } else { (b, a) };
        (z >= lo.z && z <= hi.z).then(|| {
            let t = if hi.z > lo.z { (z - lo.z) / (hi.z - lo.z) } else { 0.0 };
            lo.sigma_piston + t * (hi.sigma_piston - lo.sigma_piston)
        })
    })
}

/// CSV of a compression: a `#` line naming kernel, ν and the start, then one row per load step.
pub fn write_csv(
    out: &mut dyn std::io::Write,
    points: &[UniaxialPoint],
    kernel: Kernel,
    u: &Uniaxial,
    start: &str,
) -> std::io::Result<()> {
    writeln!(
        out,
        "# mcdem uniaxial: kernel={} kernel_scale={} E={} nu={} wall_E={} wall_nu={} lx={} ly={} solid_volume={:e} steps={} start={start}",
        kernel.kind(),
        kernel.scale(),
        u.particle.youngs_modulus,
        u.particle.poisson_ratio,
        u.wall.youngs_modulus,
        u.wall.poisson_ratio,
        u.lx,
        u.ly,
        u.solid_volume,
        u.steps
    )?;
    writeln!(
        out,
        "step,z,phi,sigma_piston,sigma_bottom,sigma_side,contacts_pp,contacts_pw,newton_iterations,fire_steps,subdivisions,residual,seconds"
    )?;
    for p in points {
        writeln!(
            out,
            "{},{:.10e},{:.10e},{:.10e},{:.10e},{:.10e},{},{},{},{},{},{:.3e},{:.4}",
            p.step,
            p.z,
            p.phi,
            p.sigma_piston,
            p.sigma_bottom,
            p.sigma_side,
            p.contacts,
            p.wall_contacts,
            p.iterations,
            p.fire_steps,
            p.subdivisions,
            p.residual,
            p.seconds
        )?;
    }
    Ok(())
}
