//! Hostile input, generated: scenario TOML, replay lines, S-records, argument vectors, sweep
//! files with Slurm fields, merges of corrupted sweep folders, raw GDB sessions, signals
//! during runs and runs under a memory limit, mutated from valid ones by proptest. Each family
//! runs `H8SWARM_FUZZ_CASES` cases (default 2 000, the same ones each time; set it for a
//! soak, which draws new ones), but for two that start a process per case and run it: the
//! signals (default 100 cases) and the memory limits (default 300), each case a real run of
//! 0.1 to 0.5 s, so that their 2 000 would take many minutes in CI; a soak sets their
//! counts too. The library families go through the entry points the binary runs; the
//! argument vectors, signals and limits run the real binary in a folder of its own. Every
//! case must end without a panic or an abort, with an exit status docs/limits-and-failures.md promises, a
//! one-line error first when it fails, and no file written outside the folder it ran in.

use std::cell::{Cell, RefCell};
use std::io::BufReader;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use proptest::prelude::*;

mod common;
use common::fuzzing::*;

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
            match swarm::scenario::Scenario::from_toml(&text) {
                Ok(s) => {
                    ok.set(ok.get() + 1);
                    // What a run checks next must not panic either.
                    let _ = h8swarm::resources::estimated_memory(&s, 2);
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
    use h8swarm::commands::learn::{Engine, ReplayFailure, run};
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
    use h8_3052f::run::{RunOptions, run_image};
    let (loaded, refused) = (Cell::new(0u32), Cell::new(0u32));
    runner()
        .run(&srec_text(), |bytes| {
            let mut console = Vec::new();
            match run_image(
                &bytes,
                &RunOptions {
                    max_states: Some(20_000),
                    ..RunOptions::default()
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

/// A `[slurm]` value: numbers of every size and sign, Slurm's time formats and near misses,
/// words, control characters.
fn slurm_value() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("0".to_string()),
        Just("1".to_string()),
        Just("-1".to_string()),
        Just("1001".to_string()),
        Just("1002".to_string()),
        Just("4096".to_string()),
        Just("4097".to_string()),
        Just("18446744073709551615".to_string()),
        Just("9223372036854775807".to_string()),
        (0u64..100_000).prop_map(|v| v.to_string()),
        Just("\"UNLIMITED\"".to_string()),
        Just("\"infinite\"".to_string()),
        Just("\"-x\"".to_string()),
        Just("\"short\"".to_string()),
        Just("\"1-24\"".to_string()),
        Just("\"12:00:00\\n#SBATCH --array=0-9\"".to_string()),
        Just("\"a\\u001b[2Jb\"".to_string()),
        "[0-9:-]{0,12}".prop_map(|t| format!("\"{t}\"")),
        "[a-zA-Z0-9_.,:=@/+ -]{0,16}".prop_map(|t| format!("\"{t}\"")),
        prop::collection::vec("--[a-z-]{1,12}(=[a-z0-9:-]{0,8})?", 0..3)
            .prop_map(|v| format!("{v:?}")),
    ]
}

#[test]
fn sweep_files_with_slurm_fields_plan_safe_scripts_or_fail_in_one_line() {
    use h8swarm::sweep::plan::{PLAN_OPTIONS, slurm_time_minutes, write_plan};
    use h8swarm::sweep::spec::parse;
    let keys = [
        "time",
        "cpus_per_task",
        "mem_mb",
        "max_cpus",
        "points_per_task",
        "max_parallel",
        "max_array_size",
        "partition",
        "account",
        "extra",
        "qos",
    ];
    let root = family_dir_in_memory("slurm");
    let (ok, bad, n) = (Cell::new(0u32), Cell::new(0u32), Cell::new(0u32));
    runner()
        .run(
            &(
                prop_oneof![9 => 1u32..4, 1 => 495u32..506],
                prop::collection::vec((0..keys.len(), slurm_value()), 0..5),
            ),
            |(seeds, fields)| {
                n.set(n.get() + 1);
                let mut text = format!(
                    "seeds = {seeds}\n[set]\nsteps = 10\nwindow = 10\nrepeats = 1\n[grid]\n\"learner.threshold\" = [10, 20]\n[slurm]\n"
                );
                for (k, v) in &fields {
                    text.push_str(&format!("{} = {v}\n", keys[*k]));
                }
                let dir = root.join(format!("c{}", n.get()));
                let planned = parse(&text, Path::new("fuzz.toml"))
                    .and_then(|s| write_plan(&s, &text, &dir, Some(Path::new("/bin/h8swarm"))));
                match planned {
                    Ok(_) => {
                        ok.set(ok.get() + 1);
                        let script = std::fs::read_to_string(dir.join("sweep.sbatch")).unwrap();
                        prop_assert!(printable_text(&script), "{script:?}");
                        let mut max_array = 1001u64;
                        for (k, v) in &fields {
                            if keys[*k] == "max_array_size" {
                                max_array = v.parse().unwrap_or(max_array);
                            }
                        }
                        for l in script.lines().filter(|l| l.starts_with("#SBATCH ")) {
                            let opt = &l["#SBATCH ".len()..];
                            if let Some(t) = opt.strip_prefix("--time=") {
                                prop_assert!(slurm_time_minutes(t).is_ok(), "{l}");
                            }
                            if let Some(a) = opt.strip_prefix("--array=0-") {
                                let last: u64 = a.split('%').next().unwrap().parse().unwrap();
                                prop_assert!(last < max_array, "{l}");
                            }
                            let name = opt.split('=').next().unwrap();
                            let own = PLAN_OPTIONS.contains(&name);
                            let count = script
                                .lines()
                                .filter(|x| x.starts_with(&format!("#SBATCH {name}")))
                                .count();
                            prop_assert!(!own || count == 1, "{name} twice: {script}");
                        }
                    }
                    Err(e) => {
                        bad.set(bad.get() + 1);
                        let m = e.to_string();
                        prop_assert!(!m.contains('\n'), "{m}");
                        prop_assert!(printable_text(&m), "{m:?}");
                        one_line_first(&m)?;
                        prop_assert!(!dir.join("sweep.sbatch").exists());
                    }
                }
                let _ = std::fs::remove_dir_all(&dir);
                Ok(())
            },
        )
        .unwrap();
    let _ = std::fs::remove_dir_all(&root);
    let (ok, bad) = (ok.get(), bad.get());
    eprintln!("fuzz: slurm fields: {ok} planned, {bad} refused");
    assert!(ok > 0 && bad > 0, "ok {ok}, refused {bad}");
}

/// One way to damage a sweep folder.
#[derive(Clone, Debug)]
enum Damage {
    /// Remove point k's folder.
    DeletePoint(usize),
    /// Overwrite byte p (per mille of the file) of file f of point k.
    Byte(usize, usize, u16, u8),
    /// Cut file f of point k to p per mille.
    Truncate(usize, usize, u16),
    /// A folder where file f of point k was.
    Folder(usize, usize),
    /// A temporary folder of a task under points/, named so.
    Temporary(String),
    /// Overwrite byte p of plan.json (0) or points.jsonl (1).
    PlanByte(usize, u16, u8),
}

fn damage() -> impl Strategy<Value = Damage> {
    prop_oneof![
        2 => any::<usize>().prop_map(Damage::DeletePoint),
        4 => (any::<usize>(), any::<usize>(), 0u16..1000, any::<u8>())
            .prop_map(|(k, f, p, b)| Damage::Byte(k, f, p, b)),
        2 => (any::<usize>(), any::<usize>(), 0u16..1000).prop_map(|(k, f, p)| Damage::Truncate(k, f, p)),
        1 => (any::<usize>(), any::<usize>()).prop_map(|(k, f)| Damage::Folder(k, f)),
        2 => prop_oneof![
            "\\.\\.?tmp-p000[0-2]-s[1-3]-[a-z]{1,6}-[0-9]{1,7}(\\.partial-[0-9]{1,7})?",
            "\\.tmp-[ -~\u{1b}\n]{0,12}",
        ]
        .prop_map(Damage::Temporary),
        1 => (0usize..2, 0u16..1000, any::<u8>()).prop_map(|(f, p, b)| Damage::PlanByte(f, p, b)),
    ]
}

fn poke(path: &Path, per_mille: u16, byte: Option<u8>) {
    let Ok(mut bytes) = std::fs::read(path) else {
        return;
    };
    let at = (usize::from(per_mille) * bytes.len()) / 1000;
    match byte {
        Some(b) if at < bytes.len() => bytes[at] = b,
        Some(_) => {}
        None => bytes.truncate(at),
    }
    let _ = std::fs::write(path, bytes);
}

#[test]
fn merges_of_corrupted_sweep_folders_list_what_is_wrong_and_keep_the_users_files() {
    use h8swarm::sweep::merge::merge;
    let root = family_dir_in_memory("merge");
    let sweep = root.join("s.toml");
    std::fs::write(
        &sweep,
        "seeds = 3\n[set]\nsteps = 10\nwindow = 10\nrepeats = 1\nrobots = 2\n",
    )
    .unwrap();
    let pristine = root.join("pristine");
    let text = std::fs::read_to_string(&sweep).unwrap();
    let s = h8swarm::sweep::spec::parse(&text, &sweep).unwrap();
    h8swarm::sweep::plan::write_plan(&s, &text, &pristine, Some(Path::new("/bin/true"))).unwrap();
    h8swarm::sweep::exec::run_task(&pristine, None, Some(1), &h8swarm::commands::run::run_file)
        .unwrap();
    let ids: Vec<String> = (0..3).map(|i| format!("p000{i}-s{}", i + 1)).collect();
    let files = ["status.json", "scenario.toml", "summary.json"];
    // What merge reads: the plan, the run list, and three files of each point.
    let mut kept: Vec<(String, Vec<u8>)> = Vec::new();
    for f in ["plan.json", "points.jsonl"] {
        kept.push((f.to_string(), std::fs::read(pristine.join(f)).unwrap()));
    }
    for id in &ids {
        for f in files {
            let rel = format!("points/{id}/{f}");
            kept.push((rel.clone(), std::fs::read(pristine.join(&rel)).unwrap()));
        }
    }
    let (complete, listed, refused) = (Cell::new(0u32), Cell::new(0u32), Cell::new(0u32));
    let n = Cell::new(0u32);
    runner()
        .run(&prop::collection::vec(damage(), 0..5), |damages| {
            n.set(n.get() + 1);
            // One folder for every case, put back as it was (rewriting files in place is
            // much cheaper than making folders afresh).
            let dir = root.join("case");
            for e in std::fs::read_dir(dir.join("points"))
                .into_iter()
                .flatten()
                .flatten()
            {
                if !ids.iter().any(|id| e.file_name() == id.as_str()) {
                    let _ = std::fs::remove_dir_all(e.path());
                }
            }
            for (rel, bytes) in &kept {
                let p = dir.join(rel);
                if p.is_dir() {
                    std::fs::remove_dir_all(&p).unwrap();
                }
                std::fs::create_dir_all(p.parent().unwrap()).unwrap();
                if std::fs::read(&p).ok().as_deref() != Some(bytes.as_slice()) {
                    std::fs::write(&p, bytes).unwrap();
                }
            }
            for d in &damages {
                let file =
                    |k: usize, f: usize| dir.join("points").join(&ids[k % 3]).join(files[f % 3]);
                match d {
                    Damage::DeletePoint(k) => {
                        let _ = std::fs::remove_dir_all(dir.join("points").join(&ids[k % 3]));
                    }
                    Damage::Byte(k, f, p, b) => poke(&file(*k, *f), *p, Some(*b)),
                    Damage::Truncate(k, f, p) => poke(&file(*k, *f), *p, None),
                    Damage::Folder(k, f) => {
                        let p = file(*k, *f);
                        if p.parent().is_some_and(Path::exists) {
                            let _ = std::fs::remove_file(&p);
                            let _ = std::fs::create_dir_all(p.join("x"));
                        }
                    }
                    Damage::Temporary(name) => {
                        let _ = std::fs::create_dir_all(dir.join("points").join(name));
                    }
                    Damage::PlanByte(f, p, b) => {
                        poke(&dir.join(["plan.json", "points.jsonl"][*f]), *p, Some(*b));
                    }
                }
            }
            let out = dir.join("report");
            if !out.join("notes.txt").exists() {
                std::fs::create_dir_all(out.join("plots")).unwrap();
                std::fs::write(out.join("plots/mine.pdf"), b"mine").unwrap();
                std::fs::write(out.join("notes.txt"), b"notes").unwrap();
            }
            match merge(&dir, Some(&out)) {
                Ok((text, all)) => {
                    if all {
                        complete.set(complete.get() + 1);
                    } else {
                        listed.set(listed.get() + 1);
                    }
                    prop_assert!(printable_text(&text), "{text:?}");
                    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
                    prop_assert_eq!(csv.lines().count(), 4, "{}", csv);
                    let doc: serde_json::Value = serde_json::from_str(
                        &std::fs::read_to_string(out.join("sweep.json")).unwrap(),
                    )
                    .unwrap();
                    let listed_ids = ["failed", "missing", "broken"]
                        .iter()
                        .map(|k| doc[k].as_array().map_or(0, Vec::len))
                        .sum::<usize>();
                    prop_assert_eq!(listed_ids + doc["ok"].as_u64().unwrap() as usize, 3);
                }
                Err(e) => {
                    refused.set(refused.get() + 1);
                    let m = e.to_string();
                    prop_assert!(!m.contains('\n') && printable_text(&m), "{m:?}");
                    one_line_first(&m)?;
                }
            }
            prop_assert_eq!(std::fs::read(out.join("plots/mine.pdf")).unwrap(), b"mine");
            prop_assert_eq!(std::fs::read(out.join("notes.txt")).unwrap(), b"notes");
            Ok(())
        })
        .unwrap();
    let _ = std::fs::remove_dir_all(&root);
    let (c, l, r) = (complete.get(), listed.get(), refused.get());
    eprintln!("fuzz: merges: {c} complete, {l} with points listed, {r} refused");
    assert!(c > 0 && l > 0 && r > 0, "{c} {l} {r}");
}

/// One thing a GDB client sends: a packet body (sent with a right checksum), or raw bytes.
#[derive(Clone, Debug)]
enum Wire {
    /// `$body#xx`, expecting `+` and a reply.
    Packet(String),
    /// `$body#00` with a wrong checksum, expecting `-`.
    BadSum(String),
    /// A packet longer than the stub takes, expecting `+` and `E07`.
    Long(usize),
    /// Bytes no reply is promised to (junk, Ctrl-C, `+`).
    Raw(Vec<u8>),
    /// `-`: the last reply again, if there was one.
    Nak,
}

fn wire() -> impl Strategy<Value = Wire> {
    let addr = prop_oneof![
        Just(0u32),
        Just(0x100),
        Just(0xFF_DF10),
        Just(0xFF_E000),
        Just(0xFF_FF00),
        any::<u32>()
    ];
    let body = prop_oneof![
        Just("?".to_string()),
        Just("g".to_string()),
        Just("qSupported".to_string()),
        Just("qSupported:multiprocess+;swbreak+;hwbreak+".to_string()),
        Just("qSupported:;".to_string()),
        Just("qXfer:features:read:target.xml:0,fff".to_string()),
        Just("qRcmd,636c6f636b".to_string()),
        Just("qRcmd,zz".to_string()),
        Just("qAttached".to_string()),
        Just("qC".to_string()),
        Just("Hg0".to_string()),
        Just("vCont?".to_string()),
        Just("s".to_string()),
        Just("vCont;s".to_string()),
        Just("p9".to_string()),
        Just("G00".to_string()),
        (addr.clone(), 0usize..300).prop_map(|(a, n)| format!("m{a:x},{n:x}")),
        (addr.clone(), prop::collection::vec(any::<u8>(), 0..8)).prop_map(|(a, b)| format!(
            "M{a:x},{:x}:{}",
            b.len(),
            b.iter().map(|x| format!("{x:02x}")).collect::<String>()
        )),
        (0u8..5, addr.clone(), 0u32..9).prop_map(|(k, a, n)| format!("Z{k},{a:x},{n:x}")),
        (0u8..5, addr, 0u32..9).prop_map(|(k, a, n)| format!("z{k},{a:x},{n:x}")),
        "[ -~]{0,24}".prop_filter("no framing bytes", |t| !t.contains(['$', '#', '}', '*'])),
    ];
    prop_oneof![
        8 => body.clone().prop_map(Wire::Packet),
        1 => body.prop_map(Wire::BadSum),
        1 => (4_100usize..20_000).prop_map(Wire::Long),
        1 => prop_oneof![
            prop::collection::vec(
                any::<u8>().prop_filter("not a packet start or a NAK", |b| *b != b'$' && *b != b'-'),
                1..40
            ),
            Just(vec![0x03]),
            Just(b"+".to_vec()),
        ]
        .prop_map(Wire::Raw),
        1 => Just(Wire::Nak),
    ]
}

fn rsp_packet(body: &[u8]) -> Vec<u8> {
    let sum = body.iter().fold(0u8, |a, b| a.wrapping_add(*b));
    let mut p = vec![b'$'];
    p.extend_from_slice(body);
    p.extend_from_slice(format!("#{sum:02x}").as_bytes());
    p
}

/// Reads one byte; `None` when the stub closed the connection.
fn rsp_byte(s: &mut std::net::TcpStream) -> Option<u8> {
    use std::io::Read;
    let mut b = [0u8; 1];
    loop {
        return match s.read(&mut b) {
            Ok(1) => Some(b[0]),
            Ok(_) => None,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset => None,
            Err(e) => panic!("the stub does not answer: {e}"),
        };
    }
}

/// The next reply packet's body (acknowledged), skipping anything before its `$`.
fn rsp_reply(s: &mut std::net::TcpStream) -> Option<String> {
    use std::io::Write;
    while rsp_byte(s)? != b'$' {}
    let mut body = Vec::new();
    loop {
        match rsp_byte(s)? {
            b'#' => break,
            b => body.push(b),
        }
    }
    rsp_byte(s)?;
    rsp_byte(s)?;
    let _ = s.write_all(b"+");
    Some(String::from_utf8_lossy(&body).into_owned())
}

#[test]
fn raw_gdb_sessions_get_protocol_answers_and_never_hang_the_stub() {
    use h8_3052f::gdb::GdbListener;
    use h8_3052f::mcu::{Mcu, McuConfig};
    use h8_3052f::pins::NullBoard;
    use h8_3052f::run::{Probes, RunOptions, run_mcu_probed};
    use robot_board::firmware::Firmware;
    use std::io::Write;
    let fw = Firmware::robot().unwrap();
    let (alive, ended) = (Cell::new(0u32), Cell::new(0u32));
    runner()
        .run(&prop::collection::vec(wire(), 0..10), |items| {
            let listener = GdbListener::bind("127.0.0.1:0").unwrap();
            let addr = listener.local_addr();
            let fw = fw.clone();
            let run = std::thread::spawn(move || {
                let mut debugger = listener.accept().unwrap();
                let mut mcu = Mcu::new(McuConfig::default(), NullBoard).unwrap();
                let mut cpu = h8300h::cpu::Cpu::new();
                fw.install(&mut mcu, &mut cpu, None).unwrap();
                run_mcu_probed(
                    &mut cpu,
                    &mut mcu,
                    &RunOptions {
                        max_states: Some(1_000_000),
                        ..RunOptions::default()
                    },
                    &mut std::io::sink(),
                    Probes {
                        debugger: Some(&mut debugger),
                        ..Probes::default()
                    },
                )
                .map(|r| r.outcome)
            });
            let mut s = std::net::TcpStream::connect(addr).unwrap();
            // A stub that stops answering fails the case instead of hanging the test.
            s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
            // Small writes go at once (as a debugger sends them), not held for an ACK.
            s.set_nodelay(true).unwrap();
            let mut open = true;
            let mut last: Option<String> = None;
            for item in &items {
                if !open {
                    break;
                }
                match item {
                    Wire::Packet(body) => {
                        s.write_all(&rsp_packet(body.as_bytes())).unwrap();
                        match rsp_byte(&mut s) {
                            Some(b'+') => loop {
                                // Console output (`O…`, a monitor command's) comes first.
                                match rsp_reply(&mut s) {
                                    Some(r) if r.starts_with('O') && r != "OK" => {}
                                    Some(r) => {
                                        last = Some(r);
                                        break;
                                    }
                                    None => {
                                        open = false;
                                        break;
                                    }
                                }
                            },
                            Some(other) => prop_assert!(false, "{body}: {:?}", other as char),
                            None => open = false,
                        }
                    }
                    Wire::BadSum(body) => {
                        let mut p = rsp_packet(body.as_bytes());
                        let n = p.len();
                        let bad = if &p[n - 2..] == b"00" { b"01" } else { b"00" };
                        p[n - 2..].copy_from_slice(bad);
                        s.write_all(&p).unwrap();
                        match rsp_byte(&mut s) {
                            Some(b) => prop_assert_eq!(b, b'-', "{}", body),
                            None => open = false,
                        }
                    }
                    Wire::Long(n) => {
                        s.write_all(&rsp_packet(&vec![b'm'; *n])).unwrap();
                        prop_assert_eq!(rsp_byte(&mut s), Some(b'+'));
                        let r = rsp_reply(&mut s);
                        prop_assert_eq!(r.as_deref(), Some("E07"));
                        last = r;
                    }
                    Wire::Nak => {
                        s.write_all(b"-").unwrap();
                        if let Some(want) = &last {
                            let again = rsp_reply(&mut s);
                            prop_assert_eq!(again.as_ref(), Some(want));
                        }
                    }
                    Wire::Raw(bytes) => {
                        let _ = s.write_all(bytes);
                    }
                }
            }
            // Still answering: a request whose reply is unmistakable, then detach.
            if open {
                let _ = s.write_all(&rsp_packet(b"qXfer:features:read:target.xml:0,fff"));
                let mut answered = false;
                while let Some(r) = rsp_reply(&mut s) {
                    if r.contains("<?xml") || r.starts_with('W') || r.starts_with('X') {
                        answered = true;
                        break;
                    }
                }
                if answered {
                    alive.set(alive.get() + 1);
                    let _ = s.write_all(&rsp_packet(b"D"));
                } else {
                    ended.set(ended.get() + 1);
                }
            } else {
                ended.set(ended.get() + 1);
            }
            drop(s);
            let outcome = run.join();
            prop_assert!(outcome.is_ok(), "the program's side panicked");
            prop_assert!(outcome.unwrap().is_ok());
            Ok(())
        })
        .unwrap();
    let (alive, ended) = (alive.get(), ended.get());
    eprintln!(
        "fuzz: gdb sessions: {alive} still answering at the end, {ended} ended by the program"
    );
    assert!(alive > 0, "{alive} {ended}");
}

/// Waits for `child` at most 120 s (a case may not hang); its exit status.
/// Files of `dir` (names and bytes), sorted.
fn files_of(dir: &Path) -> Vec<(std::ffi::OsString, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| e.path().is_file())
        .map(|e| (e.file_name(), std::fs::read(e.path()).unwrap_or_default()))
        .collect();
    v.sort();
    v
}

#[test]
fn signals_during_runs_leave_the_old_results_or_the_new_ones_and_no_staging_folder() {
    use std::os::unix::process::ExitStatusExt;
    let root = family_dir("signals");
    // The results of an earlier run, to be kept or replaced whole.
    let earlier = root.join("earlier");
    let run_args = |out: &Path, seed: &str, steps: &str| -> Vec<String> {
        [
            "run",
            "--steps",
            steps,
            "--robots",
            "3",
            "--repeats",
            "1",
            "--threads",
            "2",
            "--seed",
            seed,
            "--out",
        ]
        .iter()
        .map(|s| s.to_string())
        .chain([out.display().to_string()])
        .collect()
    };
    let st = Command::new(env!("CARGO_BIN_EXE_h8swarm"))
        .args(run_args(&earlier, "1", "40"))
        .stdout(Stdio::null())
        .status()
        .unwrap();
    assert!(st.success());
    let old = files_of(&earlier);
    let (finished, stopped) = (Cell::new(0u32), Cell::new(0u32));
    let n = Cell::new(0u32);
    runner_of(cases_or(100))
        .run(
            &(
                prop_oneof![Just("INT"), Just("TERM"), Just("HUP")],
                0u64..400,
                prop_oneof![Just("40"), Just("400"), Just("4000")],
            ),
            |(signal, delay_ms, steps)| {
                n.set(n.get() + 1);
                let case = root.join(format!("c{}", n.get()));
                let out = case.join("o");
                std::fs::create_dir_all(&out).unwrap();
                for (name, bytes) in &old {
                    std::fs::write(out.join(name), bytes).unwrap();
                }
                let mut child = Command::new(env!("CARGO_BIN_EXE_h8swarm"))
                    .args(run_args(&out, "2", steps))
                    .stdin(Stdio::null())
                    .stdout(Stdio::null())
                    .stderr(Stdio::null())
                    .spawn()
                    .unwrap();
                // The signal comes at a drawn moment: before, during or after the work.
                std::thread::sleep(Duration::from_millis(delay_ms));
                let _ = Command::new("kill")
                    .args([&format!("-{signal}"), &child.id().to_string()])
                    .stderr(Stdio::null())
                    .status();
                let st = wait_bounded(&mut child, "a signalled run");
                let number = match signal {
                    "INT" => 2,
                    "TERM" => 15,
                    _ => 1,
                };
                if st.success() {
                    finished.set(finished.get() + 1);
                } else {
                    stopped.set(stopped.get() + 1);
                    prop_assert_eq!(st.signal(), Some(number), "{:?}", st);
                }
                // Nothing beside the output folder, and in it the old files or the new ones.
                let beside: Vec<_> = entries(&case);
                prop_assert_eq!(beside, vec![std::ffi::OsString::from("o")]);
                let now = files_of(&out);
                if now != old {
                    let summary: serde_json::Value =
                        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap())
                            .unwrap();
                    prop_assert_eq!(summary["scenario"]["seed"].as_u64(), Some(2));
                    for f in ["metrics.csv", "fit.json", "learning.png", "learning.svg"] {
                        prop_assert!(out.join(f).is_file(), "{} missing", f);
                    }
                }
                let _ = std::fs::remove_dir_all(&case);
                Ok(())
            },
        )
        .unwrap();
    let _ = std::fs::remove_dir_all(&root);
    let (f, s) = (finished.get(), stopped.get());
    eprintln!("fuzz: signals: {f} runs finished first, {s} stopped by the signal");
    assert!(s > 0, "{f} {s}");
}

/// ITU1 driving a PWM edge every 50 states while the CPU loops: see tests/hostile.rs.
const FAST_PWM_MOT: &str = "S113000000000100000000000000000000000000EB\nS1130100F820386E790000636B80FF747900003248\nS11101106B80FF76F8023862F802386040FE19\nS9030000FC\n";

#[test]
fn runs_under_a_memory_limit_finish_or_are_refused_never_aborted() {
    use std::os::unix::process::ExitStatusExt;
    let root = family_dir("rlimit");
    let pwm = root.join("pwm.mot");
    std::fs::write(&pwm, FAST_PWM_MOT).unwrap();
    let statuses = RefCell::new(std::collections::BTreeMap::new());
    let n = Cell::new(0u32);
    let command = prop_oneof![
        3 => (
            prop_oneof![Just("1"), Just("3"), Just("10"), Just("2000"), Just("1000000")],
            prop_oneof![Just("5"), Just("20")],
            prop_oneof![Just("1"), Just("2"), Just("16")],
            prop_oneof![Just("model"), Just("firmware")],
        )
            .prop_map(|(robots, steps, threads, kind)| {
                // Firmware robots are slow: only few of them run.
                let robots = if kind == "firmware" && robots == "10" { "3" } else { robots };
                vec![
                    "run".to_string(),
                    "--robots".into(),
                    robots.into(),
                    "--steps".into(),
                    steps.into(),
                    "--repeats".into(),
                    "1".into(),
                    "--threads".into(),
                    threads.into(),
                    "--controller".into(),
                    kind.into(),
                ]
            }),
        1 => prop_oneof![Just("1000000"), Just("30000000")].prop_map(|states| {
            vec![
                "emu".to_string(),
                "PWM".into(),
                "--max-states".into(),
                states.into(),
                "--vcd".into(),
                "VCD".into(),
            ]
        }),
    ];
    // Address-space limits from far too small to plenty, KiB.
    let limit = prop_oneof![
        50_000u64..150_000,
        150_000u64..600_000,
        600_000u64..4_000_000
    ];
    runner_of(cases_or(300))
        .run(&(command, limit), |(args, kib)| {
            n.set(n.get() + 1);
            let case = root.join(format!("c{}", n.get()));
            std::fs::create_dir_all(&case).unwrap();
            let mut args: Vec<String> = args
                .into_iter()
                .map(|a| match a.as_str() {
                    "PWM" => pwm.display().to_string(),
                    "VCD" => case.join("t.vcd").display().to_string(),
                    _ => a,
                })
                .collect();
            if args[0] == "run" {
                args.push("--out".into());
                args.push(case.join("o").display().to_string());
            }
            let mut script = format!("ulimit -v {kib} && exec \"$0\"");
            for i in 1..=args.len() {
                script.push_str(&format!(" \"${{{i}}}\""));
            }
            let mut child = Command::new("sh")
                .arg("-c")
                .arg(script)
                .arg(env!("CARGO_BIN_EXE_h8swarm"))
                .args(&args)
                .current_dir(&case)
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap();
            let st = wait_bounded(&mut child, "a run under a memory limit");
            let mut err = String::new();
            use std::io::Read;
            child
                .stderr
                .take()
                .unwrap()
                .read_to_string(&mut err)
                .unwrap();
            prop_assert!(
                st.signal().is_none(),
                "{args:?} under {kib} KiB: killed by signal {:?}: {err}",
                st.signal()
            );
            let code = st.code().unwrap();
            // 127: the shell could not even start the program in so little space.
            let promised = matches!(code, 0..=2 | 127) || (args[0] == "emu" && code == 124);
            prop_assert!(promised, "{args:?} under {kib} KiB: status {code}: {err}");
            prop_assert!(
                !err.contains("panicked") && !err.contains("memory allocation"),
                "{err}"
            );
            if (1..=2).contains(&code) {
                prop_assert!(err.starts_with("error:"), "{args:?}: {err}");
            }
            if code == 0 && args[0] == "run" {
                prop_assert!(case.join("o/summary.json").is_file());
            }
            *statuses.borrow_mut().entry(code).or_insert(0u32) += 1;
            let _ = std::fs::remove_dir_all(&case);
            Ok(())
        })
        .unwrap();
    let _ = std::fs::remove_dir_all(&root);
    let statuses = statuses.into_inner();
    eprintln!("fuzz: memory limits: exit statuses {statuses:?}");
    assert!(
        statuses.contains_key(&0) && statuses.contains_key(&2),
        "{statuses:?}"
    );
}
