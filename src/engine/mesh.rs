//! Triangle-mesh walls: STL reading (ASCII and binary), rigid motion, and the contacts of a sphere
//! with a mesh surface, each counted exactly once wherever its closest point lies.
//!
//! The rule (one test per contact, no tie-breaks that depend on the triangle order): the closest
//! point q of a triangle to a particle centre p is a contact of the mesh only if it is a local
//! minimum of the distance over the whole surface, i.e. no neighbouring element lies "under" the
//! direction d = p − q:
//! - a point inside the face is always one;
//! - a point on an edge is one unless d leans, beyond a round-off band, into a triangle that shares
//!   the edge (then that triangle reports the contact, as a face, edge or corner of its own);
//! - a point on a corner is one unless d leans along any edge that leaves the corner.
//!
//! Points exactly on a shared edge or corner (a sphere centred over the diagonal of a split plate, a
//! lattice over a mesh seam, a ridge) are found by every triangle that shares it, at the same place:
//! the caller keeps one of those (`Mesh::same_contact`), preferring the face over an edge over a
//! corner. This replaces LIGGGHTS' "active edge" flags, which here had three holes: an edge shared
//! by coplanar triangles was ignored by both when the point sat exactly on it, the outer corners of a
//! flat mesh were ignored by both triangles sharing them, and a convex ridge counted twice.

use std::collections::HashMap;

use super::mesh_motion::{Mover, Pose};
use crate::physics::Vec3;

/// Relative width of the band within which a direction counts as perpendicular to an edge or as
/// exactly above it: the closest-point arithmetic loses a few ulps of the coordinates, so a point
/// meant to lie on an edge can come out 1e-16 relative to either side. 1e-10 of the distance is far
/// above that round-off and far below any geometry a contact law resolves.
const ON_EDGE_BAND: f64 = 1e-10;

/// Index range into one of a mesh's direction pools.
#[derive(Debug, Clone, Copy, Default)]
struct Span {
    start: u32,
    len: u32,
}

impl Span {
    #[inline]
    fn of<'a, T>(&self, pool: &'a [T]) -> &'a [T] {
        &pool[self.start as usize..(self.start + self.len) as usize]
    }
}

/// One triangle of a mesh with the neighbourhood its contact test reads.
#[derive(Debug, Clone)]
pub struct Triangle {
    pub v: [Vec3; 3],
    /// Per edge (ab, bc, ca): the in-plane unit normals, pointing away from the edge into each
    /// other triangle that shares it (`Mesh::edge_dirs`).
    edge_nbrs: [Span; 3],
    /// Per corner (a, b, c): the unit directions of every mesh edge that leaves it
    /// (`Mesh::corner_dirs`).
    corner_edges: [Span; 3],
    /// Triangles that share at least a vertex with this one and lie in its plane
    /// (`Mesh::coplanar`): a contact moving between them keeps its history.
    coplanar: Span,
}

/// A rigid mesh wall: geometry, its velocity field (rigid motion of `fix move/mesh`, conveyor
/// surface velocity of `fix mesh/surface … surface_vel`) and the total force the particles exert
/// on it in the current step (`fix mesh/surface/stress`).
#[derive(Debug, Clone)]
pub struct Mesh {
    pub name: String,
    pub wall_type: usize,
    pub tris: Vec<Triangle>,
    /// Translational velocity of the rigid motion in the current step.
    pub velocity: Vec3,
    /// Angular velocity of the rigid motion in the current step, about an axis through `origin`.
    pub omega: Vec3,
    pub origin: Vec3,
    /// Per triangle: the conveyor velocity of `surface_vel` (empty when the mesh has none).
    pub surface_vel: Vec<Vec3>,
    /// The `fix move/mesh` driving the mesh, if any.
    pub mover: Option<Mover>,
    /// Force on the mesh [N] (minus the sum of its contact forces on the particles).
    pub force: Vec3,
    /// Torque-free bookkeeping only: the stress fix reports force components 1..3.
    pub stress: bool,
    /// Axis-aligned bounding box, refreshed when the mesh moves (cheap rejection of far particles).
    pub bb_lo: Vec3,
    pub bb_hi: Vec3,
    edge_dirs: Vec<Vec3>,
    corner_dirs: Vec<Vec3>,
    coplanar: Vec<u32>,
}

