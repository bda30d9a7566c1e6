//! The core's fast path ([`Cpu::step`]) against its reference path ([`Cpu::step_reference`]):
//! two identical machines run the same code in lockstep, one on each path, and after every
//! step the complete state must be equal: the step's event (or error), ER0–ER7, CCR, PC,
//! the clock, the instruction count, the instruction executed last, the run state, every
//! write (address, value, instant) and every read of I/O or unmapped addresses with the
//! instant it happened. The RAM changes only by those writes, so it is equal after every step
//! too; all 8 KB are also compared every 64 steps and at the end.
//!
//! The programs: random instruction sequences from the decoder's valid encodings with loops,
//! calls (BSR, JSR @aa:24, JSR @ERn, a subroutine in RAM), conditional branches, EEPMOV, an
//! interrupt handler and random I/O through random pointers; every C program of
//! `tests/programs`; and the robot firmware (`firmware/robot.mot`) for a few simulated
//! seconds on an MCU with nothing connected (its tick interrupt, the A/D converter, bit-banged
//! I²C to the EEPROMs). Also: the decode caches follow every write to the flash.

use h8_3052f::machine::Machine;
use h8_3052f::mcu::{Mcu, McuConfig};
use h8_3052f::pins::{Board, NullBoard};
use h8300h::bus::{Bus, FastPathHints};
use h8300h::cpu::decode::{Decoded, Instr, decode_bytes};
use h8300h::cpu::disasm::format_instr;
use h8300h::cpu::{Cpu, CpuError, Event};
use h8300h::memmap::{Area, RAM_BYTES, RAM_START};
use h8300h::srec;
use proptest::prelude::*;
use proptest::strategy::ValueTree;
use robot_board::firmware::{ConfigBlock, Firmware};

/// A bus access some device or memory could see: writes anywhere, reads of I/O and unmapped
/// addresses (reads of ROM and RAM have no effect but the clock; instruction fetches, which
/// the two paths charge differently, are among them), and sleeps. Each with the clock after it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Access {
    Read8(u32, u8, u64),
    Read16(u32, u16, u64),
    Write8(u32, u8, u64),
    Write16(u32, u16, u64),
    Sleep(u64, bool, u64),
}

/// A bus in front of another that logs [`Access`]es and passes the inner bus's promise
/// ([`FastPathHints::code_generation`]) on: it adds no effect to ROM or RAM reads.
struct Logged<'a, M: Bus> {
    bus: &'a mut M,
    log: Vec<Access>,
}

fn logged_read(a: u32) -> bool {
    !matches!(Area::of(a), Area::Rom | Area::Ram)
}

impl<M: Bus> Bus for Logged<'_, M> {
    fn now(&self) -> u64 {
        self.bus.now()
    }
    fn read8(&mut self, addr: u32) -> u8 {
        let v = self.bus.read8(addr);
        if logged_read(addr) {
            self.log.push(Access::Read8(addr, v, self.bus.now()));
        }
        v
    }
    fn read16(&mut self, addr: u32) -> u16 {
        let v = self.bus.read16(addr);
        if logged_read(addr) {
            self.log.push(Access::Read16(addr, v, self.bus.now()));
        }
        v
    }
    fn write8(&mut self, addr: u32, value: u8) {
        self.bus.write8(addr, value);
        self.log.push(Access::Write8(addr, value, self.bus.now()));
    }
    fn write16(&mut self, addr: u32, value: u16) {
        self.bus.write16(addr, value);
        self.log.push(Access::Write16(addr, value, self.bus.now()));
    }
    fn internal(&mut self, states: u32) {
        self.bus.internal(states);
    }
    fn pending_irq(&self) -> Option<u8> {
        self.bus.pending_irq()
    }
    fn sleep_until_irq(&mut self, deadline: u64) -> bool {
        let r = self.bus.sleep_until_irq(deadline);
        self.log.push(Access::Sleep(deadline, r, self.bus.now()));
        r
    }
}

impl<M: FastPathHints> FastPathHints for Logged<'_, M> {
    fn code_generation(&self) -> Option<u64> {
        self.bus.code_generation()
    }
}

/// Everything of a CPU and its clock that a step can change (RAM apart).
#[derive(Debug, PartialEq, Eq)]
struct Snapshot {
    regs: [u32; 8],
    pc: u32,
    ccr: u8,
    now: u64,
    instructions: u64,
    last: Decoded,
    halted: bool,
    sleeping: bool,
}

fn snapshot(cpu: &Cpu, now: u64) -> Snapshot {
    Snapshot {
        regs: cpu.regs(),
        pc: cpu.pc(),
        ccr: cpu.ccr(),
        now,
        instructions: cpu.instructions(),
        last: cpu.last_executed(),
        halted: cpu.halted(),
        sleeping: cpu.sleeping(),
    }
}

fn ram_differs<B: Board>(a: &Mcu<B>, b: &Mcu<B>) -> Option<u32> {
    (RAM_START..RAM_START + RAM_BYTES).find(|&x| a.peek(x) != b.peek(x))
}

/// What a lockstep run saw.
#[derive(Debug, Default)]
struct Tally {
    steps: u64,
    instructions: u64,
    interrupts: u64,
    accesses: u64,
    /// Writes to I/O registers, by address.
    io_writes: std::collections::BTreeMap<u32, u64>,
    end: Option<Result<Event, CpuError>>,
}

/// Runs `fast` (on [`Cpu::step`]) and `reference` (on [`Cpu::step_reference`]) in lockstep
/// on their own MCUs for at most `max_steps` steps or until the clock reaches `until`, the
/// run halts or stops with an error. Returns a description of the first difference, if any.
fn lockstep<B: Board>(
    fast: (&mut Cpu, &mut Mcu<B>),
    reference: (&mut Cpu, &mut Mcu<B>),
    max_steps: u64,
    until: u64,
) -> Result<Tally, String> {
    let (ca, ma) = fast;
    let (cb, mb) = reference;
    assert!(ca.fast_path(), "the first CPU takes the fast path");
    let mut tally = Tally::default();
    let mut la = Logged {
        bus: ma,
        log: Vec::new(),
    };
    let mut lb = Logged {
        bus: mb,
        log: Vec::new(),
    };
    let i0 = ca.instructions();
    while tally.steps < max_steps && la.now() < until {
        let pc = ca.pc();
        let ea = ca.step(&mut la, until);
        let eb = cb.step_reference(&mut lb, until);
        tally.steps += 1;
        let at = || format!("step {} at PC H'{pc:06X}", tally.steps);
        if ea != eb {
            return Err(format!("{}: events {ea:?} vs {eb:?}", at()));
        }
        if la.log != lb.log {
            return Err(format!("{}: accesses {:?} vs {:?}", at(), la.log, lb.log));
        }
        tally.accesses += la.log.len() as u64;
        for a in &la.log {
            if let Access::Write8(x, ..) | Access::Write16(x, ..) = *a
                && Area::of(x) == Area::Io
            {
                *tally.io_writes.entry(x).or_default() += 1;
            }
        }
        la.log.clear();
        lb.log.clear();
        let (sa, sb) = (snapshot(ca, la.now()), snapshot(cb, lb.now()));
        if sa != sb {
            return Err(format!("{}: state {sa:?} vs {sb:?}", at()));
        }
        if tally.steps % 64 == 0
            && let Some(x) = ram_differs(la.bus, lb.bus)
        {
            return Err(format!("{}: RAM differs at H'{x:06X}", at()));
        }
        match ea {
            Ok(Event::Interrupt(_)) => tally.interrupts += 1,
            Ok(Event::Executed | Event::Reset | Event::Break) => {}
            Ok(Event::Halted) | Err(_) => {
                tally.end = Some(ea);
                break;
            }
            Ok(Event::Asleep) => {
                if la.now() >= until {
                    tally.end = Some(ea);
                    break;
                }
            }
        }
    }
    if let Some(x) = ram_differs(la.bus, lb.bus) {
        return Err(format!("at the end: RAM differs at H'{x:06X}"));
    }
    tally.instructions = ca.instructions() - i0;
    Ok(tally)
}

