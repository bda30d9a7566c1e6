//! The H8 meter pinned in nn_q15 itself (docs/design.md §2.7), so the crate used alone still
//! has its cost model checked:
//!
//! - per phase and per block, against an independent count (`common`): how often each basic
//!   block of the firmware's `learner_forward`, `learner_update` and `learner_step` runs,
//!   derived in the test from the inputs and the routines' control flow (the clamps, the
//!   negative products, the divisions, the normalising shift, a new maximum), with the cost
//!   table applied by the test — property-tested over random shapes and weights, saturating
//!   and normalising ones included;
//! - against states measured on the firmware itself for a handful of fixed cases;
//! - the cost table's instruction forms and lengths against docs/design.md §4.2 and the
//!   firmware's symbol table.

mod common;

use common::{
    Counts, PhaseCounts, argmax, block_states, compare_meter, forward_counts, input_counts, sums,
    update_counts,
};
use nn_q15::cost::{Insn, OP_STATES, OP_TABLE, Op};
use nn_q15::{
    DynLearner, H8Meter, InputLayout, Meter, NoopMeter, Params, Phase, Q7, Q15, SENSORS, Shape,
    forward_slice, update_slice,
};
use proptest::prelude::*;
use proptest::test_runner::Config;

fn q15s(w: &[i16]) -> Vec<Q15> {
    w.iter().map(|&v| Q15::from_bits(v)).collect()
}

fn q7s(x: &[i8]) -> Vec<Q7> {
    x.iter().map(|&v| Q7::from_bits(v)).collect()
}

fn bits(w: &[Q15]) -> Vec<i16> {
    w.iter().map(|q| q.to_bits()).collect()
}

/// Counts in one phase only.
fn only(phase: Phase, c: Counts) -> PhaseCounts {
    let mut out = [[0; Op::COUNT]; Phase::COUNT];
    out[phase as usize] = c;
    out
}

/// The weights of the fixed cases: a spread pattern, divided by `scale`.
fn pattern(n: usize, j: usize, scale: i32) -> Vec<i16> {
    (0..n)
        .map(|i| ((((i * 37 + j * 101) % 65536) as i32 - 32768) / scale) as i16)
        .collect()
}

fn forward_states(n: usize, m: usize, w: &[i16], x: &[i8]) -> (H8Meter, nn_q15::ForwardOut) {
    let mut meter = H8Meter::new();
    let f = forward_slice(Shape::new(n, m).unwrap(), &q15s(w), &q7s(x), &mut meter).unwrap();
    (meter, f)
}

// ---------------------------------------------------------------------------------------------
// States measured on the firmware. Each number below is what the emulated H8/300H counted from
// the routine's first instruction to its RTS, running firmware/learner.c as committed
// (firmware/robot.mot; `robot_board::firmware_learner::LearnerOnCore`, the engine of
// `h8swarm learn --replay --on-core --states`), for the same inputs.

