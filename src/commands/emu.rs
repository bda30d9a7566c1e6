//! `h8swarm emu IMAGE.mot [--max-states N] [--trace] [--stats] [--vcd FILE] [--gdb ADDR]
//! [--symbols FILE]`: runs a program on the emulated H8/3052F (docs/design.md §7) on the robot's
//! board (`robot_board::board::RobotBoard`: its two EEPROMs on port 4, seed 0, and nothing else
//! connected: the analog inputs at 0 V, port 2 released), so that programs that use the
//! EEPROMs run as on the robot. SCI1 is the console
//! (standard output); `--trace` writes one line per instruction (address, disassembly, states,
//! and the function it is in when the image has symbols) and `--stats` a JSON summary, both on
//! standard error. `--vcd` writes a pin trace of the whole run (`h8_3052f::vcd`); `--gdb`
//! waits for a GDB client on a loopback address before the program's first instruction
//! (`h8_3052f::gdb`). Symbols (for the phase names): `--symbols`, else IMAGE.sym beside the
//! image if present.
//!
//! The stack guard (`--stack-guard`) and the exit statuses: docs/design.md §7 (and
//! [`EXIT_MAX_STATES`], [`EXIT_CORE_ERROR`], [`EXIT_SLEPT_FOREVER`], [`EXIT_KILLED`]).

use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::sync::Arc;

use h8_3052f::gdb::{Debugger, GdbError, GdbListener};
use h8_3052f::mcu::{IoReport, Mcu};
use h8_3052f::pins::NullBoard;
use h8_3052f::profile::StackProfile;
use h8_3052f::run::{Outcome, Probes, RunOptions, drain_into, run_mcu_probed};
use h8_3052f::trace::{CodeNames, PhaseRecorder};
use h8_3052f::vcd::{VcdInfo, VcdStream};
use h8300h::bus::Bus;
use h8300h::cpu::{Cpu, StackGuard, StackGuardMode, StackRoom};
use h8300h::srec;
use robot_board::board::{RobotBoard, RobotConfig, robot_mcu};
use robot_board::symbols::SymbolTable;

use clap::Args;

use super::Failure;

/// The MCU `h8swarm emu` runs images on: the robot's board with nothing but its EEPROMs.
type EmuMcu = Mcu<RobotBoard<NullBoard>>;

/// Exit status when `--max-states` runs out (as `timeout(1)` does).
pub const EXIT_MAX_STATES: u8 = 124;
/// Exit status when the core stops on an error.
pub const EXIT_CORE_ERROR: u8 = 125;
/// Exit status when the program sleeps forever.
pub const EXIT_SLEPT_FOREVER: u8 = 126;
/// Exit status when a GDB client kills the program (128 + SIGKILL, as a shell reports it).
pub const EXIT_KILLED: u8 = 137;

/// What `h8swarm emu` was asked to do.
pub struct EmuOptions<'a> {
    /// The image (.mot).
    pub image: &'a str,
    /// The state budget.
    pub max_states: Option<u64>,
    /// One line per instruction on standard error.
    pub trace: bool,
    /// The JSON summary on standard error at the end.
    pub stats: bool,
    /// Write a pin trace of the whole run here (VCD).
    pub vcd: Option<&'a Path>,
    /// Serve a GDB client on this loopback address before the program runs.
    pub gdb: Option<&'a str>,
    /// The image's symbol table (nm -n output); default IMAGE.sym beside the image if present.
    pub symbols: Option<&'a Path>,
    /// What the stack guard does when a stack access leaves the stack's room.
    pub stack_guard: StackGuardMode,
    /// Write a profile of where the states go by call stack here (folded stacks).
    pub profile: Option<&'a Path>,
    /// Stop at the first access to an address the chip does not model.
    pub strict_io: bool,
}

fn input(msg: String) -> Failure {
    Failure::Input(anyhow::anyhow!(msg))
}

/// The symbol table for the phase names: `--symbols FILE`, else IMAGE.sym beside the image
/// when it exists, else none.
fn symbols(image: &str, given: Option<&Path>) -> Result<Option<SymbolTable>, Failure> {
    let path = match given {
        Some(p) => p.to_path_buf(),
        None => {
            let p = Path::new(image).with_extension("sym");
            if !p.is_file() {
                return Ok(None);
            }
            p
        }
    };
    let max = robot_board::firmware::Firmware::MAX_FILE_BYTES;
    let text = robot_board::firmware::read_bounded(&path, max)
        .and_then(|b| String::from_utf8(b).map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e)))
        .map_err(|e| {
        input(format!(
            "cannot read symbol file `{}`: {e} (give the output of `h8300-hms-nm -n`, or leave --symbols out)",
            path.display()
        ))
    })?;
    SymbolTable::parse(&text)
        .map(Some)
        .map_err(|e| input(format!("symbol file `{}`: {e}", path.display())))
}

