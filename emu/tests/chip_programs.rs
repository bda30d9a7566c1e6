//! The chip's test programs (`tests/programs/chip/`, C built with `h8300-hms-gcc` by
//! `tests/programs/build.sh`): the watchdog (a program that is reset and sees WRST; the
//! watchdog counting through fast-forwarded loops and idle cycles), the IRQ inputs (driven by
//! the program's own port pin and by a board), registers the chip does not model (reported with
//! the instruction and its function), and a program of known call structure for the profile
//! (folded stacks that add up to the run's states).

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use h8_3052f::machine::Machine;
use h8_3052f::mcu::{Mcu, McuConfig};
use h8_3052f::periph::ports::{ExternalPins, PortId};
use h8_3052f::periph::wdt;
use h8_3052f::pins::{Board, NullBoard};
use h8_3052f::profile::StackProfile;
use h8_3052f::run::{Outcome, Probes, RunOptions, run_mcu_probed};
use h8_3052f::trace::CodeNames;
use h8300h::bus::Bus;
use h8300h::cpu::{Cpu, Event};
use h8300h::srec;
use robot_board::symbols::SymbolTable;

/// A chip program's image and symbols.
fn program(name: &str) -> (Vec<u8>, SymbolTable) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/programs/chip");
    let image = std::fs::read(dir.join(format!("{name}.mot")))
        .expect("the image (built by tests/programs/build.sh)");
    let sym = std::fs::read_to_string(dir.join(format!("{name}.sym"))).expect("its symbols");
    (image, SymbolTable::parse(&sym).expect("symbols parse"))
}

/// A machine with `image` loaded and the CPU reset.
fn boot(image: &[u8]) -> (Cpu, Machine) {
    let m = Machine::with_image(&srec::parse(image).unwrap()).unwrap();
    let mut m = m;
    let mut cpu = Cpu::new();
    cpu.reset(&mut m);
    (cpu, m)
}

/// Runs `name` to its end on a machine with nothing connected, with its symbols; returns the
/// console text and the report.
fn run(name: &str, options: &RunOptions) -> (String, h8_3052f::run::RunReport) {
    let (image, syms) = program(name);
    let (mut cpu, mut m) = boot(&image);
    let mut console = Vec::new();
    let report = run_mcu_probed(
        &mut cpu,
        m.mcu_mut(),
        options,
        &mut console,
        Probes {
            names: Some(&syms),
            ..Probes::default()
        },
    )
    .unwrap();
    (String::from_utf8(console).unwrap(), report)
}

fn budget(states: u64) -> RunOptions {
    RunOptions {
        max_states: Some(states),
        ..RunOptions::default()
    }
}

#[test]
fn the_watchdog_resets_a_program_that_stops_writing_it_and_the_program_sees_wrst() {
    let (image, syms) = program("wdt");
    // The RAM word that counts the starts lies above the program's data.
    assert!(syms.addr("_bss_end").unwrap() < 0xFF_E800);
    let (console, report) = run("wdt", &budget(50_000_000));
    assert_eq!(
        console,
        "boot=1\nwrst=0\ninterval_polled=3\nwovi=4\nkicked=5\nspinning\n\
         boot=2\nwrst=1\nfailures=0\nchecksum 4AB757A4\n"
    );
    assert_eq!(report.outcome, Outcome::Halted { exit_status: 0 });
    assert_eq!(report.stats.resets, 1);
    assert_eq!(report.stats.interrupts, 4, "the four WOVI interrupts");
    assert!(report.io_reports.is_empty(), "{:?}", report.io_reports);

    // The reset, step by step: requested from the overflow (a count edge of phi/4096), taken
    // at the next instruction boundary, and the CPU at the reset vector 518 states after the
    // overflow (then the vector's two word reads, 4 states).
    let (mut cpu, mut m) = boot(&image);
    let mut overflow = None;
    loop {
        if overflow.is_none() && m.pending_irq() == Some(h8300h::bus::RESET_REQUEST) {
            // The request appeared during the last instruction: the overflow was at most its
            // states ago, at a multiple of 4096.
            overflow = Some(m.now() / 4096 * 4096);
        }
        match cpu.step(&mut m, u64::MAX).unwrap() {
            Event::Reset => break,
            Event::Halted => panic!("halted before the reset"),
            _ => {}
        }
        assert!(m.now() < 50_000_000, "no reset");
    }
    let overflow = overflow.expect("the reset was requested before it was taken");
    assert_eq!(m.now(), overflow + wdt::RESET_STATES + 4);
    assert_eq!(cpu.pc(), 0xF4, "at the reset vector's target, _start");
    assert_eq!(m.resets(), 1);
    assert_eq!(m.wdt().rstcsr() & wdt::RSTCSR_WRST, wdt::RSTCSR_WRST);
}

