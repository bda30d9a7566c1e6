//! The learner as the robot runs it: one call per step (docs/design.md §3.5), and its RAM footprint on the
//! H8/3052F.
//!
//! A step at time t, given the proximities p(t):
//! 1. `D(t) = Σ_k p_k(t)` and, from the second step on, `E(t−1) = D(t) − D(t−1)`;
//! 2. the update of docs/design.md §2.4 with E(t−1) on x(t−1) and its winner;
//! 3. the input vector x(t) of docs/design.md §2.2;
//! 4. the forward pass of docs/design.md §2.3 on x(t), whose winner picks the behaviour.

use crate::cost::{Meter, Op, Phase};
use crate::error::{ConfigError, ShapeError};
use crate::format::{Q7, Q15, evaluation_to_q7, output_to_q7, proximity_to_q7};
use crate::input::{InputLayout, SENSORS};
use crate::limits::{MAX_BEHAVIOURS, MAX_INPUTS};
use crate::net::{ForwardOut, Network, Params, Shape, UpdateKind, forward_core, update_core};

/// The four primitive behaviours (docs/design.md §2.3 step 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Behaviour {
    /// Both wheels forward at v.
    Forward = 0,
    /// Both wheels backward at v.
    Backward = 1,
    /// Left wheel at 0.3 v, right wheel at v.
    TurnLeftForward = 2,
    /// Left wheel at v, right wheel at 0.3 v.
    TurnRightForward = 3,
}

impl Behaviour {
    /// All four behaviours in the paper's order: output j maps to `ALL[j]` by default, so the
    /// corridor's two outputs are forward and backward.
    pub const ALL: [Behaviour; 4] = [
        Behaviour::Forward,
        Behaviour::Backward,
        Behaviour::TurnLeftForward,
        Behaviour::TurnRightForward,
    ];

    /// A short lower-case name.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Behaviour::Forward => "forward",
            Behaviour::Backward => "backward",
            Behaviour::TurnLeftForward => "turn-left-forward",
            Behaviour::TurnRightForward => "turn-right-forward",
        }
    }
}

/// What one step did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepOut {
    /// The behaviour to run until the next step.
    pub behaviour: Behaviour,
    /// The forward pass on x(t).
    pub forward: ForwardOut,
    /// D(t), the summed proximities.
    pub d: i16,
    /// E(t−1) = D(t) − D(t−1); 0 at the first step.
    pub e: i16,
    /// The update with E(t−1), or `None` at the first step (nothing to evaluate yet).
    pub update: Option<UpdateKind>,
}

/// One item of the learner's RAM on the H8: a name and its size in bytes (i8 = 1, i16 = 2,
/// i32 = 4; every item starts on an even address, so odd sizes are padded to even).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RamItem {
    /// What the item holds.
    pub name: &'static str,
    /// Its size in bytes, padded to even.
    pub bytes: u32,
}

/// Rounds a byte count up to the H8's word alignment (2).
#[must_use]
pub const fn align2(bytes: u32) -> u32 {
    (bytes + 1) & !1
}

/// The learner's RAM items on the H8 for N inputs and M outputs, in placement order.
#[must_use]
pub const fn ram_items(n_in: usize, n_out: usize) -> [RamItem; 7] {
    let (n, m) = (n_in as u32, n_out as u32);
    [
        RamItem {
            name: "weights w (i16, N x M)",
            bytes: 2 * n * m,
        },
        RamItem {
            name: "input vector x (i8, N)",
            bytes: align2(n),
        },
        RamItem {
            name: "update deltas (i16, N)",
            bytes: 2 * n,
        },
        RamItem {
            name: "sums y (i32, M)",
            bytes: 4 * m,
        },
        RamItem {
            name: "outputs O (i16, M)",
            bytes: 2 * m,
        },
        RamItem {
            name: "eta, T (i16 each)",
            bytes: 4,
        },
        RamItem {
            name: "D(t-1) (i16), winner and started flag (u8 each)",
            bytes: 4,
        },
    ]
}

/// The learner's RAM footprint on the H8 in bytes for N inputs and M outputs: the sum of
/// [`ram_items`].
#[must_use]
pub const fn ram_bytes(n_in: usize, n_out: usize) -> u32 {
    let items = ram_items(n_in, n_out);
    let mut total = 0;
    let mut i = 0;
    while i < items.len() {
        total += items[i].bytes;
        i += 1;
    }
    total
}

/// The state a learner carries from one step to the next besides its vectors.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Carried {
    win: u8,
    d_prev: i16,
    started: bool,
}

