//! Structured hexahedral meshes: a box (verification tests) and one octant of a sphere (the die and
//! Hertz problems).
//!
//! The octant x, y, z ≥ 0 of the sphere of radius r is an inner cube [0, c]³ (c = r/2) plus three
//! mapped blocks, one per axis, reaching from the cube's outer faces to the sphere: the block of
//! axis a joins the cube-face point c·(1, s, t) to the sphere point r·(1, s, t)/|(1, s, t)| (axes
//! permuted), at radial fraction ρ. The contacts are at the poles, the corners s = t = 0 of the
//! blocks, where the contact radius at small load is a = √(R δ); so s and t are graded towards 0
//! and ρ towards the sphere, both by the same smooth map g(ξ) = (e^{βξ} − 1)/(e^β − 1), β = 4
//! (first interval ≈ 0.075/n of the range). Refinement halves every interval in ξ, so the element
//! size shrinks by two everywhere: the sequence needed for Richardson extrapolation.

use std::collections::HashMap;

/// Nodes (reference coordinates) and 8-node hexahedra (see `element::CORNERS` for the order).
#[derive(Clone, Debug)]
pub struct Mesh {
    pub x: Vec<[f64; 3]>,
    pub hex: Vec<[usize; 8]>,
}

/// Grading strength of the octant mesh.
const BETA: f64 = 4.0;

fn grade(xi: f64) -> f64 {
    ((BETA * xi).exp() - 1.0) / (BETA.exp() - 1.0)
}

/// Box [0, l₀]×[0, l₁]×[0, l₂] with n₀×n₁×n₂ elements; `shift` moves every interior node by a
/// fixed pseudo-random fraction of the spacing (distorted elements for the patch test).
pub fn cuboid(l: [f64; 3], n: [usize; 3], shift: f64) -> Mesh {
    let id = |i: usize, j: usize, k: usize| (k * (n[1] + 1) + j) * (n[0] + 1) + i;
    let mut x = Vec::new();
    for k in 0..=n[2] {
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                let idx = [i, j, k];
                let mut p = [0.0; 3];
                for d in 0..3 {
                    let h = l[d] / n[d] as f64;
                    p[d] = idx[d] as f64 * h;
                    let interior = (0..3).all(|e| idx[e] > 0 && idx[e] < n[e]);
                    if interior {
                        // deterministic irregular offsets in (−shift, shift)·h
                        let s = ((i * 7 + j * 13 + k * 29 + d * 3) % 11) as f64 / 10.0 - 0.5;
                        p[d] += 2.0 * shift * s * h;
                    }
                }
                x.push(p);
            }
        }
    }
    let mut hex = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                hex.push([
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                    id(i, j, k + 1),
                    id(i + 1, j, k + 1),
                    id(i + 1, j + 1, k + 1),
                    id(i, j + 1, k + 1),
                ]);
            }
        }
    }
    Mesh { x, hex }
}

/// Where the octant's surface intervals are refined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Grading {
    /// Towards the poles on the axes (s, t → 0): the contacts of a sphere between walls.
    Poles,
    /// Towards the poles and towards the diagonal (1, 1, 1) where three blocks meet (s, t → 1):
    /// each half of the range graded like `Poles`, for the contact along a bcc cell's diagonal.
    PolesAndDiagonal,
}

/// One octant of the sphere of radius `r`, centred at the origin, with `n` intervals along each
/// cube edge and each block's surface edge and `n` radial layers per block. Level ℓ of the
/// studies is n = 4·2^{ℓ−1}.
pub fn sphere_octant(r: f64, n: usize) -> Mesh {
    sphere_octant_graded(r, n, Grading::Poles)
}

