//! The firmware measured on the H8/300H core: boot, the step periods counted from the first
//! step, states attributed to phases by PC, RAM from the symbol table and the stack's
//! high-water mark.
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

use super::config::{BOOT_LIMIT_S, FitConfig, FitError, PHASE_BOOT, PHASE_OTHER};
use super::meter::{FitMeter, Measured, Rig};
use super::report::{MemLine, StackLine};
use h8_3052f::mcu::Mcu;
use h8_3052f::pins::Board;
use h8300h::bus::Bus;
use h8300h::cpu::{Cpu, CpuError, Event, StackFault, StackGuard};
use robot_board::firmware::{ConfigBlock, ConfigStatus, Firmware, RunError, halted};
use robot_board::profile::Profiler;

/// Runs the firmware for `cfg.steps` step periods.
pub(super) fn measure_firmware(cfg: &FitConfig) -> Result<Measured, FitError> {
    let fw = &cfg.firmware.firmware;
    let block = config_block(cfg)?;
    let mut run = FirmwareRun::start(cfg, block)?;
    let mut periods = StepPeriods::new(run.profiler.names().len(), cfg.steps);
    let mut boot_states = 0;
    let mut meter = None;
    // The measurement, up to a stack overflow if there is one.
    let fault: Option<Box<StackFault>> = 'run: {
        if let Some(f) = run.boot()? {
            break 'run Some(f);
        }
        boot_states = run.profiler.states().iter().sum();
        // Booted: what the firmware carved above its data is not the stack's.
        fw.raise_stack_low(&mut run.cpu, &run.rig.mcu);
        run.check_config_status(fw, block.as_ref())?;
        let m = meter.insert(FitMeter::new(&run.rig.mcu));
        run.step_periods(cfg.steps, &mut periods, m)?
    };
    let energy = match (fault.is_none(), meter) {
        (true, Some(m)) => Some(m.finish(&run.rig.mcu, periods.busy.iter().sum())),
        _ => None,
    };
    let fault = fault.map(|mut f| {
        f.function = fw.symbols.function_at(f.pc).map(|s| s.c_name().to_string());
        *f
    });
    let phases: Vec<(String, Vec<u64>)> = run
        .profiler
        .names()
        .iter()
        .cloned()
        .zip(periods.per_phase)
        .filter(|(n, _)| n != PHASE_BOOT)
        .collect();
    let stack_top = fw
        .symbols
        .addr("_stack_top")
        .unwrap_or(h8300h::memmap::RAM_END + 1);
    let stack_high_water = stack_top.saturating_sub(run.profiler.min_sp());
    let stack = run.stack_line(fw, fault.as_ref());
    let unmodelled = run
        .rig
        .mcu
        .io_reports()
        .iter()
        .map(|r| (r.short(), fw.describe_io(r)))
        .collect();
    Ok(Measured {
        source: fw.name.clone(),
        boot_states,
        phases,
        busy: periods.busy,
        ram: firmware_ram(fw, &run.rig.mcu, stack_high_water),
        stack_high_water: Some(stack_high_water),
        stack: Some(stack),
        energy,
        unmodelled,
    })
}

/// The configuration block to install in the firmware: the controller's, or none for an image
/// without one when the controller is the arena's (the image's own constants are then the
/// arena's).
pub(super) fn config_block(cfg: &FitConfig) -> Result<Option<ConfigBlock>, FitError> {
    let fw = &cfg.firmware.firmware;
    let block = ConfigBlock::from_controller(&cfg.controller)?;
    if fw.has_config_block() {
        Ok(Some(block))
    } else if block == ConfigBlock::ARENA {
        Ok(None)
    } else {
        Err(FitError::NoBlock {
            image: fw.name.clone(),
        })
    }
}

/// The states of each measured step period: per phase, and all of them (the busy states).
pub(super) struct StepPeriods {
    per_phase: Vec<Vec<u64>>,
    busy: Vec<u64>,
}

impl StepPeriods {
    fn new(n_phases: usize, steps: u32) -> StepPeriods {
        StepPeriods {
            per_phase: vec![Vec::with_capacity(steps as usize); n_phases],
            busy: Vec::with_capacity(steps as usize),
        }
    }

    /// A step period ended with the profiler's counts at `now`, from `before` at its start.
    fn push(&mut self, before: &[u64], now: &[u64]) {
        for (i, v) in self.per_phase.iter_mut().enumerate() {
            v.push(now[i] - before[i]);
        }
        self.busy
            .push(now.iter().sum::<u64>() - before.iter().sum::<u64>());
    }
}

/// The firmware under measurement: its robot, CPU and phase profiler, and the limits of the run.
pub(super) struct FirmwareRun {
    rig: Rig,
    cpu: Cpu,
    profiler: Profiler,
    /// The step's first phase (A/D for the robot firmware), or `usize::MAX` without phases
    /// (the step periods are then fixed windows from the first SLEEP).
    step_phase: usize,
    /// The most states boot may take, and the slack of a step period beyond two periods.
    boot_limit: u64,
    /// A step period, states.
    period: u64,
    /// The MCU's clock, Hz.
    clock: f64,
    /// Stop at the first access to what the chip does not model ([`FitConfig::strict_io`]).
    strict_io: bool,
    /// The image's symbols, to name that access's function.
    symbols: robot_board::symbols::SymbolTable,
}

