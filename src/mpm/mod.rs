//! Implicit finite-strain Material Point Method for soft particles (Nezamabadi et al. 2019,
//! Comput. Phys. Commun. 237, 17–25).
//!
//! - [`constitutive`]: P(F) and ∂P/∂F of the Hooke, Saint-Venant–Kirchhoff (Eq. 17) and
//!   Neo-Hookean (Eq. 18) laws;
//! - [`grid`]: the regular background grid, multilinear shape functions, one code for D = 2, 3;
//! - [`points`]: material points and their seeding;
//! - [`implicit`]: the implicit step (Eqs. 4, 5, 10–16, App. A) with rigid frictionless walls;
//! - [`scene`], [`cli`]: JSON scenes and the `mcdem mpm` command (CSV and PNG outputs);
//! - [`vtk`]: VTK snapshots of a run for ParaView (`--vtk-every`).

// The tensor and grid loops index several arrays with the same indices, written as in the equations.
#![allow(clippy::needless_range_loop)]

pub mod cli;
pub mod compaction;
pub mod compaction_fit;
pub mod constitutive;
pub mod contact;
mod contact_law;
mod contact_share;
mod delassus;
mod fbar;
pub mod grid;
pub mod implicit;
pub mod packing;
mod packing_dem;
pub mod points;
pub mod scene;
pub mod vtk;
