//! Hostile input, round three (docs/limits-and-failures.md): a full disk during a merge, a
//! trace file of a run that never ran, two sweep tasks on one plan, plans edited by hand,
//! Unicode format characters, a reader that closes the pipe early. Each test failed on the
//! build before its fix (`H8SWARM_BIN=… cargo test --release --test hostile3` runs them
//! against another build).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

mod common;
use common::tmpfs::Tmpfs;
use common::*;

/// A sweep of two points (learner.threshold 10 and 20) with master seed `seed`, 20-step
/// arena runs of 2 robots, planned and run in `root/name`.
fn sweep(root: &Path, name: &str, seed: u64) -> PathBuf {
    let dir = root.join(name);
    let file = root.join(format!("{name}.toml"));
    std::fs::write(
        &file,
        format!(
            "seeds = [{seed}]\n[set]\nsteps = 20\nwindow = 10\nrepeats = 1\nrobots = 2\ncontrols.random_walk = false\n[grid]\n\"learner.threshold\" = [10, 20]\n"
        ),
    )
    .unwrap();
    ok(&["sweep", "plan", s(&file), "--out", s(&dir)]);
    ok(&["sweep", "run", s(&dir), "--threads", "1"]);
    dir
}

fn bytes_under(dir: &Path) -> u64 {
    tree(dir)
        .iter()
        .filter_map(|(_, b)| b.as_ref().map(|b| b.len() as u64))
        .sum()
}

