//! The standalone DEM (`mcdem run`): conservation, decks, insertion, walls (fixed, moving and conveyor meshes), the multi-contact laws through the engine, threads, sorting, shear, and step-by-step agreement with LIGGGHTS.
//!
//! One test binary per area (each module below was a binary of its own).

#[allow(dead_code)] // not every helper is used by every area
#[path = "../common/mod.rs"]
mod common;

mod adapt;
mod against_liggghts;
mod cohesion_hysteresis;
mod conservation;
mod deck;
mod eq2_fixed_point;
mod groups_lattice;
mod insert;
mod mc_advanced;
mod mc_approximations;
mod mc_budget;
mod mesh_walls;
mod moving_meshes;
mod mpr_test;
mod portable;
mod restart;
mod rolling_epsd;
mod rolling_friction;
mod shear;
mod sorting;
mod threads;
