//! Drives the real `h8swarm` binary: the replay of docs/design.md §2.6 checked line by line against an
//! independent reference written here, its error reports, and the cost summary.

use std::io::Write;
use std::process::{Command, Output, Stdio};

use serde_json::Value;

fn h8swarm(args: &[&str], stdin: Option<&str>) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_h8swarm"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    if let Some(text) = stdin {
        child
            .stdin
            .take()
            .expect("stdin is piped")
            .write_all(text.as_bytes())
            .expect("stdin takes the input");
    }
    child.wait_with_output().expect("the binary runs")
}

/// The learner core of docs/design.md §2.3–2.4 in i64, written from the spec for this test.
struct Reference {
    n: usize,
    eta: i64,
    t: i64,
    w: Vec<Vec<i64>>,
}

impl Reference {
    fn step(&mut self, x: &[i64], e: i64) -> Value {
        let y: Vec<i64> = self
            .w
            .iter()
            .map(|row| row.iter().zip(x).map(|(a, b)| a * b).sum())
            .collect();
        let win = (0..y.len()).fold(0, |best, j| if y[j] > y[best] { j } else { best });
        let m = y[win];
        let o: Vec<i64> = if m < 1 << 22 {
            y.iter().map(|v| (v >> 7).clamp(-32768, 32767)).collect()
        } else {
            let s = 64 - m.leading_zeros() as i64 - 15;
            let ms = m >> s;
            y.iter()
                .map(|v| {
                    let vs = v >> s;
                    if vs <= -ms {
                        -32768
                    } else {
                        ((vs << 15) / ms).min(32767)
                    }
                })
                .collect()
        };
        if e.abs() > self.t {
            let se = if e > 0 { self.eta } else { -self.eta };
            for (j, row) in self.w.iter_mut().enumerate() {
                let s = if j == win { 1 } else { -1 };
                for (wi, xi) in row.iter_mut().zip(x) {
                    let exact = (se * xi) as f64 / 128.0;
                    let d = (exact.abs() + 0.5).floor().copysign(exact) as i64;
                    *wi = (*wi + s * d).clamp(-32768, 32767);
                }
            }
        }
        serde_json::json!({"y": y, "o": o, "win": win, "weights": self.w})
    }
}

fn ints(v: &Value) -> Vec<i64> {
    v.as_array()
        .expect("an array")
        .iter()
        .map(|n| n.as_i64().expect("an integer"))
        .collect()
}

#[test]
fn replay_of_the_shipped_example_matches_the_reference_line_by_line() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/replay-arena.jsonl"
    ))
    .expect("the example exists");
    let mut lines = text.lines();
    let header: Value = serde_json::from_str(lines.next().expect("a header")).expect("json");
    let mut reference = Reference {
        n: header["n_in"].as_u64().expect("n_in") as usize,
        eta: header["eta"].as_i64().expect("eta"),
        t: header["threshold"].as_i64().expect("threshold"),
        w: header["weights"]
            .as_array()
            .expect("rows")
            .iter()
            .map(ints)
            .collect(),
    };
    let out = h8swarm(&["learn", "--replay", "examples/replay-arena.jsonl"], None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).expect("utf-8");
    let produced: Vec<&str> = stdout.lines().collect();
    let steps: Vec<&str> = lines.collect();
    assert_eq!(produced.len(), steps.len());
    let mut updates = 0;
    for (k, (step, got)) in steps.iter().zip(&produced).enumerate() {
        let step: Value = serde_json::from_str(step).expect("json");
        let x = ints(&step["x"]);
        assert_eq!(x.len(), reference.n);
        let before = reference.w.clone();
        let expected = reference.step(&x, step["e"].as_i64().expect("e"));
        updates += usize::from(before != reference.w);
        let got: Value = serde_json::from_str(got).expect("output is json");
        assert_eq!(got, expected, "step {}", k + 1);
    }
    assert!(
        updates > 10,
        "the example exercises the update ({updates} steps changed weights)"
    );
}

