//! The H8/3052F as one chip: clock, flash, RAM and the peripherals, with the board outside its
//! pins, behind the [`Bus`] every program (the Rust controller or machine code on the H8/300H
//! core) talks through.
//!
//! # Memory
//! A swarm holds thousands of MCUs and the Rust controller never touches ROM or RAM contents,
//! so memory is allocated only when used:
//! - the 512 KB flash exists only once an image is loaded ([`Mcu::load_image`]) or poked;
//!   reads of an empty flash return H'FF (erased flash);
//! - the 8 KB RAM is allocated on the first write (bus or [`Mcu::poke`]); reads of untouched
//!   RAM return 0.
//!
//! An `Mcu` without image and RAM holds a few hundred bytes plus its board.
//!
//! # Peripherals and time
//! The clock counts states since reset; every bus access advances it by the states of the
//! area it touches ([`h8300h::memmap`]) before it takes effect. Word accesses to the ITU's
//! 16-bit registers take one 3-state cycle ([`itu::ITU_WORD_ACCESS_STATES`]); other I/O word
//! accesses take two byte cycles, upper byte first.
//!
//! Every on-chip module is a [`Peripheral`] that owns one block of I/O addresses: the ITU,
//! SCI1, the ports, the A/D converter and the interrupt controller (with SYSCR). An I/O
//! access goes to the module whose block holds the address; the chip asks
//! every module the same questions for the next event, the interrupt requests and reset.
//! Modules are synchronised lazily: each keeps the time it was last brought up to date and
//! catches up, in O(1), when accessed, when the clock is fast-forwarded
//! ([`Bus::sleep_until_irq`], [`Mcu::advance_to`]) or on [`Mcu::sync`]. The pending interrupt
//! is cached until the next write to a module that can change it
//! ([`Peripheral::AFFECTS_IRQ`]), or the next instant a source can raise a request, so
//! [`Bus::pending_irq`], called by the core before every instruction, is one comparison in
//! the common case.
//!
//! The board (the robot outside the chip, [`Board`]) is asked for analog inputs with each
//! conversion's sampling instant — at the latest when the MCU is next synchronised (an A/D
//! access, the end of a sleep, [`Mcu::sync`], [`Mcu::advance_to`]) — and for the port-2 pins
//! at each P2DR read. A board must answer for any instant not earlier than one it was already
//! asked about and not later than the MCU clock.
//!
//! # Port 4 and the board's own events
//! Port 4 is open-drain ([`crate::periph::ports`]): the board is told what the port pulls low
//! at every write to P4DDR or P4DR and asked for the line levels at every P4DR read. On the
//! robot the lines are its EEPROM bus (two 24LC256 at 0x50 and 0x51 on P4.7/P4.6,
//! docs/design.md §3.6), which the board holds (`robot_board::board`). The board's own events
//! (an EEPROM's write cycle ending, [`Board::next_event_states`]) count among the chip's
//! events, so that they are synchronised with the chip's clock, and the board is brought up to
//! the clock whenever the chip is ([`Mcu::sync`]); the board applies them lazily.
//!
//! # The watchdog's reset
//! The watchdog timer ([`crate::periph::wdt`]) in watchdog timer mode resets the chip when its
//! counter overflows: the chip offers the CPU a reset request
//! ([`RESET_REQUEST`](h8300h::bus::RESET_REQUEST)), and when the
//! CPU takes it ([`CpuSignal::Reset`]) every module returns to its reset state (the WDT keeps
//! RSTCSR, with WRST set), port 4's lines are released, and the clock moves to the end of the
//! internal reset (518 states after the overflow). The RAM keeps its contents, the board its
//! parts' state.
//!
//! # Registers the chip does not model
//! Registers of modules not modelled (the DMA controller, the flash memory's control, SCI0,
//! the TPC, the refresh controller, the D/A converter, the bus controller, MDCR, DIVCR,
//! MSTCR, SCMR1), reserved I/O addresses and addresses outside the memory map read 0 (H'FF
//! outside the map) and ignore writes, as on a chip where nothing answers; the first access to
//! each is *reported* ([`IoReport`], named from [`crate::iomap`]). With
//! [`Mcu::set_io_break`] on, the chip also asks the CPU to stop right after the access
//! ([`BREAK_REQUEST`]), and the report gets the instruction's address when the CPU stops
//! ([`CpuSignal::Break`]).

use std::cell::Cell;

use crate::flash::Flash;
use crate::iomap::{Register, register_at};
use crate::periph::Peripheral;
use crate::periph::adc::{ADCR, ADDRA, Adc};
use crate::periph::intc::Intc;
use crate::periph::irq::{self, Irq};
use crate::periph::itu::{self, Itu, PwmWave};
use crate::periph::ports::{PortId, PortPins, Ports};
use crate::periph::sci::Sci;
use crate::periph::wdt::{self, Wdt};
use crate::pins::Board;
use crate::trace::{Accepted, ChipView, PinTrace, Tracer};
use h8300h::bus::{BREAK_REQUEST, Bus, CpuSignal, FastPathHints, fresh_code_generation};
use h8300h::memmap::{
    ADDRESS_MASK, Area, IO_ACCESS_STATES, RAM_BYTES, RAM_START, ROM_BYTES, ROM_END,
};
use h8300h::srec::SrecImage;

/// Lowest φ accepted: 2 MHz (H8/3052F hardware manual, electrical characteristics: operating
/// frequency 2–25 MHz).
pub const MIN_CLOCK_HZ: u32 = 2_000_000;
/// Highest φ accepted: 25 MHz (same table). The one definition of the chip's top speed; the
/// robot's board runs the chip at it (`robot_board::board::CLOCK_HZ`).
pub const MAX_CLOCK_HZ: u32 = 25_000_000;

/// Index masks of the flash and RAM arrays (both sizes are powers of two).
const ROM_INDEX_MASK: usize = ROM_BYTES as usize - 1;
const RAM_INDEX_MASK: usize = RAM_BYTES as usize - 1;

/// How to build an [`Mcu`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct McuConfig {
    /// The system clock φ in Hz ([`MIN_CLOCK_HZ`]..=[`MAX_CLOCK_HZ`]; default the chip's
    /// highest, [`MAX_CLOCK_HZ`]). The MCU counts states; φ converts them to seconds.
    pub clock_hz: u32,
}

impl Default for McuConfig {
    fn default() -> Self {
        McuConfig {
            clock_hz: MAX_CLOCK_HZ,
        }
    }
}

impl McuConfig {
    /// Checks the configuration as [`Mcu::new`] does.
    ///
    /// # Errors
    /// [`McuError::InvalidClock`] if `clock_hz` is outside [`MIN_CLOCK_HZ`]..=[`MAX_CLOCK_HZ`].
    pub fn validate(&self) -> Result<(), McuError> {
        if (MIN_CLOCK_HZ..=MAX_CLOCK_HZ).contains(&self.clock_hz) {
            Ok(())
        } else {
            Err(McuError::InvalidClock {
                clock_hz: self.clock_hz,
            })
        }
    }
}

