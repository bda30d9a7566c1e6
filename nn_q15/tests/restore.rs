//! Restart and restore (docs/design.md §2.5): what a reboot that restores the weights from the
//! EEPROMs relies on, and what freezing the learning (η = 0) relies on.
//!
//! - a learner restarted mid-run applies no update on its first step (no stale D(t−1), winner
//!   or input) and from then on matches a learner that was never stopped, built on the same
//!   weights;
//! - weights and parameters restored from a record give the same next steps as the run that
//!   wrote them; a restore keeps the carried state;
//! - a refused restore (wrong length) leaves the learner as it was;
//! - η = 0 freezes the weights bit for bit;
//! - a shape at `MAX_WEIGHTS` works, one input more is refused.

mod common;

use nn_q15::{
    Behaviour, DynLearner, H8Meter, InputLayout, Learner, MAX_WEIGHTS, Network, NoopMeter, Params,
    Q15, ShapeError, StepOut,
};
use proptest::prelude::*;
use proptest::test_runner::Config;

type Arena = Learner<13, 4>;

fn bits(w: &[Q15]) -> Vec<i16> {
    w.iter().map(|q| q.to_bits()).collect()
}

fn net13x4(w: &[i16]) -> Network<13, 4> {
    let mut rows = [[0i16; 13]; 4];
    for (j, row) in rows.iter_mut().enumerate() {
        row.copy_from_slice(&w[j * 13..(j + 1) * 13]);
    }
    Network::from_bits(rows)
}

/// A walk of proximities that gives rewards and punishments (a fixed pattern, no generator).
fn walk(len: usize, phase: u32) -> Vec<[u8; 4]> {
    (0..len as u32)
        .map(|t| {
            let t = t + phase;
            [
                (t * 37 % 256) as u8,
                (t * 11 % 256) as u8,
                (t * t % 251) as u8,
                (255 - t * 5 % 256) as u8,
            ]
        })
        .collect()
}

fn spread_weights(n: usize, scale: i32) -> Vec<i16> {
    (0..n)
        .map(|i| ((((i * 7919) % 65536) as i32 - 32768) / scale) as i16)
        .collect()
}

fn arena(w: &[i16], params: Params) -> Arena {
    Arena::new(net13x4(w), params, InputLayout::DEFAULT).unwrap()
}

fn dynamic(w: &[i16], params: Params) -> DynLearner {
    let wq: Vec<Q15> = w.iter().map(|&v| Q15::from_bits(v)).collect();
    DynLearner::new(4, InputLayout::DEFAULT, params, &wq).unwrap()
}

/// Steps both learners through `ps`, asserting the same step, states per phase, weights,
/// inputs and outputs each time.
fn same_from_here(a: &mut Arena, b: &mut Arena, ps: &[[u8; 4]]) -> Result<(), TestCaseError> {
    for (k, p) in ps.iter().enumerate() {
        let (mut ma, mut mb) = (H8Meter::new(), H8Meter::new());
        prop_assert_eq!(a.step(p, &mut ma), b.step(p, &mut mb), "step {}", k);
        prop_assert_eq!(ma.phase_states(), mb.phase_states(), "step {}", k);
        prop_assert_eq!(a.network(), b.network(), "step {}", k);
        prop_assert_eq!(a.inputs(), b.inputs(), "step {}", k);
        prop_assert_eq!(a.outputs(), b.outputs(), "step {}", k);
    }
    Ok(())
}

fn same_from_here_dyn(
    a: &mut DynLearner,
    b: &mut DynLearner,
    ps: &[[u8; 4]],
) -> Result<(), TestCaseError> {
    for (k, p) in ps.iter().enumerate() {
        let (mut ma, mut mb) = (H8Meter::new(), H8Meter::new());
        prop_assert_eq!(a.step(p, &mut ma), b.step(p, &mut mb), "step {}", k);
        prop_assert_eq!(ma.phase_states(), mb.phase_states(), "step {}", k);
        prop_assert_eq!(a.weights(), b.weights(), "step {}", k);
        prop_assert_eq!(a.inputs(), b.inputs(), "step {}", k);
        prop_assert_eq!(a.outputs(), b.outputs(), "step {}", k);
    }
    Ok(())
}

