//! `h8swarm learn --replay --on-core` (the firmware's routines on the emulated H8/300H) prints
//! the same lines as `learn --replay` (nn_q15), with and without `--states`, for any input.

use std::io::Cursor;
use std::process::Command;

use h8swarm::commands::learn::{self, Engine};
use robot_board::firmware::Firmware;

fn replay_text(input: &str, engine: &Engine, states: bool) -> String {
    let mut out = Vec::new();
    learn::run(&mut Cursor::new(input.as_bytes()), &mut out, states, engine)
        .unwrap_or_else(|e| panic!("replay failed: {e:?}"));
    String::from_utf8(out).unwrap()
}

fn input_text(
    n_in: usize,
    n_out: usize,
    eta: i16,
    threshold: i16,
    weights: &[i16],
    steps: &[(Vec<i8>, i16)],
) -> String {
    let rows: Vec<String> = weights
        .chunks(n_in)
        .map(|r| {
            format!(
                "[{}]",
                r.iter()
                    .map(|v| v.to_string())
                    .collect::<Vec<_>>()
                    .join(",")
            )
        })
        .collect();
    let mut s = format!(
        "{{\"n_in\":{n_in},\"n_out\":{n_out},\"eta\":{eta},\"threshold\":{threshold},\"weights\":[{}]}}\n",
        rows.join(",")
    );
    for (x, e) in steps {
        let xs: Vec<String> = x.iter().map(|v| v.to_string()).collect();
        s += &format!("{{\"x\":[{}],\"e\":{e}}}\n", xs.join(","));
    }
    s
}

/// A seeded generator for the cases (SplitMix64).
struct Gen(u64);

impl Gen {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// A random replay: N 1–40, M 2–8, any η, T of 0, 10 or up to 2 000, weights anywhere
/// (saturated ones included), 1–12 steps with any x and E.
fn case(g: &mut Gen) -> String {
    let n = 1 + g.below(40) as usize;
    let m = 2 + g.below(7) as usize;
    let eta = g.below(32768) as i16;
    let t = match g.below(3) {
        0 => 0,
        1 => 10,
        _ => g.below(2001) as i16,
    };
    let w: Vec<i16> = (0..n * m)
        .map(|_| match g.below(4) {
            0 => i16::MAX,
            1 => i16::MIN,
            2 => g.below(400) as i16 - 200,
            _ => g.next() as i16,
        })
        .collect();
    let steps: Vec<(Vec<i8>, i16)> = (0..1 + g.below(12))
        .map(|_| {
            let x = (0..n).map(|_| g.next() as i8).collect();
            let e = if g.below(2) == 0 {
                g.next() as i16
            } else {
                g.below(40) as i16 - 20
            };
            (x, e)
        })
        .collect();
    input_text(n, m, eta, t, &w, &steps)
}

#[test]
fn on_core_prints_what_nn_q15_prints() {
    let fw = Engine::OnCore(Box::new(Firmware::robot().unwrap()));
    let mut g = Gen(2024);
    for k in 0..300 {
        let input = case(&mut g);
        assert_eq!(
            replay_text(&input, &Engine::Model, true),
            replay_text(&input, &fw, true),
            "case {k}:\n{input}"
        );
    }
}

#[test]
fn the_cli_on_core_agrees_on_the_shipped_example() {
    let run = |extra: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_h8swarm"))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args(["learn", "--replay", "examples/replay-arena.jsonl"])
            .args(extra)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap()
    };
    let model = run(&["--states"]);
    assert_eq!(model.lines().count(), 40);
    assert_eq!(model, run(&["--states", "--on-core"]));
    assert_eq!(run(&[]), run(&["--on-core"]));
}