#[test]
fn a_merge_that_fills_the_disk_leaves_the_earlier_merge_whole() {
    let root = fresh("r3-full-disk");
    let a = sweep(&root, "a", 1);
    let b = sweep(&root, "b", 2);
    // B's merge on a roomy disk: how much it writes, and how much of it is sweep.csv.
    let roomy = root.join("roomy");
    ok(&["sweep", "merge", s(&b), "--out", s(&roomy)]);
    let all = bytes_under(&roomy);
    let csv = std::fs::metadata(roomy.join("sweep.csv")).unwrap().len();
    let Some(disk) = Tmpfs::mount(&root.join("disk"), 16 * 1024) else {
        eprintln!("SKIPPED: cannot mount a tmpfs here (needs root)");
        return;
    };
    let out = disk.0.join("report");
    ok(&["sweep", "merge", s(&a), "--out", s(&out)]);
    std::fs::write(out.join("notes.txt"), b"the user's notes").unwrap();
    let before = tree(&out);
    // Room for B's sweep.csv and a little more, not for all of B's files.
    let leave = csv + 8192;
    assert!(
        leave + 16384 < all,
        "the figures take more than a few pages"
    );
    disk.fill_leaving(leave);
    let (code, _, err) = status(&["sweep", "merge", s(&b), "--out", s(&out)]);
    assert_eq!(code, 1, "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("No space left"), "{err}");
    let diff = tree_diff(&tree(&out), &before);
    assert!(
        diff.is_empty(),
        "the earlier merge whole, nothing of B's: {diff:?}"
    );
    let leftovers: Vec<String> = std::fs::read_dir(&disk.0)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != "filler" && n != "report")
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    // With room again, B's merge replaces A's and keeps the user's file.
    std::fs::remove_file(disk.0.join("filler")).unwrap();
    ok(&["sweep", "merge", s(&b), "--out", s(&out)]);
    assert_eq!(
        std::fs::read(out.join("sweep.csv")).unwrap(),
        std::fs::read(roomy.join("sweep.csv")).unwrap()
    );
    assert_eq!(
        std::fs::read(out.join("notes.txt")).unwrap(),
        b"the user's notes"
    );
    drop(disk);
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn a_trace_file_is_untouched_by_a_run_that_never_ran_or_failed() {
    let root = fresh("r3-vcd");
    let vcd = root.join("trace.vcd");
    std::fs::write(&vcd, b"an earlier trace").unwrap();
    // The profile (issue 36) is an output outside the folder too, staged the same way.
    let prof = root.join("robot.folded");
    std::fs::write(&prof, b"an earlier profile").unwrap();
    // --out is a file: refused before anything runs.
    let file = root.join("x");
    std::fs::write(&file, b"a file").unwrap();
    let args = |out: &Path| {
        vec![
            "run".to_string(),
            "--controller".into(),
            "firmware".into(),
            "--steps".into(),
            "20".into(),
            "--repeats".into(),
            "1".into(),
            "--vcd".into(),
            s(&vcd).into(),
            "--profile".into(),
            s(&prof).into(),
            "--out".into(),
            s(out).into(),
        ]
    };
    let a = args(&file);
    let (code, _, err) = status(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 1, "{err}");
    assert_eq!(std::fs::read(&vcd).unwrap(), b"an earlier trace");
    assert_eq!(std::fs::read(&prof).unwrap(), b"an earlier profile");
    // A run that fails after its trace began (the robots run an image that spins at boot, and
    // the step watchdog stops it): status 2, the trace untouched.
    let spin = root.join("spin.mot");
    std::fs::write(&spin, spin_image()).unwrap();
    let scenario = root.join("spin.toml");
    std::fs::write(
        &scenario,
        format!(
            "[controls]\nlearning_off = false\nrandom_walk = false\n[controller]\nkind = \"firmware\"\nimage = \"{}\"\n",
            spin.display()
        ),
    )
    .unwrap();
    let out = root.join("o");
    let (code, _, err) = status(&[
        "run",
        s(&scenario),
        "--steps",
        "5",
        "--repeats",
        "1",
        "--vcd",
        s(&vcd),
        "--profile",
        s(&prof),
        "--out",
        s(&out),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("nothing was written"), "{err}");
    assert_eq!(std::fs::read(&vcd).unwrap(), b"an earlier trace");
    assert_eq!(std::fs::read(&prof).unwrap(), b"an earlier profile");
    assert!(!out.exists());
    // A run that succeeds replaces it, and leaves no staging file beside it.
    let out = root.join("good");
    let a = args(&out);
    let o = ok(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let trace = std::fs::read_to_string(&vcd).unwrap();
    assert!(trace.starts_with("$version"), "{o}");
    let folded = std::fs::read_to_string(&prof).unwrap();
    assert!(
        folded.lines().count() > 1 && folded.contains(";main"),
        "{folded}"
    );
    // One file cannot be both.
    let (code, _, err) = status(&[
        "run",
        "--controller",
        "firmware",
        "--steps",
        "5",
        "--repeats",
        "1",
        "--vcd",
        s(&vcd),
        "--profile",
        s(&vcd),
        "--out",
        s(&root.join("both")),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("also the --vcd file"), "{err}");
    let names: Vec<String> = std::fs::read_dir(&root)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(names.is_empty(), "{names:?}");
    let _ = std::fs::remove_dir_all(&root);
}

/// An S-record image whose reset vector points at `BRA .` at H'000100 (it never starts the
/// A/D converter, so the robot's step watchdog stops it).
fn spin_image() -> String {
    use h8300h::srec::{Chunk, SrecImage, write_s3};
    let img = SrecImage {
        header: None,
        chunks: vec![
            Chunk {
                address: 0,
                data: 0x100u32.to_be_bytes().to_vec(),
            },
            Chunk {
                address: 0x100,
                data: vec![0x40, 0xFE],
            },
        ],
        start: Some(0x100),
    };
    write_s3(&img, 16)
}

/// Runs `sweep merge` and `sweep run` on `dir`: both refuse it with status 2 and one line
/// naming `words`.
fn refused_by_merge_and_run(dir: &Path, words: &[&str]) {
    for args in [
        vec!["sweep", "merge", s(dir)],
        vec!["sweep", "run", s(dir), "--threads", "1"],
    ] {
        let (code, _, err) = status(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        for w in words {
            assert!(err.contains(w), "{args:?}: {w}: {err}");
        }
    }
}

/// Rewrites `dir/file` (JSON, or JSON Lines with `lines`) through `edit`.
fn edit_json(dir: &Path, file: &str, edit: &dyn Fn(&mut serde_json::Value)) {
    let path = dir.join(file);
    let text = std::fs::read_to_string(&path).unwrap();
    let out: Vec<String> = if file.ends_with(".jsonl") {
        text.lines()
            .map(|l| {
                let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
                edit(&mut v);
                v.to_string()
            })
            .collect()
    } else {
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        edit(&mut v);
        vec![v.to_string()]
    };
    std::fs::write(&path, out.join("\n") + "\n").unwrap();
}

#[test]
fn plans_edited_by_hand_are_refused_in_one_line_not_a_panic_or_an_abort() {
    let root = fresh("r3-edited");
    let pristine = sweep(&root, "p", 3);
    let copy = |name: &str| {
        let d = root.join(name);
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        for f in ["plan.json", "points.jsonl", "sweep.toml", "sweep.sbatch"] {
            std::fs::copy(pristine.join(f), d.join(f)).unwrap();
        }
        d
    };
    // A point whose coords lie outside the axes (it was an index out of bounds, exit 101).
    let d = copy("coords");
    edit_json(&d, "points.jsonl", &|v| {
        v["coords"] = serde_json::json!([7])
    });
    refused_by_merge_and_run(&d, &["points.jsonl line 1", "outside the plan's axes"]);
    // An axis shortened by hand.
    let d = copy("shortened");
    edit_json(&d, "plan.json", &|v| {
        v["axes"][0]["values"].as_array_mut().unwrap().pop();
    });
    refused_by_merge_and_run(
        &d,
        &["plan.json", "2 points, but its axes and seeds make 1"],
    );
    // Two axes of 100 000 values each (it asked for 560 GB and aborted).
    let d = copy("huge");
    edit_json(&d, "plan.json", &|v| {
        let axis = serde_json::json!({
            "keys": ["learner.threshold"],
            "values": (0..100_000).map(|i| vec![i]).collect::<Vec<_>>(),
        });
        v["axes"] = serde_json::json!([axis.clone(), axis]);
    });
    refused_by_merge_and_run(&d, &["plan.json", "cells"]);
    // Two points with one id: two tasks would share a folder.
    let d = copy("twins");
    edit_json(&d, "points.jsonl", &|v| v["id"] = serde_json::json!("twin"));
    refused_by_merge_and_run(
        &d,
        &["points.jsonl line 2", "`twin` is another point's too"],
    );
    let _ = std::fs::remove_dir_all(&root);
}

/// Plans a sweep of `n` threshold values (one seed) of 30-step runs in `root/name`.
fn plan_only(root: &Path, name: &str, n: usize) -> PathBuf {
    let dir = root.join(name);
    let file = root.join(format!("{name}.toml"));
    let values: Vec<String> = (0..n).map(|i| (10 + 5 * i).to_string()).collect();
    std::fs::write(
        &file,
        format!(
            "seeds = [4]\n[set]\nsteps = 30\nwindow = 10\nrepeats = 1\nrobots = 2\ncontrols.random_walk = false\n[grid]\n\"learner.threshold\" = [{}]\n",
            values.join(", ")
        ),
    )
    .unwrap();
    ok(&["sweep", "plan", s(&file), "--out", s(&dir)]);
    dir
}

/// Every point's summary.json under `dir/points`, by id.
fn summaries(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir.join("points"))
        .unwrap()
        .flatten()
        .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path().join("summary.json")).unwrap(),
            )
        })
        .collect();
    out.sort();
    out
}