/// The first step after a restart: no update, E = 0, and `started` only after it.
fn first_step_is_fresh(out: &StepOut) -> Result<(), TestCaseError> {
    prop_assert_eq!(
        out.update,
        None,
        "a restarted learner has nothing to evaluate yet"
    );
    prop_assert_eq!(out.e, 0);
    Ok(())
}

fn weight() -> impl Strategy<Value = i16> {
    prop_oneof![4 => any::<i16>(), 1 => Just(i16::MAX), 1 => Just(i16::MIN), 2 => -4096i16..=4096]
}

fn params() -> impl Strategy<Value = Params> {
    (
        prop_oneof![Just(33), Just(3277), Just(32767), 1..=32767],
        prop_oneof![Just(10), Just(0), 0..=200],
    )
        .prop_map(|(eta, t)| Params::new(eta, t).unwrap())
}

fn proximities() -> impl Strategy<Value = Vec<[u8; 4]>> {
    prop::collection::vec(
        prop_oneof![
            4 => prop::array::uniform4(any::<u8>()),
            1 => Just([0u8; 4]),
            1 => Just([255u8; 4]),
        ],
        1..24,
    )
}

proptest! {
    #![proptest_config(Config::with_cases(common::cases()))]

    /// A learner restarted after any run applies no update on its first step and from then on
    /// is step for step (and state for state) the learner built fresh on its weights.
    #[test]
    fn a_restarted_learner_starts_afresh_on_its_weights(
        w in prop::collection::vec(weight(), 52),
        params in params(),
        before in proximities(),
        after in proximities(),
    ) {
        // The static learner.
        let mut a = arena(&w, params);
        for p in &before {
            a.step(p, &mut NoopMeter);
        }
        prop_assert!(a.started());
        a.restart();
        prop_assert!(!a.started());
        prop_assert!(a.inputs().iter().all(|q| q.to_bits() == 0));
        prop_assert!(a.outputs().iter().all(|q| q.to_bits() == 0));
        let mut fresh = Arena::new(a.network().clone(), params, InputLayout::DEFAULT).unwrap();
        let mut probe = a.clone();
        first_step_is_fresh(&probe.step(&after[0], &mut NoopMeter))?;
        prop_assert!(probe.started());
        same_from_here(&mut a, &mut fresh, &after)?;

        // The same with the runtime-shaped learner.
        let mut b = dynamic(&w, params);
        for p in &before {
            b.step(p, &mut NoopMeter);
        }
        b.restart();
        prop_assert!(b.inputs().iter().all(|q| q.to_bits() == 0));
        prop_assert!(b.outputs().iter().all(|q| q.to_bits() == 0));
        let mut fresh = DynLearner::new(4, InputLayout::DEFAULT, params, b.weights()).unwrap();
        let mut probe = b.clone();
        first_step_is_fresh(&probe.step(&after[0], &mut NoopMeter))?;
        same_from_here_dyn(&mut b, &mut fresh, &after)?;
    }

    /// Weights and parameters written at any point of a run and restored after a reboot into a
    /// learner that had others give the same next steps as the run that wrote them.
    #[test]
    fn a_restored_record_gives_the_same_next_steps(
        w in prop::collection::vec(weight(), 52),
        other in prop::collection::vec(weight(), 52),
        (params, other_params) in (params(), params()),
        before in proximities(),
        after in proximities(),
    ) {
        let mut writer = arena(&w, params);
        for p in &before {
            writer.step(p, &mut NoopMeter);
        }
        // The record, then the reboot.
        let (record_net, record_params) = (writer.network().clone(), writer.params());
        writer.restart();
        let mut restored = arena(&other, other_params);
        restored.set_network(record_net.clone());
        restored.set_params(record_params);
        prop_assert_eq!(restored.network(), &record_net);
        prop_assert_eq!(restored.params(), record_params);
        same_from_here(&mut writer, &mut restored, &after)?;

        let mut writer = dynamic(&w, params);
        for p in &before {
            writer.step(p, &mut NoopMeter);
        }
        let (record_w, record_params) = (writer.weights().to_vec(), writer.params());
        writer.restart();
        let mut restored = dynamic(&other, other_params);
        prop_assert_eq!(restored.set_weights(&record_w), Ok(()));
        restored.set_params(record_params);
        prop_assert_eq!(restored.weights(), record_w.as_slice());
        prop_assert_eq!(restored.params(), record_params);
        same_from_here_dyn(&mut writer, &mut restored, &after)?;
    }

    /// A restore with the wrong number of weights is refused with the lengths named, and the
    /// learner goes on exactly as if it had not been asked.
    #[test]
    fn a_refused_restore_leaves_the_learner_as_it_was(
        w in prop::collection::vec(weight(), 52),
        before in proximities(),
        after in proximities(),
        len in prop_oneof![Just(0usize), Just(51), Just(53), Just(104), 0usize..=1100],
        fill in weight(),
    ) {
        prop_assume!(len != 52);
        let mut a = dynamic(&w, Params::CORRIDOR);
        for p in &before {
            a.step(p, &mut NoopMeter);
        }
        let mut untouched = a.clone();
        let wrong = vec![Q15::from_bits(fill); len];
        prop_assert_eq!(
            a.set_weights(&wrong),
            Err(ShapeError::Length { what: "weights", expected: 52, got: len })
        );
        prop_assert_eq!(a.weights(), untouched.weights());
        prop_assert_eq!(a.inputs(), untouched.inputs());
        prop_assert_eq!(a.outputs(), untouched.outputs());
        prop_assert_eq!(a.params(), untouched.params());
        same_from_here_dyn(&mut a, &mut untouched, &after)?;
    }

    /// η = 0 freezes the weights bit for bit, whatever the evaluations (the updates still run
    /// and are still classified), on both learners.
    #[test]
    fn eta_zero_freezes_the_weights_bit_for_bit(
        w in prop::collection::vec(weight(), 52),
        t in prop_oneof![Just(0), Just(10), 0..=1020],
        before in proximities(),
        after in proximities(),
    ) {
        let frozen = Params::new(0, t).unwrap();
        let mut a = arena(&w, Params::CORRIDOR);
        let mut b = dynamic(&w, Params::CORRIDOR);
        for p in &before {
            a.step(p, &mut NoopMeter);
            b.step(p, &mut NoopMeter);
        }
        a.set_params(frozen);
        b.set_params(frozen);
        prop_assert_eq!(a.params(), frozen);
        prop_assert_eq!(b.params(), frozen);
        let (wa, wb) = (a.network().clone(), b.weights().to_vec());
        for p in &after {
            a.step(p, &mut NoopMeter);
            b.step(p, &mut NoopMeter);
            prop_assert_eq!(a.network(), &wa);
            prop_assert_eq!(b.weights(), wb.as_slice());
        }
    }
}