// ----- random programs ---------------------------------------------------------------------

/// Where the pieces of a random program go.
const START: u32 = 0x100;
const HANDLER: u32 = 0x2000;
const SUBS: u32 = 0x3000;
const SUB_SPACING: u32 = 0x100;
const RAM_SUB: u32 = 0xFF_E000;
const STACK_TOP: u32 = 0xFF_FF00;

/// Register tokens a random instruction may not name: ER6 counts the program's loops and ER7
/// is the stack pointer.
const RESERVED: [&str; 10] = [
    "er6", "r6", "e6", "r6h", "r6l", "er7", "r7", "e7", "r7h", "r7l",
];

/// A random instruction from the decoder's encodings fit for straight-line code: no control
/// transfer, no SLEEP, no EEPMOV (the program has its own), no MOVFPE/MOVTPE (they stop the
/// run), and no ER6/ER7.
fn straight(bytes: &[u8; 10]) -> Option<Vec<u8>> {
    let d = decode_bytes(bytes).ok()?;
    match d.instr {
        Instr::Bcc { .. }
        | Instr::Bsr { .. }
        | Instr::Jmp(_)
        | Instr::Jsr(_)
        | Instr::Rts
        | Instr::Rte
        | Instr::Trapa(_)
        | Instr::Sleep
        | Instr::Eepmov { .. }
        | Instr::Movfpe { .. }
        | Instr::Movtpe { .. } => return None,
        _ => {}
    }
    let text = format_instr(d, 0x1000);
    if text
        .split(|c: char| !c.is_ascii_alphanumeric())
        .any(|t| RESERVED.contains(&t))
    {
        return None;
    }
    Some(bytes[..d.len_bytes() as usize].to_vec())
}

/// One piece of a random program's main loop.
#[derive(Clone, Debug)]
enum Piece {
    /// Straight-line instructions.
    Straight(Vec<[u8; 10]>),
    /// `mov.w #n,r6; body; dec.w #1,r6; bne body`.
    Loop(u8, Vec<[u8; 10]>),
    /// A conditional branch (condition 0–15) over the instructions that follow it.
    Skip(u8, Vec<[u8; 10]>),
    /// BSR to subroutine n (d:8 when it reaches, else d:16).
    Bsr(usize),
    /// JSR @aa:24 to subroutine n.
    JsrAbs(usize),
    /// `mov.l #sub,er6; jsr @er6`.
    JsrReg(usize),
    /// JSR to the subroutine in RAM.
    JsrRam,
    /// `mov.l #a,er5; mov.l #b,er6; mov.b #n,r4l; eepmov.b`.
    Eepmov(u16, u16, u8),
    /// `ldc #ccr,ccr` (may unmask interrupts).
    Ldc(u8),
    /// ITU0 counting φ/8 with a compare-match A interrupt every GRA + 1 counts, and
    /// interrupts unmasked.
    StartTimer(u16),
    /// `sleep`: halts with interrupts masked, else waits for the next interrupt.
    Sleep,
    /// A delay loop for the core's fast-forwarding: `mov #init,rd; 1: op rd; bne 1b` with op
    /// (by `kind` modulo 5) ADD #amount, SUB #amount (word, long), INC, DEC (by 1 or 2),
    /// on a byte, word or long register other than the stack pointer.
    Countdown {
        size: u8,
        kind: u8,
        rd: u8,
        init: u32,
        amount: u32,
    },
    /// A poll loop on RAM: `mov.b @TOGGLE:8,r1l; 1: mov.b @TOGGLE:8,r0l; cmp.b r0l,r1l; beq 1b`
    /// (the interrupt handler toggles TOGGLE's bit 0).
    PollRam,
    /// A poll loop on the A/D converter: start channel `ch` (single mode), then
    /// `1: mov.b @ADCSR:8,r0l; bpl 1b` until ADF.
    PollAdc(u8),
    /// `1: bra 1b`: spins until an interrupt (for ever with interrupts masked).
    Spin,
}

/// The RAM byte whose bit 0 the interrupt handler toggles (above the stack).
const TOGGLE: u32 = 0xFF_FF08;

/// A small assembler for the pieces (each encoding is checked against the decoder).
struct Asm {
    at: u32,
    code: Vec<u8>,
}

impl Asm {
    fn new(at: u32) -> Asm {
        Asm {
            at,
            code: Vec::new(),
        }
    }
    fn here(&self) -> u32 {
        self.at + self.code.len() as u32
    }
    fn emit(&mut self, bytes: &[u8], mnemonic: &str) {
        let d = decode_bytes(bytes).expect("the test's own encodings decode");
        assert_eq!(d.len_bytes() as usize, bytes.len(), "{bytes:02x?}");
        let text = format_instr(d, self.here());
        assert!(text.starts_with(mnemonic), "{text} is not {mnemonic}");
        self.code.extend_from_slice(bytes);
    }
    fn straight(&mut self, raw: &[[u8; 10]]) {
        for r in raw {
            if let Some(b) = straight(r) {
                self.code.extend_from_slice(&b);
            }
        }
    }
    fn mov_l(&mut self, reg: u8, v: u32) {
        let [a, b, c, d] = v.to_be_bytes();
        self.emit(&[0x7a, reg, a, b, c, d], "mov.l");
    }
    fn jsr_abs(&mut self, target: u32) {
        let [_, a, b, c] = target.to_be_bytes();
        self.emit(&[0x5e, a, b, c], "jsr");
    }
    /// A branch to `target` with condition `cond`: d:8 if it reaches, else d:16.
    fn branch(&mut self, cond: u8, target: u32) {
        let d8 = target as i64 - (self.here() as i64 + 2);
        if (-128..=127).contains(&d8) {
            self.emit(&[0x40 | cond, d8 as u8], "b");
        } else {
            let d16 = (target as i64 - (self.here() as i64 + 4)) as i16 as u16;
            let [h, l] = d16.to_be_bytes();
            self.emit(&[0x58, cond << 4, h, l], "b");
        }
    }
    fn bsr(&mut self, target: u32) {
        let d8 = target as i64 - (self.here() as i64 + 2);
        if (-128..=127).contains(&d8) {
            self.emit(&[0x55, d8 as u8], "bsr");
        } else {
            let d16 = (target as i64 - (self.here() as i64 + 4)) as i16 as u16;
            let [h, l] = d16.to_be_bytes();
            self.emit(&[0x5c, 0x00, h, l], "bsr");
        }
    }
    /// [`Piece::Countdown`].
    fn countdown(&mut self, size: u8, kind: u8, rd: u8, init: u32, amount: u32) {
        // Byte and word registers 0-15 (7 and 15 are parts of ER7), longs 0-6.
        let (size, rd) = match size % 3 {
            0 => (
                0,
                [0u8, 1, 2, 3, 4, 5, 6, 8, 9, 10, 11, 12, 13, 14][usize::from(rd) % 14],
            ),
            1 => (
                1,
                [0u8, 1, 2, 3, 4, 5, 6, 8, 9, 10, 11, 12, 13, 14][usize::from(rd) % 14],
            ),
            _ => (2, rd % 7),
        };
        let by2 = amount & 1 == 1;
        match size {
            0 => self.emit(&[0xf0 | rd, init as u8], "mov.b"),
            1 => {
                let [h, l] = (init as u16).to_be_bytes();
                self.emit(&[0x79, rd, h, l], "mov.w");
            }
            _ => self.mov_l(rd, init),
        }
        let top = self.here();
        match (size, kind % 5) {
            (0, 0 | 1) => self.emit(&[0x80 | rd, amount as u8], "add.b"),
            (0, 2) => self.emit(&[0x0a, rd], "inc"),
            (0, _) => self.emit(&[0x1a, rd], "dec"),
            (1, 0) => {
                let [h, l] = (amount as u16).to_be_bytes();
                self.emit(&[0x79, 0x10 | rd, h, l], "add.w");
            }
            (1, 1) => {
                let [h, l] = (amount as u16).to_be_bytes();
                self.emit(&[0x79, 0x30 | rd, h, l], "sub.w");
            }
            (1, 2) => self.emit(&[0x0b, if by2 { 0xd0 } else { 0x50 } | rd], "inc"),
            (1, _) => self.emit(&[0x1b, if by2 { 0xd0 } else { 0x50 } | rd], "dec"),
            (_, 0) => {
                let [a, b, c, d] = amount.to_be_bytes();
                self.emit(&[0x7a, 0x10 | rd, a, b, c, d], "add.l");
            }
            (_, 1) => {
                let [a, b, c, d] = amount.to_be_bytes();
                self.emit(&[0x7a, 0x30 | rd, a, b, c, d], "sub.l");
            }
            (_, 2) => self.emit(&[0x0b, if by2 { 0xf0 } else { 0x70 } | rd], "inc"),
            (_, _) => self.emit(&[0x1b, if by2 { 0xf0 } else { 0x70 } | rd], "dec"),
        }
        self.branch(6, top); // bne
    }

