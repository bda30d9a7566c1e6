//! Hostile input, generated, round three (docs/testing.md): plans edited by hand, Unicode
//! format characters in every place a name enters, a full disk under `run` and `sweep merge`
//! (a small tmpfs, where the tests run as root), and concurrent sweep tasks, some of them
//! killed. Each family's default number of cases is set so that the four take about a minute
//! in CI; `H8SWARM_FUZZ_CASES` sets them all for a soak (which draws new cases each time).

use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use proptest::prelude::*;

mod common;
use common::fuzzing::*;
use common::tmpfs::Tmpfs;

/// The real binary, run in `dir`, its standard input closed.
fn h8swarm_in(dir: &Path, args: &[String]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_h8swarm"))
        .args(args)
        .current_dir(dir)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SLURM_CPUS_PER_TASK")
        .stdin(Stdio::null())
        .output()
        .expect("the binary runs")
}

fn strings(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| (*s).to_string()).collect()
}

/// A small sweep (3 points: three thresholds, one seed; 10-step runs of 2 robots) planned and
/// run by the library into `dir`.
fn pristine_sweep(root: &Path, name: &str, seed: u64) -> PathBuf {
    let file = root.join(format!("{name}.toml"));
    std::fs::write(
        &file,
        format!(
            "seeds = [{seed}]\n[set]\nsteps = 10\nwindow = 10\nrepeats = 1\nrobots = 2\ncontrols.random_walk = false\n[grid]\n\"learner.threshold\" = [5, 10, 20]\n"
        ),
    )
    .unwrap();
    let text = std::fs::read_to_string(&file).unwrap();
    let s = h8swarm::sweep::spec::parse(&text, &file).unwrap();
    let dir = root.join(name);
    h8swarm::sweep::plan::write_plan(&s, &text, &dir, Some(Path::new("/bin/true"))).unwrap();
    h8swarm::sweep::exec::run_task(&dir, None, Some(1), &h8swarm::commands::run::run_file).unwrap();
    dir
}

/// JSON values a hand may put where a plan had another.
fn hostile_json() -> impl Strategy<Value = serde_json::Value> {
    use serde_json::json;
    prop_oneof![
        Just(json!(-1)),
        Just(json!(0)),
        Just(json!(1)),
        Just(json!(2)),
        Just(json!(7)),
        Just(json!(100_000)),
        Just(json!(u64::MAX)),
        Just(json!(1e300)),
        Just(json!(-0.0)),
        Just(json!(null)),
        Just(json!("p0000")),
        Just(json!("../x")),
        Just(json!([])),
        Just(json!([0])),
        Just(json!([0, 0, 0])),
        Just(json!([[1]])),
        Just(json!({})),
        (0usize..200_000).prop_map(|n| json!((0..n).map(|i| vec![i]).collect::<Vec<_>>())),
        any::<i64>().prop_map(|v| json!(v)),
    ]
}

