//! "Does it fit the H8/3052?" (docs/design.md §6), measured by running the controller on the
//! emulated MCU ([`measure()`]): by default the robot firmware (`firmware/robot.mot`) on the
//! H8/300H core, with the Rust model of the controller (`robot_board::model`) beside it.
//!
//! Its parts: [`config`] (what is measured), [`meter`] (the rig: the MCU and its sensors, and
//! the phase meter), [`firmware`] (the firmware's run), [`mod@measure`] (both controllers),
//! [`verdict`] (the report's lines, margins and verdict), [`report`] (the report's types) and
//! [`budget`] (the largest network within a CPU budget).

pub mod budget;
pub mod config;
pub mod firmware;
pub mod measure;
pub mod meter;
pub mod report;
pub mod verdict;

pub use budget::{Budget, largest_fitting};
pub use config::{
    BOOT_LIMIT_S, ENDURANCE_CYCLES, FirmwareUnderTest, FitConfig, FitError, fit_weight_seed,
    robot_phases,
};
pub use measure::measure;
pub use meter::FitBoard;
pub use report::{
    EepromLine, EnergyReport, FitReport, MemLine, PartLine, PhaseLine, Spread, StackLine,
};
