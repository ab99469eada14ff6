//! The standalone DEM engine: particle state as a struct of arrays, cell-list neighbours with a
//! skin, contact history keyed by particle ids, walls (primitive planes and STL meshes), periodic
//! boundaries and velocity Verlet with rotation (LIGGGHTS `fix nve/sphere`).
//!
//! Contact forces come only from [`crate::physics`]: this module does geometry bookkeeping and
//! integration, never a contact formula of its own.
//!
//! One step follows the LAMMPS/LIGGGHTS Verlet order, so both engines agree step by step:
//! first half kick + drift (and mesh motion), neighbour check, forces (multi-contact radius
//! changes, pairs, gravity, walls), second half kick. [`World::step`] reads as that list; each
//! stage is a file of its own:
//!
//! - `world`: the system, its set-up and its step; `domain`, `particles`, `walls`, `mesh`: what
//!   it is made of; `contacts`: pair records and wall contacts with their history;
//! - `integrate`: the half-kicks and the drift;
//! - `neighbor_list` (with the cell list of `neighbor`): the skin test, list rebuilds and sorting;
//! - `wall_pass` (with the search of `wall_contacts`): wall contacts and their forces;
//! - `multicontact`: the radius changes of Eq. 2 (iterated within the step by `mc_fixed_point`);
//! - `pair_pass`: the pair forces by one of three strategies, evaluated by `pair_eval` into one
//!   of the `sinks`;
//! - `blocks` (with the timing `probe`): the threads' team and the pair blocks;
//! - `observe`: energies, stress, contact counts.

mod blocks;
mod contacts;
mod domain;
mod integrate;
mod mc_budget;
mod mc_fixed_point;
pub mod mesh;
pub mod mesh_motion;
mod multicontact;
pub mod neighbor;
mod neighbor_list;
mod observe;
mod pair_eval;
mod pair_pass;
mod particles;
mod probe;
mod restart;
mod sinks;
mod wall_contacts;
mod wall_pass;
mod walls;
mod world;

pub use blocks::{PairThreads, THREAD_PROBE_STEPS};
pub use contacts::PairContact;
pub use domain::Domain;
pub use mc_budget::{BudgetStats, DEFAULT_CHECK_EVERY, FLOOR_STRAIN, WHY as BUDGET_WHY};
pub use mc_fixed_point::{FixedPoint, FixedPointStats};
pub use mesh::Mesh;
pub use mesh_motion::{Motion, Mover};
pub use particles::{Particles, GROUP_ALL};
pub use restart::{EngineState, ParticleState, WallContactState};
pub use walls::{CylinderWall, PlaneWall, WallFix, WallGeom};
pub use world::{Closure, StepError, World};
