//! Scenarios: every parameter of an experiment (docs/design.md §3 and §5), as TOML, with the built-in
//! `corridor` (paper env. 1) and `arena` (paper env. 2).
//!
//! A scenario file lists only what differs from the built-in it names in `base` (default
//! `arena`); every table and key is optional, and an unknown key is an error naming it. Values
//! are checked when the scenario is resolved, with messages that name the key and the valid
//! range. `h8swarm run --robots N` on a square arena scales its side to keep the paper's
//! density (3 robots in 1.8 m × 1.8 m: side = 1.8 m · √(N / 3)).

use std::path::Path;

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

/// The arenas of docs/design.md §5.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ArenaKind {
    /// Walled corridor 3.0 m × (body width + 4 cm), robots in one line (paper env. 1).
    Corridor,
    /// Walled square 1.8 m × 1.8 m (paper env. 2), scaled for more robots to keep the density.
    Square,
}

/// The learner and its controller.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LearnerSpec {
    /// Enabled behaviours M: 2 (forward, backward) or 4.
    pub behaviours: usize,
    /// Learning rate η as a real number in [0, 1) (stored in Q15: 0.1 → 3277, 0.001 → 33).
    pub eta: f64,
    /// Dead-zone threshold T in du.
    pub threshold: i32,
    /// History depth H (0–8).
    pub history: usize,
    /// The bias input +127.
    pub bias: bool,
    /// One EEPROM record every this many steps.
    pub save_every: u32,
}

/// Timing of the robot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TimingSpec {
    /// Step period in seconds (a whole number of 10 ms ticks).
    pub step_period_s: f64,
    /// MCU clock φ in Hz.
    pub clock_hz: u32,
}

/// The deepest sensor setback: less than the body's half width (90 mm), so the mount stays
/// inside the body.
pub const MAX_SENSOR_SETBACK_M: f64 = 0.08;

/// The physical world (defaults from docs/design.md §3.5 and the `world` crate).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WorldSpec {
    /// Top wheel speed in m/s.
    pub top_speed_m_per_s: f64,
    /// Motor lag time constant in seconds (0.020–0.100).
    pub motor_time_constant_s: f64,
    /// Per-wheel motor gain spread (0.05 = ±5 %).
    pub motor_gain_spread: f64,
    /// Wheel track in metres.
    pub wheel_track_m: f64,
    /// World sub-step in seconds.
    pub substep_s: f64,
    /// Farthest distance a sensor ray reports, metres.
    pub sensor_range_m: f64,
    /// How far each IR sensor sits inside the body, back from the middle of its side along
    /// its axis, metres (0 = on the side; at most 0.08). Default 0.08: a GP2D12-class sensor
    /// reads unambiguously only from 8 cm (its curve folds back nearer, docs/design.md §3.1), so set back
    /// by 8 cm an obstacle touching the body reads as near as the curve allows (the peak,
    /// about 3.2 V), where on the surface it would read as 28–42 cm.
    pub sensor_setback_m: f64,
    /// Friction coefficient between a robot's body and a wall (0–2; default 0.3). The paper
    /// gives none; it decides whether a robot driving into a wall squares up against it or
    /// slides along (see `docs/claims.md`).
    pub mu_wall: f64,
    /// The corridor's width beyond the robot's, metres (0.001–1; default 0.04 as the paper's
    /// figure suggests: robots in one line that cannot pass each other). The square arena
    /// ignores it.
    pub corridor_clearance_m: f64,
    /// The contact solver: `capped` (default: an island of robots in contact is solved until a
    /// sweep changes no impulse by more than 1e-6 N·s, at most 12 sweeps; every result in
    /// docs/claims.md was made with it), `converged` (until a sweep changes no robot's
    /// velocity by more than 2 µm/s, at most 256 sweeps, the cap counted and reported) or
    /// `newton` (islands of up to 16 robots solved by Newton's method to the sweeps' fixed
    /// point, larger ones by sweeps under the impulse test, at most 256; caps counted); see
    /// docs/physics.md, "The contact solver's cap". Written into a run's outputs only when it
    /// is not the default, so that the outputs of every run made before it existed stay the same.
    #[serde(skip_serializing_if = "SolverKind::is_capped")]
    pub solver: SolverKind,
}

