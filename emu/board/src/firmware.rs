//! Firmware images on the robot board: loading an image with its symbol table, writing the
//! configuration block (docs/design.md §8) into the flash at load, reading back what the firmware made of
//! it, and running the image on the core.

use std::path::Path;
use std::sync::{Arc, OnceLock};

use crate::symbols::{SymbolError, SymbolTable};
use h8_3052f::flash::Flash;
use h8_3052f::gdb::{DebugAction, Debugger};
use h8_3052f::mcu::{IoReport, LoadError, Mcu, check_image};
use h8_3052f::pins::Board;
use h8_3052f::profile::StackProfile;
use h8_3052f::trace::{CodeNames, PhaseRecorder};
use h8300h::bus::FastPathHints;
use h8300h::cpu::{
    Cpu, CpuError, Event, SharedCode, StackFault, StackGuard, StackGuardMode, StackRoom,
};
use h8300h::srec::{self, SrecError, SrecImage};

/// Where the configuration block sits in the flash (docs/design.md §8: "say H'000400, after the
/// vectors").
pub const CONFIG_BLOCK_ADDR: u32 = 0x400;
/// Bytes of the block.
pub const CONFIG_BLOCK_BYTES: usize = 32;
/// The block's magic.
pub const CONFIG_MAGIC: [u8; 4] = *b"H8SW";
/// The block's format version.
pub const CONFIG_VERSION: u8 = 1;
/// Flags bit 0: the bias input.
pub const FLAG_BIAS: u8 = 0x01;
/// Flags bit 1: the random-walk control (the learner runs; the motors take a random behaviour).
pub const FLAG_RANDOM_WALK: u8 = 0x02;

/// The settings the emulator gives the firmware (see `firmware/README.md` for the layout).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConfigBlock {
    /// Behaviours M (2–4).
    pub outputs: u8,
    /// History depth H (0–8).
    pub history: u8,
    /// Flags ([`FLAG_BIAS`], [`FLAG_RANDOM_WALK`]).
    pub flags: u8,
    /// Spare inputs held at 0.
    pub spare: u16,
    /// η, Q15 (0–32767).
    pub eta: i16,
    /// T in du (0–32767).
    pub threshold: i16,
    /// One record every this many steps (0: never).
    pub save_every: u16,
    /// Ticks per step K.
    pub ticks_per_step: u16,
    /// Counts of φ/8 per tick: GRA0 + 1.
    pub tick_counts: u16,
    /// A/D channel of each sensor (front, rear, left, right).
    pub channels: [u8; 4],
    /// Seed of the fresh weights (xorshift32; the firmware ORs it with 1).
    pub seed: u32,
}

impl ConfigBlock {
    /// The firmware's compiled defaults: the arena (docs/design.md §5) at φ = 25 MHz.
    pub const ARENA: ConfigBlock = ConfigBlock {
        outputs: 4,
        history: 1,
        flags: 0,
        spare: 0,
        eta: 33,
        threshold: 10,
        save_every: 20,
        ticks_per_step: 45,
        tick_counts: 31_250,
        channels: [0, 1, 2, 3],
        seed: 1,
    };

    /// The 32 bytes of the block, big-endian, with its CRC-16.
    #[must_use]
    pub fn encode(&self) -> [u8; CONFIG_BLOCK_BYTES] {
        let mut b = [0u8; CONFIG_BLOCK_BYTES];
        b[0..4].copy_from_slice(&CONFIG_MAGIC);
        b[4] = CONFIG_VERSION;
        b[5] = self.outputs;
        b[6] = self.history;
        b[7] = self.flags;
        b[8..10].copy_from_slice(&self.spare.to_be_bytes());
        b[10..12].copy_from_slice(&self.eta.to_be_bytes());
        b[12..14].copy_from_slice(&self.threshold.to_be_bytes());
        b[14..16].copy_from_slice(&self.save_every.to_be_bytes());
        b[16..18].copy_from_slice(&self.ticks_per_step.to_be_bytes());
        b[18..20].copy_from_slice(&self.tick_counts.to_be_bytes());
        b[20..24].copy_from_slice(&self.channels);
        b[24..28].copy_from_slice(&self.seed.to_be_bytes());
        // 28..30 reserved, 0.
        let crc = eeprom::crc::crc16_ccitt_false(&b[..30]);
        b[30..32].copy_from_slice(&crc.to_be_bytes());
        b
    }

    /// The block for the settings of the model controller's configuration: the same network,
    /// parameters, save period, step period (in 10 ms ticks) and wiring; the tick in counts of
    /// φ/8 at its clock; the weight seed folded to 32 bits as the model folds it (so both start
    /// from the same weights).
    ///
    /// # Errors
    /// A setting the block cannot carry, naming it and what would be valid.
    pub fn from_controller(
        cfg: &crate::model::ControllerConfig,
    ) -> Result<ConfigBlock, BlockError> {
        let bad = |field: &'static str, value: String, valid: &'static str| BlockError {
            field,
            value,
            valid,
        };
        let ticks = cfg.step_period_s / crate::model::TICK_S;
        if !(ticks.is_finite()
            && (ticks - ticks.round()).abs() < 1e-9
            && (1.0..=65535.0).contains(&ticks.round()))
        {
            return Err(bad(
                "step_period_s",
                cfg.step_period_s.to_string(),
                "a whole number of 10 ms ticks, 0.01 to 655.35 s",
            ));
        }
        let tick_counts = (crate::model::TICK_S * f64::from(cfg.clock_hz) / 8.0).round();
        if !(2.0..=65535.0).contains(&tick_counts) {
            return Err(bad(
                "clock_hz",
                cfg.clock_hz.to_string(),
                "2 to 25 MHz (a 10 ms tick of φ/8 counts must fit ITU0's 16-bit GRA)",
            ));
        }
        let save_every = u16::try_from(cfg.save_every_steps).map_err(|_| {
            bad(
                "save_every_steps",
                cfg.save_every_steps.to_string(),
                "1 to 65535 steps",
            )
        })?;
        let spare = u16::try_from(cfg.layout.spare())
            .map_err(|_| bad("spare inputs", cfg.layout.spare().to_string(), "0 to 256"))?;
        let outputs = u8::try_from(cfg.behaviours)
            .map_err(|_| bad("behaviours", cfg.behaviours.to_string(), "2 to 4"))?;
        Ok(ConfigBlock {
            outputs,
            history: cfg.layout.history() as u8,
            flags: if cfg.layout.bias() { FLAG_BIAS } else { 0 },
            spare,
            eta: cfg.params.eta().to_bits(),
            threshold: cfg.params.threshold(),
            save_every,
            ticks_per_step: ticks.round() as u16,
            tick_counts: tick_counts as u16,
            channels: cfg.sensor_channels,
            seed: (cfg.weight_seed ^ (cfg.weight_seed >> 32)) as u32,
        })
    }