impl FirmwareRun {
    /// The firmware installed (with `block`) on a fresh robot, at reset.
    fn start(cfg: &FitConfig, block: Option<ConfigBlock>) -> Result<FirmwareRun, FitError> {
        let fw = &cfg.firmware.firmware;
        let mut rig = Rig::new(cfg)?;
        let mut cpu = Cpu::new();
        // The stack guard stops the measurement at a stack access outside the room: the verdict
        // is then that it does not fit, with how far it went.
        cpu.set_stack_guard(Some(StackGuard::stop(fw.stack_room())));
        fw.install(&mut rig.mcu, &mut cpu, block.as_ref())?;
        let profiler = Profiler::new(&fw.symbols, &cfg.firmware.phases, PHASE_OTHER)?;
        let clock = f64::from(cfg.controller.clock_hz);
        let step_phase = profiler
            .names()
            .iter()
            .position(|n| n != PHASE_BOOT && n != PHASE_OTHER)
            .unwrap_or(usize::MAX);
        let period = match block {
            Some(b) => b.step_period_states(),
            None => ConfigBlock::ARENA.step_period_states(),
        };
        Ok(FirmwareRun {
            rig,
            cpu,
            profiler,
            step_phase,
            boot_limit: (BOOT_LIMIT_S * clock) as u64,
            period,
            clock,
            strict_io: cfg.strict_io,
            symbols: fw.symbols.clone(),
        })
    }

    /// Runs the CPU up to one event, before `deadline`; a halt is an error.
    fn step(&mut self, deadline: u64) -> Result<Event, FitError> {
        let at = self.rig.mcu.now();
        match self
            .profiler
            .run_one(&mut self.cpu, &mut self.rig.mcu, deadline)
        {
            Ok(Event::Halted) => Err(FitError::Run {
                at,
                source: halted(&self.cpu),
            }),
            Ok(Event::Break) if self.strict_io => {
                let what = self
                    .rig
                    .mcu
                    .io_reports()
                    .last()
                    .map_or_else(String::new, |r| {
                        robot_board::firmware::describe_io(&self.symbols, r)
                    });
                Err(FitError::Run {
                    at,
                    source: RunError::Unmodelled(what),
                })
            }
            Ok(e) => Ok(e),
            Err(e) => Err(FitError::Run {
                at,
                source: RunError::Cpu(e),
            }),
        }
    }

    /// Boot: from reset until the first step begins (the first entry into the step's first
    /// phase, A/D for the robot firmware; without phases, the first SLEEP). The step periods
    /// are counted from there. A stack overflow on the way is returned.
    fn boot(&mut self) -> Result<Option<Box<StackFault>>, FitError> {
        let booted = |run: &FirmwareRun| {
            if run.step_phase == usize::MAX {
                run.cpu.sleeping()
            } else {
                run.profiler.first_entry(run.step_phase).is_some()
            }
        };
        while !booted(self) {
            if self.rig.mcu.now() >= self.boot_limit {
                return Err(FitError::BootTimeout { pc: self.cpu.pc() });
            }
            if let Err(e) = self.step(self.boot_limit) {
                return Ok(Some(overflow(e)?));
            }
        }
        Ok(None)
    }

    /// A firmware that checks its configuration block and rejected it is an error.
    fn check_config_status(
        &self,
        fw: &Firmware,
        block: Option<&ConfigBlock>,
    ) -> Result<(), FitError> {
        if let Some(addr) = fw.symbols.addr("cfg_status")
            && block.is_some()
            && let ConfigStatus::Rejected { field, code } =
                ConfigStatus::from_code(self.rig.mcu.peek(addr))
        {
            return Err(FitError::Rejected { field, code });
        }
        Ok(())
    }

    /// Runs `steps` step periods after boot, counting their states into `periods` and their
    /// charge into `meter`. A stack overflow on the way ends them and is returned.
    fn step_periods(
        &mut self,
        steps: u32,
        periods: &mut StepPeriods,
        meter: &mut FitMeter,
    ) -> Result<Option<Box<StackFault>>, FitError> {
        let mut before: Vec<u64> = self.profiler.states().to_vec();
        // A step period runs from one step's start (the entry into its first phase) to the next
        // one's: one step, its ticks and the idle time up to the next (K ticks in steady state;
        // the first may be shorter when boot outlasted the first tick). Without phases, fixed
        // windows of K ticks from the first SLEEP.
        let mut window_end = self.rig.mcu.now();
        for k in 0..u64::from(steps) {
            // The world moves before each step's A/D scan.
            self.rig.move_world();
            let fault = if self.step_phase == usize::MAX {
                window_end += self.period;
                self.run_window(window_end)?
            } else {
                self.run_step(k)?
            };
            if fault.is_some() {
                return Ok(fault);
            }
            let now = self.profiler.states();
            periods.push(&before, now);
            before = now.to_vec();
            let seconds = self.period as f64 / self.clock;
            meter.period(&mut self.rig.mcu, seconds);
        }
        Ok(None)
    }