/// Runs the image as `o` asks: the console on standard output, the trace, the summary and the
/// stop's reason on standard error; the error carries the exit status (module docs).
///
/// # Errors
/// A bad image, symbol file or option ([`Failure::Input`]), an output that cannot be written
/// ([`Failure::Tool`]), or the program's own exit status ([`Failure::Program`]).
pub fn run(o: &EmuOptions<'_>) -> Result<(), Failure> {
    let image = o.image;
    let mut mcu = load(image)?;
    let names = symbols(image, o.symbols)?.map(Arc::new);
    // Fail on a file that cannot be created before the program runs.
    let vcd_file = create_vcd(o.vcd)?;
    let mut profile_file = create_profile(o.profile)?;
    let mut debugger = wait_for_debugger(o.gdb)?;
    let mut cpu = Cpu::new();
    let room = names
        .as_deref()
        .map_or(StackRoom::RAM, SymbolTable::stack_room);
    cpu.set_stack_guard(Some(StackGuard {
        room,
        mode: o.stack_guard,
    }));
    cpu.reset(&mut mcu);
    let mcu = &mut mcu;
    // The trace is written as the run makes it (never held whole).
    let (mut stream, mut phases) = match vcd_file {
        Some(file) => {
            let (stream, phases) = start_vcd(file, &cpu, mcu, names.as_ref(), o)?;
            (Some(stream), phases)
        }
        None => (None, None),
    };
    let options = RunOptions {
        max_states: o.max_states,
        strict_io: o.strict_io,
    };
    let mut profile = profile_file.as_ref().map(|_| {
        let entries = names.as_deref().map(SymbolTable::function_entries);
        let code: Option<Arc<dyn CodeNames + Send + Sync>> =
            names.clone().map(|n| n as Arc<dyn CodeNames + Send + Sync>);
        StackProfile::new(code, entries, &cpu, mcu.now())
    });
    let stdout = io::stdout();
    let mut console = stdout.lock();
    // Not locked for the whole run: the GDB stub's thread may have to say on stderr that
    // its debugger is lost.
    let mut trace_out = BufWriter::with_capacity(1 << 16, io::stderr());
    let report = run_mcu_probed(
        &mut cpu,
        mcu,
        &options,
        &mut console,
        Probes {
            trace: if o.trace { Some(&mut trace_out) } else { None },
            names: names.as_deref().map(|n| n as &dyn CodeNames),
            phases: phases.as_mut(),
            debugger: debugger.as_mut(),
            vcd: stream.as_mut(),
            profile: profile.as_mut(),
        },
    );
    let _ = trace_out.flush();
    drop(trace_out);
    if let Some(v) = stream {
        finish_vcd(v, mcu, phases.as_mut()).map_err(|e| vcd_failure(o, e))?;
    }
    let report = match report {
        Ok(r) => r,
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => return Ok(()),
        Err(e) => {
            return Err(Failure::Tool(
                anyhow::Error::new(e).context("writing the console or the VCD file"),
            ));
        }
    };
    if let (Some(p), Some((file, path))) = (profile.as_mut(), profile_file.as_mut()) {
        p.catch_up(mcu.now(), cpu.sleeping());
        file.write_all(p.folded().as_bytes())
            .and_then(|()| file.flush())
            .map_err(|e| {
                Failure::Tool(
                    anyhow::Error::new(e)
                        .context(format!("writing the profile `{}`", path.display())),
                )
            })?;
    }
    if o.stats {
        eprintln!("{}", report.to_json());
    }
    if let Some(f) = &report.stack_fault {
        eprintln!("warning: image `{image}`: {f}");
    }
    if !matches!(report.outcome, Outcome::Unmodelled(_)) {
        for r in &report.io_reports {
            eprintln!(
                "warning: image `{image}`: {}",
                describe(r, names.as_deref())
            );
        }
    }
    exit(
        &report.outcome,
        report.stats.states,
        image,
        names.as_deref(),
    )
}

/// A report of the chip as one line, its function named when the image has symbols.
fn describe(r: &IoReport, names: Option<&SymbolTable>) -> String {
    match names {
        Some(n) => robot_board::firmware::describe_io(n, r),
        None => r.describe(None),
    }
}

/// The `--profile` file, created (empty) when asked for, with its path.
fn create_profile(
    path: Option<&Path>,
) -> Result<Option<(BufWriter<std::fs::File>, std::path::PathBuf)>, Failure> {
    match path {
        Some(p) => {
            let f = std::fs::File::create(p).map_err(|e| {
                input(format!(
                    "--profile: cannot create `{}`: {e} (give a writable file path)",
                    p.display()
                ))
            })?;
            Ok(Some((BufWriter::new(f), p.to_path_buf())))
        }
        None => Ok(None),
    }
}

