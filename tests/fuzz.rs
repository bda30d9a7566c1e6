//! Hostile input, generated (issue 13): scenario TOML, replay lines, S-records and argument
//! vectors, mutated from valid ones by proptest. Each family runs `H8SWARM_FUZZ_CASES` cases
//! (default 2 000, the same ones each time; set it for a soak, which draws new ones). The first three go through the library's entry
//! points (the code the binary runs on them); the argument vectors run the real binary in a
//! folder of its own. Every case must end without a panic or an abort, with an exit status the
//! README promises, a one-line error first when it fails, and no file written outside the
//! folder it ran in.

use std::cell::{Cell, RefCell};
use std::io::BufReader;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

fn cases() -> u32 {
    std::env::var("H8SWARM_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2_000)
}

/// The same cases on every CI run (a fixed seed); a soak (`H8SWARM_FUZZ_CASES` set) draws new
/// ones each time.
fn runner() -> TestRunner {
    let config = Config {
        cases: cases(),
        failure_persistence: None,
        ..Config::default()
    };
    if std::env::var_os("H8SWARM_FUZZ_CASES").is_some() {
        TestRunner::new(config)
    } else {
        let rng = proptest::test_runner::TestRng::deterministic_rng(config.rng_algorithm);
        TestRunner::new_with_rng(config, rng)
    }
}

/// Values that break things: wrong types, signs, sizes, special floats, long strings.
fn hostile_value() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("-1".to_string()),
        Just("0".to_string()),
        Just("-0".to_string()),
        Just("4294967296".to_string()),
        Just("9223372036854775807".to_string()),
        Just("1e308".to_string()),
        Just("-1e-308".to_string()),
        Just("nan".to_string()),
        Just("inf".to_string()),
        Just("true".to_string()),
        Just("\"junk\"".to_string()),
        Just("\"../../x\"".to_string()),
        Just("[0, 1, 2, 3, 4]".to_string()),
        Just("[0, 1, 2, 3, \"junk\", {a = 1}]".to_string()),
        Just("[]".to_string()),
        Just("{a = 1}".to_string()),
        Just(format!("\"{}\"", "x".repeat(10_000))),
        any::<i64>().prop_map(|v| v.to_string()),
        any::<f64>()
            .prop_filter("finite", |v| v.is_finite())
            .prop_map(|v| format!("{v:?}")),
        (0u32..2_000_000).prop_map(|v| v.to_string()),
    ]
}

/// One edit of a line-based text.
#[derive(Clone, Debug)]
enum Edit {
    /// Replace the value of line k (after `=`) with a hostile value.
    Value(usize, String),
    /// Delete line k.
    Delete(usize),
    /// Duplicate line k.
    Duplicate(usize),
    /// Insert a raw line before line k.
    Insert(usize, String),
    /// Flip a byte at a position (per mille of the text's length) to a printable one.
    Byte(u16, u8),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        4 => (any::<usize>(), hostile_value()).prop_map(|(k, v)| Edit::Value(k, v)),
        1 => any::<usize>().prop_map(Edit::Delete),
        1 => any::<usize>().prop_map(Edit::Duplicate),
        1 => (any::<usize>(), prop_oneof![
            Just("[learner]".to_string()),
            Just("[[zip]]".to_string()),
            Just("robts = 4".to_string()),
            Just("base = \"moon\"".to_string()),
            Just("controller.image = \"/dev/zero\"".to_string()),
            Just("[controller]\nkind = \"firmware\"\nrobots = [0, 99]".to_string()),
            "[a-z_.]{1,12} = [0-9a-z\"]{0,6}",
        ]).prop_map(|(k, l)| Edit::Insert(k, l)),
        1 => (0u16..1000, 0x20u8..0x7f).prop_map(|(p, b)| Edit::Byte(p, b)),
    ]
}

fn apply(text: &str, edits: &[Edit]) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for e in edits {
        let n = lines.len().max(1);
        match e {
            Edit::Value(k, v) => {
                if let Some(l) = lines.get_mut(k % n)
                    && let Some((key, _)) = l.split_once('=')
                {
                    *l = format!("{key}= {v}");
                }
            }
            Edit::Delete(k) => {
                if !lines.is_empty() {
                    lines.remove(k % n);
                }
            }
            Edit::Duplicate(k) => {
                if let Some(l) = lines.get(k % n).cloned() {
                    lines.insert(k % n, l);
                }
            }
            Edit::Insert(k, l) => lines.insert(k % n, l.clone()),
            Edit::Byte(p, b) => {
                let mut all = lines.join("\n").into_bytes();
                if !all.is_empty() {
                    let last = all.len() - 1;
                    let at = (usize::from(*p) * all.len() / 1000).min(last);
                    all[at] = *b;
                }
                lines = String::from_utf8_lossy(&all)
                    .lines()
                    .map(str::to_string)
                    .collect();
            }
        }
    }
    lines.join("\n") + "\n"
}

