//! `h8swarm run` with firmware robots: the same outputs, a user's image on some robots, a
//! faulty image stopping the run (or, with --keep-going, one robot), determinism across threads.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use h8300h::srec::{Chunk, SrecImage, write_s3};

fn h8swarm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_h8swarm"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .output()
        .unwrap()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("h8swarm-runfw-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn metrics(dir: &Path) -> String {
    std::fs::read_to_string(dir.join("metrics.csv")).unwrap()
}

/// An image whose reset vector points at `code` placed at H'000100.
fn image(code: &[u8]) -> String {
    let mut img = SrecImage {
        header: None,
        chunks: vec![
            Chunk {
                address: 0,
                data: 0x100u32.to_be_bytes().to_vec(),
            },
            Chunk {
                address: 0x100,
                data: code.to_vec(),
            },
        ],
        start: None,
    };
    img.start = Some(0x100);
    write_s3(&img, 16)
}

#[test]
fn firmware_robots_write_every_output_with_their_cpu_load_and_the_same_for_any_thread_count() {
    let (a, b) = (tmp("t1"), tmp("t2"));
    let base = [
        "run",
        "arena",
        "--controller",
        "firmware",
        "--steps",
        "120",
        "--repeats",
        "2",
    ];
    let out = h8swarm(&[&base[..], &["--threads", "1", "--out", a.to_str().unwrap()]].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in h8swarm::outputs::OUTPUT_FILES
        .iter()
        .filter(|f| !matches!(**f, "spacetime.png" | "replay.html"))
    {
        assert!(a.join(f).exists(), "{f}");
    }
    let m = metrics(&a);
    assert!(m.starts_with(
        "condition,repeat,step,mean_d,collisions_per_robot,contact_percent,held_percent,shuttling_percent,circling_percent,exploring_percent,moving_percent,moved_mm,net_mm,msd_1_cm2,msd_10_cm2,msd_100_cm2,fresh_cells,new_cells,gap_cv,robots_touching,cpu_load_percent,energy_per_robot_mj"
    ));
    // Every step's CPU load: the ticks and the step at least (about 0.1 %), a save about 5 %.
    let loads: Vec<f64> = m
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(20).unwrap().parse().unwrap())
        .collect();
    assert!(loads.iter().all(|&l| l > 0.05 && l < 10.0), "{loads:?}");
    assert!(loads.iter().any(|&l| l > 4.0), "a step with a save");
    let out = h8swarm(&[&base[..], &["--threads", "2", "--out", b.to_str().unwrap()]].concat());
    assert!(out.status.success());
    assert_eq!(m, metrics(&b), "1 and 2 threads give the same metrics");
    let _ = std::fs::remove_dir_all(&a);
    let _ = std::fs::remove_dir_all(&b);
}