/// The world's contact solver (`world.solver`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SolverKind {
    /// At most [`world::params::SOLVER_ITERATIONS`] sweeps, stopped when no impulse changes by
    /// more than 1e-6 N·s.
    Capped,
    /// At most [`CONVERGED_SOLVER_SWEEPS`] sweeps, stopped when no robot's velocity changes by
    /// more than 2 µm/s.
    Converged,
    /// Islands of up to 16 robots solved by Newton's method until every row's velocity error
    /// is below 0.1 µm/s; larger ones by at most [`CONVERGED_SOLVER_SWEEPS`] sweeps, stopped
    /// when no impulse changes by more than 1e-6 N·s.
    Newton,
}

/// The cap of the converged solver's sweeps (and of the newton solver's, for islands too large
/// for Newton's method), a safety net that is counted ([`world::SolverStats`]).
pub const CONVERGED_SOLVER_SWEEPS: u32 = 256;

impl SolverKind {
    /// Whether this is the default, capped solver.
    #[must_use]
    pub fn is_capped(&self) -> bool {
        *self == SolverKind::Capped
    }

    /// Its name in a scenario file.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Capped => "capped",
            SolverKind::Converged => "converged",
            SolverKind::Newton => "newton",
        }
    }

    /// The world's sweep cap and convergence test for this solver.
    #[must_use]
    pub fn params(self) -> (u32, world::params::Convergence) {
        match self {
            SolverKind::Capped => (
                world::params::SOLVER_ITERATIONS,
                world::params::Convergence::Impulse,
            ),
            SolverKind::Converged => (
                CONVERGED_SOLVER_SWEEPS,
                world::params::Convergence::Velocity,
            ),
            SolverKind::Newton => (CONVERGED_SOLVER_SWEEPS, world::params::Convergence::Newton),
        }
    }
}

/// The IR sensors (defaults: docs/design.md §3.1 and the `sensors` crate).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorSpec {
    /// Gaussian read noise σ in volts.
    pub noise_sigma_v: f64,
    /// Probability that a read lands in a spike.
    pub spike_probability: f64,
    /// Unit-to-unit spread on (the datasheet's) or off (every sensor nominal).
    pub spread: bool,
    /// The A/D input (0–7 for AN0–AN7) of each sensor, front, rear, left, right: four distinct
    /// channels of one scan group (AN0–AN3 or AN4–AN7). Default AN0–AN3.
    pub channels: [u8; 4],
}

/// Which controller a robot runs (the fit measures; the swarm runs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ControllerKind {
    /// Machine code on the H8/300H core: the robot firmware or a user's image.
    Firmware,
    /// The Rust model of the controller.
    Model,
}

/// The robots' controller.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControllerSpec {
    /// `firmware` (the robot firmware, machine code on the emulated H8/300H) or `model` (the
    /// Rust model of it, checked against it).
    pub kind: ControllerKind,
    /// A firmware image of the user's (Motorola S-records) for the robots in `robots` (every
    /// robot when `robots` is absent); the others run the robot firmware. Firmware only.
    pub image: Option<String>,
    /// The image's symbol table (`h8300-hms-nm -n`); default: the image's path with `.sym`,
    /// when that file exists. With the symbol `config_block` at H'000400 the image gets the
    /// configuration block; without it the scenario's learner settings do not reach it.
    pub symbols: Option<String>,
    /// The robots (0-based) that run `image`.
    pub robots: Option<Vec<usize>>,
}

impl Default for ControllerSpec {
    fn default() -> Self {
        Self {
            kind: ControllerKind::Model,
            image: None,
            symbols: None,
            robots: None,
        }
    }
}

/// Which controls run beside learning (docs/design.md §5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControlSpec {
    /// The same run with learning off (η = 0, frozen initial weights).
    pub learning_off: bool,
    /// The same run with uniformly random behaviours.
    pub random_walk: bool,
}