    fn piece(&mut self, p: &Piece, subs: usize) {
        match p {
            Piece::Straight(raw) => self.straight(raw),
            Piece::Loop(n, raw) => {
                self.emit(&[0x79, 0x06, 0x00, *n], "mov.w");
                let top = self.here();
                self.straight(raw);
                self.emit(&[0x1b, 0x56], "dec");
                self.branch(6, top); // bne
            }
            Piece::Skip(cond, raw) => {
                // The body stays within a d:8 branch's reach, whole instructions only.
                let mut body = Vec::new();
                for r in raw {
                    if let Some(b) = straight(r)
                        && body.len() + b.len() <= 127
                    {
                        body.extend_from_slice(&b);
                    }
                }
                self.emit(&[0x40 | cond, body.len() as u8], "b");
                self.code.extend_from_slice(&body);
            }
            Piece::Bsr(n) => self.bsr(SUBS + (*n % subs) as u32 * SUB_SPACING),
            Piece::JsrAbs(n) => self.jsr_abs(SUBS + (*n % subs) as u32 * SUB_SPACING),
            Piece::JsrReg(n) => {
                self.mov_l(6, SUBS + (*n % subs) as u32 * SUB_SPACING);
                self.emit(&[0x5d, 0x60], "jsr");
            }
            Piece::JsrRam => self.jsr_abs(RAM_SUB),
            Piece::Eepmov(a, b, n) => {
                self.mov_l(5, 0xFF_E800 + u32::from(*a % 0x400));
                self.mov_l(6, 0xFF_EC00 + u32::from(*b % 0x400));
                self.emit(&[0xfc, *n], "mov.b");
                self.emit(&[0x7b, 0x5c, 0x59, 0x8f], "eepmov.b");
            }
            Piece::Ldc(v) => self.emit(&[0x07, *v], "ldc"),
            Piece::StartTimer(gra) => {
                let [h, l] = gra.to_be_bytes();
                self.emit(&[0x79, 0x00, h, l], "mov.w");
                self.emit(&[0x6b, 0x80, 0xff, 0x6a], "mov.w"); // GRA0
                self.emit(&[0xf8, 0x23], "mov.b"); // CCLR = GRA, phi/8
                self.emit(&[0x38, 0x64], "mov.b"); // TCR0
                self.emit(&[0xf8, 0x01], "mov.b");
                self.emit(&[0x38, 0x66], "mov.b"); // TIER0 = IMIEA
                self.emit(&[0x38, 0x60], "mov.b"); // TSTR: start ITU0
                self.emit(&[0x06, 0x7f], "andc"); // unmask
            }
            Piece::Sleep => self.emit(&[0x01, 0x80], "sleep"),
            Piece::Countdown {
                size,
                kind,
                rd,
                init,
                amount,
            } => self.countdown(*size, *kind, *rd, *init, *amount),
            Piece::PollRam => {
                let t = TOGGLE as u8;
                self.emit(&[0x29, t], "mov.b"); // @TOGGLE:8,r1l
                let top = self.here();
                self.emit(&[0x28, t], "mov.b"); // @TOGGLE:8,r0l
                self.emit(&[0x1c, 0x89], "cmp.b"); // r0l,r1l
                self.branch(7, top); // beq
            }
            Piece::PollAdc(ch) => {
                self.emit(&[0xf8, 0x20 | (ch & 7)], "mov.b"); // ADST, channel
                self.emit(&[0x38, 0xe8], "mov.b"); // r0l,@ADCSR:8
                let top = self.here();
                self.emit(&[0x28, 0xe8], "mov.b"); // @ADCSR:8,r0l
                self.branch(10, top); // bpl
            }
            Piece::Spin => {
                let top = self.here();
                self.branch(0, top);
            }
        }
    }
}

/// A random program: the main loop's pieces, the subroutines, the RAM subroutine, the
/// interrupt handler.
#[derive(Clone, Debug)]
struct Program {
    main: Vec<Piece>,
    subs: Vec<Vec<[u8; 10]>>,
    ram_sub: Vec<[u8; 10]>,
    handler: Vec<[u8; 10]>,
    regs: [u32; 6],
}

fn raw_insns(max: usize) -> impl Strategy<Value = Vec<[u8; 10]>> {
    proptest::collection::vec(any::<[u8; 10]>(), 0..max)
}

fn piece() -> impl Strategy<Value = Piece> {
    prop_oneof![
        4 => raw_insns(12).prop_map(Piece::Straight),
        2 => (1u8..20, raw_insns(8)).prop_map(|(n, b)| Piece::Loop(n, b)),
        2 => (0u8..16, raw_insns(6)).prop_map(|(c, b)| Piece::Skip(c, b)),
        1 => any::<usize>().prop_map(Piece::Bsr),
        1 => any::<usize>().prop_map(Piece::JsrAbs),
        1 => any::<usize>().prop_map(Piece::JsrReg),
        1 => Just(Piece::JsrRam),
        1 => (any::<u16>(), any::<u16>(), any::<u8>()).prop_map(|(a, b, n)| Piece::Eepmov(a, b, n)),
        1 => any::<u8>().prop_map(Piece::Ldc),
        1 => (20u16..400).prop_map(Piece::StartTimer),
        1 => Just(Piece::Sleep),
        2 => (any::<u8>(), any::<u8>(), any::<u8>(), countdown_init(), prop_oneof![Just(1u32), Just(2), Just(0xFF), Just(0xFFFE), Just(0xFFFF_FFFF), any::<u32>()])
            .prop_map(|(size, kind, rd, init, amount)| Piece::Countdown { size, kind, rd, init, amount }),
        1 => Just(Piece::PollRam),
        1 => (0u8..8).prop_map(Piece::PollAdc),
        1 => Just(Piece::Spin),
    ]
}

