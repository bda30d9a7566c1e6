//! A GDB remote stub for the emulated H8/3052F (the `gdbstub` crate speaks the GDB Remote Serial
//! Protocol): a GDB for `h8300-elf` (or any client of the protocol) connects over TCP and
//! reads and writes the registers and memory, sets breakpoints and watchpoints, steps and
//! continues the program.
//!
//! # What a client gets
//! - Registers as GDB's `h8300h` architecture lays them out (`gdb/h8300-tdep.c`): ER0–ER6, SP
//!   (ER7), CCR, PC, then GDB's simulator counters `cycles`, `tick` and `inst`, 13 registers of
//!   4 bytes, big-endian. Here `cycles` is the MCU clock in states and `inst` the instructions
//!   executed (both modulo 2^32, read-only); `tick` reads 0. The target description names the
//!   architecture (`h8300:h8300h`), so GDB needs no `set architecture`.
//! - Memory: the flash and the RAM, read and written without bus cycles and without time
//!   passing (a write to the flash invalidates the core's decoded instructions, as loading an
//!   image does). On-chip I/O registers are refused: reading one has effects on the chip (a
//!   flag armed for clearing, a converter caught up), which a debugger must not cause.
//! - Software and hardware breakpoints (both kept by the stub, nothing is written into the
//!   flash; any number), single steps (one instruction, or one interrupt's acceptance) and
//!   continue; Ctrl-C stops a running program.
//! - Watchpoints (write, read, access) on RAM: the program stops after the instruction whose
//!   data access touched the watched bytes.
//! - `monitor clock`: the emulated clock in states (and in seconds at the MCU's φ) and the
//!   instructions executed; `monitor help` lists the commands.
//!
//! # How it runs
//! The stub runs on a thread of its own with the connection ([`GdbStub::run_blocking`]); the
//! program runs where it always runs (`h8swarm emu`'s loop, a robot of the swarm), with a
//! [`Debugger`] that it asks before each step ([`Debugger::before_step`]) and steps through
//! ([`Debugger::step`]). While the client has the program stopped, `before_step` blocks and
//! answers the client's requests (so a swarm waits for the robot being debugged). The two
//! sides talk over channels; the program's side never waits for the network while the client
//! lets it run. A debugged program runs instruction by instruction ([`Cpu::step`]: no loop
//! fast-forwarding, which could skip over a breakpoint), so the same program gives the same
//! states whether a debugger is attached or not.
//!
//! # Limits
//! One client per stub; only loopback addresses are accepted (the stub gives full control of
//! the emulated chip to whoever connects). Watchpoints on I/O registers and breakpoint
//! conditions evaluated in the stub are not supported (GDB evaluates conditions itself).

use std::collections::BTreeSet;
use std::io;
use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::num::NonZeroUsize;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::thread::JoinHandle;
use std::time::Duration;

use gdbstub::arch::{Arch, RegId, Registers};
use gdbstub::common::Signal;
use gdbstub::outputln;
use gdbstub::stub::state_machine::GdbStubStateMachine;
use gdbstub::stub::{DisconnectReason, GdbStub, SingleThreadStopReason};
use gdbstub::target::ext::base::BaseOps;
use gdbstub::target::ext::base::singlethread::{
    SingleThreadBase, SingleThreadResume, SingleThreadResumeOps, SingleThreadSingleStep,
    SingleThreadSingleStepOps,
};
use gdbstub::target::ext::breakpoints::{
    Breakpoints, BreakpointsOps, HwBreakpoint, HwBreakpointOps, HwWatchpoint, HwWatchpointOps,
    SwBreakpoint, SwBreakpointOps, WatchKind,
};
use gdbstub::target::ext::monitor_cmd::{ConsoleOutput, MonitorCmd, MonitorCmdOps};
use gdbstub::target::{Target, TargetError, TargetResult};

use crate::mcu::Mcu;
use crate::pins::Board;
use h8300h::bus::{Bus, FastPathHints};
use h8300h::cpu::{Cpu, CpuError, Event};
use h8300h::memmap::{ADDRESS_MASK, Area};

/// GDB's register numbers for the H8/300H: ER0–ER6, SP, CCR, PC, cycles, tick, inst.
pub const GDB_REGISTERS: usize = 13;
/// Bytes per register in GDB's `h8300h` layout.
pub const GDB_REGISTER_BYTES: usize = 4;

/// The target description the stub sends: only the architecture (GDB's own `h8300h`
/// register layout applies).
const TARGET_XML: &str = r#"<?xml version="1.0"?><target version="1.0"><architecture>h8300:h8300h</architecture></target>"#;

/// The register file as GDB's `h8300h` architecture exchanges it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct H8Registers {
    /// ER0–ER7 (ER7 is SP).
    pub er: [u32; 8],
    /// CCR.
    pub ccr: u8,
    /// PC (24 bits).
    pub pc: u32,
    /// The MCU clock in states, modulo 2^32 (GDB's `cycles`; read-only).
    pub cycles: u32,
    /// GDB's `tick` (reads 0; read-only).
    pub tick: u32,
    /// Instructions executed, modulo 2^32 (GDB's `inst`; read-only).
    pub inst: u32,
}

impl Registers for H8Registers {
    type ProgramCounter = u32;

    fn pc(&self) -> u32 {
        self.pc
    }

    fn gdb_serialize(&self, mut write_byte: impl FnMut(Option<u8>)) {
        let mut words = [0u32; GDB_REGISTERS];
        words[..8].copy_from_slice(&self.er);
        words[8] = u32::from(self.ccr);
        words[9] = self.pc;
        words[10] = self.cycles;
        words[11] = self.tick;
        words[12] = self.inst;
        for w in words {
            for b in w.to_be_bytes() {
                write_byte(Some(b));
            }
        }
    }

