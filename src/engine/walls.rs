//! Wall fixes as the deck declares them: a primitive plane or the meshes of a `fix wall/gran`.

/// A primitive plane wall `xplane|yplane|zplane POS`; particles on either side touch it.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneWall {
    pub axis: usize,
    pub pos: f64,
    pub wall_type: usize,
}

/// A `fix wall/gran`: one plane, or the meshes it uses (indices into [`World::meshes`]).
#[derive(Debug, Clone, PartialEq)]
pub enum WallGeom {
    Plane(PlaneWall),
    Meshes(Vec<usize>),
}

#[derive(Debug, Clone, PartialEq)]
pub struct WallFix {
    pub name: String,
    pub geom: WallGeom,
}