    /// Runs up to `window_end` or the next SLEEP, whichever comes first. A stack overflow on
    /// the way is returned.
    fn run_window(&mut self, window_end: u64) -> Result<Option<Box<StackFault>>, FitError> {
        while self.rig.mcu.now() < window_end {
            match self.step(window_end) {
                Ok(Event::Asleep) => break,
                Ok(_) => {}
                Err(e) => return Ok(Some(overflow(e)?)),
            }
        }
        Ok(None)
    }

    /// Runs until step `k + 1` begins (the `k + 2`th entry into the step's first phase); taking
    /// too long is an error. A stack overflow on the way is returned.
    fn run_step(&mut self, k: u64) -> Result<Option<Box<StackFault>>, FitError> {
        let limit = self.rig.mcu.now() + 2 * self.period + self.boot_limit;
        while self.profiler.entries(self.step_phase) < k + 2 {
            if self.rig.mcu.now() >= limit {
                return Err(FitError::StepTimeout {
                    phase: self.profiler.names()[self.step_phase].clone(),
                    pc: self.cpu.pc(),
                });
            }
            if let Err(e) = self.step(limit) {
                return Ok(Some(overflow(e)?));
            }
        }
        Ok(None)
    }

    /// The stack's room and what the firmware left of it, with the overflow if there was one.
    fn stack_line(&self, fw: &Firmware, fault: Option<&StackFault>) -> StackLine {
        let room = self
            .cpu
            .stack_guard()
            .map_or_else(|| fw.stack_room(), |g| g.room);
        let lowest_sp = self.profiler.min_sp().min(room.top);
        StackLine {
            room_low: room.low,
            room_top: room.top,
            room_bytes: room.bytes(),
            lowest_sp,
            left_bytes: i64::from(lowest_sp) - i64::from(room.low),
            overflow: fault.map(ToString::to_string),
            overflow_bytes: fault.map(StackFault::bytes_over),
        }
    }
}

/// The stack fault an error of the measurement is, or the error itself.
pub(super) fn overflow(e: FitError) -> Result<Box<StackFault>, FitError> {
    match e {
        FitError::Run {
            source: RunError::Cpu(CpuError::StackOverflow(f)),
            ..
        } => Ok(f),
        e => Err(e),
    }
}

/// A big-endian u32 in RAM.
pub(super) fn peek_u32<B: Board>(mcu: &Mcu<B>, addr: u32) -> u32 {
    (0..4).fold(0, |v, i| (v << 8) | u32::from(mcu.peek(addr + i)))
}

/// The image's RAM: every variable of `.data` and `.bss` (sized by the next symbol), the
/// network's arrays (from the firmware's pointers, when it has them), the stack's high-water.
pub(super) fn firmware_ram<B: Board>(fw: &Firmware, mcu: &Mcu<B>, stack: u32) -> Vec<MemLine> {
    let sym = |n: &str| fw.symbols.addr(n);
    let mut lines = Vec::new();
    if let (Some(start), Some(end)) = (
        sym("_data_start").or(sym("_bss_start")),
        sym("_bss_end").or(sym("_heap_start")),
    ) {
        let vars: Vec<&robot_board::symbols::Symbol> = fw
            .symbols
            .symbols()
            .iter()
            .filter(|s| {
                matches!(s.kind, 'b' | 'B' | 'd' | 'D')
                    && !s.name.starts_with('.')
                    && !s.name.starts_with("__")
                    && s.addr >= start
                    && s.addr < end
            })
            .collect();
        for (i, v) in vars.iter().enumerate() {
            let next = vars.get(i + 1).map_or(end, |n| n.addr);
            lines.push(MemLine {
                item: format!("{} (variable)", v.c_name()),
                addr: v.addr,
                bytes: next - v.addr,
            });
        }
    }
    let net = ["net_w", "net_delta", "net_y", "net_o", "net_x"].map(&sym);
    if let (Some(heap_end), [Some(w), Some(d), Some(y), Some(o), Some(x)]) = (sym("heap_end"), net)
    {
        let end = peek_u32(mcu, heap_end);
        let p = [w, d, y, o, x].map(|a| peek_u32(mcu, a));
        let names = [
            "weights w (i16, N x M)",
            "update deltas (i16, N)",
            "sums y (i32, M)",
            "outputs O (i16, M)",
            "input vector x (i8, N, word-aligned)",
        ];
        for k in 0..5 {
            let next = if k + 1 < 5 { p[k + 1] } else { end };
            lines.push(MemLine {
                item: format!("{} [carved at boot]", names[k]),
                addr: p[k],
                bytes: next.saturating_sub(p[k]),
            });
        }
    }
    let top = sym("_stack_top").unwrap_or(h8300h::memmap::RAM_END + 1);
    lines.push(MemLine {
        item: "stack (high-water mark measured)".to_string(),
        addr: top - stack,
        bytes: stack,
    });
    lines
}