    fn gdb_deserialize(&mut self, bytes: &[u8]) -> Result<(), ()> {
        // ER0–ER7, CCR and PC at least; the counters that may follow are read-only.
        if bytes.len() < 10 * GDB_REGISTER_BYTES || !bytes.len().is_multiple_of(GDB_REGISTER_BYTES)
        {
            return Err(());
        }
        let word = |i: usize| {
            let b = &bytes[i * 4..i * 4 + 4];
            u32::from_be_bytes([b[0], b[1], b[2], b[3]])
        };
        for n in 0..8 {
            self.er[n] = word(n);
        }
        self.ccr = word(8) as u8;
        self.pc = word(9);
        Ok(())
    }
}

/// A register number as GDB sends it (`p`/`P` packets).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct H8RegId(pub usize);

impl RegId for H8RegId {
    fn from_raw_id(id: usize) -> Option<(Self, Option<NonZeroUsize>)> {
        (id < GDB_REGISTERS).then(|| (H8RegId(id), NonZeroUsize::new(GDB_REGISTER_BYTES)))
    }
}

/// The H8/300H in advanced mode as GDB sees it (`h8300:h8300h`).
#[derive(Debug)]
pub enum H8300h {}

impl Arch for H8300h {
    type Usize = u32;
    type Registers = H8Registers;
    type BreakpointKind = usize;
    type RegId = H8RegId;

    fn target_description_xml() -> Option<&'static str> {
        Some(TARGET_XML)
    }
}

/// Why a GDB stub cannot be set up.
#[derive(Debug, thiserror::Error)]
pub enum GdbError {
    /// The address is not `HOST:PORT`.
    #[error("`{0}` is not an address and port (expected 127.0.0.1:PORT)")]
    BadAddress(String),
    /// The address is not a loopback address.
    #[error(
        "`{0}` is not a loopback address: the GDB stub gives full control of the emulated chip, so it listens on 127.0.0.1 or ::1 only"
    )]
    NotLoopback(String),
    /// Binding or accepting failed.
    #[error("cannot listen for GDB on `{addr}`")]
    Io {
        /// The address.
        addr: String,
        /// The cause.
        #[source]
        source: io::Error,
    },
}

/// A bound listening socket, waiting for one GDB client ([`GdbListener::accept`]).
#[derive(Debug)]
pub struct GdbListener {
    listener: TcpListener,
    addr: SocketAddr,
}

impl GdbListener {
    /// Binds `addr` (`127.0.0.1:PORT`, `[::1]:PORT` or `localhost:PORT`; port 0 picks a free
    /// one, see [`GdbListener::local_addr`]).
    ///
    /// # Errors
    /// [`GdbError`] for an address that is not `HOST:PORT`, not loopback, or cannot be bound.
    pub fn bind(addr: &str) -> Result<GdbListener, GdbError> {
        let addrs: Vec<SocketAddr> = addr
            .to_socket_addrs()
            .map_err(|_| GdbError::BadAddress(addr.to_string()))?
            .collect();
        let Some(first) = addrs.first().copied() else {
            return Err(GdbError::BadAddress(addr.to_string()));
        };
        if !addrs.iter().all(|a| a.ip().is_loopback()) {
            return Err(GdbError::NotLoopback(addr.to_string()));
        }
        let listener = TcpListener::bind(first).map_err(|source| GdbError::Io {
            addr: addr.to_string(),
            source,
        })?;
        let addr = listener.local_addr().map_err(|source| GdbError::Io {
            addr: addr.to_string(),
            source,
        })?;
        Ok(GdbListener { listener, addr })
    }

    /// The address the stub listens on.
    #[must_use]
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// Waits for a client and starts the stub's thread with it; the program is stopped until
    /// the client lets it run.
    ///
    /// # Errors
    /// [`GdbError::Io`] when accepting fails.
    pub fn accept(self) -> Result<Debugger, GdbError> {
        let (conn, _) = self.listener.accept().map_err(|source| GdbError::Io {
            addr: self.addr.to_string(),
            source,
        })?;
        let _ = conn.set_nodelay(true);
        Ok(Debugger::start(conn))
    }
}

/// Control bits the stub's thread sets for the program's side.
const CTL_INTERRUPT: u8 = 1;
const CTL_GONE: u8 = 2;
const CTL_KILL: u8 = 4;

/// Why the program stopped, as the program's side reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum StopKind {
    DoneStep,
    SwBreak,
    HwBreak,
    Watch(WatchKind, u32),
    Signal(Signal),
    Exited(u8),
    Terminated(Signal),
}

impl StopKind {
    fn reason(self) -> SingleThreadStopReason<u32> {
        match self {
            StopKind::DoneStep => SingleThreadStopReason::DoneStep,
            StopKind::SwBreak => SingleThreadStopReason::SwBreak(()),
            StopKind::HwBreak => SingleThreadStopReason::HwBreak(()),
            StopKind::Watch(kind, addr) => SingleThreadStopReason::Watch {
                tid: (),
                kind,
                addr,
            },
            StopKind::Signal(s) => SingleThreadStopReason::Signal(s),
            StopKind::Exited(code) => SingleThreadStopReason::Exited(code),
            StopKind::Terminated(s) => SingleThreadStopReason::Terminated(s),
        }
    }
}

/// What the stub's thread asks of the program's side.
#[derive(Debug)]
enum Request {
    ReadRegs,
    WriteRegs(H8Registers),
    ReadMem(u32, usize),
    WriteMem(u32, Vec<u8>),
    Break { add: bool, hw: bool, addr: u32 },
    Watch { add: bool, watch: Watchpoint },
    Monitor(String),
    Resume,
    Step,
}

/// What the program's side answers.
#[derive(Debug)]
enum Reply {
    Regs(H8Registers),
    Mem(Vec<u8>),
    Done(bool),
    Text(String),
    Stopped(StopKind),
}

/// A watched range of RAM.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Watchpoint {
    addr: u32,
    len: u32,
    kind: WatchKind,
}

impl Watchpoint {
    fn touches(&self, addr: u32, len: u32) -> bool {
        addr < self.addr.wrapping_add(self.len) && self.addr < addr.wrapping_add(len)
    }
}

/// The stub's side: a [`Target`] that forwards every request to the program's side.
struct RemoteTarget {
    requests: Sender<Request>,
    replies: Receiver<Reply>,
    control: Arc<AtomicU8>,
    /// A stand-in that answers every request itself and reaches no program: it runs each
    /// packet through a throwaway stub first, to learn whether the real one can take it.
    probe: bool,
}