/// Where in plan.json or a line of points.jsonl the edit goes.
#[derive(Clone, Debug)]
enum PlanEdit {
    /// A top-level field of plan.json.
    Plan(&'static str, serde_json::Value),
    /// A field of an axis of plan.json (`keys` or `values`).
    Axis(usize, &'static str, serde_json::Value),
    /// A second copy of the first axis.
    DoubleAxis,
    /// A field of line k of points.jsonl.
    Line(usize, &'static str, serde_json::Value),
    /// Line k of points.jsonl deleted, or duplicated.
    DropLine(usize),
    /// Line k duplicated.
    DupLine(usize),
}

fn plan_edit() -> impl Strategy<Value = PlanEdit> {
    prop_oneof![
        (
            prop::sample::select(vec!["points", "tasks", "points_per_task", "seeds", "axes"]),
            hostile_json()
        )
            .prop_map(|(k, v)| PlanEdit::Plan(k, v)),
        (
            0usize..2,
            prop::sample::select(vec!["keys", "values"]),
            hostile_json()
        )
            .prop_map(|(a, k, v)| PlanEdit::Axis(a, k, v)),
        Just(PlanEdit::DoubleAxis),
        (
            0usize..4,
            prop::sample::select(vec!["index", "id", "task", "coords", "seed", "scenario"]),
            hostile_json()
        )
            .prop_map(|(l, k, v)| PlanEdit::Line(l, k, v)),
        (0usize..4).prop_map(PlanEdit::DropLine),
        (0usize..4).prop_map(PlanEdit::DupLine),
    ]
}

#[test]
fn plans_edited_by_hand_are_read_or_refused_in_one_line() {
    use h8swarm::sweep::{SweepError, merge::merge, plan::read_plan};
    let root = family_dir_in_memory("edited-plans");
    let pristine = pristine_sweep(&root, "pristine", 1);
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(pristine.join("plan.json")).unwrap())
            .unwrap();
    let lines: Vec<serde_json::Value> = std::fs::read_to_string(pristine.join("points.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let case = root.join("case");
    std::fs::create_dir_all(&case).unwrap();
    // The points' folders are the pristine sweep's (a symbolic link: merge reads them only).
    std::os::unix::fs::symlink(pristine.join("points"), case.join("points")).unwrap();
    let (read, refused) = (Cell::new(0u32), Cell::new(0u32));
    runner_of(cases_or(400))
        .run(&prop::collection::vec(plan_edit(), 1..4), |edits| {
            let mut plan = plan.clone();
            let mut lines = lines.clone();
            for e in &edits {
                match e {
                    PlanEdit::Plan(k, v) => plan[*k] = v.clone(),
                    PlanEdit::Axis(a, k, v) => {
                        if let Some(axis) = plan["axes"].get_mut(*a) {
                            axis[*k] = v.clone();
                        }
                    }
                    PlanEdit::DoubleAxis => {
                        if let Some(axes) = plan["axes"].as_array_mut()
                            && let Some(first) = axes.first().cloned()
                        {
                            axes.push(first);
                        }
                    }
                    PlanEdit::Line(l, k, v) => {
                        if let Some(line) = lines.get_mut(*l) {
                            line[*k] = v.clone();
                        }
                    }
                    PlanEdit::DropLine(l) => {
                        if *l < lines.len() {
                            lines.remove(*l);
                        }
                    }
                    PlanEdit::DupLine(l) => {
                        if let Some(line) = lines.get(*l).cloned() {
                            lines.insert(*l, line);
                        }
                    }
                }
            }
            std::fs::write(case.join("plan.json"), plan.to_string()).unwrap();
            let list: String = lines.iter().map(|l| l.to_string() + "\n").collect();
            std::fs::write(case.join("points.jsonl"), list).unwrap();
            match read_plan(&case) {
                Ok((p, ls)) => {
                    read.set(read.get() + 1);
                    // What was read fits together: merge runs on it.
                    prop_assert_eq!(ls.len(), p.points);
                    let out = root.join("out");
                    match merge(&case, Some(&out)) {
                        Ok((text, _)) => prop_assert!(printable_text(&text)),
                        Err(SweepError::Tool(m)) => prop_assert!(false, "merge failed: {m}"),
                        Err(SweepError::Input(m)) => one_line_first(&m)?,
                    }
                }
                Err(e) => {
                    refused.set(refused.get() + 1);
                    prop_assert!(matches!(e, SweepError::Input(_)), "{e}");
                    let m = e.to_string();
                    prop_assert!(!m.contains('\n') && printable_text(&m), "{m:?}");
                    prop_assert!(m.len() < 2_000, "a long message: {} bytes", m.len());
                }
            }
            Ok(())
        })
        .unwrap();
    let _ = std::fs::remove_dir_all(&root);
    let (r, x) = (read.get(), refused.get());
    eprintln!("fuzz: plans edited by hand: {r} read (and merged), {x} refused");
    assert!(r > 0 && x > 0, "{r} {x}");
}

/// Text with Unicode format characters (bidirectional overrides and isolates, zero-width
/// characters, the byte-order mark, tags, the line separator, the soft hyphen) and control
/// characters among ordinary letters.
fn tricky_text() -> impl Strategy<Value = String> {
    let piece = prop_oneof![
        4 => "[a-z0-9_]{1,6}",
        2 => prop::sample::select(vec![
            "\u{202e}", "\u{202d}", "\u{2066}", "\u{2069}", "\u{200b}", "\u{200d}", "\u{2060}",
            "\u{feff}", "\u{e0041}", "\u{2028}", "\u{2029}", "\u{61c}", "\u{ad}", "\u{200f}",
        ])
        .prop_map(str::to_string),
        1 => prop::sample::select(vec!["\u{1b}[2J", "\n", "\r", "\t", "\u{7}", "\u{9b}"])
            .prop_map(str::to_string),
        1 => prop::sample::select(vec!["é", "Ω", "名前", " "]).prop_map(str::to_string),
    ];
    prop::collection::vec(piece, 1..6).prop_map(|v| v.concat())
}

/// Where a name enters.
#[derive(Clone, Debug)]
enum Entry {
    /// A scenario's `name`.
    ScenarioName,
    /// A scenario file's own name.
    ScenarioFile,
    /// The output folder.
    OutFolder,
    /// A symbol of an image's symbol table (`emu --symbols`).
    Symbol,
    /// A sweep's `name`.
    SweepName,
    /// An option's value.
    OptionValue(&'static str),
}

fn entry() -> impl Strategy<Value = Entry> {
    prop_oneof![
        Just(Entry::ScenarioName),
        Just(Entry::ScenarioFile),
        Just(Entry::OutFolder),
        Just(Entry::Symbol),
        Just(Entry::SweepName),
        prop::sample::select(vec![
            "--replay-stride",
            "--seed",
            "--firmware",
            "--vcd-robot"
        ])
        .prop_map(Entry::OptionValue),
    ]
}

/// Whether `text` holds a character that would act on a terminal (a control other than the
/// line end, or a format character).
fn acts_on_a_terminal(text: &str) -> bool {
    text.chars()
        .any(|c| (c.is_control() && c != '\n') || swarm::terminal_text::is_format_char(c))
}

#[test]
fn format_characters_never_reach_the_terminal_raw() {
    let root = family_dir("format-chars");
    let image = Path::new(env!("CARGO_MANIFEST_DIR")).join("emu/tests/programs/q15learn.mot");
    let small = "steps = 5\nwindow = 5\nrepeats = 1\nrobots = 2\n[controls]\nlearning_off = false\nrandom_walk = false\n";
    let n = Cell::new(0u32);
    runner_of(cases_or(300))
        .run(&(entry(), tricky_text()), |(entry, text)| {
            n.set(n.get() + 1);
            let case = root.join(format!("c{}", n.get()));
            std::fs::create_dir_all(&case).unwrap();
            let quoted = toml::Value::String(text.clone()).to_string();
            let scenario = case.join("s.toml");
            std::fs::write(&scenario, small).unwrap();
            let path = |p: &Path| p.display().to_string();
            let args: Vec<String> = match &entry {
                Entry::ScenarioName => {
                    std::fs::write(&scenario, format!("name = {quoted}\n{small}")).unwrap();
                    strings(&["run", &path(&scenario), "--out", "o"])
                }
                Entry::ScenarioFile => {
                    let named = case.join(format!("{text}.toml"));
                    if std::fs::write(&named, small).is_err() {
                        return Ok(());
                    }
                    strings(&["run", &path(&named)])
                }
                Entry::OutFolder => strings(&["run", &path(&scenario), "--out", &text]),
                Entry::Symbol => {
                    let sym = case.join("p.sym");
                    std::fs::write(&sym, format!("00000100 T _{text}\n")).unwrap();
                    strings(&[
                        "emu",
                        &path(&image),
                        "--symbols",
                        &path(&sym),
                        "--max-states",
                        "1000",
                    ])
                }
                Entry::SweepName => {
                    let sweep = case.join("w.toml");
                    std::fs::write(&sweep, format!("name = {quoted}\n[set]\nsteps = 5\n")).unwrap();
                    strings(&["sweep", "plan", &path(&sweep), "--out", "plan"])
                }
                Entry::OptionValue(option) => strings(&["run", &path(&scenario), option, &text]),
            };
            let o = h8swarm_in(&case, &args);
            let (out, err) = (
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr),
            );
            prop_assert!(!err.contains("panicked"), "{args:?}: {err}");
            prop_assert!(o.status.code().is_some(), "{args:?}: killed: {err}");
            prop_assert!(!acts_on_a_terminal(&out), "{args:?}: stdout {out:?}");
            prop_assert!(!acts_on_a_terminal(&err), "{args:?}: stderr {err:?}");
            let _ = std::fs::remove_dir_all(&case);
            Ok(())
        })
        .unwrap();
    let _ = std::fs::remove_dir_all(&root);
    eprintln!("fuzz: format characters: {} cases", n.get());
}

/// Every file under `dir` with its bytes, sorted by path.
fn tree(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((p.clone(), std::fs::read(&p).unwrap_or_default()));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn a_full_disk_leaves_the_earlier_outputs_whole_or_the_new_ones_complete() {
    let root = family_dir("full-disk");
    let Some(disk) = Tmpfs::mount(&root.join("disk"), 8 * 1024) else {
        eprintln!("SKIPPED: cannot mount a tmpfs here (needs root)");
        return;
    };
    let sweeps = root.join("sweeps");
    std::fs::create_dir_all(&sweeps).unwrap();
    let (a, b) = (
        pristine_sweep(&sweeps, "a", 1),
        pristine_sweep(&sweeps, "b", 2),
    );
    let run_args = |seed: &str, out: &Path| {
        strings(&[
            "run",
            "--steps",
            "20",
            "--robots",
            "2",
            "--repeats",
            "1",
            "--seed",
            seed,
            "--out",
            &out.display().to_string(),
        ])
    };
    let merge_args = |dir: &Path, out: &Path| {
        strings(&[
            "sweep",
            "merge",
            &dir.display().to_string(),
            "--out",
            &out.display().to_string(),
        ])
    };
    let (kept, replaced, n) = (Cell::new(0u32), Cell::new(0u32), Cell::new(0u32));
    runner_of(cases_or(40))
        .run(&(any::<bool>(), 0u64..1_500_000), |(merging, leave)| {
            n.set(n.get() + 1);
            for e in std::fs::read_dir(&disk.0).unwrap().flatten() {
                let p = e.path();
                let _ = std::fs::remove_dir_all(&p).or_else(|_| std::fs::remove_file(&p));
            }
            let out = disk.0.join("out");
            let (first, second) = if merging {
                (merge_args(&a, &out), merge_args(&b, &out))
            } else {
                (run_args("1", &out), run_args("2", &out))
            };
            let o = h8swarm_in(&root, &first);
            prop_assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            std::fs::write(out.join("notes.txt"), b"the user's").unwrap();
            let before = tree(&out);
            let filler = disk.0.join("filler");
            let fill = disk.free().saturating_sub(leave);
            std::fs::write(&filler, vec![0u8; fill as usize]).unwrap();
            let o = h8swarm_in(&root, &second);
            let err = String::from_utf8_lossy(&o.stderr);
            match o.status.code() {
                Some(0) => {
                    replaced.set(replaced.get() + 1);
                    prop_assert_ne!(tree(&out), before.clone(), "status 0, nothing new");
                }
                Some(1) => {
                    kept.set(kept.get() + 1);
                    prop_assert_eq!(err.lines().count(), 1, "{}", err);
                    prop_assert!(tree(&out) == before, "a failure changed the outputs: {err}");
                }
                other => prop_assert!(false, "status {other:?}: {err}"),
            }
            prop_assert_eq!(
                std::fs::read(out.join("notes.txt")).unwrap(),
                b"the user's".to_vec()
            );
            let left: Vec<String> = std::fs::read_dir(&disk.0)
                .unwrap()
                .flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n != "out" && n != "filler")
                .collect();
            prop_assert!(left.is_empty(), "left behind: {left:?}");
            Ok(())
        })
        .unwrap();
    drop(disk);
    let _ = std::fs::remove_dir_all(&root);
    let (k, r) = (kept.get(), replaced.get());
    eprintln!(
        "fuzz: full disk: {k} kept the earlier outputs, {r} replaced them, of {}",
        n.get()
    );
    assert!(k > 0 && r > 0, "{k} {r}");
}

/// Every point's summary.json of the sweep in `dir`, by id.
fn summaries(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir.join("points"))
        .unwrap()
        .flatten()
        .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path().join("summary.json")).unwrap_or_default(),
            )
        })
        .collect();
    out.sort();
    out
}

