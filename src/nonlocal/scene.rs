//! Scene files for `mcdem nonlocal SCENE` (format in `docs/nonlocal.md`), the LIGGGHTS data-file
//! reader, and the driver that walks the loading path and writes one CSV row per load step.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Deserialize;

use super::kernel::{Kernel, KernelKind};
use super::solver::{Nonlocal, Other, Settings, Sphere, StepStats, Wall};
use crate::physics::material::Material;
use crate::physics::Vec3;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    pub x: [f64; 3],
    pub radius: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    pub name: String,
    /// A point of the plane at the start of the loading path [m].
    pub point: [f64; 3],
    /// Normal pointing into the domain (normalised on reading).
    pub normal: [f64; 3],
    /// Total displacement of the wall over the loading path [m] (linear in the step index).
    #[serde(default)]
    pub displacement: Option<[f64; 3]>,
}

/// A scene as written in JSON.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// LIGGGHTS data file (`Atoms` lines `id type diameter density x y z`), relative to the scene file.
    #[serde(default)]
    pub liggghts_data: Option<PathBuf>,
    /// LIGGGHTS/mcdem `dump custom` file with columns `id radius x y z` (any order, more allowed;
    /// the last frame is used), relative to the scene file. Alternative to `liggghts_data`.
    #[serde(default)]
    pub liggghts_dump: Option<PathBuf>,
    /// Inline spheres (used when `liggghts_data` is absent).
    #[serde(default)]
    pub spheres: Option<Vec<SphereSpec>>,
    pub particle_material: MaterialSpec,
    pub wall_material: MaterialSpec,
    /// `boussinesq` (default), `sphere` (finite elastic sphere, docs/spec.md §4.1) or `none` (pure Hertz).
    #[serde(default = "default_kernel")]
    pub kernel: String,
    /// Prefactor of the kernel (γ in "kernel γ·G"); 1 for the reference.
    #[serde(default = "one")]
    pub kernel_scale: f64,
    pub walls: Vec<WallSpec>,
    /// Number of load steps of the path (≥ 1); step 0, the initial equilibrium, is written too.
    pub steps: usize,
    /// Solid volume for φ [m³]; default: the sum of the sphere volumes.
    #[serde(default)]
    pub solid_volume: Option<f64>,
    /// Gravity [m/s²]: with it, step 0 is the equilibrium under gravity (a packing settled in a
    /// DEM run), then `gravity_release_steps` steps ramp it to zero with the walls fixed, then the
    /// loading path runs. With `gravity_release_steps` = 0 gravity stays on throughout.
    #[serde(default)]
    pub gravity: Option<[f64; 3]>,
    #[serde(default)]
    pub gravity_release_steps: usize,
    /// Particle density [kg/m³] for inline spheres (data files carry their own).
    #[serde(default)]
    pub density: Option<f64>,
    /// Pre-relax the initial packing by FIRE with plain Hertz contacts before step 0 (for snapshots
    /// that are not at rest): maximum FIRE steps (0 = off).
    #[serde(default)]
    pub prerelax_steps: usize,
    #[serde(default)]
    pub tolerance: Option<f64>,
    #[serde(default)]
    pub max_subdivisions: Option<u32>,
    /// Affine predictor for the load increments (see `Settings::affine_predictor`).
    #[serde(default)]
    pub affine_predictor: bool,
    /// FIRE before Newton at every increment (see `Settings::fire_first`).
    #[serde(default)]
    pub fire_first: bool,
}

fn default_kernel() -> String {
    "boussinesq".into()
}

fn one() -> f64 {
    1.0
}