    /// The step period in states: K ticks of `tick_counts` counts of φ/8.
    #[must_use]
    pub fn step_period_states(&self) -> u64 {
        u64::from(self.ticks_per_step) * u64::from(self.tick_counts) * 8
    }

    /// Number of inputs N the block makes.
    #[must_use]
    pub fn n_inputs(&self) -> usize {
        4 * (1 + usize::from(self.history))
            + usize::from(self.outputs)
            + 1
            + usize::from(self.flags & FLAG_BIAS)
            + usize::from(self.spare)
    }
}

/// A setting the configuration block cannot carry.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{field} = {value}: the firmware's configuration block takes {valid}")]
pub struct BlockError {
    /// The setting.
    pub field: &'static str,
    /// Its value.
    pub value: String,
    /// What would be valid.
    pub valid: &'static str,
}

/// What the firmware made of the block at boot (its `cfg_status`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConfigStatus {
    /// The block was used.
    Used,
    /// No block: the compiled defaults run.
    Absent,
    /// The block's CRC did not match: the compiled defaults run.
    Corrupt,
    /// The firmware cannot run a value of the block (the field named): the defaults run.
    Rejected {
        /// The field, as the firmware's code names it.
        field: &'static str,
        /// The status byte.
        code: u8,
    },
}

impl ConfigStatus {
    /// Decodes `cfg_status`.
    #[must_use]
    pub fn from_code(code: u8) -> ConfigStatus {
        match code {
            0 => ConfigStatus::Used,
            1 => ConfigStatus::Absent,
            2 => ConfigStatus::Corrupt,
            c => ConfigStatus::Rejected {
                code: c,
                field: match c {
                    0x10 => "version",
                    0x11 => "outputs (valid 2 to 4)",
                    0x12 => "history (valid 0 to 8)",
                    0x13 => "flags (valid: bit 0 bias, bit 1 random walk)",
                    0x14 => {
                        "spare inputs (N = 4 (1 + H) + M + 1 + bias + spare must be at most 256)"
                    }
                    0x15 => "eta (valid 0 to 32767)",
                    0x16 => "threshold (valid 0 to 32767)",
                    0x18 => "ticks per step (valid 1 to 65535)",
                    0x19 => "tick counts (valid 2 to 65535)",
                    0x1A => "A/D channels (0 to 7, distinct, one scan group)",
                    0x1B => "reserved (must be 0)",
                    0x1C => {
                        "network size (the network and a 256-byte stack do not fit the 8 KB RAM)"
                    }
                    _ => "unknown",
                },
            },
        }
    }
}

