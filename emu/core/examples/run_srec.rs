//! Runs an H8/300H program image (Motorola S-records) on the bare core with a bus of its own:
//! flat memory with the access states of the core's memory map, and a console port where a
//! byte written to H'FFFFBB (where the H8/3052F's SCI1 has its transmit data register) is
//! printed. The program ends when it halts (SLEEP with interrupts masked); nothing raises an
//! interrupt on this bus.
//!
//! ```text
//! cargo run -p h8300h --example run_srec -- emu/tests/programs/arith.mot [--trace]
//! ```
//!
//! `--trace` prints every instruction with its address and the states it took.

use std::io::Write;
use std::process::ExitCode;

use h8300h::bus::{Bus, NoHints};
use h8300h::cpu::disasm::format_instr;
use h8300h::cpu::{Cpu, Event};
use h8300h::memmap::{ADDRESS_MASK, Area};
use h8300h::srec;

/// Where a written byte goes to the console.
const CONSOLE_DATA: u32 = 0xFF_FFBB;
/// A status register the program polls before writing a byte: it always reads "ready"
/// (H'84: transmit data register empty, transmission ended).
const CONSOLE_STATUS: u32 = 0xFF_FFBC;
const CONSOLE_READY: u8 = 0x84;
/// Give up after this many states.
const STATE_BUDGET: u64 = 250_000_000;

/// The whole 16 MB address space as one array, a clock, and the console's output.
struct FlatBus {
    mem: Vec<u8>,
    now: u64,
    console: Vec<u8>,
}

impl FlatBus {
    fn new() -> Self {
        FlatBus {
            mem: vec![0; (ADDRESS_MASK + 1) as usize],
            now: 0,
            console: Vec::new(),
        }
    }
}

impl Bus for FlatBus {
    fn now(&self) -> u64 {
        self.now
    }

    fn read8(&mut self, addr: u32) -> u8 {
        let a = addr & ADDRESS_MASK;
        self.now += u64::from(Area::of(a).byte_states());
        if a == CONSOLE_STATUS {
            return CONSOLE_READY;
        }
        self.mem[a as usize]
    }

    fn read16(&mut self, addr: u32) -> u16 {
        let a = addr & ADDRESS_MASK & !1;
        self.now += u64::from(Area::of(a).word_states());
        u16::from_be_bytes([self.mem[a as usize], self.mem[a as usize + 1]])
    }

    fn write8(&mut self, addr: u32, value: u8) {
        let a = addr & ADDRESS_MASK;
        self.now += u64::from(Area::of(a).byte_states());
        if a == CONSOLE_DATA {
            self.console.push(value);
        }
        self.mem[a as usize] = value;
    }

    fn write16(&mut self, addr: u32, value: u16) {
        let a = addr & ADDRESS_MASK & !1;
        self.now += u64::from(Area::of(a).word_states());
        let [hi, lo] = value.to_be_bytes();
        self.mem[a as usize] = hi;
        self.mem[a as usize + 1] = lo;
    }

    fn internal(&mut self, states: u32) {
        self.now += u64::from(states);
    }

    fn pending_irq(&self) -> Option<u8> {
        None
    }

    fn sleep_until_irq(&mut self, deadline: u64) -> bool {
        // Nothing here ever requests an interrupt: sleep to the deadline.
        self.now = self.now.max(deadline);
        false
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let trace = args.iter().any(|a| a == "--trace");
    let Some(path) = args.iter().find(|a| !a.starts_with("--")) else {
        eprintln!("usage: run_srec <image.mot> [--trace]");
        return ExitCode::from(2);
    };
    let text = match std::fs::read(path) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("{path}: {e}");
            return ExitCode::from(2);
        }
    };
    let image = match srec::parse(&text) {
        Ok(i) => i,
        Err(e) => {
            eprintln!("{path}: {e}");
            return ExitCode::from(2);
        }
    };
    let mut bus = FlatBus::new();
    for chunk in &image.chunks {
        let a = (chunk.address & ADDRESS_MASK) as usize;
        let end = (a + chunk.data.len()).min(bus.mem.len());
        bus.mem[a..end].copy_from_slice(&chunk.data[..end - a]);
    }

    let mut cpu = Cpu::new();
    cpu.reset(&mut bus);
    let mut printed = 0;
    let outcome = loop {
        let (pc, before) = (cpu.pc(), bus.now());
        // The flat bus makes no fast-path promises: NoHints runs the CPU on it as it is.
        let event = cpu.step(&mut NoHints(&mut bus), STATE_BUDGET);
        if trace && event == Ok(Event::Executed) {
            let line = format_instr(cpu.last_executed(), pc).replacen('\t', " ", 1);
            eprintln!("{pc:06x}: {line:<32} {:>3} states", bus.now() - before);
        }
        if bus.console.len() > printed {
            let mut out = std::io::stdout();
            let _ = out.write_all(&bus.console[printed..]);
            let _ = out.flush();
            printed = bus.console.len();
        }
        match event {
            Ok(Event::Executed | Event::Interrupt(_)) if bus.now() < STATE_BUDGET => {}
            Ok(Event::Halted) => break Ok(cpu.er(0) as u8),
            Ok(_) => break Err("the state budget ran out".to_string()),
            Err(e) => break Err(e.to_string()),
        }
    };
    eprintln!("{} instructions, {} states", cpu.instructions(), bus.now());
    match outcome {
        Ok(status) => {
            eprintln!("halted, R0L = {status}");
            ExitCode::from(status)
        }
        Err(e) => {
            eprintln!("stopped: {e}");
            ExitCode::from(1)
        }
    }
}