/// The vectors one step works on, borrowed from whichever learner owns them.
struct StepData<'a> {
    w: &'a mut [Q15],
    x: &'a mut [Q7],
    o: &'a mut [Q15],
    delta: &'a mut [i16],
}

/// One step (docs/design.md §3.5) on borrowed storage: shared by [`Learner`] and [`DynLearner`].
#[inline]
fn step_core<Mt: Meter>(
    data: StepData<'_>,
    carried: &mut Carried,
    layout: InputLayout,
    params: Params,
    p: &[u8; SENSORS],
    meter: &mut Mt,
) -> (ForwardOut, i16, i16, Option<UpdateKind>) {
    let StepData { w, x, o, delta } = data;
    let n_out = o.len();
    // The blocks of the firmware's `learner_step` (see `crate::cost`); its calls of
    // `learner_update` and `learner_forward` (the JSRs) are part of this phase.
    meter.enter(Phase::Input);

    // 1. D(t), E(t−1). D ≤ 4 · 255 = 1020 and |E| ≤ 1020: both fit an i16.
    let d = p.iter().map(|&v| i16::from(v)).sum::<i16>();
    meter.charge(Op::InEntry, 1);
    meter.charge(Op::InStartedTest, 1);
    let e = if carried.started {
        meter.charge(Op::InEval, 1);
        d - carried.d_prev
    } else {
        0
    };

    // 2. The update on the previous input and winner.
    let update = if carried.started {
        Some(update_core(
            w,
            x,
            usize::from(carried.win),
            e,
            params,
            delta,
            meter,
        ))
    } else {
        None
    };

    // 3. x(t): history one block deeper, the new readings, past outputs, E, bias.
    meter.enter(Phase::Input);
    meter.charge(Op::InHistoryTest, 1);
    let h = layout.history();
    if h > 0 {
        x.copy_within(0..SENSORS * h, SENSORS);
        meter.charge(Op::InHistorySetup, 1);
        meter.charge(Op::InHistoryByte, (SENSORS * h) as u32);
    }
    for (xk, &pk) in x.iter_mut().zip(p) {
        *xk = Q7::from_bits(proximity_to_q7(pk));
    }
    meter.charge(Op::InReadings, 1);
    let at = layout.outputs_at();
    for (xj, oj) in x[at..at + n_out].iter_mut().zip(o.iter()) {
        *xj = Q7::from_bits(output_to_q7(oj.to_bits()));
    }
    meter.charge(Op::InOutputsSetup, 1);
    meter.charge(Op::InOutput, n_out as u32);
    let e_in = evaluation_to_q7(e);
    x[at + n_out] = Q7::from_bits(e_in);
    meter.charge(Op::InEvalScale, 1);
    if Mt::ACTIVE {
        // |E| ≤ 1020 keeps E >> 3 in −128 … 127; the clamps are there for any i16.
        let e3 = e >> 3;
        if e3 > 127 {
            meter.charge(Op::InEvalHigh, 1);
        } else {
            meter.charge(Op::InEvalLowTest, 1);
            meter.charge(Op::InEvalLow, u32::from(e3 < -128));
        }
    }
    meter.charge(Op::InEvalStore, 1);
    if layout.bias() {
        x[at + n_out + 1] = Q7::from_bits(i8::MAX);
        meter.charge(Op::InBias, 1);
    }
    meter.charge(Op::InForwardCall, 1);

    // 4. The forward pass picks the behaviour.
    let forward = forward_core(w, x, n_out, meter);
    meter.enter(Phase::Input);
    meter.charge(Op::InExit, 1);
    for (oj, &bits) in o.iter_mut().zip(forward.o_bits()) {
        *oj = Q15::from_bits(bits);
    }
    carried.win = forward.win() as u8;
    carried.d_prev = d;
    carried.started = true;
    (forward, d, e, update)
}

fn default_behaviours<const M: usize>() -> [Behaviour; M] {
    let mut behaviours = [Behaviour::Forward; M];
    for (b, a) in behaviours.iter_mut().zip(Behaviour::ALL) {
        *b = a;
    }
    behaviours
}

/// The continuously learning controller with its shape fixed at compile time: the network, its
/// parameters and the state it carries from step to step.
#[derive(Clone, Debug)]
pub struct Learner<const N: usize, const M: usize> {
    net: Network<N, M>,
    params: Params,
    layout: InputLayout,
    behaviours: [Behaviour; M],
    x: [Q7; N],
    o: [Q15; M],
    carried: Carried,
}

impl<const N: usize, const M: usize> Learner<N, M> {
    /// The learner's RAM items on the H8, in placement order.
    pub const RAM_ITEMS: [RamItem; 7] = ram_items(N, M);