/// The properties above must not pass for want of anything to restore: on this walk, a
/// learner that is not restarted, not restored or not frozen does differ.
#[test]
fn the_restart_and_restore_checks_have_something_to_catch() {
    let w = spread_weights(52, 4);
    let ps = walk(40, 0);
    let more = walk(40, 17);

    // Not restarted: the first step evaluates the stale D(t−1) and updates.
    let mut a = arena(&w, Params::CORRIDOR);
    for p in &ps {
        a.step(p, &mut NoopMeter);
    }
    let mut stale = a.clone();
    assert!(stale.step(&more[0], &mut NoopMeter).update.is_some());
    a.restart();
    assert_eq!(a.step(&more[0], &mut NoopMeter).update, None);

    // Restored weights without the parameters (or the reverse) go another way.
    let mut writer = arena(&w, Params::CORRIDOR);
    for p in &ps {
        writer.step(p, &mut NoopMeter);
    }
    writer.restart();
    let mut weights_only = arena(&spread_weights(52, 2), Params::ARENA);
    weights_only.set_network(writer.network().clone());
    let mut params_only = arena(&spread_weights(52, 2), Params::ARENA);
    params_only.set_params(writer.params());
    let mut both = arena(&spread_weights(52, 2), Params::ARENA);
    both.set_network(writer.network().clone());
    both.set_params(writer.params());
    let diverges = |mut x: Arena, mut y: Arena| {
        more.iter().any(|p| {
            x.step(p, &mut NoopMeter) != y.step(p, &mut NoopMeter) || x.network() != y.network()
        })
    };
    assert!(
        diverges(writer.clone(), weights_only),
        "η matters on this walk"
    );
    assert!(
        diverges(writer.clone(), params_only),
        "the weights matter on this walk"
    );
    assert!(
        !diverges(writer, both),
        "weights and η are the whole record"
    );

    // Not frozen: the weights move on this walk.
    let mut moving = arena(&w, Params::CORRIDOR);
    let before = moving.network().clone();
    for p in &more {
        moving.step(p, &mut NoopMeter);
    }
    assert_ne!(moving.network(), &before);
}

