//! The implicit MPM + Contact Dynamics solver (`mcdem mpm`): closed forms, contact, compaction.
//!
//! One test binary per area (each module below was a binary of its own).

mod closed_forms;
mod compaction;
mod contact;
mod disc_plates;
