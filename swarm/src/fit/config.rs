//! What a fit measures ([`FitConfig`]): the controller, the firmware image under test and its
//! phases, and why a measurement fails ([`FitError`]).

use crate::scenario::ControllerKind;
use crate::seeds::robot_stream;
use robot_board::board::BoardError;
use robot_board::firmware::{BlockError, Firmware, FirmwareError, RunError};
use robot_board::model::{ControllerConfig, ControllerError};
use robot_board::profile::{PhaseDef, UnknownFunction};
use seeding::Purpose;

/// Endurance of a 24LC256 page: 1 000 000 write cycles (docs/design.md §3.6; Microchip DS21203).
pub const ENDURANCE_CYCLES: f64 = 1_000_000.0;

/// Longest boot the fit waits for before calling the image stuck: 10 s of MCU time.
pub const BOOT_LIMIT_S: f64 = 10.0;

/// What to measure.
#[derive(Clone, Debug)]
pub struct FitConfig {
    /// The controller's settings (the firmware gets them through its configuration block).
    pub controller: ControllerConfig,
    /// Step periods to run (after boot).
    pub steps: u32,
    /// The master seed: the fit's robot is robot 0 of repeat 0 under it ([`crate::seeds`]), whose
    /// streams give its sensors, their distances and its EEPROMs. (The initial weights come
    /// with [`Self::controller`]; the commands take them from the same robot,
    /// [`fit_weight_seed`].)
    pub seed: u64,
    /// Which controller the verdict is about.
    pub kind: ControllerKind,
    /// The image when `kind` is [`ControllerKind::Firmware`] (and the ROM figure of the model).
    pub firmware: FirmwareUnderTest,
    /// Also run the other controller and put its figures beside each phase.
    pub compare: bool,
    /// Stop the measurement at the image's first access to a register the emulated chip does
    /// not model (or a reserved address) instead of noting it in the verdict.
    pub strict_io: bool,
}

/// Why the fit could not be measured.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// The model controller refused the settings.
    #[error(transparent)]
    Controller(#[from] ControllerError),
    /// The configuration block cannot carry a setting.
    #[error(transparent)]
    Block(#[from] BlockError),
    /// The image could not be used.
    #[error(transparent)]
    Firmware(#[from] FirmwareError),
    /// A phase names a function the image lacks.
    #[error(transparent)]
    Phase(#[from] UnknownFunction),
    /// The firmware rejected its configuration block.
    #[error("the firmware rejected its configuration block: {field} (cfg_status 0x{code:02X})")]
    Rejected {
        /// The field, as the firmware names it.
        field: &'static str,
        /// The status byte.
        code: u8,
    },
    /// The firmware stopped.
    #[error("the firmware stopped at state {at}")]
    Run {
        /// When.
        at: u64,
        /// Why.
        #[source]
        source: RunError,
    },
    /// The firmware never went to sleep after reset.
    #[error(
        "the firmware did not reach SLEEP within {BOOT_LIMIT_S} s of reset (PC H'{pc:06X}): the fit counts boot up to the first SLEEP"
    )]
    BootTimeout {
        /// Where it was.
        pc: u32,
    },
    /// The step's first phase did not come again.
    #[error(
        "the next step's `{phase}` did not begin within two step periods and {BOOT_LIMIT_S} s (PC H'{pc:06X})"
    )]
    StepTimeout {
        /// The phase the step periods start with.
        phase: String,
        /// Where the CPU was.
        pc: u32,
    },
    /// The MCU could not be built.
    #[error("building the MCU")]
    Mcu(#[from] BoardError),
    /// A what-if on an image without a configuration block.
    #[error(
        "`{image}` has no configuration block (symbol config_block at H'000400), so the settings cannot reach it; measure it without what-ifs"
    )]
    NoBlock {
        /// The image.
        image: String,
    },
    /// A sensor model refused the clock.
    #[error("clock_hz = {clock_hz}: {why}")]
    Sensor {
        /// The clock.
        clock_hz: u32,
        /// The sensor model's reason.
        why: String,
    },
}

/// A firmware image to measure and its phases.
#[derive(Clone, Debug)]
pub struct FirmwareUnderTest {
    /// The image and its symbols.
    pub firmware: Firmware,
    /// The phases, each a name and its functions (see [`robot_phases`]).
    pub phases: Vec<PhaseDef>,
}

impl FirmwareUnderTest {
    /// The robot firmware with its phases.
    ///
    /// # Errors
    /// Only if the built-in image were damaged.
    pub fn robot() -> Result<Self, FirmwareError> {
        Ok(FirmwareUnderTest {
            firmware: Firmware::robot()?,
            phases: robot_phases(),
        })
    }
}

/// The robot firmware's phases, in report order, and the functions that make them (docs/design.md §8).
#[must_use]
pub fn robot_phases() -> Vec<PhaseDef> {
    vec![
        PhaseDef::new(PHASE_ADC, &["ad_scan"]),
        PhaseDef::new(PHASE_INPUT, &["learner_step"]),
        PhaseDef::new(PHASE_UPDATE, &["learner_update"]),
        PhaseDef::new(PHASE_FORWARD, &["learner_forward"]),
        PhaseDef::new(PHASE_MOTORS, &["motors_set"]),
        PhaseDef::new(PHASE_SAVE, &["record_save"]),
        PhaseDef::new(PHASE_TICKS, &["tick_isr"]),
        PhaseDef::new(PHASE_BOOT, &["boot"]),
    ]
}

/// Phase names shared by the firmware's profile and the model's accounting.
pub(super) const PHASE_ADC: &str = "A/D";

pub(super) const PHASE_INPUT: &str = "input";

pub(super) const PHASE_UPDATE: &str = "update";

pub(super) const PHASE_FORWARD: &str = "forward";

pub(super) const PHASE_MOTORS: &str = "motors";

pub(super) const PHASE_SAVE: &str = "EEPROM save (amortised)";

pub(super) const PHASE_TICKS: &str = "tick interrupts";

pub(super) const PHASE_BOOT: &str = "boot";

pub(super) const PHASE_OTHER: &str = "main loop and the rest";

/// The initial-weight seed of the fit's robot under master seed `seed`: robot 0 of repeat 0's
/// weight stream, as in a run.
#[must_use]
pub const fn fit_weight_seed(seed: u64) -> u64 {
    robot_stream(seed, 0, 0, 0, Purpose::Weights)
}
