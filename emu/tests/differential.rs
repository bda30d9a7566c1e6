//! Differential tests: every `tests/programs/<name>.mot` (built from C by
//! `tests/programs/build.sh` with `h8300-hms-gcc -mh -mint32 -O2`) runs on the core and must print
//! exactly `<name>.expected` (the same C program compiled for the host) and halt with exit
//! status 0.
//!
//! If the folder has C sources but no images, the test fails loudly: the images are committed
//! so that this test needs no cross compiler.

use std::path::{Path, PathBuf};

use h8_3052f::run::{Outcome, RunOptions, run_image};

/// A generous state budget per program (the programs are meant to stay under 50 M states).
const MAX_STATES_PER_PROGRAM: u64 = 500_000_000;

fn programs_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("programs")
}

fn files_with_ext(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(Result::ok)
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|e| e == ext))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn every_program_image_prints_its_host_output_and_exits_0() {
    let dir = programs_dir();
    let images = files_with_ext(&dir, "mot");
    let sources = files_with_ext(&dir, "c");
    if images.is_empty() {
        assert!(
            sources.is_empty(),
            "{} has {} C sources but no .mot images: run tests/programs/build.sh and commit the images",
            dir.display(),
            sources.len()
        );
        println!("no program images in {} yet", dir.display());
        return;
    }
    let mut failures = Vec::new();
    for mot in &images {
        let name = mot
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let expected_path = mot.with_extension("expected");
        let Ok(expected) = std::fs::read(&expected_path) else {
            failures.push(format!("{name}: no {}", expected_path.display()));
            continue;
        };
        let image = std::fs::read(mot).expect("read image");
        let mut console = Vec::new();
        let options = RunOptions {
            max_states: Some(MAX_STATES_PER_PROGRAM),
            ..RunOptions::default()
        };
        let report = match run_image(&image, &options, &mut console, None) {
            Ok(r) => r,
            Err(e) => {
                failures.push(format!("{name}: {e}"));
                continue;
            }
        };
        println!(
            "{name}: {:?}, {} instructions, {} states ({:.3} s at 25 MHz), {} console bytes",
            report.outcome,
            report.stats.instructions,
            report.stats.states,
            report.stats.emulated_seconds,
            console.len()
        );
        if report.outcome != (Outcome::Halted { exit_status: 0 }) {
            failures.push(format!(
                "{name}: ended with {:?} instead of exit status 0; output so far:\n{}",
                report.outcome,
                String::from_utf8_lossy(&console)
            ));
            continue;
        }
        if console != expected {
            let got = String::from_utf8_lossy(&console);
            let want = String::from_utf8_lossy(&expected);
            let first_diff = got
                .lines()
                .zip(want.lines())
                .position(|(a, b)| a != b)
                .unwrap_or_else(|| got.lines().count().min(want.lines().count()));
            failures.push(format!(
                "{name}: output differs from {} at line {}:\n  core: {:?}\n  host: {:?}",
                expected_path.display(),
                first_diff + 1,
                got.lines().nth(first_diff),
                want.lines().nth(first_diff)
            ));
        }
    }
    println!("{} program images run", images.len());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
