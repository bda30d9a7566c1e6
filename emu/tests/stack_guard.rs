//! The stack guard (`h8300h::cpu::stack`): every kind of stack access stopped at the
//! instruction that leaves the room, on the fast path and the reference path alike, with the
//! CPU left as it was before the instruction; the warning guard lets it run and keeps the
//! first fault; and three C programs (`tests/programs/stack/`, built by
//! `tests/programs/build.sh` with their symbol tables): a recursion that overflows, a
//! recursion that fits followed by a frame that does not, and a recursion that comes close
//! and is not stopped. The instruction the guard names is checked against an oracle that
//! knows nothing of the guard: the first instruction after which SP lies below the end of the
//! data, found by stepping with no guard.

use std::path::{Path, PathBuf};

use h8_3052f::machine::Machine;
use h8_3052f::periph::itu::{CHANNEL_BASE, IMFA, OFF_GRA, OFF_TCR, OFF_TIER, TSTR};
use h8_3052f::run::{Outcome, Probes, RunOptions, run_image, run_mcu_probed};
use h8_3052f::trace::CodeNames;
use h8300h::bus::Bus;
use h8300h::cpu::{
    Cpu, CpuError, Event, StackAccess, StackFault, StackGuard, StackGuardMode, StackRoom,
};
use h8300h::srec;
use robot_board::symbols::SymbolTable;

/// The room of the hand-assembled cases.
const ROOM: StackRoom = StackRoom {
    low: 0xFF_E000,
    top: 0xFF_FF10,
};
/// Where the cases' code starts (the reset vector points here).
const CODE: u32 = 0x100;
/// A subroutine (`rts`) that calls, the trap and the tick interrupt go to.
const SUB: u32 = 0x200;

/// A machine with `code` at [`CODE`], `rts` at [`SUB`], vectors 8 (TRAPA #0) and 24 (ITU0
/// compare match A) at [`SUB`], reset, with ER7 = `sp` and the guard over [`ROOM`].
fn case(code: &[u8], sp: u32, fast: bool, mode: StackGuardMode) -> (Cpu, Machine) {
    let mut m = Machine::new();
    m.poke(0, &CODE.to_be_bytes());
    m.poke(8 * 4, &SUB.to_be_bytes());
    m.poke(24 * 4, &SUB.to_be_bytes());
    m.poke(CODE, code);
    m.poke(SUB, &[0x54, 0x70]);
    let mut cpu = Cpu::new();
    cpu.set_fast_path(fast);
    cpu.set_stack_guard(Some(StackGuard { room: ROOM, mode }));
    cpu.reset(&mut m);
    cpu.set_er(7, sp);
    (cpu, m)
}