/// A scenario file: everything optional, over a built-in base.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFile {
    /// The built-in this file changes: `arena` (default) or `corridor`.
    pub base: Option<String>,
    /// A name for the run.
    pub name: Option<String>,
    /// The arena: `corridor` or `square`.
    pub arena: Option<ArenaKind>,
    /// Robots.
    pub robots: Option<usize>,
    /// Steps per run.
    pub steps: Option<u32>,
    /// Repeats of each condition.
    pub repeats: Option<u32>,
    /// Master seed.
    pub seed: Option<u64>,
    /// Steps per metric window (first and last window of the summary, plot points).
    pub window: Option<u32>,
    /// The learner.
    pub learner: Option<LearnerPatch>,
    /// Timing.
    pub timing: Option<TimingPatch>,
    /// World.
    pub world: Option<WorldPatch>,
    /// Sensors.
    pub sensors: Option<SensorPatch>,
    /// Controls.
    pub controls: Option<ControlPatch>,
    /// The controller.
    pub controller: Option<ControllerPatch>,
}

macro_rules! patch {
    ($patch:ident for $spec:ident { $($field:ident : $ty:ty),* $(,)? }) => {
        #[doc = concat!("Optional values over a [`", stringify!($spec), "`].")]
        #[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct $patch {
            $(
                #[doc = concat!("Overrides `", stringify!($field), "`.")]
                pub $field: Option<$ty>,
            )*
        }
        impl $patch {
            fn apply(&self, spec: &mut $spec) {
                $( if let Some(v) = &self.$field { spec.$field = v.clone().into(); } )*
            }
        }
    };
}

patch!(LearnerPatch for LearnerSpec { behaviours: usize, eta: f64, threshold: i32, history: usize, bias: bool, save_every: u32 });
patch!(TimingPatch for TimingSpec { step_period_s: f64, clock_hz: u32 });
patch!(WorldPatch for WorldSpec { top_speed_m_per_s: f64, motor_time_constant_s: f64, motor_gain_spread: f64, wheel_track_m: f64, substep_s: f64, sensor_range_m: f64, sensor_setback_m: f64, mu_wall: f64, corridor_clearance_m: f64, solver: SolverKind });
patch!(SensorPatch for SensorSpec { noise_sigma_v: f64, spike_probability: f64, spread: bool, channels: Channels });

/// `sensors.channels` as a file gives it: exactly four whole numbers 0-255, checked when read
/// (a fifth value or a string is an error naming the key, never dropped). Their range (AN0-AN7,
/// one scan group) is checked with the rest of the scenario.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(transparent)]
pub struct Channels(pub [u8; 4]);

impl<'de> Deserialize<'de> for Channels {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let v: Vec<u8> = Vec::deserialize(d)?;
        let n = v.len();
        <[u8; 4]>::try_from(v).map(Channels).map_err(|_| {
            D::Error::custom(format!(
                "{n} channels given: give exactly four analog inputs (left, front left, front right, right), e.g. [0, 1, 2, 3]"
            ))
        })
    }
}

impl From<Channels> for [u8; 4] {
    fn from(c: Channels) -> Self {
        c.0
    }
}
patch!(ControlPatch for ControlSpec { learning_off: bool, random_walk: bool });
patch!(ControllerPatch for ControllerSpec { kind: ControllerKind, image: Option<String>, symbols: Option<String>, robots: Option<Vec<usize>> });

/// The largest scenario or sweep file read (1 MiB; the documented example is 4 KB).
pub const MAX_FILE_BYTES: u64 = 1 << 20;

/// The longest scenario `name`, in characters: it titles every figure, and drawing a title
/// costs time with its length (a name of 1 MB took seconds to draw).
pub const MAX_NAME_CHARS: usize = 200;

/// A text file a user named, at most `limit` bytes of UTF-8 (see
/// [`robot_board::firmware::read_bounded`]).
///
/// # Errors
/// The file cannot be read, is larger, or is not UTF-8.
pub fn read_text(path: &Path, limit: u64) -> std::io::Result<String> {
    let bytes = robot_board::firmware::read_bounded(path, limit)?;
    String::from_utf8(bytes).map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))
}

/// A resolved, checked scenario.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Scenario {
    /// Its name.
    pub name: String,
    /// The arena.
    pub arena: ArenaKind,
    /// Robots.
    pub robots: usize,
    /// Steps per run.
    pub steps: u32,
    /// Repeats of each condition.
    pub repeats: u32,
    /// Master seed.
    pub seed: u64,
    /// Steps per metric window.
    pub window: u32,
    /// The learner.
    pub learner: LearnerSpec,
    /// Timing.
    pub timing: TimingSpec,
    /// World.
    pub world: WorldSpec,
    /// Sensors.
    pub sensors: SensorSpec,
    /// Controls.
    pub controls: ControlSpec,
    /// The controller.
    pub controller: ControllerSpec,
}

