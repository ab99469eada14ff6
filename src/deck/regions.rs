//! `region ID block|cylinder|sphere|mesh/tet …`: the box (`create_box`), the volumes `fix
//! insert/pack` fills, the volumes of `group` and `create_atoms`.

use super::*;

/// A region (LIGGGHTS `units box`, `side in`).
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Region {
    /// xlo xhi ylo yhi zlo zhi.
    Block([f64; 6]),
    /// A circular cylinder along axis `axis` (0 x, 1 y, 2 z): centre (c1, c2) in the other two
    /// coordinates in order, radius r, from lo to hi along the axis.
    Cylinder {
        axis: usize,
        c: [f64; 2],
        r: f64,
        lo: f64,
        hi: f64,
    },
    Sphere {
        c: Vec3,
        r: f64,
    },
    /// `mesh/tet`: the tetrahedra of a VTK mesh ([`tet_mesh`]).
    TetMesh(Box<tet_mesh::TetMesh>),
}

impl Region {
    /// Volume (m³), exact: LIGGGHTS estimates it by Monte Carlo (`ntry_mc`).
    pub(super) fn volume(&self) -> f64 {
        match self {
            Region::Block(b) => (b[1] - b[0]) * (b[3] - b[2]) * (b[5] - b[4]),
            Region::Cylinder { r, lo, hi, .. } => std::f64::consts::PI * r * r * (hi - lo),
            Region::Sphere { r, .. } => 4.0 / 3.0 * std::f64::consts::PI * r * r * r,
            Region::TetMesh(m) => m.volume(),
        }
    }

    /// The bounding box: lower and upper corners.
    pub(super) fn bounds(&self) -> (Vec3, Vec3) {
        match self {
            Region::Block(b) => (Vec3::new(b[0], b[2], b[4]), Vec3::new(b[1], b[3], b[5])),
            Region::Cylinder { axis, c, r, lo, hi } => {
                let (mut l, mut h) = (Vec3::zeros(), Vec3::zeros());
                let (u, v) = cross_axes(*axis);
                (l[*axis], h[*axis]) = (*lo, *hi);
                (l[u], h[u]) = (c[0] - r, c[0] + r);
                (l[v], h[v]) = (c[1] - r, c[1] + r);
                (l, h)
            }
            Region::Sphere { c, r } => (c - Vec3::new(*r, *r, *r), c + Vec3::new(*r, *r, *r)),
            Region::TetMesh(m) => m.bounds(),
        }
    }

    /// Whether a sphere of radius `margin` around `x` lies inside (`margin` 0: the point is inside;
    /// the surface counts as inside, as in LIGGGHTS).
    pub(super) fn holds(&self, x: &Vec3, margin: f64) -> bool {
        match self {
            Region::Block(b) => (0..3).all(|k| x[k] - margin >= b[2 * k] && x[k] + margin <= b[2 * k + 1]),
            Region::Cylinder { axis, c, r, lo, hi } => {
                let (u, v) = cross_axes(*axis);
                let (du, dv) = (x[u] - c[0], x[v] - c[1]);
                let a = x[*axis];
                a - margin >= *lo && a + margin <= *hi && (du * du + dv * dv).sqrt() + margin <= *r
            }
            Region::Sphere { c, r } => (x - c).norm() + margin <= *r,
            // Only centres are tested against a tet mesh (insertion into one is refused, see
            // `Deck::insert_pack`): LIGGGHTS has no distance to its surface either.
            Region::TetMesh(m) => margin == 0.0 && m.holds(x),
        }
    }
}

/// The two coordinates across an axis, in LIGGGHTS' order for `region cylinder` (x: y z, y: x z,
/// z: x y).
fn cross_axes(axis: usize) -> (usize, usize) {
    match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

fn finite(s: &str, what: &str) -> R<f64> {
    if matches!(s, "INF" | "-INF" | "EDGE") {
        return Err(unsupported(&format!("region bound {s} (give {what} as a number)")));
    }
    let v = num(s)?;
    if !v.is_finite() {
        return Err(format!("region: {what} must be finite, got {s}"));
    }
    Ok(v)
}

impl Deck {
    pub(super) fn region(&mut self, a: &[&str]) -> R<()> {
        commands::need(a, 3)?;
        let (region, nargs) = match a[2] {
            "block" => {
                commands::need(a, 9)?;
                let mut b = [0.0; 6];
                for (k, v) in b.iter_mut().enumerate() {
                    *v = finite(a[3 + k], "a block bound")?;
                }
                // (create_box says when a block is empty.)
                (Region::Block(b), 6)
            }
            "cylinder" => {
                commands::need(a, 9)?;
                let axis = match a[3] {
                    "x" => 0,
                    "y" => 1,
                    "z" => 2,
                    other => return Err(format!("region cylinder: axis must be x, y or z, got '{other}'")),
                };
                let c = [finite(a[4], "the centre")?, finite(a[5], "the centre")?];
                let r = finite(a[6], "the radius")?;
                let (lo, hi) = (finite(a[7], "lo")?, finite(a[8], "hi")?);
                if r <= 0.0 {
                    return Err(format!("region cylinder: radius must be > 0, got {}", a[6]));
                }
                if hi <= lo {
                    return Err(format!("region cylinder: hi ({hi}) must exceed lo ({lo})"));
                }
                (Region::Cylinder { axis, c, r, lo, hi }, 6)
            }
            "sphere" => {
                commands::need(a, 7)?;
                let c = Vec3::new(
                    finite(a[3], "the centre")?,
                    finite(a[4], "the centre")?,
                    finite(a[5], "the centre")?,
                );
                let r = finite(a[6], "the radius")?;
                if r <= 0.0 {
                    return Err(format!("region sphere: radius must be > 0, got {}", a[6]));
                }
                (Region::Sphere { c, r }, 4)
            }
            "mesh/tet" => self.region_mesh_tet(a)?,
            other => {
                return Err(unsupported(&format!(
                    "region style {other} (block, cylinder, sphere or mesh/tet)"
                )))
            }
        };
        let mut k = 3 + nargs;
        while k < a.len() {
            match (a[k], a.get(k + 1)) {
                ("units", Some(&"box")) => k += 2,
                ("side", Some(&"in")) => k += 2,
                _ => return Err(unsupported(&format!("region keyword {}", a[k]))),
            }
        }
        self.regions.insert(a[1].into(), region);
        Ok(())
    }
}