/// Reads the atoms of a LIGGGHTS data file (atom_style sphere) with the crate's one data-file
/// reader ([`crate::deck::data_file`]). Every particle gets `material`. Returns the spheres and
/// their densities.
pub fn read_liggghts_data(path: &Path, material: Material) -> Result<(Vec<Sphere>, Vec<f64>), String> {
    let d = crate::deck::data_file::read(path)?;
    let mut out = Vec::with_capacity(d.atoms.len());
    let mut densities = Vec::with_capacity(d.atoms.len());
    for a in &d.atoms {
        let bad = |what: &str| format!("{}: atom {}: {what}", path.display(), a.id);
        if a.diameter <= 0.0 {
            return Err(bad("diameter must be > 0"));
        }
        if a.density <= 0.0 {
            return Err(bad("density must be > 0"));
        }
        let id = u64::try_from(a.id).map_err(|_| bad("bad atom id"))?;
        out.push(Sphere { id, x: Vec3::new(a.x[0], a.x[1], a.x[2]), radius: 0.5 * a.diameter, material });
        densities.push(a.density);
    }
    Ok((out, densities))
}

/// Reads the last frame of a LIGGGHTS `dump custom` text file (with the crate's one dump reader,
/// [`crate::outputs::read_dump`]) that has the columns `id`, `radius` (or `diameter`), `x`, `y`,
/// `z` (any order, other columns ignored), e.g. the state written by `liggghts_inputs/hydrogel.in`
/// with `-var statestroke N`. Every particle gets `material`.
pub fn read_liggghts_dump(path: &Path, material: Material) -> Result<Vec<Sphere>, String> {
    let frame = crate::outputs::read_dump(path)?
        .pop()
        .ok_or_else(|| format!("{}: no 'ITEM: TIMESTEP' frame", path.display()))?;
    let need = |name: &str| {
        frame.column(name).ok_or_else(|| format!("{}: dump has no '{name}' column", path.display()))
    };
    let (ci, cx, cy, cz) = (need("id")?, need("x")?, need("y")?, need("z")?);
    let (cr, scale) = match (frame.column("radius"), frame.column("diameter")) {
        (Some(c), _) => (c, 1.0),
        (None, Some(c)) => (c, 0.5),
        _ => return Err(format!("{}: dump has neither 'radius' nor 'diameter'", path.display())),
    };
    let mut out = Vec::with_capacity(frame.rows.len());
    for (k, row) in frame.rows.iter().enumerate() {
        let v = row[ci];
        if !(v >= 0.0 && v.fract() == 0.0) {
            return Err(format!("{} frame line {}: bad atom id {v}", path.display(), k + 1));
        }
        let id = v as u64;
        let radius = scale * row[cr];
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(format!("{}: particle {id}: radius must be > 0", path.display()));
        }
        let x = Vec3::new(row[cx], row[cy], row[cz]);
        if !x.iter().all(|c| c.is_finite()) {
            return Err(format!("{}: particle {id}: non-finite position", path.display()));
        }
        out.push(Sphere { id, x, radius, material });
    }
    Ok(out)
}

/// An axis-aligned box found among the walls: for each axis the indices of the low and high wall.
#[derive(Debug, Clone, Copy)]
struct BoxWalls {
    pairs: [(usize, usize); 3],
}

fn find_box(walls: &[Wall]) -> Option<BoxWalls> {
    let mut pairs = [(usize::MAX, usize::MAX); 3];
    for (w, wall) in walls.iter().enumerate() {
        for (a, pair) in pairs.iter_mut().enumerate() {
            let c = wall.normal[a];
            if c > 1.0 - 1e-12 {
                if pair.0 != usize::MAX {
                    return None;
                }
                pair.0 = w;
            } else if c < -(1.0 - 1e-12) {
                if pair.1 != usize::MAX {
                    return None;
                }
                pair.1 = w;
            }
        }
    }
    pairs.iter().all(|p| p.0 != usize::MAX && p.1 != usize::MAX).then_some(BoxWalls { pairs })
}

fn box_lengths(b: &BoxWalls, walls: &[Wall]) -> [f64; 3] {
    std::array::from_fn(|a| {
        let (lo, hi) = b.pairs[a];
        walls[hi].point[a] - walls[lo].point[a]
    })
}

