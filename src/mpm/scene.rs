//! JSON scenes of `mcdem mpm`: one body (`"body"`) or several (`"bodies"`), discs/spheres or
//! blocks of one material, the grid resolution, the walls, the friction coefficients of Contact
//! Dynamics and the time stepping. Every value is validated with a message naming the problem.

use serde::Deserialize;

use super::constitutive::{Hooke, Law, NeoHookean, SaintVenantKirchhoff};
use super::contact::ContactOptions;
use super::grid::{Grid, Vector};
use super::implicit::{Body, Locking, Newton, StepOptions, Wall, WallsOn};
use super::packing::PackingSpec;
use super::points::Points;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// 2 (plane strain) or 3.
    pub dimension: usize,
    pub material: MaterialSpec,
    /// One body, or several in `bodies` (exactly one of the two).
    #[serde(default)]
    pub body: Option<BodySpec>,
    #[serde(default)]
    pub bodies: Option<Vec<BodySpec>>,
    /// Or a generated packing of discs (spheres) in a box.
    #[serde(default)]
    pub packing: Option<PackingSpec>,
    pub grid: GridSpec,
    #[serde(default)]
    pub walls: Vec<WallSpec>,
    /// Time step Δt [s].
    pub dt: f64,
    /// Number of steps.
    pub steps: usize,
    /// Write a row every this many steps (and the last one).
    #[serde(default = "one")]
    pub output_every: usize,
    #[serde(default)]
    pub gravity: Vec<f64>,
    #[serde(default)]
    pub newton: Option<NewtonSpec>,
    /// FLIP fraction of the point velocity update (1 = FLIP, 0 = PIC).
    #[serde(default = "one_f")]
    pub flip: f64,
    /// Volumetric-locking remedy: "none" or "fbar" (see `implicit::Locking`); absent: "none", as
    /// F-bar removes locking in the cantilever test but still stops in the line search on the
    /// disc-between-plates scenes (docs/mpm.md).
    #[serde(default)]
    pub locking: Option<String>,
    /// Contact Dynamics between bodies and with the walls (friction, stop rule).
    #[serde(default)]
    pub contact: Option<ContactSpec>,
    /// A step that does not converge is taken again as two steps of Δt/2, each cut again if it
    /// fails, at most this many times (Δt/16 by default; 0: a failed step stops the run).
    #[serde(default = "four")]
    pub step_cuts: u32,
    /// Where the walls act: "nodes" (Moreau's condition on grid nodes, Section 2.2) or "points"
    /// (no material point's domain crosses a wall; `implicit::WallsOn`). Absent: "nodes", the
    /// recorded scenes' treatment.
    #[serde(default)]
    pub walls_on: Option<String>,
    /// A packing in a box ends its run once its solid fraction Φ reaches this (Section 6.2
    /// compacts to Φ ≈ 0.97); absent: the run takes all its steps.
    #[serde(default)]
    pub until_phi: Option<f64>,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Coulomb coefficient body–wall (default 0).
    #[serde(default)]
    pub wall_friction: f64,
    /// Coulomb coefficient body–body (default 0).
    #[serde(default)]
    pub body_friction: f64,
    /// Stop rule of the contact iterations, in cells of relative nodal displacement per step.
    #[serde(default)]
    pub tolerance: Option<f64>,
    #[serde(default)]
    pub max_iter: Option<usize>,
}

fn one() -> usize {
    1
}
fn four() -> u32 {
    4
}

fn one_f() -> f64 {
    1.0
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// "hooke", "svk" or "neohookean".
    pub law: String,
    /// Lamé λ [Pa].
    pub lambda: f64,
    /// Shear modulus μ [Pa].
    pub mu: f64,
    /// Density ρ [kg/m³].
    pub density: f64,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "shape", rename_all = "lowercase", deny_unknown_fields)]
pub enum BodySpec {
    /// Disc (2-D) or sphere (3-D).
    Disc {
        center: Vec<f64>,
        radius: f64,
        /// Initial velocity of all its points [m/s] (default at rest).
        #[serde(default)]
        velocity: Vec<f64>,
    },
    Block {
        lo: Vec<f64>,
        hi: Vec<f64>,
        #[serde(default)]
        velocity: Vec<f64>,
    },
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// Cell size h [m].
    pub h: f64,
    /// Material points per cell and axis.
    pub points_per_cell: usize,
    /// Empty cells around the body's bounding box (room to deform into).
    #[serde(default = "three")]
    pub margin: usize,
}

