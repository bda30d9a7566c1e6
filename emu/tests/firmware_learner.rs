//! The firmware's learner (firmware/learner.c, run on the H8/300H core) against `nn_q15`:
//! bit-exact step for step (weights, y, O, winner), and the H8 meter's states against the
//! states the core counts (the calibration of docs/design.md §2.7's cost model).

use nn_q15::{
    DynLearner, H8Meter, InputLayout, Params, Phase, Q7, Q15, Shape, forward_slice, update_slice,
};
use robot_board::firmware::Firmware;
use robot_board::firmware_learner::LearnerOnCore;

/// A small seeded generator for test inputs (SplitMix64).
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
    fn i16(&mut self) -> i16 {
        self.next() as i16
    }
    fn i8(&mut self) -> i8 {
        self.next() as i8
    }
}

fn firmware() -> Firmware {
    Firmware::robot().expect("the committed firmware parses")
}

/// How the weights and inputs of a forward/update run are drawn.
#[derive(Clone, Copy, Debug)]
enum Draw {
    /// Weights uniform in ±0.25, x uniform.
    Plain,
    /// Weights within 64 of ±32767 and η large: updates clamp.
    Saturating,
    /// Large positive weights and large positive x: m ≥ 2^22, Eq. 2's division.
    Normalising,
}

fn draw_weights(g: &mut Gen, n: usize, draw: Draw) -> Vec<i16> {
    (0..n)
        .map(|_| match draw {
            Draw::Plain => g.i16() / 4,
            Draw::Saturating => {
                let off = g.below(64) as i16;
                if g.below(2) == 0 {
                    32767 - off
                } else {
                    -32768 + off
                }
            }
            Draw::Normalising => 8192 + (g.below(24576) as i16) - (g.below(4) as i16) * 8192,
        })
        .collect()
}

fn draw_x(g: &mut Gen, n: usize, draw: Draw) -> Vec<i8> {
    (0..n)
        .map(|_| match draw {
            Draw::Normalising => 32 + (g.below(96) as i8),
            _ => match g.below(8) {
                0 => -128,
                1 => 127,
                2 => 0,
                _ => g.i8(),
            },
        })
        .collect()
}

fn draw_e(g: &mut Gen, threshold: i16) -> i16 {
    match g.below(6) {
        0 => threshold,
        1 => -threshold,
        2 => threshold.saturating_add(1),
        3 => (g.below(41) as i16) - 20,
        4 => g.i16() >> 5,
        _ => g.i16(),
    }
}

/// What a forward/update comparison saw.
#[derive(Debug, Default)]
struct Seen {
    steps: u64,
    normalising: u64,
    clamped: u64,
    fw_forward: Vec<u64>,
    fw_update: Vec<u64>,
    meter_forward: Vec<u64>,
    meter_update: Vec<u64>,
}

/// Runs `steps` forward passes and updates on both the firmware and `nn_q15`, asserting
/// bit-exact results at every step.
fn forward_update(n_in: usize, n_out: usize, eta: i16, draw: Draw, steps: u64, seed: u64) -> Seen {
    let threshold = 10;
    let mut g = Gen(seed);
    let fw = firmware();
    let mut core = LearnerOnCore::new(&fw).unwrap();
    let mut w = draw_weights(&mut g, n_in * n_out, draw);
    core.setup(n_in, n_out, eta, threshold, &w).unwrap();
    let shape = Shape::new(n_in, n_out).unwrap();
    let params = Params::new(i32::from(eta), i32::from(threshold)).unwrap();
    let mut seen = Seen::default();
    for step in 0..steps {
        if step % 97 == 0 && !matches!(draw, Draw::Plain) {
            // Keep the weights where the run means them to be.
            w = draw_weights(&mut g, n_in * n_out, draw);
            core.set_weights(&w);
        }
        let x = draw_x(&mut g, n_in, draw);
        let e = draw_e(&mut g, threshold);
        let f = core.forward(&x).unwrap();
        let fu = core.update(e).unwrap();

        let mut wq: Vec<Q15> = w.iter().map(|&v| Q15::from_bits(v)).collect();
        let xq: Vec<Q7> = x.iter().map(|&v| Q7::from_bits(v)).collect();
        let mut meter = H8Meter::new();
        let out = forward_slice(shape, &wq, &xq, &mut meter).unwrap();
        update_slice(shape, &mut wq, &xq, out.win(), e, params, &mut meter).unwrap();
        let w_next: Vec<i16> = wq.iter().map(|q| q.to_bits()).collect();

        assert_eq!(f.y, out.y_bits(), "{n_in}x{n_out} step {step}: y");
        assert_eq!(f.o, out.o_bits(), "{n_in}x{n_out} step {step}: O");
        assert_eq!(f.win, out.win(), "{n_in}x{n_out} step {step}: winner");
        assert_eq!(
            core.weights(),
            w_next,
            "{n_in}x{n_out} step {step}: weights after E = {e}"
        );
        seen.clamped += w_next
            .iter()
            .zip(&w)
            .filter(|&(&a, &b)| (a == i16::MAX || a == i16::MIN) && a != b)
            .count() as u64;
        w = w_next;
        seen.normalising += u64::from(out.y_bits().iter().any(|&y| y >= 1 << 22));
        seen.steps += 1;
        seen.fw_forward.push(f.states);
        seen.fw_update.push(fu);
        seen.meter_forward.push(meter.states(Phase::Forward));
        seen.meter_update.push(meter.states(Phase::Update));
    }
    seen
}