/// A case: its name, its code, the SP it starts from, and what the guard must see: the
/// access, its lowest address and its size.
type Case = (&'static str, Vec<u8>, u32, StackAccess, u32, u32);

/// One stack access of each kind.
fn cases() -> Vec<Case> {
    let (low, top) = (ROOM.low, ROOM.top);
    vec![
        // jsr @0x000200:24
        (
            "jsr",
            vec![0x5e, 0x00, 0x02, 0x00],
            low + 2,
            StackAccess::Call,
            low - 2,
            4,
        ),
        // mov.l er0,@-er7
        (
            "push",
            vec![0x01, 0x00, 0x6d, 0xf0],
            low + 2,
            StackAccess::Write,
            low - 2,
            4,
        ),
        // mov.l @er7+,er0
        (
            "pop above the top",
            vec![0x01, 0x00, 0x6d, 0x70],
            top - 2,
            StackAccess::Read,
            top - 2,
            4,
        ),
        // rts
        (
            "rts above the top",
            vec![0x54, 0x70],
            top,
            StackAccess::Return,
            top,
            4,
        ),
        // mov.w r0,@(-4:16,er7)
        (
            "store at a negative displacement",
            vec![0x6f, 0xf0, 0xff, 0xfc],
            low + 2,
            StackAccess::Write,
            low - 2,
            2,
        ),
        // mov.l @(8:16,er7),er1
        (
            "load of an argument above the top",
            vec![0x01, 0x00, 0x6f, 0x71, 0x00, 0x08],
            top - 8,
            StackAccess::Read,
            top,
            4,
        ),
        // bset #0,@er7
        (
            "bset through er7",
            vec![0x7d, 0x70, 0x70, 0x00],
            low - 1,
            StackAccess::Write,
            low - 1,
            1,
        ),
        // stc ccr,@-er7
        (
            "stc push",
            vec![0x01, 0x40, 0x6d, 0xf0],
            low + 1,
            StackAccess::Write,
            low - 1,
            2,
        ),
        // ldc @er7+,ccr
        (
            "ldc pop",
            vec![0x01, 0x40, 0x6d, 0x70],
            top - 1,
            StackAccess::Read,
            top - 1,
            2,
        ),
        // trapa #0
        (
            "trapa",
            vec![0x57, 0x00],
            low + 2,
            StackAccess::Trap,
            low - 2,
            4,
        ),
        // add.l #-8,er7
        (
            "frame allocation",
            vec![0x7a, 0x17, 0xff, 0xff, 0xff, 0xf8],
            low + 4,
            StackAccess::MoveSp,
            low - 4,
            0,
        ),
        // subs #4,er7
        (
            "subs from sp",
            vec![0x1b, 0x97],
            low + 2,
            StackAccess::MoveSp,
            low - 2,
            0,
        ),
        // mov.w #0,e7: SP loaded with H'00xxxx
        (
            "sp loaded off ram",
            vec![0x79, 0x0f, 0x00, 0x00],
            0xFF_E100,
            StackAccess::MoveSp,
            0x00_E100,
            0,
        ),
    ]
}

#[test]
fn every_kind_of_stack_access_is_stopped_at_its_instruction_with_the_cpu_as_before() {
    for fast in [true, false] {
        for (name, code, sp, access, addr, bytes) in cases() {
            let (mut cpu, mut m) = case(&code, sp, fast, StackGuardMode::Stop);
            let ccr = cpu.ccr();
            let t0 = m.now();
            let r = cpu.step(&mut m, u64::MAX);
            let Err(CpuError::StackOverflow(f)) = r else {
                panic!("{name} (fast {fast}): {r:?}");
            };
            assert_eq!(
                (f.pc, f.sp, f.access, f.addr, f.bytes, f.room),
                (CODE, sp, access, addr, bytes, ROOM),
                "{name} (fast {fast})"
            );
            assert!(f.bytes_over() > 0, "{name}");
            assert_eq!(cpu.pc(), CODE, "{name}: PC at the instruction");
            assert_eq!(cpu.er(7), sp, "{name}: SP as before");
            assert_eq!(cpu.ccr(), ccr, "{name}: CCR as before");
            assert_eq!(cpu.instructions(), 0, "{name}: not counted");
            assert_eq!(cpu.stack_fault(), Some(&*f), "{name}: kept");
            assert!(m.now() >= t0);
            let text = f.to_string();
            assert!(
                text.contains("H'000100") && text.contains(&format!("{} bytes", f.bytes_over())),
                "{name}: {text}"
            );
        }
    }
}

#[test]
fn accesses_inside_the_room_go_through() {
    let (low, top) = (ROOM.low, ROOM.top);
    let inside: [(&[u8], u32); 8] = [
        (&[0x5e, 0x00, 0x02, 0x00], low + 4),
        (&[0x01, 0x00, 0x6d, 0xf0], low + 4),
        (&[0x01, 0x00, 0x6d, 0x70], top - 4),
        (&[0x54, 0x70], top - 4),
        (&[0x7d, 0x70, 0x70, 0x00], low),
        (&[0x57, 0x00], low + 4),
        (&[0x7a, 0x17, 0xff, 0xff, 0xff, 0xf8], low + 8),
        (&[0x1b, 0x97], top),
    ];
    for fast in [true, false] {
        for (code, sp) in inside {
            let (mut cpu, mut m) = case(code, sp, fast, StackGuardMode::Stop);
            assert_eq!(
                cpu.step(&mut m, u64::MAX),
                Ok(Event::Executed),
                "{code:02x?}"
            );
            assert_eq!(cpu.stack_fault(), None);
        }
    }
}

#[test]
fn a_warning_guard_keeps_the_first_fault_and_lets_the_instruction_run() {
    for fast in [true, false] {
        for (name, code, sp, access, addr, _) in cases() {
            let (mut cpu, mut m) = case(&code, sp, fast, StackGuardMode::Warn);
            assert_eq!(cpu.step(&mut m, u64::MAX), Ok(Event::Executed), "{name}");
            let f = cpu.stack_fault().cloned().expect(name);
            assert_eq!((f.pc, f.access, f.addr), (CODE, access, addr), "{name}");
            assert_eq!(cpu.instructions(), 1, "{name}: it ran");
            assert_ne!(cpu.pc(), CODE, "{name}: it ran");
        }
    }
}

#[test]
fn no_guard_lets_everything_through() {
    for (name, code, sp, ..) in cases() {
        let (mut cpu, mut m) = case(&code, sp, true, StackGuardMode::Stop);
        cpu.set_stack_guard(None);
        assert_eq!(cpu.step(&mut m, u64::MAX), Ok(Event::Executed), "{name}");
        assert_eq!(cpu.stack_fault(), None);
    }
}

#[test]
fn an_interrupt_whose_entry_would_leave_the_room_stops_before_it_is_taken() {
    // andc #0x7f,ccr; bra . — with ITU0's compare match A interrupt enabled every 10 counts.
    for fast in [true, false] {
        let (mut cpu, mut m) = case(
            &[0x06, 0x7f, 0x40, 0xfe],
            ROOM.low + 2,
            fast,
            StackGuardMode::Stop,
        );
        let b = CHANNEL_BASE[0];
        m.write8(b + OFF_TCR, 0x20);
        m.write16(b + OFF_GRA, 9);
        m.write8(b + OFF_TIER, IMFA);
        m.write8(TSTR, 0x01);
        let err = loop {
            match cpu.step(&mut m, u64::MAX) {
                Ok(Event::Executed) => assert!(m.now() < 10_000, "no interrupt came"),
                Ok(e) => panic!("{e:?}"),
                Err(e) => break e,
            }
        };
        let CpuError::StackOverflow(f) = err else {
            panic!("{err:?}");
        };
        assert_eq!(f.access, StackAccess::InterruptEntry(24));
        assert_eq!(f.pc, CODE + 2, "the interrupted instruction: the bra");
        assert!(f.instruction.is_empty());
        assert_eq!(cpu.pc(), CODE + 2);
        assert_eq!(cpu.er(7), ROOM.low + 2);
        assert_eq!(cpu.ccr() & 0x80, 0, "not entered: the mask is still clear");
    }
}

// ----- the C programs ------------------------------------------------------------------

fn stack_program(name: &str) -> (PathBuf, Vec<u8>, SymbolTable) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/programs/stack");
    let mot = dir.join(format!("{name}.mot"));
    let image = std::fs::read(&mot).expect("the image (built by tests/programs/build.sh)");
    let sym = std::fs::read_to_string(dir.join(format!("{name}.sym"))).expect("its symbols");
    (mot, image, SymbolTable::parse(&sym).expect("symbols parse"))
}

