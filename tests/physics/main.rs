//! The contact core: property tests over random inputs and the C ABI seen from C.
//!
//! One test binary per area (each module below was a binary of its own).

mod c_abi;
mod properties;
