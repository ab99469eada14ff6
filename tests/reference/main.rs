//! The references the contact laws are measured against: the nonlocal solver (Hertz limit, die, bcc, parity with the DEM, the 514-particle compression) and the finite-element continuum.
//!
//! One test binary per area (each module below was a binary of its own).

mod fem;
mod fem_in_report;
mod nonlocal;
mod nonlocal_parity;
mod nonlocal_uniaxial;