/// Where on its triangle a contact point lies; a contact found by several triangles keeps the
/// lowest (a face point is the plane's own projection, the most exact of the three).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Feature {
    Face,
    Edge,
    Corner,
}

/// Where on the triangle the closest point lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Region {
    Face,
    Edge(usize),
    Corner(usize),
}

/// Reads an STL file (ASCII or binary) into raw triangles.
pub fn read_stl(path: &std::path::Path) -> Result<Vec<[Vec3; 3]>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read mesh file {}: {e}", path.display()))?;
    let text_like = bytes.starts_with(b"solid") && bytes.iter().take(1000).all(|b| b.is_ascii());
    if text_like {
        if let Ok(t) = parse_ascii_stl(&String::from_utf8_lossy(&bytes)) {
            if !t.is_empty() {
                return Ok(t);
            }
        }
    }
    parse_binary_stl(&bytes).map_err(|e| format!("mesh file {}: {e}", path.display()))
}

fn parse_ascii_stl(text: &str) -> Result<Vec<[Vec3; 3]>, String> {
    let mut tris = Vec::new();
    let mut cur: Vec<Vec3> = Vec::with_capacity(3);
    for (ln, line) in text.lines().enumerate() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("vertex") => {
                let mut c = [0.0; 3];
                for v in &mut c {
                    *v = w
                        .next()
                        .and_then(|s| s.parse::<f64>().ok())
                        .ok_or_else(|| format!("line {}: bad vertex", ln + 1))?;
                }
                cur.push(Vec3::new(c[0], c[1], c[2]));
            }
            Some("endloop") => {
                if cur.len() != 3 {
                    return Err(format!("line {}: facet with {} vertices", ln + 1, cur.len()));
                }
                tris.push([cur[0], cur[1], cur[2]]);
                cur.clear();
            }
            _ => {}
        }
    }
    Ok(tris)
}

fn parse_binary_stl(b: &[u8]) -> Result<Vec<[Vec3; 3]>, String> {
    if b.len() < 84 {
        return Err("not a valid STL file (too short)".into());
    }
    let n = u32::from_le_bytes([b[80], b[81], b[82], b[83]]) as usize;
    if b.len() < 84 + n * 50 {
        return Err(format!("binary STL announces {n} facets but is truncated"));
    }
    let f = |o: usize| f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]) as f64;
    Ok((0..n)
        .map(|k| {
            let o = 84 + k * 50 + 12;
            let v = |m: usize| Vec3::new(f(o + 12 * m), f(o + 12 * m + 4), f(o + 12 * m + 8));
            [v(0), v(1), v(2)]
        })
        .collect())
}