impl RemoteTarget {
    /// A stand-in with the real target's abilities ([`RemoteTarget::probe`]).
    fn probe() -> RemoteTarget {
        let (requests, _) = mpsc::channel();
        let (_, replies) = mpsc::channel();
        RemoteTarget {
            requests,
            replies,
            control: Arc::new(AtomicU8::new(0)),
            probe: true,
        }
    }

    fn ask(&mut self, r: Request) -> Result<Reply, &'static str> {
        if self.probe {
            return Ok(match r {
                Request::ReadRegs => Reply::Regs(H8Registers::default()),
                Request::ReadMem(_, len) => Reply::Mem(vec![0; len.min(1 << 16)]),
                Request::Monitor(_) => Reply::Text(String::new()),
                _ => Reply::Done(true),
            });
        }
        self.requests
            .send(r)
            .map_err(|_| "the emulated program has ended")?;
        loop {
            match self.replies.recv() {
                // A stop report cannot come while the program is stopped; ignore a stale one.
                Ok(Reply::Stopped(_)) => {}
                Ok(reply) => return Ok(reply),
                Err(_) => return Err("the emulated program has ended"),
            }
        }
    }

    fn done(&mut self, r: Request) -> TargetResult<bool, Self> {
        match self.ask(r).map_err(TargetError::Fatal)? {
            Reply::Done(ok) => Ok(ok),
            _ => Err(TargetError::Fatal("unexpected reply")),
        }
    }
}

impl Target for RemoteTarget {
    type Arch = H8300h;
    type Error = &'static str;

    fn base_ops(&mut self) -> BaseOps<'_, H8300h, &'static str> {
        BaseOps::SingleThread(self)
    }

    fn support_breakpoints(&mut self) -> Option<BreakpointsOps<'_, Self>> {
        Some(self)
    }

    fn support_monitor_cmd(&mut self) -> Option<MonitorCmdOps<'_, Self>> {
        Some(self)
    }

    // Every packet is acknowledged (the framing in front of the stub relies on it).
    fn use_no_ack_mode(&self) -> bool {
        false
    }
}

impl SingleThreadBase for RemoteTarget {
    fn read_registers(&mut self, regs: &mut H8Registers) -> TargetResult<(), Self> {
        match self.ask(Request::ReadRegs).map_err(TargetError::Fatal)? {
            Reply::Regs(r) => {
                *regs = r;
                Ok(())
            }
            _ => Err(TargetError::Fatal("unexpected reply")),
        }
    }

    fn write_registers(&mut self, regs: &H8Registers) -> TargetResult<(), Self> {
        if self.done(Request::WriteRegs(regs.clone()))? {
            Ok(())
        } else {
            Err(TargetError::NonFatal)
        }
    }

    fn read_addrs(&mut self, start_addr: u32, data: &mut [u8]) -> TargetResult<usize, Self> {
        match self
            .ask(Request::ReadMem(start_addr, data.len()))
            .map_err(TargetError::Fatal)?
        {
            Reply::Mem(bytes) if !bytes.is_empty() || data.is_empty() => {
                data[..bytes.len()].copy_from_slice(&bytes);
                Ok(bytes.len())
            }
            Reply::Mem(_) => Err(TargetError::NonFatal),
            _ => Err(TargetError::Fatal("unexpected reply")),
        }
    }

    fn write_addrs(&mut self, start_addr: u32, data: &[u8]) -> TargetResult<(), Self> {
        if self.done(Request::WriteMem(start_addr, data.to_vec()))? {
            Ok(())
        } else {
            Err(TargetError::NonFatal)
        }
    }

    fn support_resume(&mut self) -> Option<SingleThreadResumeOps<'_, Self>> {
        Some(self)
    }
}

impl SingleThreadResume for RemoteTarget {
    fn resume(&mut self, _signal: Option<Signal>) -> Result<(), Self::Error> {
        if self.probe {
            return Ok(());
        }
        self.requests
            .send(Request::Resume)
            .map_err(|_| "the emulated program has ended")
    }

    fn support_single_step(&mut self) -> Option<SingleThreadSingleStepOps<'_, Self>> {
        Some(self)
    }
}

impl SingleThreadSingleStep for RemoteTarget {
    fn step(&mut self, _signal: Option<Signal>) -> Result<(), Self::Error> {
        if self.probe {
            return Ok(());
        }
        self.requests
            .send(Request::Step)
            .map_err(|_| "the emulated program has ended")
    }
}

impl Breakpoints for RemoteTarget {
    fn support_sw_breakpoint(&mut self) -> Option<SwBreakpointOps<'_, Self>> {
        Some(self)
    }

    fn support_hw_breakpoint(&mut self) -> Option<HwBreakpointOps<'_, Self>> {
        Some(self)
    }

    fn support_hw_watchpoint(&mut self) -> Option<HwWatchpointOps<'_, Self>> {
        Some(self)
    }
}

impl SwBreakpoint for RemoteTarget {
    fn add_sw_breakpoint(&mut self, addr: u32, _kind: usize) -> TargetResult<bool, Self> {
        self.done(Request::Break {
            add: true,
            hw: false,
            addr,
        })
    }

    fn remove_sw_breakpoint(&mut self, addr: u32, _kind: usize) -> TargetResult<bool, Self> {
        self.done(Request::Break {
            add: false,
            hw: false,
            addr,
        })
    }
}

impl HwBreakpoint for RemoteTarget {
    fn add_hw_breakpoint(&mut self, addr: u32, _kind: usize) -> TargetResult<bool, Self> {
        self.done(Request::Break {
            add: true,
            hw: true,
            addr,
        })
    }

    fn remove_hw_breakpoint(&mut self, addr: u32, _kind: usize) -> TargetResult<bool, Self> {
        self.done(Request::Break {
            add: false,
            hw: true,
            addr,
        })
    }
}