/// What a run produced.
#[derive(Debug, Clone)]
pub struct RunSummary {
    pub steps: usize,
    pub wall_seconds: f64,
    pub final_phi: Option<f64>,
    pub final_wall_forces: Vec<(String, f64)>,
}

/// A loaded scene ready to run.
pub struct Scene {
    pub spec: SceneSpec,
    pub solver: Nonlocal,
    walls0: Vec<Wall>,
    solid_volume: f64,
}

fn material(m: &MaterialSpec, what: &str) -> Result<Material, String> {
    Material::hertz(m.youngs_modulus, m.poisson_ratio).map_err(|e| format!("{what}: {e}"))
}

impl Scene {
    /// Parses and validates a scene; relative paths are taken relative to `base`.
    pub fn from_json(text: &str, base: &Path) -> Result<Self, String> {
        let spec: SceneSpec = serde_json::from_str(text).map_err(|e| format!("scene: {e}"))?;
        let pm = material(&spec.particle_material, "particle_material")?;
        let wm = material(&spec.wall_material, "wall_material")?;
        let resolve = |p: &PathBuf| if p.is_absolute() { p.clone() } else { base.join(p) };
        let (spheres, densities) = match (&spec.liggghts_data, &spec.liggghts_dump, &spec.spheres) {
            (Some(p), None, None) => read_liggghts_data(&resolve(p), pm)?,
            (None, Some(p), None) => {
                let s = read_liggghts_dump(&resolve(p), pm)?;
                let d = vec![spec.density.unwrap_or(f64::NAN); s.len()];
                (s, d)
            }
            (None, None, Some(s)) => (
                s.iter()
                    .enumerate()
                    .map(|(k, s)| Sphere {
                        id: k as u64 + 1,
                        x: Vec3::from(s.x),
                        radius: s.radius,
                        material: pm,
                    })
                    .collect::<Vec<_>>(),
                vec![spec.density.unwrap_or(f64::NAN); s.len()],
            ),
            _ => {
                return Err("scene: give exactly one of 'liggghts_data', 'liggghts_dump' and 'spheres'".into())
            }
        };
        if spec.steps == 0 {
            return Err("scene: 'steps' must be >= 1".into());
        }
        let kind: KernelKind = spec.kernel.parse()?;
        let kernel = Kernel::new(kind, spec.kernel_scale)?;
        let mut walls0 = Vec::new();
        for w in &spec.walls {
            if let Some(d) = w.displacement {
                if d.iter().any(|v| !v.is_finite()) {
                    return Err(format!("wall '{}': displacement must be finite", w.name));
                }
            }
            walls0.push(Wall {
                name: w.name.clone(),
                point: Vec3::from(w.point),
                normal: Vec3::from(w.normal),
            });
        }
        let mut settings = Settings::default();
        if let Some(t) = spec.tolerance {
            if !(t.is_finite() && t > 0.0 && t <= 1e-9) {
                return Err(format!("scene: tolerance {t} must be in (0, 1e-9]"));
            }
            settings.tolerance = t;
        }
        if let Some(m) = spec.max_subdivisions {
            settings.max_subdivisions = m;
        }
        settings.affine_predictor = spec.affine_predictor;
        settings.fire_first = spec.fire_first;
        let solid_volume = match spec.solid_volume {
            Some(v) if v.is_finite() && v > 0.0 => v,
            Some(v) => return Err(format!("scene: solid_volume {v} must be finite and > 0")),
            None => spheres.iter().map(|s| 4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3)).sum(),
        };
        let mut solver = Nonlocal::new(&spheres, &walls0, wm, kernel, settings)?;
        if let Some(g) = spec.gravity {
            let g = Vec3::from(g);
            if !g.iter().all(|v| v.is_finite()) {
                return Err("scene: gravity must be finite".into());
            }
            if densities.iter().any(|d| !(d.is_finite() && *d > 0.0)) {
                return Err(
                    "scene: gravity needs a density > 0 for every particle ('density' for inline spheres)"
                        .into(),
                );
            }
            let weights: Vec<Vec3> = spheres
                .iter()
                .zip(&densities)
                .map(|(s, d)| g * (d * 4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3)))
                .collect();
            solver.set_body_forces(&weights)?;
        }
        let walls0 = solver.walls();
        Ok(Self { spec, solver, walls0, solid_volume })
    }

    pub fn load(path: &Path) -> Result<Self, String> {
        let text =
            std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        Self::from_json(&text, path.parent().unwrap_or(Path::new(".")))
    }

    /// Start points and total displacements of the walls: the point at loading parameter
    /// t ∈ [0, 1] is start + t · displacement.
    fn path(&self) -> Vec<(Vec3, Vec3)> {
        self.walls0
            .iter()
            .zip(&self.spec.walls)
            .map(|(w, s)| (w.point, s.displacement.map(Vec3::from).unwrap_or_else(Vec3::zeros)))
            .collect()
    }

    /// Runs the whole path, writing the per-step CSV to `out` and, if `contacts_dir` is given, one
    /// contact file per step. `progress` receives one line per load step.
    pub fn run(
        &mut self,
        out: &mut dyn Write,
        contacts_dir: Option<&Path>,
        progress: &mut dyn FnMut(&str),
    ) -> Result<RunSummary, String> {
        let start = Instant::now();
        let walls = self.solver.walls();
        let bx = find_box(&walls);
        let io = |e: std::io::Error| format!("cannot write output: {e}");
        let k = self.solver.kernel();
        writeln!(
            out,
            "# mcdem nonlocal: kernel={} kernel_scale={} particles={} tolerance={:e} solid_volume={:e}",
            k.kind(),
            k.scale(),
            self.solver.particle_count(),
            self.spec.tolerance.unwrap_or(Settings::default().tolerance),
            self.solid_volume
        )
        .map_err(io)?;
        let mut header =
            String::from("step,t,gravity_factor,phi,coordination,contacts_pp,contacts_pw,newton_iterations,active_set_rounds,subdivisions,fire_steps,residual,relation_residual,seconds");
        for w in &walls {
            header.push_str(&format!(",{0}_position,{0}_force,{0}_stress", w.name));
        }
        writeln!(out, "{header}").map_err(io)?;
        if let Some(d) = contacts_dir {
            std::fs::create_dir_all(d).map_err(|e| format!("cannot create {}: {e}", d.display()))?;
        }
        let steps = self.spec.steps;
        let release = if self.spec.gravity.is_some() { self.spec.gravity_release_steps } else { 0 };
        let gravity_on = self.spec.gravity.is_some();
        let total = release + steps;
        let path = self.path();
        // Load parameter u ∈ [0, release + steps]: first gravity 1 → 0 with fixed walls, then the path.
        let load_at = |u: f64| {
            let t = ((u - release as f64) / steps as f64).clamp(0.0, 1.0);
            let factor = match (gravity_on, release) {
                (false, _) => 0.0,
                (true, 0) => 1.0,
                (true, r) => (1.0 - u / r as f64).max(0.0),
            };
            (path.iter().map(|(p, d)| p + t * d).collect::<Vec<Vec3>>(), factor)
        };
        let mut summary =
            RunSummary { steps: total, wall_seconds: 0.0, final_phi: None, final_wall_forces: Vec::new() };
        if self.spec.prerelax_steps > 0 {
            let (points, factor) = load_at(0.0);
            for (w, p) in points.into_iter().enumerate() {
                self.solver.set_wall_point(w, p);
            }
            self.solver.set_body_force_factor(factor);
            let t = Instant::now();
            let (n, rel) = self.solver.relax_hertz(self.spec.prerelax_steps, 1e-4);
            progress(&format!(
                "pre-relaxation (FIRE, Hertz): {n} steps, residual {rel:.2e} ({:.2} s)",
                t.elapsed().as_secs_f64()
            ));
        }
        for step in 0..=total {
            let u1 = step as f64;
            let u0 = if step == 0 { 0.0 } else { u1 - 1.0 };
            let (_, gfac) = load_at(u1);
            let t1 = ((u1 - release as f64) / steps as f64).clamp(0.0, 1.0);
            let t_step = Instant::now();
            let stats: StepStats = self
                .solver
                .advance(&load_at, u0, u1)
                .map_err(|e| format!("load step {step} (t = {t1:.6}) did not converge: {e}"))?;
            let secs = t_step.elapsed().as_secs_f64();
            let walls = self.solver.walls();
            let forces = self.solver.wall_forces();
            let lengths = bx.map(|b| box_lengths(&b, &walls));
            let phi = lengths.map(|l| self.solid_volume / (l[0] * l[1] * l[2]));
            let (pp, pw) = self.solver.contact_counts();
            let z = 2.0 * pp as f64 / self.solver.particle_count() as f64;
            let fmt_opt = |v: Option<f64>| v.map(|v| format!("{v:.10e}")).unwrap_or_default();
            let mut row = format!(
                "{step},{t1:.8},{gfac:.6},{},{z:.6},{pp},{pw},{},{},{},{},{:.3e},{:.3e},{secs:.4}",
                fmt_opt(phi),
                stats.newton_iterations,
                stats.active_set_rounds,
                stats.subdivisions,
                stats.fire_steps,
                stats.residual,
                stats.relation_residual
            );
            let mut wf = Vec::new();
            for (w, wall) in walls.iter().enumerate() {
                // Normal force the particles exert on the wall, positive when they push it outward.
                let fnorm = -forces[w].dot(&wall.normal);
                let area = lengths.and_then(|l| {
                    (0..3)
                        .find(|&a| wall.normal[a].abs() > 1.0 - 1e-12)
                        .map(|a| l[(a + 1) % 3] * l[(a + 2) % 3])
                });
                let stress = area.map(|a| fnorm / a);
                row.push_str(&format!(
                    ",{:.10e},{fnorm:.10e},{}",
                    wall.point.dot(&wall.normal),
                    fmt_opt(stress)
                ));
                wf.push((wall.name.clone(), fnorm));
            }
            writeln!(out, "{row}").map_err(io)?;
            if let Some(d) = contacts_dir {
                self.write_contacts(&d.join(format!("contacts_{step:05}.csv")), &walls)?;
            }
            progress(&format!(
                "step {step}/{total}: phi {} Z {z:.3} newton {} rounds {} halvings {} fire {} residual {:.2e} ({secs:.2} s)",
                phi.map(|p| format!("{p:.4}")).unwrap_or_else(|| "-".into()),
                stats.newton_iterations,
                stats.active_set_rounds,
                stats.subdivisions,
                stats.fire_steps,
                stats.residual
            ));
            summary.final_phi = phi;
            summary.final_wall_forces = wf;
        }
        summary.wall_seconds = start.elapsed().as_secs_f64();
        Ok(summary)
    }

    fn write_contacts(&self, path: &Path, walls: &[Wall]) -> Result<(), String> {
        let io = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
        let mut f = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
        let ids = self.solver.ids();
        writeln!(f, "id_i,other,force,overlap,hertz_overlap,dir_x,dir_y,dir_z").map_err(io)?;
        for c in self.solver.contacts() {
            let other = match c.other {
                Other::Particle(j) => ids[j].to_string(),
                Other::Wall(w) => format!("wall:{}", walls[w].name),
            };
            writeln!(
                f,
                "{},{other},{:.10e},{:.10e},{:.10e},{:.8},{:.8},{:.8}",
                ids[c.i], c.force, c.overlap, c.hertz_overlap, c.direction.x, c.direction.y, c.direction.z
            )
            .map_err(io)?;
        }
        Ok(())
    }
}