/// An error's first line says what; it must exist and not be empty.
fn one_line_first(message: &str) -> Result<(), TestCaseError> {
    let first = message.lines().next().unwrap_or("");
    prop_assert!(!first.trim().is_empty(), "an empty error: {message:?}");
    Ok(())
}

#[test]
fn scenario_files_never_panic_and_fail_in_one_line() {
    let example = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/example.toml"),
    )
    .expect("the example scenario");
    let (ok, bad) = (Cell::new(0u32), Cell::new(0u32));
    runner()
        .run(&prop::collection::vec(edit(), 1..6), |edits| {
            let text = apply(&example, &edits);
            match h8swarm::scenario::Scenario::from_toml(&text) {
                Ok(s) => {
                    ok.set(ok.get() + 1);
                    // What a run checks next must not panic either.
                    let _ = h8swarm::run_cmd::estimated_memory(&s, 2);
                    let _ = s.with_overrides(Some(7), Some(3), Some(1), Some(2));
                }
                Err(e) => {
                    bad.set(bad.get() + 1);
                    let m = e.to_string();
                    prop_assert!(!m.contains('\n'), "the first line is the whole error: {m}");
                    one_line_first(&m)?;
                }
            }
            Ok(())
        })
        .unwrap();
    // The generator reaches both sides.
    let (ok, bad) = (ok.get(), bad.get());
    eprintln!("fuzz: {ok} accepted, {bad} refused");
    assert!(ok > 0 && bad > 0, "ok {ok}, refused {bad}");
}

/// A replay line: a valid one, mutated.
fn replay_text() -> impl Strategy<Value = Vec<u8>> {
    let header = r#"{"n_in": 13, "n_out": 4, "eta": 33, "threshold": 10, "weights": [[1,2,3,4,5,6,7,8,9,10,11,12,13],[0,0,0,0,0,0,0,0,0,0,0,0,0],[-5,-5,-5,-5,-5,-5,-5,-5,-5,-5,-5,-5,-5],[32767,-32768,1,1,1,1,1,1,1,1,1,1,1]]}"#;
    let step = r#"{"x": [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13], "e": 12}"#;
    let text = format!("{header}\n{step}\n{step}\n{step}\n");
    (
        prop::collection::vec(
            prop_oneof![
                3 => (any::<u16>(), hostile_value()).prop_map(|(p, v)| (p, v.into_bytes())),
                3 => (any::<u16>(), (-128i32..128).prop_map(|v| v.to_string().into_bytes())),
                1 => (any::<u16>(), prop::collection::vec(any::<u8>(), 1..8)),
                1 => (any::<u16>(), Just(b"\n".to_vec())),
            ],
            0..4,
        ),
        Just(text),
    )
        .prop_map(|(edits, text)| {
            let mut b = text.into_bytes();
            for (p, bytes) in edits {
                let at = usize::from(p) % b.len();
                // Replace a number-ish run at `at` by the bytes.
                let end = (at..b.len())
                    .find(|&i| !(b[i].is_ascii_digit() || b[i] == b'-'))
                    .unwrap_or(b.len())
                    .max(at + 1)
                    .min(b.len());
                b.splice(at..end, bytes);
            }
            b
        })
}