#[test]
fn two_sweep_runs_on_one_plan_share_its_points_and_lose_none() {
    let root = fresh("r3-two-writers");
    let alone = plan_only(&root, "alone", 6);
    ok(&["sweep", "run", s(&alone), "--threads", "1"]);
    let reference = summaries(&alone);
    assert_eq!(reference.len(), 6);
    for trial in 0..3 {
        let dir = plan_only(&root, &format!("both{trial}"), 6);
        let spawn = || {
            Command::new(bin())
                .args(["sweep", "run", s(&dir), "--threads", "1"])
                .current_dir(env!("CARGO_MANIFEST_DIR"))
                .env_remove("SLURM_ARRAY_TASK_ID")
                .stdin(Stdio::null())
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        };
        let (a, b) = (spawn(), spawn());
        for c in [a, b] {
            let o = c.wait_with_output().unwrap();
            assert!(
                o.status.success(),
                "trial {trial}: {}{}",
                text(&o.stdout),
                text(&o.stderr)
            );
        }
        let merged = ok(&["sweep", "merge", s(&dir), "--require-complete"]);
        assert!(
            merged.contains("6 ok, 0 failed, 0 missing, 0 broken"),
            "{merged}"
        );
        assert_eq!(summaries(&dir), reference, "trial {trial}");
        let hidden: Vec<String> = std::fs::read_dir(dir.join("points"))
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with('.'))
            .collect();
        assert!(hidden.is_empty(), "trial {trial}: {hidden:?}");
    }
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn a_point_a_live_task_holds_is_left_to_it_and_taken_over_when_it_dies() {
    let root = fresh("r3-claims");
    let dir = plan_only(&root, "d", 2);
    let lines = std::fs::read_to_string(dir.join("points.jsonl")).unwrap();
    let first: serde_json::Value = serde_json::from_str(lines.lines().next().unwrap()).unwrap();
    let id = first["id"].as_str().unwrap().to_string();
    std::fs::create_dir_all(dir.join("points")).unwrap();
    // This test holds the first point's claim, as a live task would.
    let lock = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(dir.join("points").join(format!(".lock-{id}")))
        .unwrap();
    lock.lock().unwrap();
    let printed = ok(&["sweep", "run", s(&dir), "--threads", "1"]);
    assert!(
        printed.contains("1 run, 0 skipped (finished before), 0 failed, 1 left to another task"),
        "{printed}"
    );
    assert!(!dir.join("points").join(&id).exists());
    // The holder ends (its lock goes with it): the next run takes the point over.
    drop(lock);
    let printed = ok(&["sweep", "run", s(&dir), "--threads", "1"]);
    assert!(
        printed.contains("1 run, 1 skipped (finished before), 0 failed\n"),
        "{printed}"
    );
    ok(&["sweep", "merge", s(&dir), "--require-complete"]);
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn every_command_that_writes_to_standard_output_ends_quietly_when_the_reader_goes() {
    let root = fresh("r3-pipe");
    let sweep_dir = root.join("sw");
    let sweep_file = root.join("sw.toml");
    std::fs::write(
        &sweep_file,
        "seeds = [5]\n[set]\nsteps = 20\nwindow = 10\nrepeats = 1\nrobots = 2\ncontrols.random_walk = false\n",
    )
    .unwrap();
    let out = root.join("run");
    let replay = "examples/replay-arena.jsonl";
    let q15 = "emu/tests/programs/q15learn.mot";
    let commands: Vec<Vec<&str>> = vec![
        vec!["--version"],
        vec!["--help"],
        vec!["run", "--help"],
        vec!["cost"],
        vec!["cost", "--json"],
        vec!["fit"],
        vec!["learn", "--replay", replay],
        vec!["learn", "--replay", replay, "--states"],
        vec!["learn", "--replay", replay, "--on-core", "--states"],
        vec!["emu", q15],
        vec!["emu", q15, "--stats"],
        vec!["run", "--steps", "20", "--repeats", "1", "--out", s(&out)],
        vec!["sweep", "plan", s(&sweep_file), "--out", s(&sweep_dir)],
        vec!["sweep", "run", s(&sweep_dir), "--threads", "1"],
        vec!["sweep", "merge", s(&sweep_dir)],
    ];
    for args in &commands {
        // The reader is gone before the command writes a byte: every write fails with EPIPE.
        let mut child = Command::new(bin())
            .args(args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .env_remove("SLURM_ARRAY_TASK_ID")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let o = child.wait_with_output().unwrap();
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
        assert!(
            !err.contains("Broken pipe") && !err.contains("error"),
            "{args:?}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&root);
}

/// Status 2 and one error line holding every one of `words`.
fn refused(args: &[&str], words: &[&str]) {
    let (code, _, err) = status(args);
    assert_eq!(code, 2, "{args:?}: {err}");
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "{args:?}: {err}");
    for w in words {
        assert!(errors[0].contains(w), "{args:?}: {w}: {err}");
    }
    assert!(err.len() < 600, "{args:?}: a short message: {err}");
}

#[test]
fn numbers_step_periods_and_learning_rates_follow_one_rule_in_short_messages() {
    let root = fresh("r3-numbers");
    // Extreme values in exponent form, never hundreds of digits.
    refused(
        &["cost", "--step-period-s", "1e-320"],
        &["1e-320", "10 ms ticks"],
    );
    refused(&["fit", "--step-period-s", "1e308"], &["1e308"]);
    refused(
        &["fit", "--capacity-mah", "1e308"],
        &["--capacity-mah 1e308"],
    );
    refused(
        &["run", "--capacity-mah", "1e-320", "--steps", "5"],
        &["--capacity-mah 1e-320"],
    );
    let file = root.join("tiny.toml");
    std::fs::write(&file, "[world]\nsubstep_s = 1e-320\n").unwrap();
    refused(&["run", s(&file)], &["`world.substep_s` = 1e-320"]);
    let file = root.join("huge.toml");
    std::fs::write(&file, "steps = 1e308\n").unwrap();
    refused(&["run", s(&file)], &["`1e308`"]);
    // One rule for the step period: cost refuses what fit and scenarios refuse.
    refused(
        &["cost", "--step-period-s", "0.005"],
        &["--step-period-s 0.005"],
    );
    refused(
        &["fit", "--step-period-s", "0.005"],
        &["--step-period-s 0.005"],
    );
    let file = root.join("period.toml");
    std::fs::write(&file, "[timing]\nstep_period_s = 0.005\n").unwrap();
    refused(&["run", s(&file)], &["`timing.step_period_s` = 0.005"]);
    ok(&["cost", "--step-period-s", "0.6", "--steps", "10"]);
    // The largest learning rate the message offers is taken.
    let (code, _, err) = status(&["cost", "--eta", "0.99997", "--steps", "10"]);
    assert_eq!(code, 0, "{err}");
    refused(&["cost", "--eta", "0.99999"], &["0.99997"]);
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn output_folders_follow_one_rule_and_misplaced_keys_are_named() {
    let root = fresh("r3-folders");
    let dir = sweep(&root, "d", 6);
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/sweep-example.toml");
    // Run from deep inside the test's own folder, so that even a build without the rule
    // writes nothing outside it; the root itself is tried only on this build (an older one
    // would write a plan into /).
    let cwd = root.join("a/b");
    std::fs::create_dir_all(&cwd).unwrap();
    let mut bad = vec!["..", ".", "x/.."];
    if std::env::var_os("H8SWARM_BIN").is_none() {
        bad.push("/");
    }
    for bad in bad {
        let (code, _, err) = status_in(&cwd, &["sweep", "plan", s(&example), "--out", bad]);
        assert_eq!(code, 1, "plan --out {bad}: {err}");
        assert!(err.contains("give a folder name"), "{err}");
        let (code, _, err) = status_in(&cwd, &["sweep", "merge", s(&dir), "--out", bad]);
        assert_eq!(code, 1, "merge --out {bad}: {err}");
        assert!(err.contains("give a folder name"), "{err}");
        let (code, _, err) = status_in(&cwd, &["run", "--steps", "5", "--out", bad]);
        assert_eq!(code, 1, "run --out {bad}: {err}");
    }
    // A top-level key written after [set] lands in [set]: the message says where it belongs.
    let file = root.join("late-seeds.toml");
    std::fs::write(&file, "[set]\nsteps = 10\nseeds = [1, 2]\n").unwrap();
    refused(
        &["sweep", "plan", s(&file), "--out", s(&root.join("x"))],
        &[
            "`seeds` is a key of the sweep file itself",
            "before the first [table]",
        ],
    );
    // controller.symbols with nothing to name is said, not silently dropped.
    let file = root.join("symbols.toml");
    std::fs::write(&file, "[controller]\nsymbols = \"x.sym\"\n").unwrap();
    let printed = ok(&[
        "run",
        s(&file),
        "--steps",
        "10",
        "--repeats",
        "1",
        "--out",
        s(&root.join("o")),
    ]);
    assert!(
        printed.contains("WARNING `controller.symbols` = x.sym is not used"),
        "{printed}"
    );
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn format_characters_and_split_values_never_reach_the_terminal_raw() {
    let root = fresh("r3-format-chars");
    // A scenario name with a right-to-left override: refused, the character escaped.
    let file = root.join("rlo.toml");
    std::fs::write(&file, "name = \"abc\u{202e}def\"\n").unwrap();
    refused(&["run", s(&file)], &["U+202E"]);
    // A symbol name with one: the symbol table is refused, its line shown escaped.
    let image = root.join("p.mot");
    std::fs::copy("emu/tests/programs/q15learn.mot", &image).unwrap();
    let sym = root.join("p.sym");
    std::fs::write(&sym, "00000100 T _ma\u{202e}in\n").unwrap();
    for args in [
        vec!["emu", s(&image), "--symbols", s(&sym)],
        vec!["fit", "--firmware", s(&image), "--symbols", s(&sym)],
    ] {
        let (code, _, err) = status(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(!err.contains('\u{202e}'), "{args:?}: {err}");
        assert!(err.contains("\\u{202e}"), "{args:?}: {err}");
    }
    // A value with a newline or an ESC: one error line, the value escaped (not stripped).
    for (value, shown) in [("1\n2", "'1\\n2'"), ("\u{1b}[31mx", "'\\e[31mx'")] {
        let (code, _, err) = status(&["run", "--replay-stride", value]);
        assert_eq!(code, 2, "{err}");
        let first = err.lines().next().unwrap();
        assert!(
            first.starts_with("error: invalid value") && first.contains(shown),
            "{err}"
        );
        assert!(!err.contains('\u{1b}'), "{err}");
    }
    let _ = std::fs::remove_dir_all(&root);
}