impl HwWatchpoint for RemoteTarget {
    fn add_hw_watchpoint(
        &mut self,
        addr: u32,
        len: u32,
        kind: WatchKind,
    ) -> TargetResult<bool, Self> {
        self.done(Request::Watch {
            add: true,
            watch: Watchpoint { addr, len, kind },
        })
    }

    fn remove_hw_watchpoint(
        &mut self,
        addr: u32,
        len: u32,
        kind: WatchKind,
    ) -> TargetResult<bool, Self> {
        self.done(Request::Watch {
            add: false,
            watch: Watchpoint { addr, len, kind },
        })
    }
}

impl MonitorCmd for RemoteTarget {
    fn handle_monitor_cmd(
        &mut self,
        cmd: &[u8],
        mut out: ConsoleOutput<'_>,
    ) -> Result<(), Self::Error> {
        let cmd = String::from_utf8_lossy(cmd).trim().to_string();
        match self.ask(Request::Monitor(cmd))? {
            Reply::Text(t) => {
                outputln!(out, "{t}");
                Ok(())
            }
            _ => Err("unexpected reply"),
        }
    }
}

/// The largest packet the stub takes, `$`, body, `#` and checksum included: the stub's
/// packet buffer, which it offers the client as `PacketSize` in its `qSupported` reply (a
/// client sends no larger packets).
pub const MAX_PACKET_BYTES: usize = 4096;

/// The error a packet longer than [`MAX_PACKET_BYTES`] gets (`E07`: E2BIG).
const E_TOO_LONG: &str = "E07";
/// The error a packet the stub cannot parse gets (`E16`: EINVAL, 22).
const E_MALFORMED: &str = "E16";

/// What arrived from the client, framed.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Incoming {
    /// A whole packet, `$…#xx` with a right checksum, at most [`MAX_PACKET_BYTES`].
    Packet(Vec<u8>),
    /// A packet whose checksum is wrong (or not hex): answered with `-`.
    BadChecksum,
    /// A packet with a right checksum, longer than the stub takes.
    TooLong,
    /// Ctrl-C (0x03).
    Interrupt,
    /// `-`: the client wants the last reply again.
    Nack,
}

/// Where the framer is in a packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Frame {
    /// Between packets (bytes other than `$`, 0x03, `+` and `-` are dropped).
    Idle,
    /// In a packet's body.
    Body,
    /// After `#`: the checksum's first digit comes.
    Check1,
    /// The checksum's second digit comes.
    Check2(u8),
}

/// Frames the client's bytes into packets in bounded memory: a packet's body is kept up to
/// [`MAX_PACKET_BYTES`] and only summed beyond, so an endless packet costs reading, not
/// memory; bytes are read in blocks, not one system call each.
struct Framer {
    stream: TcpStream,
    buf: Vec<u8>,
    at: usize,
    len: usize,
    frame: Frame,
    packet: Vec<u8>,
    sum: u8,
    overflow: bool,
}

impl Framer {
    fn new(stream: TcpStream) -> Framer {
        Framer {
            stream,
            buf: vec![0; 16 * 1024],
            at: 0,
            len: 0,
            frame: Frame::Idle,
            packet: Vec::with_capacity(MAX_PACKET_BYTES),
            sum: 0,
            overflow: false,
        }
    }

    /// The next thing the client sent; `None` when nothing is there and `wait` is false.
    ///
    /// # Errors
    /// The connection's errors; the end of the stream as `UnexpectedEof`.
    fn next(&mut self, wait: bool) -> io::Result<Option<Incoming>> {
        use std::io::Read;
        loop {
            while self.at < self.len {
                let b = self.buf[self.at];
                self.at += 1;
                if let Some(item) = self.take(b) {
                    return Ok(Some(item));
                }
            }
            self.stream.set_nonblocking(!wait)?;
            let n = match self.stream.read(&mut self.buf) {
                Ok(0) => {
                    return Err(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        "the client closed the connection",
                    ));
                }
                Ok(n) => n,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(None),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e),
            };
            self.at = 0;
            self.len = n;
        }
    }

    /// One byte through the framing.
    fn take(&mut self, b: u8) -> Option<Incoming> {
        match self.frame {
            Frame::Idle => match b {
                b'$' => self.start(),
                0x03 => return Some(Incoming::Interrupt),
                b'-' => return Some(Incoming::Nack),
                _ => {}
            },
            // A `$` in a body starts a new packet (the old one was cut off), as GDB does.
            Frame::Body if b == b'$' => self.start(),
            Frame::Body if b == b'#' => self.frame = Frame::Check1,
            Frame::Body => {
                self.sum = self.sum.wrapping_add(b);
                if self.packet.len() + 3 < MAX_PACKET_BYTES {
                    self.packet.push(b);
                } else {
                    self.overflow = true;
                }
            }
            Frame::Check1 => self.frame = Frame::Check2(b),
            Frame::Check2(first) => {
                self.frame = Frame::Idle;
                let hex = |c: u8| (c as char).to_digit(16);
                let given = hex(first).zip(hex(b)).map(|(h, l)| (h * 16 + l) as u8);
                return Some(if given != Some(self.sum) {
                    Incoming::BadChecksum
                } else if self.overflow {
                    Incoming::TooLong
                } else {
                    let mut p = std::mem::take(&mut self.packet);
                    p.push(b'#');
                    p.push(first);
                    p.push(b);
                    Incoming::Packet(p)
                });
            }
        }
        None
    }

    fn start(&mut self) {
        self.frame = Frame::Body;
        self.packet.clear();
        self.packet.push(b'$');
        self.sum = 0;
        self.overflow = false;
    }
}

/// `$body#xx`.
fn packet(body: &[u8]) -> Vec<u8> {
    let sum = body.iter().fold(0u8, |a, b| a.wrapping_add(*b));
    let mut p = Vec::with_capacity(body.len() + 4);
    p.push(b'$');
    p.extend_from_slice(body);
    p.extend_from_slice(format!("#{sum:02x}").as_bytes());
    p
}