/// Why an image cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum FirmwareError {
    /// A file could not be read.
    #[error("cannot read `{path}`")]
    Read {
        /// The file.
        path: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The image is not a valid S-record file.
    #[error("`{path}` is not a valid S-record image")]
    Srec {
        /// The file.
        path: String,
        /// The cause.
        #[source]
        source: SrecError,
    },
    /// The symbol file is malformed.
    #[error("`{path}`")]
    Symbols {
        /// The file.
        path: String,
        /// The cause.
        #[source]
        source: SymbolError,
    },
    /// A symbol the emulator needs is missing.
    #[error("the image's symbol table has no `{0}`")]
    MissingSymbol(String),
    /// The image does not fit the flash.
    #[error("loading the image into the flash")]
    Load(#[from] LoadError),
}

/// A firmware image and its symbol table.
#[derive(Clone, Debug)]
pub struct Firmware {
    /// The image.
    pub image: SrecImage,
    /// Its symbols.
    pub symbols: SymbolTable,
    /// Where it came from (for messages).
    pub name: String,
    /// The flash with the image programmed and its decoded code, built at the first install
    /// and shared by every MCU (and CPU) the firmware is installed on, with the image it was
    /// built from (so that a changed `image` is never served from an old flash).
    flash: OnceLock<(SrecImage, Result<SharedImage, LoadError>)>,
}

/// An image programmed into a flash and decoded, for every robot running it.
#[derive(Clone, Debug)]
struct SharedImage {
    flash: Flash,
    code: SharedCode,
}

/// The flash bytes that differ from robot to robot in an image with a configuration block: the
/// block. The shared decode tables leave every instruction that covers one of them to each CPU.
const VARYING_BYTES: std::ops::Range<u32> =
    CONFIG_BLOCK_ADDR..CONFIG_BLOCK_ADDR + CONFIG_BLOCK_BYTES as u32;

impl SharedImage {
    /// `image` programmed into an erased flash, and the code from its lowest to its highest
    /// byte decoded, but for instructions covering a byte of `varies`.
    fn build(image: &SrecImage, varies: std::ops::Range<u32>) -> SharedImage {
        let flash = Flash::with_image(image);
        let start = image.chunks.iter().map(|c| c.address).min().unwrap_or(0);
        let end = image
            .chunks
            .iter()
            .map(|c| c.address.saturating_add(c.data.len() as u32))
            .max()
            .unwrap_or(0);
        let code = SharedCode::decode_rom(|a| flash.word(a as usize), start..end, varies);
        SharedImage { flash, code }
    }
}

/// The committed robot firmware (`firmware/robot.mot`, `firmware/robot.sym`), built into the
/// emulator so that it runs from any folder.
const ROBOT_MOT: &[u8] = include_bytes!("../../../firmware/robot.mot");
const ROBOT_SYM: &str = include_str!("../../../firmware/robot.sym");

impl Firmware {
    /// The project's robot firmware (`firmware/robot.mot` and `robot.sym`, built in).
    ///
    /// # Errors
    /// Only if the committed files were damaged (a test parses them).
    pub fn robot() -> Result<Firmware, FirmwareError> {
        let name = "firmware/robot.mot";
        Ok(Firmware {
            image: srec::parse(ROBOT_MOT).map_err(|source| FirmwareError::Srec {
                path: name.to_string(),
                source,
            })?,
            symbols: SymbolTable::parse(ROBOT_SYM).map_err(|source| FirmwareError::Symbols {
                path: "firmware/robot.sym".to_string(),
                source,
            })?,
            name: name.to_string(),
            flash: OnceLock::new(),
        })
    }

    /// The largest image or symbol file read (4 MiB: an S-record file of the whole 512 KB
    /// flash is about 1.4 MB; a symbol table of a program that fills it far less).
    pub const MAX_FILE_BYTES: u64 = 4 << 20;

    /// An image and its symbol file from disk.
    ///
    /// # Errors
    /// [`FirmwareError`] naming the file that could not be read or parsed.
    pub fn load(image: &Path, symbols: &Path) -> Result<Firmware, FirmwareError> {
        let read = |p: &Path| {
            read_bounded(p, Self::MAX_FILE_BYTES).map_err(|source| FirmwareError::Read {
                path: p.display().to_string(),
                source,
            })
        };
        let bytes = read(image)?;
        let image_parsed = srec::parse(&bytes).map_err(|source| FirmwareError::Srec {
            path: image.display().to_string(),
            source,
        })?;
        let text = String::from_utf8_lossy(&read(symbols)?).into_owned();
        let table = SymbolTable::parse(&text).map_err(|source| FirmwareError::Symbols {
            path: symbols.display().to_string(),
            source,
        })?;
        Ok(Firmware {
            image: image_parsed,
            symbols: table,
            name: image.display().to_string(),
            flash: OnceLock::new(),
        })
    }

    /// An image without a symbol table (a user's image run in the swarm: it gets no
    /// configuration block and no profile).
    ///
    /// # Errors
    /// [`FirmwareError`] naming the file that could not be read or parsed.
    pub fn load_without_symbols(image: &Path) -> Result<Firmware, FirmwareError> {
        let bytes =
            read_bounded(image, Self::MAX_FILE_BYTES).map_err(|source| FirmwareError::Read {
                path: image.display().to_string(),
                source,
            })?;
        Ok(Firmware {
            image: srec::parse(&bytes).map_err(|source| FirmwareError::Srec {
                path: image.display().to_string(),
                source,
            })?,
            symbols: SymbolTable::default(),
            name: image.display().to_string(),
            flash: OnceLock::new(),
        })
    }

    /// Programs the image into `mcu`'s flash: an MCU without flash takes the firmware's shared
    /// flash (its pages copied only where the MCU writes) and gets the image's shared decoded
    /// code back, one with flash has the image programmed over it (and gets `None`: bytes
    /// outside the image may differ from the shared flash's).
    fn program<B: Board>(&self, mcu: &mut Mcu<B>) -> Result<Option<&SharedCode>, LoadError> {
        if mcu.has_flash() {
            return mcu.load_image(&self.image).map(|()| None);
        }
        let (source, shared) = self.flash.get_or_init(|| {
            // An image without a configuration block gets none poked over it (a block given
            // anyway makes the CPU decode for itself, see `install`), so all its code is
            // shared, whatever lies at H'000400.
            let varies = if self.has_config_block() {
                VARYING_BYTES
            } else {
                0..0
            };
            let built = check_image(&self.image).map(|()| SharedImage::build(&self.image, varies));
            (self.image.clone(), built)
        });
        if *source != self.image {
            return mcu.load_image(&self.image).map(|()| None);
        }
        let shared = shared.as_ref().map_err(Clone::clone)?;
        mcu.load_flash(&shared.flash);
        Ok(Some(&shared.code))
    }

    /// The image's decoded code that CPUs of MCUs installed without flash of their own share
    /// ([`SharedCode`]), once an install has built it (and while the image is the one it was
    /// built from).
    #[must_use]
    pub fn shared_code(&self) -> Option<&SharedCode> {
        match self.flash.get()? {
            (source, Ok(shared)) if *source == self.image => Some(&shared.code),
            _ => None,
        }
    }

    /// Bytes of the image (its ROM).
    #[must_use]
    pub fn rom_bytes(&self) -> usize {
        self.image.data_len()
    }

    /// Whether the image has a configuration block (the symbol `config_block` at H'000400).
    #[must_use]
    pub fn has_config_block(&self) -> bool {
        self.symbols.addr("config_block") == Some(CONFIG_BLOCK_ADDR)
    }

    /// The address of a symbol the emulator needs.
    ///
    /// # Errors
    /// [`FirmwareError::MissingSymbol`].
    pub fn addr(&self, name: &str) -> Result<u32, FirmwareError> {
        self.symbols
            .addr(name)
            .ok_or_else(|| FirmwareError::MissingSymbol(name.to_string()))
    }

    /// The stack's room its symbols give ([`SymbolTable::stack_room`]; the whole RAM without
    /// symbols), before the arrays it carves at boot.
    #[must_use]
    pub fn stack_room(&self) -> StackRoom {
        self.symbols.stack_room()
    }

    /// Raises `cpu`'s stack guard's low end to the end of what the firmware carved above its
    /// data at boot (its `heap_end` pointer, read from `mcu`'s RAM), when it has one: call it
    /// once the firmware has booted.
    pub fn raise_stack_low<B: Board>(&self, cpu: &mut Cpu, mcu: &Mcu<B>) {
        if let Some(p) = self.symbols.heap_end_pointer() {
            let end = peek_be::<B, 4>(mcu, p) as u32;
            cpu.raise_stack_low(end);
        }
    }

    /// Programs the image into `mcu`'s flash and, when given, the configuration block over it,
    /// and resets `cpu` (PC from the reset vector).
    ///
    /// # Errors
    /// [`FirmwareError::Load`] when the image does not fit the flash.
    pub fn install<B: Board>(
        &self,
        mcu: &mut Mcu<B>,
        cpu: &mut Cpu,
        block: Option<&ConfigBlock>,
    ) -> Result<(), FirmwareError> {
        let mut code = self.program(mcu)?;
        if let Some(b) = block {
            // With a configuration block these are VARYING_BYTES, of which the shared code
            // holds nothing; without one they may be code the shared tables decoded.
            if !self.has_config_block() {
                code = None;
            }
            mcu.poke(CONFIG_BLOCK_ADDR, &b.encode());
        }
        // Either way the CPU forgets what it decoded before (adopting does that too).
        match (code, mcu.code_generation()) {
            (Some(code), Some(token)) => cpu.adopt_shared_code(code, token),
            _ => cpu.flush_decode_cache(),
        }
        cpu.reset(mcu);
        // The first access to what the chip does not model stops the CPU, so that its report
        // names the instruction ([`Firmware::describe_io`]).
        mcu.set_io_break(true);
        Ok(())
    }

    /// A report of the chip ([`IoReport`]) as one line, its instruction's function named from
    /// the image's symbols.
    #[must_use]
    pub fn describe_io(&self, r: &IoReport) -> String {
        describe_io(&self.symbols, r)
    }
}

/// A report of the chip ([`IoReport`]) as one line, its instruction's function named from
/// `symbols`.
#[must_use]
pub fn describe_io(symbols: &SymbolTable, r: &IoReport) -> String {
    let function =
        r.pc.and_then(|pc| symbols.function_at(pc))
            .map(|s| s.c_name());
    r.describe(function)
}

/// Reads a big-endian value of `N` bytes at `addr` (no bus cycle).
#[must_use]
pub fn peek_be<B: Board, const N: usize>(mcu: &Mcu<B>, addr: u32) -> u64 {
    (0..N as u32).fold(0u64, |v, i| (v << 8) | u64::from(mcu.peek(addr + i)))
}

/// Names the function of a stack fault the core reported, from `symbols`.
pub fn name_stack_fault(e: &mut CpuError, symbols: &SymbolTable) {
    if let CpuError::StackOverflow(f) = e {
        f.function = symbols.function_at(f.pc).map(|s| s.c_name().to_string());
    }
}

/// Why the firmware stopped.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The core could not go on.
    #[error("the core stopped")]
    Cpu(#[from] CpuError),
    /// The firmware halted (SLEEP with interrupts masked): a fault stub or `main` returned.
    #[error("the firmware halted at PC H'{pc:06X} with exit status 0x{status:02X}{why}")]
    Halted {
        /// Where.
        pc: u32,
        /// R0L.
        status: u8,
        /// What the status means for the robot firmware.
        why: String,
    },
    /// The firmware touched an address the chip does not model, with the chip told to stop
    /// it there ([`FirmwareController::set_strict_io`]).
    #[error("{0} (stopped by --strict-io)")]
    Unmodelled(String),
}

/// Runs `cpu` until the clock reaches `deadline` (sleeping through idle time).
///
/// # Errors
/// [`RunError`] when the core stops or the firmware halts.
pub fn run_until<B: Board>(cpu: &mut Cpu, mcu: &mut Mcu<B>, deadline: u64) -> Result<(), RunError> {
    use h8300h::bus::Bus;
    while mcu.now() < deadline {
        match cpu.step(mcu, deadline)? {
            Event::Halted => return Err(halted(cpu)),
            Event::Asleep => break,
            _ => {}
        }
    }
    Ok(())
}

/// The error for a halted CPU.
#[must_use]
pub fn halted(cpu: &Cpu) -> RunError {
    let status = cpu.er(0) as u8;
    let why = if (0x81..=0x80 + 60).contains(&status) {
        format!(" (an unexpected exception: vector {})", status - 0x80)
    } else {
        String::new()
    };
    RunError::Halted {
        pc: cpu.pc(),
        status,
        why,
    }
}

/// Longest a robot's firmware may go without beginning a step (starting the A/D converter) or
/// without going back to sleep after one before the emulator calls it stuck: 10 s of MCU time,
/// a watchdog's view (docs/design.md §3.5's steps come every 0.45–0.60 s).
pub const WATCHDOG_S: f64 = 10.0;

/// Why a robot's firmware cannot go on.
#[derive(Debug, thiserror::Error)]
pub enum StepError {
    /// The core stopped or the firmware halted.
    #[error(transparent)]
    Run(#[from] RunError),
    /// Nothing happened that a robot must do.
    #[error(
        "no {what} within {WATCHDOG_S} s of MCU time (at state {at}, PC H'{pc:06X}): the firmware must start the A/D converter every step and sleep between steps"
    )]
    Watchdog {
        /// What did not happen.
        what: &'static str,
        /// When the watchdog gave up.
        at: u64,
        /// Where the CPU was.
        pc: u32,
    },
}