impl Default for LearnerSpec {
    fn default() -> Self {
        Scenario::arena().learner
    }
}

impl Default for TimingSpec {
    fn default() -> Self {
        Scenario::arena().timing
    }
}

impl Default for WorldSpec {
    fn default() -> Self {
        Self {
            top_speed_m_per_s: world::params::TOP_SPEED_M_PER_S,
            motor_time_constant_s: world::params::MOTOR_TIME_CONSTANT_S,
            motor_gain_spread: world::params::MOTOR_GAIN_SPREAD,
            wheel_track_m: world::params::WHEEL_TRACK_M,
            // The world's own default: 3 mm of travel at top speed, collisions and bumpers
            // sampled 22 times per 0.45 s step.
            substep_s: world::params::MAX_SUBSTEP_S,
            sensor_range_m: world::params::SENSOR_MAX_RANGE_M,
            // Set back by the end of the sensor's fold-back zone (docs/design.md §3.1: the curve peaks at
            // 8 cm and falls again nearer), so that an obstacle touching the body reads as near
            // as the curve allows instead of folding back to a far reading.
            sensor_setback_m: sensors::curve::FAR_BRANCH_MIN_MM / 1000.0,
            mu_wall: world::params::MU_WALL,
            corridor_clearance_m: world::arena::CORRIDOR_EXTRA_WIDTH_M,
            solver: SolverKind::Capped,
        }
    }
}

impl Default for SensorSpec {
    fn default() -> Self {
        Self {
            noise_sigma_v: sensors::ir::NOISE_SIGMA_VOLTS,
            spike_probability: sensors::ir::SPIKE_PROBABILITY,
            spread: true,
            channels: robot_board::model::DEFAULT_SENSOR_CHANNELS,
        }
    }
}

impl Default for ControlSpec {
    fn default() -> Self {
        Self {
            learning_off: true,
            random_walk: true,
        }
    }
}

/// The arena's learning rate: the paper's η = 0.001. The claim map's rule (`docs/claims.md`,
/// "The defaults, by a stated rule") takes a default only from a cell confirmed on seeds the map
/// never used; no cell of the arena's map is, so the paper's number stays.
pub const ARENA_ETA: f64 = 0.001;
/// The arena's wall friction: the paper gives none, no confirmed cell gives one, so the
/// world's default (0.3, as everywhere else).
pub const ARENA_MU_WALL: f64 = 0.3;
/// The default run's repeats: enough to decide the paper's text claims that its effects can
/// decide (`docs/claims.md`, "Power"): at 20 repeats of seed 1 "collisions fall" needs about 14
/// and "keep exploring" about 8 (the opposite way); "D rises" goes 11 to 9, which no affordable
/// count decides. The largest, 14, rounded up to a multiple of 5.
pub const ARENA_REPEATS: u32 = 15;

/// `v` within `lo..=hi`, else an error naming `key` and the valid range.
fn range<T: PartialOrd + std::fmt::Display>(key: &str, v: T, lo: T, hi: T) -> Result<()> {
    if v >= lo && v <= hi {
        Ok(())
    } else {
        bail!("`{key}` = {v} is out of range: valid is {lo} to {hi}")
    }
}

/// `v` finite and within `lo..=hi`, else an error naming `key` and the valid range.
fn finite(key: &str, v: f64, lo: f64, hi: f64) -> Result<()> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        bail!(
            "`{key}` = {} is out of range: valid is {lo} to {hi}",
            crate::terminal_text::number(v)
        )
    }
}

