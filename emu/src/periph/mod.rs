//! On-chip peripherals of the H8/3052F, one file per module (as in simavr).

pub mod sci;
