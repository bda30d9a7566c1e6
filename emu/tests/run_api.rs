//! The run API: halting and exit status, console output through SCI1, the state budget, core
//! errors as outcomes, load errors as errors, traces and statistics.

use h8_3052f::run::{Outcome, RunError, RunOptions, run_image};
use h8300h::cpu::CpuError;
use h8300h::srec::{self, Chunk, SrecImage};

/// `hi.s`, assembled with h8300-hms-as 2.16.1 and converted with objcopy: reset vector →
/// H'000100; set up SCI1 (SMR = 0, BRR = 19, SCR = TE), print "hi\n" polling TDRE (BTST on
/// SSR, write TDR, BCLR TDRE), then `mov.b #3,r0l; orc #0x80,ccr; sleep`.
const HI_MOT: &str = "S009000068692E6D6F74A7
S113000000000100000000000000000000000000EB
S113001000000000000000000000000000000000DC
S113002000000000000000000000000000000000CC
S113003000000000000000000000000000000000BC
S113004000000000000000000000000000000000AC
S1130050000000000000000000000000000000009C
S1130060000000000000000000000000000000008C
S1130070000000000000000000000000000000007C
S1130080000000000000000000000000000000006C
S1130090000000000000000000000000000000005C
S11300A0000000000000000000000000000000004C
S11300B0000000000000000000000000000000003C
S11300C0000000000000000000000000000000002C
S11300D0000000000000000000000000000000001C
S11300E0000000000000000000000000000000000C
S11300F000000000000000000000000000000000FC
S11301007A0700FFFF10F80038B8F81338B9F82060
S113011038BA7A01000001306C1A470E7EBC737045
S113012047FA3ABB7FBC727040EEF803048001804A
S107013068690A00EC
S9030100FB
";

/// An image whose reset vector points at H'000100, where `code` sits.
fn image_with_code(code: &[u8]) -> String {
    let mut data = 0x100u32.to_be_bytes().to_vec();
    data.resize(0x100, 0);
    data.extend_from_slice(code);
    srec::write_s3(
        &SrecImage {
            header: Some(b"test".to_vec()),
            chunks: vec![Chunk { address: 0, data }],
            start: Some(0x100),
        },
        32,
    )
}

#[test]
fn a_program_prints_through_sci1_and_halts_with_its_status() {
    let mut console = Vec::new();
    let r = run_image(
        HI_MOT.as_bytes(),
        &RunOptions::default(),
        &mut console,
        None,
    )
    .unwrap();
    assert_eq!(console, b"hi\n");
    assert_eq!(r.outcome, Outcome::Halted { exit_status: 3 });
    assert_eq!(r.stats.console_bytes, 3);
    assert!(r.stats.instructions > 20);
    // The third byte can only be written once the second has moved into the shift register,
    // one frame (10 bits × 32 × (19 + 1) states) after the first.
    assert!(r.stats.states > 6400, "{}", r.stats.states);
    assert_eq!(r.stats.clock_hz, 25_000_000);
    let phi = f64::from(r.stats.clock_hz);
    assert!((r.stats.emulated_seconds - r.stats.states as f64 / phi).abs() < 1e-12);
    let json = r.to_json();
    assert!(json.contains("\"outcome\":\"halted\""), "{json}");
    assert!(json.contains("\"exit_status\":3"), "{json}");
    assert!(
        json.contains(&format!("\"states\":{}", r.stats.states)),
        "{json}"
    );
}

#[test]
fn the_trace_names_address_instruction_and_states() {
    let mut console = Vec::new();
    let mut trace = Vec::new();
    let r = run_image(
        HI_MOT.as_bytes(),
        &RunOptions::default(),
        &mut console,
        Some(&mut trace),
    )
    .unwrap();
    let text = String::from_utf8(trace).unwrap();
    let first = text.lines().next().unwrap();
    assert!(first.starts_with("000100: mov.l #0xffff10,er7"), "{first}");
    assert!(first.ends_with(" 6 states"), "{first}");
    assert_eq!(text.lines().count() as u64, r.stats.instructions);
    let last = text.lines().last().unwrap();
    assert!(last.starts_with("00012e: sleep"), "{last}");
}

#[test]
fn the_state_budget_stops_a_run() {
    let mut console = Vec::new();
    let opts = RunOptions {
        max_states: Some(100),
        ..RunOptions::default()
    };
    let r = run_image(HI_MOT.as_bytes(), &opts, &mut console, None).unwrap();
    assert_eq!(r.outcome, Outcome::MaxStates);
    assert!((100..130).contains(&r.stats.states), "{}", r.stats.states);
}

#[test]
fn an_undefined_opcode_is_an_outcome_naming_pc_and_bytes() {
    // nop; then 00 01 (undefined).
    let img = image_with_code(&[0x00, 0x00, 0x00, 0x01]);
    let mut console = Vec::new();
    let r = run_image(img.as_bytes(), &RunOptions::default(), &mut console, None).unwrap();
    assert_eq!(
        r.outcome,
        Outcome::Error(CpuError::UndefinedOpcode {
            pc: 0x102,
            bytes: "00 01".into()
        })
    );
    assert_eq!(r.stats.instructions, 1);
    assert!(
        r.to_json()
            .contains("undefined opcode at PC H'000102: 00 01")
    );
}

#[test]
fn a_jump_outside_rom_and_ram_is_an_outcome() {
    // jmp @0x90000:24
    let img = image_with_code(&[0x5a, 0x09, 0x00, 0x00]);
    let mut console = Vec::new();
    let r = run_image(img.as_bytes(), &RunOptions::default(), &mut console, None).unwrap();
    assert!(matches!(
        r.outcome,
        Outcome::Error(CpuError::FetchOutside { pc: 0x9_0000, .. })
    ));
}

#[test]
fn sleeping_with_nothing_to_wake_is_reported() {
    // andc #0x7f,ccr; sleep (interrupts enabled, no source)
    let img = image_with_code(&[0x06, 0x7f, 0x01, 0x80]);
    let mut console = Vec::new();
    let r = run_image(img.as_bytes(), &RunOptions::default(), &mut console, None).unwrap();
    assert_eq!(r.outcome, Outcome::SleptForever { pc: 0x104 });
    // With a budget the sleep fast-forwards to it.
    let opts = RunOptions {
        max_states: Some(1_000_000),
        ..RunOptions::default()
    };
    let r = run_image(img.as_bytes(), &opts, &mut console, None).unwrap();
    assert_eq!(r.outcome, Outcome::MaxStates);
    assert_eq!(r.stats.states, 1_000_000);
}

#[test]
fn bad_images_are_errors() {
    let mut console = Vec::new();
    let e = run_image(
        b"S1030000FB\nnot a record\n",
        &RunOptions::default(),
        &mut console,
        None,
    )
    .unwrap_err();
    assert!(matches!(e, RunError::Srec(ref s) if s.line == 1), "{e}");
    // Data in RAM cannot be flashed.
    let text = srec::write_s3(
        &SrecImage {
            header: None,
            chunks: vec![Chunk {
                address: 0xff_e000,
                data: vec![1, 2],
            }],
            start: None,
        },
        16,
    );
    let e = run_image(text.as_bytes(), &RunOptions::default(), &mut console, None).unwrap_err();
    assert!(matches!(e, RunError::Load(_)), "{e}");
    let cause = std::error::Error::source(&e).map(ToString::to_string);
    assert!(
        cause.as_deref().is_some_and(|c| c.contains("H'FFE000")),
        "{cause:?}"
    );
}
