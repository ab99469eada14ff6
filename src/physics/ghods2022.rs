//! Advanced multi-contact switch: Ghods, Poorsolhjouy, Gonzalez & Radl, Powder Technol. 401
//! (2022) 117288, Eq. 3 and App. A.
//!
//! For contact c of particle i every neighbour term δ_{k→c} of Eq. 2 is computed first; if any of
//! them exceeds δ_max = MPR · r_i, contact c falls back to plain Hertz (no correction at all),
//! otherwise it uses δ_c + Σ_k δ_{k→c}. The decision does not depend on the order of the contacts.

use std::fmt;
use std::str::FromStr;

/// How a neighbour term is compared with δ_max (docs/spec.md §3, a named option recorded in every output).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MprTest {
    /// |δ_{k→c}| > δ_max trips the switch (default): MPR = 0 is exactly Hertz and MPR ≥ 1 is
    /// practically standard MC.
    #[default]
    Abs,
    /// δ_{k→c} > δ_max trips the switch: the literal reading of App. A line 8 (only growth counts).
    Signed,
}

impl MprTest {
    pub fn as_str(self) -> &'static str {
        match self {
            MprTest::Abs => "abs",
            MprTest::Signed => "signed",
        }
    }
}

impl fmt::Display for MprTest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for MprTest {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "abs" => Ok(MprTest::Abs),
            "signed" => Ok(MprTest::Signed),
            other => Err(format!("unknown mprTest '{other}': expected 'abs' or 'signed'")),
        }
    }
}

/// The maximum-penetration-ratio cap of Eq. 3.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cap {
    /// MPR = δ_max / r_i [-], ≥ 0.
    pub mpr: f64,
    pub test: MprTest,
}

impl Cap {
    /// δ_max = MPR · r_i, with r_i the original radius of the particle that owns the contact.
    #[inline]
    pub fn delta_max(&self, radius: f64) -> f64 {
        self.mpr * radius
    }

    /// Eq. 3 / App. A line 8: does this neighbour term switch the contact back to Hertz?
    #[inline]
    pub fn trips(&self, term: f64, delta_max: f64) -> bool {
        match self.test {
            MprTest::Abs => term.abs() > delta_max,
            MprTest::Signed => term > delta_max,
        }
    }
}
