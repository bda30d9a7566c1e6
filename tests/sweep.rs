//! Drives `h8swarm sweep plan/run/merge` through the real binary: the same table
//! byte for byte however the points are split into tasks; reruns skip finished points and redo
//! broken ones; failed and missing points are listed; bad input is a one-line error with exit
//! status 2. The real-Slurm test is `scripts/slurm-test.sh`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn h8swarm(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_h8swarm"));
    c.args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SLURM_CPUS_PER_TASK");
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("the binary runs")
}

fn ok(args: &[&str]) -> String {
    let o = h8swarm(args, &[]);
    assert!(
        o.status.success(),
        "h8swarm {args:?}: {}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Exit status and standard error.
fn fails(args: &[&str], env: &[(&str, &str)]) -> (i32, String) {
    let o = h8swarm(args, env);
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn fresh(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("sweep-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A short sweep: 2 x 2 x 2 seeds of 30-step arena runs, one repeat.
/// (One name: the table names its sweep, by default the file's stem.)
const SWEEP: &str = r#"
name = "split"
seeds = [1, 2]
[set]
steps = 30
window = 10
repeats = 1
[grid]
"learner.eta" = [0.001, 0.01]
[[zip]]
"learner.history" = [0, 1]
"learner.threshold" = [10, 20]
[slurm]
points_per_task = POINTS
max_parallel = 3
"#;

/// Every file of every point folder (but run.txt, the console text with its wall time):
/// scenario.toml, status.json, metrics.csv, summary.json, fit.json and the three figures.
fn point_files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut ids: Vec<_> = std::fs::read_dir(dir.join("points"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .collect();
    ids.sort();
    for p in ids {
        let mut files: Vec<_> = std::fs::read_dir(&p)
            .unwrap()
            .flatten()
            .map(|e| e.path())
            .collect();
        files.sort();
        for f in files {
            if f.file_name().unwrap() == "run.txt" {
                continue;
            }
            let name = format!(
                "{}/{}",
                p.file_name().unwrap().to_string_lossy(),
                f.file_name().unwrap().to_string_lossy()
            );
            out.push((name, std::fs::read(&f).unwrap()));
        }
    }
    out
}

#[test]
fn the_table_is_the_same_however_the_points_are_split() {
    let root = fresh("split");
    let (a, b) = (root.join("a"), root.join("b"));
    let file_a = root.join("one.toml");
    let file_b = root.join("three.toml");
    std::fs::write(&file_a, SWEEP.replace("POINTS", "1")).unwrap();
    std::fs::write(&file_b, SWEEP.replace("POINTS", "3")).unwrap();
    let text = ok(&["sweep", "plan", s(&file_a), "--out", s(&a)]);
    assert!(
        text.contains("8 points") && text.contains("8 tasks"),
        "{text}"
    );
    ok(&["sweep", "plan", s(&file_b), "--out", s(&b)]);

    // The script: a job array over the tasks, at most 3 at once, requests computed.
    let script = std::fs::read_to_string(b.join("sweep.sbatch")).unwrap();
    assert!(script.starts_with("#!/bin/bash\n"), "{script}");
    assert!(script.contains("\n#SBATCH --array=0-2%3\n"), "{script}");
    // 3 runs a point (learning and the two controls, one repeat).
    assert!(script.contains("\n#SBATCH --cpus-per-task=3\n"), "{script}");
    assert!(script.contains("\n#SBATCH --mem=128M\n"), "{script}");
    assert!(script.contains("#SBATCH --requeue"), "{script}");
    assert!(script.contains(&format!(
        " sweep run '{}'",
        b.canonicalize().unwrap().display()
    )));
    // The run list: one line per point, each with its full scenario.
    let list = std::fs::read_to_string(a.join("points.jsonl")).unwrap();
    assert_eq!(list.lines().count(), 8);
    let line: serde_json::Value = serde_json::from_str(list.lines().nth(5).unwrap()).unwrap();
    assert_eq!(line["index"], 5);
    assert_eq!(line["seed"], 2);
    assert_eq!(line["scenario"]["steps"], 30);
    assert_eq!(line["scenario"]["world"]["substep_s"], 0.02);

    // a: one task at a time, last task first; b: every task at once on two threads.
    for t in (0..8).rev() {
        ok(&[
            "sweep",
            "run",
            s(&a),
            "--task",
            &t.to_string(),
            "--threads",
            "1",
        ]);
    }
    ok(&["sweep", "run", s(&b), "--threads", "2"]);
    let (fa, fb) = (point_files(&a), point_files(&b));
    assert_eq!(
        fa.len(),
        8 * 9,
        "{:?}",
        fa.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    assert!(
        fa == fb,
        "a point's files depend on how the points were split"
    );

    let merged = ok(&["sweep", "merge", s(&a), "--require-complete"]);
    assert!(
        merged.contains("8 points, 8 ok, 0 failed, 0 missing"),
        "{merged}"
    );
    ok(&["sweep", "merge", s(&b), "--require-complete"]);
    for f in ["sweep.csv", "sweep.json"] {
        let (x, y) = (
            std::fs::read(a.join("merged").join(f)).unwrap(),
            std::fs::read(b.join("merged").join(f)).unwrap(),
        );
        assert!(x == y, "merged/{f} differs");
    }
    let csv = std::fs::read_to_string(a.join("merged/sweep.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert_eq!(
        &header[..7],
        [
            "index",
            "id",
            "status",
            "learner.eta",
            "learner.history",
            "learner.threshold",
            "seed"
        ]
    );
    assert!(header.contains(&"learning.last.collisions_per_robot.mean"));
    assert!(header.contains(&"random-walk.first.contact_percent.hi"));
    assert!(
        header.contains(&"claim.d_rises_mean_d_in_the_last_window_above_the_first_learning.effect")
    );
    assert_eq!(*header.last().unwrap(), "error");
    assert_eq!(csv.lines().count(), 9);
    // A row's zipped values move together; a claim's effect is the difference of its values,
    // positive when the means agree with it, whichever way the claim goes.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(a.join("merged/sweep.json")).unwrap())
            .unwrap();
    for row in json["rows"].as_array().unwrap() {
        let h = row["learner.history"].as_i64().unwrap();
        assert_eq!(row["learner.threshold"].as_i64().unwrap(), 10 + 10 * h);
        let c = "claim.mean_d_in_the_last_window_learning_above_learning_off";
        let (x, y, e) = (
            row[format!("{c}.a")].as_f64().unwrap(),
            row[format!("{c}.b")].as_f64().unwrap(),
            row[format!("{c}.effect")].as_f64().unwrap(),
        );
        // "a above b": the effect is a - b, positive when the means agree with the claim.
        // (serde_json reads decimals to within an ulp, so a - b of the values read back may
        // differ from the effect in the last digit.)
        assert!(
            (e - (x - y)).abs() <= 1e-12 * x.abs().max(y.abs()).max(1.0),
            "{c}: effect {e}, a - b = {}",
            x - y
        );
        assert_eq!(row[format!("{c}.means_agree")].as_bool().unwrap(), x > y);
        // The repeat counts add up to the point's repeats (1 here).
        let n = |part: &str| row[format!("{c}.{part}")].as_u64().unwrap();
        assert_eq!(n("for") + n("against") + n("tied") + n("undefined"), 1);
        let outcome = row[format!("{c}.outcome")].as_str().unwrap();
        assert!(["holds", "unsure", "fails", "undecided"].contains(&outcome));
        for slug in json["claims"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c["column"].as_str().unwrap())
        {
            let v = |part: &str| row[format!("{slug}.{part}")].as_f64();
            let (Some(x), Some(y), Some(e)) = (v("a"), v("b"), v("effect")) else {
                continue;
            };
            let agree = row[format!("{slug}.means_agree")].as_bool().unwrap();
            assert!(
                ((e.abs() - (x - y).abs()).abs() <= 1e-12 * x.abs().max(y.abs()).max(1.0))
                    && (x == y || (e > 0.0) == agree),
                "{slug}: a {x}, b {y}, effect {e}, means agree {agree}"
            );
        }
    }
    // A map a claim, and the region of the paper's text claims.
    let plots = std::fs::read_dir(a.join("merged/plots")).unwrap().count();
    let claims = json["claims"].as_array().unwrap();
    assert!(claims.iter().any(|c| c["paper"] == true));
    assert_eq!(plots, claims.len() + 1);
    assert!(a.join("merged/plots/region.png").exists());
    assert!(json["region"].is_array());
}

#[test]
fn reruns_skip_finished_points_and_redo_broken_ones() {
    let root = fresh("rerun");
    let dir = root.join("d");
    let file = root.join("s.toml");
    std::fs::write(
        &file,
        "seeds = 3\n[set]\nsteps = 20\nwindow = 10\nrepeats = 1\ncontrols.random_walk = false\n",
    )
    .unwrap();
    ok(&["sweep", "plan", s(&file), "--out", s(&dir)]);
    // No task asked: SLURM_ARRAY_TASK_ID picks task 1.
    let o = h8swarm(&["sweep", "run", s(&dir)], &[("SLURM_ARRAY_TASK_ID", "1")]);
    assert!(o.status.success());
    let ids: Vec<String> = std::fs::read_to_string(dir.join("points.jsonl"))
        .unwrap()
        .lines()
        .map(|l| {
            serde_json::from_str::<serde_json::Value>(l).unwrap()["id"]
                .as_str()
                .unwrap()
                .to_string()
        })
        .collect();
    assert_eq!(ids, ["p0000-s1", "p0001-s2", "p0002-s3"]);
    let pts = dir.join("points");
    assert!(pts.join(&ids[1]).join("status.json").exists());
    assert!(!pts.join(&ids[0]).exists());

    let merged = ok(&["sweep", "merge", s(&dir)]);
    assert!(
        merged.contains("MISSING p0000-s1") && merged.contains("MISSING p0002-s3"),
        "{merged}"
    );
    let (code, err) = fails(&["sweep", "merge", s(&dir), "--require-complete"], &[]);
    assert_eq!(code, 2, "{err}");
    let csv = std::fs::read_to_string(dir.join("merged/sweep.csv")).unwrap();
    assert!(
        csv.lines()
            .nth(1)
            .unwrap()
            .starts_with("0,p0000-s1,missing,"),
        "{csv}"
    );

    // Everything: task 1's point is skipped, the two others run.
    let before = std::fs::read(pts.join(&ids[1]).join("metrics.csv")).unwrap();
    let o = h8swarm(&["sweep", "run", s(&dir)], &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("p0001-s2 finished before: skipped"), "{err}");
    assert!(String::from_utf8_lossy(&o.stdout).contains("2 run, 1 skipped"));

    // A broken folder (no status), a changed scenario and a killed task's leftovers are redone.
    std::fs::remove_file(pts.join(&ids[0]).join("status.json")).unwrap();
    let sc = pts.join(&ids[2]).join("scenario.toml");
    let changed = std::fs::read_to_string(&sc)
        .unwrap()
        .replace("steps = 20", "steps = 21");
    std::fs::write(&sc, changed).unwrap();
    let junk = pts.join(format!(".tmp-{}-deadhost-7", ids[1]));
    std::fs::create_dir_all(&junk).unwrap();
    std::fs::remove_file(pts.join(&ids[1]).join("status.json")).unwrap();
    let merged = ok(&["sweep", "merge", s(&dir)]);
    assert!(
        merged.contains("BROKEN  p0000-s1") && merged.contains("BROKEN  p0002-s3"),
        "{merged}"
    );
    assert!(
        merged.contains("RUNNING points/.tmp-p0001-s2-deadhost-7"),
        "{merged}"
    );
    let text = ok(&["sweep", "run", s(&dir)]);
    assert!(text.contains("3 run, 0 skipped"), "{text}");
    assert!(!junk.exists());
    assert_eq!(
        std::fs::read(pts.join(&ids[1]).join("metrics.csv")).unwrap(),
        before
    );
    let merged = ok(&["sweep", "merge", s(&dir), "--require-complete"]);
    assert!(merged.contains("3 points, 3 ok"), "{merged}");
    // No axis: a table, no figure.
    assert_eq!(
        std::fs::read_dir(dir.join("merged/plots")).unwrap().count(),
        0
    );
}

#[test]
fn failed_points_are_recorded_and_listed() {
    let root = fresh("failed");
    let dir = root.join("d");
    let file = root.join("s.toml");
    std::fs::write(
        &file,
        "[set]\nsteps = 20\nwindow = 10\nrepeats = 1\ncontrols.learning_off = false\ncontrols.random_walk = false\ncontroller.kind = \"firmware\"\n[grid]\n\"controller.image\" = [\"firmware/robot.mot\", \"no/such-image.mot\"]\n",
    )
    .unwrap();
    ok(&["sweep", "plan", s(&file), "--out", s(&dir)]);
    let o = h8swarm(&["sweep", "run", s(&dir)], &[]);
    assert_eq!(o.status.code(), Some(1), "a failed point fails the task");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("p0001-") && err.contains("FAILED"), "{err}");
    let status: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(
            std::fs::read_dir(dir.join("points"))
                .unwrap()
                .flatten()
                .find(|e| e.file_name().to_string_lossy().starts_with("p0001-"))
                .unwrap()
                .path()
                .join("status.json"),
        )
        .unwrap(),
    )
    .unwrap();
    assert_eq!(status["status"], "failed");
    assert!(
        status["error"]
            .as_str()
            .unwrap()
            .contains("no/such-image.mot"),
        "{status}"
    );
    let merged = ok(&["sweep", "merge", s(&dir)]);
    assert!(
        merged.contains("1 ok, 1 failed") && merged.contains("FAILED  p0001-"),
        "{merged}"
    );
    let csv = std::fs::read_to_string(dir.join("merged/sweep.csv")).unwrap();
    let row = csv.lines().nth(2).unwrap();
    assert!(
        row.starts_with("1,p0001-")
            && row.contains(",failed,")
            && row.contains("no/such-image.mot"),
        "{row}"
    );
    // One axis: a line figure a claim.
    assert!(std::fs::read_dir(dir.join("merged/plots")).unwrap().count() >= 2);
}

#[test]
fn bad_input_is_one_line_and_status_2() {
    let root = fresh("bad");
    let w = |name: &str, text: &str| {
        let p = root.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let out = root.join("out");
    let cases: [(PathBuf, &str); 7] = [
        (w("toml.toml", "[grid\n"), "toml.toml"),
        (
            w("key.toml", "[grid]\n\"learner.etta\" = [0.1]\n"),
            "unknown key `learner.etta`",
        ),
        (w("empty.toml", "[grid]\nrobots = []\n"), "empty list"),
        (w("range.toml", "[grid]\nrobots = [3, 0]\n"), "robots"),
        (
            w("zip.toml", "[[zip]]\nrobots = [3, 4]\nsteps = [10]\n"),
            "equal length",
        ),
        (w("top.toml", "grid = 3\n"), "grid"),
        (
            w("slurm.toml", "[slurm]\npoints_per_task = 0\n"),
            "points_per_task",
        ),
    ];
    for (file, says) in &cases {
        let (code, err) = fails(&["sweep", "plan", s(file), "--out", s(&out)], &[]);
        assert_eq!(code, 2, "{}: {err}", file.display());
        assert!(err.contains(says), "{}: {err}", file.display());
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let (code, err) = fails(
        &[
            "sweep",
            "plan",
            s(&root.join("none.toml")),
            "--out",
            s(&out),
        ],
        &[],
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("none.toml"), "{err}");

    let good = w(
        "good.toml",
        "[set]\nsteps = 10\nwindow = 5\n[grid]\nrobots = [3, 4]\n",
    );
    ok(&["sweep", "plan", s(&good), "--out", s(&out)]);
    // Planning the same again is fine; another plan into the same folder is not.
    ok(&["sweep", "plan", s(&good), "--out", s(&out)]);
    let other = w(
        "other.toml",
        "[set]\nsteps = 10\nwindow = 5\n[grid]\nrobots = [3, 5]\n",
    );
    let (code, err) = fails(&["sweep", "plan", s(&other), "--out", s(&out)], &[]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("different sweep plan"), "{err}");

    let (code, err) = fails(&["sweep", "run", s(&out), "--task", "2"], &[]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("task 2 is out of range") && err.contains("0 to 1"),
        "{err}"
    );
    let (code, err) = fails(&["sweep", "run", s(&out)], &[("SLURM_ARRAY_TASK_ID", "x1")]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("SLURM_ARRAY_TASK_ID"), "{err}");
    let (code, err) = fails(&["sweep", "run", s(&root), "--task", "0"], &[]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not a sweep folder"), "{err}");
    let (code, err) = fails(&["sweep", "merge", s(&root)], &[]);
    assert_eq!(code, 2, "{err}");
    // A tampered run list cannot point outside the folder.
    let list = std::fs::read_to_string(out.join("points.jsonl")).unwrap();
    let first_id = serde_json::from_str::<serde_json::Value>(list.lines().next().unwrap()).unwrap()
        ["id"]
        .as_str()
        .unwrap()
        .to_string();
    std::fs::write(
        out.join("points.jsonl"),
        list.replacen(&first_id, "../../escape", 1),
    )
    .unwrap();
    let (code, err) = fails(&["sweep", "run", s(&out), "--task", "0"], &[]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("points.jsonl line 1"), "{err}");
    assert!(!root.join("escape").exists());
}

#[test]
fn the_readme_example_plans() {
    let dir = fresh("example").join("d");
    let text = ok(&[
        "sweep",
        "plan",
        "scenarios/sweep-example.toml",
        "--out",
        s(&dir),
    ]);
    assert!(
        text.contains("12 points") && text.contains("6 tasks"),
        "{text}"
    );
    let script = std::fs::read_to_string(dir.join("sweep.sbatch")).unwrap();
    assert!(script.contains("\n#SBATCH --array=0-5%6\n"), "{script}");
    let first = std::fs::read_to_string(dir.join("points.jsonl")).unwrap();
    let first: serde_json::Value = serde_json::from_str(first.lines().next().unwrap()).unwrap();
    assert_eq!(first["id"], "p0000-eta0.001-history0-s1");
    assert_eq!(first["scenario"]["steps"], 2000);
}

/// The confirmation stage: a map of two cells on seed 1, one cell confirmed on seed 21 (the
/// map's point with only its seed and name changed), merged beside the map; the reserved seeds
/// and a map that is not finished are refused.
#[test]
fn a_confirmation_reruns_chosen_cells_on_new_seeds_and_merge_reports_both() {
    let root = fresh("confirm");
    let map = root.join("map");
    let file = root.join("c.toml");
    let sweep = r#"
name = "conf"
seeds = [1]
[set]
steps = 30
window = 10
repeats = 1
controls.learning_off = false
[grid]
"learner.eta" = [0.01, 0.03]
[confirm]
seeds = [21]
cells = [{ "learner.eta" = 0.03 }]
"#;
    std::fs::write(&file, sweep).unwrap();
    ok(&["sweep", "plan", s(&file), "--out", s(&map)]);
    // Not before the map is finished.
    let (code, err) = fails(&["sweep", "confirm", s(&map)], &[]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not complete"), "{err}");
    ok(&["sweep", "run", s(&map), "--threads", "1"]);
    ok(&["sweep", "merge", s(&map)]);
    let text = ok(&["sweep", "confirm", s(&map)]);
    assert!(
        text.contains("1 cells") && text.contains("learner.eta = 0.03"),
        "{text}"
    );
    let cdir = map.join("confirm");
    let list = std::fs::read_to_string(cdir.join("points.jsonl")).unwrap();
    let lines: Vec<serde_json::Value> = list
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 1);
    assert_eq!(lines[0]["seed"], 21);
    // The map's point of that cell, but for its seed and name.
    let map_list = std::fs::read_to_string(map.join("points.jsonl")).unwrap();
    let mut src: serde_json::Value =
        serde_json::from_str(map_list.lines().nth(1).unwrap()).unwrap();
    let mut got = lines[0]["scenario"].clone();
    for v in [&mut src["scenario"], &mut got] {
        v.as_object_mut().unwrap().remove("seed");
        v.as_object_mut().unwrap().remove("name");
    }
    assert_eq!(got, src["scenario"]);
    // Planning it again is allowed (the same run list); the merge before it is run lists it
    // as missing.
    ok(&["sweep", "confirm", s(&map)]);
    let text = ok(&["sweep", "merge", s(&map)]);
    assert!(text.contains("MISSING p0000"), "{text}");
    assert!(text.contains("INCOMPLETE (0 of 1 points)"), "{text}");
    ok(&["sweep", "run", s(&cdir), "--threads", "1"]);
    let text = ok(&["sweep", "merge", s(&map), "--require-complete"]);
    assert!(
        text.contains("confirmation of `conf` on seeds 21"),
        "{text}"
    );
    assert!(
        text.contains("no cell is confirmed") || text.contains("the rule's default"),
        "{text}"
    );
    let table = std::fs::read_to_string(map.join("merged/confirmation.csv")).unwrap();
    assert_eq!(table.lines().count(), 2, "{table}");
    assert!(table.starts_with("rank,cell,learner.eta,"), "{table}");
    assert!(map.join("merged/confirm/sweep.csv").is_file());
    // The same bytes when merged again.
    ok(&["sweep", "merge", s(&map)]);
    assert_eq!(
        table,
        std::fs::read_to_string(map.join("merged/confirmation.csv")).unwrap()
    );
    // A tampered confirm.json or run list is one line and status 2, not a panic (a point's
    // position outside the grid indexed past the map's cells).
    let record = cdir.join("confirm.json");
    let good = std::fs::read_to_string(&record).unwrap();
    std::fs::write(
        &record,
        good.replace("\"cells\": [\n    1\n  ]", "\"cells\": [\n    9\n  ]"),
    )
    .unwrap();
    let (code, err) = fails(&["sweep", "merge", s(&map)], &[]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("names cell 9"), "{err}");
    // Map and confirmation are one commit: the map's half is not written either.
    let elsewhere = root.join("elsewhere");
    let (code, err) = fails(&["sweep", "merge", s(&map), "--out", s(&elsewhere)], &[]);
    assert_eq!(code, 2, "{err}");
    assert!(
        !elsewhere.join("sweep.csv").exists(),
        "the map's merge was committed without its confirmation"
    );
    let left: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("partial"))
        .collect();
    assert!(left.is_empty(), "staging left behind: {left:?}");
    std::fs::write(&record, good).unwrap();
    let list_path = map.join("points.jsonl");
    let list = std::fs::read_to_string(&list_path).unwrap();
    std::fs::write(
        &list_path,
        list.replacen("\"coords\":[1]", "\"coords\":[7]", 1),
    )
    .unwrap();
    let (code, err) = fails(&["sweep", "merge", s(&map)], &[]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("lie outside the plan's axes"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    std::fs::write(&list_path, list).unwrap();
    // Seeds 11-20 are refused by plan; and a sweep without [confirm] has nothing to confirm.
    let bad = root.join("bad.toml");
    std::fs::write(&bad, sweep.replace("seeds = [21]", "seeds = [21, 13]")).unwrap();
    let (code, err) = fails(
        &["sweep", "plan", s(&bad), "--out", s(&root.join("bad"))],
        &[],
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("seed 13") && err.contains("reserved"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    let plain = root.join("plain.toml");
    let cut = sweep.find("[confirm]").unwrap();
    std::fs::write(&plain, &sweep[..cut]).unwrap();
    let pdir = root.join("plain");
    ok(&["sweep", "plan", s(&plain), "--out", s(&pdir)]);
    ok(&["sweep", "run", s(&pdir), "--threads", "1"]);
    let (code, err) = fails(&["sweep", "confirm", s(&pdir)], &[]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no [confirm] section"), "{err}");
}

/// `sweep merge` warns, in `h8swarm run`'s own words, when a point's repeats are too few for a
/// one-sided sign test to reach p < 0.05 (one repeat, or 2 to 4), and says whether a cell of
/// the maps, which pools its seeds, can; with 5 repeats neither warns.
#[test]
fn merge_warns_as_run_does_when_the_repeats_cannot_reach_significance() {
    let base = fresh("repeat-warning");
    for (repeats, seeds, pooled) in [
        (1, "[1]", "its 1 seed (1 repeat), too few to reach p < 0.05"),
        (
            3,
            "[1, 2]",
            "its 2 seeds (6 repeats), which can reach p < 0.05",
        ),
        (5, "[1]", ""),
    ] {
        let out = base.join(format!("run-{repeats}"));
        let run = ok(&[
            "run",
            "--steps",
            "20",
            "--repeats",
            &repeats.to_string(),
            "--out",
            s(&out),
        ]);
        // Run's warning about its repeats, without its advice on the option to give.
        let run_warning = run
            .lines()
            .find(|l| l.contains("repeat") && l.starts_with("WARNING "))
            .map(|l| l.split(" (use --repeats").next().unwrap_or(l).to_string());

        let file = base.join(format!("w{repeats}.toml"));
        std::fs::write(
            &file,
            format!(
                "name = \"w{repeats}\"\nseeds = {seeds}\n[set]\nsteps = 20\nwindow = 10\n\
                 repeats = {repeats}\n[grid]\n\"learner.eta\" = [0.01]\n"
            ),
        )
        .unwrap();
        let dir = base.join(format!("w{repeats}"));
        ok(&["sweep", "plan", s(&file), "--out", s(&dir)]);
        ok(&["sweep", "run", s(&dir), "--threads", "2"]);
        let merge = ok(&["sweep", "merge", s(&dir)]);
        let merge_warnings: Vec<&str> = merge
            .lines()
            .filter(|l| l.starts_with("WARNING "))
            .collect();
        match run_warning {
            None => {
                assert_eq!(
                    repeats, 5,
                    "run gave no warning for {repeats} repeats:\n{run}"
                );
                assert!(merge_warnings.is_empty(), "{merge}");
            }
            Some(w) => {
                assert!(repeats < 5, "run warned for {repeats} repeats: {w}");
                assert_eq!(merge_warnings.len(), 1, "{merge}");
                assert!(
                    merge_warnings[0].starts_with(&w),
                    "merge's warning\n  {}\ndoes not say run's\n  {w}",
                    merge_warnings[0]
                );
                assert!(merge_warnings[0].ends_with(pooled), "{}", merge_warnings[0]);
            }
        }
    }
}