#[test]
fn replay_reads_standard_input_and_writes_compact_lines() {
    let input = "{\"n_in\": 1, \"n_out\": 2, \"eta\": 32767, \"threshold\": 0, \"weights\": [[1], [0]]}\n{\"x\": [-128], \"e\": 1}\n";
    let out = h8swarm(&["learn", "--replay", "-"], Some(input));
    assert!(out.status.success());
    // y = [−128, 0]: win 1; Δ = round(32767·−128/128) = −32767; winner 0 − 32767, loser 1 + 32767.
    assert_eq!(
        String::from_utf8(out.stdout).expect("utf-8"),
        "{\"y\":[-128,0],\"o\":[-1,0],\"win\":1,\"weights\":[[32767],[-32767]]}\n"
    );
}

#[test]
fn replay_with_states_adds_the_h8_cost() {
    let out = h8swarm(
        &[
            "learn",
            "--replay",
            "examples/replay-arena.jsonl",
            "--states",
        ],
        None,
    );
    assert!(out.status.success());
    let first: Value = serde_json::from_str(
        String::from_utf8(out.stdout)
            .expect("utf-8")
            .lines()
            .next()
            .expect("a line"),
    )
    .expect("json");
    assert!(first["states"]["forward"].as_u64().expect("forward states") > 52 * 40);
    assert!(first["states"]["update"].is_u64());
}

#[test]
fn malformed_lines_stop_with_line_field_and_status_2_keeping_earlier_output() {
    let input = "{\"n_in\": 2, \"n_out\": 2, \"eta\": 1, \"threshold\": 1, \"weights\": [[1, 2], [3, 4]]}\n\
                 {\"x\": [1, 2], \"e\": 5}\n\
                 {\"x\": [1, -129], \"e\": 5}\n\
                 {\"x\": [1, 2], \"e\": 5}\n";
    let out = h8swarm(&["learn", "--replay", "-"], Some(input));
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 1);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("line 3: field `x[1]`: -129 is out of range"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn missing_file_and_bad_options_are_errors_not_panics() {
    let out = h8swarm(&["learn", "--replay", "no/such/file.jsonl"], None);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("cannot open replay file `no/such/file.jsonl`"),
        "{stderr}"
    );

    for args in [
        &["cost", "--outputs", "5"][..],
        &["cost", "--history", "9"],
        &["cost", "--eta", "-1"],
        &["cost", "--steps", "0"],
        &["cost", "--steps", "4294967295"],
        &["cost", "--steps", "10000001"],
        &["fit", "--steps", "4294967295"],
        &["fit", "--steps", "1000001"],
        &["learn"],
        &["frobnicate"],
    ] {
        let out = h8swarm(args, None);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
    }
    let out = h8swarm(&["cost", "--step-period-s", "0", "--steps", "10"], None);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--step-period-s"));
}

#[test]
fn cost_summary_reports_phases_and_ram() {
    let out = h8swarm(&["cost", "--steps", "200", "--json"], None);
    assert!(out.status.success());
    let r: Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(r["n_in"], 13);
    assert_eq!(r["n_out"], 4);
    assert_eq!(r["ram_bytes"], 176);
    let fwd_min = r["forward_states"]["min"].as_u64().expect("min");
    // 52 multiply-accumulates at 40 states and 52 loop iterations at 6 are a floor.
    assert!(fwd_min >= 52 * 46, "{fwd_min}");
    let plain = h8swarm(&["cost", "--steps", "200"], None);
    assert!(String::from_utf8_lossy(&plain.stdout).contains("RAM on the H8"));
    let default = h8swarm(&[], None);
    assert!(default.status.success());
    assert!(String::from_utf8_lossy(&default.stdout).contains("worst step"));
}

#[test]
fn emu_runs_a_differential_program_with_its_console_and_status() {
    let out = h8swarm(&["emu", "emu/tests/programs/switch.mot", "--stats"], None);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let expected = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/emu/tests/programs/switch.expected"
    ))
    .expect("the expected output is committed");
    assert_eq!(out.stdout, expected);
    let stats: Value = serde_json::from_str(
        String::from_utf8_lossy(&out.stderr)
            .lines()
            .last()
            .expect("a stats line"),
    )
    .expect("stats are JSON");
    assert_eq!(stats["outcome"], "halted");
    assert!(
        stats["states"].as_u64().expect("states")
            > stats["instructions"].as_u64().expect("instructions")
    );
}