/// A delay loop's start: mostly small counts, some of any size (which then run into the
/// deadline).
fn countdown_init() -> impl Strategy<Value = u32> {
    prop_oneof![3 => 0u32..3_000, 1 => any::<u32>()]
}

/// Initial ER0–ER5: mostly RAM addresses (so memory operands hit RAM), some I/O, some any.
fn reg_value() -> impl Strategy<Value = u32> {
    prop_oneof![
        3 => (0u32..RAM_BYTES).prop_map(|o| RAM_START + (o & !1)),
        1 => 0xFF_FF1Cu32..=0xFF_FFFF,
        1 => any::<u32>(),
    ]
}

fn program() -> impl Strategy<Value = Program> {
    (
        proptest::collection::vec(piece(), 1..12),
        proptest::collection::vec(raw_insns(10), 1..4),
        raw_insns(8),
        raw_insns(4),
        proptest::array::uniform6(reg_value()),
    )
        .prop_map(|(main, subs, ram_sub, handler, regs)| Program {
            main,
            subs,
            ram_sub,
            handler,
            regs,
        })
}

/// An MCU with the program in flash and RAM, and a CPU reset into it.
fn install(p: &Program) -> (Cpu, Mcu<NullBoard>) {
    let mut m = Mcu::new(McuConfig::default(), NullBoard).expect("default MCU");
    // Every vector but reset at the handler.
    for v in 1..61u32 {
        m.poke(v * 4, &HANDLER.to_be_bytes());
    }
    m.poke(0, &START.to_be_bytes());
    let mut a = Asm::new(START);
    a.mov_l(7, STACK_TOP);
    let top = a.here();
    for piece in &p.main {
        a.piece(piece, p.subs.len());
    }
    a.branch(0, top); // bra: the main loop repeats
    m.poke(START, &a.code);
    for (i, body) in p.subs.iter().enumerate() {
        let mut s = Asm::new(SUBS + i as u32 * SUB_SPACING);
        s.straight(body);
        s.emit(&[0x54, 0x70], "rts");
        assert!(s.code.len() as u32 <= SUB_SPACING);
        m.poke(s.at, &s.code);
    }
    let mut h = Asm::new(HANDLER);
    h.emit(&[0x7f, 0x67, 0x72, 0x00], "bclr"); // TSR0.IMFA: the timer's request served
    h.emit(&[0x7f, TOGGLE as u8, 0x71, 0x00], "bnot"); // for PollRam
    h.straight(&p.handler);
    h.emit(&[0x56, 0x70], "rte");
    m.poke(HANDLER, &h.code);
    let mut r = Asm::new(RAM_SUB);
    r.straight(&p.ram_sub);
    r.emit(&[0x54, 0x70], "rts");
    m.poke(RAM_SUB, &r.code);
    let mut cpu = Cpu::new();
    cpu.reset(&mut m);
    for (i, v) in p.regs.iter().enumerate() {
        cpu.set_er(i, *v);
    }
    (cpu, m)
}

/// Steps per random program.
const RANDOM_STEPS: u64 = 4_000;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn random_programs_run_alike_on_both_paths(p in program()) {
        let (mut ca, mut ma) = install(&p);
        let (mut cb, mut mb) = install(&p);
        let r = lockstep((&mut ca, &mut ma), (&mut cb, &mut mb), RANDOM_STEPS, u64::MAX);
        prop_assert!(r.is_ok(), "{}", r.unwrap_err());
    }
}

/// The random programs' coverage, printed (`cargo test --test fast_path -- --nocapture`):
/// steps, instructions, interrupts and logged accesses over a fixed set of programs.
#[test]
fn random_programs_cover_loops_calls_interrupts_and_io() {
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let mut total = Tally::default();
    let mut ended = 0;
    let n: u32 = 64;
    for _ in 0..n {
        let p = program()
            .new_tree(&mut runner)
            .expect("a program")
            .current();
        let (mut ca, mut ma) = install(&p);
        let (mut cb, mut mb) = install(&p);
        let t = lockstep(
            (&mut ca, &mut ma),
            (&mut cb, &mut mb),
            RANDOM_STEPS,
            u64::MAX,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        total.steps += t.steps;
        total.instructions += t.instructions;
        total.interrupts += t.interrupts;
        total.accesses += t.accesses;
        ended += usize::from(t.end.is_some());
    }
    println!(
        "{n} random programs: {} steps, {} instructions, {} interrupts, {} logged accesses, {ended} ended early (halt or error)",
        total.steps, total.instructions, total.interrupts, total.accesses
    );
    assert!(total.instructions > u64::from(n) * RANDOM_STEPS / 2);
}

// ----- the C programs and the firmware -----------------------------------------------------

fn program_images() -> Vec<(String, Vec<u8>)> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("programs");
    let mut v: Vec<_> = std::fs::read_dir(&dir)
        .expect("tests/programs")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "mot"))
        .map(|p| {
            let name = p
                .file_stem()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned();
            (name, std::fs::read(&p).expect("read image"))
        })
        .collect();
    v.sort();
    v
}

#[test]
fn every_c_program_runs_alike_on_both_paths() {
    let images = program_images();
    assert!(images.len() >= 10, "{} images", images.len());
    for (name, mot) in images {
        let image = srec::parse(&mot).expect("image parses");
        let mut ma = Machine::with_image(&image).expect("loads").into_mcu();
        let mut mb = ma.clone();
        let (mut ca, mut cb) = (Cpu::new(), Cpu::new());
        ca.reset(&mut ma);
        cb.reset(&mut mb);
        let t = lockstep(
            (&mut ca, &mut ma),
            (&mut cb, &mut mb),
            u64::MAX,
            500_000_000,
        )
        .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(t.end, Some(Ok(Event::Halted)), "{name}");
        assert_eq!(ca.er(0) & 0xff, 0, "{name}: exit status");
        println!(
            "{name}: {} instructions, {} states, {} logged accesses alike",
            t.instructions,
            ma.now(),
            t.accesses
        );
    }
}

/// Simulated seconds of firmware compared.
const FIRMWARE_S: u64 = 3;

/// P4DDR and P4DR (H8/3052F hardware manual, Table 9-7): the firmware's I²C lines.
const P4DDR: u32 = 0xFF_FFC5;
const P4DR: u32 = 0xFF_FFC7;