/// A robot's firmware on its MCU, run step by step for the swarm.
///
/// The swarm needs two instants of every step: when the robot begins to sense (the world must
/// have placed it and computed what its sensors see) and when the step's work is done (its
/// motor pins then drive the world). Both are read off the hardware, so any image that follows
/// the robot's hardware contract works: a step begins when the firmware starts the A/D
/// converter (ADST written 1: the first sample is taken 40 or 80 states later), and its work
/// is done when the CPU next executes SLEEP. Between steps the CPU sleeps through the ticks,
/// each woken by its interrupt and put back to sleep by the firmware. States the CPU spends
/// asleep are idle; all others are busy (the robot's CPU load).
#[derive(Debug)]
pub struct FirmwareController {
    cpu: Cpu,
    /// A/D runs started so far (the converter's count).
    adc_starts: u64,
    busy: u64,
    watchdog_states: u64,
    /// The phase signal of a pin trace, while one is recorded ([`Self::record_phases`]).
    phases: Option<PhaseRecorder>,
    /// A GDB client's control of the firmware, while one is attached ([`Self::attach`]).
    debugger: Option<Box<Debugger>>,
    /// The image's symbols (shared), to name the function of a stack fault and to find the
    /// end of what the firmware carves at boot.
    symbols: SymbolTable,
    /// Whether the stack guard's room still has to take in what the firmware carves at boot.
    booting: bool,
    /// Whether the first access to what the chip does not model stops the firmware.
    strict_io: bool,
    /// The reports of such accesses already looked at under `strict_io`.
    io_seen: usize,
    /// A profile of where the states go by call stack, while one is recorded
    /// ([`Self::start_profile`]): the firmware then runs instruction by instruction.
    profile: Option<Box<StackProfile>>,
}

