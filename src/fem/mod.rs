//! Finite-element continuum reference for one soft sphere between rigid frictionless walls: the
//! ground truth the contact laws (Hertz, standard and advanced multi-contact) and the nonlocal
//! kernels are measured against on the single-particle die of Ghods et al. (2022) App. B.
//!
//! Independent of the MPM solver: 3-D quasi-static total-Lagrangian finite elements with trilinear
//! hexahedra (`element`), linear elastic or compressible Neo-Hookean material (`material`), a
//! mean-dilatation F-bar / B-bar remedy against volumetric locking, frictionless rigid-plane
//! contact by a nodal active set and Newton's method with a line search and a sparse direct solve
//! (`solver`), on a graded octant mesh of the sphere (`mesh`, `octant`). `scene` reads the JSON
//! scene of `mcdem continuum` and writes its CSV and plot.

// The element and material loops index several fixed-size arrays with one index, as the tensor
// notation of the formulas they implement does; iterator chains would hide that correspondence.
#![allow(clippy::needless_range_loop)]

pub mod element;
pub mod material;
pub mod mesh;
pub mod octant;
pub mod scene;
pub mod solver;

pub use element::{Law, Volumetric};
pub use octant::{Point, SphereRun, Walls};

/// Hertz force of one sphere–rigid-plane contact, F = (4/3) E* √R δ^{3/2} with
/// E* = E / (1 − ν²) (Johnson, *Contact Mechanics*, 1985, Eq. 4.22–4.23; rigid plane).
pub fn hertz_plane_force(e: f64, nu: f64, r: f64, delta: f64) -> f64 {
    4.0 / 3.0 * e / (1.0 - nu * nu) * r.sqrt() * delta.max(0.0).powf(1.5)
}

/// Richardson extrapolation from three meshes refined by a constant ratio (coarse f₁, medium f₂,
/// fine f₃): observed order p = log₂((f₁ − f₂)/(f₂ − f₃)) for refinement ratio 2, extrapolated
/// value f₃ + (f₃ − f₂)/(2^p − 1), and as error bar the distance |f_ext − f₃| of the fine mesh from
/// it (Roache, *Verification and Validation in Computational Science*, 1998, §5.4; the
/// "grid-convergence" estimate with safety factor 1). When the three values are not monotone
/// (p undefined) the order is taken as 1 and the error bar as the larger of the two differences,
/// a deliberately conservative fallback.
#[derive(Clone, Copy, Debug)]
pub struct Richardson {
    pub value: f64,
    pub error: f64,
    pub order: f64,
}

pub fn richardson(f1: f64, f2: f64, f3: f64) -> Richardson {
    let (d12, d23) = (f1 - f2, f2 - f3);
    if d23 == 0.0 {
        return Richardson { value: f3, error: d12.abs(), order: f64::INFINITY };
    }
    let q = d12 / d23;
    if q > 1.0 {
        let p = q.log2();
        let value = f3 - d23 / (2f64.powf(p) - 1.0);
        Richardson { value, error: (value - f3).abs(), order: p }
    } else {
        Richardson { value: f3 - d23, error: d12.abs().max(d23.abs()), order: 1.0 }
    }
}