/// Why an MCU cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum McuError {
    /// φ outside what the chip runs at.
    #[error(
        "clock φ = {clock_hz} Hz is outside the H8/3052F's operating range {min}..={max} Hz",
        min = MIN_CLOCK_HZ,
        max = MAX_CLOCK_HZ
    )]
    InvalidClock {
        /// The rejected value.
        clock_hz: u32,
    },
}

/// Why an image cannot be loaded into the flash.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LoadError {
    /// Data outside the on-chip flash.
    #[error(
        "image data at H'{address:06X}..H'{end:06X} lies outside the on-chip flash H'000000-H'{rom_end:06X}; an S-record image may only load flash",
        end = .address.wrapping_add(*.len as u32).wrapping_sub(1),
        rom_end = ROM_END
    )]
    OutsideFlash {
        /// First address of the offending chunk.
        address: u32,
        /// Its length in bytes.
        len: usize,
    },
    /// No data at all.
    #[error("the image holds no data records")]
    Empty,
}

/// An ITU channel's TIOCA output at one instant ([`Mcu::tioca`]): while the ITU drives the pin
/// it shares with port A or B, the pin reads `level`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TiocaOutput {
    /// The ITU drives the pin (PWM mode, or an output-compare setting of IOA).
    pub drives: bool,
    /// The output's level now.
    pub level: bool,
    /// The steady waveform, while the ITU drives the pin and the channel counts in PWM mode
    /// with an internal clock.
    pub wave: Option<PwmWave>,
}

/// The first access to an address the chip does not model: a register of a module (or a
/// register of a module) it does not model, a reserved I/O address, or an address outside the
/// memory map ([`crate::iomap`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IoReport {
    /// The address (24 bits).
    pub addr: u32,
    /// The register there, or `None` for a reserved address or one outside the memory map.
    pub register: Option<&'static Register>,
    /// A write (else a read).
    pub write: bool,
    /// The instant of the access (states).
    pub at: u64,
    /// The address of the instruction that made it, when the CPU told the chip
    /// ([`Mcu::set_io_break`]).
    pub pc: Option<u32>,
}

impl IoReport {
    /// What lies at the address, in words: `MAR0AR (H'FFFF20) of the DMA controller (DMAC)`,
    /// `H'FFFF1C, a reserved I/O address`, `H'100000, outside the memory map`.
    #[must_use]
    pub fn what(&self) -> String {
        match self.register {
            Some(r) => format!(
                "{} (H'{:06X}) of {} ({})",
                r.name,
                self.addr,
                r.unit.title(),
                r.unit.short()
            ),
            None if Area::of(self.addr) == Area::Io => {
                format!("H'{:06X}, a reserved I/O address", self.addr)
            }
            None => format!("H'{:06X}, outside the memory map of mode 7", self.addr),
        }
    }

    /// The report as one line: the instruction (with its function's name when `function`
    /// gives it), the access, what lies there and that the chip does not model it.
    #[must_use]
    pub fn describe(&self, function: Option<&str>) -> String {
        let at = match (self.pc, function) {
            (Some(pc), Some(f)) => format!("PC H'{pc:06X} in {f}"),
            (Some(pc), None) => format!("PC H'{pc:06X}"),
            (None, _) => format!("state {}", self.at),
        };
        let access = if self.write { "writes" } else { "reads" };
        let effect = if self.write {
            "the write is ignored"
        } else if Area::of(self.addr) == Area::Io {
            "it reads 0"
        } else {
            "it reads H'FF"
        };
        format!("{at}: {access} {}, not modelled ({effect})", self.what())
    }

    /// What the program uses that the chip does not model, in a few words: the register and
    /// its module (`MAR0AR of the DMAC`), or the reserved address.
    #[must_use]
    pub fn short(&self) -> String {
        match self.register {
            Some(r) => format!("{} of the {}", r.name, r.unit.short()),
            None => format!("H'{:06X} (reserved)", self.addr),
        }
    }
}

/// Most reports of addresses outside the I/O area kept (the first access to each): a program
/// that sweeps memory gets a bounded list.
pub const MAX_UNMAPPED_REPORTS: usize = 64;

/// The H8/3052F with its board.
#[derive(Clone, Debug)]
pub struct Mcu<B: Board> {
    now: u64,
    clock_hz: u32,
    rom: Option<Flash>,
    /// The flash's [`FastPathHints::code_generation`] token: a fresh one at every write to the flash.
    rom_generation: u64,
    ram: Option<Box<[u8; RAM_BYTES as usize]>>,
    sci: Sci,
    itu: Itu,
    adc: Adc,
    intc: Intc,
    ports: Ports,
    wdt: Wdt,
    irq: Irq,
    board: B,
    /// Reports of first accesses to addresses the chip does not model, in order.
    io_reports: Vec<IoReport>,
    /// The I/O addresses (low byte) reported so far.
    io_seen: [u64; 4],
    /// Whether a first access raises a break request ([`Mcu::set_io_break`]).
    io_break: bool,
    /// A break request stands (until the CPU takes it).
    break_pending: bool,
    /// Internal resets so far (the watchdog's).
    resets: u64,
    /// The winning interrupt request as of the last computation.
    irq_cached: Cell<Option<u8>>,
    /// The cached request is valid while `now` is below this.
    irq_valid_until: Cell<u64>,
    /// The pin trace under way, if one is ([`Mcu::start_trace`]).
    tracer: Option<Box<Tracer>>,
}

/// The on-chip module that owns an I/O address: the chip's map of its register blocks, each
/// block as its module declares it ([`Peripheral::FIRST`]..=[`Peripheral::LAST`]), less the
/// addresses in it the module does not model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Module {
    Itu,
    Sci,
    Ports,
    Adc,
    Intc,
    Wdt,
    Irq,
    /// No module: reads 0, writes are ignored, the first access is reported.
    Unmodelled,
}

/// The module of each I/O address, by its low byte (the I/O area is H'FFFF1C–H'FFFFFF).
const ROUTES: [Module; 256] = {
    let mut t = [Module::Unmodelled; 256];
    let mut i = 0;
    while i < 256 {
        t[i] = Module::route(0xFF_FF00 | i as u32);
        i += 1;
    }
    t
};

impl Module {
    /// Every module, in the order the chip synchronises and resets them.
    const ALL: [Module; 7] = [
        Module::Itu,
        Module::Adc,
        Module::Sci,
        Module::Ports,
        Module::Intc,
        Module::Wdt,
        Module::Irq,
    ];