impl Clone for FirmwareController {
    /// A copy of the CPU and the counters; a phase recording is copied, a debugger is not
    /// (the copy runs on its own).
    fn clone(&self) -> Self {
        FirmwareController {
            cpu: self.cpu.clone(),
            adc_starts: self.adc_starts,
            busy: self.busy,
            watchdog_states: self.watchdog_states,
            phases: None,
            debugger: None,
            symbols: self.symbols.clone(),
            booting: self.booting,
            strict_io: self.strict_io,
            io_seen: self.io_seen,
            profile: None,
        }
    }
}

impl FirmwareController {
    /// Programs `fw` (and `block`, when given) into `mcu`'s flash and resets the CPU, with a
    /// stack guard that stops the firmware ([`Self::set_stack_guard_mode`]) over the room its
    /// symbols give ([`Firmware::stack_room`]), raised to the end of its boot-sized arrays
    /// once it has booted ([`Firmware::raise_stack_low`]).
    ///
    /// # Errors
    /// [`FirmwareError::Load`] when the image does not fit the flash.
    pub fn start<B: Board>(
        fw: &Firmware,
        mcu: &mut Mcu<B>,
        block: Option<&ConfigBlock>,
    ) -> Result<Self, FirmwareError> {
        let mut cpu = Cpu::new();
        cpu.set_stack_guard(Some(StackGuard::stop(fw.stack_room())));
        fw.install(mcu, &mut cpu, block)?;
        Ok(FirmwareController {
            cpu,
            adc_starts: mcu.adc().starts(),
            busy: 0,
            watchdog_states: (WATCHDOG_S * f64::from(mcu.clock_hz())) as u64,
            phases: None,
            debugger: None,
            symbols: fw.symbols.clone(),
            booting: true,
            strict_io: false,
            io_seen: 0,
            profile: None,
        })
    }

    /// Whether the first access to an address the chip does not model stops the firmware
    /// with [`RunError::Unmodelled`] (`true`) or is only reported (`false`, the default;
    /// [`Mcu::io_reports`], [`Self::describe_io`]).
    pub fn set_strict_io(&mut self, on: bool) {
        self.strict_io = on;
    }

    /// A report of the chip as one line, named from the image's symbols.
    #[must_use]
    pub fn describe_io(&self, r: &IoReport) -> String {
        describe_io(&self.symbols, r)
    }

    /// Starts a profile of where the states go by call stack ([`StackProfile`]) from the
    /// clock `now` (the states before it go to `[reset]`): from here on the firmware runs
    /// instruction by instruction (the same states at the same instants, more slowly).
    pub fn start_profile(&mut self, now: u64) {
        let names: std::sync::Arc<dyn CodeNames + Send + Sync> =
            std::sync::Arc::new(self.symbols.clone());
        let entries = self.symbols.function_entries();
        self.profile = Some(Box::new(StackProfile::new(
            Some(names),
            Some(entries),
            &self.cpu,
            now,
        )));
    }

    /// Ends the profile, with the states up to `now` attributed, and returns it.
    pub fn take_profile(&mut self, now: u64) -> Option<StackProfile> {
        let mut p = self.profile.take()?;
        p.catch_up(now, self.cpu.sleeping());
        Some(*p)
    }

    /// What the stack guard does when a stack access leaves the room: stop the firmware with
    /// an error (the default) or keep the first fault ([`Self::stack_fault`]) and go on.
    pub fn set_stack_guard_mode(&mut self, mode: StackGuardMode) {
        if let Some(mut g) = self.cpu.stack_guard() {
            g.mode = mode;
            self.cpu.set_stack_guard(Some(g));
        }
    }

