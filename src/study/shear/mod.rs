//! `mcdem study shear`: simple shear with Lees–Edwards boundaries over a (φ, μ, ν, γ̂) grid with the
//! advanced multi-contact law (Ghods et al. 2022, Section 4 and App. D), run in-process with the
//! standalone engine, one run per thread.
//!
//! One run: N equal spheres placed by random sequential addition at φ₀ = min(φ, 0.3) in a periodic
//! cube, compressed affinely to φ (box and positions scaled together, no shear), then sheared at
//! constant volume at γ̇ = γ̂ √(k_n/ρ) / d. The shear runs in strain windows; the steady state is
//! reached when the mean pressure of the last `block` windows differs from that of the `block`
//! windows before by less than a tolerance (not before a minimum strain); the last block and
//! `avg_windows` further windows are averaged.
//!
//! Results: one JSON file per finished run in `DIR/runs/` (a restarted study skips those runs),
//! `DIR/runs.csv`, the Eq. 8 fit `DIR/response_surface.csv` next to Tables D.1/D.2, plots and
//! `DIR/report.md`.
//!
//! Files: `protocol` (one run), `grid` (the grid and its options), `runs` (the grid's runs),
//! `recorded_stop` (a stop on record before classification),
//! `paper` (Tables D.1/D.2), `jamming` (φ_c from the rate data, the quasi-static set per μ),
//! `surface` (the Eq. 8 fit over the grid), `report` (CSV, plots, report).

mod grid;
mod jamming;
mod jamming_report;
mod paper;
mod protocol;
mod recorded_stop;
mod report;
mod runs;
mod surface;

pub use grid::{CostRow, Grid, Options};
pub use jamming::{
    crossing, data_fit, jamming, linearised_phi_c, qs_phis, qs_sets, Crossing, DataFit, Jamming, RatePoint,
    N_CROSS,
};
pub use paper::{paper_values, PAPER_ALPHA, PAPER_BETA, PAPER_MU, PAPER_NU};
pub use protocol::{
    classify, classify_from, k_n, run_one, run_one_from, run_refined, sheared_start, time_step, time_unit,
    Protocol, RunResult, RunSpec, Stop, DENSITY, DIAMETER, DT_OVERLAP, DT_PER_CONTACT, FP_PASSES,
    FP_TOLERANCE, OUT_OF_RANGE, PHI_START, RESTITUTION, SKIN, YOUNGS_MODULUS,
};
pub use recorded_stop::recorded_stop;
pub use runs::{run, Summary};
pub use surface::{jamming_of, phi_c_floor, response_surface, SurfaceRow};