    /// The learner's RAM footprint on the H8 in bytes: the sum of [`Self::RAM_ITEMS`].
    pub const RAM_BYTES: u32 = ram_bytes(N, M);

    /// M is at most [`MAX_BEHAVIOURS`] (one output per behaviour), checked at compile time.
    const BEHAVIOURS_OK: () = assert!(
        M <= MAX_BEHAVIOURS,
        "a learner that drives the robot has at most 4 outputs, one per behaviour"
    );

    /// A learner starting from `net` (weights as initialised), with `params` and the input
    /// `layout`; output j runs behaviour `Behaviour::ALL[j]`.
    ///
    /// # Errors
    /// [`ConfigError::Inputs`] when the layout does not make exactly N inputs for M outputs.
    pub fn new(
        net: Network<N, M>,
        params: Params,
        layout: InputLayout,
    ) -> Result<Self, ConfigError> {
        let () = Self::BEHAVIOURS_OK;
        let needed = layout.n_inputs(M);
        if needed != N {
            return Err(ConfigError::Inputs {
                layout: needed,
                network: N,
            });
        }
        Ok(Self {
            net,
            params,
            layout,
            behaviours: default_behaviours(),
            x: [Q7::ZERO; N],
            o: [Q15::ZERO; M],
            carried: Carried::default(),
        })
    }

    /// Maps output j to `behaviours[j]` instead of the default order.
    #[must_use]
    pub fn with_behaviours(mut self, behaviours: [Behaviour; M]) -> Self {
        self.behaviours = behaviours;
        self
    }

    /// The network.
    #[must_use]
    pub const fn network(&self) -> &Network<N, M> {
        &self.net
    }

    /// The learning parameters.
    #[must_use]
    pub const fn params(&self) -> Params {
        self.params
    }

    /// Changes the learning parameters (for instance η = 0 to freeze learning).
    pub fn set_params(&mut self, params: Params) {
        self.params = params;
    }

    /// The input layout.
    #[must_use]
    pub const fn layout(&self) -> InputLayout {
        self.layout
    }

    /// The input vector of the last step.
    #[must_use]
    pub const fn inputs(&self) -> &[Q7; N] {
        &self.x
    }

    /// The outputs of the last step.
    #[must_use]
    pub const fn outputs(&self) -> &[Q15; M] {
        &self.o
    }

    /// Whether a step has run since construction (or [`Self::restart`]).
    #[must_use]
    pub const fn started(&self) -> bool {
        self.carried.started
    }

    /// Forgets the carried state (inputs, outputs, D, the started flag) but keeps the weights:
    /// what a reboot that restored the weights from EEPROM leaves.
    pub fn restart(&mut self) {
        self.x = [Q7::ZERO; N];
        self.o = [Q15::ZERO; M];
        self.carried = Carried::default();
    }

    /// Replaces the weights (restored from a record, say), keeping the carried state.
    pub fn set_network(&mut self, net: Network<N, M>) {
        self.net = net;
    }

    /// One step with the proximities `p` (du) read after the last behaviour.
    pub fn step<Mt: Meter>(&mut self, p: &[u8; SENSORS], meter: &mut Mt) -> StepOut {
        let mut delta = [0i16; N];
        let data = StepData {
            w: self.net.weights_flat_mut(),
            x: &mut self.x,
            o: &mut self.o,
            delta: &mut delta,
        };
        let (forward, d, e, update) =
            step_core(data, &mut self.carried, self.layout, self.params, p, meter);
        StepOut {
            behaviour: self.behaviours[forward.win()],
            forward,
            d,
            e,
            update,
        }
    }
}

/// Capacity of a [`DynLearner`]'s weight storage: the largest network, 256 × 4.
pub const MAX_WEIGHTS: usize = MAX_INPUTS * MAX_BEHAVIOURS;

/// The same learner with its shape chosen at run time (within the bounds of [`Shape`]), for
/// what-if studies and the emulated controller. Storage is `heapless` at the largest shape, so
/// it never allocates; it computes bit for bit what [`Learner`] computes.
#[derive(Clone, Debug)]
pub struct DynLearner {
    shape: Shape,
    params: Params,
    layout: InputLayout,
    behaviours: heapless::Vec<Behaviour, MAX_BEHAVIOURS>,
    w: heapless::Vec<Q15, MAX_WEIGHTS>,
    x: heapless::Vec<Q7, MAX_INPUTS>,
    o: heapless::Vec<Q15, MAX_BEHAVIOURS>,
    carried: Carried,
}

