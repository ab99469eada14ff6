//! The command line as a user sees it: validate, calibrate, bench, compare, contacts, progress, study shear.
//!
//! One test binary per area (each module below was a binary of its own).

#[allow(dead_code)] // not every helper is used by every area
#[path = "../common/mod.rs"]
mod common;

mod bench;
mod calibrate_resume;
mod compare_vtk;
mod contacts;
mod heldout;
mod progress;
mod study_shear;
mod validate;