#[test]
fn replay_lines_never_panic_and_fail_at_a_line() {
    use h8swarm::replay::{Engine, ReplayFailure, run};
    let (ok, bad) = (Cell::new(0u32), Cell::new(0u32));
    runner()
        .run(&replay_text(), |bytes| {
            let mut input = BufReader::new(&bytes[..]);
            let mut out = Vec::new();
            match run(&mut input, &mut out, true, &Engine::Model) {
                Ok(_) => ok.set(ok.get() + 1),
                Err(ReplayFailure::Input(e)) => {
                    bad.set(bad.get() + 1);
                    prop_assert!(e.line >= 1);
                    let m = e.to_string();
                    prop_assert!(m.starts_with(&format!("line {}", e.line)), "{m}");
                    prop_assert!(!m.contains('\n'), "{m}");
                }
                Err(other) => prop_assert!(false, "not an input error: {other:?}"),
            }
            // Every line written is JSON.
            for l in String::from_utf8(out).unwrap().lines() {
                prop_assert!(serde_json::from_str::<serde_json::Value>(l).is_ok(), "{l}");
            }
            Ok(())
        })
        .unwrap();
    let (ok, bad) = (ok.get(), bad.get());
    eprintln!("fuzz: {ok} accepted, {bad} refused");
    assert!(ok > 0 && bad > 0, "ok {ok}, refused {bad}");
}

/// S-record text: records of every type with random fields, some with right checksums.
fn srec_text() -> impl Strategy<Value = Vec<u8>> {
    // Mostly data records (S1 above all: 16-bit addresses are all in the flash) with right
    // checksums, so that many images load and run;
    // every other type and wrong checksums now and then.
    let kind = prop_oneof![6 => Just(1u8), 2 => 2u8..4, 1 => 0u8..10];
    let good_sum = prop_oneof![9 => Just(true), 1 => Just(false)];
    let record = (
        kind,
        prop::collection::vec(any::<u8>(), 0..40),
        good_sum,
        any::<u8>(),
    )
        .prop_map(|(kind, body, good_sum, junk)| {
            let count = body.len() + 1;
            let mut sum: u32 = count as u32;
            for b in &body {
                sum += u32::from(*b);
            }
            let check = if good_sum { !(sum as u8) } else { junk };
            let mut line = format!("S{kind}{:02X}", count.min(255));
            for b in &body {
                line.push_str(&format!("{b:02X}"));
            }
            line.push_str(&format!("{check:02X}"));
            line
        });
    (
        prop::collection::vec(record, 0..12),
        prop_oneof![3 => Just(Vec::new()), 1 => prop::collection::vec(any::<u8>(), 0..4)],
    )
        .prop_map(|(records, noise)| {
            let mut text = records.join("\n").into_bytes();
            // A little noise: stray bytes at the end (CR, NUL, non-ASCII...).
            text.extend(noise);
            text
        })
}

#[test]
fn s_records_never_panic_and_images_that_load_run_to_a_stop() {
    use emu::chip::run::{RunOptions, run_image};
    let (loaded, refused) = (Cell::new(0u32), Cell::new(0u32));
    runner()
        .run(&srec_text(), |bytes| {
            let mut console = Vec::new();
            match run_image(
                &bytes,
                &RunOptions {
                    max_states: Some(20_000),
                },
                &mut console,
                None,
            ) {
                Ok(_) => loaded.set(loaded.get() + 1),
                Err(e) => {
                    refused.set(refused.get() + 1);
                    let m = e.to_string();
                    prop_assert!(!m.contains('\n'), "{m}");
                    one_line_first(&m)?;
                }
            }
            Ok(())
        })
        .unwrap();
    let (loaded, refused) = (loaded.get(), refused.get());
    eprintln!("fuzz: s-records: {loaded} loaded and run, {refused} refused");
    assert!(
        loaded > 0 && refused > 0,
        "loaded {loaded}, refused {refused}"
    );
}