    /// The module that models the register at `a` (an I/O address), if any: the blocks the
    /// modules own, less the addresses inside them they do not model (the port block's
    /// reserved addresses; BRCR and H'FFFFF7 in the interrupt controller's).
    const fn route(a: u32) -> Module {
        match a {
            <Itu as Peripheral>::FIRST..=<Itu as Peripheral>::LAST => Module::Itu,
            <Sci as Peripheral>::FIRST..=<Sci as Peripheral>::LAST => Module::Sci,
            <Ports as Peripheral>::FIRST..=<Ports as Peripheral>::LAST => {
                if crate::periph::ports::PortId::of_register(a).is_some() {
                    Module::Ports
                } else {
                    Module::Unmodelled
                }
            }
            <Adc as Peripheral>::FIRST..=<Adc as Peripheral>::LAST => Module::Adc,
            <Wdt as Peripheral>::FIRST..=<Wdt as Peripheral>::LAST => Module::Wdt,
            irq::ISCR..=irq::ISR => Module::Irq,
            crate::periph::intc::SYSCR | crate::periph::intc::IPRA | crate::periph::intc::IPRB => {
                Module::Intc
            }
            _ => Module::Unmodelled,
        }
    }

    /// The module whose block holds `a` (an I/O address).
    #[inline]
    fn of(a: u32) -> Module {
        ROUTES[(a & 0xFF) as usize]
    }

    /// Whether a write to the module can change the interrupt decision.
    #[inline]
    const fn affects_irq(self) -> bool {
        match self {
            Module::Itu => <Itu as Peripheral>::AFFECTS_IRQ,
            Module::Sci => <Sci as Peripheral>::AFFECTS_IRQ,
            Module::Ports => <Ports as Peripheral>::AFFECTS_IRQ,
            Module::Adc => <Adc as Peripheral>::AFFECTS_IRQ,
            Module::Intc => <Intc as Peripheral>::AFFECTS_IRQ,
            Module::Wdt => <Wdt as Peripheral>::AFFECTS_IRQ,
            Module::Irq => true,
            Module::Unmodelled => false,
        }
    }
}

/// Evaluates `$body` with `$p` bound to module `$m` of the MCU `$mcu` and `$outside` to what
/// that module sees outside itself (the board's analog inputs for the A/D converter; the
/// port-2 and port-4 pins and the ITU for the ports; nothing for the others), or `$none`
/// for [`Module::Unmodelled`]. The one place that says which field holds which module.
macro_rules! on_module {
    ($mcu:ident, $m:expr, |$p:ident, $outside:ident| $body:expr, $none:expr) => {
        match $m {
            Module::Itu => {
                let ($p, $outside) = (&mut $mcu.itu, ());
                $body
            }
            Module::Sci => {
                let ($p, $outside) = (&mut $mcu.sci, ());
                $body
            }
            Module::Ports => {
                let $p = &mut $mcu.ports;
                let $outside = PortPins {
                    board: &mut $mcu.board,
                    itu: &mut $mcu.itu,
                };
                $body
            }
            Module::Adc => {
                let ($p, $outside) = (&mut $mcu.adc, &mut $mcu.board);
                $body
            }
            Module::Intc => {
                let ($p, $outside) = (&mut $mcu.intc, ());
                $body
            }
            Module::Wdt => {
                let ($p, $outside) = (&mut $mcu.wdt, ());
                $body
            }
            Module::Irq => {
                let $p = &mut $mcu.irq;
                let $outside = irq::IrqView {
                    ports: &$mcu.ports,
                    board: &$mcu.board,
                };
                $body
            }
            Module::Unmodelled => $none,
        }
    };
}

/// `$body` for each module of `$mcu` in turn, with `$p` bound to it by shared reference (for
/// the questions that need nothing outside the module), the answers combined left to right
/// with `$combine`. Unrolled, so that the answers of modules with nothing to say fold away.
macro_rules! fold_modules {
    ($mcu:ident, |$p:ident| $body:expr, $combine:expr) => {{
        let combine = $combine;
        let all = {
            let $p = &$mcu.itu;
            $body
        };
        let all = combine(all, {
            let $p = &$mcu.adc;
            $body
        });
        let all = combine(all, {
            let $p = &$mcu.sci;
            $body
        });
        let all = combine(all, {
            let $p = &$mcu.ports;
            $body
        });
        let all = combine(all, {
            let $p = &$mcu.intc;
            $body
        });
        let all = combine(all, {
            let $p = &$mcu.wdt;
            $body
        });
        combine(all, {
            let $p = &$mcu.irq;
            $body
        })
    }};
}

/// The earlier of two instants, if any.
#[inline]
fn earliest(a: Option<u64>, b: Option<u64>) -> Option<u64> {
    match (a, b) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (x, None) => x,
        (None, y) => y,
    }
}

impl<B: Board> Mcu<B> {
    /// An MCU after reset with `board` outside it.
    ///
    /// # Errors
    /// [`McuError::InvalidClock`] if `config.clock_hz` is outside
    /// [`MIN_CLOCK_HZ`]..=[`MAX_CLOCK_HZ`].
    pub fn new(config: McuConfig, board: B) -> Result<Self, McuError> {
        config.validate()?;
        Ok(Mcu {
            now: 0,
            clock_hz: config.clock_hz,
            rom: None,
            rom_generation: fresh_code_generation(),
            ram: None,
            sci: Sci::new(),
            itu: Itu::new(),
            adc: Adc::new(),
            intc: Intc::new(),
            ports: Ports::new(),
            wdt: Wdt::new(),
            irq: Irq::new(),
            board,
            io_reports: Vec::new(),
            io_seen: [0; 4],
            io_break: false,
            break_pending: false,
            resets: 0,
            irq_cached: Cell::new(None),
            irq_valid_until: Cell::new(0),
            tracer: None,
        })
        .map(|mut m: Mcu<B>| {
            m.irq.reset(0, &m.ports, &m.board);
            m
        })
    }

    /// The board outside the chip.
    #[must_use]
    pub fn board(&self) -> &B {
        &self.board
    }

    /// The board, mutably (the world updates what the sensors see).
    pub fn board_mut(&mut self) -> &mut B {
        &mut self.board
    }

    /// φ in Hz.
    #[must_use]
    pub const fn clock_hz(&self) -> u32 {
        self.clock_hz
    }

    /// SCI1 (the console).
    #[must_use]
    pub fn sci(&self) -> &Sci {
        &self.sci
    }

    /// SCI1, mutably (to collect console output).
    pub fn sci_mut(&mut self) -> &mut Sci {
        self.invalidate_irq();
        &mut self.sci
    }

    /// The ITU (read-only view; use the bus to program it).
    #[must_use]
    pub fn itu(&self) -> &Itu {
        &self.itu
    }

    /// The A/D converter (read-only view).
    #[must_use]
    pub fn adc(&self) -> &Adc {
        &self.adc
    }

    /// The interrupt controller (read-only view).
    #[must_use]
    pub fn intc(&self) -> &Intc {
        &self.intc
    }

    /// Whether the flash holds an image (or poked bytes).
    #[must_use]
    pub fn has_flash(&self) -> bool {
        self.rom.is_some()
    }

    /// Whether the RAM has been written since reset or the last power cut.
    #[must_use]
    pub fn has_ram(&self) -> bool {
        self.ram.is_some()
    }

    /// The flash, for writing (loading an image, poking): every caller may change it, so the
    /// CPU's decoded copies of it are out of date from here on.
    fn rom_mut(&mut self) -> &mut Flash {
        self.rom_generation = fresh_code_generation();
        self.rom.get_or_insert_with(Flash::erased)
    }