    /// Runs the firmware without a stack guard (to measure what the guard costs; the results
    /// are the same when nothing overflows).
    pub fn disable_stack_guard(&mut self) {
        self.cpu.set_stack_guard(None);
    }

    /// The first stack access that left the room, with its function (under a warning guard).
    #[must_use]
    pub fn stack_fault(&self) -> Option<StackFault> {
        self.cpu.stack_fault().map(|f| {
            let mut f = f.clone();
            f.function = self
                .symbols
                .function_at(f.pc)
                .map(|s| s.c_name().to_string());
            f
        })
    }

    /// Starts recording the phase signal of a pin trace (which function runs, by `names`)
    /// from `now` on; the MCU's pin trace is started apart ([`Mcu::start_trace`]).
    pub fn record_phases(&mut self, names: Arc<dyn CodeNames + Send + Sync>, now: u64) {
        let mut p = PhaseRecorder::new(names);
        p.observe(now, self.cpu.pc());
        self.phases = Some(p);
    }

    /// The phase signal being recorded, if one is (to take its changes as they come).
    pub fn phases_mut(&mut self) -> Option<&mut PhaseRecorder> {
        self.phases.as_mut()
    }

    /// Stops recording phases and returns the changes recorded (empty if none were).
    pub fn take_phases(&mut self) -> Vec<(u64, String)> {
        self.phases.take().map(|mut p| p.take()).unwrap_or_default()
    }

    /// Puts the firmware under a GDB client's control: from here on it runs instruction by
    /// instruction, stops at the client's breakpoints and watchpoints, and waits (and with it
    /// whatever runs it, the swarm) while the client has it stopped.
    pub fn attach(&mut self, debugger: Debugger) {
        self.debugger = Some(Box::new(debugger));
    }

    /// Ends a GDB session: tells the client the program ended (`None` when none is attached).
    pub fn detach(&mut self) {
        if let Some(mut d) = self.debugger.take() {
            d.finish(None, std::time::Duration::from_secs(1));
        }
    }

    /// The CPU (registers, PC).
    #[must_use]
    pub fn cpu(&self) -> &Cpu {
        &self.cpu
    }

    /// Busy states since the last call (or since start).
    pub fn take_busy(&mut self) -> u64 {
        std::mem::take(&mut self.busy)
    }

    /// Turns the core's loop fast-forwarding on (the default) or off ([`Cpu::set_fast_forward`]):
    /// the same states at the same instants either way.
    pub fn set_fast_forward(&mut self, on: bool) {
        self.cpu.set_fast_forward(on);
    }

    /// Runs the CPU until `stop` holds after an instruction, the CPU goes to sleep (SLEEP
    /// executed), an interrupt is accepted, or the clock reaches `deadline`; a sleeping CPU
    /// first sleeps until an interrupt wakes it (idle time). Busy states are counted apart.
    fn run<B: Board>(
        &mut self,
        mcu: &mut Mcu<B>,
        deadline: u64,
        stop: impl FnMut(&Mcu<B>) -> bool,
    ) -> Result<Event, RunError> {
        self.run_unnamed(mcu, deadline, stop).map_err(|mut e| {
            if let RunError::Cpu(c) = &mut e {
                name_stack_fault(c, &self.symbols);
            }
            e
        })
    }

    /// [`Self::run`] without naming the function of a stack fault.
    fn run_unnamed<B: Board>(
        &mut self,
        mcu: &mut Mcu<B>,
        deadline: u64,
        mut stop: impl FnMut(&Mcu<B>) -> bool,
    ) -> Result<Event, RunError> {
        use h8300h::bus::Bus;
        if self.cpu.sleeping()
            && self.debugger.is_none()
            && self.phases.is_none()
            && self.profile.is_none()
        {
            // Idle cycles (tick, handler, back to sleep) proven to repeat are advanced at once.
            let idle = self.cpu.run_idle(mcu, deadline, &mut |_, m| stop(m))?;
            self.busy += idle.busy;
            match idle.end {
                Some(Event::Halted) => return Err(halted(&self.cpu)),
                Some(event) => {
                    self.check_io(mcu, event)?;
                    return Ok(event);
                }
                None => {}
            }
        }
        if self.cpu.sleeping() {
            let t = mcu.now();
            mcu.sleep_until_irq(deadline);
            if let Some(p) = self.profile.as_mut() {
                p.catch_up(t, false);
                p.catch_up(mcu.now(), true);
            }
            if mcu.now() >= deadline {
                return Ok(Event::Asleep);
            }
        }
        let t0 = mcu.now();
        let event = if self.debugger.is_some() {
            self.run_debugged(mcu, deadline, &mut stop)?
        } else if self.profile.is_some() {
            self.run_profiled(mcu, deadline, &mut stop)?
        } else if let Some(p) = self.phases.as_mut() {
            // Which function runs, observed after every instruction (a stretch that loop
            // fast-forwarding skips stays in one loop, so in one function).
            let event = self.cpu.run_until(mcu, deadline, |cpu, m| {
                p.observe(m.now(), cpu.pc());
                cpu.sleeping() || stop(m)
            })?;
            if let Event::Interrupt(_) = event {
                let at = mcu
                    .trace_last_interrupt()
                    .map_or(mcu.now(), |a| a.t.clamp(t0, mcu.now()));
                p.observe(at, self.cpu.pc());
            }
            event
        } else {
            self.cpu
                .run_until(mcu, deadline, |cpu, m| cpu.sleeping() || stop(m))?
        };
        match event {
            Event::Halted => return Err(halted(&self.cpu)),
            Event::Asleep => {}
            Event::Executed | Event::Interrupt(_) | Event::Reset | Event::Break => {
                self.busy += mcu.now() - t0;
            }
        }
        self.check_io(mcu, event)?;
        Ok(event)
    }