#[test]
fn the_robot_firmware_runs_alike_on_both_paths() {
    let fw = Firmware::robot().expect("the committed firmware");
    // On the robot's board: its EEPROMs on port 4, nothing else connected.
    let mut ma =
        robot_board::board::robot_mcu(NullBoard, &robot_board::board::RobotConfig::default())
            .expect("default MCU");
    let mut ca = Cpu::new();
    // A step every 10 ticks (0.1 s) and a record saved over I2C every 2 steps, so that a few
    // seconds hold many steps and saves.
    let block = ConfigBlock {
        save_every: 2,
        ticks_per_step: 10,
        ..ConfigBlock::ARENA
    };
    fw.install(&mut ma, &mut ca, Some(&block))
        .expect("installs");
    let mut mb = ma.clone();
    let mut cb = ca.clone();
    let until = FIRMWARE_S * u64::from(ma.clock_hz());
    let t = lockstep((&mut ca, &mut ma), (&mut cb, &mut mb), u64::MAX, until)
        .unwrap_or_else(|e| panic!("firmware: {e}"));
    assert!(
        t.end.is_none() || t.end == Some(Ok(Event::Asleep)),
        "{:?}",
        t.end
    );
    let ticks = FIRMWARE_S * 100;
    assert!(t.interrupts >= ticks - 2, "{} interrupts", t.interrupts);
    assert!(
        ma.adc().starts() >= ticks / 10 - 2,
        "{} A/D runs",
        ma.adc().starts()
    );
    assert_eq!(ma.adc().starts(), mb.adc().starts());
    let i2c_writes = t.io_writes.get(&P4DDR).copied().unwrap_or(0)
        + t.io_writes.get(&P4DR).copied().unwrap_or(0);
    assert!(i2c_writes > 10_000, "{i2c_writes} writes to the I2C lines");
    println!(
        "firmware, {FIRMWARE_S} s: {} steps, {} instructions, {} interrupts, {} A/D runs, {i2c_writes} writes to P4DDR/P4DR, {} logged accesses alike",
        t.steps,
        t.instructions,
        t.interrupts,
        ma.adc().starts(),
        t.accesses
    );
}

// ----- run, the switch, the caches ---------------------------------------------------------

/// Robots installed from one firmware share its decoded code (each with its own configuration
/// block, which the shared tables leave out) and run exactly as a robot whose CPU fills tables
/// of its own; a write to the flash outside the block gives that robot its own tables again and
/// leaves the others' alone.
#[test]
fn robots_sharing_decoded_firmware_run_as_with_tables_of_their_own() {
    let fw = Firmware::robot().expect("the committed firmware");
    let robot = || {
        robot_board::board::robot_mcu(NullBoard, &robot_board::board::RobotConfig::default())
            .expect("default MCU")
    };
    let block = ConfigBlock {
        save_every: 2,
        ticks_per_step: 10,
        ..ConfigBlock::ARENA
    };
    let (mut ma, mut ca) = (robot(), Cpu::new());
    fw.install(&mut ma, &mut ca, Some(&block))
        .expect("installs");
    let code = fw.shared_code().expect("built by the install").clone();
    assert!(ca.shares_code(&code));
    assert!(code.filled() > 1_000, "{} slots", code.filled());
    let (mut mb, mut cb) = (robot(), Cpu::new());
    fw.install(&mut mb, &mut cb, Some(&block))
        .expect("installs");
    cb.flush_decode_cache();
    assert!(!cb.shares_code(&code), "cb decodes for itself");
    // Another block: another page of flash, the same shared code.
    let (mut mc, mut cc) = (robot(), Cpu::new());
    let other = ConfigBlock {
        save_every: 3,
        ..block
    };
    fw.install(&mut mc, &mut cc, Some(&other))
        .expect("installs");
    assert!(cc.shares_code(&code));
    let until = FIRMWARE_S * u64::from(ma.clock_hz());
    run_vs_steps((&mut ca, &mut ma), (&mut cb, &mut mb), 12_345, until)
        .unwrap_or_else(|e| panic!("shared vs own tables: {e}"));
    assert!(ca.instructions() > 1_000_000, "{}", ca.instructions());
    assert!(
        ca.shares_code(&code),
        "every instruction run was in the shared tables: none copied"
    );
    cc.run(&mut mc, until).expect("runs");
    assert!(cc.shares_code(&code));
    // A flash write outside the block: a new token, and cc's tables are its own from the next
    // step on; the shared tables and ca's are untouched.
    mc.poke(0x7_0000, &[0x12]);
    cc.run(&mut mc, until + 1_000).expect("runs");
    assert!(!cc.shares_code(&code));
    assert!(ca.shares_code(&code));
    assert!(
        fw.shared_code()
            .is_some_and(|c| c.filled() == code.filled())
    );
}

fn crcmacdiv() -> srec::SrecImage {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/programs/crcmacdiv.mot");
    srec::parse(&std::fs::read(path).expect("crcmacdiv.mot")).expect("parses")
}

/// Runs `ca` with [`Cpu::run`] and `cb` with [`Cpu::step`] in a loop to the same deadlines,
/// `chunk` states apart, until `until`, a halt or an error; compares the events, the states
/// and the RAM at every deadline. Returns the number of [`Cpu::run`] calls.
fn run_vs_steps<B: Board>(
    (ca, ma): (&mut Cpu, &mut Mcu<B>),
    (cb, mb): (&mut Cpu, &mut Mcu<B>),
    chunk: u64,
    until: u64,
) -> Result<u64, String> {
    let mut deadline = ma.now();
    let mut calls = 0;
    while deadline < until {
        deadline = (deadline + chunk).min(until);
        let ea = ca.run(ma, deadline);
        calls += 1;
        let eb = loop {
            if mb.now() >= deadline {
                break Ok(Event::Executed);
            }
            match cb.step(mb, deadline) {
                Ok(Event::Executed) => {}
                other => break other,
            }
        };
        if ea != eb {
            return Err(format!("run to {deadline}: {ea:?} vs {eb:?}"));
        }
        let (sa, sb) = (snapshot(ca, ma.now()), snapshot(cb, mb.now()));
        if sa != sb {
            return Err(format!("run to {deadline}: {sa:?} vs {sb:?}"));
        }
        if let Some(x) = ram_differs(ma, mb) {
            return Err(format!("run to {deadline}: RAM differs at H'{x:06X}"));
        }
        match ea {
            Ok(Event::Halted) | Err(_) => break,
            // An interrupt or a wait: go on to the same deadline.
            Ok(Event::Interrupt(_) | Event::Asleep | Event::Reset | Event::Break) => {
                deadline = ma.now().min(deadline);
            }
            Ok(Event::Executed) => {}
        }
    }
    Ok(calls)
}

#[test]
fn run_is_step_in_a_loop() {
    let image = crcmacdiv();
    let mut ma = Machine::with_image(&image).expect("loads").into_mcu();
    let mut mb = ma.clone();
    let (mut ca, mut cb) = (Cpu::new(), Cpu::new());
    ca.reset(&mut ma);
    cb.reset(&mut mb);
    run_vs_steps((&mut ca, &mut ma), (&mut cb, &mut mb), 12_345, 100_000_000)
        .unwrap_or_else(|e| panic!("crcmacdiv: {e}"));
    assert!(ca.halted(), "crcmacdiv ran to its halt");
    // The firmware: interrupts, sleep, I/O.
    let fw = Firmware::robot().expect("the committed firmware");
    let mut ma =
        robot_board::board::robot_mcu(NullBoard, &robot_board::board::RobotConfig::default())
            .expect("default MCU");
    let mut ca = Cpu::new();
    let block = ConfigBlock {
        save_every: 2,
        ticks_per_step: 10,
        ..ConfigBlock::ARENA
    };
    fw.install(&mut ma, &mut ca, Some(&block))
        .expect("installs");
    let (mut mb, mut cb) = (ma.clone(), ca.clone());
    let until = u64::from(ma.clock_hz());
    let calls = run_vs_steps((&mut ca, &mut ma), (&mut cb, &mut mb), 9_999, until)
        .unwrap_or_else(|e| panic!("firmware: {e}"));
    assert!(calls > 2_500, "{calls}");
}

/// A program of the given main-loop pieces, with one empty subroutine and handler.
fn program_of(main: Vec<Piece>) -> Program {
    Program {
        main,
        subs: vec![Vec::new()],
        ram_sub: Vec::new(),
        handler: Vec::new(),
        regs: [RAM_START; 6],
    }
}