impl DynLearner {
    /// A learner for `n_out` behaviours with the input `layout`, starting from `weights`
    /// (row-major, one row of N per output).
    ///
    /// # Errors
    /// [`ShapeError`] when N or M is out of range or `weights` has the wrong length.
    pub fn new(
        n_out: usize,
        layout: InputLayout,
        params: Params,
        weights: &[Q15],
    ) -> Result<Self, ShapeError> {
        let shape = Shape::new(layout.n_inputs(n_out), n_out)?;
        if n_out > MAX_BEHAVIOURS {
            return Err(ShapeError::Behaviours { got: n_out });
        }
        if weights.len() != shape.n_weights() {
            return Err(ShapeError::Length {
                what: "weights",
                expected: shape.n_weights(),
                got: weights.len(),
            });
        }
        let mut behaviours = heapless::Vec::new();
        let mut w = heapless::Vec::new();
        let mut x = heapless::Vec::new();
        let mut o = heapless::Vec::new();
        // Every length below was checked against the capacities by `Shape::new`.
        let filled = behaviours
            .extend_from_slice(&Behaviour::ALL[..n_out])
            .and(w.extend_from_slice(weights))
            .and(x.resize(shape.n_in(), Q7::ZERO))
            .and(o.resize(n_out, Q15::ZERO));
        if filled.is_err() {
            return Err(ShapeError::Length {
                what: "weights",
                expected: MAX_WEIGHTS,
                got: weights.len(),
            });
        }
        Ok(Self {
            shape,
            params,
            layout,
            behaviours,
            w,
            x,
            o,
            carried: Carried::default(),
        })
    }

    /// The network shape.
    #[must_use]
    pub const fn shape(&self) -> Shape {
        self.shape
    }

    /// The input layout.
    #[must_use]
    pub const fn layout(&self) -> InputLayout {
        self.layout
    }

    /// The learning parameters.
    #[must_use]
    pub const fn params(&self) -> Params {
        self.params
    }

    /// Changes the learning parameters.
    pub fn set_params(&mut self, params: Params) {
        self.params = params;
    }

    /// The weights, row-major.
    #[must_use]
    pub fn weights(&self) -> &[Q15] {
        &self.w
    }

    /// Replaces the weights (restored from a record, say), keeping the carried state.
    ///
    /// # Errors
    /// [`ShapeError::Length`] when `weights` has the wrong length.
    pub fn set_weights(&mut self, weights: &[Q15]) -> Result<(), ShapeError> {
        if weights.len() != self.w.len() {
            return Err(ShapeError::Length {
                what: "weights",
                expected: self.w.len(),
                got: weights.len(),
            });
        }
        self.w.copy_from_slice(weights);
        Ok(())
    }

    /// The input vector of the last step.
    #[must_use]
    pub fn inputs(&self) -> &[Q7] {
        &self.x
    }

    /// The outputs O of the last forward pass (Q15), one per behaviour.
    #[must_use]
    pub fn outputs(&self) -> &[Q15] {
        &self.o
    }

    /// The learner's RAM items on the H8.
    #[must_use]
    pub const fn ram_items(&self) -> [RamItem; 7] {
        ram_items(self.shape.n_in(), self.shape.n_out())
    }

    /// The learner's RAM footprint on the H8 in bytes.
    #[must_use]
    pub const fn ram_bytes(&self) -> u32 {
        ram_bytes(self.shape.n_in(), self.shape.n_out())
    }

    /// Forgets the carried state but keeps the weights (see [`Learner::restart`]).
    pub fn restart(&mut self) {
        self.x.fill(Q7::ZERO);
        self.o.fill(Q15::ZERO);
        self.carried = Carried::default();
    }