    /// After a break (the first access to an address the chip does not model): under
    /// [`Self::set_strict_io`], the firmware stops with the report.
    fn check_io<B: Board>(&mut self, mcu: &Mcu<B>, event: Event) -> Result<(), RunError> {
        if event == Event::Break && self.strict_io {
            let reports = mcu.io_reports();
            if let Some(r) = reports.get(self.io_seen) {
                self.io_seen = reports.len();
                return Err(RunError::Unmodelled(self.describe_io(r)));
            }
        }
        Ok(())
    }

    /// [`Self::run`]'s loop while a profile is recorded: step by step, each step attributed.
    fn run_profiled<B: Board>(
        &mut self,
        mcu: &mut Mcu<B>,
        deadline: u64,
        stop: &mut impl FnMut(&Mcu<B>) -> bool,
    ) -> Result<Event, RunError> {
        use h8300h::bus::Bus;
        while mcu.now() < deadline {
            let Some(p) = self.profile.as_deref_mut() else {
                break;
            };
            let t0 = mcu.now();
            let event = p.step(&mut self.cpu, mcu, deadline)?;
            if let Some(ph) = self.phases.as_mut() {
                match event {
                    Event::Executed | Event::Reset => ph.observe(mcu.now(), self.cpu.pc()),
                    Event::Interrupt(_) => {
                        let at = mcu
                            .trace_last_interrupt()
                            .map_or(t0, |a| a.t.clamp(t0, mcu.now()));
                        ph.observe(at, self.cpu.pc());
                    }
                    _ => {}
                }
            }
            if event != Event::Executed || self.cpu.sleeping() || stop(mcu) {
                return Ok(event);
            }
        }
        Ok(Event::Executed)
    }

    /// [`Self::run`]'s loop under a debugger: step by step, asking it before each step.
    fn run_debugged<B: Board>(
        &mut self,
        mcu: &mut Mcu<B>,
        deadline: u64,
        stop: &mut impl FnMut(&Mcu<B>) -> bool,
    ) -> Result<Event, RunError> {
        use h8300h::bus::Bus;
        while mcu.now() < deadline {
            let Some(d) = self.debugger.as_deref_mut() else {
                break;
            };
            match d.before_step(&mut self.cpu, mcu) {
                DebugAction::Run => {}
                DebugAction::Detached | DebugAction::Kill => {
                    // Without a client the firmware runs on as before.
                    self.debugger = None;
                    return Ok(Event::Executed);
                }
            }
            let t0 = mcu.now();
            let event = match d.step(&mut self.cpu, mcu, deadline) {
                Ok(e) => e,
                Err(e) => {
                    d.report_error(&mut self.cpu, mcu);
                    return Err(e.into());
                }
            };
            if let Some(p) = self.phases.as_mut() {
                match event {
                    Event::Executed => p.observe(mcu.now(), self.cpu.pc()),
                    Event::Interrupt(_) => {
                        let at = mcu
                            .trace_last_interrupt()
                            .map_or(t0, |a| a.t.clamp(t0, mcu.now()));
                        p.observe(at, self.cpu.pc());
                    }
                    _ => {}
                }
            }
            if event != Event::Executed || self.cpu.sleeping() || stop(mcu) {
                return Ok(event);
            }
        }
        Ok(Event::Executed)
    }

    /// Runs until the firmware starts the A/D converter (its step begins); returns the clock
    /// then. The first sample is taken at least 40 states later, so the board's inputs can
    /// still be set.
    ///
    /// # Errors
    /// [`StepError`] when the core stops, the firmware halts, or no conversion starts within
    /// [`WATCHDOG_S`].
    pub fn run_to_sensing<B: Board>(&mut self, mcu: &mut Mcu<B>) -> Result<u64, StepError> {
        use h8300h::bus::Bus;
        let deadline = mcu.now() + self.watchdog_states;
        let before = self.adc_starts;
        loop {
            self.run(mcu, deadline, |m| m.adc().starts() != before)?;
            let starts = mcu.adc().starts();
            if starts != before {
                self.adc_starts = starts;
                if std::mem::take(&mut self.booting)
                    && let Some(p) = self.symbols.heap_end_pointer()
                {
                    // Booted: the arrays the firmware carved above its data are not the
                    // stack's.
                    let end = peek_be::<B, 4>(mcu, p) as u32;
                    self.cpu.raise_stack_low(end);
                }
                return Ok(mcu.now());
            }
            if mcu.now() >= deadline {
                return Err(StepError::Watchdog {
                    what: "A/D conversion started (no step)",
                    at: mcu.now(),
                    pc: self.cpu.pc(),
                });
            }
        }
    }

    /// Runs until the CPU executes SLEEP (the step's work is done).
    ///
    /// # Errors
    /// As [`FirmwareController::run_to_sensing`]; the watchdog when the CPU does not sleep
    /// within [`WATCHDOG_S`].
    pub fn run_to_sleep<B: Board>(&mut self, mcu: &mut Mcu<B>) -> Result<(), StepError> {
        use h8300h::bus::Bus;
        let deadline = mcu.now() + self.watchdog_states;
        while !self.cpu.sleeping() {
            self.run(mcu, deadline, |_| false)?;
            if mcu.now() >= deadline && !self.cpu.sleeping() {
                return Err(StepError::Watchdog {
                    what: "SLEEP after the step's work",
                    at: mcu.now(),
                    pc: self.cpu.pc(),
                });
            }
        }
        Ok(())
    }
}