impl Mesh {
    /// Builds the mesh and the neighbourhood of every triangle. Degenerate triangles are an error
    /// (no normal).
    pub fn new(name: &str, wall_type: usize, raw: Vec<[Vec3; 3]>) -> Result<Self, String> {
        if raw.is_empty() {
            return Err(format!("mesh {name}: no triangles"));
        }
        let normals: Vec<Vec3> = raw
            .iter()
            .enumerate()
            .map(|(k, t)| {
                let n = (t[1] - t[0]).cross(&(t[2] - t[0]));
                let l = n.norm();
                if !(l > 0.0 && l.is_finite()) {
                    Err(format!("mesh {name}: triangle {} is degenerate", k + 1))
                } else {
                    Ok(n / l)
                }
            })
            .collect::<Result<_, _>>()?;
        // Vertex identity by rounded coordinates (STL repeats vertices per facet).
        let scale = raw.iter().flat_map(|t| t.iter()).map(|v| v.amax()).fold(0.0_f64, f64::max).max(1e-300);
        let key = |v: &Vec3| {
            let q = |x: f64| (x / scale * 1e9).round() as i64;
            (q(v.x), q(v.y), q(v.z))
        };
        let mut ids: HashMap<(i64, i64, i64), u32> = HashMap::new();
        let vid: Vec<[u32; 3]> = raw
            .iter()
            .map(|t| {
                t.map(|v| {
                    let next = ids.len() as u32;
                    *ids.entry(key(&v)).or_insert(next)
                })
            })
            .collect();
        let mut vert_tris: Vec<Vec<u32>> = vec![Vec::new(); ids.len()];
        for (k, t) in vid.iter().enumerate() {
            for &v in t {
                vert_tris[v as usize].push(k as u32);
            }
        }
        let coplanar_with = |a: usize, b: usize| normals[a].dot(&normals[b]).abs() > 1.0 - 1e-8;
        let (mut edge_dirs, mut corner_dirs, mut coplanar) = (Vec::new(), Vec::new(), Vec::new());
        let span =
            |pool_len: usize, start: usize| Span { start: start as u32, len: (pool_len - start) as u32 };
        let mut tris = Vec::with_capacity(raw.len());
        for (k, t) in raw.iter().enumerate() {
            let mut edge_nbrs = [Span::default(); 3];
            for (e, s) in edge_nbrs.iter_mut().enumerate() {
                let (va, vb) = (vid[k][e], vid[k][(e + 1) % 3]);
                let (a, b) = (t[e], t[(e + 1) % 3]);
                let along = (b - a).normalize();
                let start = edge_dirs.len();
                for &o in &vert_tris[va as usize] {
                    let o = o as usize;
                    if o == k || !vid[o].contains(&vb) {
                        continue;
                    }
                    // The other triangle's third vertex, seen from the edge, in its own plane.
                    let c = (0..3).find(|&m| vid[o][m] != va && vid[o][m] != vb).map(|m| raw[o][m]);
                    if let Some(c) = c {
                        let off = (c - a) - along * along.dot(&(c - a));
                        edge_dirs.push(off.normalize());
                    }
                }
                *s = span(edge_dirs.len(), start);
            }
            let mut corner_edges = [Span::default(); 3];
            for (c, s) in corner_edges.iter_mut().enumerate() {
                let vc = vid[k][c];
                let start = corner_dirs.len();
                let mut seen: Vec<u32> = Vec::new();
                for &o in &vert_tris[vc as usize] {
                    for m in 0..3 {
                        let w = vid[o as usize][m];
                        if w != vc && !seen.contains(&w) {
                            seen.push(w);
                            corner_dirs.push((raw[o as usize][m] - t[c]).normalize());
                        }
                    }
                }
                *s = span(corner_dirs.len(), start);
            }
            let start = coplanar.len();
            let mut near: Vec<u32> =
                vid[k].iter().flat_map(|&v| vert_tris[v as usize].iter().copied()).collect();
            near.sort_unstable();
            near.dedup();
            coplanar.extend(near.into_iter().filter(|&o| o as usize != k && coplanar_with(k, o as usize)));
            let coplanar_span = span(coplanar.len(), start);
            tris.push(Triangle { v: *t, edge_nbrs, corner_edges, coplanar: coplanar_span });
        }
        let mut m = Mesh {
            name: name.to_string(),
            wall_type,
            tris,
            velocity: Vec3::zeros(),
            omega: Vec3::zeros(),
            origin: Vec3::zeros(),
            surface_vel: Vec::new(),
            mover: None,
            force: Vec3::zeros(),
            stress: false,
            bb_lo: Vec3::zeros(),
            bb_hi: Vec3::zeros(),
            edge_dirs,
            corner_dirs,
            coplanar,
        };
        m.update_bbox();
        Ok(m)
    }