impl Scenario {
    /// Paper env. 2: three robots in the 1.8 m square, all four behaviours, T = 10, 0.45 s
    /// steps, 10 000 steps, [`ARENA_REPEATS`] repeats, the paper's η ([`ARENA_ETA`]) and the
    /// world's wall friction ([`ARENA_MU_WALL`]).
    #[must_use]
    pub fn arena() -> Self {
        Self {
            name: "arena".into(),
            arena: ArenaKind::Square,
            robots: 3,
            steps: 10_000,
            repeats: ARENA_REPEATS,
            seed: 1,
            window: 500,
            learner: LearnerSpec {
                behaviours: 4,
                eta: ARENA_ETA,
                threshold: 10,
                history: 1,
                bias: false,
                save_every: 20,
            },
            timing: TimingSpec {
                step_period_s: 0.45,
                clock_hz: robot_board::board::CLOCK_HZ,
            },
            world: WorldSpec {
                mu_wall: ARENA_MU_WALL,
                ..WorldSpec::default()
            },
            sensors: SensorSpec::default(),
            controls: ControlSpec::default(),
            controller: ControllerSpec::default(),
        }
    }

    /// Paper env. 1: three robots in the corridor, forward and backward, η = 0.1, T = 10, 0.60 s
    /// steps, 500 steps, 5 repeats (the arena's repeat count was chosen for the arena).
    #[must_use]
    pub fn corridor() -> Self {
        Self {
            name: "corridor".into(),
            arena: ArenaKind::Corridor,
            steps: 500,
            repeats: 5,
            window: 50,
            learner: LearnerSpec {
                behaviours: 2,
                eta: 0.1,
                ..Self::arena().learner
            },
            timing: TimingSpec {
                step_period_s: 0.60,
                ..Self::arena().timing
            },
            // The claim map finds no region in the corridor: the paper's numbers and the
            // world's defaults stay.
            world: WorldSpec::default(),
            ..Self::arena()
        }
    }

    /// A built-in by name.
    ///
    /// # Errors
    /// An unknown name, listing the built-ins.
    pub fn builtin(name: &str) -> Result<Self> {
        match name {
            "arena" => Ok(Self::arena()),
            "corridor" => Ok(Self::corridor()),
            other => bail!(
                "unknown built-in scenario `{other}`: valid are `arena` and `corridor`, or a path to a .toml file"
            ),
        }
    }

    /// `arena`, `corridor`, or a TOML file.
    ///
    /// # Errors
    /// An unreadable file, bad TOML, an unknown key or a value out of range, naming it.
    pub fn load(what: &str) -> Result<Self> {
        if what == "arena" || what == "corridor" {
            return Self::builtin(what);
        }
        let path = Path::new(what);
        if path.extension().and_then(|e| e.to_str()) != Some("toml") && !path.exists() {
            return Self::builtin(what);
        }
        let text = read_text(path, MAX_FILE_BYTES)
            .with_context(|| format!("cannot read scenario file `{what}`"))?;
        Self::from_toml(&text).with_context(|| format!("scenario file `{what}`"))
    }

    /// Parses a scenario file's text over its base and checks it.
    ///
    /// # Errors
    /// Bad TOML, an unknown key, or a value out of range.
    pub fn from_toml(text: &str) -> Result<Self> {
        // One line: where (line, column, the line's text) and what.
        let file: ScenarioFile = toml::from_str(text)
            .map_err(|e| anyhow::anyhow!("{}", crate::terminal_text::toml_error(text, &e)))?;
        Self::from_file(file)
    }

    /// A scenario file already read as a TOML table (a sweep's point), over its base and
    /// checked; an error names the key (`… in `world.solver``), there being no text to point
    /// into.
    ///
    /// # Errors
    /// An unknown key, a value of the wrong kind, or a value out of range.
    pub fn from_table(table: &toml::Table) -> Result<Self> {
        // The message and the key it is in (`… in `world.solver``), on one line.
        let file = ScenarioFile::deserialize(table.clone()).map_err(|e| {
            let text = e.to_string();
            let words: Vec<&str> = text.split_whitespace().collect();
            anyhow::anyhow!("{}", crate::terminal_text::one_line(&words.join(" ")))
        })?;
        Self::from_file(file)
    }