#[test]
fn run_fast_forwards_each_kind_of_loop_to_the_state_stepping_reaches() {
    let countdown = |size, kind, rd, init, amount| Piece::Countdown {
        size,
        kind,
        rd,
        init,
        amount,
    };
    let cases: Vec<(&str, Vec<Piece>)> = vec![
        ("dec.w from 833", vec![countdown(1, 4, 3, 833, 0)]),
        ("dec.w #2 from 0 (wraps)", vec![countdown(1, 4, 9, 0, 1)]),
        ("add.b #-1", vec![countdown(0, 0, 10, 200, 0xFF)]),
        ("add.b #3 (odd step)", vec![countdown(0, 0, 2, 7, 3)]),
        (
            "inc.l #2 from odd (never zero)",
            vec![countdown(2, 2, 4, 5, 1)],
        ),
        ("sub.l", vec![countdown(2, 1, 1, 1_000_000, 10)]),
        (
            "add.w under a timer",
            vec![Piece::StartTimer(97), countdown(1, 0, 5, 40_000, 0xFFFF)],
        ),
        (
            "RAM poll under a timer",
            vec![Piece::StartTimer(300), Piece::PollRam],
        ),
        ("A/D poll", vec![Piece::PollAdc(3), Piece::PollAdc(6)]),
        (
            "spin under a timer",
            vec![Piece::StartTimer(250), Piece::Spin],
        ),
    ];
    for (name, main) in cases {
        for chunk in [997, 20_011] {
            let p = program_of(main.clone());
            let (mut ca, mut ma) = install(&p);
            let (mut cb, mut mb) = install(&p);
            run_vs_steps((&mut ca, &mut ma), (&mut cb, &mut mb), chunk, 400_000)
                .unwrap_or_else(|e| panic!("{name}, chunk {chunk}: {e}"));
            assert!(
                ca.skipped_instructions() > ca.instructions() / 4,
                "{name}, chunk {chunk}: {} of {} instructions skipped",
                ca.skipped_instructions(),
                ca.instructions()
            );
            assert_eq!(cb.skipped_instructions(), 0);
        }
    }
}

#[test]
fn with_fast_forwarding_off_run_executes_every_instruction() {
    let p = program_of(vec![Piece::Countdown {
        size: 1,
        kind: 4,
        rd: 3,
        init: 30_000,
        amount: 0,
    }]);
    let (mut ca, mut ma) = install(&p);
    let (mut cb, mut mb) = install(&p);
    ca.set_fast_forward(false);
    let (ea, eb) = (ca.run(&mut ma, 100_000), cb.run(&mut mb, 100_000));
    assert_eq!(ea, eb);
    assert_eq!(snapshot(&ca, ma.now()), snapshot(&cb, mb.now()));
    assert_eq!(ca.skipped_instructions(), 0);
    assert!(cb.skipped_instructions() > 10_000);
}

/// The random programs' fast-forwarding, printed (`-- --nocapture`): how much of a fixed set
/// of programs' run was skipped, which must be some (the test above cannot pass vacuously).
#[test]
fn random_programs_have_loops_to_fast_forward() {
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let (mut skipped, mut total) = (0, 0);
    for _ in 0..64 {
        let p = program()
            .new_tree(&mut runner)
            .expect("a program")
            .current();
        let (mut ca, mut ma) = install(&p);
        let (mut cb, mut mb) = install(&p);
        run_vs_steps((&mut ca, &mut ma), (&mut cb, &mut mb), 3_001, 60_000)
            .unwrap_or_else(|e| panic!("{e}"));
        skipped += ca.skipped_instructions();
        total += ca.instructions();
    }
    println!("64 random programs: {skipped} of {total} instructions fast-forwarded");
    assert!(skipped > 0 && skipped < total);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn run_is_step_in_a_loop_on_random_programs(p in program(), chunk in 1u64..5_000) {
        let (mut ca, mut ma) = install(&p);
        let (mut cb, mut mb) = install(&p);
        let r = run_vs_steps((&mut ca, &mut ma), (&mut cb, &mut mb), chunk, 60_000);
        prop_assert!(r.is_ok(), "{}", r.unwrap_err());
    }
}

#[test]
fn with_the_fast_path_off_step_is_the_reference() {
    let image = crcmacdiv();
    let mut ma = Machine::with_image(&image).expect("loads");
    let mut ca = Cpu::new();
    ca.set_fast_path(false);
    assert!(!ca.fast_path());
    ca.reset(&mut ma);
    let mut mb = ma.clone();
    let mut cb = ca.clone();
    let mut la = Logged {
        bus: &mut *ma,
        log: Vec::new(),
    };
    let mut lb = Logged {
        bus: &mut *mb,
        log: Vec::new(),
    };
    for _ in 0..20_000 {
        // Off, step fetches every word through the bus: the logs see the same reads.
        let ea = ca.step(&mut la, u64::MAX);
        let eb = cb.step_reference(&mut lb, u64::MAX);
        assert_eq!(ea, eb);
        assert_eq!(la.log, lb.log);
        assert_eq!(snapshot(&ca, la.now()), snapshot(&cb, lb.now()));
    }
}

/// `bytes` then `sleep` at H'1000 with CCR.I set, run to the halt on `cpu`; returns the
/// registers and the clock.
fn halting_code(bytes: &[u8]) -> Vec<u8> {
    let mut v = bytes.to_vec();
    v.extend_from_slice(&[0x01, 0x80]); // sleep
    v
}

fn run_to_halt<M: FastPathHints>(cpu: &mut Cpu, m: &mut M) -> ([u32; 8], u64) {
    cpu.set_pc(0x1000);
    cpu.set_ccr(0x80);
    for _ in 0..100 {
        match cpu.step(m, u64::MAX) {
            Ok(Event::Halted) => return (cpu.regs(), m.now()),
            Ok(_) => {}
            Err(e) => panic!("{e}"),
        }
    }
    panic!("no halt");
}

/// `mov.l #v,er0; add.l er0,er1` then SLEEP.
fn code_adding(v: u32) -> Vec<u8> {
    let [a, b, c, d] = v.to_be_bytes();
    halting_code(&[0x7a, 0x00, a, b, c, d, 0x0a, 0x81])
}