/// Runs `image` on two machines, one stepping instruction by instruction and one with the
/// loop fast-forwarding and idle-cycle advancing a firmware robot gets (`run_until` and
/// `run_idle` in chunks), and compares the whole state at every chunk's end. Returns the
/// fast run's CPU and machine.
fn fast_against_stepping(image: &[u8], chunk: u64, until: u64) -> (Cpu, Mcu<NullBoard>) {
    let (mut ca, mut ma) = boot(image);
    // The MCU itself (a `Machine` makes no idle-cycle promises).
    let (mut cb, mb) = boot(image);
    let mut mb = mb.into_mcu();
    ca.set_fast_forward(false);
    let mut deadline = 0;
    while deadline < until {
        deadline += chunk;
        while ma.now() < deadline {
            match ca.step(&mut ma, deadline).unwrap() {
                Event::Halted | Event::Asleep => break,
                _ => {}
            }
        }
        while mb.now() < deadline {
            if cb.sleeping() {
                let idle = cb.run_idle(&mut mb, deadline, &mut |_, _| false).unwrap();
                if let Some(Event::Halted | Event::Asleep) = idle.end {
                    break;
                }
                if cb.sleeping() && !mb.sleep_until_irq(deadline) {
                    break;
                }
                continue;
            }
            match cb
                .run_until(&mut mb, deadline, |c, _| c.sleeping())
                .unwrap()
            {
                Event::Halted | Event::Asleep => break,
                _ => {}
            }
        }
        assert_eq!(ma.now(), mb.now(), "clock at the chunk ending {deadline}");
        assert_eq!(ca.regs(), cb.regs(), "registers at {deadline}");
        assert_eq!(
            (ca.pc(), ca.ccr()),
            (cb.pc(), cb.ccr()),
            "PC, CCR at {deadline}"
        );
        assert_eq!(
            ca.instructions(),
            cb.instructions(),
            "instructions at {deadline}"
        );
        assert_eq!(ma.resets(), mb.resets(), "resets at {deadline}");
        assert_eq!(
            ma.wdt().tcnt_at(ma.now()),
            mb.wdt().tcnt_at(mb.now()),
            "TCNT at {deadline}"
        );
        for a in (h8300h::memmap::RAM_START..=h8300h::memmap::RAM_END).step_by(4) {
            assert_eq!(ma.peek(a), mb.peek(a), "RAM H'{a:06X} at {deadline}");
        }
        if ca.halted() {
            break;
        }
    }
    (cb, mb)
}

#[test]
fn a_fast_forwarded_spin_loop_is_reset_by_the_watchdog_at_its_state() {
    // wdt.mot ends its first start in `for (;;) {}` with the watchdog counting: loop
    // fast-forwarding skips the spin up to the reset request, the reset comes at the same state
    // as stepping gives.
    let (image, _) = program("wdt");
    let (cpu, m) = fast_against_stepping(&image, 1_000_003, 8_000_000);
    assert!(cpu.halted());
    assert_eq!(m.resets(), 1);
    assert!(
        cpu.skipped_instructions() > 100_000,
        "the spin was skipped: {}",
        cpu.skipped_instructions()
    );
}

#[test]
fn idle_cycles_advance_the_watchdog_and_its_overflow_resets_at_its_state() {
    // idle_wdt.mot sleeps between ITU ticks while the watchdog counts to its overflow: idle
    // cycles are advanced in closed form up to the overflow, and the reset comes at the same
    // state as stepping gives (compared at every chunk's end, chunks of 100 ticks).
    let (image, _) = program("idle_wdt");
    let (cpu, m) = fast_against_stepping(&image, 200_001, 3_000_000);
    assert!(cpu.halted(), "the program ended after its reset");
    assert_eq!(m.resets(), 1);
    assert!(
        cpu.idle_cycles_skipped() > 100,
        "idle cycles were advanced: {}",
        cpu.idle_cycles_skipped()
    );
    let (console, report) = run("idle_wdt", &budget(10_000_000));
    assert_eq!(
        console,
        "idling\nreset by the watchdog\nfailures=0\nchecksum CA4306F0\n"
    );
    assert_eq!(report.outcome, Outcome::Halted { exit_status: 0 });
    assert_eq!(report.stats.resets, 1);
}

#[test]
fn irq0_from_the_programs_own_pin_edges_and_levels() {
    let (console, report) = run("irq", &budget(10_000_000));
    assert_eq!(
        report.outcome,
        Outcome::Halted { exit_status: 0 },
        "{console}"
    );
    assert!(
        console.starts_with("edges=5\nlevels=9\nfailures=0\n"),
        "{console}"
    );
    assert_eq!(report.stats.interrupts, 9);
}

