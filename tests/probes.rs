//! `h8swarm emu/run --vcd` and `--gdb` through the real binary: the trace of a window of steps
//! of one firmware robot, the results unchanged by tracing or by a debugger, the phases of
//! `--trace` and of the VCD file, and the one-line errors for bad values.

#[path = "../emu/tests/gdb_client/mod.rs"]
mod gdb_client;

use std::io::{BufRead, BufReader};
use std::process::{Command, Output, Stdio};

fn h8swarm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_h8swarm"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the binary runs")
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("h8swarm-probes-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// A small firmware run: 3 robots, 8 steps, one repeat of each condition.
fn run_args(out: &std::path::Path) -> Vec<String> {
    [
        "run",
        "arena",
        "--controller",
        "firmware",
        "--robots",
        "3",
        "--steps",
        "8",
        "--repeats",
        "1",
        "--out",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain([out.display().to_string()])
    .collect()
}

fn ok(out: &Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The trace's span in states: the header's "Trace from state A", to the last timestamp
/// (4 units a state at 25 MHz).
fn trace_span(vcd: &str) -> (u64, u64) {
    let at = vcd
        .find("Trace from state ")
        .expect("the span in the header");
    let words: Vec<&str> = vcd[at..].split_whitespace().collect();
    let a = words[3].parse().expect("start");
    let last: u64 = vcd
        .lines()
        .last()
        .and_then(|l| l.strip_prefix('#'))
        .and_then(|n| n.parse().ok())
        .expect("the last timestamp");
    (a, last / 4)
}

/// The phase names in the VCD file, in order.
fn vcd_phases(vcd: &str) -> Vec<String> {
    let id = vcd
        .lines()
        .find(|l| l.starts_with("$var string"))
        .and_then(|l| l.split_whitespace().nth(3))
        .expect("the phase variable");
    vcd.lines()
        .filter_map(|l| l.strip_prefix('s'))
        .filter_map(|l| l.strip_suffix(&format!(" {id}")))
        .map(str::to_string)
        .collect()
}

#[test]
fn run_vcd_traces_a_window_of_one_robot_and_changes_no_result() {
    let dir = temp_dir("vcd");
    let plain = dir.join("plain");
    let traced = dir.join("traced");
    let vcd = dir.join("robot2.vcd");
    let args = run_args(&plain);
    ok(&h8swarm(
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
    ));
    let mut args = run_args(&traced);
    for a in ["--vcd", vcd.to_str().unwrap(), "--vcd-robot", "2"] {
        args.push(a.to_string());
    }
    for a in ["--vcd-from", "3", "--vcd-steps", "2"] {
        args.push(a.to_string());
    }
    ok(&h8swarm(
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
    ));
    for f in ["metrics.csv", "summary.json"] {
        assert_eq!(
            std::fs::read(plain.join(f)).unwrap(),
            std::fs::read(traced.join(f)).unwrap(),
            "{f}: tracing changed the run"
        );
    }
    let text = std::fs::read_to_string(&vcd).unwrap();
    assert!(text.contains("$timescale 10 ns $end"), "40 ns states");
    assert!(text.contains("robot 2 of h8swarm run arena (learning run, repeat 0"));
    assert!(text.contains("steps 3 to 4"));
    for s in [
        "TIOCA1", "TIOCA2", "PB0", "PB3", "SDA", "SCL", "ADST", "ADF", "IMIA0", "SLEEP",
    ] {
        assert!(text.contains(&format!(" {s} $end")), "{s} declared");
    }
    // From where the robot is before step 3 (asleep after step 2's work) to step 5's
    // sensing: steps 3 and 4 and the end of step 2's behaviour, 0.45 s a step.
    let (a, b) = trace_span(&text);
    let period = 11_250_000;
    assert!(a > 2 * period && a < 3 * period, "starts at {a}");
    assert!(b > 5 * period && b < 6 * period, "ends at {b}");
    assert!(b - a > 2 * period && b - a < 3 * period);
    let phases = vcd_phases(&text);
    for f in ["ad_scan", "learner_forward", "motors_set", "tick_isr"] {
        assert!(phases.iter().any(|p| p == f), "{f} in {phases:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn emu_trace_and_vcd_name_the_same_phases() {
    let dir = temp_dir("phases");
    let vcd = dir.join("boot.vcd");
    let out = h8swarm(&[
        "emu",
        "firmware/robot.mot",
        "--max-states",
        "800000",
        "--trace",
        "--vcd",
        vcd.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(124));
    let trace = String::from_utf8_lossy(&out.stderr);
    let mut from_trace: Vec<String> = Vec::new();
    for line in trace.lines().filter(|l| l.contains(" states  ")) {
        let name = line.rsplit("  ").next().unwrap().to_string();
        if from_trace.last() != Some(&name) {
            from_trace.push(name);
        }
    }
    let from_vcd = vcd_phases(&std::fs::read_to_string(&vcd).unwrap());
    assert!(from_vcd.len() > 20, "{from_vcd:?}");
    assert!(from_vcd.iter().any(|p| p == "learner_forward"));
    assert_eq!(from_trace, from_vcd);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_under_gdb_stops_at_a_breakpoint_and_detaches_to_the_same_results() {
    let dir = temp_dir("gdb");
    let plain = dir.join("plain");
    let debugged = dir.join("debugged");
    ok(&h8swarm(
        &run_args(&plain)
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    ));
    let mut args = run_args(&debugged);
    for a in ["--gdb", "127.0.0.1:0", "--gdb-robot", "1"] {
        args.push(a.to_string());
    }
    let mut child = Command::new(env!("CARGO_BIN_EXE_h8swarm"))
        .args(&args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    stderr.read_line(&mut line).unwrap();
    let addr = line
        .split_whitespace()
        .find(|w| w.starts_with("127.0.0.1:"))
        .unwrap_or_else(|| panic!("no address in {line:?}"));
    let mut gdb = gdb_client::Client::connect(addr.parse().unwrap());
    gdb.handshake();
    let fw = robot_board::firmware::Firmware::robot().unwrap();
    let forward = fw.symbols.addr("learner_forward").unwrap();
    let steps = fw.symbols.addr("steps").unwrap();
    assert_eq!(gdb.ask(&format!("Z0,{forward:x},2")), "OK");
    // The forward passes of steps 0, 1 and 2 (step 0 runs at the first tick after boot).
    for _ in 0..3 {
        let stop = gdb.ask("c");
        assert!(stop.contains("swbreak"), "{stop}");
        assert_eq!(gdb.registers()[9], forward);
    }
    // Stopped: the swarm waits (the run has not ended).
    std::thread::sleep(std::time::Duration::from_millis(300));
    assert!(child.try_wait().unwrap().is_none(), "the run went on");
    let n = gdb.read(steps, 4).unwrap();
    assert_eq!(
        u32::from_be_bytes(n.try_into().unwrap()),
        2,
        "two steps done"
    );
    assert_eq!(gdb.ask("D"), "OK");
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    for f in ["metrics.csv", "summary.json"] {
        assert_eq!(
            std::fs::read(plain.join(f)).unwrap(),
            std::fs::read(debugged.join(f)).unwrap(),
            "{f}: the debugger changed the run"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_probe_values_are_one_line_errors_with_their_statuses() {
    let dir = temp_dir("bad");
    let out_dir = dir.join("out");
    let out_s = out_dir.display().to_string();
    let vcd = dir.join("t.vcd").display().to_string();
    let no_dir = dir.join("no/such/dir/t.vcd").display().to_string();
    let base = [
        "run",
        "arena",
        "--robots",
        "3",
        "--steps",
        "4",
        "--repeats",
        "1",
        "--out",
        &out_s,
    ];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "--controller",
                "firmware",
                "--vcd",
                &vcd,
                "--vcd-robot",
                "3",
            ],
            "--vcd-robot 3: the run has 3 robots (valid: 0 to 2)",
        ),
        (
            vec!["--controller", "model", "--vcd", &vcd],
            "--vcd-robot 0: robot 0 runs the Rust model",
        ),
        (
            vec!["--controller", "firmware", "--vcd", &vcd, "--vcd-from", "4"],
            "--vcd-from 4: the run has 4 steps (valid: 0 to 3)",
        ),
        (
            vec![
                "--controller",
                "firmware",
                "--vcd",
                &vcd,
                "--vcd-steps",
                "0",
            ],
            "--vcd-steps 0",
        ),
        (
            vec!["--controller", "firmware", "--vcd", &no_dir],
            "--vcd: cannot create",
        ),
        (
            vec!["--controller", "firmware", "--gdb", "0.0.0.0:3333"],
            "not a loopback address",
        ),
        (
            vec!["--controller", "firmware", "--gdb", "nowhere"],
            "is not an address and port",
        ),
        (
            vec![
                "--controller",
                "firmware",
                "--gdb",
                "127.0.0.1:0",
                "--gdb-robot",
                "7",
            ],
            "--gdb-robot 7: the run has 3 robots",
        ),
        (
            vec!["--controller", "firmware", "--vcd-robot", "1"],
            "--vcd",
        ),
    ];
    for (extra, expected) in cases {
        let args: Vec<&str> = base.iter().copied().chain(extra.iter().copied()).collect();
        let out = h8swarm(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        // A trace file that cannot be made is an output that cannot be written: the tool
        // failed (status 1); every other case is bad input (status 2).
        let status = if expected == "--vcd: cannot create" {
            1
        } else {
            2
        };
        assert_eq!(out.status.code(), Some(status), "{extra:?}: {stderr}");
        assert!(stderr.contains(expected), "{extra:?}: {stderr}");
        assert!(!stderr.contains("panicked"));
        // (clap's own usage error for an option without the one it needs has more lines.)
        if expected != "--vcd" {
            assert_eq!(
                stderr.trim_end().lines().count(),
                1,
                "{extra:?}: one line: {stderr}"
            );
        }
    }
    for (args, expected) in [
        (
            vec!["emu", "firmware/robot.mot", "--vcd", no_dir.as_str()],
            "--vcd: cannot create",
        ),
        (
            vec!["emu", "firmware/robot.mot", "--gdb", "10.1.2.3:1234"],
            "not a loopback address",
        ),
        (
            vec![
                "emu",
                "firmware/robot.mot",
                "--symbols",
                "no/such.sym",
                "--max-states",
                "10",
            ],
            "cannot read symbol file",
        ),
    ] {
        let out = h8swarm(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