/// An argument vector from the tool's own vocabulary, with hostile values.
fn argv() -> impl Strategy<Value = Vec<String>> {
    let value = prop_oneof![
        Just("0".to_string()),
        Just("-1".to_string()),
        Just("1".to_string()),
        Just("3".to_string()),
        Just("65536".to_string()),
        Just("4294967295".to_string()),
        Just("18446744073709551616".to_string()),
        Just("1e9".to_string()),
        Just("nan".to_string()),
        Just("".to_string()),
        Just("arena".to_string()),
        Just("corridor".to_string()),
        Just("moon".to_string()),
        Just("/dev/null".to_string()),
        Just("/dev/zero".to_string()),
        Just("sub/dir".to_string()),
        Just("no/such/file".to_string()),
        Just("firmware".to_string()),
        Just("model".to_string()),
        Just("5%".to_string()),
        Just("1K".to_string()),
        Just("127.0.0.1:1".to_string()),
        "[ -~]{0,12}",
    ];
    let option = prop_oneof![
        Just("--robots"),
        Just("--steps"),
        Just("--repeats"),
        Just("--seed"),
        Just("--threads"),
        Just("--out"),
        Just("--controller"),
        Just("--firmware"),
        Just("--max-memory"),
        Just("--outputs"),
        Just("--history"),
        Just("--eta"),
        Just("--threshold"),
        Just("--replay"),
        Just("--max-states"),
        Just("--inputs"),
        Just("--cpu-budget"),
        Just("--phase"),
        Just("--vcd"),
        Just("--gdb-robot"),
        Just("--json"),
        Just("--states"),
        Just("--bogus"),
    ];
    let sub = prop_oneof![
        Just("run"),
        Just("cost"),
        Just("learn"),
        Just("fit"),
        Just("emu"),
        Just("sweep"),
        Just("frobnicate"),
    ];
    (
        sub,
        prop::collection::vec((option, value.clone()), 0..5),
        prop::option::of(value),
    )
        .prop_map(|(sub, opts, positional)| {
            let mut v = vec![sub.to_string()];
            v.extend(positional);
            for (o, val) in opts {
                // A run's own memory cap is the one below.
                if sub == "run" && o == "--max-memory" {
                    continue;
                }
                v.push(o.to_string());
                v.push(val);
            }
            // Runs that would be long are refused early: a cap on memory that every real run
            // exceeds (the parse and the checks before it are what is fuzzed here).
            if sub == "run" {
                v.push("--max-memory".into());
                v.push("1K".into());
            }
            if sub == "cost" && !v.iter().any(|a| a == "--steps") {
                v.push("--steps".into());
                v.push("50".into());
            }
            if sub == "emu" && !v.iter().any(|a| a == "--max-states") {
                v.push("--max-states".into());
                v.push("100000".into());
            }
            v
        })
}

fn entries(dir: &Path) -> Vec<std::ffi::OsString> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .map(|r| r.filter_map(|e| e.ok().map(|e| e.file_name())).collect())
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn argument_vectors_end_with_a_promised_status_and_write_only_where_they_ran() {
    let base = std::env::temp_dir().join(format!("h8swarm-fuzz-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    let cwd = base.join("cwd");
    std::fs::create_dir_all(&cwd).unwrap();
    let outside_before = entries(&base);
    let statuses = RefCell::new(std::collections::BTreeMap::new());
    let n = Cell::new(0u32);
    runner()
        .run(&argv(), |args| {
            n.set(n.get() + 1);
            let started = Instant::now();
            let mut child = Command::new(env!("CARGO_BIN_EXE_h8swarm"))
                .args(&args)
                .current_dir(&cwd)
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .expect("the binary starts");
            // A case may not hang: 60 s at most (a debug build).
            let status = loop {
                if let Some(s) = child.try_wait().unwrap() {
                    break s;
                }
                if started.elapsed() > Duration::from_secs(60) {
                    let _ = child.kill();
                    prop_assert!(false, "{args:?} did not end within 60 s");
                }
                std::thread::sleep(Duration::from_millis(2));
            };
            let mut stderr = String::new();
            use std::io::Read;
            child
                .stderr
                .take()
                .unwrap()
                .read_to_string(&mut stderr)
                .unwrap();
            prop_assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
            let code = status.code();
            prop_assert!(
                code.is_some(),
                "{args:?}: killed by a signal (abort?): {stderr}"
            );
            let code = code.unwrap();
            let promised =
                matches!(code, 0..=2) || (args[0] == "emu" && (code <= 126 || code == 137));
            prop_assert!(promised, "{args:?}: status {code}: {stderr}");
            if code != 0 && args[0] != "emu" {
                let first = stderr.lines().next().unwrap_or("");
                prop_assert!(first.starts_with("error:"), "{args:?}: {stderr}");
            }
            *statuses.borrow_mut().entry(code).or_insert(0u32) += 1;
            prop_assert_eq!(
                &entries(&base),
                &outside_before,
                "{:?} wrote outside its folder",
                args
            );
            Ok(())
        })
        .unwrap();
    let _ = std::fs::remove_dir_all(&base);
    // Both success and refusals occur.
    let (statuses, n) = (statuses.into_inner(), n.get());
    eprintln!("fuzz: argument vectors: exit statuses {statuses:?} over {n} cases");
    assert!(
        statuses.contains_key(&0) && statuses.contains_key(&2),
        "{statuses:?} over {n}"
    );
}