fn three() -> usize {
    3
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    pub axis: usize,
    /// +1: the body is on the side of larger coordinates, −1: smaller.
    pub side: f64,
    pub position: f64,
    #[serde(default)]
    pub velocity: f64,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NewtonSpec {
    pub eps1: f64,
    pub eps2: f64,
    pub max_iter: usize,
}

/// Membership test of the body's shape.
type Inside<const D: usize> = Box<dyn Fn(&Vector<D>) -> bool>;

/// Everything a run needs, built from a validated scene.
pub struct Setup<const D: usize> {
    pub bodies: Vec<Body<D>>,
    pub walls: Vec<Wall>,
    pub options: StepOptions,
    pub contact: ContactOptions,
    /// See `Scene::step_cuts`.
    pub step_cuts: u32,
    /// The DEM preparation of a `"packing"` with `"compress"` (where it left the top wall).
    pub prepared: Option<super::packing_dem::Compressed>,
}

impl Scene {
    pub fn from_json(text: &str) -> Result<Self, String> {
        serde_json::from_str(text).map_err(|e| format!("scene: {e}"))
    }

    pub fn law(&self) -> Result<Law, String> {
        let m = &self.material;
        if !(m.density.is_finite() && m.density > 0.0) {
            return Err(format!("material: density must be positive, got {}", m.density));
        }
        let (l, mu) = (m.lambda, m.mu);
        Ok(match m.law.as_str() {
            "hooke" => Law::Hooke(Hooke::new(l, mu)?),
            "svk" => Law::SaintVenantKirchhoff(SaintVenantKirchhoff::new(l, mu)?),
            "neohookean" => Law::NeoHookean(NeoHookean::new(l, mu)?),
            other => return Err(format!("material: unknown law \"{other}\" (hooke, svk, neohookean)")),
        })
    }

    /// Validates the scene and builds the body, its grid and walls.
    pub fn setup<const D: usize>(&self) -> Result<Setup<D>, String> {
        if self.dimension != D {
            return Err(format!("dimension must be 2 or 3, got {}", self.dimension));
        }
        let law = self.law()?;
        let g = &self.grid;
        if !(g.h.is_finite() && g.h > 0.0) {
            return Err(format!("grid: cell size h must be positive, got {}", g.h));
        }
        if g.points_per_cell == 0 {
            return Err("grid: points_per_cell must be at least 1".into());
        }
        if !(self.dt.is_finite() && self.dt > 0.0) {
            return Err(format!("dt must be positive, got {}", self.dt));
        }
        if self.steps == 0 || self.output_every == 0 {
            return Err("steps and output_every must be at least 1".into());
        }
        if !(0.0..=1.0).contains(&self.flip) {
            return Err(format!("flip must lie in [0, 1], got {}", self.flip));
        }
        let (generated, prepared) = match &self.packing {
            Some(p) if self.body.is_none() && self.bodies.is_none() => {
                let packed = p.packed::<D>()?;
                let discs = packed
                    .discs
                    .into_iter()
                    .map(|(center, radius)| BodySpec::Disc { center, radius, velocity: Vec::new() })
                    .collect();
                (discs, packed.compressed)
            }
            Some(_) => return Err("scene: give one of \"body\", \"bodies\" or \"packing\", not both".into()),
            None => (Vec::new(), None),
        };
        let specs: Vec<&BodySpec> = match (&self.body, &self.bodies) {
            _ if !generated.is_empty() => generated.iter().collect(),
            (Some(b), None) => vec![b],
            (None, Some(v)) if !v.is_empty() => v.iter().collect(),
            (None, Some(_)) => return Err("bodies: the list is empty".into()),
            (None, None) => return Err("scene: give \"body\", \"bodies\" or \"packing\"".into()),
            (Some(_), Some(_)) => return Err("scene: give either \"body\" or \"bodies\", not both".into()),
        };
        let mut bodies = Vec::new();
        let mut shapes: Vec<Inside<D>> = Vec::new();
        // The first body's grid origin anchors the common lattice of all proper grids (Section 2.2).
        let mut anchor: Option<Vector<D>> = None;
        for (b, spec) in specs.iter().enumerate() {
            let vec = |v: &[f64], what: &str| -> Result<Vector<D>, String> {
                if v.len() != D || v.iter().any(|x| !x.is_finite()) {
                    return Err(format!("body {b}: {what} needs {D} finite coordinates, got {v:?}"));
                }
                Ok(Vector::<D>::from_fn(|d, _| v[d]))
            };
            let (lo, hi, inside, velocity): (Vector<D>, Vector<D>, Inside<D>, &Vec<f64>) = match spec {
                BodySpec::Disc { center, radius, velocity } => {
                    let c = vec(center, "center")?;
                    if !(radius.is_finite() && *radius > 0.0) {
                        return Err(format!("body {b}: radius must be positive, got {radius}"));
                    }
                    let r = *radius;
                    (
                        c.add_scalar(-r),
                        c.add_scalar(r),
                        Box::new(move |x: &Vector<D>| (x - c).norm() < r),
                        velocity,
                    )
                }
                BodySpec::Block { lo, hi, velocity } => {
                    let (l, h) = (vec(lo, "lo")?, vec(hi, "hi")?);
                    if (0..D).any(|d| h[d] <= l[d]) {
                        return Err(format!("body {b}: block hi {hi:?} must exceed lo {lo:?} on every axis"));
                    }
                    (
                        l,
                        h,
                        Box::new(move |x: &Vector<D>| (0..D).all(|d| x[d] > l[d] && x[d] < h[d])),
                        velocity,
                    )
                }
            };
            let v0 = if velocity.is_empty() { Vector::<D>::zeros() } else { vec(velocity, "velocity")? };
            // The grid starts at the body's lower corner minus the margin (on the common lattice),
            // so that a body resting on a wall through its bounding box has that wall on a grid line.
            let m = g.margin as f64 * g.h;
            let a0 = *anchor.get_or_insert(lo.add_scalar(-m));
            let origin = Vector::<D>::from_fn(|d, _| a0[d] + ((lo[d] - m - a0[d]) / g.h).floor() * g.h);
            let cells: [usize; D] =
                std::array::from_fn(|d| ((hi[d] + m - origin[d]) / g.h - 1e-9).ceil() as usize);
            let grid = Grid::new(origin, g.h, cells)?;
            let mut points =
                Points::seed(lo, hi, origin, g.h, g.points_per_cell, self.material.density, &inside);
            if points.is_empty() {
                return Err(format!("body {b}: no material point falls inside the body (refine the grid)"));
            }
            points.v.iter_mut().for_each(|v| *v = v0);
            bodies.push(Body { grid, points, law });
            shapes.push(inside);
        }
        // Bodies must not overlap at start: no point of one inside the shape of another.
        for (a, body) in bodies.iter().enumerate() {
            for (b, inside) in shapes.iter().enumerate() {
                if a == b {
                    continue;
                }
                if let Some(p) = body.points.x.iter().position(inside) {
                    return Err(format!(
                        "bodies {a} and {b} overlap at start: material point {p} of body {a} at {:?} lies inside body {b}",
                        body.points.x[p].as_slice()
                    ));
                }
            }
        }
        let walls_on = match self.walls_on.as_deref() {
            None | Some("nodes") => WallsOn::Nodes,
            Some("points") => WallsOn::Points,
            Some(other) => return Err(format!("walls_on: unknown value \"{other}\" (nodes, points)")),
        };
        // A DEM-compressed packing moves the top wall (the high side of the last axis, at the
        // packing box's top) to where the DEM left it.
        let mut wall_specs = self.walls.clone();
        if let (Some(c), Some(p)) = (&prepared, &self.packing) {
            let top = p.hi[D - 1];
            let w = wall_specs
                .iter_mut()
                .find(|w| w.axis == D - 1 && w.side == -1.0 && (w.position - top).abs() <= 1e-12 * top.abs().max(1e-3))
                .ok_or_else(|| {
                    format!(
                        "packing: compress needs a wall on axis {} with side -1 at the packing's top hi[{}] = {top} (the wall the DEM moves)",
                        D - 1,
                        D - 1
                    )
                })?;
            w.position = c.top;
        }
        let mut walls = Vec::new();
        for (w, ws) in wall_specs.iter().enumerate() {
            if ws.axis >= D || !(ws.side == 1.0 || ws.side == -1.0) {
                return Err(format!(
                    "wall {w}: axis must be below {D} and side ±1 (got axis {}, side {})",
                    ws.axis, ws.side
                ));
            }
            if !ws.position.is_finite() || !ws.velocity.is_finite() {
                return Err(format!("wall {w}: position and velocity must be finite"));
            }
            for (b, body) in bodies.iter().enumerate() {
                let points = &body.points;
                if let Some(p) = points.x.iter().position(|x| ws.side * (x[ws.axis] - ws.position) < 0.0) {
                    return Err(format!(
                        "wall {w}: material point {p} of body {b} at {:?} starts on the wrong side of the wall (overlap at start)",
                        points.x[p].as_slice()
                    ));
                }
                // On the points, a point's domain (its sub-cell, half-size l/2) must start on the
                // body's side too; a round-off of the lattice is allowed.
                if walls_on == WallsOn::Points {
                    let half = |p: usize| 0.5 * points.vol0[p].powf(1.0 / D as f64);
                    if let Some(p) = (0..points.len())
                        .find(|&p| ws.side * (points.x[p][ws.axis] - ws.position) - half(p) < -1e-9 * g.h)
                    {
                        return Err(format!(
                            "wall {w}: the domain of material point {p} of body {b} at {:?} (half-size {:.3e} m) starts past the wall (walls_on = \"points\"; overlap at start)",
                            points.x[p].as_slice(),
                            half(p)
                        ));
                    }
                }
            }
            walls.push(Wall { axis: ws.axis, side: ws.side, position: ws.position, velocity: ws.velocity });
        }
        let mut gravity = [0.0; 3];
        if !self.gravity.is_empty() {
            if self.gravity.len() != D {
                return Err(format!("gravity needs {D} components, got {}", self.gravity.len()));
            }
            gravity[..D].copy_from_slice(&self.gravity);
        }
        let newton = match &self.newton {
            None => Newton::default(),
            Some(n) => {
                if !(n.eps1 > 0.0 && n.eps2 > 0.0 && n.max_iter > 0) {
                    return Err("newton: eps1, eps2 and max_iter must be positive".into());
                }
                Newton { eps1: n.eps1, eps2: n.eps2, max_iter: n.max_iter }
            }
        };
        let locking = match self.locking.as_deref() {
            None | Some("none") => Locking::None,
            Some("fbar") => Locking::FBar,
            Some(other) => return Err(format!("locking: unknown value \"{other}\" (fbar, none)")),
        };
        let mut contact = ContactOptions::default();
        if let Some(c) = &self.contact {
            contact.wall_friction = c.wall_friction;
            contact.body_friction = c.body_friction;
            contact.tolerance = c.tolerance.unwrap_or(contact.tolerance);
            contact.max_iter = c.max_iter.unwrap_or(contact.max_iter);
        }
        contact.validate()?;
        if walls_on == WallsOn::Points && contact.wall_friction != 0.0 {
            return Err(format!(
                "contact.wall_friction = {} is not built with walls_on = \"points\" (frictionless walls only); set it to 0 or use walls_on = \"nodes\"",
                contact.wall_friction
            ));
        }
        if let Some(u) = self.until_phi {
            if !(u > 0.0 && u <= 1.0) {
                return Err(format!("until_phi must lie in (0, 1], got {u}"));
            }
            // The same condition under which `mcdem mpm` measures Φ (`compaction::box_walls`).
            if bodies.len() < 2 || super::compaction::box_walls::<D>(&walls).is_none() {
                return Err(
                    "until_phi needs several bodies in a box: a wall on each side of every axis (a packing's Φ)".into()
                );
            }
        }
        if self.step_cuts > 20 {
            return Err(format!(
                "step_cuts must be at most 20 (a step of Δt/2^20 is round-off for any scene), got {}",
                self.step_cuts
            ));
        }
        Ok(Setup {
            bodies,
            walls,
            options: StepOptions { dt: self.dt, gravity, newton, flip: self.flip, locking, walls_on },
            contact,
            step_cuts: self.step_cuts,
            prepared,
        })
    }
}