#[test]
fn emu_trace_budget_and_bad_images_have_their_exit_statuses() {
    let out = h8swarm(
        &[
            "emu",
            "emu/tests/programs/arith.mot",
            "--trace",
            "--max-states",
            "200",
        ],
        None,
    );
    assert_eq!(out.status.code(), Some(124));
    let trace = String::from_utf8_lossy(&out.stderr);
    assert!(trace.starts_with("0000f4: mov.l #0xffff10,er7"), "{trace}");
    assert!(trace.contains("6 states"));

    let dir = std::env::temp_dir().join(format!("h8swarm-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    // Reset vector pointing at H'100000, outside ROM and RAM: the first fetch is refused.
    let outside = dir.join("outside.mot");
    std::fs::write(&outside, "S107000000100000E8\nS9030000FC\n").expect("write");
    let out = h8swarm(&["emu", outside.to_str().expect("utf-8 path")], None);
    assert_eq!(out.status.code(), Some(125));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("100000"), "{stderr}");

    let corrupt = dir.join("corrupt.mot");
    std::fs::write(&corrupt, "S107000000100000E9\n").expect("write");
    let out = h8swarm(&["emu", corrupt.to_str().expect("utf-8 path")], None);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("line 1"), "{stderr}");
    assert!(!stderr.contains("panicked"));

    let out = h8swarm(&["emu", "no/such/image.mot"], None);
    assert_eq!(out.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("h8swarm-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Runs h8swarm with `args`, which must succeed; its standard output.
fn succeeds(args: &[&str]) -> String {
    let out = h8swarm(args, None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).to_string()
}

#[test]
fn run_writes_identical_metrics_for_any_thread_count() {
    // Runs spread over the threads (3 and 80 robots, six runs), and one run of 4 200 robots
    // whose stages (the per-robot meters too) run in parallel inside it, alone on its pool:
    // with a second worker spinning through its world's sub-steps (on 8 threads too, more
    // than this machine's cores).
    let learning_only = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/arena-learning-only.toml"
    );
    for (scenario, robots, repeats) in [
        ("arena", "3", "2"),
        ("arena", "80", "2"),
        (learning_only, "4200", "1"),
    ] {
        let mut files = Vec::new();
        for threads in ["1", "2", "8"] {
            let dir = temp_dir(&format!("det-{robots}-{threads}"));
            let stdout = succeeds(&[
                "run",
                scenario,
                "--steps",
                "40",
                "--repeats",
                repeats,
                "--robots",
                robots,
                "--threads",
                threads,
                "--out",
                dir.to_str().expect("utf-8 path"),
            ]);
            assert!(stdout.contains("learning.png"), "{stdout}");
            for f in h8swarm::outputs::OUTPUT_FILES
                .iter()
                .filter(|f| !matches!(**f, "spacetime.png" | "replay.html"))
            {
                assert!(dir.join(f).exists(), "{f} written");
            }
            files.push((
                std::fs::read(dir.join("metrics.csv")).expect("metrics"),
                std::fs::read(dir.join("summary.json")).expect("summary"),
            ));
            let _ = std::fs::remove_dir_all(&dir);
        }
        assert!(files[0].0.len() > 1000);
        for (k, threads) in [(1, 2), (2, 8)] {
            assert!(
                files[0] == files[k],
                "{robots} robots: 1 and {threads} threads give different outputs"
            );
        }
    }
}

/// A run of one repeat says "1 repeat" and gives no interval legend, since it has no intervals.
#[test]
fn one_repeat_is_worded_as_one_and_promises_no_intervals() {
    let dir = temp_dir("one-repeat");
    let out = h8swarm(
        &[
            "run",
            "arena",
            "--steps",
            "60",
            "--repeats",
            "1",
            "--out",
            dir.to_str().expect("utf-8 path"),
        ],
        None,
    );
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(!stdout.contains("1 repeats"), "{stdout}");
    assert!(!stdout.contains("95 % interval"), "{stdout}");
    assert!(stdout.contains("one repeat, so no intervals"), "{stdout}");
}

#[test]
fn the_report_counts_the_contact_solves_the_cap_stopped_under_each_solver() {
    let dir = temp_dir("solver-line");
    let file = dir.with_extension("toml");
    std::fs::write(&file, "[world]\nsolver = \"converged\"\n").expect("scenario file");
    let newton_file = dir.with_extension("newton.toml");
    std::fs::write(&newton_file, "[world]\nsolver = \"newton\"\n").expect("scenario file");
    let line = |scenario: &str| {
        let stdout = succeeds(&[
            "run",
            scenario,
            "--steps",
            "300",
            "--repeats",
            "1",
            "--out",
            dir.to_str().expect("utf-8 path"),
        ]);
        stdout
            .lines()
            .find(|l| l.starts_with("contact solver"))
            .unwrap_or_else(|| panic!("no solver line: {stdout}"))
            .to_string()
    };
    let capped = line("arena");
    let converged = line(file.to_str().expect("utf-8 path"));
    let newton = line(newton_file.to_str().expect("utf-8 path"));
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_file(&file);
    let _ = std::fs::remove_file(&newton_file);
    // The numbers of the line: islands, sweeps each, islands at the cap, their share, the cap.
    let numbers = |l: &str| -> Vec<f64> {
        l.split(|c: char| !(c.is_ascii_digit() || c == '.'))
            .filter_map(|w| w.parse().ok())
            .collect()
    };
    let (a, b) = (numbers(&capped), numbers(&converged));
    assert!(capped.contains("(world.solver = \"capped\")"), "{capped}");
    assert!(
        converged.contains("(world.solver = \"converged\")"),
        "{converged}"
    );
    assert_eq!((a[4], b[4]), (12.0, 256.0), "{capped} / {converged}");
    // 300 steps of three robots in the arena meet the walls; the capped solve stops at its
    // cap in some islands, the converged one in far fewer.
    assert!(a[0] > 1000.0 && a[2] > 0.0, "{capped}");
    assert!(b[3] < a[3], "{capped} / {converged}");
    // Newton's method: every island of three robots is small enough for it (none by sweeps),
    // and its cap stops fewer solves than the capped solver's.
    assert!(newton.contains("(world.solver = \"newton\")"), "{newton}");
    let c = numbers(&newton);
    // islands, Newton's, steps each, by sweeps, sweeps each, capped, share, outer cap, sweep cap
    assert_eq!(c.len(), 9, "{newton}");
    assert!(c[0] > 1000.0 && c[1] == c[0] && c[3] == 0.0, "{newton}");
    assert!(c[2] >= 1.0 && c[6] < a[3], "{capped} / {newton}");
    assert_eq!((c[7], c[8]), (64.0, 256.0), "{newton}");
}

#[test]
fn run_reports_bad_scenarios_and_folders_clearly() {
    let dir = temp_dir("bad");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let bad_key = dir.join("bad_key.toml");
    std::fs::write(&bad_key, "robots = 3\n[learner]\neta_q15 = 33\n").expect("write");
    let bad_value = dir.join("bad_value.toml");
    std::fs::write(&bad_value, "[world]\nmotor_time_constant_s = 0.5\n").expect("write");
    let bad_channel = dir.join("bad_channel.toml");
    std::fs::write(&bad_channel, "[sensors]\nchannels = [0, 1, 2, 9]\n").expect("write");
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["run".into(), bad_channel.display().to_string()],
            "`sensors.channels` = [0, 1, 2, 9]: sensor_channels[3] (right) = 9: an analog input the H8/3052F has: 0 to 7 (AN0 to AN7)",
        ),
        (vec!["run".into(), bad_key.display().to_string()], "eta_q15"),
        (
            vec!["run".into(), bad_value.display().to_string()],
            "world.motor_time_constant_s",
        ),
        (
            vec!["run".into(), "moon".into()],
            "unknown built-in scenario `moon`",
        ),
        (
            vec![
                "run".into(),
                "corridor".into(),
                "--robots".into(),
                "40".into(),
            ],
            "robots",
        ),
        (
            vec!["run".into(), "arena".into(), "--steps".into(), "0".into()],
            "`steps` = 0",
        ),
        (
            vec![
                "run".into(),
                "arena".into(),
                "--threads".into(),
                "100000".into(),
            ],
            "--threads 100000: at most",
        ),
    ];
    for (args, expected) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = h8swarm(&args, None);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// An output that cannot be written is the tool failing (status 1), named in one line, and
/// nothing of the run is left behind.
#[test]
fn run_outputs_that_cannot_be_written_are_status_1() {
    let dir = temp_dir("unwritable");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("a-file");
    std::fs::write(&file, "mine\n").expect("write");
    for (out, expected) in [
        (file.clone(), "is a file: give a folder"),
        (file.join("sub"), "cannot create the staging folder"),
    ] {
        let o = h8swarm(
            &[
                "run",
                "--steps",
                "20",
                "--repeats",
                "2",
                "--out",
                out.to_str().unwrap(),
            ],
            None,
        );
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{out:?}: {stderr}");
        assert!(
            stderr.starts_with("error: ") && stderr.contains(expected),
            "{stderr}"
        );
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine\n");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run that fails after it started leaves the earlier results in its folder as they were,
/// says so, and leaves no staging folder.
#[test]
fn a_failed_run_leaves_the_earlier_results_untouched() {
    let dir = temp_dir("atomic");
    let out = dir.join("results");
    let out_s = out.to_str().unwrap();
    let o = h8swarm(
        &["run", "--steps", "30", "--repeats", "2", "--out", out_s],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let before: Vec<(String, Vec<u8>)> = h8swarm::outputs::OUTPUT_FILES
        .iter()
        .filter(|f| !matches!(**f, "spacetime.png" | "replay.html"))
        .map(|f| (f.to_string(), std::fs::read(out.join(f)).expect("written")))
        .collect();
    // A program that is no robot firmware: it halts at once, so the run fails at its first
    // step, after the staging folder was made. (It has no configuration block, so it runs
    // only with the controls off.)
    let scenario = dir.join("halts.toml");
    std::fs::write(
        &scenario,
        "[controls]\nlearning_off = false\nrandom_walk = false\n[controller]\nkind = \"firmware\"\nimage = \"emu/tests/programs/arith.mot\"\n",
    )
    .unwrap();
    let o = h8swarm(
        &[
            "run",
            scenario.to_str().unwrap(),
            "--steps",
            "30",
            "--repeats",
            "2",
            "--seed",
            "9",
            "--out",
            out_s,
        ],
        None,
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_ne!(o.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("the earlier results there are untouched"),
        "{stderr}"
    );
    for (f, bytes) in &before {
        assert_eq!(&std::fs::read(out.join(f)).unwrap(), bytes, "{f} changed");
    }
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    let mut left = left;
    left.sort();
    assert_eq!(
        left,
        vec![
            std::ffi::OsString::from("halts.toml"),
            std::ffi::OsString::from("results")
        ]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Help, version and replay output that cannot be written: status 1, not 0 with nothing
/// written; a replay line without end is refused (status 2) instead of filling the memory.
#[test]
fn writes_to_a_full_device_and_endless_lines_have_their_statuses() {
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full")
    };
    let bin = env!("CARGO_BIN_EXE_h8swarm");
    let run = |args: &[&str], stdout: std::fs::File| {
        Command::new(bin)
            .args(args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .stdout(stdout)
            .stderr(Stdio::piped())
            .output()
            .expect("runs")
    };
    for args in [
        &["--help"][..],
        &["--version"],
        &["learn", "--replay", "examples/replay-arena.jsonl"],
    ] {
        let o = run(args, full());
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains("writing the output"), "{args:?}: {stderr}");
    }
    // Files without end as scenario, sweep, image and symbols: refused at their bound.
    for args in [
        &["run", "/dev/zero"][..],
        &["sweep", "plan", "/dev/zero", "--out", "/nonexistent/x"],
        &["emu", "/dev/zero"],
        &[
            "emu",
            "emu/tests/programs/arith.mot",
            "--symbols",
            "/dev/zero",
        ],
        &["run", "--firmware", "/dev/zero"],
    ] {
        let o = h8swarm(args, None);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains("larger than"), "{args:?}: {stderr}");
    }
    let o = h8swarm(&["learn", "--replay", "/dev/zero"], None);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("longer than 1048576 bytes"), "{stderr}");
}

/// `--replay` changes nothing else: every other file byte for byte as without it; and the
/// page itself is the same for one thread and two.
#[test]
fn replay_changes_no_other_output_and_is_the_same_for_any_thread_count() {
    let run = |name: &str, extra: &[&str]| {
        let dir = temp_dir(name);
        let mut args = vec![
            "run",
            "arena",
            "--steps",
            "150",
            "--repeats",
            "2",
            "--robots",
            "4",
            "--out",
        ];
        let d = dir.to_str().unwrap().to_string();
        args.push(&d);
        args.extend_from_slice(extra);
        let o = h8swarm(&args, None);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        dir
    };
    let plain = run("replay-off", &["--threads", "1"]);
    let rec1 = run("replay-on-1", &["--threads", "1", "--replay"]);
    let rec2 = run(
        "replay-on-2",
        &["--threads", "2", "--replay", "--replay-repeats", "all"],
    );
    let rec2b = run(
        "replay-on-2b",
        &["--threads", "1", "--replay", "--replay-repeats", "0,1"],
    );
    for f in h8swarm::outputs::OUTPUT_FILES {
        if f == "replay.html" || f == "spacetime.png" {
            continue;
        }
        let a = std::fs::read(plain.join(f)).unwrap();
        assert_eq!(
            a,
            std::fs::read(rec1.join(f)).unwrap(),
            "{f} changed by --replay"
        );
    }
    assert!(!plain.join("replay.html").exists());
    let page = std::fs::read(rec2.join("replay.html")).unwrap();
    assert_eq!(
        page,
        std::fs::read(rec2b.join("replay.html")).unwrap(),
        "the page differs between 1 and 2 threads"
    );
    let decoded = h8swarm::viewer::decode(&String::from_utf8(page).unwrap()).unwrap();
    assert_eq!(decoded.header.runs.len(), 6, "3 conditions x 2 repeats");
    assert_eq!(decoded.frames[0].len(), 150);
    assert_eq!(decoded.frames[0][0].len(), 4);
    // No staging leftovers.
    for d in [&plain, &rec1, &rec2, &rec2b] {
        let stray: Vec<_> = std::fs::read_dir(d)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with('.'))
            .collect();
        assert!(stray.is_empty(), "{stray:?}");
        let _ = std::fs::remove_dir_all(d);
    }
    // Bad replay options are one line and status 2.
    for (args, expected) in [
        (
            vec!["run", "--replay", "--replay-stride", "0"],
            "--replay-stride 0",
        ),
        (
            vec!["run", "--repeats", "5", "--replay", "--replay-repeats", "7"],
            "repeat 7 does not exist",
        ),
        (
            vec!["run", "--replay", "--replay-repeats", "x"],
            "is not a repeat",
        ),
        (
            vec!["run", "--replay", "--replay-robots", "9"],
            "--replay-robots 9",
        ),
        (vec!["run", "--replay-stride", "3"], "--replay"),
    ] {
        let o = h8swarm(&args, None);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(expected), "{args:?}: {err}");
    }
}

/// `run --help` (and `-h`) gives the defaults of --robots, --steps, --repeats and --seed: the
/// built-in scenarios' own values, which a run without the option uses.
#[test]
fn run_help_shows_the_scenario_defaults() {
    use swarm::scenario::Scenario;
    let (arena, corridor) = (Scenario::arena(), Scenario::corridor());
    for flag in ["--help", "-h"] {
        let o = h8swarm(&["run", flag], None);
        assert_eq!(o.status.code(), Some(0));
        let help = String::from_utf8_lossy(&o.stdout);
        for (option, a, c) in [
            (
                "--robots",
                arena.robots.to_string(),
                corridor.robots.to_string(),
            ),
            (
                "--steps",
                arena.steps.to_string(),
                corridor.steps.to_string(),
            ),
            (
                "--repeats",
                arena.repeats.to_string(),
                corridor.repeats.to_string(),
            ),
            ("--seed", arena.seed.to_string(), corridor.seed.to_string()),
        ] {
            let want = format!(
                "[default: the scenario's: arena {a}, corridor {c}, a file's own or its base's]"
            );
            let at = help
                .find(&format!("{option} <"))
                .unwrap_or_else(|| panic!("{option}"));
            let next = help[at + 2..]
                .find("\n      --")
                .map_or(help.len(), |n| at + 2 + n);
            assert!(
                help[at..next].contains(&want),
                "{flag}: {option}: {}",
                &help[at..next]
            );
        }
    }
    // The built-ins differ in steps, so the help cannot be showing one value for both.
    assert_ne!(arena.steps, corridor.steps);
}
