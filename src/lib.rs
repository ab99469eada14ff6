//! mcdem: the advanced multi-contact (MC) contact model of Ghods et al. (2022) for strongly
//! deformed soft particles, with the standard MC closure of Brodu et al. (2015) and Hertz as its
//! limits.
//!
//! Layers point inward: [`physics`] is the single implementation of the contact laws; [`ffi`] exposes
//! it to C/C++ (the LIGGGHTS plugin); the command-line front end lives in `src/main.rs`.

pub mod bench;
pub mod checks;
pub mod compare;
pub mod contacts_cli;
pub mod deck;
pub mod engine;
pub mod fem;
pub mod ffi;
pub mod harness;
#[cfg(feature = "liggghts")]
pub mod liggghts;
pub mod mpm;
pub mod nonlocal;
pub mod outputs;
pub mod physics;
pub mod rng;
pub mod study;
pub mod team;
pub mod validate;
pub mod vtk_legacy;