    /// Whether triangle `t` lies surely beyond `reach` of `p`, by the distance to its plane (a lower
    /// bound of the distance to the triangle): a few products instead of the closest-point search
    /// for the many neighbour-list candidates a step finds out of reach. The margin 1e-9 keeps
    /// every pair whose closest point could be within reach by round-off, so the contacts found
    /// are those of the full search, bit for bit.
    #[inline]
    pub fn surely_beyond(&self, t: usize, p: &Vec3, reach: f64) -> bool {
        let [a, b, c] = &self.tris[t].v;
        let n = (b - a).cross(&(c - a));
        let h = n.dot(&(p - a));
        h * h > reach * reach * n.norm_squared() * (1.0 + 1e-9)
    }

    /// The contact of triangle `t` with a sphere centred at `p`: its closest point and where on the
    /// triangle it lies, or `None` when that point is not a local minimum of the distance over the
    /// mesh (a neighbouring element reports the contact; see the module's doc).
    #[inline]
    pub fn contact(&self, t: usize, p: &Vec3) -> Option<(Vec3, Feature)> {
        let tri = &self.tris[t];
        let (q, region) = closest_on_triangle(&tri.v[0], &tri.v[1], &tri.v[2], p);
        let (dirs, feature) = match region {
            Region::Face => return Some((q, Feature::Face)),
            Region::Edge(e) => (tri.edge_nbrs[e].of(&self.edge_dirs), Feature::Edge),
            Region::Corner(c) => (tri.corner_edges[c].of(&self.corner_dirs), Feature::Corner),
        };
        let d = p - q;
        let band = self.band(p, d.norm());
        dirs.iter().all(|u| u.dot(&d) <= band).then_some((q, feature))
    }

    /// Do two contact points found for the same sphere (centre distance `dist`) by two triangles
    /// of this mesh stand for one contact? They do when they coincide to within the band that
    /// `contact` allows on either side of an edge.
    #[inline]
    pub fn same_contact(&self, p: &Vec3, q1: &Vec3, q2: &Vec3, dist: f64) -> bool {
        (q1 - q2).norm() <= 4.0 * self.band(p, dist)
    }

    /// Triangles in the plane of `t` that share a vertex with it.
    #[inline]
    pub fn coplanar_neighbours(&self, t: usize) -> &[u32] {
        self.tris[t].coplanar.of(&self.coplanar)
    }

    /// Length below which an offset from an edge is round-off: the band relative to the distance,
    /// plus the round-off of the coordinates themselves (a few ulps of the largest).
    #[inline]
    fn band(&self, p: &Vec3, dist: f64) -> f64 {
        let coords = p.amax().max(self.bb_lo.amax()).max(self.bb_hi.amax());
        ON_EDGE_BAND * dist + 64.0 * f64::EPSILON * coords
    }

    fn update_bbox(&mut self) {
        let mut lo = Vec3::repeat(f64::INFINITY);
        let mut hi = Vec3::repeat(f64::NEG_INFINITY);
        for t in &self.tris {
            for v in &t.v {
                lo = lo.inf(v);
                hi = hi.sup(v);
            }
        }
        self.bb_lo = lo;
        self.bb_hi = hi;
    }

    /// The wall's velocity at point `q` of triangle `t`: the rigid motion's v + ω × (q − origin)
    /// plus the triangle's conveyor velocity. LIGGGHTS (`fix_wall_gran.cpp`, post_force_mesh)
    /// interpolates the node velocities with the contact point's barycentric coordinates; the
    /// rigid field is linear in position, so that interpolation is this same value.
    #[inline]
    pub fn velocity_at(&self, t: usize, q: &Vec3) -> Vec3 {
        let mut v = self.velocity + self.omega.cross(&(q - self.origin));
        if let Some(s) = self.surface_vel.get(t) {
            v += s;
        }
        v
    }