/// The stub's side of the connection: replies are sent whole when the stub flushes, and the
/// last one is kept to send again when the client answers it with `-`.
struct Wire {
    stream: TcpStream,
    pending: Vec<u8>,
    /// The last packet sent (by the stub or by the framing), shared by both writers.
    last: std::rc::Rc<std::cell::RefCell<Vec<u8>>>,
}

impl gdbstub::conn::Connection for Wire {
    type Error = io::Error;

    fn write(&mut self, byte: u8) -> io::Result<()> {
        self.pending.push(byte);
        Ok(())
    }

    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.pending.extend_from_slice(buf);
        Ok(())
    }

    fn flush(&mut self) -> io::Result<()> {
        if self.pending.is_empty() {
            return Ok(());
        }
        self.stream.set_nonblocking(false)?;
        io::Write::write_all(&mut self.stream, &self.pending)?;
        if let Some(at) = self.pending.iter().position(|&b| b == b'$') {
            *self.last.borrow_mut() = self.pending[at..].to_vec();
        }
        self.pending.clear();
        Ok(())
    }
}

impl Wire {
    /// Acknowledges a packet and answers it with `body` (what the stub does for one it takes).
    fn answer(&mut self, body: &str) -> io::Result<()> {
        use gdbstub::conn::Connection;
        self.write(b'+')?;
        self.write_all(&packet(body.as_bytes()))?;
        self.flush()
    }

    fn send_raw(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.stream.set_nonblocking(false)?;
        io::Write::write_all(&mut self.stream, bytes)
    }
}

/// A sink for the throwaway stubs' replies.
struct NullConn;

impl gdbstub::conn::Connection for NullConn {
    type Error = ();

    fn write(&mut self, _: u8) -> Result<(), ()> {
        Ok(())
    }

    fn flush(&mut self) -> Result<(), ()> {
        Ok(())
    }
}

/// Whether the stub can take `p` (a whole packet with a right checksum): it is run through a
/// throwaway stub whose target answers everything itself. A packet the stub cannot parse
/// would end the real session, so it is answered with an error instead.
fn stub_takes(p: &[u8]) -> bool {
    let mut target = RemoteTarget::probe();
    let Ok(stub) = GdbStub::<RemoteTarget, NullConn>::builder(NullConn)
        .packet_buffer_size(MAX_PACKET_BYTES)
        .build()
    else {
        return false;
    };
    let Ok(mut sm) = stub.run_state_machine(&mut target) else {
        return false;
    };
    for &b in p {
        sm = match sm {
            GdbStubStateMachine::Idle(g) => match g.incoming_data(&mut target, b) {
                Ok(next) => next,
                Err(_) => return false,
            },
            // The packet ended (a resume, a kill, a detach): it was taken.
            _ => return true,
        };
    }
    true
}

/// A bare `qSupported` (the client lists no features, which the protocol allows) as the
/// stub parses it: the same request with the one feature it knows declined.
fn normalised(p: Vec<u8>) -> Vec<u8> {
    if p.starts_with(b"$qSupported#") {
        packet(b"qSupported:multiprocess-")
    } else {
        p
    }
}

/// How a session ended.
#[derive(Debug)]
enum SessionEnd {
    /// The client detached, killed the program, or the program ended.
    Ended(DisconnectReason),
    /// The connection failed or closed without a detach.
    Lost(String),
}

/// The three ends of a session's connection `conn`: the framer reading the client's bytes,
/// the framing's own writer (acknowledgements and error answers), and the stub's writer; the
/// two writers share the last packet sent.
fn ends_of(conn: TcpStream) -> io::Result<(Framer, Wire, Wire)> {
    let framer = Framer::new(conn.try_clone()?);
    let last = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    let wire_out = Wire {
        stream: conn.try_clone()?,
        pending: Vec::new(),
        last: std::rc::Rc::clone(&last),
    };
    let wire = Wire {
        stream: conn,
        pending: Vec::new(),
        last: std::rc::Rc::clone(&last),
    };
    Ok((framer, wire_out, wire))
}

/// The bytes of `incoming` for the stub's state machine, or `None` when the framing has
/// answered it itself on `wire_out`: a packet the stub cannot take (an error), a bad checksum
/// (`-`), a packet too long (an error), a `-` from the client (the last packet again).
fn for_stub(incoming: Incoming, wire_out: &mut Wire) -> io::Result<Option<Vec<u8>>> {
    match incoming {
        Incoming::Packet(p) => {
            let p = normalised(p);
            if stub_takes(&p) {
                return Ok(Some(p));
            }
            wire_out.answer(E_MALFORMED)?;
        }
        Incoming::Interrupt => return Ok(Some(vec![0x03])),
        Incoming::BadChecksum => wire_out.send_raw(b"-")?,
        Incoming::TooLong => wire_out.answer(E_TOO_LONG)?,
        Incoming::Nack => {
            let again = wire_out.last.borrow().clone();
            if !again.is_empty() {
                wire_out.send_raw(&again)?;
            }
        }
    }
    Ok(None)
}

