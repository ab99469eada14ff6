//! Parameter studies run with the standalone engine in-process (`mcdem study …`).

pub mod fit;
pub mod shear;