#[test]
fn forward_states_match_the_firmware_on_every_path() {
    let mut w_max = vec![-32768i16; 256];
    for j in 1..8 {
        w_max.extend(pattern(256, j, 1));
    }
    let w_norm = [
        32767, 32767, 32767, -32768, -32768, -32768, 32767, 32767, 32766, 1000, -2000, 3000,
    ];
    // (what it exercises, N, M, weights, x, states on the firmware)
    type Case<'a> = (&'a str, usize, usize, &'a [i16], &'a [i8], u64);
    let cases: [Case; 6] = [
        (
            "plain, one output clamped at the bottom, a new maximum",
            2,
            3,
            &[-32768, -32768, 100, 100, 0, 0],
            &[127, 127],
            1084,
        ),
        (
            "normalising by 2^9: a low clamp, a full-scale non-winner, a division",
            3,
            4,
            &w_norm,
            &[127, 127, 127],
            1764,
        ),
        (
            "256 x 8 with the largest sum 2^30: the normalising shift at its 16",
            256,
            8,
            &w_max,
            &[-128; 256],
            97408,
        ),
        ("ties to the lowest index", 1, 4, &[5, 9, 9, 9], &[1], 1180),
        (
            "the largest sum exactly 2^22: normalising by 2^8",
            1,
            2,
            &[-32768, 0],
            &[-128],
            812,
        ),
        (
            "a sum of exactly -2^22 below 1.0: not clamped",
            2,
            2,
            &[-32768, -32768, 0, 0],
            &[64, 64],
            808,
        ),
    ];
    for (what, n, m, w, x, firmware) in cases {
        let (meter, _) = forward_states(n, m, w, x);
        assert_eq!(meter.states(Phase::Forward), firmware, "{what}");
        assert_eq!(
            meter.total_states(),
            firmware,
            "{what}: nothing outside forward"
        );
        let want = forward_counts(&sums(w, x, n), n);
        compare_meter(&meter, &only(Phase::Forward, want))
            .unwrap_or_else(|e| panic!("{what}: {e}"));
    }
    // The all-zero 13 x 4 pass (nn_q15's unit test itemises it): 3 380 states.
    let (meter, _) = forward_states(13, 4, &[0; 52], &[0; 13]);
    assert_eq!(meter.states(Phase::Forward), 3380);
}

#[test]
fn update_states_match_the_firmware_on_every_path() {
    let mut w13 = vec![];
    for j in 0..4 {
        w13.extend(pattern(13, j, 4));
    }
    let x13: Vec<i8> = (0..13).map(|i| (i * 19) as i8).collect();
    let x13b: Vec<i8> = (0..13).map(|i| (i * 53 + 7) as i8).collect();
    let w8 = pattern(16, 3, 2);
    // (what, N, M, weights, x, winner, E, η, T, states on the firmware)
    type Case<'a> = (
        &'a str,
        usize,
        usize,
        &'a [i16],
        &'a [i8],
        usize,
        i16,
        i16,
        i16,
        u64,
    );
    let cases: [Case; 6] = [
        (
            "dead zone at E = T",
            13,
            4,
            &[0; 52],
            &x13,
            0,
            10,
            3277,
            10,
            104,
        ),
        (
            "dead zone at E = -T",
            13,
            4,
            &[0; 52],
            &x13,
            0,
            -10,
            3277,
            10,
            104,
        ),
        (
            "reward at full η: clamps at both rails, a zero and negative products",
            4,
            3,
            &[
                20000, -20000, 5, 1, -20000, 20000, 0, 0, 32767, -32768, -7, 7,
            ],
            &[100, -100, 0, 127],
            2,
            500,
            32767,
            10,
            970,
        ),
        (
            "punishment with η = 0: every product zero",
            5,
            2,
            &[1, 2, 3, 4, 5, -1, -2, -3, -4, -5],
            &[1, -1, 0, 127, -128],
            1,
            -11,
            0,
            10,
            912,
        ),
        (
            "punishment, 13 x 4",
            13,
            4,
            &w13,
            &x13b,
            3,
            -300,
            3277,
            10,
            2744,
        ),
        (
            "reward at E = T + 1 with T = 0",
            8,
            2,
            &w8,
            &[-128, -64, -1, 0, 1, 64, 127, 3],
            1,
            1,
            33,
            0,
            1286,
        ),
    ];
    for (what, n, m, w, x, win, e, eta, t, firmware) in cases {
        let mut meter = H8Meter::new();
        let mut wq = q15s(w);
        let params = Params::new(i32::from(eta), i32::from(t)).unwrap();
        let shape = Shape::new(n, m).unwrap();
        update_slice(shape, &mut wq, &q7s(x), win, e, params, &mut meter).unwrap();
        assert_eq!(meter.states(Phase::Update), firmware, "{what}");
        let want = update_counts(w, x, win, e, eta, t);
        compare_meter(&meter, &only(Phase::Update, want)).unwrap_or_else(|e| panic!("{what}: {e}"));
    }
}