/// Runs the stub on `conn` until the session ends: packets are framed here (bounded, bad
/// checksums answered with `-`, packets the stub cannot take answered with an error) and fed
/// to `gdbstub`'s state machine; while the program runs, its stop reports and the client's
/// bytes are watched in turn.
fn serve(conn: TcpStream, target: &mut RemoteTarget) -> SessionEnd {
    use gdbstub::stub::state_machine::GdbStubStateMachine as Sm;
    let lost = |e: &dyn std::fmt::Display| SessionEnd::Lost(e.to_string());
    let (mut framer, mut wire_out, wire) = match ends_of(conn) {
        Ok(ends) => ends,
        Err(e) => return lost(&e),
    };
    let stub = match GdbStub::<RemoteTarget, Wire>::builder(wire)
        .packet_buffer_size(MAX_PACKET_BYTES)
        .build()
    {
        Ok(s) => s,
        Err(e) => return lost(&e),
    };
    let mut sm = match stub.run_state_machine(target) {
        Ok(sm) => sm,
        Err(e) => return lost(&e),
    };
    loop {
        let incoming = match sm {
            Sm::Disconnected(mut g) => {
                // What the stub wrote last and did not flush (the acknowledgement of a kill).
                let _ = gdbstub::conn::Connection::flush(g.borrow_conn());
                return SessionEnd::Ended(g.get_reason());
            }
            Sm::CtrlCInterrupt(g) => {
                // The program's side stops at its next step and reports SIGINT.
                target.control.fetch_or(CTL_INTERRUPT, Ordering::SeqCst);
                sm = match g.interrupt_handled(target, None::<SingleThreadStopReason<u32>>) {
                    Ok(next) => next,
                    Err(e) => return lost(&e),
                };
                continue;
            }
            Sm::Idle(g) => {
                sm = Sm::Idle(g);
                match framer.next(true) {
                    Ok(Some(i)) => i,
                    Ok(None) => continue,
                    Err(e) => return lost(&e),
                }
            }
            Sm::Running(g) => {
                match target.replies.recv_timeout(Duration::from_millis(5)) {
                    Ok(Reply::Stopped(kind)) => {
                        sm = match g.report_stop(target, kind.reason()) {
                            Ok(next) => next,
                            Err(e) => return lost(&e),
                        };
                        continue;
                    }
                    Ok(_) | Err(RecvTimeoutError::Timeout) => {}
                    Err(RecvTimeoutError::Disconnected) => {
                        let reason = SingleThreadStopReason::Terminated(Signal::SIGKILL);
                        sm = match g.report_stop(target, reason) {
                            Ok(next) => next,
                            Err(e) => return lost(&e),
                        };
                        continue;
                    }
                }
                sm = Sm::Running(g);
                match framer.next(false) {
                    Ok(Some(i)) => i,
                    Ok(None) => continue,
                    Err(e) => return lost(&e),
                }
            }
        };
        let bytes = match for_stub(incoming, &mut wire_out) {
            Ok(Some(bytes)) => bytes,
            Ok(None) => continue,
            Err(e) => return lost(&e),
        };
        for b in bytes {
            let next = match sm {
                Sm::Idle(g) => g.incoming_data(target, b),
                Sm::Running(g) => g.incoming_data(target, b),
                other => Ok(other),
            };
            sm = match next {
                Ok(next) => next,
                // Not reached for a packet the probe took; the session cannot go on.
                Err(e) => return SessionEnd::Lost(format!("a protocol error: {e}")),
            };
        }
    }
}
/// How the program's side runs between stops.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RunMode {
    /// Stopped: requests are answered.
    Stopped,
    /// Running until a breakpoint, a watchpoint, Ctrl-C or the end.
    Continue,
    /// One step, then stop (`true` once the step ran).
    Step(bool),
}

/// What the program's loop does after [`Debugger::before_step`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DebugAction {
    /// Run the next step.
    Run,
    /// The client went away (detached or disconnected): run on without the debugger.
    Detached,
    /// The client killed the program: end the run.
    Kill,
}

/// The program's side of a GDB session: breakpoints, watchpoints and the run mode; it answers
/// the client's requests while the program is stopped.
#[derive(Debug)]
pub struct Debugger {
    replies: Sender<Reply>,
    requests: Receiver<Request>,
    control: Arc<AtomicU8>,
    sw_breaks: BTreeSet<u32>,
    hw_breaks: BTreeSet<u32>,
    watches: Vec<Watchpoint>,
    mode: RunMode,
    /// A breakpoint at this PC is passed once (the client resumed from it).
    pass_break_at: Option<u32>,
    /// A watchpoint hit by the last step, to report before the next.
    watch_hit: Option<StopKind>,
    gone: bool,
    thread: Option<JoinHandle<()>>,
}

impl Debugger {
    /// Starts the stub's thread on a connected client.
    fn start(conn: TcpStream) -> Debugger {
        let (req_tx, req_rx) = mpsc::channel();
        let (rep_tx, rep_rx) = mpsc::channel();
        let control = Arc::new(AtomicU8::new(0));
        let mut target = RemoteTarget {
            requests: req_tx,
            replies: rep_rx,
            control: Arc::clone(&control),
            probe: false,
        };
        let peer = conn
            .peer_addr()
            .map_or_else(|_| "the client".to_string(), |a| a.to_string());
        let thread = std::thread::spawn(move || {
            let end = serve(conn, &mut target);
            let kill = matches!(end, SessionEnd::Ended(DisconnectReason::Kill));
            if let SessionEnd::Lost(why) = &end {
                // Said where the user sees it: the program goes on without the debugger.
                eprintln!(
                    "GDB stub: the debugger at {peer} is lost ({why}) without detaching; the program runs on without it"
                );
            }
            target.control.fetch_or(
                if kill { CTL_KILL | CTL_GONE } else { CTL_GONE },
                Ordering::SeqCst,
            );
            // Dropping the target closes the request channel: a program waiting for a
            // request sees the client gone.
        });
        Debugger {
            replies: rep_tx,
            requests: req_rx,
            control,
            sw_breaks: BTreeSet::new(),
            hw_breaks: BTreeSet::new(),
            watches: Vec::new(),
            mode: RunMode::Stopped,
            pass_break_at: None,
            watch_hit: None,
            gone: false,
            thread: Some(thread),
        }
    }

    /// Whether the client is gone (detached, disconnected or killed).
    #[must_use]
    pub fn is_gone(&self) -> bool {
        self.gone
    }