/// The oracle: with no guard, stepping, the first instruction after which SP lies below
/// `low` (GCC's code never accesses below SP, so this is where the stack leaves its room),
/// with SP before it. None if the program halts first.
fn first_below(image: &[u8], low: u32, fast: bool) -> Option<(u32, u32)> {
    let mut m = Machine::with_image(&srec::parse(image).unwrap()).unwrap();
    let mut cpu = Cpu::new();
    cpu.set_fast_path(fast);
    cpu.reset(&mut m);
    while m.now() < 50_000_000 {
        let (pc, sp) = (cpu.pc(), cpu.er(7));
        match cpu.step(&mut m, u64::MAX) {
            Ok(Event::Executed) if cpu.er(7) < low => return Some((pc, sp)),
            Ok(Event::Halted) | Err(_) => return None,
            _ => {}
        }
    }
    None
}

/// Runs `image` under a guard over `room` to its end (at most 50 M states) step by step;
/// returns how it ended, the console and the lowest SP seen.
fn run_guarded(
    image: &[u8],
    room: StackRoom,
    fast: bool,
    names: &SymbolTable,
) -> (Result<u8, Box<StackFault>>, String, u32) {
    let mut m = Machine::with_image(&srec::parse(image).unwrap()).unwrap();
    let mut cpu = Cpu::new();
    cpu.set_fast_path(fast);
    cpu.set_stack_guard(Some(StackGuard::stop(room)));
    cpu.reset(&mut m);
    let mut min_sp = u32::MAX;
    let mut console = Vec::new();
    let end = loop {
        assert!(m.now() < 50_000_000, "the program did not end");
        match cpu.step(&mut m, u64::MAX) {
            Ok(Event::Halted) => break Ok(cpu.er(0) as u8),
            Ok(_) => {}
            Err(CpuError::StackOverflow(mut f)) => {
                f.function = names.name_at(f.pc).map(str::to_string);
                break Err(f);
            }
            Err(e) => panic!("{e}"),
        }
        if m.mcu().sci().has_output() {
            console.extend_from_slice(m.mcu().sci().output());
            m.mcu_mut().sci_mut().clear_output();
        }
        if cpu.pc() >= 0x100 {
            min_sp = min_sp.min(cpu.er(7));
        }
    };
    let now = m.now();
    m.mcu_mut().sci_mut().flush(now);
    console.extend_from_slice(m.mcu().sci().output());
    (end, String::from_utf8_lossy(&console).into_owned(), min_sp)
}