    #[inline]
    fn ram_mut(&mut self) -> &mut [u8; RAM_BYTES as usize] {
        self.ram.get_or_insert_with(new_zeroed_ram)
    }

    /// Programs `image` into the flash (nothing is written if any chunk lies outside it). The
    /// flash is allocated, erased (H'FF), on the first load.
    ///
    /// # Errors
    /// [`LoadError`] if the image has data outside the flash or none at all.
    pub fn load_image(&mut self, image: &SrecImage) -> Result<(), LoadError> {
        check_image(image)?;
        self.rom_mut().program(image);
        Ok(())
    }

    /// Makes `flash` this MCU's flash (its pages shared with `flash` until this MCU writes one):
    /// what [`Mcu::load_image`] gives for the image `flash` holds, without a copy per MCU.
    pub fn load_flash(&mut self, flash: &Flash) {
        self.rom_generation = fresh_code_generation();
        self.rom = Some(flash.clone());
    }

    /// Writes bytes into flash or RAM directly (no bus cycle, no time): test set-up. Bytes at
    /// addresses outside flash and RAM are ignored.
    pub fn poke(&mut self, addr: u32, bytes: &[u8]) {
        for (i, &b) in bytes.iter().enumerate() {
            let a = addr.wrapping_add(i as u32) & ADDRESS_MASK;
            match Area::of(a) {
                Area::Rom => self.rom_mut().set(a as usize & ROM_INDEX_MASK, b),
                Area::Ram => self.ram_mut()[(a - RAM_START) as usize & RAM_INDEX_MASK] = b,
                _ => {}
            }
        }
    }

    /// Reads a byte of flash or RAM directly (no bus cycle, no time); other areas read H'FF.
    #[must_use]
    pub fn peek(&self, addr: u32) -> u8 {
        let a = addr & ADDRESS_MASK;
        match Area::of(a) {
            Area::Rom => self.rom_byte(a),
            Area::Ram => self.ram_byte(a),
            _ => 0xff,
        }
    }

    #[inline]
    fn rom_byte(&self, a: u32) -> u8 {
        match &self.rom {
            Some(r) => r.byte(a as usize & ROM_INDEX_MASK),
            None => 0xff,
        }
    }

    #[inline]
    fn ram_byte(&self, a: u32) -> u8 {
        match &self.ram {
            Some(r) => r[(a.wrapping_sub(RAM_START)) as usize & RAM_INDEX_MASK],
            None => 0,
        }
    }

    /// Lets the clock run to `t_states` (if later) without bus cycles, then synchronises every
    /// peripheral (the board is sampled for conversions that ended).
    pub fn advance_to(&mut self, t_states: u64) {
        if t_states > self.now {
            self.now = t_states;
        }
        self.sync();
    }

    /// Brings every peripheral and the board ([`Board::sync`]) up to the current clock.
    pub fn sync(&mut self) {
        let now = self.now;
        for m in Module::ALL {
            on_module!(
                self,
                m,
                |p, outside| Peripheral::sync::<B>(p, now, outside),
                ()
            );
        }
        self.board.sync(now);
        self.invalidate_irq();
    }

    /// The earliest state after now at which a peripheral next needs attention (an ITU compare
    /// match or overflow, an A/D sampling instant or conversion end, an SCI frame end) or the
    /// board's own parts do ([`Board::next_event_states`]: an EEPROM's write cycle end), if any.
    #[must_use]
    pub fn next_event(&self) -> Option<u64> {
        let now = self.now;
        earliest(
            fold_modules!(self, |p| Peripheral::next_event(p, now), earliest),
            self.board.next_event_states(now),
        )
    }

    /// The earliest state after now at which an enabled interrupt request (or the watchdog's
    /// reset request) appears: a module's, or a change of the pins the board drives while an
    /// IRQ is enabled.
    fn next_irq_time(&self) -> Option<u64> {
        let now = self.now;
        let modules = fold_modules!(self, |p| Peripheral::next_request(p, now), earliest);
        if self.irq.enabled() {
            earliest(modules, self.board.next_pin_change(now))
        } else {
            modules
        }
    }

    /// What ITU channel `n`'s TIOCA output does now (channels out of range: neither driving nor
    /// counting).
    pub fn tioca(&mut self, n: usize) -> TiocaOutput {
        let (level, drives) = self.itu.tioca(n, self.now);
        let wave = if drives && self.itu.running(n) {
            self.itu.pwm(n, level)
        } else {
            None
        };
        TiocaOutput {
            drives,
            level,
            wave,
        }
    }

    /// Levels of port A's pins now: TIOCA0–2 where the ITU drives them, else the output latch;
    /// input pins read 0 (port A has no pull-ups and nothing outside drives it here).
    pub fn port_a_pins(&mut self) -> u8 {
        self.ports.pa_pins(&mut self.itu, self.now)
    }

    /// Levels of port B's pins now: TIOCA3/TIOCA4 where the ITU drives them, else the output
    /// latch; input pins read 0.
    pub fn port_b_pins(&mut self) -> u8 {
        self.ports.pb_pins(&mut self.itu, self.now)
    }

    /// Starts a pin trace now ([`crate::trace`]): from here on every change of the traced
    /// signals is recorded at its instant, until [`Mcu::finish_trace`]. `cpu_sleeping` says
    /// whether the CPU is in sleep mode now (the CPU reports later changes itself through
    /// [`Bus::cpu_signal`]). A trace already under way is discarded.
    pub fn start_trace(&mut self, cpu_sleeping: bool) {
        let now = self.now;
        let tracer = Tracer::start(
            now,
            &self.itu,
            &self.adc,
            ChipView {
                ports: &self.ports,
                board: &mut self.board,
            },
            cpu_sleeping,
        );
        self.tracer = Some(Box::new(tracer));
    }

    /// Whether a pin trace is under way.
    #[must_use]
    pub fn tracing(&self) -> bool {
        self.tracer.is_some()
    }

    /// The last interrupt accepted during the trace under way, if any.
    #[must_use]
    pub fn trace_last_interrupt(&self) -> Option<Accepted> {
        self.tracer.as_ref().and_then(|t| t.last_accepted())
    }

    /// The pin trace under way: its first instant and every signal's level then.
    #[must_use]
    pub fn trace_beginning(&self) -> Option<(u64, [bool; crate::trace::SIGNAL_COUNT])> {
        self.tracer.as_ref().map(|t| t.beginning())
    }

    /// Changes of the pin trace under way recorded and not yet drained.
    #[must_use]
    pub fn trace_pending(&self) -> usize {
        self.tracer.as_ref().map_or(0, |t| t.pending())
    }

