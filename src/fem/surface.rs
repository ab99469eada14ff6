//! Frictionless contact between two deformable bodies of one mesh: slave nodes kept out of a master
//! surface by an augmented-Lagrangian penalty (node-to-surface; Wriggers, *Computational Contact
//! Mechanics*, 2006, §5.2 and §6.3).
//!
//! The master surface is the boundary quadrilaterals of the master body, bilinear. The gap of a
//! slave node is its distance to the master surface along one fixed direction per pair (the line
//! of centres), positive outside the master: the small-sliding form, for interfaces that stay
//! nearly normal to that line, as between two spheres pressed together. Within a face the gap is a
//! smooth function of the positions and its derivatives are exact, so the energy, its gradient and
//! the solver's line search stay consistent; across face edges only its slope jumps. Tried first
//! and dropped: the gap to the nearest point of the surface split into triangles, singular where
//! the nearest point is a vertex or an edge (Newton stalled on the slave nodes of matching meshes,
//! which sit there), and the same triangles crossed along the direction, whose edges along the
//! faces' diagonals put a ridge under every slave node of a mesh symmetric about x = y.
//!
//! Energy per slave node (tributary reference area A, penalty k [Pa/m], multiplier λ [Pa]):
//! Ψ = A (⟨λ − k g⟩² − λ²) / (2k), so the contact pressure is p = ⟨λ − k g⟩ and the force on the
//! node A p ν. Uzawa's update λ ← p after each converged solve drives the penetration to zero
//! without an infinite penalty. The tangent is the Gauss–Newton part A k (∂g)(∂g)ᵀ (the curvature
//! of the faceted surface is left out: Newton then converges linearly near a kink, which the line
//! search tolerates).

use super::mesh::Mesh;
use crate::physics::Vec3;

/// Corner nodes of the six faces of a hexahedron (node order of `element::CORNERS`), each ordered
/// counter-clockwise seen from outside the element, so (b − a) × (d − a) points outward.
pub const HEX_FACES: [[usize; 4]; 6] =
    [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]];

/// The boundary faces of the elements `elems` of `mesh` (faces not shared by two of them), outward
/// ordered.
pub fn boundary_faces(mesh: &Mesh, elems: impl Iterator<Item = usize>) -> Vec<[usize; 4]> {
    use std::collections::HashMap;
    let mut count: HashMap<[usize; 4], ([usize; 4], u32)> = HashMap::new();
    for e in elems {
        for f in HEX_FACES {
            let face = f.map(|i| mesh.hex[e][i]);
            let mut key = face;
            key.sort_unstable();
            count.entry(key).or_insert((face, 0)).1 += 1;
        }
    }
    let mut out: Vec<[usize; 4]> = count.into_values().filter(|v| v.1 == 1).map(|v| v.0).collect();
    out.sort_unstable();
    out
}

/// The gap of one slave node: its signed distance `g` [m] to the master surface along the pair's
/// direction (> 0: outside), ν = ∂g/∂x_s (the facet's normal over its cosine to the direction), the
/// master face it lies against (index into `SurfacePair::master`) and the crossing point's weights
/// on that face's four nodes.
#[derive(Clone, Copy, Debug)]
pub struct Gap {
    pub g: f64,
    pub nu: [f64; 3],
    pub face: usize,
    pub w: [f64; 4],
}

/// One slave–master pairing of the contact between two bodies.
#[derive(Clone, Debug)]
pub struct SurfacePair {
    /// Slave nodes and their tributary reference areas [m²].
    pub slave: Vec<usize>,
    pub area: Vec<f64>,
    /// Master faces (outward ordered) and, per slave node, the faces it may meet (indices into
    /// `master`), fixed at set-up so that the tangent's sparsity pattern is fixed.
    pub master: Vec<[usize; 4]>,
    pub candidates: Vec<Vec<usize>>,
    /// Unit direction along which gaps are measured, from the master into the slave (the line of
    /// centres of two spheres: small sliding, the interface nearly normal to it).
    pub direction: [f64; 3],
    /// Penalty k [Pa/m] and the gap tolerance [m] at which Uzawa's updates stop.
    pub penalty: f64,
    pub gap_tolerance: f64,
}