/// A board that drives P8.0 (IRQ0) low at the instants of `falls` and high again 1 000 states
/// later.
#[derive(Clone, Debug)]
struct Pulses {
    falls: Vec<u64>,
}

impl Board for Pulses {
    fn analog_volts(&mut self, _channel: u8, _now: u64) -> f64 {
        0.0
    }
    fn port2_pins(&mut self, _now: u64) -> u8 {
        0xFF
    }
    fn port_pins(&self, port: PortId, now: u64) -> ExternalPins {
        if port != PortId::P8 {
            return ExternalPins::NONE;
        }
        let low = self.falls.iter().any(|&t| now >= t && now < t + 1000);
        ExternalPins {
            driven: 0x01,
            levels: u8::from(!low),
        }
    }
    fn next_pin_change(&self, now: u64) -> Option<u64> {
        self.falls
            .iter()
            .flat_map(|&t| [t, t + 1000])
            .filter(|&t| t > now)
            .min()
    }
}

#[test]
fn a_board_drives_irq0_and_wakes_the_sleeping_cpu_at_each_edge() {
    let (image, _) = program("irq_board");
    let falls = vec![400_000, 700_013, 1_000_501];
    let mut m = Mcu::new(
        McuConfig::default(),
        Pulses {
            falls: falls.clone(),
        },
    )
    .unwrap();
    m.load_image(&srec::parse(&image).unwrap()).unwrap();
    let mut cpu = Cpu::new();
    cpu.reset(&mut m);
    m.start_trace(false);
    let mut taken = Vec::new();
    let mut console = Vec::new();
    loop {
        match cpu.step(&mut m, 5_000_000).unwrap() {
            Event::Interrupt(12) => {
                taken.push(m.trace_last_interrupt().expect("traced").t);
            }
            Event::Halted => break,
            Event::Asleep => panic!("asleep at the deadline: {taken:?}"),
            _ => {}
        }
        console.extend_from_slice(m.sci().output());
        m.sci_mut().clear_output();
    }
    // Each falling edge wakes the CPU (asleep in `while (irqs < 3) sleep();`) and is taken at
    // once, at the edge's state.
    assert_eq!(taken, falls);
    assert!(
        String::from_utf8_lossy(&console).starts_with("irqs=3\n"),
        "{}",
        String::from_utf8_lossy(&console)
    );
}

#[test]
fn unmodelled_accesses_are_reported_with_the_instruction_and_its_function() {
    let (_, syms) = program("unmodelled");
    let (console, report) = run("unmodelled", &budget(10_000_000));
    assert_eq!(
        report.outcome,
        Outcome::Halted { exit_status: 0 },
        "{console}"
    );
    let lines: Vec<String> = report
        .io_reports
        .iter()
        .map(|r| robot_board::firmware::describe_io(&syms, r))
        .collect();
    assert_eq!(lines.len(), 3, "{lines:#?}");
    let pcs: Vec<u32> = report.io_reports.iter().map(|r| r.pc.unwrap()).collect();
    let names: Vec<&str> = pcs
        .iter()
        .map(|&pc| syms.function_at(pc).unwrap().c_name())
        .collect();
    assert_eq!(names, ["start_dma", "flash_status", "reserved"]);
    assert_eq!(
        lines[0],
        format!(
            "PC H'{:06X} in start_dma: writes MAR0AR (H'FFFF20) of the DMA controller (DMAC), \
             not modelled (the write is ignored)",
            pcs[0]
        )
    );
    assert!(lines[1].contains("reads FLMCR1 (H'FFFF40)"), "{}", lines[1]);
    assert!(
        lines[2].contains("H'FFFF1C, a reserved I/O address"),
        "{}",
        lines[2]
    );
    // Each PC is the instruction that made the access: a byte move to or from the address.
    let (image, _) = program("unmodelled");
    let m = Machine::with_image(&srec::parse(&image).unwrap()).unwrap();
    for r in &report.io_reports {
        let pc = r.pc.unwrap();
        let bytes: Vec<u8> = (0..10).map(|i| m.peek(pc + i)).collect();
        let d = h8300h::cpu::decode::decode_bytes(&bytes).unwrap();
        let text = h8300h::cpu::disasm::format_instr(d, pc);
        assert!(text.starts_with("mov.b"), "{text}");
        assert!(
            text.contains(&format!("{:x}", r.addr & 0xFF)),
            "{text} for H'{:06X}",
            r.addr
        );
    }

    // --strict-io: the first one stops the program.
    let (_, report) = run(
        "unmodelled",
        &RunOptions {
            max_states: Some(10_000_000),
            strict_io: true,
        },
    );
    let Outcome::Unmodelled(r) = report.outcome else {
        panic!("{:?}", report.outcome);
    };
    assert_eq!(r.register.map(|x| x.name), Some("MAR0AR"));
    assert_eq!(r.pc, Some(pcs[0]));
}

