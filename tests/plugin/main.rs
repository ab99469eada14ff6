//! The LIGGGHTS plugin (`pair_style gran model mc_advanced`, feature `liggghts`): decks run by
//! `mcdem-liggghts`, and MPI. The library bindings are tested in `tests/plugin_library.rs`, a binary
//! of its own (LIGGGHTS opened inside a process initialises MPI there, and the `mpirun` children
//! started here would inherit its OpenMPI variables and fail).
//!
//! One test binary per area (each module below was a binary of its own).

#[allow(dead_code)] // not every helper is used by every area
#[path = "../common/mod.rs"]
mod common;

mod decks;
mod mpi;