/// [`sphere_octant`] with a choice of [`Grading`]; `PolesAndDiagonal` needs an even `n`.
pub fn sphere_octant_graded(r: f64, n: usize, grading: Grading) -> Mesh {
    let c = 0.5 * r;
    let m = n;
    let mut x = Vec::new();
    // Key: (min(index, n) per axis, radial layer), which names a node shared by two blocks once.
    let mut ids: HashMap<([usize; 3], usize), usize> = HashMap::new();
    let mut node = |key: ([usize; 3], usize), p: [f64; 3], x: &mut Vec<[f64; 3]>| -> usize {
        *ids.entry(key).or_insert_with(|| {
            x.push(p);
            x.len() - 1
        })
    };
    let gn = |i: usize| match grading {
        Grading::Poles => grade(i as f64 / n as f64),
        Grading::PolesAndDiagonal if 2 * i <= n => 0.5 * grade(2.0 * i as f64 / n as f64),
        Grading::PolesAndDiagonal => 1.0 - 0.5 * grade(2.0 * (n - i) as f64 / n as f64),
    };
    let mut hex = Vec::new();
    // Inner cube.
    let mut cube = vec![0usize; (n + 1).pow(3)];
    let cid = |i: usize, j: usize, k: usize| (k * (n + 1) + j) * (n + 1) + i;
    for k in 0..=n {
        for j in 0..=n {
            for i in 0..=n {
                cube[cid(i, j, k)] = node(([i, j, k], 0), [c * gn(i), c * gn(j), c * gn(k)], &mut x);
            }
        }
    }
    let lattice =
        |ids: [[usize; 3]; 8], f: &dyn Fn(usize, usize, usize) -> usize| ids.map(|[a, b, d]| f(a, b, d));
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                hex.push(lattice(
                    [
                        [i, j, k],
                        [i + 1, j, k],
                        [i + 1, j + 1, k],
                        [i, j + 1, k],
                        [i, j, k + 1],
                        [i + 1, j, k + 1],
                        [i + 1, j + 1, k + 1],
                        [i, j + 1, k + 1],
                    ],
                    &|a, b, d| cube[cid(a, b, d)],
                ));
            }
        }
    }
    // Three blocks: axis a, the other two axes (b, d) carry the surface parameters (s, t).
    for a in 0..3 {
        let (b, d) = ((a + 1) % 3, (a + 2) % 3);
        let mut blk = vec![0usize; (m + 1) * (n + 1) * (n + 1)];
        let bid = |l: usize, p: usize, q: usize| (q * (n + 1) + p) * (m + 1) + l;
        for q in 0..=n {
            for p in 0..=n {
                let (s, t) = (gn(p), gn(q));
                let norm = (1.0 + s * s + t * t).sqrt();
                for l in 0..=m {
                    let rho = 1.0 - grade(1.0 - l as f64 / m as f64);
                    let mut pt = [0.0; 3];
                    let dir = [1.0, s, t];
                    for (e, ax) in [a, b, d].into_iter().enumerate() {
                        pt[ax] = (1.0 - rho) * c * dir[e] + rho * r * dir[e] / norm;
                    }
                    let mut key = [0usize; 3];
                    key[a] = n;
                    key[b] = p;
                    key[d] = q;
                    // The pole nodes lie exactly on the axis and on the sphere.
                    if l == m && p == 0 && q == 0 {
                        pt = [0.0; 3];
                        pt[a] = r;
                    }
                    blk[bid(l, p, q)] =
                        if l == 0 { cube[cid(key[0], key[1], key[2])] } else { node((key, l), pt, &mut x) };
                }
            }
        }
        for q in 0..n {
            for p in 0..n {
                for l in 0..m {
                    let mut h = lattice(
                        [
                            [l, p, q],
                            [l + 1, p, q],
                            [l + 1, p + 1, q],
                            [l, p + 1, q],
                            [l, p, q + 1],
                            [l + 1, p, q + 1],
                            [l + 1, p + 1, q + 1],
                            [l, p + 1, q + 1],
                        ],
                        &|u, v, w| blk[bid(u, v, w)],
                    );
                    // (l, p, q) maps to axes (a, a+1, a+2): a cyclic permutation, so right-handed;
                    // kept as a check in case the construction changes.
                    if super::element::geometry(&h.map(|i| x[i])).is_err() {
                        h = [h[0], h[3], h[2], h[1], h[4], h[7], h[6], h[5]];
                    }
                    hex.push(h);
                }
            }
        }
    }
    Mesh { x, hex }
}