    /// One step with the proximities `p` (du) read after the last behaviour.
    pub fn step<Mt: Meter>(&mut self, p: &[u8; SENSORS], meter: &mut Mt) -> StepOut {
        let mut delta = [0i16; MAX_INPUTS];
        let data = StepData {
            w: &mut self.w,
            x: &mut self.x,
            o: &mut self.o,
            delta: &mut delta,
        };
        let (forward, d, e, update) =
            step_core(data, &mut self.carried, self.layout, self.params, p, meter);
        StepOut {
            behaviour: self.behaviours[forward.win()],
            forward,
            d,
            e,
            update,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cost::{H8Meter, NoopMeter};

    type Arena = Learner<13, 4>;

    #[test]
    fn ram_footprint_of_the_default_learner() {
        // 104 weights + 14 x + 26 deltas + 16 sums + 8 outputs + 4 params + 4 state.
        assert_eq!(Arena::RAM_BYTES, 104 + 14 + 26 + 16 + 8 + 4 + 4);
        assert_eq!(
            Learner::<11, 2>::RAM_ITEMS[1].bytes,
            12,
            "odd N pads to even"
        );
    }

    #[test]
    fn layout_must_match_the_network() {
        let err = Learner::<12, 4>::new(Network::zeroed(), Params::ARENA, InputLayout::DEFAULT)
            .unwrap_err();
        assert_eq!(
            err,
            ConfigError::Inputs {
                layout: 13,
                network: 12
            }
        );
    }

    #[test]
    fn input_vector_follows_spec_2_2() {
        let mut l = Arena::new(Network::zeroed(), Params::ARENA, InputLayout::DEFAULT).unwrap();
        let first = l.step(&[10, 20, 30, 40], &mut NoopMeter);
        assert_eq!(first.update, None);
        assert_eq!(first.e, 0);
        assert_eq!(first.d, 100);
        let bits: [i8; 13] = l.inputs().map(|q| q.to_bits());
        assert_eq!(bits, [-118, -108, -98, -88, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
        let second = l.step(&[200, 200, 200, 200], &mut NoopMeter);
        assert_eq!(second.e, 700);
        assert_eq!(second.update, Some(UpdateKind::Reward));
        let bits: [i8; 13] = l.inputs().map(|q| q.to_bits());
        // current, one step of history, the (zero) outputs of step 1, sat_i8(700 >> 3) = 87.
        assert_eq!(bits, [72, 72, 72, 72, -118, -108, -98, -88, 0, 0, 0, 0, 87]);
    }

    #[test]
    fn deeper_history_shifts_blocks_in_order() {
        let layout = InputLayout::new(2, true).unwrap();
        let mut l = Learner::<16, 2>::new(Network::zeroed(), Params::CORRIDOR, layout).unwrap();
        l.step(&[1, 1, 1, 1], &mut NoopMeter);
        l.step(&[2, 2, 2, 2], &mut NoopMeter);
        l.step(&[3, 3, 3, 3], &mut NoopMeter);
        let bits: [i8; 16] = l.inputs().map(|q| q.to_bits());
        assert_eq!(&bits[0..4], &[-125; 4]);
        assert_eq!(&bits[4..8], &[-126; 4]);
        assert_eq!(&bits[8..12], &[-127; 4]);
        assert_eq!(bits[15], 127, "bias");
    }

    #[test]
    fn dyn_learner_matches_the_static_one_bit_for_bit() {
        let rows = [[1200; 13], [-700; 13], [300; 13], [5; 13]];
        let net = Network::<13, 4>::from_bits(rows);
        let mut a = Arena::new(net.clone(), Params::CORRIDOR, InputLayout::DEFAULT).unwrap();
        let mut b = DynLearner::new(
            4,
            InputLayout::DEFAULT,
            Params::CORRIDOR,
            net.weights_flat(),
        )
        .unwrap();
        let (mut ma, mut mb) = (H8Meter::new(), H8Meter::new());
        for t in 0..200u32 {
            let p = [
                (t * 37 % 256) as u8,
                (t * 11 % 256) as u8,
                (t % 7) as u8,
                (255 - t % 256) as u8,
            ];
            assert_eq!(a.step(&p, &mut ma), b.step(&p, &mut mb), "step {t}");
        }
        assert_eq!(a.network().weights_flat(), b.weights());
        assert_eq!(ma.phase_states(), mb.phase_states());
        assert_eq!(b.ram_bytes(), Arena::RAM_BYTES);
        assert!(DynLearner::new(4, InputLayout::DEFAULT, Params::ARENA, &[Q15::ZERO; 51]).is_err());
    }

    #[test]
    fn metered_and_unmetered_steps_agree_and_phases_are_charged() {
        let net = Network::<13, 4>::from_bits([[1000; 13], [-500; 13], [300; 13], [0; 13]]);
        let mut a = Arena::new(net.clone(), Params::CORRIDOR, InputLayout::DEFAULT).unwrap();
        let mut b = Arena::new(net, Params::CORRIDOR, InputLayout::DEFAULT).unwrap();
        let mut meter = H8Meter::new();
        for t in 0..50u32 {
            let p = [
                (t * 37 % 256) as u8,
                (t * 11 % 256) as u8,
                128,
                (255 - t) as u8,
            ];
            let sa = a.step(&p, &mut NoopMeter);
            let sb = b.step(&p, &mut meter);
            assert_eq!(sa, sb);
        }
        assert_eq!(a.network(), b.network());
        for phase in Phase::ALL {
            assert!(meter.states(phase) > 0, "{phase:?} charged");
        }
    }
}
