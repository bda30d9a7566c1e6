//! The crate's public surface read back: accessors, names, error messages, RAM accounting — what
//! a user of the crate alone relies on besides the learning rule and the meter.

use nn_q15::learner::align2;
use nn_q15::{
    Behaviour, ConfigError, DynLearner, InputLayout, Learner, Network, NoopMeter, ParamError,
    Params, Q7, Q15, Q22, Shape, ShapeError, forward_slice, ram_bytes, ram_items,
};

#[test]
fn errors_say_what_was_wrong_and_what_is_valid() {
    let cases: [(Box<dyn std::error::Error>, &str); 10] = [
        (
            Box::new(ShapeError::Inputs { got: 257 }),
            "257 inputs is outside the no-overflow bound: valid is 1 to 256",
        ),
        (
            Box::new(ShapeError::Outputs { got: 9 }),
            "9 outputs: valid is 2 to 8",
        ),
        (
            Box::new(ShapeError::Behaviours { got: 5 }),
            "5 outputs: a learner that drives the robot has one per enabled behaviour, 2 to 4",
        ),
        (
            Box::new(ShapeError::Length {
                what: "weights",
                expected: 52,
                got: 51,
            }),
            "weights has 51 values, the shape needs 52",
        ),
        (
            Box::new(ShapeError::Winner { got: 4, n_out: 4 }),
            "winner 4 is not an output: valid is 0 to 3",
        ),
        (
            Box::new(ParamError::Eta { got: -1 }),
            "learning rate eta = -1 is out of range: valid is 0 to 32767 (Q15, 0.1 = 3277)",
        ),
        (
            Box::new(ParamError::Threshold { got: 40000 }),
            "threshold T = 40000 is out of range: valid is 0 to 32767 (distance units)",
        ),
        (
            Box::new(ConfigError::History { got: 9 }),
            "history depth 9 is out of range: valid is 0 to 8",
        ),
        (
            Box::new(ConfigError::Inputs {
                layout: 13,
                network: 12,
            }),
            "the input layout makes 13 inputs but the network has 12",
        ),
        (
            Box::new(Shape::new(3, 1).unwrap_err()),
            "1 outputs: valid is 2 to 8",
        ),
    ];
    for (err, text) in cases {
        assert_eq!(err.to_string(), text);
    }
    assert_eq!(Params::new(-1, 10), Err(ParamError::Eta { got: -1 }));
    assert_eq!(Params::new(32768, 10), Err(ParamError::Eta { got: 32768 }));
    assert_eq!(
        Params::new(3277, -1),
        Err(ParamError::Threshold { got: -1 })
    );
    assert_eq!(
        Params::new(3277, 32768),
        Err(ParamError::Threshold { got: 32768 })
    );
}

#[test]
fn behaviours_and_layouts_read_back() {
    assert_eq!(
        Behaviour::ALL.map(Behaviour::name),
        [
            "forward",
            "backward",
            "turn-left-forward",
            "turn-right-forward"
        ]
    );
    let l = InputLayout::new(3, true).unwrap().with_spare(5);
    assert_eq!((l.history(), l.bias(), l.spare()), (3, true, 5));
    // 4 · (1 + 3) + 2 outputs + E + bias + 5 spare.
    assert_eq!(l.n_inputs(2), 16 + 2 + 1 + 1 + 5);
    assert_eq!(l.outputs_at(), 16);
    let d = InputLayout::default();
    assert_eq!(d, InputLayout::DEFAULT);
    assert_eq!((d.history(), d.bias(), d.spare()), (1, false, 0));
    assert_eq!(d.outputs_at(), 8);
    assert_eq!(InputLayout::new(0, false).unwrap().n_inputs(3), 8);
    assert_eq!(InputLayout::new(0, false).unwrap().outputs_at(), 4);
}

