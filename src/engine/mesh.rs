//! Triangle-mesh walls: STL reading (ASCII and binary), rigid translation, and the closest point
//! of a triangle to a particle centre with LIGGGHTS' edge/corner activity rule.
//!
//! Why the activity rule: a sphere above the shared edge of two coplanar triangles would otherwise
//! touch both and feel the wall twice. An edge (corner) shared only by coplanar triangles is
//! inactive: a closest point there is ignored, because the neighbouring triangle reports the same
//! contact as a face contact.

use std::collections::HashMap;

use crate::physics::Vec3;

/// One triangle of a mesh with the activity flags of its edges (ab, bc, ca) and corners (a, b, c).
#[derive(Debug, Clone)]
pub struct Triangle {
    pub v: [Vec3; 3],
    pub edge_active: [bool; 3],
    pub corner_active: [bool; 3],
}

/// A rigid mesh wall: geometry, translational velocity (set by `fix move/mesh … linear`) and the
/// total force the particles exert on it in the current step (`fix mesh/surface/stress`).
#[derive(Debug, Clone)]
pub struct Mesh {
    pub name: String,
    pub wall_type: usize,
    pub tris: Vec<Triangle>,
    pub velocity: Vec3,
    /// Force on the mesh [N] (minus the sum of its contact forces on the particles).
    pub force: Vec3,
    /// Torque-free bookkeeping only: the stress fix reports force components 1..3.
    pub stress: bool,
    /// Axis-aligned bounding box, refreshed when the mesh moves (cheap rejection of far particles).
    pub bb_lo: Vec3,
    pub bb_hi: Vec3,
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
    /// Builds the mesh and the activity flags. Degenerate triangles are an error (no normal).
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
        let mut vert_tris: HashMap<(i64, i64, i64), Vec<usize>> = HashMap::new();
        for (k, t) in raw.iter().enumerate() {
            for v in t {
                vert_tris.entry(key(v)).or_default().push(k);
            }
        }
        let coplanar = |a: usize, b: usize| normals[a].dot(&normals[b]).abs() > 1.0 - 1e-8;
        let mut tris = Vec::with_capacity(raw.len());
        for (k, t) in raw.iter().enumerate() {
            let mut edge_active = [true; 3];
            for (e, flag) in edge_active.iter_mut().enumerate() {
                let (ka, kb) = (key(&t[e]), key(&t[(e + 1) % 3]));
                let sa = &vert_tris[&ka];
                let sb = &vert_tris[&kb];
                let shared: Vec<usize> = sa.iter().copied().filter(|o| *o != k && sb.contains(o)).collect();
                if !shared.is_empty() && shared.iter().all(|&o| coplanar(k, o)) {
                    *flag = false;
                }
            }
            let mut corner_active = [true; 3];
            for (c, flag) in corner_active.iter_mut().enumerate() {
                let s = &vert_tris[&key(&t[c])];
                if s.len() > 1 && s.iter().all(|&o| coplanar(k, o)) {
                    *flag = false;
                }
            }
            tris.push(Triangle { v: *t, edge_active, corner_active });
        }
        let mut m = Mesh {
            name: name.to_string(),
            wall_type,
            tris,
            velocity: Vec3::zeros(),
            force: Vec3::zeros(),
            stress: false,
            bb_lo: Vec3::zeros(),
            bb_hi: Vec3::zeros(),
        };
        m.update_bbox();
        Ok(m)
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

    /// Rigid translation of every node (LIGGGHTS moves nodes incrementally by v dt each step).
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
        self.update_bbox();
    }

    /// Is the point farther than `reach` from the bounding box?
    #[inline]
    pub fn far(&self, x: &Vec3, reach: f64) -> bool {
        (0..3).any(|a| x[a] < self.bb_lo[a] - reach || x[a] > self.bb_hi[a] + reach)
    }
}

/// Closest point of triangle `t` to `p`, or `None` when it lies on an inactive edge or corner.
#[inline]
pub fn closest_point(t: &Triangle, p: &Vec3) -> Option<Vec3> {
    let (q, region) = closest_on_triangle(&t.v[0], &t.v[1], &t.v[2], p);
    let active = match region {
        Region::Face => true,
        Region::Edge(e) => t.edge_active[e],
        Region::Corner(c) => t.corner_active[c],
    };
    active.then_some(q)
}

/// Squared distance from `p` to triangle `t`, active edges or not.
#[inline]
pub fn distance_squared(t: &Triangle, p: &Vec3) -> f64 {
    (closest_on_triangle(&t.v[0], &t.v[1], &t.v[2], p).0 - p).norm_squared()
}

/// Closest point on triangle abc to p with the Voronoi region it lies in (Ericson, Real-Time
/// Collision Detection, 5.1.5). Edges are numbered ab = 0, bc = 1, ca = 2.
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
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
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
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, Region::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
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

    fn square() -> Mesh {
        let raw = vec![
            [Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
            [Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.0)],
        ];
        Mesh::new("sq", 1, raw).unwrap()
    }

    #[test]
    fn shared_coplanar_edge_counts_once() {
        let m = square();
        // A point exactly above the diagonal's interior, slightly to one side: one face contact.
        let p = Vec3::new(0.5, 0.5 + 1e-9, 0.3);
        let hits: Vec<Vec3> = m.tris.iter().filter_map(|t| closest_point(t, &p)).collect();
        assert_eq!(hits.len(), 1);
        assert!((hits[0] - Vec3::new(0.5, 0.5 + 1e-9, 0.0)).norm() < 1e-12);
        // Outer edges stay active.
        let q = Vec3::new(1.2, 0.5, 0.0);
        let hits: Vec<Vec3> = m.tris.iter().filter_map(|t| closest_point(t, &q)).collect();
        assert_eq!(hits.len(), 1);
    }
}