impl SurfacePair {
    /// The pairing of the slave faces `slave_faces` against `master`, candidates the master faces
    /// whose centroid lies within `reach` [m] of a slave node in the reference configuration;
    /// penalty `stiffness_factor`·E/h and gap tolerance 1e-4·h, h the shortest master edge.
    pub fn new(
        mesh: &Mesh,
        slave_faces: &[[usize; 4]],
        master: Vec<[usize; 4]>,
        direction: [f64; 3],
        reach: f64,
        youngs_modulus: f64,
        stiffness_factor: f64,
    ) -> Result<SurfacePair, String> {
        if master.is_empty() || slave_faces.is_empty() {
            return Err("surface contact: empty slave or master surface".into());
        }
        let len = Vec3::from(direction).norm();
        if !(len > 0.0 && len.is_finite()) {
            return Err(format!("surface contact: direction {direction:?} has no length"));
        }
        let direction = direction.map(|v| v / len);
        let at = |i: usize| Vec3::from(mesh.x[i]);
        // Tributary area: a quarter of each adjacent face's area.
        let mut area_of = std::collections::BTreeMap::<usize, f64>::new();
        for f in slave_faces {
            let a = 0.5 * (at(f[2]) - at(f[0])).cross(&(at(f[3]) - at(f[1]))).norm();
            for &i in f {
                *area_of.entry(i).or_insert(0.0) += 0.25 * a;
            }
        }
        let cents: Vec<Vec3> = master.iter().map(|f| f.iter().map(|&i| 0.25 * at(i)).sum()).collect();
        let mut h = f64::INFINITY;
        for f in &master {
            for k in 0..4 {
                h = h.min((at(f[(k + 1) % 4]) - at(f[k])).norm());
            }
        }
        let (mut slave, mut area, mut candidates) = (Vec::new(), Vec::new(), Vec::new());
        for (&s, &a) in &area_of {
            let c: Vec<usize> = (0..master.len()).filter(|&m| (cents[m] - at(s)).norm() <= reach).collect();
            if !c.is_empty() {
                slave.push(s);
                area.push(a);
                candidates.push(c);
            }
        }
        if slave.is_empty() {
            return Err(format!("surface contact: no slave node within {reach} m of the master surface"));
        }
        Ok(SurfacePair {
            slave,
            area,
            master,
            candidates,
            direction,
            penalty: stiffness_factor * youngs_modulus / h,
            gap_tolerance: 1e-4 * h,
        })
    }

    /// The gap of slave `i` with the current positions `pos(node)`, measured along the pair's
    /// `direction` d: the line x_s − g d meets the bilinear master faces x(ξ, η) = Σ N_a(ξ, η) x_a
    /// whose outward normal n = x_ξ × x_η faces the slave (n·d > 0); the nearest such crossing gives
    /// g, with ∂g/∂x_s = n/(n·d) and ∂g/∂x_a = −N_a(ξ, η) n/(n·d) (the implicit-function derivatives
    /// of x_s − g d = x(ξ, η)), exact and smooth within a face. `g = ∞` where no candidate face is
    /// crossed (no contact possible).
    pub fn gap(&self, i: usize, pos: &impl Fn(usize) -> [f64; 3]) -> Gap {
        let p = pos(self.slave[i]);
        let d = self.direction;
        let mut best = Gap { g: f64::INFINITY, nu: [0.0; 3], face: usize::MAX, w: [0.0; 4] };
        for &m in &self.candidates[i] {
            let x = self.master[m].map(pos);
            if let Some((g, n, w)) = cross_bilinear(p, d, &x) {
                if g.abs() < best.g.abs() {
                    best = Gap { g, nu: n, face: m, w };
                }
            }
        }
        best
    }

    /// Contact pressure ⟨λ − k g⟩ [Pa] of a gap under multiplier λ.
    pub fn pressure(&self, lambda: f64, g: f64) -> f64 {
        if g.is_finite() {
            (lambda - self.penalty * g).max(0.0)
        } else {
            0.0
        }
    }

    /// Energy Ψ [J] of slave `i` at gap g under multiplier λ.
    pub fn energy(&self, i: usize, lambda: f64, g: f64) -> f64 {
        let p = self.pressure(lambda, g);
        self.area[i] * (p * p - lambda * lambda) / (2.0 * self.penalty)
    }

    /// The 15 dofs of slave `i` against master face `face` (slave node first, then the face's
    /// nodes), for the sparsity pattern and the assembly.
    pub fn dofs(&self, i: usize, face: usize) -> [usize; 15] {
        let nodes = [
            self.slave[i],
            self.master[face][0],
            self.master[face][1],
            self.master[face][2],
            self.master[face][3],
        ];
        std::array::from_fn(|k| 3 * nodes[k / 3] + k % 3)
    }

    /// ∂g over the 15 dofs of [`SurfacePair::dofs`].
    pub fn gap_gradient(gap: &Gap) -> [f64; 15] {
        std::array::from_fn(|k| {
            let (node, axis) = (k / 3, k % 3);
            if node == 0 {
                gap.nu[axis]
            } else {
                -gap.w[node - 1] * gap.nu[axis]
            }
        })
    }
}