    /// Hands the pin trace's changes up to now to `sink`, a slice of at most `slice` states at
    /// a time (so a long stretch without a register write, e.g. a sleep with the PWM running,
    /// is never held whole): for each slice, the changes before its end and that end, below
    /// which the trace is final. The trace goes on; nothing it records changes.
    ///
    /// # Errors
    /// `sink`'s.
    pub fn drain_trace(
        &mut self,
        slice: u64,
        sink: &mut dyn FnMut(Vec<crate::trace::PinChange>, u64) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        let now = self.now;
        loop {
            let Some(t) = self.tracer.as_mut() else {
                return Ok(());
            };
            // A slice never ends before the board's own clock (its logged changes up to there
            // are taken whole).
            let to = t
                .caught_up()
                .saturating_add(slice.max(1))
                .max(self.board.now_states())
                .min(now);
            t.catch_up(
                to,
                ChipView {
                    ports: &self.ports,
                    board: &mut self.board,
                },
            );
            let changes = t.drain_before(to);
            sink(changes, to)?;
            if to >= now {
                return Ok(());
            }
        }
    }

    /// Ends the pin trace now and returns it (`None` when none was under way).
    pub fn finish_trace(&mut self) -> Option<PinTrace> {
        let mut tracer = self.tracer.take()?;
        let now = self.now;
        tracer.catch_up(
            now,
            ChipView {
                ports: &self.ports,
                board: &mut self.board,
            },
        );
        Some(tracer.finish(now, self.clock_hz, &mut self.board))
    }

    /// The CPU stopped for the break request after the instruction at `pc`: the reports
    /// made since get its address.
    #[cold]
    fn break_taken(&mut self, pc: u32) {
        for r in self.io_reports.iter_mut().rev() {
            if r.pc.is_some() {
                break;
            }
            r.pc = Some(pc);
        }
        self.break_pending = false;
        self.invalidate_irq();
    }

    /// A CPU signal for the trace under way.
    #[cold]
    fn trace_cpu_signal(&mut self, signal: CpuSignal) {
        self.trace_before_write();
        let now = self.now;
        if let Some(t) = self.tracer.as_mut() {
            match signal {
                CpuSignal::Sleep => t.set_sleeping(now, true, &self.ports),
                CpuSignal::Wake => t.set_sleeping(now, false, &self.ports),
                CpuSignal::Interrupt(v) => t.accepted(now, v),
                CpuSignal::Reset | CpuSignal::Break { .. } => {}
            }
        }
    }

    /// Before a write at `now` that may change a traced level: records what happened up to it.
    #[cold]
    fn trace_before_write(&mut self) {
        let now = self.now;
        if let Some(t) = self.tracer.as_mut() {
            t.catch_up(
                now,
                ChipView {
                    ports: &self.ports,
                    board: &mut self.board,
                },
            );
        }
    }

    /// After a write at `now` to `module`: records its effect.
    #[cold]
    fn trace_after_write(&mut self, module: Module) {
        let now = self.now;
        if let Some(t) = self.tracer.as_mut() {
            t.after_write(
                now,
                (module == Module::Itu).then_some(&self.itu),
                (module == Module::Adc).then_some(&self.adc),
                ChipView {
                    ports: &self.ports,
                    board: &mut self.board,
                },
            );
        }
    }

    /// Cuts the robot's power now: the board's parts lose power ([`Board::power_cut`]; on the
    /// robot, an EEPROM write cycle under way is corrupted as the `eeprom` crate models it),
    /// the RAM loses its contents and every peripheral returns to its reset state (ports
    /// released). The flash keeps its image. The clock keeps running.
    pub fn power_cut(&mut self) {
        self.board.power_cut(self.now);
        self.reset_peripherals();
        self.ram = None;
    }

    /// Powers the robot on at `at_states` (the clock jumps there if it is later): the board's
    /// parts power up ([`Board::power_on`]), the peripherals are in their reset state. The
    /// caller resets the CPU (or restarts the controller program).
    pub fn power_on(&mut self, at_states: u64) {
        self.now = self.now.max(at_states);
        self.board.power_on(self.now);
        self.reset_peripherals();
    }

    fn reset_peripherals(&mut self) {
        if self.tracer.is_some() {
            self.trace_before_write();
        }
        for m in Module::ALL {
            on_module!(self, m, |p, _outside| Peripheral::reset(p), ());
        }
        self.irq.reset(self.now, &self.ports, &self.board);
        self.invalidate_irq();
        if self.tracer.is_some() {
            self.trace_after_write(Module::Itu);
            self.trace_after_write(Module::Adc);
        }
    }

    /// The watchdog's internal reset, taken by the CPU now (module docs): every module to its
    /// reset state but the WDT's RSTCSR, port 4's lines released, the clock to the reset's end.
    #[cold]
    fn internal_reset(&mut self) {
        // Everything up to the reset happens first (a byte SCI1 has finished sending is out;
        // the WDT has set WRST).
        self.sync();
        let now = self.now;
        let end = self.wdt.reset_end().unwrap_or(now).max(now);
        let wdt = self.wdt.clone();
        self.reset_peripherals();
        self.wdt = wdt;
        self.wdt.internal_reset(now);
        self.board.port4_drive(self.ports.port4().driven_low(), now);
        self.now = end;
        self.resets += 1;
        self.invalidate_irq();
    }

    /// Internal resets so far (the watchdog's, [`crate::periph::wdt`]).
    #[must_use]
    pub const fn resets(&self) -> u64 {
        self.resets
    }

    /// The watchdog timer (read-only view; use the bus to program it).
    #[must_use]
    pub fn wdt(&self) -> &Wdt {
        &self.wdt
    }

    /// The IRQ inputs (read-only view).
    #[must_use]
    pub fn irq(&self) -> &Irq {
        &self.irq
    }

    /// The ports' registers (read-only view).
    #[must_use]
    pub fn ports(&self) -> &Ports {
        &self.ports
    }

    /// Levels of port `id`'s pins now: output pins at their latch (or at the ITU's output on
    /// ports A and B), input pins as the board leaves them (a pull-up, else 0); for a board
    /// that watches the chip's outputs ([`crate::pins::Board::port_pins`] is the other way).
    /// Port 2 and 4 give their latch and pull-ups only.
    pub fn port_pins(&mut self, id: PortId) -> u8 {
        let now = self.now;
        match id {
            PortId::PA => self.ports.pa_pins(&mut self.itu, now),
            PortId::PB => self.ports.pb_pins(&mut self.itu, now),
            _ => {
                let outside = self.board.port_pins(id, now);
                self.ports.levels(id, outside)
            }
        }
    }

    /// The reports of first accesses to addresses the chip does not model, in order
    /// ([`IoReport`]).
    #[must_use]
    pub fn io_reports(&self) -> &[IoReport] {
        &self.io_reports
    }

    /// Turns break requests on (or off, the default): with them on, the first access to an
    /// address the chip does not model asks the CPU to stop before its next instruction
    /// ([`BREAK_REQUEST`]; the CPU returns [`h8300h::cpu::Event::Break`]), and the report gets
    /// the instruction's address when it does.
    pub fn set_io_break(&mut self, on: bool) {
        self.io_break = on;
        if !on {
            self.break_pending = false;
        }
        self.invalidate_irq();
    }