#[test]
fn the_symbols_give_the_room_from_the_end_of_the_data_to_the_stack_s_top() {
    let (_, _, syms) = stack_program("stack_deep");
    let room = syms.stack_room();
    assert_eq!(Some(room.low), syms.addr("_bss_end"));
    assert_eq!(room.top, 0xFF_FF10);
    assert_eq!(SymbolTable::default().stack_room(), StackRoom::RAM);
}

#[test]
fn a_recursion_that_overflows_is_stopped_at_the_instruction_that_leaves_the_room() {
    let (_, image, syms) = stack_program("stack_deep");
    let room = syms.stack_room();
    for fast in [true, false] {
        let oracle = first_below(&image, room.low, fast).expect("the oracle sees it");
        let (end, console, min_sp) = run_guarded(&image, room, fast, &syms);
        let f = end.expect_err("stopped");
        assert_eq!((f.pc, f.sp), oracle, "fast {fast}: {f}");
        assert_eq!(f.function.as_deref(), Some("descend"), "{f}");
        assert!(f.below());
        assert_eq!(f.bytes_over(), room.low - f.addr);
        assert!(f.bytes_over() <= 48, "one frame at most: {f}");
        assert!(min_sp >= room.low, "nothing went below before the fault");
        assert_eq!(console, "descending 400 levels\n");
    }
}

#[test]
fn a_frame_that_does_not_fit_after_a_deep_recursion_that_does_is_stopped_at_its_allocation() {
    let (_, image, syms) = stack_program("stack_after");
    let room = syms.stack_room();
    for fast in [true, false] {
        let oracle = first_below(&image, room.low, fast).expect("the oracle sees it");
        let (end, console, min_sp) = run_guarded(&image, room, fast, &syms);
        let f = end.expect_err("stopped");
        assert_eq!((f.pc, f.sp), oracle, "fast {fast}: {f}");
        assert_eq!(f.function.as_deref(), Some("fill"), "{f}");
        assert_eq!(f.access, StackAccess::MoveSp, "{f}");
        // The recursion went 60 levels (over 3 KB) deep and was let through.
        assert!(room.top - min_sp > 3_000, "{}", room.top - min_sp);
        assert_eq!(console, "descend=0\n");
    }
}

#[test]
fn a_recursion_that_comes_close_is_not_stopped() {
    let (_, image, syms) = stack_program("stack_close");
    let room = syms.stack_room();
    for fast in [true, false] {
        assert_eq!(first_below(&image, room.low, fast), None);
        let (end, console, min_sp) = run_guarded(&image, room, fast, &syms);
        assert_eq!(end, Ok(0), "{console}");
        let left = min_sp - room.low;
        assert!(left < 96, "it came within {left} bytes of the data");
        assert!(console.contains("failures=0"), "{console}");
    }
}