/// Where the line p − g d crosses the bilinear quadrilateral x (corners at (ξ, η) = (−1, −1),
/// (1, −1), (1, 1), (−1, 1)): Newton on x(ξ, η) + g d = p from the centre. Returns g, n/(n·d) and
/// the shape-function values, or `None` if the crossing lies outside the face, the face is seen
/// edge-on or from behind, or Newton does not settle (a face folded over the line).
fn cross_bilinear(p: [f64; 3], d: [f64; 3], x: &[[f64; 3]; 4]) -> Option<(f64, [f64; 3], [f64; 4])> {
    const XI: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let (p, d) = (Vec3::from(p), Vec3::from(d));
    let x = x.map(Vec3::from);
    let (mut xi, mut eta, mut g) = (0.0f64, 0.0f64, 0.0f64);
    for _ in 0..30 {
        let n_a: [f64; 4] = std::array::from_fn(|a| 0.25 * (1.0 + XI[a][0] * xi) * (1.0 + XI[a][1] * eta));
        let mut f = g * d - p;
        let (mut t1, mut t2) = (Vec3::zeros(), Vec3::zeros());
        for a in 0..4 {
            f += n_a[a] * x[a];
            t1 += 0.25 * XI[a][0] * (1.0 + XI[a][1] * eta) * x[a];
            t2 += 0.25 * XI[a][1] * (1.0 + XI[a][0] * xi) * x[a];
        }
        let n = t1.cross(&t2);
        let nd = n.dot(&d);
        if nd <= 1e-9 * n.norm() {
            return None;
        }
        // Cramer's rule on [t1 t2 d] (δξ, δη, δg) = −f.
        let t2_d = t2.cross(&d);
        let det = t1.dot(&t2_d);
        let dxi = -f.dot(&t2_d) / det;
        let deta = -t1.dot(&f.cross(&d)) / det;
        let dg = -t1.dot(&t2.cross(&f)) / det;
        xi += dxi;
        eta += deta;
        g += dg;
        if dxi.abs().max(deta.abs()) < 1e-13 {
            if xi.abs() > 1.0 + 1e-9 || eta.abs() > 1.0 + 1e-9 {
                return None;
            }
            let n_a: [f64; 4] =
                std::array::from_fn(|a| 0.25 * (1.0 + XI[a][0] * xi) * (1.0 + XI[a][1] * eta));
            return Some((g, (n / nd).into(), n_a));
        }
        if xi.abs() > 3.0 || eta.abs() > 3.0 {
            return None;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::mesh::cuboid;

    /// The boundary of a 2×2×2 box has 24 faces, each with its normal pointing away from the centre.
    #[test]
    fn boundary_faces_of_a_box_point_outward() {
        let mesh = cuboid([2.0, 2.0, 2.0], [2, 2, 2], 0.0);
        let faces = boundary_faces(&mesh, 0..mesh.hex.len());
        assert_eq!(faces.len(), 24);
        for f in faces {
            let x = f.map(|i| Vec3::from(mesh.x[i]));
            let n = (x[1] - x[0]).cross(&(x[3] - x[0]));
            let c = 0.25 * (x[0] + x[1] + x[2] + x[3]) - Vec3::repeat(1.0);
            assert!(n.dot(&c) > 0.0, "face {f:?} points inward");
        }
    }

    /// The gap's gradient against central differences of the gap itself, for nodes above, below
    /// and beside the centre of a warped (non-planar) face.
    #[test]
    fn gap_gradient_matches_finite_differences() {
        let mesh = cuboid([1.0, 1.0, 0.5], [1, 1, 1], 0.0);
        let top = boundary_faces(&mesh, 0..1)
            .into_iter()
            .filter(|f| f.iter().all(|&i| mesh.x[i][2] > 0.4))
            .collect::<Vec<_>>();
        let mut m = mesh.clone();
        m.x[6][2] += 0.1; // a warped face
        for p in [[0.3, 0.4, 0.55], [0.7, 0.2, 0.45], [0.8, 0.6, 0.7]] {
            m.x.push(p);
            let s = m.x.len() - 1;
            let pair = SurfacePair {
                slave: vec![s],
                area: vec![1.0],
                master: top.clone(),
                candidates: vec![vec![0]],
                direction: [0.0, 0.0, 1.0],
                penalty: 1.0,
                gap_tolerance: 0.0,
            };
            let gap = pair.gap(0, &|i| m.x[i]);
            assert!(gap.g.is_finite(), "point {p:?} crosses no facet");
            let grad = SurfacePair::gap_gradient(&gap);
            let dofs = pair.dofs(0, gap.face);
            for (k, &d) in dofs.iter().enumerate() {
                let h = 1e-6;
                let mut mp = m.clone();
                mp.x[d / 3][d % 3] += h;
                let gp = pair.gap(0, &|i| mp.x[i]).g;
                mp.x[d / 3][d % 3] -= 2.0 * h;
                let gm = pair.gap(0, &|i| mp.x[i]).g;
                let fd = (gp - gm) / (2.0 * h);
                assert!((fd - grad[k]).abs() < 1e-6, "point {p:?} dof {k}: {} vs {fd}", grad[k]);
            }
            m.x.pop();
        }
    }
}