    /// An access to I/O address `a` that no module models: the first one is reported.
    #[cold]
    #[inline(never)]
    fn unmodelled_io(&mut self, a: u32, write: bool) {
        let low = (a & 0xFF) as usize;
        let bit = 1u64 << (low & 63);
        if self.io_seen[low >> 6] & bit != 0 {
            return;
        }
        self.io_seen[low >> 6] |= bit;
        self.report_io(a, write);
    }

    /// An access to an address outside the memory map: the first one to each is reported (at
    /// most [`MAX_UNMAPPED_REPORTS`] such).
    #[cold]
    #[inline(never)]
    fn unmapped_access(&mut self, a: u32, write: bool) {
        let mut n = 0;
        for r in &self.io_reports {
            if r.register.is_none() && Area::of(r.addr) == Area::Unmapped {
                if r.addr == a {
                    return;
                }
                n += 1;
            }
        }
        if n < MAX_UNMAPPED_REPORTS {
            self.report_io(a, write);
        }
    }

    fn report_io(&mut self, a: u32, write: bool) {
        self.io_reports.push(IoReport {
            addr: a,
            register: register_at(a),
            write,
            at: self.now,
            pc: None,
        });
        if self.io_break {
            self.break_pending = true;
            self.invalidate_irq();
        }
    }

    #[inline]
    fn invalidate_irq(&self) {
        self.irq_valid_until.set(0);
    }

    /// Before a write that changes the interrupt decision: forget the cached decision and
    /// catch up the ITU channels that can request, so recomputing it is cheap.
    #[inline]
    fn before_irq_write(&mut self) {
        self.invalidate_irq();
        self.itu.sync_irq_sources(self.now);
    }

    /// Recomputes the pending interrupt and how long it stays valid.
    #[cold]
    fn refresh_irq(&self) -> Option<u8> {
        let now = self.now;
        if self.break_pending {
            // Asked at every boundary until the CPU takes it.
            self.irq_cached.set(Some(BREAK_REQUEST));
            self.irq_valid_until.set(now);
            return Some(BREAK_REQUEST);
        }
        if self.irq.enabled() {
            self.irq.catch_up(now, &self.ports, &self.board);
        }
        let requests = fold_modules!(self, |p| Peripheral::requests(p, now), |a, b| a | b);
        let winner = self.intc.choose(requests);
        let valid_until = match self.next_irq_time() {
            Some(t) if t > now => t,
            Some(_) => now, // recompute at every call until something changes
            None => u64::MAX,
        };
        self.irq_cached.set(winner);
        self.irq_valid_until.set(valid_until);
        winner
    }

    #[inline]
    fn io_read8(&mut self, a: u32) -> u8 {
        // Reads catch modules up but change no request (flags clear only by writes), so the
        // cached interrupt decision stays valid.
        let now = self.now;
        on_module!(
            self,
            Module::of(a),
            |p, outside| Peripheral::read::<B>(p, a, now, outside),
            {
                self.unmodelled_io(a, false);
                0
            }
        )
    }

    #[inline]
    fn io_write8(&mut self, a: u32, v: u8) {
        let now = self.now;
        let module = Module::of(a);
        if module.affects_irq() {
            self.before_irq_write();
        }
        if self.tracer.is_some() {
            self.trace_before_write();
        }
        if module == Module::Ports && irq::is_irq_port_register(a) {
            self.port_write_irq(a, v);
        } else {
            on_module!(
                self,
                module,
                |p, outside| Peripheral::write::<B>(p, a, v, now, outside),
                self.unmodelled_io(a, true)
            );
        }
        if self.tracer.is_some() {
            self.trace_after_write(module);
        }
    }

    /// A write to port 8's or 9's DDR or DR, whose pins are IRQ inputs: the IRQ flags are
    /// caught up to the write and see the pins' new levels at its instant.
    #[cold]
    fn port_write_irq(&mut self, a: u32, v: u8) {
        let now = self.now;
        self.irq.catch_up(now, &self.ports, &self.board);
        Peripheral::write::<B>(
            &mut self.ports,
            a,
            v,
            now,
            PortPins {
                board: &mut self.board,
                itu: &mut self.itu,
            },
        );
        self.irq.after_port_write(now, &self.ports, &self.board);
        self.invalidate_irq();
    }
}

/// Checks that `image` has data and that all of it lies inside the flash.
///
/// # Errors
/// [`LoadError`] if the image has data outside the flash or none at all.
pub fn check_image(image: &SrecImage) -> Result<(), LoadError> {
    if image.data_len() == 0 {
        return Err(LoadError::Empty);
    }
    for c in &image.chunks {
        let end = u64::from(c.address) + c.data.len() as u64;
        if end > u64::from(ROM_BYTES) {
            return Err(LoadError::OutsideFlash {
                address: c.address,
                len: c.data.len(),
            });
        }
    }
    Ok(())
}

#[cold]
fn new_zeroed_ram() -> Box<[u8; RAM_BYTES as usize]> {
    Box::new([0u8; RAM_BYTES as usize])
}

impl<B: Board> Bus for Mcu<B> {
    #[inline]
    fn now(&self) -> u64 {
        self.now
    }

    #[inline]
    fn read8(&mut self, addr: u32) -> u8 {
        let a = addr & ADDRESS_MASK;
        let area = Area::of(a);
        self.now += u64::from(area.byte_states());
        match area {
            Area::Rom => self.rom_byte(a),
            Area::Ram => self.ram_byte(a),
            Area::Io => self.io_read8(a),
            Area::Unmapped => {
                self.unmapped_access(a, false);
                0xff
            }
        }
    }

    #[inline]
    fn read16(&mut self, addr: u32) -> u16 {
        let a = addr & ADDRESS_MASK & !1;
        match Area::of(a) {
            Area::Rom => {
                self.now += u64::from(Area::Rom.word_states());
                match &self.rom {
                    Some(r) => r.word(a as usize & ROM_INDEX_MASK),
                    None => 0xffff,
                }
            }
            Area::Ram => {
                self.now += u64::from(Area::Ram.word_states());
                match &self.ram {
                    Some(r) => {
                        let i = (a - RAM_START) as usize & RAM_INDEX_MASK & !1;
                        u16::from_be_bytes([r[i], r[i | 1]])
                    }
                    None => 0,
                }
            }
            Area::Io => {
                if itu::is_word_register(a) || wdt::is_word_register(a) {
                    // One cycle on the ITU's (the WDT's) 16-bit internal bus.
                    self.now += u64::from(itu::ITU_WORD_ACCESS_STATES);
                    let hi = self.io_read8(a);
                    let lo = self.io_read8(a + 1);
                    u16::from_be_bytes([hi, lo])
                } else {
                    // Two byte cycles on the 8-bit bus, upper byte first.
                    self.now += u64::from(IO_ACCESS_STATES);
                    let hi = self.io_read8(a);
                    self.now += u64::from(IO_ACCESS_STATES);
                    let lo = self.io_read8(a + 1);
                    u16::from_be_bytes([hi, lo])
                }
            }
            Area::Unmapped => {
                self.now += u64::from(Area::Unmapped.word_states());
                self.unmapped_access(a, false);
                0xffff
            }
        }
    }

