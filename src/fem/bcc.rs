//! The bcc cell of Ghods et al. (2022) App. B (Fig. B.2b) by finite elements: nine spheres of
//! radius r in a rigid frictionless cubic die of side L = 2r (1 + 2/√3), eight at the corners
//! (each touching three walls and the centre sphere) and one at the centre, compressed by the top
//! plate. The geometry of `validate`'s `bcc` case (`liggghts_inputs/bcc_box.in`).
//!
//! Symmetry: with frictionless walls the quasi-static solution with the bottom plate fixed and the
//! top plate moved by Δ is, up to a rigid translation, the one with both plates moved by Δ/2, which
//! is symmetric about the three mid-planes x, y, z = L/2. One octant box [0, L/2]³ is therefore the
//! whole problem: one corner sphere, whole, against the walls x = 0, y = 0 and the plate z = Δ/2
//! (and, as rigid planes, the mid-planes: contact with its mirror images), and the octant of the
//! centre sphere that lies in the box, its cut faces held by u·n = 0. The corner–centre contact is
//! the body–body contact of `surface`, the gap measured along the line of centres. Wall forces of
//! the die are four times the octant's (the octant box holds a quarter of each wall); stresses are
//! wall force / L², the convention of `validate::die`.
//!
//! The meshes are graded towards the poles (the wall contacts) and towards the diagonal (the
//! corner–centre contact), `mesh::Grading::PolesAndDiagonal`.

use super::material::Lame;
use super::mesh::{sphere_octant_graded, Grading};
use super::octant::{load_path, SphereRun, Walls};
use super::solver::{Plane, Problem, Settings};
use super::surface::{boundary_faces, SurfacePair};

/// Penalty of the corner–centre contact in units of E/h (`SurfacePair::new`).
const PENALTY_FACTOR: f64 = 100.0;

/// Proximal regularisation (`Settings::proximal`, units of E L): the corner sphere is held only by
/// frictionless contacts, single nodes at the first load step, which leave its rotations free.
const PROXIMAL: f64 = 1e-9;

/// Newton's tolerance relative to the largest reaction. The die's 1e-9 cannot be reached here:
/// where a slave node crosses a master face edge the gap's slope jumps, and the free residual then
/// cycles between two values at 1e-6 … 5e-5 of the reaction (measured at 4 intervals) instead of
/// falling. An equilibrium defect of 1e-4 of the largest reaction, at a few nodes, moves the wall
/// forces by about as much, far below the meshes' discretisation error (percent).
const RTOL: f64 = 1e-4;

/// Specification of one bcc run: the spheres, mesh and load path of a die run (`walls` must be
/// `Die`; `intervals` even, the grading refines both ends of each edge; `delta_over_r` the
/// top-plate travel).
#[derive(Clone, Debug)]
pub struct BccRun {
    pub spec: SphereRun,
}

/// One reported point of the bcc cell.
#[derive(Clone, Copy, Debug)]
pub struct BccPoint {
    pub delta_over_r: f64,
    /// Forces on the whole die's plate and on one side wall [N], and their stresses force / L² [Pa].
    pub plate_force: f64,
    pub side_force: f64,
    pub plate_stress: f64,
    pub side_stress: f64,
    /// Force of one corner–centre contact on the corner sphere [N].
    pub contact: [f64; 3],
    /// Nodes of the octant in contact with the plate, the x side wall, and the centre sphere.
    pub plate_nodes: usize,
    pub side_nodes: usize,
    pub contact_nodes: usize,
}

impl BccRun {
    /// Side of the die, L = 2r (1 + 2/√3): the corner spheres touch the centre one.
    pub fn side(&self) -> f64 {
        2.0 * self.spec.radius * (1.0 + 2.0 / 3f64.sqrt())
    }

    /// Checks the inputs; every message names the offending field.
    pub fn check(&self) -> Result<(), String> {
        self.spec.check()?;
        if self.spec.walls != Walls::Die {
            return Err("the bcc cell is a die: walls must be die".into());
        }
        if self.spec.intervals % 2 != 0 {
            return Err(format!(
                "mesh intervals per block edge must be even for the bcc cell (graded at both ends), got {}",
                self.spec.intervals
            ));
        }
        Ok(())
    }