/// `set_network` and `set_weights` keep the carried state: the next step updates the restored
/// weights with the input, winner and D(t−1) carried over.
#[test]
fn a_restore_keeps_the_carried_state() {
    let w = spread_weights(52, 4);
    let other = spread_weights(52, 3);
    let ps = walk(12, 3);
    let mut a = arena(&w, Params::CORRIDOR);
    let mut last = None;
    for p in &ps {
        last = Some(a.step(p, &mut NoopMeter));
    }
    let last = last.unwrap();
    let (x, o) = (*a.inputs(), *a.outputs());
    a.set_network(net13x4(&other));
    assert!(a.started());
    assert_eq!(a.inputs(), &x);
    assert_eq!(a.outputs(), &o);
    let p = [250, 250, 250, 250];
    let out = a.step(&p, &mut NoopMeter);
    let e = 1000 - last.d;
    assert_eq!(out.e, e);
    let mut want = other.clone();
    let xb: Vec<i8> = x.iter().map(|q| q.to_bits()).collect();
    let kind = common::update(&mut want, &xb, last.forward.win(), e, 3277, 10);
    assert!(kind.is_some(), "the walk ends with an update to check");
    assert_eq!(bits(a.network().weights_flat()), want);

    let mut b = dynamic(&w, Params::CORRIDOR);
    for p in &ps {
        b.step(p, &mut NoopMeter);
    }
    let oq: Vec<Q15> = other.iter().map(|&v| Q15::from_bits(v)).collect();
    b.set_weights(&oq).unwrap();
    assert_eq!(
        b.inputs().iter().map(|q| q.to_bits()).collect::<Vec<_>>(),
        xb
    );
    b.step(&p, &mut NoopMeter);
    assert_eq!(bits(b.weights()), want);
}