    /// Call before every step of the program (an instruction, an interrupt's acceptance, a
    /// sleep): stops the program where the client wants it stopped (a breakpoint at PC, the
    /// end of a single step, a watchpoint hit by the last step, Ctrl-C) and then answers the
    /// client's requests until it resumes. Blocks while the program is stopped.
    pub fn before_step<B: Board>(&mut self, cpu: &mut Cpu, mcu: &mut Mcu<B>) -> DebugAction {
        if self.gone {
            return DebugAction::Detached;
        }
        let control = self.control.load(Ordering::SeqCst);
        if control & CTL_GONE != 0 {
            return self.client_gone();
        }
        let stop = match self.mode {
            RunMode::Stopped => None,
            RunMode::Step(true) => Some(self.watch_hit.take().unwrap_or(StopKind::DoneStep)),
            RunMode::Step(false) => None,
            RunMode::Continue => {
                let pc = cpu.pc();
                let passing = self.pass_break_at.take() == Some(pc);
                if control & CTL_INTERRUPT != 0 {
                    self.control.fetch_and(!CTL_INTERRUPT, Ordering::SeqCst);
                    Some(StopKind::Signal(Signal::SIGINT))
                } else if let Some(hit) = self.watch_hit.take() {
                    Some(hit)
                } else if !passing && self.sw_breaks.contains(&pc) {
                    Some(StopKind::SwBreak)
                } else if !passing && self.hw_breaks.contains(&pc) {
                    Some(StopKind::HwBreak)
                } else {
                    None
                }
            }
        };
        if let Some(kind) = stop {
            self.mode = RunMode::Stopped;
            if self.replies.send(Reply::Stopped(kind)).is_err() {
                return self.client_gone();
            }
        }
        if self.mode == RunMode::Stopped {
            return self.serve(cpu, mcu);
        }
        DebugAction::Run
    }

    /// Runs one step of `cpu` ([`Cpu::step`]), watching the data accesses when watchpoints are
    /// set.
    ///
    /// # Errors
    /// The core's error.
    pub fn step<B: Board>(
        &mut self,
        cpu: &mut Cpu,
        mcu: &mut Mcu<B>,
        deadline: u64,
    ) -> Result<Event, CpuError> {
        let event = if self.watches.is_empty() || self.gone {
            cpu.step(mcu, deadline)
        } else {
            let mut bus = WatchBus {
                bus: mcu,
                watches: &self.watches,
                hit: None,
            };
            let e = cpu.step(&mut bus, deadline);
            if let Some((kind, addr)) = bus.hit {
                self.watch_hit = Some(StopKind::Watch(kind, addr));
            }
            e
        };
        if let RunMode::Step(done) = &mut self.mode {
            *done = true;
        }
        event
    }

    /// Reports that the program stopped on a core error (SIGILL: an undefined opcode, a fetch
    /// outside ROM and RAM) and lets the client look at it; returns when the client resumes
    /// (the run then ends) or goes.
    pub fn report_error<B: Board>(&mut self, cpu: &mut Cpu, mcu: &mut Mcu<B>) -> DebugAction {
        if self.gone || self.control.load(Ordering::SeqCst) & CTL_GONE != 0 {
            return DebugAction::Detached;
        }
        self.mode = RunMode::Stopped;
        if self
            .replies
            .send(Reply::Stopped(StopKind::Signal(Signal::SIGILL)))
            .is_err()
        {
            return self.client_gone();
        }
        self.serve(cpu, mcu)
    }

    /// The program ended: tells a client that still follows it (`Some(status)`: exited with
    /// that status, `None`: terminated) and waits up to `linger` for the client to close the
    /// session.
    pub fn finish(&mut self, exit_status: Option<u8>, linger: Duration) {
        if !self.gone && self.control.load(Ordering::SeqCst) & CTL_GONE == 0 {
            let kind = match exit_status {
                Some(code) => StopKind::Exited(code),
                None => StopKind::Terminated(Signal::SIGTERM),
            };
            let _ = self.replies.send(Reply::Stopped(kind));
        }
        self.gone = true;
        let Some(thread) = self.thread.take() else {
            return;
        };
        let deadline = std::time::Instant::now() + linger;
        while !thread.is_finished() && std::time::Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(5));
        }
        if thread.is_finished() {
            let _ = thread.join();
        }
    }

    fn client_gone(&mut self) -> DebugAction {
        self.gone = true;
        self.mode = RunMode::Continue;
        if self.control.load(Ordering::SeqCst) & CTL_KILL != 0 {
            DebugAction::Kill
        } else {
            DebugAction::Detached
        }
    }

    /// Answers requests until the client resumes or goes.
    fn serve<B: Board>(&mut self, cpu: &mut Cpu, mcu: &mut Mcu<B>) -> DebugAction {
        loop {
            let Ok(request) = self.requests.recv() else {
                return self.client_gone();
            };
            let reply = match request {
                Request::ReadRegs => Reply::Regs(registers(cpu, mcu)),
                Request::WriteRegs(r) => {
                    for (n, v) in r.er.iter().enumerate() {
                        cpu.set_er(n, *v);
                    }
                    cpu.set_ccr(r.ccr);
                    cpu.set_pc(r.pc);
                    Reply::Done(true)
                }
                Request::ReadMem(addr, len) => Reply::Mem(read_memory(mcu, addr, len)),
                Request::WriteMem(addr, data) => Reply::Done(write_memory(mcu, addr, &data)),
                Request::Break { add, hw, addr } => {
                    let set = if hw {
                        &mut self.hw_breaks
                    } else {
                        &mut self.sw_breaks
                    };
                    let addr = addr & ADDRESS_MASK;
                    if add {
                        set.insert(addr);
                    } else {
                        set.remove(&addr);
                    }
                    Reply::Done(true)
                }
                Request::Watch { add, watch } => {
                    let watch = Watchpoint {
                        addr: watch.addr & ADDRESS_MASK,
                        ..watch
                    };
                    let in_ram = watch.len > 0
                        && Area::of(watch.addr) == Area::Ram
                        && Area::of(watch.addr.wrapping_add(watch.len - 1) & ADDRESS_MASK)
                            == Area::Ram;
                    if add {
                        if in_ram {
                            self.watches.push(watch);
                        }
                        Reply::Done(in_ram)
                    } else {
                        let before = self.watches.len();
                        self.watches.retain(|w| *w != watch);
                        Reply::Done(self.watches.len() != before)
                    }
                }
                Request::Monitor(cmd) => Reply::Text(monitor(&cmd, cpu, mcu)),
                Request::Resume => {
                    self.mode = RunMode::Continue;
                    self.pass_break_at = Some(cpu.pc());
                    return DebugAction::Run;
                }
                Request::Step => {
                    self.mode = RunMode::Step(false);
                    return DebugAction::Run;
                }
            };
            if self.replies.send(reply).is_err() {
                return self.client_gone();
            }
        }
    }
}