#[test]
fn concurrent_sweep_tasks_some_killed_lose_no_point() {
    let root = family_dir("concurrent-sweeps");
    let reference = pristine_sweep(&root, "reference", 3);
    let expected = summaries(&reference);
    assert_eq!(expected.len(), 3);
    let plan_files = ["plan.json", "points.jsonl", "sweep.toml", "sweep.sbatch"];
    let n = Cell::new(0u32);
    runner_of(cases_or(10))
        .run(
            &(
                2usize..4,
                prop::collection::vec(0u64..40, 3),
                any::<Option<u8>>(),
            ),
            |(tasks, delays, kill)| {
                n.set(n.get() + 1);
                let dir = root.join(format!("case{}", n.get()));
                std::fs::create_dir_all(dir.join("points")).unwrap();
                for f in plan_files {
                    std::fs::copy(reference.join(f), dir.join(f)).unwrap();
                }
                let args = strings(&["sweep", "run", &dir.display().to_string(), "--threads", "1"]);
                let mut children = Vec::new();
                for t in 0..tasks {
                    std::thread::sleep(Duration::from_millis(delays[t % delays.len()]));
                    children.push(
                        Command::new(env!("CARGO_BIN_EXE_h8swarm"))
                            .args(&args)
                            .env_remove("SLURM_ARRAY_TASK_ID")
                            .stdin(Stdio::null())
                            .stdout(Stdio::null())
                            .stderr(Stdio::piped())
                            .spawn()
                            .unwrap(),
                    );
                }
                // One task killed (SIGKILL: nothing of its own cleans up) after a while.
                let killed = kill.map(|k| usize::from(k) % tasks);
                if let Some(k) = killed {
                    std::thread::sleep(Duration::from_millis(u64::from(kill.unwrap_or(0)) % 60));
                    let _ = children[k].kill();
                }
                for (i, mut c) in children.into_iter().enumerate() {
                    let status = wait_bounded(&mut c, "a sweep task");
                    if Some(i) != killed {
                        let mut err = String::new();
                        use std::io::Read;
                        let _ = c.stderr.take().unwrap().read_to_string(&mut err);
                        prop_assert!(status.success(), "task {i}: {err}");
                    }
                }
                // Whatever the killed task left, one more run finishes the sweep.
                let o = h8swarm_in(&root, &args);
                prop_assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
                let merged = h8swarm_in(
                    &root,
                    &strings(&[
                        "sweep",
                        "merge",
                        &dir.display().to_string(),
                        "--require-complete",
                    ]),
                );
                prop_assert!(
                    merged.status.success(),
                    "{}",
                    String::from_utf8_lossy(&merged.stderr)
                );
                prop_assert!(
                    summaries(&dir) == expected,
                    "the points differ from one task's"
                );
                let _ = std::fs::remove_dir_all(&dir);
                Ok(())
            },
        )
        .unwrap();
    let _ = std::fs::remove_dir_all(&root);
    eprintln!("fuzz: concurrent sweep tasks: {} cases", n.get());
}