/// More back edges than the fast-forward keeps entries for (65 534): 65 600 countdown loops
/// one after the other, each taken 63 times. Those with entries are advanced in closed form,
/// the rest simply run; `run` reaches the state stepping reaches at every deadline.
#[test]
fn more_loops_than_the_fast_forward_indexes_run_to_the_same_state() {
    let loops = 65_600;
    let mut code = Vec::with_capacity(loops * 6);
    for _ in 0..loops {
        // mov.b #64,r0l; L: dec.b r0l; bne L
        code.extend_from_slice(&[0xF8, 0x40, 0x1A, 0x08, 0x46, 0xFC]);
    }
    let mut m = Machine::new();
    m.poke(0x1000, &halting_code(&code));
    let mut ma = m.into_mcu();
    let mut mb = ma.clone();
    let (mut ca, mut cb) = (Cpu::new(), Cpu::new());
    for c in [&mut ca, &mut cb] {
        c.set_pc(0x1000);
        c.set_ccr(0x80);
    }
    run_vs_steps(
        (&mut ca, &mut ma),
        (&mut cb, &mut mb),
        1_000_003,
        200_000_000,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(ca.halted(), "ran to the end");
    assert!(
        ca.skipped_instructions() > 1_000_000,
        "{}",
        ca.skipped_instructions()
    );
    assert_eq!(ca.instructions(), cb.instructions());
}

#[test]
fn a_poke_into_the_flash_empties_the_decode_caches() {
    let mut m = Machine::new();
    m.poke(0x1000, &code_adding(5));
    let mut cpu = Cpu::new();
    let (regs, _) = run_to_halt(&mut cpu, &mut m);
    assert_eq!(regs[1], 5);
    // The same addresses, new code: the CPU (caches filled, now halted) is reset and runs it.
    m.poke(0x1000, &code_adding(7));
    cpu.reset(&mut m);
    cpu.set_er(1, 0);
    let (regs, _) = run_to_halt(&mut cpu, &mut m);
    assert_eq!(regs[1], 7, "the new code ran, not the cached one");
    // One byte is enough: the immediate's last byte.
    m.poke(0x1005, &[9]);
    cpu.reset(&mut m);
    cpu.set_er(1, 0);
    let (regs, _) = run_to_halt(&mut cpu, &mut m);
    assert_eq!(regs[1], 9);
    // A poke into RAM is no flash write: the token stays.
    let t = m.code_generation();
    m.poke(0xFF_E000, &[1, 2, 3]);
    assert_eq!(m.code_generation(), t);
    assert!(t.is_some());
}

#[test]
fn loading_an_image_empties_the_decode_caches_and_each_mcu_has_its_own_token() {
    let image = |v: u32| srec::SrecImage {
        header: None,
        chunks: vec![srec::Chunk {
            address: 0x1000,
            data: code_adding(v),
        }],
        start: None,
    };
    let mut m = Mcu::new(McuConfig::default(), NullBoard).expect("default MCU");
    m.load_image(&image(3)).expect("loads");
    let mut cpu = Cpu::new();
    assert_eq!(run_to_halt(&mut cpu, &mut m).0[1], 3);
    let t = m.code_generation();
    m.load_image(&image(4)).expect("loads");
    assert_ne!(m.code_generation(), t);
    cpu.reset(&mut m);
    cpu.set_er(1, 0);
    assert_eq!(run_to_halt(&mut cpu, &mut m).0[1], 4);
    // The firmware loader (image and configuration block) goes through the same writes.
    let fw = Firmware::robot().expect("the committed firmware");
    let t = m.code_generation();
    fw.install(&mut m, &mut cpu, None).expect("installs");
    assert_ne!(m.code_generation(), t);
    // A CPU moved to another MCU with other code in the same place runs that code.
    let mut other = Mcu::new(McuConfig::default(), NullBoard).expect("default MCU");
    other.load_image(&image(6)).expect("loads");
    assert_ne!(other.code_generation(), m.code_generation());
    let mut cpu = Cpu::new();
    assert_eq!(run_to_halt(&mut cpu, &mut other).0[1], 6);
    let mut third = Mcu::new(McuConfig::default(), NullBoard).expect("default MCU");
    third.load_image(&image(8)).expect("loads");
    cpu.reset(&mut third);
    cpu.set_er(1, 0);
    assert_eq!(run_to_halt(&mut cpu, &mut third).0[1], 8);
    // A clone has the same flash and may keep the token.
    let clone = third.clone();
    assert_eq!(clone.code_generation(), third.code_generation());
}

/// A bus that shows no token: the CPU fetches every word through it (as a probe needs), on
/// `step` as on `step_reference`.
struct NoPromise<'a>(&'a mut Machine, u64);

impl FastPathHints for NoPromise<'_> {}

impl Bus for NoPromise<'_> {
    fn now(&self) -> u64 {
        self.0.now()
    }
    fn read8(&mut self, addr: u32) -> u8 {
        self.0.read8(addr)
    }
    fn read16(&mut self, addr: u32) -> u16 {
        self.1 += 1;
        self.0.read16(addr)
    }
    fn write8(&mut self, addr: u32, value: u8) {
        self.0.write8(addr, value);
    }
    fn write16(&mut self, addr: u32, value: u16) {
        self.0.write16(addr, value);
    }
    fn internal(&mut self, states: u32) {
        self.0.internal(states);
    }
    fn pending_irq(&self) -> Option<u8> {
        self.0.pending_irq()
    }
    fn sleep_until_irq(&mut self, deadline: u64) -> bool {
        self.0.sleep_until_irq(deadline)
    }
}

#[test]
fn a_bus_without_a_token_sees_every_fetch() {
    let mut m = Machine::new();
    m.poke(0x1000, &code_adding(5));
    let mut cpu = Cpu::new();
    let mut bus = NoPromise(&mut m, 0);
    let (regs, _) = run_to_halt(&mut cpu, &mut bus);
    assert_eq!(regs[1], 5);
    // mov.l #imm (3 words) + add.l (1) + sleep (1), and nothing else is read as a word.
    assert_eq!(bus.1, 5);
    // The Machine passes its MCU's token on.
    assert_eq!(m.code_generation(), m.mcu().code_generation());
}

/// The benchmark's window (`benches/core_speed.rs`): the first 2 M states of crcmacdiv after
/// reset touch no I/O register and the program is still computing at their end.
#[test]
fn the_benchmark_window_of_crcmacdiv_has_no_io() {
    let image = crcmacdiv();
    let mut m = Machine::with_image(&image).expect("loads");
    let mut cpu = Cpu::new();
    cpu.reset(&mut m);
    let mut bus = Logged {
        bus: &mut m,
        log: Vec::new(),
    };
    while bus.now() < 2_000_000 {
        assert_eq!(cpu.step(&mut bus, u64::MAX), Ok(Event::Executed));
    }
    let io: Vec<_> = bus
        .log
        .iter()
        .filter(|a| match a {
            Access::Read8(x, ..)
            | Access::Read16(x, ..)
            | Access::Write8(x, ..)
            | Access::Write16(x, ..) => Area::of(*x) != Area::Ram,
            Access::Sleep(..) => true,
        })
        .collect();
    assert!(io.is_empty(), "{:?}", &io[..io.len().min(5)]);
}

// ----- idle cycles (Cpu::run_idle) -----------------------------------------------------------

/// The tick counter of the idle-loop programs (a RAM longword above the stack).
const TICKS: u32 = 0xFF_FF0C;

/// An idle-loop program: ITU0 ticking every `gra + 1` counts of φ/8, a main loop of random
/// straight code and a wait for `wait` ticks (`mov.l @TICKS,er5; add.l #wait,er5; 1: sleep;
/// mov.l @TICKS,er6; cmp.l er5,er6; blt 1b`), and a handler that clears the flag, adds
/// `stride` to the counter (`add.l`, or `inc.l #1` when `stride` is 0) and runs `body`.
#[derive(Clone, Debug)]
struct IdleProgram {
    gra: u16,
    wait: u32,
    stride: u32,
    ticks: u32,
    main: Vec<[u8; 10]>,
    body: Vec<[u8; 10]>,
}

