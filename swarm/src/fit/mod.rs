//! "Does it fit the H8/3052?" (docs/design.md §6), measured by running the controller on the emulated
//! MCU: by default the robot firmware (`firmware/robot.mot`, docs/design.md §8) on the H8/300H core,
//! with the Rust model of the controller (`robot_board::model`) measured beside it.
//!
//! [`measure`] builds an MCU with four modelled IR sensors (`sensors::IrSensor`, datasheet
//! spread and noise, their own seeds) whose true distances follow a seeded random walk between
//! 30 mm and 1 m (so the learner sees rewards, punishments and dead zones, and the readings
//! include the fold-back), and runs the controller on it for `steps` step periods.
//!
//! With the firmware, the settings reach it through its configuration block (written into the
//! flash at load); boot runs from reset until the first step begins (the first entry into the
//! step's first phase, `ad_scan` for the robot firmware); the step periods are counted from
//! there, one window of K ticks each, so each holds one step and the ticks and idle time up to
//! the next. States are attributed to phases by PC through the image's symbol table,
//! each phase a function with its callees ([`robot_board::profile`]); a window's busy states are
//! all but those asleep. RAM is the image's `.data` and `.bss` (every variable, sized from the
//! symbol table), the network's arrays carved at boot (from the firmware's own pointers), and
//! the stack's high-water mark (the lowest SP the run saw). ROM is the image's bytes.
//!
//! With the model, the phases are the model's own accounting; RAM is its placement of the same
//! items and ROM the firmware image's size (the model has no image of its own).
//!
//! The report gives the maximum and mean states per phase (with the other controller's mean
//! and the ratio when both ran), the time at φ against the step period, the RAM items against
//! the 8 192 bytes, the ROM against the 512 KB of flash, the EEPROM traffic and the lifetime the
//! endurance allows, and a one-line verdict with the tightest margin.

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