    /// The boundary-value problem at zero load: the corner sphere's nodes first, then the centre
    /// octant's.
    pub fn problem(&self) -> Result<Problem, String> {
        let (r, half) = (self.spec.radius, 0.5 * self.side());
        let tol = 1e-9 * r;
        let octant = sphere_octant_graded(r, self.spec.intervals, Grading::PolesAndDiagonal);
        let corner = octant.whole_from_octant(tol).translated([r, r, r]);
        let centre = octant.mirrored(0, 0.0).mirrored(1, 0.0).mirrored(2, 0.0).translated([half; 3]);
        let mesh = corner.joined(&centre);
        let (nc, ec) = (corner.x.len(), corner.hex.len());
        let on_cut = |x: &[f64; 3], k: usize| (x[k] - half).abs() < tol;
        let mut fixed = Vec::new();
        for (i, x) in mesh.x.iter().enumerate().skip(nc) {
            for k in 0..3 {
                if on_cut(x, k) {
                    fixed.push((3 * i + k, 0.0));
                }
            }
        }
        let slave = boundary_faces(&mesh, 0..ec);
        let master: Vec<[usize; 4]> = boundary_faces(&mesh, ec..mesh.hex.len())
            .into_iter()
            .filter(|f| !(0..3).any(|k| f.iter().all(|&i| on_cut(&mesh.x[i], k))))
            .collect();
        let d = -1.0 / 3f64.sqrt();
        let pair = SurfacePair::new(
            &mesh,
            &slave,
            master,
            [d; 3],
            0.5 * r,
            self.spec.youngs_modulus,
            PENALTY_FACTOR,
        )
        .map_err(|e| format!("bcc corner-centre contact: {e}"))?;
        let plane = |axis, pos, upper| Plane { axis, pos, upper };
        Ok(Problem {
            mesh,
            law: self.spec.law,
            lame: Lame::from_e_nu(self.spec.youngs_modulus, self.spec.poisson_ratio),
            vol: self.spec.vol,
            fixed,
            // Plate, the two side walls, then the mid-planes (the corner sphere's mirror images).
            planes: vec![
                plane(2, 0.0, false),
                plane(0, 0.0, false),
                plane(1, 0.0, false),
                plane(0, half, true),
                plane(1, half, true),
                plane(2, half, true),
            ],
            pairs: vec![pair],
        })
    }

    /// Runs the load path; `progress` sees every reported point.
    pub fn run(&self, mut progress: impl FnMut(&BccPoint)) -> Result<Vec<BccPoint>, String> {
        self.check()?;
        let mut p = self.problem()?;
        let area = self.side() * self.side();
        let r = self.spec.radius;
        let set = Settings { proximal: PROXIMAL, max_iter: 300, rtol: RTOL, ..Settings::default() };
        let what = format!(
            "bcc cell, {} intervals per edge, {:?}, nu = {}",
            self.spec.intervals, self.spec.law, self.spec.poisson_ratio
        );
        let mut out = Vec::new();
        load_path(
            &mut p,
            &set,
            &self.spec.delta_over_r,
            &what,
            |p, next| p.planes[0].pos = 0.5 * next * r,
            |eq, target| {
                let pt = BccPoint {
                    delta_over_r: target,
                    plate_force: 4.0 * eq.plane_force[0],
                    side_force: 4.0 * eq.plane_force[1],
                    plate_stress: 4.0 * eq.plane_force[0] / area,
                    side_stress: 4.0 * eq.plane_force[1] / area,
                    contact: eq.pair_force[0],
                    plate_nodes: eq.contact_nodes[0],
                    side_nodes: eq.contact_nodes[1],
                    contact_nodes: eq.pair_nodes[0],
                };
                progress(&pt);
                out.push(pt);
            },
        )?;
        Ok(out)
    }
}
