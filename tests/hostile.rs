//! Hostile input through the real binary: what a user's files, folders, signals and limits can
//! do to `h8swarm`, and what it promises in return (docs/limits-and-failures.md): it never
//! deletes a user's files, an output folder is replaced whole or not at all, a failure is one
//! line on standard error with the exit status the README gives, and nothing a file or an
//! argument holds reaches the terminal as a control sequence.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn h8swarm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_h8swarm"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SLURM_CPUS_PER_TASK")
        .stdin(Stdio::null())
        .output()
        .expect("the binary runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn ok(args: &[&str]) -> String {
    let o = h8swarm(args);
    assert!(
        o.status.success(),
        "h8swarm {args:?}: {}\n{}",
        text(&o.stdout),
        text(&o.stderr)
    );
    text(&o.stdout)
}

/// Exit status, standard output and standard error.
fn status(args: &[&str]) -> (i32, String, String) {
    let o = h8swarm(args);
    (
        o.status.code().unwrap_or(-1),
        text(&o.stdout),
        text(&o.stderr),
    )
}

fn fresh(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("hostile-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Every file under `dir` with its bytes, sorted by path (folders as empty entries).
fn tree(dir: &Path) -> Vec<(String, Option<Vec<u8>>)> {
    fn walk(root: &Path, d: &Path, out: &mut Vec<(String, Option<Vec<u8>>)>) {
        let Ok(entries) = std::fs::read_dir(d) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            let name = p.strip_prefix(root).unwrap().display().to_string();
            if p.is_dir() {
                out.push((name + "/", None));
                walk(root, &p, out);
            } else {
                out.push((name, std::fs::read(&p).ok()));
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// A sweep of two points on one axis (so merge draws a figure per claim), 20-step arena runs.
fn small_sweep(root: &Path) -> PathBuf {
    let dir = root.join("d");
    let file = root.join("s.toml");
    std::fs::write(
        &file,
        "[set]\nsteps = 20\nwindow = 10\nrepeats = 1\nrobots = 2\ncontrols.random_walk = false\n[grid]\n\"learner.threshold\" = [10, 20]\n",
    )
    .unwrap();
    ok(&["sweep", "plan", s(&file), "--out", s(&dir)]);
    ok(&["sweep", "run", s(&dir), "--threads", "1"]);
    dir
}

#[test]
fn merge_replaces_only_its_own_files_in_the_output_folder() {
    let root = fresh("merge-own-files");
    let dir = small_sweep(&root);
    let out = root.join("report");
    std::fs::create_dir_all(out.join("plots")).unwrap();
    std::fs::write(out.join("plots/figure1.pdf"), b"the user's figure").unwrap();
    std::fs::write(out.join("notes.txt"), b"the user's notes").unwrap();
    let printed = ok(&["sweep", "merge", s(&dir), "--out", s(&out)]);
    assert_eq!(
        std::fs::read(out.join("plots/figure1.pdf")).unwrap(),
        b"the user's figure",
        "{printed}"
    );
    assert_eq!(
        std::fs::read(out.join("notes.txt")).unwrap(),
        b"the user's notes"
    );
    let figures: Vec<String> = std::fs::read_dir(out.join("plots"))
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".png"))
        .collect();
    assert!(!figures.is_empty(), "{printed}");
    // A figure of an earlier merge that this one does not draw is removed (it is merge's own:
    // the earlier sweep.json lists it); the user's files stay.
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    doc["figures"]
        .as_array_mut()
        .expect("sweep.json lists its figures")
        .push("plots/old-claim.png".into());
    std::fs::write(out.join("sweep.json"), doc.to_string()).unwrap();
    std::fs::write(out.join("plots/old-claim.png"), b"an old figure").unwrap();
    ok(&["sweep", "merge", s(&dir), "--out", s(&out)]);
    assert!(!out.join("plots/old-claim.png").exists());
    assert!(out.join("plots/figure1.pdf").exists() && out.join("notes.txt").exists());
}

#[test]
fn merge_lists_a_finished_point_with_a_corrupt_summary_as_broken_and_goes_on() {
    let root = fresh("merge-corrupt");
    let dir = small_sweep(&root);
    let points = dir.join("points");
    let mut ids: Vec<String> = std::fs::read_dir(&points)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    ids.sort();
    std::fs::write(points.join(&ids[0]).join("summary.json"), b"{ not json").unwrap();
    let (code, out, err) = status(&["sweep", "merge", s(&dir)]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains(&format!("BROKEN  {}", ids[0])), "{out}");
    assert!(out.contains("2 points, 1 ok"), "{out}");
    let csv = std::fs::read_to_string(dir.join("merged/sweep.csv")).unwrap();
    assert!(csv.contains(&format!("{},broken,", ids[0])), "{csv}");
    // Incomplete with --require-complete: status 2 (the sweep folder is what falls short).
    let (code, _, err) = status(&["sweep", "merge", s(&dir), "--require-complete"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.starts_with("error: ") && err.contains("not complete"),
        "{err}"
    );
    // The next run redoes the broken point.
    let printed = ok(&["sweep", "run", s(&dir), "--threads", "1"]);
    assert!(printed.contains("1 run, 1 skipped"), "{printed}");
    ok(&["sweep", "merge", s(&dir), "--require-complete"]);
}