impl Mesh {
    /// The mirror image in the plane x_axis = `about`; each hexahedron's bottom and top faces are
    /// swapped so that it stays right-handed.
    pub fn mirrored(&self, axis: usize, about: f64) -> Mesh {
        let x = self
            .x
            .iter()
            .map(|p| {
                let mut q = *p;
                q[axis] = 2.0 * about - q[axis];
                q
            })
            .collect();
        let hex = self.hex.iter().map(|h| [h[4], h[5], h[6], h[7], h[0], h[1], h[2], h[3]]).collect();
        Mesh { x, hex }
    }

    /// Moved rigidly by `by`.
    pub fn translated(&self, by: [f64; 3]) -> Mesh {
        Mesh {
            x: self.x.iter().map(|p| [p[0] + by[0], p[1] + by[1], p[2] + by[2]]).collect(),
            hex: self.hex.clone(),
        }
    }

    /// Nodes closer than `tol` in every coordinate merged into one (the first of them kept), so
    /// that mirrored copies of a mesh joined along their common plane form one body.
    pub fn welded(&self, tol: f64) -> Mesh {
        use std::collections::HashMap;
        let key = |p: &[f64; 3]| p.map(|v| (v / tol).round() as i64);
        let mut first: HashMap<[i64; 3], usize> = HashMap::new();
        let mut map = vec![0; self.x.len()];
        let mut x = Vec::new();
        for (i, p) in self.x.iter().enumerate() {
            map[i] = *first.entry(key(p)).or_insert_with(|| {
                x.push(*p);
                x.len() - 1
            });
        }
        Mesh { x, hex: self.hex.iter().map(|h| h.map(|i| map[i])).collect() }
    }

    /// The whole sphere from one octant centred at the origin: its eight mirror images, welded.
    pub fn whole_from_octant(&self, tol: f64) -> Mesh {
        let mut all = self.clone();
        for mask in 1..8 {
            let mut m = self.clone();
            for axis in 0..3 {
                if mask & (1 << axis) != 0 {
                    m = m.mirrored(axis, 0.0);
                }
            }
            all = all.joined(&m);
        }
        all.welded(tol)
    }

    /// This mesh and `other` as one (disconnected bodies); `other`'s nodes follow this mesh's.
    pub fn joined(&self, other: &Mesh) -> Mesh {
        let off = self.x.len();
        let mut x = self.x.clone();
        x.extend_from_slice(&other.x);
        let mut hex = self.hex.clone();
        hex.extend(other.hex.iter().map(|h| h.map(|i| i + off)));
        Mesh { x, hex }
    }

    /// Volume by the 2×2×2 Gauss rule (exact for trilinear elements' Jacobians of this degree).
    pub fn volume(&self) -> Result<f64, String> {
        let mut v = 0.0;
        for h in &self.hex {
            v += super::element::geometry(&h.map(|i| self.x[i]))?.w.iter().sum::<f64>();
        }
        Ok(v)
    }
    /// Smallest edge length at the node `pole` (the element size where a contact starts).
    pub fn edge_at(&self, pole: usize) -> f64 {
        let mut h = f64::INFINITY;
        for e in self.hex.iter().filter(|e| e.contains(&pole)) {
            for &i in e.iter().filter(|&&i| i != pole) {
                let d = (0..3).map(|k| (self.x[i][k] - self.x[pole][k]).powi(2)).sum::<f64>().sqrt();
                h = h.min(d);
            }
        }
        h
    }
}
