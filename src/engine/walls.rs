//! Wall fixes as the deck declares them: a primitive plane or the meshes of a `fix wall/gran`.

use crate::physics::Vec3;

/// A primitive plane wall `xplane|yplane|zplane POS`; particles on either side touch it.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneWall {
    pub axis: usize,
    pub pos: f64,
    pub wall_type: usize,
}

/// A primitive cylinder wall `xcylinder|ycylinder|zcylinder R C1 C2`, as LIGGGHTS defines it: the
/// axis is parallel to `axis` through (C1, C2) in the cross coordinates (axis + 1, axis + 2) mod 3,
/// and particles touch it from inside and from outside. Like LIGGGHTS' primitive walls, the contact
/// law sees a flat wall at the nearest surface point (the wall's own curvature is not in R*).
#[derive(Debug, Clone, PartialEq)]
pub struct CylinderWall {
    pub axis: usize,
    pub radius: f64,
    pub center: [f64; 2],
    pub wall_type: usize,
}

impl CylinderWall {
    /// The point of the surface nearest to `x`; `None` on the axis itself, where every surface
    /// point is equally near (a radius away, so out of reach of any particle that fits inside).
    pub fn nearest(&self, x: &Vec3) -> Option<Vec3> {
        let (u, v) = ((self.axis + 1) % 3, (self.axis + 2) % 3);
        let (du, dv) = (x[u] - self.center[0], x[v] - self.center[1]);
        let rho = du.hypot(dv);
        if rho == 0.0 {
            return None;
        }
        let mut q = *x;
        q[u] = self.center[0] + du * self.radius / rho;
        q[v] = self.center[1] + dv * self.radius / rho;
        Some(q)
    }
}

/// A `fix wall/gran`: one plane, or the meshes it uses (indices into [`World::meshes`]).
#[derive(Debug, Clone, PartialEq)]
pub enum WallGeom {
    Plane(PlaneWall),
    Cylinder(CylinderWall),
    Meshes(Vec<usize>),
}

#[derive(Debug, Clone, PartialEq)]
pub struct WallFix {
    pub name: String,
    pub geom: WallGeom,
}

impl WallGeom {
    /// The 0-based atom type of the wall element a contact touches: the primitive's own, or that
    /// of mesh `mesh` (an index into `meshes`).
    pub(super) fn wall_type(&self, meshes: &[super::Mesh], mesh: u32) -> usize {
        match self {
            WallGeom::Plane(pl) => pl.wall_type,
            WallGeom::Cylinder(cy) => cy.wall_type,
            WallGeom::Meshes(_) => meshes[mesh as usize].wall_type,
        }
    }
}