/// Sums of a folded profile by its stacks' innermost frame (without a `[...]` mark).
fn by_leaf(folded: &str) -> BTreeMap<String, u64> {
    let mut m = BTreeMap::new();
    for line in folded.lines() {
        let (stack, n) = line.rsplit_once(' ').unwrap();
        let leaf = stack.rsplit(';').next().unwrap();
        let leaf = leaf.split(" [").next().unwrap().to_string();
        *m.entry(leaf).or_insert(0) += n.parse::<u64>().unwrap();
    }
    m
}

#[test]
fn the_profile_of_a_known_call_structure_adds_up_to_the_run() {
    let (image, syms) = program("callstack");
    let (mut cpu, mut m) = boot(&image);
    let names: Arc<dyn CodeNames + Send + Sync> = Arc::new(syms.clone());
    let mut profile = StackProfile::new(Some(names), Some(syms.function_entries()), &cpu, m.now());
    let mut trace = Vec::new();
    let report = run_mcu_probed(
        &mut cpu,
        m.mcu_mut(),
        &budget(10_000_000),
        &mut std::io::sink(),
        Probes {
            trace: Some(&mut trace),
            names: Some(&syms),
            profile: Some(&mut profile),
            ..Probes::default()
        },
    )
    .unwrap();
    assert_eq!(report.outcome, Outcome::Halted { exit_status: 0 });
    let folded = profile.folded();
    // Every state of the run is in one line.
    let total: u64 = folded
        .lines()
        .map(|l| l.rsplit_once(' ').unwrap().1.parse::<u64>().unwrap())
        .sum();
    assert_eq!(total, report.stats.states);
    assert_eq!(profile.total(), report.stats.states);
    let stacks: Vec<&str> = folded
        .lines()
        .map(|l| l.rsplit_once(' ').unwrap().0)
        .collect();
    // The call structure: main -> top -> mid -> leaf, and nothing else below top.
    for s in [
        "[reset]",
        "start;main",
        "start;main;top",
        "start;main;top;mid",
        "start;main;top;mid;leaf",
        "start;main;[sleep]",
    ] {
        assert!(stacks.contains(&s), "{s} missing from\n{folded}");
    }
    for s in &stacks {
        let calls: Vec<&str> = s.split(';').filter(|f| !f.contains(" [")).collect();
        if calls.contains(&"top") {
            let below: Vec<&str> = calls.iter().skip_while(|f| **f != "top").copied().collect();
            assert!(
                ["top"][..] == below[..]
                    || ["top", "mid"][..] == below[..]
                    || ["top", "mid", "leaf"][..] == below[..]
                    || below.ends_with(&["tick_work"]),
                "{s}"
            );
        }
        // The tick's handler sits under the function it interrupted, and calls tick_work.
        if let Some(i) = s.find("isr_imia0") {
            assert!(s[i..].starts_with("isr_imia0 [interrupt 24]"), "{s}");
            assert!(s.starts_with("start;main"), "{s}");
            let after = &s[i + "isr_imia0 [interrupt 24]".len()..];
            assert!(after.is_empty() || after == ";tick_work", "{s}");
        }
    }
    // Thirty ticks: as many handler entries as interrupts taken, spread over where they hit.
    assert_eq!(report.stats.interrupts, 30);
    // The same states per function as the instruction trace's lines give (each line the
    // states of one step, named by the code it ran in; an interrupt's entry by its handler).
    let trace = String::from_utf8(trace).unwrap();
    let mut from_trace: BTreeMap<String, u64> = BTreeMap::new();
    for line in trace.lines() {
        let (head, name) = line.rsplit_once("  ").unwrap();
        let states: u64 = head
            .trim_end()
            .trim_end_matches("states")
            .trim_end()
            .rsplit(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        *from_trace.entry(name.to_string()).or_insert(0) += states;
    }
    let mut leaves = by_leaf(&folded);
    let sleep = leaves.remove("[sleep]").unwrap_or(0);
    let reset = leaves.remove("[reset]").unwrap_or(0);
    assert_eq!(reset, 4, "the reset vector's fetch");
    // With a profile the run waits in sleep mode outside the steps (the profile's [sleep]), so
    // the trace's lines, the sleeps and the reset's fetch make the run.
    let traced: u64 = from_trace.values().sum();
    assert_eq!(traced + sleep + reset, report.stats.states);
    for f in ["top", "mid", "leaf", "tick_work", "con_init"] {
        assert_eq!(leaves.get(f), from_trace.get(f), "{f}");
    }
    assert!(sleep > 0);
}