    /// A scenario file over its base, checked.
    fn from_file(file: ScenarioFile) -> Result<Self> {
        let base = file.base.as_deref().unwrap_or("arena");
        if base != "arena" && base != "corridor" {
            bail!(
                "key `base`: `{base}` is not a built-in scenario: a scenario file changes `arena` or `corridor` (it cannot be based on another file)"
            );
        }
        let mut s = Self::builtin(base)?;
        if let Some(v) = file.name {
            s.name = v;
        }
        if let Some(v) = file.arena {
            s.arena = v;
        }
        if let Some(v) = file.robots {
            s.robots = v;
        }
        if let Some(v) = file.steps {
            s.steps = v;
            // As `--steps` does: a file that shortens the run without naming a window gets
            // one window of the whole run rather than an error about the base's window.
            if file.window.is_none() {
                s.window = s.window.min(v);
            }
        }
        if let Some(v) = file.repeats {
            s.repeats = v;
        }
        if let Some(v) = file.seed {
            s.seed = v;
        }
        if let Some(v) = file.window {
            s.window = v;
        }
        if let Some(p) = &file.learner {
            p.apply(&mut s.learner);
        }
        if let Some(p) = &file.timing {
            p.apply(&mut s.timing);
        }
        if let Some(p) = &file.world {
            p.apply(&mut s.world);
        }
        if let Some(p) = &file.sensors {
            p.apply(&mut s.sensors);
        }
        if let Some(p) = &file.controls {
            p.apply(&mut s.controls);
        }
        if let Some(p) = &file.controller {
            p.apply(&mut s.controller);
        }
        s.check()?;
        Ok(s)
    }

    /// η as a Q15 integer (rounded).
    #[must_use]
    pub fn eta_q15(&self) -> i32 {
        (self.learner.eta * 32768.0).round() as i32
    }

    /// Checks every value; the error names the key and the valid range.
    ///
    /// # Errors
    /// The first value out of range.
    pub fn check(&self) -> Result<()> {
        self.check_name()?;
        if let Err(e) = robot_board::model::check_sensor_channels(&self.sensors.channels) {
            bail!("`sensors.channels` = {:?}: {e}", self.sensors.channels);
        }
        self.check_run_and_learner()?;
        self.check_timing()?;
        self.check_world_and_sensors()?;
        if self.timing.step_period_s < self.world.substep_s {
            bail!(
                "`world.substep_s` = {} is longer than the step period {} s",
                self.world.substep_s,
                self.timing.step_period_s
            );
        }
        self.check_controller()
    }

    /// The name: short enough to title the figures, and printable.
    fn check_name(&self) -> Result<()> {
        let name_chars = self.name.chars().count();
        if name_chars > MAX_NAME_CHARS {
            bail!(
                "`name` is {name_chars} characters long: give at most {MAX_NAME_CHARS} (it titles the figures and the summary)"
            );
        }
        if let Some(c) = self
            .name
            .chars()
            .find(|&c| c.is_control() || crate::terminal_text::is_format_char(c))
        {
            bail!(
                "`name` holds the control or format character U+{:04X}: give printable text (it is shown on the terminal and in the figures)",
                u32::from(c)
            );
        }
        Ok(())
    }

    /// The run's size (robots, steps, repeats, window) and the learner's settings.
    fn check_run_and_learner(&self) -> Result<()> {
        range("robots", self.robots, 1, 100_000)?;
        range("steps", self.steps, 1, 10_000_000)?;
        range("repeats", self.repeats, 1, 1000)?;
        range("window", self.window, 1, self.steps)?;
        range("learner.behaviours", self.learner.behaviours, 2, 4)?;
        finite("learner.eta", self.learner.eta, 0.0, 32767.0 / 32768.0)?;
        range("learner.threshold", self.learner.threshold, 0, 1020)?;
        range(
            "learner.history",
            self.learner.history,
            0,
            nn_q15::MAX_HISTORY,
        )?;
        range("learner.save_every", self.learner.save_every, 1, 1_000_000)?;
        Ok(())
    }

    /// The step period (a whole number of ticks) and the clock.
    fn check_timing(&self) -> Result<()> {
        if !robot_board::model::step_period_ok(self.timing.step_period_s) {
            bail!(
                "`timing.step_period_s` = {}: valid is {}",
                crate::terminal_text::number(self.timing.step_period_s),
                robot_board::model::STEP_PERIOD_VALID
            );
        }
        range(
            "timing.clock_hz",
            self.timing.clock_hz,
            robot_board::model::CLOCK_MIN_HZ,
            robot_board::model::CLOCK_MAX_HZ,
        )?;
        Ok(())
    }