#[test]
fn a_users_image_on_chosen_robots_and_a_faulty_one_named() {
    let dir = tmp("user");
    // The robot firmware under another name, on robot 1 only: the same metrics as all-robot
    // firmware.
    let mine = dir.join("mine.mot");
    std::fs::copy("firmware/robot.mot", &mine).unwrap();
    std::fs::copy("firmware/robot.sym", dir.join("mine.sym")).unwrap();
    let scenario = dir.join("s.toml");
    std::fs::write(
        &scenario,
        format!(
            "base = \"arena\"\nsteps = 60\nrepeats = 1\nwindow = 10\n[controller]\nkind = \"firmware\"\nimage = \"{}\"\nrobots = [1]\n",
            mine.display()
        ),
    )
    .unwrap();
    let (x, y) = (dir.join("x"), dir.join("y"));
    let out = h8swarm(&[
        "run",
        scenario.to_str().unwrap(),
        "--out",
        x.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = h8swarm(&[
        "run",
        "arena",
        "--controller",
        "firmware",
        "--steps",
        "60",
        "--repeats",
        "1",
        "--out",
        y.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    assert_eq!(metrics(&x), metrics(&y));

    // Images without a configuration block run only with the controls off (the controls
    // could not reach them).
    let alone = |image: &std::path::Path| {
        let sc = image.with_extension("toml");
        std::fs::write(
            &sc,
            format!(
                "[controls]\nlearning_off = false\nrandom_walk = false\n[controller]\nkind = \"firmware\"\nimage = \"{}\"\n",
                image.display()
            ),
        )
        .unwrap();
        sc.display().to_string()
    };

    // An image that spins without ever starting the A/D converter: the watchdog names the
    // robot and the PC; with --keep-going the robot dies and the run goes on.
    let spin = dir.join("spin.mot");
    std::fs::write(&spin, image(&[0x40, 0xFE])).unwrap(); // BRA . at H'000100
    let z = dir.join("z");
    let out = h8swarm(&[
        "run",
        &alone(&spin),
        "--steps",
        "5",
        "--repeats",
        "1",
        "--out",
        z.to_str().unwrap(),
    ]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("robot 0") && err.contains("PC H'000100") && err.contains("A/D"),
        "{err}"
    );

    // An undefined opcode, named with its bytes; with --keep-going every robot dies: the run
    // writes its outputs, which name the dead robots, judges nothing, and says it failed.
    let bad = dir.join("bad.mot");
    std::fs::write(&bad, image(&[0x01, 0x50])).unwrap();
    let out = h8swarm(&[
        "run",
        &alone(&bad),
        "--steps",
        "5",
        "--repeats",
        "2",
        "--keep-going",
        "--out",
        z.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.lines().filter(|l| l.starts_with("error:")).count() == 1
            && err.contains("every robot of every run died"),
        "{err}"
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("DEAD  robot 2 in learning repeat 1 (from step 0)")
            && text.contains("undefined opcode at PC H'000100: 01 50")
            && !text.contains("HOLDS"),
        "{text}"
    );
    assert_dead_everywhere(&z, 2, 3);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The outputs in `out` of a learning-only run of `repeats` repeats in which every one of
/// `robots` robots died at step 0 name them, and judge no claim.
fn assert_dead_everywhere(out: &Path, repeats: u32, robots: usize) {
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let dead = summary["dead_robots"].as_array().unwrap();
    assert_eq!(dead.len(), repeats as usize * robots, "{dead:?}");
    assert!(
        dead.iter()
            .all(|d| d["step"] == 0 && d["why"].as_str().unwrap().contains("undefined opcode")),
        "{dead:?}"
    );
    for c in summary["claims"].as_array().unwrap() {
        assert_eq!(c["outcome"], "undecided", "{c}");
    }
    let robots_csv = std::fs::read_to_string(out.join("robots.csv")).unwrap();
    let mut lines = robots_csv.lines();
    assert!(lines.next().unwrap().ends_with(",died_at_step"));
    assert!(lines.all(|l| l.ends_with(",0")), "{robots_csv}");
    let m = metrics(out);
    let mut lines = m.lines();
    assert!(lines.next().unwrap().ends_with(",dead_robots"));
    let n = robots.to_string();
    assert!(
        lines.all(|l| l.rsplit(',').next() == Some(n.as_str())),
        "{m}"
    );
}

#[test]
fn a_repeat_with_a_dead_robot_is_left_out_of_the_claims() {
    // One robot of three runs an image that dies at boot: the run goes on (--keep-going),
    // exits 0, and no claim is judged on the repeats that robot died in.
    let dir = tmp("onedead");
    let bad = dir.join("bad.mot");
    std::fs::write(&bad, image(&[0x01, 0x50])).unwrap();
    let scenario = dir.join("s.toml");
    std::fs::write(
        &scenario,
        format!(
            "base = \"arena\"\nsteps = 40\nrepeats = 2\nwindow = 10\n[controls]\nlearning_off = false\nrandom_walk = false\n[controller]\nkind = \"firmware\"\nimage = \"{}\"\nrobots = [1]\n",
            bad.display()
        ),
    )
    .unwrap();
    let out_dir = dir.join("o");
    let out = h8swarm(&[
        "run",
        scenario.to_str().unwrap(),
        "--keep-going",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("summary.json")).unwrap())
            .unwrap();
    let dead = summary["dead_robots"].as_array().unwrap();
    assert_eq!(dead.len(), 2, "{dead:?}");
    assert!(dead.iter().all(|d| d["robot"] == 1), "{dead:?}");
    for c in summary["claims"].as_array().unwrap() {
        assert_eq!(c["outcome"], "undecided", "{c}");
        assert_eq!(c["repeats"]["undefined"], 2, "{c}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_rejected_configuration_block_is_an_error() {
    let dir = tmp("reject");
    let scenario = dir.join("s.toml");
    // A save period the scenario allows but the firmware's 16-bit field cannot carry.
    std::fs::write(&scenario, "base = \"arena\"\nsteps = 5\nrepeats = 1\nwindow = 5\n[learner]\nsave_every = 70000\n[controller]\nkind = \"firmware\"\n").unwrap();
    let out = h8swarm(&[
        "run",
        scenario.to_str().unwrap(),
        "--out",
        dir.join("o").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("save_every_steps = 70000") && err.contains("configuration block"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