    /// Does the mesh carry a velocity field (LIGGGHTS: has the element property `v`)?
    pub fn has_velocity(&self) -> bool {
        self.mover.is_some() || !self.surface_vel.is_empty()
    }

    /// Largest node speed of a mesh under a `fix move/mesh`, 0 for others: what `fix
    /// check/timestep/gran` reads (LIGGGHTS 3.8 `fix_check_timestep_gran.cpp` counts only meshes
    /// that move, not a conveyor's `surface_vel`).
    pub fn max_node_speed(&self) -> f64 {
        if self.mover.is_none() {
            return 0.0;
        }
        let mut vmax: f64 = 0.0;
        for (t, tri) in self.tris.iter().enumerate() {
            for v in &tri.v {
                vmax = vmax.max(self.velocity_at(t, v).norm());
            }
        }
        vmax
    }

    /// Sets the conveyor velocity `surface_vel` (LIGGGHTS `FixMeshSurface::setVel`): on each
    /// triangle the given velocity projected into the triangle's plane and scaled back to the
    /// given speed, so that a belt moves at that speed whatever its slope (a triangle
    /// perpendicular to the velocity gets none).
    pub fn set_surface_velocity(&mut self, vs: &Vec3) {
        let speed = vs.norm();
        self.surface_vel = self
            .tris
            .iter()
            .map(|tri| {
                let n = (tri.v[1] - tri.v[0]).cross(&(tri.v[2] - tri.v[0])).normalize();
                let tangential = vs - n * vs.dot(&n);
                let l = tangential.norm();
                if l > 0.0 {
                    tangential * (speed / l)
                } else {
                    tangential
                }
            })
            .collect();
    }

    /// One step of the mover (if any): sets the mesh's velocity field for the step and moves
    /// the nodes by the step's increment. Returns the largest node displacement.
    pub fn advance_motion(&mut self, dt: f64) -> f64 {
        let Some(mut mv) = self.mover.take() else { return 0.0 };
        let step = mv.advance(dt, || self.pose());
        self.velocity = step.velocity;
        let travel = match step.turn {
            Some(t) => {
                self.omega = t.omega;
                self.origin = t.origin;
                self.place_turned(t.start, &t.axis, t.angle, &t.origin)
            }
            None => {
                let d = step.velocity * dt;
                self.translate(&d);
                d.norm()
            }
        };
        self.mover = Some(mv);
        travel
    }

    /// `unfix` of the mover: the mesh stays where it is, at rest.
    pub fn stop_motion(&mut self) {
        self.mover = None;
        self.velocity = Vec3::zeros();
        self.omega = Vec3::zeros();
    }

    /// The node positions and contact directions, as the reference a turning motion starts from.
    pub(super) fn pose(&self) -> Pose {
        Pose {
            tris: self.tris.iter().map(|t| t.v).collect(),
            edge_dirs: self.edge_dirs.clone(),
            corner_dirs: self.corner_dirs.clone(),
        }
    }

    /// Places the mesh at `reference` turned by `angle` [rad] about the unit `axis` through
    /// `origin`: every node by the unit quaternion q = (cos(φ/2), sin(φ/2) axis) as
    /// q (0, x − p) q* + p, the rotation of LIGGGHTS' `MultiNodeMesh::rotate`. Returns the largest
    /// distance a node moved.
    pub(super) fn place_turned(&mut self, reference: &Pose, axis: &Vec3, angle: f64, origin: &Vec3) -> f64 {
        let (c, s) = ((0.5 * angle).cos(), (0.5 * angle).sin());
        let q = [c, axis.x * s, axis.y * s, axis.z * s];
        let mut travel: f64 = 0.0;
        for (t, r) in self.tris.iter_mut().zip(&reference.tris) {
            for (v, r) in t.v.iter_mut().zip(r) {
                let new = quat_rotate(&q, &(r - origin)) + origin;
                travel = travel.max((new - *v).norm());
                *v = new;
            }
        }
        let dirs = self.edge_dirs.iter_mut().chain(self.corner_dirs.iter_mut());
        for (u, r) in dirs.zip(reference.edge_dirs.iter().chain(&reference.corner_dirs)) {
            *u = quat_rotate(&q, r);
        }
        self.update_bbox();
        travel
    }