/// Runs `steps` whole learner steps (`learner_step` against `DynLearner::step`) from a walk of
/// proximities, asserting the same weights, outputs and winner at every step and the same
/// states per phase.
fn whole_steps(n_out: usize, history: usize, bias: bool, eta: i16, steps: u64, seed: u64) {
    let mut g = Gen(seed);
    let layout = InputLayout::new(history, bias).unwrap();
    let n_in = layout.n_inputs(n_out);
    let w = draw_weights(&mut g, n_in * n_out, Draw::Plain);
    let fw = firmware();
    let mut core = LearnerOnCore::new(&fw).unwrap();
    core.setup(n_in, n_out, eta, 10, &w).unwrap();
    core.set_layout(history as u8, bias);
    let wq: Vec<Q15> = w.iter().map(|&v| Q15::from_bits(v)).collect();
    let params = Params::new(i32::from(eta), 10).unwrap();
    let mut learner = DynLearner::new(n_out, layout, params, &wq).unwrap();
    let mut p = [128u8; 4];
    let (mut rewards, mut punishments) = (0u64, 0u64);
    for step in 0..steps {
        for v in &mut p {
            *v = if g.below(50) == 0 {
                g.next() as u8
            } else {
                v.saturating_add(g.below(25) as u8).saturating_sub(12)
            };
        }
        let (win, states) = core.step(p).unwrap();
        let mut meter = H8Meter::new();
        let out = learner.step(&p, &mut meter);
        let wd: Vec<i16> = learner.weights().iter().map(|q| q.to_bits()).collect();
        assert_eq!(core.weights(), wd, "step {step}: weights");
        assert_eq!(win, out.behaviour as usize, "step {step}: winner");
        assert_eq!(
            states.input,
            meter.states(Phase::Input),
            "step {step}: input states"
        );
        assert_eq!(
            states.update,
            meter.states(Phase::Update),
            "step {step}: update states"
        );
        assert_eq!(
            states.forward,
            meter.states(Phase::Forward),
            "step {step}: forward states"
        );
        match out.update {
            Some(nn_q15::UpdateKind::Reward) => rewards += 1,
            Some(nn_q15::UpdateKind::Punish) => punishments += 1,
            _ => {}
        }
    }
    assert!(
        rewards > steps / 20 && punishments > steps / 20,
        "{rewards} rewards, {punishments} punishments"
    );
}

const STEPS: u64 = 10_000;

#[test]
fn arena_13x4_step_by_step_at_every_eta() {
    for (k, eta) in [0i16, 33, 3277, 32767].into_iter().enumerate() {
        whole_steps(4, 1, false, eta, STEPS, 100 + k as u64);
    }
}

#[test]
fn corridor_11x2_step_by_step() {
    whole_steps(2, 1, false, 3277, STEPS, 200);
}

#[test]
fn history_0_and_8_and_the_bias_step_by_step() {
    whole_steps(4, 0, false, 3277, STEPS, 300);
    whole_steps(4, 8, false, 3277, STEPS, 301);
    whole_steps(4, 1, true, 3277, STEPS, 302);
    whole_steps(2, 8, true, 33, STEPS, 303);
}

#[test]
fn saturating_weights_forward_and_update() {
    let seen = forward_update(13, 4, 32767, Draw::Saturating, STEPS, 400);
    assert!(seen.clamped > 1000, "only {} clamps", seen.clamped);
}

#[test]
fn the_normalising_branch_forward_and_update() {
    let seen = forward_update(13, 4, 3277, Draw::Normalising, STEPS, 500);
    assert!(
        seen.normalising > STEPS / 2,
        "only {} normalising steps",
        seen.normalising
    );
    let seen = forward_update(256, 8, 33, Draw::Normalising, 1_000, 501);
    assert_eq!(seen.normalising, seen.steps);
}

#[test]
fn plain_forward_and_update_at_every_eta() {
    for (k, eta) in [0i16, 33, 3277, 32767].into_iter().enumerate() {
        forward_update(13, 4, eta, Draw::Plain, STEPS, 600 + k as u64);
    }
    forward_update(11, 2, 3277, Draw::Plain, STEPS, 610);
}

fn mean(v: &[u64]) -> f64 {
    v.iter().sum::<u64>() as f64 / v.len() as f64
}

/// Over a grid of shapes N 5…256 × M 2…8, the meter's mean states per phase
/// within ±5 % of the firmware's measured mean on the same inputs, its worst step within ±10 %.
/// (Today they are equal: the meter follows the firmware's listing block by block; the second
/// assertion holds that, so that any drift of either side shows.)
#[test]
fn the_meter_is_calibrated_against_the_firmware_over_a_grid_of_shapes() {
    let mut seed = 700;
    for n_in in [5, 6, 9, 13, 24, 41, 64, 100, 128, 200, 256] {
        for n_out in 2..=8 {
            for draw in [Draw::Plain, Draw::Normalising] {
                seed += 1;
                let steps = if n_in > 100 { 60 } else { 200 };
                let s = forward_update(n_in, n_out, 3277, draw, steps, seed);
                for (phase, fw, model) in [
                    ("forward", &s.fw_forward, &s.meter_forward),
                    ("update", &s.fw_update, &s.meter_update),
                ] {
                    let (fm, mm) = (mean(fw), mean(model));
                    let (fx, mx) = (*fw.iter().max().unwrap(), *model.iter().max().unwrap());
                    let label = format!("{n_in}x{n_out} {draw:?} {phase}");
                    assert!(
                        (mm / fm - 1.0).abs() <= 0.05,
                        "{label}: mean model {mm} firmware {fm}"
                    );
                    assert!(
                        (mx as f64 / fx as f64 - 1.0).abs() <= 0.10,
                        "{label}: worst model {mx} firmware {fx}"
                    );
                    assert_eq!(
                        fw, model,
                        "{label}: the meter no longer follows the firmware step for step"
                    );
                }
            }
        }
    }
}
