//! Nonlocal quasi-static reference (Gonzalez & Cuitiño, J. Mech. Phys. Solids 60 (2012) 333;
//! docs/spec.md §4): static equilibrium of elastic, frictionless spheres between rigid walls, where each
//! contact force deforms its particle at all the particle's other contacts.
//!
//! - [`kernel`]: the compliance G of one particle's surface at one contact to the load at another
//!   (`sphere`: finite elastic sphere, Legendre series; `boussinesq`: half-space; `none`).
//! - [`solver`]: Newton with an exact sparse Jacobian, active set, line search and load stepping.
//! - [`uniaxial`]: piston compression of a packing in a rigid box (the 514-particle hydrogel
//!   reference curve σ(φ)).
//! - [`scene`]: the JSON scene format, the LIGGGHTS data-file reader and the CSV-writing driver
//!   behind `mcdem nonlocal SCENE` (documented in `docs/nonlocal.md`).

pub mod kernel;
pub mod scene;
pub mod solver;
pub mod uniaxial;

pub use kernel::{Kernel, KernelKind};
pub use solver::{ContactState, Nonlocal, Other, Settings, SolveError, Sphere, StepStats, Wall};