/// The image loaded into a fresh MCU on the robot's board.
fn load(image: &str) -> Result<EmuMcu, Failure> {
    let max = robot_board::firmware::Firmware::MAX_FILE_BYTES;
    let bytes =
        robot_board::firmware::read_bounded(std::path::Path::new(image), max).map_err(|e| {
            input(format!(
                "cannot read image `{image}`: {e} (give a Motorola S-record file, .mot)"
            ))
        })?;
    let srec = srec::parse(&bytes).map_err(|e| {
        Failure::Input(anyhow::Error::new(e).context(format!("image `{image}`: bad image")))
    })?;
    let mut mcu = robot_mcu(NullBoard, &RobotConfig::default())
        .map_err(|e| Failure::Tool(anyhow::Error::new(e).context("building the robot's board")))?;
    mcu.load_image(&srec).map_err(|e| {
        Failure::Input(anyhow::Error::new(e).context(format!("image `{image}`: cannot load image")))
    })?;
    Ok(mcu)
}

/// The `--vcd` file, created (empty) when asked for.
fn create_vcd(vcd: Option<&Path>) -> Result<Option<std::fs::File>, Failure> {
    match vcd {
        Some(path) => Ok(Some(std::fs::File::create(path).map_err(|e| {
            input(format!(
                "--vcd: cannot create `{}`: {e} (give a writable file path)",
                path.display()
            ))
        })?)),
        None => Ok(None),
    }
}

/// With `--gdb ADDR`, listens there and waits for a GDB client.
fn wait_for_debugger(gdb: Option<&str>) -> Result<Option<Debugger>, Failure> {
    match gdb {
        Some(addr) => {
            let listener = GdbListener::bind(addr).map_err(gdb_failure)?;
            let at = listener.local_addr();
            eprintln!(
                "h8swarm emu: GDB stub listening on {at}; waiting for a client (target remote {at})"
            );
            Ok(Some(listener.accept().map_err(gdb_failure)?))
        }
        None => Ok(None),
    }
}

/// A VCD file that cannot be written: the tool's failure.
fn vcd_failure(o: &EmuOptions<'_>, e: io::Error) -> Failure {
    Failure::Tool(anyhow::Error::new(e).context(format!(
        "writing the VCD file `{}`",
        o.vcd.map(|p| p.display().to_string()).unwrap_or_default()
    )))
}

/// Starts the pin trace into `file`: its header and the values at reset, with a phase signal
/// (and the recorder that follows it) when the image has symbols.
fn start_vcd(
    file: std::fs::File,
    cpu: &Cpu,
    mcu: &mut EmuMcu,
    names: Option<&Arc<SymbolTable>>,
    o: &EmuOptions<'_>,
) -> Result<(VcdStream<'static>, Option<PhaseRecorder>), Failure> {
    mcu.start_trace(cpu.sleeping());
    let mut phases = None;
    let mut phase_at_start = None;
    if let Some(n) = names {
        let mut p = PhaseRecorder::new(n.clone());
        p.observe(mcu.now(), cpu.pc());
        phase_at_start = p.drain_before(mcu.now() + 1).pop().map(|(_, name)| name);
        phases = Some(p);
    }
    let (start, initial) = mcu
        .trace_beginning()
        .unwrap_or((0, [false; h8_3052f::trace::SIGNAL_COUNT]));
    let stream = VcdStream::start(
        Box::new(file),
        mcu.clock_hz(),
        start,
        initial,
        phase_at_start.as_deref(),
        &VcdInfo {
            source: format!("{} on h8swarm emu", o.image),
        },
    )
    .map_err(|e| vcd_failure(o, e))?;
    Ok((stream, phases))
}

/// Writes the rest of the pin trace and the phases, and the trace's end.
fn finish_vcd(
    mut v: VcdStream<'_>,
    mcu: &mut EmuMcu,
    mut phases: Option<&mut PhaseRecorder>,
) -> io::Result<()> {
    drain_into(&mut v, mcu, phases.as_deref_mut())?;
    if let Some(rest) = mcu.finish_trace() {
        let changes = phases.map(PhaseRecorder::take).unwrap_or_default();
        v.finish(&rest.changes, &changes, rest.end)?;
    }
    Ok(())
}

