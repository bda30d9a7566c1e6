//! The chip's reports and profiles through the real binary: `emu --profile` (folded stacks
//! that add up to the run's states), the warnings of `emu`, `run` and `fit` for registers the
//! emulated chip does not model and their `--strict-io` errors, `run --profile` of one robot
//! (the same results as without), and the watchdog's reset seen from `emu --stats`.

use std::process::{Command, Output};

fn h8swarm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_h8swarm"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the binary runs")
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("h8swarm-chip-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// The `states` of an `emu --stats` line.
fn stats_states(stderr: &str) -> u64 {
    let line = stderr
        .lines()
        .find(|l| l.starts_with("{\"outcome\""))
        .expect("the --stats line");
    let v: serde_json::Value = serde_json::from_str(line).unwrap();
    v["states"].as_u64().unwrap()
}

/// The sum of a folded profile's counts, checking every line's form.
fn folded_total(folded: &str) -> u64 {
    folded
        .lines()
        .map(|l| {
            let (stack, n) = l.rsplit_once(' ').expect("`stack count`");
            assert!(!stack.is_empty() && !stack.contains('\t'), "{l}");
            n.parse::<u64>().expect("a count")
        })
        .sum()
}

#[test]
fn emu_profile_writes_folded_stacks_that_add_up_to_the_run() {
    let dir = temp_dir("profile");
    let file = dir.join("callstack.folded");
    let out = h8swarm(&[
        "emu",
        "emu/tests/programs/chip/callstack.mot",
        "--stats",
        "--profile",
        file.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let folded = std::fs::read_to_string(&file).unwrap();
    assert_eq!(folded_total(&folded), stats_states(&text(&out.stderr)));
    for stack in [
        "start;main;top;mid;leaf ",
        "start;main;[sleep] ",
        "start;main;top;isr_imia0 [interrupt 24];tick_work ",
    ] {
        assert!(
            folded.lines().any(|l| l.starts_with(stack)),
            "{stack} in\n{folded}"
        );
    }
    // The robot firmware for 2 M states: the same sum, its functions by name.
    let file = dir.join("robot.folded");
    let out = h8swarm(&[
        "emu",
        "firmware/robot.mot",
        "--max-states",
        "2000000",
        "--stats",
        "--profile",
        file.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(124), "{}", text(&out.stderr));
    let folded = std::fs::read_to_string(&file).unwrap();
    assert_eq!(folded_total(&folded), stats_states(&text(&out.stderr)));
    assert!(folded.contains(";main;"), "{folded}");
    assert!(folded.contains("[interrupt 24]"), "{folded}");
    // A file that cannot be created: bad input before the run.
    let out = h8swarm(&[
        "emu",
        "emu/tests/programs/chip/callstack.mot",
        "--profile",
        "/nonexistent-dir/x.folded",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("--profile: cannot create"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn emu_warns_of_unmodelled_registers_and_strict_io_stops_at_the_first() {
    let out = h8swarm(&["emu", "emu/tests/programs/chip/unmodelled.mot"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let err = text(&out.stderr);
    let warnings: Vec<&str> = err.lines().filter(|l| l.starts_with("warning:")).collect();
    assert_eq!(warnings.len(), 3, "{err}");
    assert!(
        warnings[0].contains(
            "in start_dma: writes MAR0AR (H'FFFF20) of the DMA controller (DMAC), not modelled"
        ),
        "{err}"
    );
    assert!(
        warnings[1].contains("in flash_status: reads FLMCR1"),
        "{err}"
    );
    assert!(
        warnings[2].contains("in reserved: reads H'FFFF1C, a reserved I/O address"),
        "{err}"
    );
    // The robot firmware touches nothing unmodelled.
    let out = h8swarm(&["emu", "firmware/robot.mot", "--max-states", "3000000"]);
    assert!(
        !text(&out.stderr).contains("not modelled"),
        "{}",
        text(&out.stderr)
    );

    let out = h8swarm(&[
        "emu",
        "emu/tests/programs/chip/unmodelled.mot",
        "--strict-io",
    ]);
    assert_eq!(out.status.code(), Some(125));
    let err = text(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: image `emu/tests/programs/chip/unmodelled.mot`: PC H'"),
        "{err}"
    );
    assert!(
        err.contains("in start_dma: writes MAR0AR") && err.contains("(--strict-io)"),
        "{err}"
    );
}

#[test]
fn emu_stats_count_the_watchdogs_reset() {
    let out = h8swarm(&["emu", "emu/tests/programs/chip/wdt.mot", "--stats"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("spinning\nboot=2\nwrst=1\n"));
    assert!(
        text(&out.stderr).contains("\"resets\":1"),
        "{}",
        text(&out.stderr)
    );
    // A program without a reset has no such field (the output is as it always was).
    let out = h8swarm(&["emu", "emu/tests/programs/arith.mot", "--stats"]);
    assert!(!text(&out.stderr).contains("resets"));
    assert!(!text(&out.stderr).contains("unmodelled"));
}

/// A scenario running the minimal robot image (`chip/minibot.c`, which touches two registers
/// the chip does not model) on two robots for three steps, without the controls.
fn minibot_scenario(dir: &std::path::Path) -> std::path::PathBuf {
    let path = dir.join("minibot.toml");
    std::fs::write(
        &path,
        "base = \"arena\"\nrobots = 2\nsteps = 3\nrepeats = 2\n\
         [controller]\nkind = \"firmware\"\nimage = \"emu/tests/programs/chip/minibot.mot\"\n\
         [controls]\nlearning_off = false\nrandom_walk = false\n",
    )
    .unwrap();
    path
}

#[test]
fn run_reports_each_robots_unmodelled_registers_once_and_strict_io_stops_it() {
    let dir = temp_dir("run-io");
    let scenario = minibot_scenario(&dir);
    let out_dir = dir.join("out");
    let out = h8swarm(&[
        "run",
        scenario.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let io: Vec<&str> = stdout.lines().filter(|l| l.starts_with("IO ")).collect();
    // Two robots, two registers each, once (repeat 1 touches the same and is not repeated).
    assert_eq!(io.len(), 4, "{stdout}");
    for k in 0..2 {
        assert!(
            io.iter().any(|l| l
                .starts_with(&format!("IO    robot {k} in learning repeat 0: PC H'"))
                && l.contains("in boot_dma: writes MAR0AR")),
            "{stdout}"
        );
        assert!(
            io.iter()
                .any(|l| l.starts_with(&format!("IO    robot {k} "))
                    && l.contains("in flash_busy: reads FLMCR1")),
            "{stdout}"
        );
    }
    let out = h8swarm(&[
        "run",
        scenario.to_str().unwrap(),
        "--out",
        dir.join("strict").to_str().unwrap(),
        "--strict-io",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(
        err.contains("robot 0: PC H'")
            && err.contains("writes MAR0AR")
            && err.contains("(stopped by --strict-io)"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_profile_profiles_one_robot_without_changing_the_results() {
    let dir = temp_dir("run-profile");
    let base = [
        "run",
        "arena",
        "--controller",
        "firmware",
        "--robots",
        "2",
        "--steps",
        "6",
        "--repeats",
        "1",
        "--threads",
        "1",
    ];
    let plain = dir.join("plain");
    let out = h8swarm(&[&base[..], &["--out", plain.to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", text(&out.stderr));
    let profiled = dir.join("profiled");
    let file = dir.join("robot1.folded");
    let out = h8swarm(
        &[
            &base[..],
            &[
                "--out",
                profiled.to_str().unwrap(),
                "--profile",
                file.to_str().unwrap(),
                "--profile-robot",
                "1",
            ],
        ]
        .concat(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    for f in ["metrics.csv", "robots.csv"] {
        assert_eq!(
            std::fs::read(plain.join(f)).unwrap(),
            std::fs::read(profiled.join(f)).unwrap(),
            "{f}"
        );
    }
    let folded = std::fs::read_to_string(&file).unwrap();
    // The robot's states up to its sixth step's sensing: five step periods of 0.45 s and
    // boot (the sum is exactly the robot's clock: `a_robots_profile_adds_up_to_its_clock`).
    let total = folded_total(&folded);
    assert!((5 * 11_250_000..6 * 11_250_000).contains(&total), "{total}");
    assert!(
        folded
            .lines()
            .any(|l| l.contains(";main;") && l.contains("[sleep]")),
        "{folded}"
    );
    assert!(folded.contains("[interrupt 24]"), "{folded}");
    // The model has no firmware to profile.
    let out = h8swarm(&[
        "run",
        "arena",
        "--steps",
        "2",
        "--repeats",
        "1",
        "--out",
        dir.join("model").to_str().unwrap(),
        "--profile",
        dir.join("m.folded").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("--profile-robot 0: robot 0 runs the Rust model"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_robots_profile_adds_up_to_its_clock() {
    let s = swarm::scenario::Scenario::builtin("arena").unwrap();
    let mut s = s;
    s.robots = 2;
    s.controller.kind = swarm::scenario::ControllerKind::Firmware;
    let images = swarm::robot::Images::load(&s).unwrap();
    let mut sw = swarm::experiment::Swarm::new(
        &s,
        swarm::robot::Condition::Learning,
        0,
        false,
        images.as_ref(),
    )
    .unwrap();
    sw.robot_mut(1).unwrap().start_profile().unwrap();
    for _ in 0..4 {
        sw.step().unwrap();
    }
    let (folded, now) = sw.robot_mut(1).unwrap().take_profile().unwrap();
    assert_eq!(folded_total(&folded), now);
    assert!(now > 3 * 11_250_000, "{now}");
}

/// The minimal robot image (`chip/minibot.c`) under `fit`, with the arena's settings (the
/// image has no configuration block, so only those reach it), `strict_io` as given.
fn fit_minibot(strict_io: bool) -> Result<swarm::fit::FitReport, swarm::fit::FitError> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("emu/tests/programs/chip");
    let firmware =
        robot_board::firmware::Firmware::load(&dir.join("minibot.mot"), &dir.join("minibot.sym"))
            .unwrap();
    swarm::fit::measure(&swarm::fit::FitConfig {
        controller: robot_board::model::ControllerConfig::arena(1),
        steps: 3,
        seed: 1,
        kind: swarm::scenario::ControllerKind::Firmware,
        firmware: swarm::fit::FirmwareUnderTest {
            firmware,
            phases: Vec::new(),
        },
        compare: false,
        strict_io,
    })
}

#[test]
fn fit_names_what_an_image_uses_that_the_chip_does_not_model() {
    let r = fit_minibot(false).unwrap();
    assert!(
        r.verdict
            .contains(": uses MAR0AR of the DMAC and FLMCR1 of the flash, not modelled; "),
        "{}",
        r.verdict
    );
    assert_eq!(r.unmodelled.len(), 2);
    assert!(
        r.unmodelled[0].contains("in boot_dma: writes MAR0AR"),
        "{:?}",
        r.unmodelled
    );
    let e = fit_minibot(true).unwrap_err().to_string();
    assert!(e.starts_with("the firmware stopped at state"), "{e}");
    let chain = format!("{:#}", anyhow::Error::new(fit_minibot(true).unwrap_err()));
    assert!(
        chain.contains("in boot_dma: writes MAR0AR") && chain.contains("--strict-io"),
        "{chain}"
    );
    // The robot firmware's verdict says nothing of the kind (and its JSON has no such field).
    let out = h8swarm(&[
        "fit",
        "--steps",
        "3",
        "--setting",
        "arena",
        "--alone",
        "--json",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(!text(&out.stdout).contains("not modelled"));
    assert!(!text(&out.stdout).contains("unmodelled"));
}