    /// Rigid translation of every node (the `move` keyword of `fix mesh/surface`).
    pub fn translate(&mut self, d: &Vec3) {
        for t in &mut self.tris {
            for v in &mut t.v {
                *v += d;
            }
        }
        self.bb_lo += d;
        self.bb_hi += d;
    }

    /// Rotate about an axis through the origin by `degrees` (the `rotate axis X Y Z angle A`
    /// keyword of `fix mesh/surface`). The degree-to-radian factor is LIGGGHTS' own
    /// (π written as 3.14159265), so both engines place the mesh at the same doubles.
    #[allow(clippy::approx_constant)] // LIGGGHTS' truncated π, on purpose (see above)
    pub fn rotate(&mut self, axis: &Vec3, degrees: f64) -> Result<(), String> {
        if axis.norm() < 1e-5 {
            return Err("mesh rotate: the axis must not be zero".into());
        }
        let rot = nalgebra::Rotation3::from_axis_angle(
            &nalgebra::Unit::new_normalize(*axis),
            degrees * 3.14159265 / 180.0,
        );
        for t in &mut self.tris {
            for v in &mut t.v {
                *v = rot * *v;
            }
        }
        for u in self.edge_dirs.iter_mut().chain(self.corner_dirs.iter_mut()) {
            *u = rot * *u;
        }
        self.update_bbox();
        Ok(())
    }

    /// Scale about the origin (the `scale` keyword of `fix mesh/surface`).
    pub fn scale(&mut self, s: f64) {
        for t in &mut self.tris {
            for v in &mut t.v {
                *v *= s;
            }
        }
        if s < 0.0 {
            for u in self.edge_dirs.iter_mut().chain(self.corner_dirs.iter_mut()) {
                *u = -*u;
            }
        }
        self.update_bbox();
    }

    /// Is the point farther than `reach` from the bounding box?
    #[inline]
    pub fn far(&self, x: &Vec3, reach: f64) -> bool {
        (0..3).any(|a| x[a] < self.bb_lo[a] - reach || x[a] > self.bb_hi[a] + reach)
    }
}

/// Hamilton product of two quaternions (w, x, y, z).
#[inline]
fn quat_mul(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + b[0] * a[1] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] + b[0] * a[2] + a[3] * b[1] - a[1] * b[3],
        a[0] * b[3] + b[0] * a[3] + a[1] * b[2] - a[2] * b[1],
    ]
}

/// The vector `v` rotated by the unit quaternion `q`: q (0, v) q*.
#[inline]
fn quat_rotate(q: &[f64; 4], v: &Vec3) -> Vec3 {
    let r = quat_mul(&quat_mul(q, &[0.0, v.x, v.y, v.z]), &[q[0], -q[1], -q[2], -q[3]]);
    Vec3::new(r[1], r[2], r[3])
}

/// Squared distance from `p` to triangle `t` (whether or not its closest point is a contact).
#[inline]
pub fn distance_squared(t: &Triangle, p: &Vec3) -> f64 {
    (closest_on_triangle(&t.v[0], &t.v[1], &t.v[2], p).0 - p).norm_squared()
}

