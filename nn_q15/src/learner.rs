//! The learner as the robot runs it: one call per step (SPEC §3.5), and its RAM footprint on the
//! H8/3052F.
//!
//! A step at time t, given the proximities p(t):
//! 1. `D(t) = Σ_k p_k(t)` and, from the second step on, `E(t−1) = D(t) − D(t−1)`;
//! 2. the update of SPEC §2.4 with E(t−1) on x(t−1) and its winner;
//! 3. the input vector x(t) of SPEC §2.2;
//! 4. the forward pass of SPEC §2.3 on x(t), whose winner picks the behaviour.

use crate::cost::{Meter, Op, Phase};
use crate::error::ConfigError;
use crate::format::{Q7, Q15, evaluation_to_q7, output_to_q7, proximity_to_q7};
use crate::input::{InputLayout, SENSORS};
use crate::net::{ForwardOut, Network, Params, UpdateKind, update_core};

/// The four primitive behaviours (SPEC §2.3 step 4).
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

/// The continuously learning controller: the network, its parameters and the state it carries
/// from step to step.
#[derive(Clone, Debug)]
pub struct Learner<const N: usize, const M: usize> {
    net: Network<N, M>,
    params: Params,
    layout: InputLayout,
    behaviours: [Behaviour; M],
    x: [Q7; N],
    o: [Q15; M],
    win: u8,
    d_prev: i16,
    started: bool,
}

impl<const N: usize, const M: usize> Learner<N, M> {
    /// The learner's RAM items on the H8, in placement order.
    pub const RAM_ITEMS: [RamItem; 7] = [
        RamItem {
            name: "weights w (i16, N x M)",
            bytes: 2 * (N * M) as u32,
        },
        RamItem {
            name: "input vector x (i8, N)",
            bytes: align2(N as u32),
        },
        RamItem {
            name: "update deltas (i16, N)",
            bytes: 2 * N as u32,
        },
        RamItem {
            name: "sums y (i32, M)",
            bytes: 4 * M as u32,
        },
        RamItem {
            name: "outputs O (i16, M)",
            bytes: 2 * M as u32,
        },
        RamItem {
            name: "eta, T (i16 each)",
            bytes: 4,
        },
        RamItem {
            name: "D(t-1) (i16), winner and started flag (u8 each)",
            bytes: 4,
        },
    ];

    /// The learner's RAM footprint on the H8 in bytes: the sum of [`Self::RAM_ITEMS`].
    pub const RAM_BYTES: u32 = {
        let mut total = 0;
        let mut i = 0;
        while i < Self::RAM_ITEMS.len() {
            total += Self::RAM_ITEMS[i].bytes;
            i += 1;
        }
        total
    };

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
        let needed = layout.n_inputs(M);
        if needed != N {
            return Err(ConfigError::Inputs {
                layout: needed,
                network: N,
            });
        }
        let mut behaviours = [Behaviour::Forward; M];
        for (b, a) in behaviours.iter_mut().zip(Behaviour::ALL) {
            *b = a;
        }
        Ok(Self {
            net,
            params,
            layout,
            behaviours,
            x: [Q7::ZERO; N],
            o: [Q15::ZERO; M],
            win: 0,
            d_prev: 0,
            started: false,
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
        self.started
    }

    /// Forgets the carried state (inputs, outputs, D, the started flag) but keeps the weights:
    /// what a reboot that restored the weights from EEPROM leaves.
    pub fn restart(&mut self) {
        self.x = [Q7::ZERO; N];
        self.o = [Q15::ZERO; M];
        self.win = 0;
        self.d_prev = 0;
        self.started = false;
    }

    /// Replaces the weights (restored from a record, say), keeping the carried state.
    pub fn set_network(&mut self, net: Network<N, M>) {
        self.net = net;
    }

    /// One step with the proximities `p` (du) read after the last behaviour.
    pub fn step<Mt: Meter>(&mut self, p: &[u8; SENSORS], meter: &mut Mt) -> StepOut {
        meter.enter(Phase::Input);
        meter.charge(Op::CallFrame, 1);

        // 1. D(t), E(t−1). D ≤ 4 · 255 = 1020 and |E| ≤ 1020: both fit an i16.
        let d = p.iter().map(|&v| i16::from(v)).sum::<i16>();
        let k = SENSORS as u32;
        meter.charge(Op::PtrInit, 1);
        meter.charge(Op::AccClear, 1);
        meter.charge(Op::LoopInitB, 1);
        meter.charge(Op::SumIn, k);
        meter.charge(Op::LoopIter, k);
        meter.charge(Op::FlagTest, 1);
        let e = if self.started {
            meter.charge(Op::LoadW, 1);
            meter.charge(Op::RegOp, 1);
            d - self.d_prev
        } else {
            0
        };
        meter.charge(Op::StoreVarW, 1);

        // 2. The update on the previous input and winner.
        let update = if self.started {
            let mut delta = [0i16; N];
            Some(update_core(
                self.net.weights_flat_mut(),
                &self.x,
                usize::from(self.win),
                e,
                self.params,
                &mut delta,
                meter,
            ))
        } else {
            None
        };

        // 3. x(t): history one block deeper, the new readings, past outputs, E, bias.
        meter.enter(Phase::Input);
        let h = self.layout.history();
        if h > 0 {
            self.x.copy_within(0..SENSORS * h, SENSORS);
            meter.charge(Op::PtrInit, 2);
            meter.charge(Op::LoopInitB, 1);
            meter.charge(Op::HistoryShift, h as u32);
        }
        for (xk, &pk) in self.x.iter_mut().zip(p) {
            *xk = Q7::from_bits(proximity_to_q7(pk));
        }
        meter.charge(Op::PtrInit, 2);
        meter.charge(Op::LoopInitB, 1);
        meter.charge(Op::ProximityIn, k);
        meter.charge(Op::LoopIter, k);
        let at = self.layout.outputs_at();
        for (xj, oj) in self.x[at..at + M].iter_mut().zip(&self.o) {
            *xj = Q7::from_bits(output_to_q7(oj.to_bits()));
        }
        meter.charge(Op::PtrInit, 2);
        meter.charge(Op::LoopInitB, 1);
        meter.charge(Op::OutputIn, M as u32);
        meter.charge(Op::LoopIter, M as u32);
        let e_in = evaluation_to_q7(e);
        self.x[at + M] = Q7::from_bits(e_in);
        meter.charge(Op::RegOp, 1);
        meter.charge(Op::EvalIn, 1);
        if Mt::ACTIVE && i16::from(e_in) != e >> 3 {
            meter.charge(Op::ClampW, 1);
        }
        if self.layout.bias() {
            self.x[at + M + 1] = Q7::from_bits(i8::MAX);
            meter.charge(Op::BiasIn, 1);
        }

        // 4. The forward pass picks the behaviour.
        let forward = self.net.forward(&self.x, meter);
        for (oj, &bits) in self.o.iter_mut().zip(forward.o_bits()) {
            *oj = Q15::from_bits(bits);
        }
        self.win = forward.win() as u8;
        self.d_prev = d;
        self.started = true;
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