#[test]
fn run_image_guards_the_whole_ram_and_emu_names_the_function() {
    let (_, image, syms) = stack_program("stack_deep");
    // Without symbols the room is the RAM: the fault comes later, off the RAM's bottom.
    let mut console = Vec::new();
    let report = run_image(&image, &RunOptions::default(), &mut console, None).unwrap();
    let Outcome::Error(CpuError::StackOverflow(f)) = report.outcome else {
        panic!("{:?}", report.outcome);
    };
    assert_eq!(f.room, StackRoom::RAM);
    let oracle = first_below(&image, StackRoom::RAM.low, true).unwrap();
    assert_eq!((f.pc, f.sp), oracle);
    // With the names, the run reports the function.
    let mut m = Machine::with_image(&srec::parse(&image).unwrap()).unwrap();
    let mut cpu = Cpu::new();
    cpu.set_stack_guard(Some(StackGuard::stop(syms.stack_room())));
    cpu.reset(&mut m);
    let report = run_mcu_probed(
        &mut cpu,
        m.mcu_mut(),
        &RunOptions::default(),
        &mut console,
        Probes {
            names: Some(&syms),
            ..Probes::default()
        },
    )
    .unwrap();
    let Outcome::Error(CpuError::StackOverflow(f)) = report.outcome else {
        panic!("{:?}", report.outcome);
    };
    assert_eq!(f.function.as_deref(), Some("descend"));
    // A warning guard: the run goes on (to the fetch outside ROM and RAM the overflow ends
    // in), and the first fault is in the report.
    let mut m = Machine::with_image(&srec::parse(&image).unwrap()).unwrap();
    let mut cpu = Cpu::new();
    cpu.set_stack_guard(Some(StackGuard {
        room: syms.stack_room(),
        mode: StackGuardMode::Warn,
    }));
    cpu.reset(&mut m);
    let warned = run_mcu_probed(
        &mut cpu,
        m.mcu_mut(),
        &RunOptions {
            max_states: Some(20_000_000),
            ..RunOptions::default()
        },
        &mut console,
        Probes {
            names: Some(&syms),
            ..Probes::default()
        },
    )
    .unwrap();
    let w = warned.stack_fault.expect("the warning");
    assert_eq!((w.pc, w.function.as_deref()), (f.pc, Some("descend")));
    assert!(!matches!(
        warned.outcome,
        Outcome::Error(CpuError::StackOverflow(_))
    ));
}

#[test]
fn the_differential_programs_run_under_the_guard_untouched() {
    // Their stacks stay in RAM: run_image's guard lets every one of them through (the
    // differential test runs them so too); here one with deep recursion, on both paths.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/programs");
    let image = std::fs::read(dir.join("recursion.mot")).unwrap();
    let mut console = Vec::new();
    let r = run_image(&image, &RunOptions::default(), &mut console, None).unwrap();
    assert_eq!(r.outcome, Outcome::Halted { exit_status: 0 });
    assert_eq!(r.stack_fault, None);
}

#[test]
fn the_robot_firmware_s_room_takes_in_its_boot_sized_arrays_and_is_never_left() {
    use h8_3052f::pins::NullBoard;
    use robot_board::board::{RobotConfig, robot_mcu};
    use robot_board::firmware::{ConfigBlock, Firmware, FirmwareController, peek_be};
    let fw = Firmware::robot().unwrap();
    // On the robot's board: the saves reach the EEPROMs.
    let mut mcu = robot_mcu(NullBoard, &RobotConfig::default()).unwrap();
    let mut c = FirmwareController::start(&fw, &mut mcu, Some(&ConfigBlock::ARENA)).unwrap();
    let before = c.cpu().stack_guard().unwrap().room;
    assert_eq!(Some(before.low), fw.symbols.addr("_bss_end"));
    for _ in 0..30 {
        c.run_to_sensing(&mut mcu).unwrap();
        c.run_to_sleep(&mut mcu).unwrap();
    }
    let room = c.cpu().stack_guard().unwrap().room;
    let heap_end = peek_be::<_, 4>(&mcu, fw.symbols.addr("heap_end").unwrap()) as u32;
    assert!(heap_end > before.low, "the firmware carved its arrays");
    assert_eq!(
        room,
        StackRoom {
            low: heap_end,
            top: 0xFF_FF10
        }
    );
    assert_eq!(c.stack_fault(), None);
}