/// The exit the run's outcome calls for, with its line on standard error (module docs).
fn exit(
    outcome: &Outcome,
    states: u64,
    image: &str,
    names: Option<&SymbolTable>,
) -> Result<(), Failure> {
    match *outcome {
        Outcome::Halted { exit_status: 0 } => Ok(()),
        Outcome::Halted { exit_status } => Err(Failure::Program(exit_status)),
        Outcome::MaxStates => {
            eprintln!("h8swarm emu: stopped after {states} states (--max-states)");
            Err(Failure::Program(EXIT_MAX_STATES))
        }
        Outcome::Error(ref e) => {
            eprintln!("error: image `{image}`: the core stopped: {e}");
            Err(Failure::Program(EXIT_CORE_ERROR))
        }
        Outcome::SleptForever { pc } => {
            eprintln!(
                "error: image `{image}`: SLEEP at H'{pc:06X} with interrupts enabled and nothing to wake the CPU"
            );
            Err(Failure::Program(EXIT_SLEPT_FOREVER))
        }
        Outcome::Killed => {
            eprintln!("h8swarm emu: the GDB client killed the program");
            Err(Failure::Program(EXIT_KILLED))
        }
        Outcome::Unmodelled(ref r) => {
            eprintln!(
                "error: image `{image}`: {} (--strict-io)",
                describe(r, names)
            );
            Err(Failure::Program(EXIT_CORE_ERROR))
        }
    }
}

/// A GDB stub that cannot start (an address that is not loopback `HOST:PORT`, a port that
/// cannot be bound): bad input, status 2.
fn gdb_failure(e: GdbError) -> Failure {
    Failure::Input(anyhow::Error::new(e).context("--gdb"))
}

/// Options of `h8swarm emu`.
#[derive(Args, Debug)]
pub struct EmuArgs {
    /// The program: a Motorola S-record image (.mot).
    image: String,
    /// Stop after this many states (exit status 124).
    #[arg(long, value_name = "N")]
    max_states: Option<u64>,
    /// Print every instruction, disassembled, with its address and states, on standard error.
    #[arg(long)]
    trace: bool,
    /// Print instructions, states and emulated time as JSON on standard error at the end.
    #[arg(long)]
    stats: bool,
    /// Write a pin trace of the run (PWM, H-bridge, I2C lines, A/D, tick, sleep, the function
    /// that runs) to FILE as VCD, for GTKWave or sigrok (written as the run goes).
    #[arg(long, value_name = "FILE")]
    vcd: Option<std::path::PathBuf>,
    /// Wait for a GDB client on this loopback address (127.0.0.1:PORT; port 0 picks a free
    /// one, printed on standard error) and run the program under its control.
    #[arg(long, value_name = "ADDR")]
    gdb: Option<String>,
    /// The image's symbol table (`h8300-hms-nm -n` output) for function names in --trace and
    /// --vcd and the stack guard's room (default: IMAGE.sym beside the image, if present).
    #[arg(long, value_name = "FILE")]
    symbols: Option<std::path::PathBuf>,
    /// What the stack guard does with the first stack access outside the stack's room (the
    /// end of the image's data to its stack's top, or the whole RAM without symbols): `stop`
    /// the program with an error (exit status 125), or `warn` at the end and let it run.
    #[arg(long, value_enum, value_name = "ACTION", default_value_t = GuardArg::Stop)]
    stack_guard: GuardArg,
    /// Write a profile of where the states go by call stack to FILE, as folded stacks
    /// (`caller;callee;… states`, one stack a line) for speedscope, inferno-flamegraph or
    /// flamegraph.pl; the lines add up to the run's states.
    #[arg(long, value_name = "FILE")]
    profile: Option<std::path::PathBuf>,
    /// Stop the program (exit status 125) at the first access to a register the chip does
    /// not model or to a reserved address, instead of warning about each at the end.
    #[arg(long)]
    strict_io: bool,
}

/// What the stack guard does (`--stack-guard`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum GuardArg {
    /// Stop the program at the instruction, with a one-line error.
    #[default]
    Stop,
    /// Let it run on; print the first fault as a warning.
    Warn,
}

impl From<GuardArg> for h8300h::cpu::StackGuardMode {
    fn from(g: GuardArg) -> Self {
        match g {
            GuardArg::Stop => h8300h::cpu::StackGuardMode::Stop,
            GuardArg::Warn => h8300h::cpu::StackGuardMode::Warn,
        }
    }
}

/// `h8swarm emu`: runs the image as `args` ask.
///
/// # Errors
/// As [`run`].
pub fn command(args: &EmuArgs) -> Result<(), Failure> {
    run(&EmuOptions {
        image: &args.image,
        max_states: args.max_states,
        trace: args.trace,
        stats: args.stats,
        vcd: args.vcd.as_deref(),
        gdb: args.gdb.as_deref(),
        symbols: args.symbols.as_deref(),
        stack_guard: args.stack_guard.into(),
        profile: args.profile.as_deref(),
        strict_io: args.strict_io,
    })
}
