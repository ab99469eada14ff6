//! Regular background grid of 4-node quadrilaterals (D = 2) or 8-node hexahedra (D = 3), one code
//! for both dimensions: multilinear shape functions N_I(x) = Π_d N¹(ξ_d) on cells of size h.
//!
//! The grid is the MPM's computational mesh (Nezamabadi et al. 2019, Section 2): N_p and G_p of
//! Eq. 4 are the values and gradients returned by [`Grid::stencil`].

use nalgebra::{SMatrix, SVector};

/// A point of the space.
pub type Vector<const D: usize> = SVector<f64, D>;

/// Corners of a cell: 2^D ≤ 8.
pub const MAX_CORNERS: usize = 8;

/// Regular grid: `cells[d]` cells of size `h` along axis d from `origin`.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid<const D: usize> {
    pub origin: Vector<D>,
    pub h: f64,
    pub cells: [usize; D],
}

/// The shape-function values and gradients of the 2^D nodes of the cell that holds one point.
#[derive(Clone, Copy, Debug)]
pub struct Stencil<const D: usize> {
    pub nodes: [usize; MAX_CORNERS],
    pub n: [f64; MAX_CORNERS],
    pub grad: [Vector<D>; MAX_CORNERS],
}

impl<const D: usize> Stencil<D> {
    /// Corners in use (2^D).
    pub const LEN: usize = 1 << D;
}

impl<const D: usize> Grid<D> {
    pub fn new(origin: Vector<D>, h: f64, cells: [usize; D]) -> Result<Self, String> {
        const { assert!(D == 2 || D == 3, "the MPM is written for D = 2 or 3") };
        if !(h.is_finite() && h > 0.0) {
            return Err(format!("grid cell size h must be positive, got {h}"));
        }
        if cells.contains(&0) {
            return Err("the grid needs at least one cell along each axis".into());
        }
        Ok(Self { origin, h, cells })
    }

    /// Keeps a body's proper grid around its points as it moves (multi-mesh scheme, Section 2.2):
    /// when the points' bounding box [lo, hi] comes within `room` cells of the grid's edge, the
    /// window is re-centred on the box by a whole number of cells (so it stays on the common
    /// lattice) and widened if the box has outgrown it. A grid carries no state between steps
    /// (Section 2), so moving it changes nothing else. Returns whether it moved.
    pub fn follow(&mut self, lo: &Vector<D>, hi: &Vector<D>, room: usize) -> bool {
        let pad = room as f64 * self.h;
        let fits = (0..D).all(|d| {
            lo[d] - pad >= self.origin[d] && hi[d] + pad <= self.origin[d] + self.cells[d] as f64 * self.h
        });
        if fits {
            return false;
        }
        for d in 0..D {
            let need = ((hi[d] - lo[d]) / self.h).ceil() as usize + 2 * room + 2;
            self.cells[d] = self.cells[d].max(need);
            let centre = 0.5 * (lo[d] + hi[d]);
            let now = self.origin[d] + 0.5 * self.cells[d] as f64 * self.h;
            self.origin[d] += ((centre - now) / self.h).round() * self.h;
        }
        true
    }

    /// Nodes along each axis.
    pub fn nodes_per_axis(&self) -> [usize; D] {
        self.cells.map(|c| c + 1)
    }

    pub fn n_nodes(&self) -> usize {
        self.nodes_per_axis().iter().product()
    }

    /// Linear node index, axis 0 fastest.
    pub fn node_index(&self, ijk: [usize; D]) -> usize {
        let npa = self.nodes_per_axis();
        let mut idx = 0;
        for d in (0..D).rev() {
            idx = idx * npa[d] + ijk[d];
        }
        idx
    }

    /// Integer coordinates of a node.
    pub fn node_ijk(&self, mut idx: usize) -> [usize; D] {
        let npa = self.nodes_per_axis();
        let mut out = [0; D];
        for d in 0..D {
            out[d] = idx % npa[d];
            idx /= npa[d];
        }
        out
    }

    pub fn node_position(&self, idx: usize) -> Vector<D> {
        let ijk = self.node_ijk(idx);
        Vector::<D>::from_fn(|d, _| self.origin[d] + self.h * ijk[d] as f64)
    }

    /// Upper corner of the grid.
    pub fn upper(&self) -> Vector<D> {
        Vector::<D>::from_fn(|d, _| self.origin[d] + self.h * self.cells[d] as f64)
    }

    /// Shape functions of the cell holding `x`, or `None` when `x` is outside the grid.
    pub fn stencil(&self, x: &Vector<D>) -> Option<Stencil<D>> {
        let mut cell = [0usize; D];
        let mut xi = [0.0; D];
        for d in 0..D {
            let s = (x[d] - self.origin[d]) / self.h;
            if !(s >= 0.0 && s < self.cells[d] as f64) {
                return None;
            }
            let c = (s.floor() as usize).min(self.cells[d] - 1);
            cell[d] = c;
            xi[d] = s - c as f64;
        }
        let mut st = Stencil {
            nodes: [0; MAX_CORNERS],
            n: [0.0; MAX_CORNERS],
            grad: [Vector::<D>::zeros(); MAX_CORNERS],
        };
        for corner in 0..Stencil::<D>::LEN {
            let mut ijk = cell;
            // 1-D factors of this corner: N¹ = ξ at the upper node, 1 − ξ at the lower one.
            let mut fac = [0.0; D];
            let mut dfac = [0.0; D];
            for d in 0..D {
                let upper = (corner >> d) & 1 == 1;
                ijk[d] += upper as usize;
                fac[d] = if upper { xi[d] } else { 1.0 - xi[d] };
                dfac[d] = if upper { 1.0 / self.h } else { -1.0 / self.h };
            }
            st.nodes[corner] = self.node_index(ijk);
            st.n[corner] = fac.iter().product();
            for d in 0..D {
                let others: f64 = (0..D).filter(|&e| e != d).map(|e| fac[e]).product();
                st.grad[corner][d] = dfac[d] * others;
            }
        }
        Some(st)
    }
}

/// ΔF_p = I + Σ_I u_I ⊗ ∇N_I(x_p).
pub fn incremental_gradient<const D: usize>(
    st: &Stencil<D>,
    dof_of: &[usize],
    u: &[f64],
) -> SMatrix<f64, D, D> {
    let mut df = SMatrix::<f64, D, D>::identity();
    for c in 0..Stencil::<D>::LEN {
        let a = dof_of[st.nodes[c]];
        for i in 0..D {
            for j in 0..D {
                df[(i, j)] += u[a * D + i] * st.grad[c][j];
            }
        }
    }
    df
}