/// Reads a file a user named, refusing one larger than `limit` bytes (an error of kind
/// `InvalidData` that says the bound) instead of holding whatever it gives: `/dev/zero` or a
/// huge file as a scenario, image or symbol table.
///
/// # Errors
/// The file cannot be opened or read, or is larger than `limit`.
pub fn read_bounded(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(limit + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("larger than {limit} bytes, the most this file may hold"),
        ));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use h8_3052f::mcu::McuConfig;
    use h8_3052f::pins::NullBoard;

    fn flash_bytes(mcu: &Mcu<NullBoard>, image: &SrecImage) -> Vec<u8> {
        image
            .chunks
            .iter()
            .flat_map(|c| (0..c.data.len()).map(move |i| c.address + i as u32))
            .map(|a| mcu.peek(a))
            .collect()
    }

    /// An image without a configuration block whose code runs through H'000400 (a user's
    /// image): its robots share all of its decoded code, run it as a CPU decoding for itself
    /// does, and one given a block anyway (poked over that code) decodes for itself.
    #[test]
    fn code_at_the_block_address_is_shared_when_no_block_lands_there() {
        // Reset vector -> H'000100; NOPs up to H'000500, then mov.b #7,r0l and SLEEP (with
        // CCR.I set after reset: the program halts).
        let mut code = vec![0u8; 0x400];
        code.extend_from_slice(&[0xF8, 0x07, 0x01, 0x80]);
        let image = SrecImage {
            header: None,
            chunks: vec![
                h8300h::srec::Chunk {
                    address: 0,
                    data: vec![0, 0, 0x01, 0x00],
                },
                h8300h::srec::Chunk {
                    address: 0x100,
                    data: code,
                },
            ],
            start: None,
        };
        let fw = Firmware {
            image,
            symbols: SymbolTable::default(),
            name: "user.mot".to_string(),
            flash: OnceLock::new(),
        };
        assert!(!fw.has_config_block());
        let run = |block: Option<&ConfigBlock>, own: bool| {
            let mut mcu = Mcu::new(McuConfig::default(), NullBoard).expect("mcu");
            let mut cpu = Cpu::new();
            fw.install(&mut mcu, &mut cpu, block).expect("install");
            if own {
                cpu.flush_decode_cache();
            }
            let shares = cpu.shares_code(fw.shared_code().expect("built"));
            let _ = run_until(&mut cpu, &mut mcu, 1_000_000);
            let shares_after = cpu.shares_code(fw.shared_code().expect("built"));
            (
                cpu.regs(),
                cpu.halted(),
                h8300h::bus::Bus::now(&mcu),
                shares,
                shares_after,
            )
        };
        let shared = run(None, false);
        let own = run(None, true);
        assert!(shared.3 && shared.4, "shared before and after the run");
        assert!(!own.3);
        assert!(shared.1, "halted");
        assert_eq!(shared.0[0] & 0xFF, 7);
        assert_eq!((shared.0, shared.1, shared.2), (own.0, own.1, own.2));
        let code = fw.shared_code().expect("built");
        assert!(code.filled() >= 0x200, "{} slots", code.filled());
        // A block poked over the code: that CPU decodes for itself, and runs the bytes it has.
        let blocked = run(Some(&ConfigBlock::ARENA), false);
        let blocked_own = run(Some(&ConfigBlock::ARENA), true);
        assert!(!blocked.3);
        assert_eq!(
            (blocked.0, blocked.1, blocked.2),
            (blocked_own.0, blocked_own.1, blocked_own.2)
        );
    }

    /// MCUs sharing the firmware's flash read the image, each keeps its own configuration
    /// block, and a firmware whose image changed after its flash was built installs the new
    /// image, not the old flash.
    #[test]
    fn shared_flash_reads_as_the_image_each_mcu_wrote() {
        let fw = Firmware::robot().expect("the robot firmware");
        let want: Vec<u8> = fw
            .image
            .chunks
            .iter()
            .flat_map(|c| c.data.clone())
            .collect();
        let mut mcus = Vec::new();
        for seed in [1u32, 2] {
            let mut mcu = Mcu::new(McuConfig::default(), NullBoard).expect("mcu");
            let mut cpu = Cpu::new();
            let block = ConfigBlock {
                seed,
                ..ConfigBlock::ARENA
            };
            fw.install(&mut mcu, &mut cpu, Some(&block))
                .expect("install");
            mcus.push(mcu);
        }
        let blocks: Vec<Vec<u8>> = mcus
            .iter()
            .map(|m| {
                let len = ConfigBlock::ARENA.encode().len() as u32;
                (0..len).map(|i| m.peek(CONFIG_BLOCK_ADDR + i)).collect()
            })
            .collect();
        assert_ne!(blocks[0], blocks[1], "each MCU keeps its own block");
        let mut plain = Mcu::new(McuConfig::default(), NullBoard).expect("mcu");
        plain.load_image(&fw.image).expect("load");
        for m in &mcus {
            for a in (0..0x2000u32).filter(|a| {
                !(CONFIG_BLOCK_ADDR..CONFIG_BLOCK_ADDR + CONFIG_BLOCK_BYTES as u32).contains(a)
            }) {
                assert_eq!(m.peek(a), plain.peek(a), "flash byte at H'{a:06X}");
            }
        }
        let mut changed = fw.clone();
        changed.image.chunks[0].data[0] ^= 0xFF;
        let mut mcu = Mcu::new(McuConfig::default(), NullBoard).expect("mcu");
        changed
            .install(&mut mcu, &mut Cpu::new(), None)
            .expect("install");
        let got = flash_bytes(&mcu, &changed.image);
        assert_eq!(got[0], want[0] ^ 0xFF);
        assert_eq!(&got[1..], &want[1..]);
    }
}