/// The registers as GDB's `h8300h` lays them out.
fn registers<B: Board>(cpu: &Cpu, mcu: &Mcu<B>) -> H8Registers {
    H8Registers {
        er: cpu.regs(),
        ccr: cpu.ccr(),
        pc: cpu.pc(),
        cycles: mcu.now() as u32,
        tick: 0,
        inst: cpu.instructions() as u32,
    }
}

/// Bytes of flash and RAM from `addr`, up to the first byte elsewhere.
fn read_memory<B: Board>(mcu: &Mcu<B>, addr: u32, len: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(len.min(1 << 16));
    for i in 0..len as u32 {
        let a = addr.wrapping_add(i) & ADDRESS_MASK;
        match Area::of(a) {
            Area::Rom | Area::Ram => out.push(mcu.peek(a)),
            _ => break,
        }
    }
    out
}

/// Writes bytes into flash and RAM; refuses (writing nothing) when any lies elsewhere.
fn write_memory<B: Board>(mcu: &mut Mcu<B>, addr: u32, data: &[u8]) -> bool {
    let ok = (0..data.len() as u32).all(|i| {
        matches!(
            Area::of(addr.wrapping_add(i) & ADDRESS_MASK),
            Area::Rom | Area::Ram
        )
    });
    if ok {
        mcu.poke(addr, data);
    }
    ok
}

/// The `monitor` commands.
fn monitor<B: Board>(cmd: &str, cpu: &Cpu, mcu: &Mcu<B>) -> String {
    match cmd {
        "clock" | "states" => {
            let states = mcu.now();
            let hz = mcu.clock_hz();
            format!(
                "clock: {states} states ({:.9} s at phi = {hz} Hz, {} ns a state); {} instructions executed",
                states as f64 / f64::from(hz),
                1e9 / f64::from(hz),
                cpu.instructions()
            )
        }
        "" | "help" => "monitor commands: clock (the emulated clock in states and seconds, and the instructions executed), help".to_string(),
        other => format!("unknown monitor command `{other}`; try `monitor help`"),
    }
}

/// A bus that notes data accesses touching a watchpoint (the program's side of watchpoints).
struct WatchBus<'a, B: FastPathHints> {
    bus: &'a mut B,
    watches: &'a [Watchpoint],
    hit: Option<(WatchKind, u32)>,
}

impl<B: FastPathHints> WatchBus<'_, B> {
    #[inline]
    fn note(&mut self, addr: u32, len: u32, write: bool) {
        if self.hit.is_some() {
            return;
        }
        let addr = addr & ADDRESS_MASK;
        for w in self.watches {
            let wants = match w.kind {
                WatchKind::Write => write,
                WatchKind::Read => !write,
                WatchKind::ReadWrite => true,
            };
            if wants && w.touches(addr, len) {
                self.hit = Some((w.kind, w.addr));
                return;
            }
        }
    }
}

impl<B: FastPathHints> Bus for WatchBus<'_, B> {
    h8300h::forward_bus_timing!(bus);
    fn read8(&mut self, addr: u32) -> u8 {
        self.note(addr, 1, false);
        self.bus.read8(addr)
    }
    fn read16(&mut self, addr: u32) -> u16 {
        self.note(addr & !1, 2, false);
        self.bus.read16(addr)
    }
    fn write8(&mut self, addr: u32, value: u8) {
        self.note(addr, 1, true);
        self.bus.write8(addr, value);
    }
    fn write16(&mut self, addr: u32, value: u16) {
        self.note(addr & !1, 2, true);
        self.bus.write16(addr, value);
    }
}

impl<B: FastPathHints> FastPathHints for WatchBus<'_, B> {
    h8300h::forward_fast_path_hints!(bus);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registers_serialise_as_gdb_h8300h_lays_them_out() {
        let r = H8Registers {
            er: [1, 2, 3, 4, 5, 6, 7, 0x00FF_FF00],
            ccr: 0x84,
            pc: 0x0012_3456,
            cycles: 0xDEAD_BEEF,
            tick: 0,
            inst: 9,
        };
        let mut bytes = Vec::new();
        r.gdb_serialize(|b| bytes.push(b.unwrap_or(0)));
        assert_eq!(bytes.len(), GDB_REGISTERS * GDB_REGISTER_BYTES);
        assert_eq!(&bytes[0..4], &[0, 0, 0, 1]);
        assert_eq!(&bytes[28..32], &[0, 0xFF, 0xFF, 0]);
        assert_eq!(&bytes[32..36], &[0, 0, 0, 0x84]);
        assert_eq!(&bytes[36..40], &[0, 0x12, 0x34, 0x56]);
        assert_eq!(&bytes[40..44], &[0xDE, 0xAD, 0xBE, 0xEF]);
        let mut back = H8Registers::default();
        back.gdb_deserialize(&bytes).unwrap();
        assert_eq!(back.er, r.er);
        assert_eq!((back.ccr, back.pc), (r.ccr, r.pc));
        // Counters are read-only: a write leaves them alone.
        assert_eq!(back.cycles, 0);
        assert!(back.gdb_deserialize(&bytes[..39]).is_err());
    }

    #[test]
    fn only_loopback_addresses_are_accepted() {
        assert!(matches!(
            GdbListener::bind("0.0.0.0:0"),
            Err(GdbError::NotLoopback(_))
        ));
        assert!(matches!(
            GdbListener::bind("no-port"),
            Err(GdbError::BadAddress(_))
        ));
        let l = GdbListener::bind("127.0.0.1:0").unwrap();
        assert!(l.local_addr().ip().is_loopback());
        assert_ne!(l.local_addr().port(), 0);
    }

    #[test]
    fn watchpoints_overlap_ranges() {
        let w = Watchpoint {
            addr: 0xFF_E000,
            len: 4,
            kind: WatchKind::Write,
        };
        assert!(w.touches(0xFF_E003, 1));
        assert!(w.touches(0xFF_DFFF, 2));
        assert!(!w.touches(0xFF_E004, 2));
        assert!(!w.touches(0xFF_DFFE, 2));
    }
}