/// Closest point on triangle abc to p with the Voronoi region it lies in (Ericson, Real-Time
/// Collision Detection, 5.1.5). Edges are numbered ab = 0, bc = 1, ca = 2. A point exactly above
/// an edge (its barycentric coordinate exactly zero) is a face point, as in LIGGGHTS.
fn closest_on_triangle(a: &Vec3, b: &Vec3, c: &Vec3, p: &Vec3) -> (Vec3, Region) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (*a, Region::Corner(0));
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (*b, Region::Corner(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc < 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, Region::Edge(0));
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (*c, Region::Corner(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb < 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, Region::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va < 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, Region::Edge(1));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w, Region::Face)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The contacts of a sphere centred at `p` with mesh `m`, each once (the engine's merge rule:
    /// a point found by several triangles is one contact).
    fn contacts(m: &Mesh, p: Vec3) -> Vec<(Vec3, Feature)> {
        let mut out: Vec<(Vec3, Feature)> = Vec::new();
        for t in 0..m.tris.len() {
            if let Some((q, f)) = m.contact(t, &p) {
                let dist = (p - q).norm();
                match out.iter_mut().find(|(o, _)| m.same_contact(&p, o, &q, dist)) {
                    Some(kept) if f < kept.1 => *kept = (q, f),
                    Some(_) => {}
                    None => out.push((q, f)),
                }
            }
        }
        out
    }

    /// The unit square split along its diagonal (0,0)–(1,1), as the Debian hydrogel piston is.
    fn square() -> Mesh {
        let raw = vec![
            [Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
            [Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.0)],
        ];
        Mesh::new("sq", 1, raw).unwrap()
    }

    #[test]
    fn a_point_over_the_shared_edge_is_one_face_contact() {
        let m = square();
        for s in [0.5, 0.25, 1.0 / 3.0, 0.9] {
            for off in [0.0, 1e-15, -1e-15, 1e-9, -1e-9] {
                let p = Vec3::new(s, s + off, 0.3);
                let hits = contacts(&m, p);
                assert_eq!(hits.len(), 1, "at {p:?}: {hits:?}");
                assert_eq!(hits[0].1, Feature::Face, "at {p:?}");
                assert!((hits[0].0 - Vec3::new(p.x, p.y, 0.0)).norm() < 1e-15, "at {p:?}: {hits:?}");
            }
        }
    }

    #[test]
    fn outer_corners_and_edges_count_once() {
        let m = square();
        // Beyond the corner the diagonal ends at (shared by both triangles) and beyond one that
        // belongs to one triangle only: the corner itself.
        for (p, q) in [
            (Vec3::new(-0.3, -0.2, 0.1), Vec3::new(0.0, 0.0, 0.0)),
            (Vec3::new(1.3, -0.2, 0.1), Vec3::new(1.0, 0.0, 0.0)),
            (Vec3::new(-0.1, 1.2, 0.0), Vec3::new(0.0, 1.0, 0.0)),
        ] {
            assert_eq!(contacts(&m, p), vec![(q, Feature::Corner)], "at {p:?}");
        }
        // Beside an outer edge next to the shared corner: the edge point, not also the corner
        // (which a triangle not owning that edge sees as its closest point).
        let hits = contacts(&m, Vec3::new(-0.5, 0.2, 0.1));
        assert_eq!(hits, vec![(Vec3::new(0.0, 0.2, 0.0), Feature::Edge)]);
        let hits = contacts(&m, Vec3::new(1.2, 0.5, 0.0));
        assert_eq!(hits, vec![(Vec3::new(1.0, 0.5, 0.0), Feature::Edge)]);
    }

    /// A roof of two triangles meeting at the ridge y = 0 (slopes ±30°).
    fn roof() -> Mesh {
        let h = 30.0_f64.to_radians().tan();
        let raw = vec![
            [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, -1.0, -h)],
            [Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 1.0, -h)],
        ];
        Mesh::new("roof", 1, raw).unwrap()
    }

    #[test]
    fn a_convex_ridge_counts_once() {
        let m = roof();
        // Straight above the ridge: the ridge point, once (both triangles find it).
        assert_eq!(contacts(&m, Vec3::new(0.4, 0.0, 0.2)), vec![(Vec3::new(0.4, 0.0, 0.0), Feature::Edge)]);
        // Above one slope, close to the ridge: that slope's face only; the other triangle's ridge
        // point is not a local minimum of the distance.
        let p = Vec3::new(0.4, 0.3, 0.1);
        let hits = contacts(&m, p);
        assert_eq!(hits.len(), 1, "{hits:?}");
        assert_eq!(hits[0].1, Feature::Face);
        assert!((p - hits[0].0).norm() < (p - Vec3::new(0.4, 0.0, 0.0)).norm());
    }

    #[test]
    fn a_concave_fold_gives_two_contacts() {
        // Floor z = 0 (x > 0) and wall x = 0 (z > 0), one mesh folded along the y axis.
        let raw = vec![
            [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0)],
            [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
            [Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 1.0)],
            [Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 1.0), Vec3::new(0.0, 0.0, 1.0)],
        ];
        let m = Mesh::new("fold", 1, raw).unwrap();
        let mut hits = contacts(&m, Vec3::new(0.2, 0.5, 0.3));
        hits.sort_by(|a, b| a.0.x.total_cmp(&b.0.x));
        assert_eq!(hits.len(), 2, "{hits:?}");
        for ((q, f), want) in hits.iter().zip([Vec3::new(0.0, 0.5, 0.3), Vec3::new(0.2, 0.5, 0.0)]) {
            assert_eq!(*f, Feature::Face);
            assert!((q - want).norm() < 1e-15, "{q:?} vs {want:?}");
        }
    }

    /// A binary STL (80-byte header, count, 50 bytes per facet) reads as the same triangles as
    /// the ASCII form, and a truncated one is refused with the facet count it announced.
    #[test]
    fn binary_stl_reads_like_ascii() {
        let tris = [
            [[1.0f32, 1.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            [[1.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
        ];
        let mut b = vec![0u8; 80];
        b.extend(2u32.to_le_bytes());
        for t in &tris {
            b.extend([0.0f32, 0.0, -1.0].iter().flat_map(|c| c.to_le_bytes()));
            b.extend(t.iter().flatten().flat_map(|c| c.to_le_bytes()));
            b.extend([0u8, 0]);
        }
        let dir = std::env::temp_dir().join(format!("mcdem_stl_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (bin, text) = (dir.join("plate_bin.stl"), dir.join("plate_ascii.stl"));
        std::fs::write(&bin, &b).unwrap();
        let mut ascii = String::from("solid plate\n");
        for t in &tris {
            ascii += "facet normal 0 0 -1\nouter loop\n";
            for v in t {
                ascii += &format!("vertex {} {} {}\n", v[0], v[1], v[2]);
            }
            ascii += "endloop\nendfacet\n";
        }
        ascii += "endsolid plate\n";
        std::fs::write(&text, ascii).unwrap();
        let (a, t) = (read_stl(&bin).unwrap(), read_stl(&text).unwrap());
        assert_eq!(a, t);
        assert_eq!(a.len(), 2);
        std::fs::write(&bin, &b[..b.len() - 10]).unwrap();
        let e = read_stl(&bin).unwrap_err();
        assert!(e.contains("announces 2 facets but is truncated"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn directions_follow_a_rotation() {
        let mut m = square();
        m.rotate(&Vec3::new(1.0, 0.0, 0.0), 90.0).unwrap();
        // The plate now lies in y = 0 (z from 0 to 1); beside its outer edge x = 0.
        let hits = contacts(&m, Vec3::new(-0.5, 0.1, 0.2));
        assert_eq!(hits.len(), 1, "{hits:?}");
        assert_eq!(hits[0].1, Feature::Edge);
        assert!((hits[0].0 - Vec3::new(0.0, 0.0, 0.2)).norm() < 1e-8, "{hits:?}");
    }
}