#[test]
fn step_states_match_the_firmware_phase_by_phase() {
    type Run = (usize, usize, bool, i16, &'static [([u8; 4], [u64; 3])]);
    // (M, history, bias, η, [(p, states on the firmware: input, update, forward)]), T = 10,
    // the weights `pattern(N, j, 4)`.
    let runs: [Run; 3] = [
        (
            4,
            1,
            false,
            3277,
            &[
                ([10, 20, 30, 40], [500, 0, 3380]),
                ([200, 200, 200, 200], [530, 2726, 3404]),
                ([255, 255, 255, 255], [530, 2726, 3394]),
                ([0, 0, 0, 0], [530, 2746, 3666]),
                ([128, 128, 128, 128], [530, 2736, 3582]),
            ],
        ),
        (
            2,
            8,
            true,
            33,
            &[
                ([255; 4], [974, 0, 4300]),
                ([0; 4], [1004, 5332, 4304]),
                ([255; 4], [1004, 5326, 4292]),
                ([3, 0, 0, 0], [1004, 5346, 4304]),
                ([255; 4], [1004, 5334, 4292]),
            ],
        ),
        (
            3,
            0,
            false,
            32767,
            &[
                ([1, 2, 3, 4], [388, 0, 1906]),
                ([90, 80, 70, 60], [418, 1600, 1902]),
                ([90, 80, 70, 60], [418, 104, 2064]),
                ([250, 0, 250, 0], [418, 1716, 1996]),
            ],
        ),
    ];
    for (m, h, bias, eta, steps) in runs {
        let layout = InputLayout::new(h, bias).unwrap();
        let n = layout.n_inputs(m);
        let w: Vec<i16> = (0..m).flat_map(|j| pattern(n, j, 4)).collect();
        let params = Params::new(i32::from(eta), 10).unwrap();
        let mut learner = DynLearner::new(m, layout, params, &q15s(&w)).unwrap();
        for (k, &(p, firmware)) in steps.iter().enumerate() {
            let mut meter = H8Meter::new();
            learner.step(&p, &mut meter);
            assert_eq!(
                meter.phase_states(),
                firmware,
                "M = {m}, H = {h}, bias {bias}: step {k}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The cost table.

#[test]
fn instruction_forms_cost_what_the_manual_gives() {
    // (form, states, bytes): docs/design.md §4.2 (on-chip operands, 2 states per access) and
    // the H8/300H instruction formats.
    let table = [
        (Insn::Reg, 2, 2),
        (Insn::ImmW, 4, 4),
        (Insn::ImmL, 6, 6),
        (Insn::MovBwInd, 4, 2),
        (Insn::MovBwPostInc, 6, 2),
        (Insn::MovBwAbs16, 6, 4),
        (Insn::MovBwAbs24, 8, 6),
        (Insn::MovBwDisp24, 10, 8),
        (Insn::MovLInd, 8, 4),
        (Insn::MovLPostInc, 10, 4),
        (Insn::MovLAbs16, 10, 6),
        (Insn::MovLAbs24, 12, 8),
        (Insn::PushPopL, 10, 4),
        (Insn::Bcc8, 4, 2),
        (Insn::Bcc16, 6, 4),
        (Insn::JsrAbs24, 10, 4),
        (Insn::Rts, 10, 2),
        (Insn::MulxsW, 24, 4),
        (Insn::DivxsW, 24, 4),
    ];
    assert_eq!(table.len(), Insn::ALL.len());
    for (insn, states, bytes) in table {
        assert_eq!(insn.states(), states, "{insn:?} states");
        assert_eq!(insn.bytes(), bytes, "{insn:?} bytes");
        let (asm, encoding) = insn.example();
        assert!(!asm.is_empty(), "{insn:?} has an example");
        assert_eq!(encoding.len() as u32, bytes, "{insn:?}: {asm}");
    }
    // Three examples' encodings, from the H8/300H manual's instruction formats.
    assert_eq!(Insn::Rts.example(), ("rts", &[0x54, 0x70][..]));
    assert_eq!(Insn::MulxsW.example().1, &[0x01, 0xC0, 0x52, 0x23]);
    assert_eq!(Insn::Bcc8.example().1, &[0x46, 0x00]);
}

#[test]
fn each_block_costs_the_sum_of_its_instructions() {
    for (k, &op) in Op::ALL.iter().enumerate() {
        let spec = op.spec();
        assert_eq!(spec.op, op);
        // `OP_TABLE` is a constant: compare the entry, not its address.
        let entry = &OP_TABLE[k];
        assert_eq!(
            (entry.op, entry.insns, entry.asm),
            (op, spec.insns, spec.asm)
        );
        let states: u32 = spec.insns.iter().map(|i| i.states()).sum();
        let bytes: u32 = spec.insns.iter().map(|i| i.bytes()).sum();
        assert_eq!(spec.states(), states, "{op:?}");
        assert_eq!(op.states(), states, "{op:?}");
        assert_eq!(OP_STATES[k], states, "{op:?}");
        assert_eq!(u64::from(states), block_states(op), "{op:?}");
        assert_eq!(spec.bytes(), bytes, "{op:?}");
        assert!(!spec.asm.is_empty(), "{op:?}");
    }
    // Two blocks itemised by hand from the listing (firmware/build.sh --listing).
    assert_eq!(Op::FwdMac.spec().bytes(), 2 + 2 + 2 + 4 + 2 + 2 + 2);
    assert_eq!(Op::DeltaHead.spec().bytes(), 2 + 2 + 4 + 2 + 2);
}

#[test]
fn the_blocks_cover_each_routine_byte_for_byte() {
    // The routines' extents in firmware/robot.sym (the committed image's symbol table):
    // learner_forward 0x83c .. 0xa2c, learner_update 0xa2c .. 0xb34, learner_step 0xb34 ..
    // 0xc5e (crc16 follows).
    let bytes = |prefixes: &[&str]| -> u32 {
        Op::ALL
            .iter()
            .filter(|op| prefixes.iter().any(|p| format!("{op:?}").starts_with(p)))
            .map(|op| op.spec().bytes())
            .sum()
    };
    assert_eq!(bytes(&["Fwd"]), 0xa2c - 0x83c, "learner_forward");
    assert_eq!(bytes(&["In"]), 0xc5e - 0xb34, "learner_step");
    // learner_update has its weight loop twice (ADD.W for the winner's row, SUB.W for the
    // others'), each one UpdWeight with the clamp's three instructions (UpdClampLo, whose
    // first two are UpdClampHi): the blocks once, less UpdClampHi, plus one more loop.
    let loop_bytes = Op::UpdWeight.spec().bytes() + Op::UpdClampLo.spec().bytes();
    assert_eq!(
        bytes(&["Upd", "Delta"]) - Op::UpdClampHi.spec().bytes() + loop_bytes,
        0xb34 - 0xa2c,
        "learner_update"
    );
}

#[test]
fn the_meter_keeps_each_phase_and_block_apart() {
    let mut m = H8Meter::default();
    assert_eq!(m.phase_states(), [0; 3]);
    // Charges go to the phase entered last; a new meter starts in `input`.
    m.charge(Op::InEntry, 2);
    m.enter(Phase::Forward);
    m.charge(Op::FwdMac, 3);
    m.charge(Op::FwdMac, 4);
    m.enter(Phase::Update);
    m.charge(Op::UpdWeight, 5);
    m.charge(Op::FwdMac, 1);
    let (entry, mac, weight) = (
        u64::from(Op::InEntry.states()),
        u64::from(Op::FwdMac.states()),
        u64::from(Op::UpdWeight.states()),
    );
    assert_eq!(m.count_in(Phase::Input, Op::InEntry), 2);
    assert_eq!(m.count_in(Phase::Forward, Op::FwdMac), 7);
    assert_eq!(m.count_in(Phase::Update, Op::FwdMac), 1);
    assert_eq!(m.count_in(Phase::Update, Op::UpdWeight), 5);
    assert_eq!(m.count_in(Phase::Input, Op::FwdMac), 0);
    assert_eq!(m.count(Op::FwdMac), 8);
    assert_eq!(m.count(Op::UpdWeight), 5);
    assert_eq!(m.count(Op::InExit), 0);
    assert_eq!(m.phase_states(), [2 * entry, 5 * weight + mac, 7 * mac]);
    assert_eq!(m.states(Phase::Forward), 7 * 46);
    assert_eq!(m.total_states(), 2 * entry + 5 * weight + 8 * mac);
    m.reset();
    assert_eq!(m.total_states(), 0);
    assert_eq!(m.count(Op::FwdMac), 0);
    // After a reset the meter is back in `input`.
    m.charge(Op::InExit, 1);
    assert_eq!(m.count_in(Phase::Input, Op::InExit), 1);
    const { assert!(H8Meter::ACTIVE && !NoopMeter::ACTIVE) };
    assert_eq!(Phase::ALL.map(Phase::name), ["input", "update", "forward"]);
}

// ---------------------------------------------------------------------------------------------
// Property tests: the meter against the independent count.

fn weight() -> impl Strategy<Value = i16> {
    prop_oneof![
        6 => any::<i16>(),
        2 => Just(i16::MAX),
        2 => Just(i16::MIN),
        2 => (i16::MAX - 400)..=i16::MAX,
        2 => i16::MIN..=(i16::MIN + 400),
        1 => -64i16..=64,
        1 => Just(0i16),
    ]
}

fn input() -> impl Strategy<Value = i8> {
    prop_oneof![
        6 => any::<i8>(),
        2 => Just(-128i8),
        2 => Just(127i8),
        2 => Just(0i8),
        1 => Just(64i8),
        1 => Just(-64i8),
        1 => -2i8..=2,
    ]
}

fn eta() -> impl Strategy<Value = i16> {
    prop_oneof![3 => 0i16..=i16::MAX, 2 => Just(0i16), 2 => Just(i16::MAX), 1 => Just(33i16), 1 => Just(3277i16), 1 => 1i16..=200]
}

fn threshold() -> impl Strategy<Value = i16> {
    prop_oneof![3 => Just(10i16), 2 => 0i16..=1020, 1 => Just(0i16), 1 => 0i16..=i16::MAX]
}

fn n_inputs() -> impl Strategy<Value = usize> {
    prop_oneof![4 => 1usize..=16, 2 => 17usize..=255, 1 => Just(256usize)]
}

/// A network and an input: random, saturating (every weight at a rail, x at ±128/127), or
/// normalising (large weights lined up with large inputs: sums of 2^22 and more), with some
/// rows copied so that sums tie.
fn net_and_input() -> impl Strategy<Value = (usize, usize, Vec<i16>, Vec<i8>)> {
    (n_inputs(), 2usize..=8, 0u8..4).prop_flat_map(|(n, m, kind)| {
        let w = match kind {
            0 | 1 => prop::collection::vec(weight(), n * m).boxed(),
            2 => prop::collection::vec(prop_oneof![Just(i16::MAX), Just(i16::MIN)], n * m).boxed(),
            _ => prop::collection::vec(8192i16..=i16::MAX, n * m).boxed(),
        };
        let x = match kind {
            3 => prop::collection::vec(64i8..=127, n).boxed(),
            2 => prop::collection::vec(prop_oneof![Just(-128i8), Just(127i8)], n).boxed(),
            _ => prop::collection::vec(input(), n).boxed(),
        };
        (Just(n), Just(m), w, x, any::<u8>()).prop_map(|(n, m, mut w, x, dup)| {
            for j in 1..m {
                if dup & (1 << j) != 0 && dup & 1 != 0 {
                    w.copy_within(0..n, j * n);
                }
            }
            (n, m, w, x)
        })
    })
}

/// E at and around the dead zone's edges and anywhere.
fn evaluation(t: i16) -> impl Strategy<Value = i16> {
    prop_oneof![
        Just(t),
        Just(-t),
        Just(t.saturating_add(1)),
        Just(-t - 1),
        Just(0i16),
        Just(i16::MAX),
        Just(i16::MIN),
        any::<i16>(),
        -1020i16..=1020,
    ]
}

proptest! {
    #![proptest_config(Config::with_cases(common::cases()))]

    /// `learner_forward`'s blocks, per phase and per block, for any shape and weights: the
    /// meter charges exactly the count, nothing to the other phases.
    #[test]
    fn forward_is_charged_block_by_block((n, m, w, x) in net_and_input()) {
        let (meter, f) = forward_states(n, m, &w, &x);
        let y = sums(&w, &x, n);
        let want = forward_counts(&y, n);
        if let Err(e) = compare_meter(&meter, &only(Phase::Forward, want)) {
            prop_assert!(false, "{}", e);
        }
        // And the values the counts were derived from.
        prop_assert_eq!(f.win(), argmax(&y));
        prop_assert_eq!(f.o_bits().to_vec(), common::outputs(&y));
    }

    /// `learner_update`'s blocks for any shape, weights, winner, η, T and E (dead zone, reward,
    /// punishment, clamps at both rails, zero and negative products).
    #[test]
    fn update_is_charged_block_by_block(
        (n, m, w, x, win, eta, t, e) in (net_and_input(), eta(), threshold()).prop_flat_map(
            |((n, m, w, x), eta, t)| (Just(n), Just(m), Just(w), Just(x), 0..m, Just(eta), Just(t), evaluation(t))
        )
    ) {
        let mut meter = H8Meter::new();
        let mut wq = q15s(&w);
        let params = Params::new(i32::from(eta), i32::from(t)).unwrap();
        update_slice(Shape::new(n, m).unwrap(), &mut wq, &q7s(&x), win, e, params, &mut meter).unwrap();
        let want = update_counts(&w, &x, win, e, eta, t);
        if let Err(why) = compare_meter(&meter, &only(Phase::Update, want)) {
            prop_assert!(false, "{}", why);
        }
        let mut w_ref = w.clone();
        common::update(&mut w_ref, &x, win, e, eta, t);
        prop_assert_eq!(bits(&wq), w_ref);
    }

    /// Whole steps of a robot's learner, any layout (history 0 … 8, bias, spare inputs), 2 … 4
    /// behaviours: the input vector built in the test from §2.2, then each phase's blocks
    /// (`learner_step`'s own, the update on the previous input and winner, the forward pass)
    /// against the count, step after step; proximities include 0 and 255 runs, so E reaches
    /// ±1020.
    #[test]
    fn steps_are_charged_phase_by_phase(
        (m, h, bias, spare, w, eta, t, ps) in (2usize..=4, 0usize..=8, any::<bool>(), prop_oneof![3 => Just(0u16), 1 => 0u16..=40])
            .prop_flat_map(|(m, h, bias, spare)| {
                let n = InputLayout::new(h, bias).unwrap().with_spare(spare).n_inputs(m);
                let p = prop_oneof![
                    2 => Just([255u8; 4]),
                    2 => Just([0u8; 4]),
                    4 => prop::array::uniform4(any::<u8>()),
                    2 => prop::array::uniform4(prop_oneof![Just(0u8), Just(255u8), any::<u8>()]),
                ];
                (
                    Just(m), Just(h), Just(bias), Just(spare),
                    prop::collection::vec(weight(), n * m),
                    eta(), threshold(),
                    prop::collection::vec(p, 1..12),
                )
            })
    ) {
        let layout = InputLayout::new(h, bias).unwrap().with_spare(spare);
        let n = layout.n_inputs(m);
        let params = Params::new(i32::from(eta), i32::from(t)).unwrap();
        let mut learner = DynLearner::new(m, layout, params, &q15s(&w)).unwrap();
        // The reference's own state: weights, x, outputs, D(t−1), winner.
        let mut w_ref = w.clone();
        let mut x_ref = vec![0i8; n];
        let mut o_ref = vec![0i16; m];
        let mut d_prev: Option<i16> = None;
        let mut win_ref = 0usize;
        for (k, p) in ps.iter().enumerate() {
            let mut meter = H8Meter::new();
            let out = learner.step(p, &mut meter);
            let d: i16 = p.iter().map(|&v| i16::from(v)).sum();
            let e = d_prev.map_or(0, |dp| d - dp);
            let mut expected = [[0; Op::COUNT]; Phase::COUNT];
            expected[Phase::Input as usize] = input_counts(d_prev.is_some(), e, h, bias, m);
            if d_prev.is_some() {
                expected[Phase::Update as usize] = update_counts(&w_ref, &x_ref, win_ref, e, eta, t);
                common::update(&mut w_ref, &x_ref, win_ref, e, eta, t);
            }
            // x(t): current proximities, H delayed blocks (newest first), past outputs, E, bias.
            let mut x_new = vec![0i8; n];
            for (s, &pk) in p.iter().enumerate() {
                x_new[s] = (i16::from(pk) - 128) as i8;
            }
            x_new[SENSORS..SENSORS * (1 + h)].copy_from_slice(&x_ref[..SENSORS * h]);
            let at = SENSORS * (1 + h);
            for j in 0..m {
                x_new[at + j] = (o_ref[j] >> 8) as i8;
            }
            x_new[at + m] = (e >> 3).clamp(-128, 127) as i8;
            if bias {
                x_new[at + m + 1] = 127;
            }
            x_ref = x_new;
            let y = sums(&w_ref, &x_ref, n);
            expected[Phase::Forward as usize] = forward_counts(&y, n);
            win_ref = argmax(&y);
            o_ref = common::outputs(&y);
            d_prev = Some(d);

            if let Err(why) = compare_meter(&meter, &expected) {
                prop_assert!(false, "step {}: {}", k, why);
            }
            prop_assert_eq!(out.d, d, "step {}", k);
            prop_assert_eq!(out.e, e, "step {}", k);
            prop_assert_eq!(out.update.is_some(), k > 0, "step {}", k);
            prop_assert_eq!(out.forward.win(), win_ref, "step {}", k);
            prop_assert_eq!(out.behaviour as usize, win_ref, "step {}", k);
            prop_assert_eq!(learner.inputs().iter().map(|q| q.to_bits()).collect::<Vec<_>>(), x_ref.clone(), "step {}", k);
            prop_assert_eq!(bits(learner.outputs()), o_ref.clone(), "step {}", k);
            prop_assert_eq!(bits(learner.weights()), w_ref.clone(), "step {}", k);
        }
    }

    /// A meter that records nothing changes nothing: the same steps with `NoopMeter` and with
    /// `H8Meter` give the same results.
    #[test]
    fn metering_changes_nothing(
        (w, ps) in (prop::collection::vec(weight(), 52), prop::collection::vec(prop::array::uniform4(any::<u8>()), 1..20))
    ) {
        let make = || DynLearner::new(4, InputLayout::DEFAULT, Params::CORRIDOR, &q15s(&w)).unwrap();
        let (mut a, mut b) = (make(), make());
        let mut meter = H8Meter::new();
        for p in &ps {
            prop_assert_eq!(a.step(p, &mut NoopMeter), b.step(p, &mut meter));
        }
        prop_assert_eq!(a.weights(), b.weights());
    }
}