    #[inline]
    fn write8(&mut self, addr: u32, value: u8) {
        let a = addr & ADDRESS_MASK;
        let area = Area::of(a);
        self.now += u64::from(area.byte_states());
        match area {
            Area::Ram => self.ram_mut()[(a - RAM_START) as usize & RAM_INDEX_MASK] = value,
            Area::Io => self.io_write8(a, value),
            // Flash is not writable through the bus.
            Area::Rom => {}
            // Nothing answers unmapped addresses.
            Area::Unmapped => self.unmapped_access(a, true),
        }
    }

    #[inline]
    fn write16(&mut self, addr: u32, value: u16) {
        let a = addr & ADDRESS_MASK & !1;
        let [hi, lo] = value.to_be_bytes();
        match Area::of(a) {
            Area::Ram => {
                self.now += u64::from(Area::Ram.word_states());
                let i = (a - RAM_START) as usize & RAM_INDEX_MASK & !1;
                let r = self.ram_mut();
                r[i] = hi;
                r[i | 1] = lo;
            }
            Area::Io => {
                if itu::is_word_register(a) {
                    self.now += u64::from(itu::ITU_WORD_ACCESS_STATES);
                    self.before_irq_write();
                    if self.tracer.is_some() {
                        self.trace_before_write();
                    }
                    self.itu.write16(a, value, self.now);
                    if self.tracer.is_some() {
                        self.trace_after_write(Module::Itu);
                    }
                } else if wdt::is_word_register(a) {
                    // The WDT's password words: one cycle, the word as a whole.
                    self.now += u64::from(wdt::WDT_WORD_ACCESS_STATES);
                    self.before_irq_write();
                    self.wdt.write16(a, value, self.now);
                } else {
                    self.now += u64::from(IO_ACCESS_STATES);
                    self.io_write8(a, hi);
                    self.now += u64::from(IO_ACCESS_STATES);
                    self.io_write8(a + 1, lo);
                }
            }
            Area::Rom => self.now += u64::from(Area::Rom.word_states()),
            Area::Unmapped => {
                self.now += u64::from(Area::Unmapped.word_states());
                self.unmapped_access(a, true);
            }
        }
    }

    #[inline]
    fn internal(&mut self, states: u32) {
        self.now += u64::from(states);
    }

    #[inline]
    fn pending_irq(&self) -> Option<u8> {
        if self.now < self.irq_valid_until.get() {
            self.irq_cached.get()
        } else {
            self.refresh_irq()
        }
    }

    /// Tells a pin trace under way (SLEEP, and the accepted interrupts); takes the reset
    /// (module docs), withdraws a break request (the reports get the instruction's address),
    /// and clears an IRQ flag whose exception handling begins.
    #[inline]
    fn cpu_signal(&mut self, signal: CpuSignal) {
        match signal {
            CpuSignal::Reset => self.internal_reset(),
            CpuSignal::Break { pc } => self.break_taken(pc),
            CpuSignal::Interrupt(v) if (irq::VECTOR_IRQ0..irq::VECTOR_IRQ0 + 6).contains(&v) => {
                self.irq.accepted(v);
                self.invalidate_irq();
            }
            _ => {}
        }
        if self.tracer.is_some() {
            self.trace_cpu_signal(signal);
        }
    }

    /// Moves the clock to the next instant a request can appear, again while none does (a pin
    /// the board drives may change without requesting: a rising edge, a disabled IRQ), up to
    /// `deadline`.
    fn sleep_until_irq(&mut self, deadline: u64) -> bool {
        loop {
            if self.pending_irq().is_some() {
                return true;
            }
            match self.next_irq_time() {
                Some(t) if t <= deadline && t > self.now => {
                    self.now = t;
                    self.sync();
                }
                Some(t) if t <= self.now => return false,
                _ => {
                    if deadline != u64::MAX {
                        self.now = self.now.max(deadline);
                        self.sync();
                    }
                    return false;
                }
            }
        }
    }
}

impl<B: Board> FastPathHints for Mcu<B> {
    /// Fetching from flash or RAM touches no device, and the token changes at every write to
    /// the flash ([`Mcu::load_image`], [`Mcu::poke`]).
    #[inline]
    fn code_generation(&self) -> Option<u64> {
        Some(self.rom_generation)
    }

    /// The cached interrupt decision's end: the next instant a module raises a request
    /// ([`Mcu::next_event`]'s requesting part); writes to I/O empty the cache.
    #[inline]
    fn irq_stable_until(&self) -> u64 {
        if self.now >= self.irq_valid_until.get() {
            self.refresh_irq();
        }
        self.irq_valid_until.get()
    }

    /// ROM and RAM change only by writes (no DMA here): for ever. The A/D converter's
    /// registers change only at its own events (a sample, a conversion's end): until the
    /// next. Re-reading any of these changes nothing more than the first read did (reading
    /// ADCSR with ADF = 1 arms the flag's clearing once; reading ADDRnH latches the same low
    /// byte). Every other register: unknown.
    fn reads_stable_until(&self, addr: u32) -> Option<u64> {
        let a = addr & ADDRESS_MASK;
        match Area::of(a) {
            Area::Rom | Area::Ram => Some(u64::MAX),
            Area::Io if (ADDRA..=ADCR).contains(&a) => {
                Some(self.adc.next_event(self.now).unwrap_or(u64::MAX))
            }
            _ => None,
        }
    }

    /// The ITU's state relative to now ([`Itu::idle_signature`]), when every other module is
    /// quiet: the A/D converter, SCI1 and the board's parts (the EEPROMs) have nothing under
    /// way (no event to come), so that without accesses their state stays as it is and they
    /// request nothing new. `None` while a pin trace is recorded (it must see every cycle) or a
    /// module or the board is busy.
    fn idle_signature(&mut self) -> Option<Vec<u64>> {
        let now = self.now;
        if self.tracer.is_some()
            || self.adc.next_event(now).is_some()
            || Peripheral::next_event(&self.sci, now).is_some()
            || Peripheral::next_event(&self.ports, now).is_some()
            || Peripheral::next_event(&self.intc, now).is_some()
            || self.board.next_event_states(now).is_some()
            || (self.irq.enabled() && self.board.next_pin_change(now).is_some())
        {
            return None;
        }
        let mut out = Vec::with_capacity(80);
        self.itu.idle_signature(now, &mut out);
        Some(out)
    }

    /// The watchdog's next request (an overflow of a running counter): the signature leaves
    /// the WDT out — it counts on in absolute time whatever the cycles do, and the program may
    /// not touch it in a cycle ([`FastPathHints::idle_io`]) — so no cycle is advanced past it.
    fn idle_horizon(&self) -> u64 {
        Peripheral::next_request(&self.wdt, self.now).unwrap_or(u64::MAX)
    }

    /// The ITU's registers: the only ones [`FastPathHints::idle_signature`] covers.
    fn idle_io(&self, addr: u32) -> bool {
        Module::of(addr & ADDRESS_MASK) == Module::Itu
    }