fn install_idle(p: &IdleProgram) -> (Cpu, Mcu<NullBoard>) {
    let mut m = Mcu::new(McuConfig::default(), NullBoard).expect("default MCU");
    for v in 1..61u32 {
        m.poke(v * 4, &HANDLER.to_be_bytes());
    }
    m.poke(0, &START.to_be_bytes());
    m.poke(TICKS, &p.ticks.to_be_bytes());
    let [t0, t1, t2, t3] = TICKS.to_be_bytes();
    let mut a = Asm::new(START);
    a.mov_l(7, STACK_TOP);
    a.piece(&Piece::StartTimer(p.gra), 1);
    let top = a.here();
    a.straight(&p.main);
    a.emit(&[0x01, 0x00, 0x6b, 0x25, t0, t1, t2, t3], "mov.l"); // @TICKS,er5
    let [w0, w1, w2, w3] = p.wait.to_be_bytes();
    a.emit(&[0x7a, 0x15, w0, w1, w2, w3], "add.l"); // #wait,er5
    let wait = a.here();
    a.emit(&[0x01, 0x80], "sleep");
    a.emit(&[0x01, 0x00, 0x6b, 0x26, t0, t1, t2, t3], "mov.l"); // @TICKS,er6
    a.emit(&[0x1f, 0xd6], "cmp.l"); // er5,er6
    a.branch(13, wait); // blt
    a.branch(0, top);
    m.poke(START, &a.code);
    let mut h = Asm::new(HANDLER);
    h.emit(&[0x7f, 0x67, 0x72, 0x00], "bclr"); // TSR0.IMFA
    h.emit(&[0x01, 0x00, 0x6b, 0x26, t0, t1, t2, t3], "mov.l"); // @TICKS,er6
    if p.stride == 0 {
        h.emit(&[0x0b, 0x76], "inc"); // inc.l #1,er6
    } else {
        let [s0, s1, s2, s3] = p.stride.to_be_bytes();
        h.emit(&[0x7a, 0x16, s0, s1, s2, s3], "add.l");
    }
    h.emit(&[0x01, 0x00, 0x6b, 0xa6, t0, t1, t2, t3], "mov.l"); // er6,@TICKS
    h.straight(&p.body);
    h.emit(&[0x56, 0x70], "rte");
    m.poke(HANDLER, &h.code);
    let mut cpu = Cpu::new();
    cpu.reset(&mut m);
    (cpu, m)
}

/// What `FirmwareController` does per call: idle cycles first when asleep, then sleep to the
/// next interrupt and run to the next SLEEP, interrupt or the deadline.
fn drive(cpu: &mut Cpu, m: &mut Mcu<NullBoard>, deadline: u64) -> Result<Event, CpuError> {
    if cpu.sleeping() {
        let r = cpu.run_idle(m, deadline, &mut |_, _| false)?;
        if let Some(e) = r.end {
            return Ok(e);
        }
    }
    if cpu.sleeping() {
        m.sleep_until_irq(deadline);
        if m.now() >= deadline {
            return Ok(Event::Asleep);
        }
    }
    cpu.run_until(m, deadline, |c, _| c.sleeping())
}

/// Runs `p` with idle cycles advanced and with everything stepped (fast-forwarding off), to
/// the same deadlines `chunk` states apart until `until`; compares the state and the RAM at
/// every deadline. Returns the idle cycles advanced.
fn idle_vs_steps(p: &IdleProgram, chunk: u64, until: u64) -> Result<u64, String> {
    let (mut ca, mut ma) = install_idle(p);
    let (mut cb, mut mb) = install_idle(p);
    cb.set_fast_forward(false);
    let mut deadline = 0;
    let mut errors: [Option<CpuError>; 2] = [None, None];
    while deadline < until {
        deadline += chunk;
        for (k, (c, m)) in [(&mut ca, &mut ma), (&mut cb, &mut mb)]
            .into_iter()
            .enumerate()
        {
            while m.now() < deadline && !c.halted() && errors[k].is_none() {
                if let Err(e) = drive(c, m, deadline) {
                    errors[k] = Some(e);
                }
            }
        }
        if errors[0] != errors[1] {
            return Err(format!("at {deadline}: {errors:?}"));
        }
        let (sa, sb) = (snapshot(&ca, ma.now()), snapshot(&cb, mb.now()));
        if sa != sb {
            return Err(format!("at {deadline}: {sa:?} vs {sb:?}"));
        }
        if let Some(x) = ram_differs(&ma, &mb) {
            return Err(format!("at {deadline}: RAM differs at H'{x:06X}"));
        }
        if errors[0].is_some() {
            break;
        }
    }
    assert_eq!(cb.idle_cycles_skipped(), 0);
    Ok(ca.idle_cycles_skipped())
}

fn idle_program() -> impl Strategy<Value = IdleProgram> {
    (
        20u16..400,
        1u32..300,
        prop_oneof![3 => Just(0u32), 1 => Just(1), 1 => Just(0xFFFF_FFFF), 1 => any::<u32>()],
        prop_oneof![2 => 0u32..1_000, 1 => any::<u32>()],
        raw_insns(6),
        prop_oneof![1 => Just(Vec::new()), 1 => raw_insns(3)],
    )
        .prop_map(|(gra, wait, stride, ticks, main, body)| IdleProgram {
            gra,
            wait,
            stride,
            ticks,
            main,
            body,
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn idle_cycles_advance_to_the_state_stepping_reaches(p in idle_program(), chunk in 50_000u64..700_000) {
        let r = idle_vs_steps(&p, chunk, 3_000_000);
        prop_assert!(r.is_ok(), "{}", r.unwrap_err());
    }
}

#[test]
fn idle_cycles_are_advanced_and_only_when_proven() {
    let plain = IdleProgram {
        gra: 99,
        wait: 200,
        stride: 0,
        ticks: 0,
        main: Vec::new(),
        body: Vec::new(),
    };
    // A counter by 1, by 3 and downwards; the wait's end and the counter's sign change
    // (ticks from H'7FFFFF00) are crossed by stepping.
    for (stride, ticks) in [(0, 0), (3, 5), (0xFFFF_FFFF, 1000), (0, 0x7FFF_FF00)] {
        let p = IdleProgram {
            stride,
            ticks,
            ..plain.clone()
        };
        for chunk in [99_991, 1_000_003] {
            let n = idle_vs_steps(&p, chunk, 4_000_000).unwrap_or_else(|e| panic!("{e}"));
            assert!(
                n > 1_000,
                "stride {stride:#x}, chunk {chunk}: {n} idle cycles advanced"
            );
        }
    }
    // A handler that shifts the counter (not affine): stepped, and alike.
    let shifting = IdleProgram {
        body: vec![[0x10, 0x36, 0, 0, 0, 0, 0, 0, 0, 0]], // shll.l er6
        ..plain.clone()
    };
    let n = idle_vs_steps(&shifting, 333_333, 2_000_000).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        n > 0,
        "shll.l of a copy in ER6 changes nothing the proof needs: {n}"
    );
    let toggling = IdleProgram {
        body: vec![[0x7f, TOGGLE as u8, 0x71, 0x00, 0, 0, 0, 0, 0, 0]], // bnot #0,@TOGGLE
        ..plain
    };
    let n = idle_vs_steps(&toggling, 333_333, 2_000_000).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(n, 0, "a byte that alternates: no cycle repeats");
}

/// The random idle programs' advancing, printed (`-- --nocapture`): some cycles must be
/// advanced, or the property test above passes vacuously.
#[test]
fn random_idle_programs_have_cycles_to_advance() {
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let (mut advanced, mut with) = (0, 0);
    for _ in 0..32 {
        let p = idle_program()
            .new_tree(&mut runner)
            .expect("a program")
            .current();
        let n = idle_vs_steps(&p, 250_000, 2_000_000).unwrap_or_else(|e| panic!("{e}"));
        advanced += n;
        with += usize::from(n > 0);
    }
    println!("32 random idle programs: {advanced} idle cycles advanced, in {with} programs");
    assert!(with > 4, "{with}");
}
