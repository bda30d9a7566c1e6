//! The H8/300H CPU core (advanced mode).
pub mod decode;
pub mod disasm;