    /// The clock and the ITU move `states` ahead; the other modules, quiet, catch up lazily;
    /// `ram` is stored as by [`Mcu::poke`]. Refused (nothing done) while a pin trace is
    /// recorded or when an address of `ram` is not in RAM.
    fn idle_shift(&mut self, states: u64, ram: &[(u32, u32)]) -> bool {
        if self.tracer.is_some()
            || ram
                .iter()
                .any(|&(a, _)| (0..4).any(|i| Area::of((a + i) & ADDRESS_MASK) != Area::Ram))
        {
            return false;
        }
        for &(a, v) in ram {
            self.poke(a, &v.to_be_bytes());
        }
        self.now += states;
        self.itu.shift(states);
        self.invalidate_irq();
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::periph::adc;
    use crate::pins::NullBoard;

    fn mcu() -> Mcu<NullBoard> {
        Mcu::new(McuConfig::default(), NullBoard).unwrap()
    }

    #[test]
    fn clock_out_of_range_is_an_error() {
        for hz in [0, MIN_CLOCK_HZ - 1, MAX_CLOCK_HZ + 1] {
            let e = Mcu::new(McuConfig { clock_hz: hz }, NullBoard).unwrap_err();
            assert_eq!(e, McuError::InvalidClock { clock_hz: hz });
            assert!(e.to_string().contains("2000000..=25000000"), "{e}");
        }
        let m = Mcu::new(
            McuConfig {
                clock_hz: 16_000_000,
            },
            NullBoard,
        )
        .unwrap();
        assert_eq!(m.clock_hz(), 16_000_000);
    }

    #[test]
    fn memory_is_allocated_lazily() {
        let mut m = mcu();
        assert!(!m.has_flash() && !m.has_ram());
        assert_eq!(m.read16(0x100), 0xFFFF);
        assert_eq!(m.read8(RAM_START + 10), 0);
        assert!(!m.has_flash() && !m.has_ram());
        m.write16(RAM_START + 10, 0x1234);
        assert!(m.has_ram());
        assert_eq!(m.read16(RAM_START + 10), 0x1234);
        // Flash is not writable through the bus.
        m.write8(0x100, 0);
        assert!(!m.has_flash());
        m.poke(0x100, &[1, 2]);
        assert!(m.has_flash());
        assert_eq!(m.read16(0x100), 0x0102);
        assert_eq!(m.peek(0x102), 0xFF);
    }

    #[test]
    fn io_words_cost_two_cycles_but_itu_words_one() {
        let mut m = mcu();
        let t = m.now();
        m.read16(adc::ADDRA);
        assert_eq!(m.now() - t, 6);
        let t = m.now();
        m.read16(0xFF_FF68); // TCNT0
        assert_eq!(m.now() - t, 3);
        let t = m.now();
        m.write16(0xFF_FF6A, 0x1234); // GRA0
        assert_eq!(m.now() - t, 3);
        assert_eq!(m.read16(0xFF_FF6A), 0x1234);
        let t = m.now();
        m.read8(itu::TSTR);
        assert_eq!(m.now() - t, 3);
    }

    #[test]
    fn syscr_and_unmodelled_registers() {
        use crate::periph::intc::{SYSCR, SYSCR_RESET};
        let mut m = mcu();
        assert_eq!(m.read8(SYSCR), SYSCR_RESET);
        m.write8(SYSCR, 0x09);
        assert_eq!(m.read8(SYSCR), 0x09);
        // P1DDR: modelled now (write-only, reads H'FF); nothing reported.
        assert_eq!(m.read8(0xFF_FFC0), 0xFF);
        assert!(m.io_reports().is_empty());
        // MAR0AR (the DMAC's): reads 0, ignores writes, reported once per address.
        assert_eq!(m.read8(0xFF_FF20), 0);
        m.write8(0xFF_FF20, 0x12);
        assert_eq!(m.read8(0xFF_FF20), 0);
        // BRCR (bus controller) inside the interrupt controller's block; a reserved address;
        // outside the memory map (a word: one report of its address).
        m.write8(0xFF_FFF3, 1);
        assert_eq!(m.read8(0xFF_FF1C), 0);
        assert_eq!(m.read16(0x10_0000), 0xFFFF);
        m.write16(0x10_0000, 1);
        let r = m.io_reports();
        assert_eq!(r.len(), 4, "{r:?}");
        assert_eq!(r[0].register.map(|x| x.name), Some("MAR0AR"));
        assert!(!r[0].write);
        assert_eq!(r[1].register.map(|x| x.name), Some("BRCR"));
        assert!(r[1].write);
        assert_eq!(r[2].register, None);
        assert_eq!(r[2].addr, 0xFF_FF1C);
        assert_eq!(r[3].addr, 0x10_0000);
        assert!(r.iter().all(|x| x.pc.is_none()));
        assert_eq!(
            r[0].describe(Some("main")),
            "state 15: reads MAR0AR (H'FFFF20) of the DMA controller (DMAC), not modelled (it reads 0)"
        );
        assert!(
            r[2].describe(None).contains("a reserved I/O address"),
            "{}",
            r[2].describe(None)
        );
        assert!(r[3].describe(None).contains("outside the memory map"));
        // Breaks: a first access raises a break request until the CPU takes it.
        assert_eq!(m.pending_irq(), None);
        m.set_io_break(true);
        m.write8(0xFF_FFB0, 0); // SMR0 (SCI0)
        assert_eq!(m.pending_irq(), Some(BREAK_REQUEST));
        m.cpu_signal(CpuSignal::Break { pc: 0x1234 });
        assert_eq!(m.pending_irq(), None);
        assert_eq!(m.io_reports()[4].pc, Some(0x1234));
        assert_eq!(m.io_reports()[4].register.map(|x| x.name), Some("SMR0"));
        // Already reported: no new break.
        m.write8(0xFF_FFB0, 0);
        assert_eq!(m.pending_irq(), None);
    }

    #[test]
    fn every_io_address_is_modelled_or_reported() {
        // The chip's routes agree with the register table: an address a module models is a
        // register of that module's unit; every other one is reported.
        use crate::iomap::Unit;
        for a in h8300h::memmap::IO_START..=h8300h::memmap::IO_END {
            let reg = register_at(a);
            let module = Module::of(a);
            let unit = reg.map(|r| r.unit);
            let expected = match module {
                Module::Itu => Some(Unit::Itu),
                Module::Sci => Some(Unit::Sci1),
                Module::Ports => Some(Unit::Ports),
                Module::Adc => Some(Unit::Ad),
                Module::Wdt => Some(Unit::Wdt),
                Module::Intc | Module::Irq => Some(Unit::Intc),
                Module::Unmodelled => {
                    let mut m = mcu();
                    m.read8(a);
                    assert_eq!(m.io_reports().len(), 1, "H'{a:06X}");
                    continue;
                }
            };
            assert_eq!(unit, expected, "H'{a:06X} routed to {module:?}");
        }
    }
}