    /// The world's physics and the sensors' noise.
    fn check_world_and_sensors(&self) -> Result<()> {
        finite(
            "world.top_speed_m_per_s",
            self.world.top_speed_m_per_s,
            0.001,
            world::params::MAX_TOP_SPEED_M_PER_S,
        )?;
        finite(
            "world.motor_time_constant_s",
            self.world.motor_time_constant_s,
            world::params::MOTOR_TIME_CONSTANT_MIN_S,
            world::params::MOTOR_TIME_CONSTANT_MAX_S,
        )?;
        finite(
            "world.motor_gain_spread",
            self.world.motor_gain_spread,
            0.0,
            0.5,
        )?;
        finite("world.wheel_track_m", self.world.wheel_track_m, 0.05, 0.18)?;
        finite("world.substep_s", self.world.substep_s, 0.001, 0.020)?;
        finite("world.sensor_range_m", self.world.sensor_range_m, 0.1, 10.0)?;
        finite(
            "world.sensor_setback_m",
            self.world.sensor_setback_m,
            0.0,
            MAX_SENSOR_SETBACK_M,
        )?;
        finite("world.mu_wall", self.world.mu_wall, 0.0, 2.0)?;
        finite(
            "world.corridor_clearance_m",
            self.world.corridor_clearance_m,
            0.001,
            1.0,
        )?;
        finite(
            "sensors.noise_sigma_v",
            self.sensors.noise_sigma_v,
            0.0,
            1.0,
        )?;
        finite(
            "sensors.spike_probability",
            self.sensors.spike_probability,
            0.0,
            1.0,
        )?;
        Ok(())
    }

    /// The controller: an image only for the firmware, and robots that exist to run it.
    fn check_controller(&self) -> Result<()> {
        let c = &self.controller;
        if c.kind == ControllerKind::Model && (c.image.is_some() || c.robots.is_some()) {
            bail!(
                "`controller.image` and `controller.robots` need `controller.kind = \"firmware\"` (the model runs no image)"
            );
        }
        if c.robots.is_some() && c.image.is_none() {
            bail!(
                "`controller.robots` names the robots that run `controller.image`: give the image too"
            );
        }
        if let Some(robots) = &c.robots
            && let Some(&bad) = robots.iter().find(|&&r| r >= self.robots)
        {
            bail!(
                "`controller.robots` lists robot {bad}: valid are 0 to {} ({} robots)",
                self.robots - 1,
                self.robots
            );
        }
        Ok(())
    }

    /// Applies the command line's overrides and checks again.
    ///
    /// # Errors
    /// A value out of range.
    pub fn with_overrides(
        mut self,
        robots: Option<usize>,
        steps: Option<u32>,
        repeats: Option<u32>,
        seed: Option<u64>,
    ) -> Result<Self> {
        if let Some(v) = robots {
            self.robots = v;
        }
        if let Some(v) = steps {
            self.steps = v;
            self.window = self.window.min(v);
        }
        if let Some(v) = repeats {
            self.repeats = v;
        }
        if let Some(v) = seed {
            self.seed = v;
        }
        self.check().context("command-line option")?;
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_match_the_paper() {
        let a = Scenario::arena();
        assert_eq!(
            (a.robots, a.steps, a.repeats, a.learner.behaviours),
            (3, 10_000, 15, 4)
        );
        assert_eq!(
            a.eta_q15(),
            33,
            "the paper's eta 0.001: no confirmed cell gives another"
        );
        assert_eq!(a.world.mu_wall, 0.3);
        // The scenario files stand at the workspace's root, one folder above this crate.
        let paper = Scenario::load(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scenarios/arena-paper.toml"
        ))
        .unwrap();
        assert_eq!((paper.eta_q15(), paper.world.mu_wall), (33, 0.3));
        let c = Scenario::corridor();
        assert_eq!((c.steps, c.learner.behaviours, c.eta_q15()), (500, 2, 3277));
        assert_eq!(c.world.mu_wall, 0.3);
        assert_eq!(c.timing.step_period_s, 0.60);
        a.check().unwrap();
        c.check().unwrap();
    }