#[test]
fn shapes_and_forward_outputs_read_back() {
    let s = Shape::new(7, 3).unwrap();
    assert_eq!((s.n_in(), s.n_out(), s.n_weights()), (7, 3, 21));
    assert_eq!(Network::<5, 2>::SHAPE, Shape::new(5, 2).unwrap());
    // y = [2·100 − 3·50, −(2·100)] = [50, −200] below 1.0: O = y >> 7.
    let net = Network::<2, 2>::from_bits([[2, -3], [-2, 0]]);
    let f = net.forward(&[Q7::from_bits(100), Q7::from_bits(50)], &mut NoopMeter);
    assert_eq!(f.y_bits(), &[50, -200]);
    assert_eq!(f.y(0), Some(Q22::from_bits(50)));
    assert_eq!(f.y(1), Some(Q22::from_bits(-200)));
    assert_eq!(f.y(2), None);
    assert_eq!(f.o_bits(), &[0, -2]);
    assert_eq!(f.o(1), Some(Q15::from_bits(-2)));
    assert_eq!(f.o(2), None);
    assert_eq!(f.win(), 0);
    let w = [
        Q15::from_bits(2),
        Q15::from_bits(-3),
        Q15::from_bits(-2),
        Q15::ZERO,
    ];
    assert_eq!(net.weights_flat(), &w);
    assert_eq!(net.weights()[1], [Q15::from_bits(-2), Q15::ZERO]);
    assert_eq!(
        forward_slice(
            Shape::new(2, 2).unwrap(),
            &w,
            &[Q7::from_bits(100), Q7::from_bits(50)],
            &mut NoopMeter
        ),
        Ok(f)
    );
    assert!(
        Network::<3, 2>::zeroed()
            .weights_flat()
            .iter()
            .all(|q| *q == Q15::ZERO)
    );
    let mut net = net;
    assert_eq!(
        net.update(&[Q7::ZERO; 2], 2, 100, Params::ARENA, &mut NoopMeter),
        Err(ShapeError::Winner { got: 2, n_out: 2 })
    );
}

#[test]
fn learners_read_back_their_configuration() {
    let layout = InputLayout::new(2, true).unwrap();
    let net = Network::<16, 2>::from_bits([[7; 16], [-7; 16]]);
    let l = Learner::<16, 2>::new(net.clone(), Params::CORRIDOR, layout).unwrap();
    assert_eq!(l.layout(), layout);
    assert_eq!(l.network(), &net);
    assert_eq!(l.params(), Params::CORRIDOR);
    assert!(!l.started());
    let d = DynLearner::new(2, layout, Params::ARENA, net.weights_flat()).unwrap();
    assert_eq!(d.layout(), layout);
    assert_eq!(d.shape(), Shape::new(16, 2).unwrap());
    assert_eq!(d.params(), Params::ARENA);
    assert_eq!(d.weights(), net.weights_flat());
    assert_eq!(d.inputs().len(), 16);
    assert_eq!(d.outputs().len(), 2);
    assert_eq!(d.ram_items(), Learner::<16, 2>::RAM_ITEMS);
    assert_eq!(d.ram_bytes(), Learner::<16, 2>::RAM_BYTES);
}

#[test]
fn ram_is_itemised_with_the_h8_sizes() {
    // 11 × 2 (the corridor): 44 weights bytes, x 11 → 12, Δ 22, y 8, O 4, η and T 4, state 4.
    let items = ram_items(11, 2);
    assert_eq!(
        items.map(|i| i.bytes),
        [44, 12, 22, 8, 4, 4, 4],
        "{items:?}"
    );
    assert_eq!(ram_bytes(11, 2), 98);
    assert_eq!(ram_bytes(256, 4), 2048 + 256 + 512 + 16 + 8 + 4 + 4);
    assert_eq!(items[0].name, "weights w (i16, N x M)");
    assert!(items.iter().all(|i| !i.name.is_empty()));
    assert_eq!([0, 1, 2, 3, 13].map(align2), [0, 2, 2, 4, 14]);
}