#[test]
fn the_largest_shape_works_and_one_input_more_is_refused() {
    assert_eq!(MAX_WEIGHTS, 256 * 4, "256 inputs by 4 behaviours");
    // H = 8 and the bias make 42 inputs for 4 behaviours; 214 spare make 256.
    let layout = InputLayout::new(8, true).unwrap().with_spare(214);
    assert_eq!(layout.n_inputs(4), 256);
    let w: Vec<Q15> = spread_weights(MAX_WEIGHTS, 8)
        .into_iter()
        .map(Q15::from_bits)
        .collect();
    let mut big = DynLearner::new(4, layout, Params::CORRIDOR, &w).expect("256 x 4 fits");
    assert_eq!(big.shape().n_weights(), MAX_WEIGHTS);
    assert_eq!(big.weights(), w.as_slice());
    let mut meter = H8Meter::new();
    let mut updates = 0;
    for p in walk(30, 5) {
        updates += usize::from(big.step(&p, &mut meter).update.is_some());
    }
    assert_eq!(updates, 29);
    assert_ne!(big.weights(), w.as_slice(), "it learns");
    assert_eq!(big.set_weights(&w), Ok(()));
    assert_eq!(big.weights(), w.as_slice());
    // The static learner of the same shape computes the same.
    let rows: [[Q15; 256]; 4] = core::array::from_fn(|j| core::array::from_fn(|i| w[j * 256 + i]));
    let mut fixed = Learner::<256, 4>::new(Network::new(rows), Params::CORRIDOR, layout).unwrap();
    let mut again = DynLearner::new(4, layout, Params::CORRIDOR, &w).unwrap();
    for p in walk(10, 9) {
        assert_eq!(
            fixed.step(&p, &mut NoopMeter),
            again.step(&p, &mut NoopMeter)
        );
    }

    // One input more, a fifth behaviour, one weight more or less: refused, with the reason.
    assert_eq!(
        DynLearner::new(4, layout.with_spare(215), Params::CORRIDOR, &w).unwrap_err(),
        ShapeError::Inputs { got: 257 }
    );
    let small = InputLayout::DEFAULT;
    assert_eq!(
        DynLearner::new(5, small, Params::CORRIDOR, &[Q15::ZERO; 14 * 5]).unwrap_err(),
        ShapeError::Behaviours { got: 5 }
    );
    let mut longer = w.clone();
    longer.push(Q15::ZERO);
    assert_eq!(
        DynLearner::new(4, layout, Params::CORRIDOR, &longer).unwrap_err(),
        ShapeError::Length {
            what: "weights",
            expected: MAX_WEIGHTS,
            got: MAX_WEIGHTS + 1
        }
    );
    assert_eq!(
        DynLearner::new(4, layout, Params::CORRIDOR, &w[1..]).unwrap_err(),
        ShapeError::Length {
            what: "weights",
            expected: MAX_WEIGHTS,
            got: MAX_WEIGHTS - 1
        }
    );
}

#[test]
fn parameters_read_back_as_given() {
    for (eta, t) in [
        (0, 0),
        (33, 10),
        (3277, 10),
        (32767, 32767),
        (1, 1),
        (200, 1020),
    ] {
        let p = Params::new(eta, t).unwrap();
        assert_eq!(i32::from(p.eta().to_bits()), eta);
        assert_eq!(i32::from(p.threshold()), t);
    }
    assert_eq!(Params::ARENA.threshold(), 10);
    assert_eq!(Params::ARENA.eta().to_bits(), 33);
    assert_eq!(Params::CORRIDOR.threshold(), 10);
    assert_eq!(Params::CORRIDOR.eta().to_bits(), 3277);
    let mut l = arena(&[0; 52], Params::ARENA);
    assert_eq!(l.params(), Params::ARENA);
    l.set_params(Params::CORRIDOR);
    assert_eq!(l.params(), Params::CORRIDOR);
    let mut d = dynamic(&[0; 52], Params::ARENA);
    d.set_params(Params::CORRIDOR);
    assert_eq!(d.params(), Params::CORRIDOR);
    // The behaviours a learner maps its outputs to.
    let l = l.with_behaviours([
        Behaviour::TurnRightForward,
        Behaviour::TurnLeftForward,
        Behaviour::Backward,
        Behaviour::Forward,
    ]);
    let mut l = l;
    let out = l.step(&[100, 100, 100, 100], &mut NoopMeter);
    assert_eq!(out.forward.win(), 0, "all-zero weights: output 0 wins");
    assert_eq!(out.behaviour, Behaviour::TurnRightForward);
}