    /// `scenarios/example.toml` names every key with the built-in arena's values: loaded, it is
    /// the built-in arena but for its name (so it cannot drift from the defaults unseen).
    #[test]
    fn the_example_file_holds_the_arena_s_values() {
        let mut example = Scenario::load(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scenarios/example.toml"
        ))
        .unwrap();
        let arena = Scenario::arena();
        example.name.clone_from(&arena.name);
        assert_eq!(example, arena);
    }

    #[test]
    fn files_override_the_base_and_unknown_keys_fail() {
        let s = Scenario::from_toml("base = \"corridor\"\nrobots = 4\n[learner]\neta = 0.05\n")
            .unwrap();
        assert_eq!(s.robots, 4);
        assert_eq!(s.learner.behaviours, 2);
        assert_eq!(s.eta_q15(), 1638);
        // A shorter run without a window gets the base's window cut to it; a window named
        // beyond the run is still an error.
        let s = Scenario::from_toml("steps = 200\n").unwrap();
        assert_eq!((s.steps, s.window), (200, 200));
        let s = Scenario::from_toml("steps = 2000\n").unwrap();
        assert_eq!((s.steps, s.window), (2000, 500));
        let e = format!(
            "{:#}",
            Scenario::from_toml("steps = 200\nwindow = 300\n").unwrap_err()
        );
        assert!(e.contains("window"), "{e}");
        // A base is a built-in, and the error says so (not "or a path").
        let e = format!(
            "{:#}",
            Scenario::from_toml("base = \"arena-learning-only.toml\"\n").unwrap_err()
        );
        assert!(
            e.contains("key `base`") && e.contains("cannot be based on another file"),
            "{e}"
        );
        // The contact solver by name; another name is an error naming the key.
        let s = Scenario::from_toml("[world]\nsolver = \"converged\"\n").unwrap();
        assert_eq!(s.world.solver, SolverKind::Converged);
        assert_eq!(
            s.world.solver.params(),
            (256, world::params::Convergence::Velocity)
        );
        assert_eq!(Scenario::arena().world.solver, SolverKind::Capped);
        // The name the report prints is the one a file gives.
        for k in [
            SolverKind::Capped,
            SolverKind::Converged,
            SolverKind::Newton,
        ] {
            let text = format!("[world]\nsolver = \"{}\"\n", k.name());
            assert_eq!(Scenario::from_toml(&text).unwrap().world.solver, k);
        }
        let e = format!(
            "{:#}",
            Scenario::from_toml("[world]\nsolver = \"exact\"\n").unwrap_err()
        );
        assert!(
            e.contains("solver") && e.contains("converged") && e.contains("newton"),
            "{e}"
        );
        // Channels: exactly four whole numbers, never silently cut.
        for (text, expected) in [
            (
                "[sensors]\nchannels = [0, 1, 2, 3, 4]\n",
                "5 channels given",
            ),
            ("[sensors]\nchannels = [0, 1, 2]\n", "3 channels given"),
            (
                "[sensors]\nchannels = [0, 1, 2, 3, \"junk\", {a = 1}]\n",
                "channels",
            ),
            ("[sensors]\nchannels = [0, 1, 2, -3]\n", "channels"),
        ] {
            let e = format!("{:#}", Scenario::from_toml(text).unwrap_err());
            assert!(e.contains(expected), "{text}: {e}");
        }
        let s = Scenario::from_toml("[sensors]\nchannels = [4, 5, 6, 7]\n").unwrap();
        assert_eq!(s.sensors.channels, [4, 5, 6, 7]);
        let e = Scenario::from_toml("robts = 4\n").unwrap_err().to_string();
        assert!(e.contains("robts"), "{e}");
        let e = Scenario::from_toml("[learner]\netaa = 0.1\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("etaa"), "{e}");
        let e = format!(
            "{:#}",
            Scenario::from_toml("[learner]\neta = 2.0\n").unwrap_err()
        );
        assert!(e.contains("learner.eta"), "{e}");
        let e = format!(
            "{:#}",
            Scenario::from_toml("[timing]\nstep_period_s = 0.455\n").unwrap_err()
        );
        assert!(e.contains("10 ms ticks"), "{e}");
        let e = format!(
            "{:#}",
            Scenario::from_toml("base = \"moon\"\n").unwrap_err()
        );
        assert!(e.contains("moon"), "{e}");
    }
}
