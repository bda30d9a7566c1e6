//! The two-layer network: the forward pass of docs/design.md §2.3 and the update of docs/design.md §2.4, bit-exact to
//! the integer definitions there, charged to a [`Meter`] as the H8 routine would spend it.
//!
//! Weights are stored row-major, one row of N inputs per output neuron (the layout of the replay
//! format, docs/design.md §2.6, and the order the H8 routine walks them with post-increment loads).

use crate::cost::{Meter, Op, Phase};
use crate::error::{ParamError, ShapeError};
use crate::format::{Q7, Q15, Q22, round_half_away_shr7, sat16};
use crate::limits::{MAX_INPUTS, MAX_OUTPUTS, MIN_OUTPUTS};

/// 1.0 in Q22: a weighted sum at or above it switches the forward pass to Eq. 2's division by
/// the largest sum (docs/design.md §2.3 step 3).
pub const ONE_Q22: i32 = 1 << 22;

/// A validated network shape: 1 ≤ N ≤ [`MAX_INPUTS`] inputs, [`MIN_OUTPUTS`] ≤ M ≤
/// [`MAX_OUTPUTS`] outputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shape {
    n_in: u16,
    n_out: u8,
}

impl Shape {
    /// Checks a shape against the no-overflow bound and the number of behaviours.
    ///
    /// # Errors
    /// [`ShapeError::Inputs`] or [`ShapeError::Outputs`] naming the bad count and the valid range.
    pub const fn new(n_in: usize, n_out: usize) -> Result<Shape, ShapeError> {
        if n_in == 0 || n_in > MAX_INPUTS {
            return Err(ShapeError::Inputs { got: n_in });
        }
        if n_out < MIN_OUTPUTS || n_out > MAX_OUTPUTS {
            return Err(ShapeError::Outputs { got: n_out });
        }
        Ok(Shape {
            n_in: n_in as u16,
            n_out: n_out as u8,
        })
    }

    /// Number of inputs N.
    #[must_use]
    pub const fn n_in(self) -> usize {
        self.n_in as usize
    }

    /// Number of outputs M.
    #[must_use]
    pub const fn n_out(self) -> usize {
        self.n_out as usize
    }

    /// Number of weights N · M.
    #[must_use]
    pub const fn n_weights(self) -> usize {
        self.n_in() * self.n_out()
    }
}

/// The learning parameters: η (Q15, ≥ 0) and the dead-zone threshold T (du, ≥ 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Params {
    eta: i16,
    threshold: i16,
}

impl Params {
    /// The corridor's parameters (paper env. 1): η = 0.1 → 3277, T = 10.
    pub const CORRIDOR: Params = Params {
        eta: 3277,
        threshold: 10,
    };
    /// The arena's parameters (paper env. 2): η = 0.001 → 33, T = 10.
    pub const ARENA: Params = Params {
        eta: 33,
        threshold: 10,
    };

    /// Parameters from raw integers: η in Q15 (0 … 32767), T in du (0 … 32767).
    ///
    /// # Errors
    /// [`ParamError`] naming the parameter, its value and the valid range.
    pub const fn new(eta: i32, threshold: i32) -> Result<Params, ParamError> {
        if eta < 0 || eta > i16::MAX as i32 {
            return Err(ParamError::Eta { got: eta });
        }
        if threshold < 0 || threshold > i16::MAX as i32 {
            return Err(ParamError::Threshold { got: threshold });
        }
        Ok(Params {
            eta: eta as i16,
            threshold: threshold as i16,
        })
    }

    /// η as a Q15 number.
    #[must_use]
    pub const fn eta(self) -> Q15 {
        Q15::from_bits(self.eta)
    }

    /// T in du.
    #[must_use]
    pub const fn threshold(self) -> i16 {
        self.threshold
    }
}

/// What the forward pass produced: the sums y, the outputs O, the winner.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ForwardOut {
    y: [i32; MAX_OUTPUTS],
    o: [i16; MAX_OUTPUTS],
    n_out: u8,
    win: u8,
}

impl ForwardOut {
    /// The weighted sums y_j as raw Q22 integers (M values).
    #[must_use]
    pub fn y_bits(&self) -> &[i32] {
        &self.y[..usize::from(self.n_out)]
    }

    /// The outputs O_j as raw Q15 integers (M values).
    #[must_use]
    pub fn o_bits(&self) -> &[i16] {
        &self.o[..usize::from(self.n_out)]
    }

    /// Sum y_j as a Q22 number.
    ///
    /// Returns `None` when `j` is not an output of this network.
    #[must_use]
    pub fn y(&self, j: usize) -> Option<Q22> {
        self.y_bits().get(j).map(|&v| Q22::from_bits(v))
    }

    /// Output O_j as a Q15 number.
    ///
    /// Returns `None` when `j` is not an output of this network.
    #[must_use]
    pub fn o(&self, j: usize) -> Option<Q15> {
        self.o_bits().get(j).map(|&v| Q15::from_bits(v))
    }

    /// The winning output: the index of the largest sum, ties to the lowest index.
    #[must_use]
    pub const fn win(&self) -> usize {
        self.win as usize
    }
}

/// Which branch of Eq. 8 an update took.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum UpdateKind {
    /// |E| ≤ T: no change (α = 0).
    DeadZone,
    /// E > T: the winner pushed up, the others down, for the same input.
    Reward,
    /// E < −T: the winner pushed down, the others up.
    Punish,
}

/// The forward pass on raw slices: `w` holds M rows of N weights, `x` N inputs.
/// The caller guarantees `w.len() == x.len() * n_out`, `1 ≤ x.len() ≤ 256` and `2 ≤ n_out ≤ 4`.
// Always inlined: in `Network<N, M>` the lengths then become constants and the sums vectorise
// with or without a meter.
#[inline(always)]
pub(crate) fn forward_core<Mt: Meter>(
    w: &[Q15],
    x: &[Q7],
    n_out: usize,
    meter: &mut Mt,
) -> ForwardOut {
    let n_in = x.len();
    let mut y = [0i32; MAX_OUTPUTS];
    let mut o = [0i16; MAX_OUTPUTS];

    meter.enter(Phase::Forward);

    // Step 1: y_j = Σ_i w_ij · x_i, exact in i32.
    for (row, yj) in w.chunks_exact(n_in).zip(y.iter_mut()) {
        *yj = row
            .iter()
            .zip(x)
            .map(|(wi, xi)| i32::from(wi.to_bits()) * i32::from(xi.to_bits()))
            .sum();
    }

    // Steps 2 and 4: the maximum and the winner, ties to the lowest index.
    let ys = &y[..n_out];
    let mut win = 0usize;
    let mut max = ys[0];
    let mut new_max = 0u32;
    for (j, &v) in ys.iter().enumerate().skip(1) {
        if v > max {
            max = v;
            win = j;
            new_max += 1;
        }
    }

    // Step 3: the activation of Eq. 2.
    // What the scaling did, for the meter.
    let mut plain_lows = 0u32;
    let (mut shift, mut divides, mut lows, mut highs) = (0u32, 0u32, 0u32, 0u32);
    let plain = max < ONE_Q22;
    if plain {
        for (oj, &yj) in o.iter_mut().zip(ys) {
            // Every y_j ≤ max < 2^22: only the bottom can clamp.
            *oj = sat16(yj >> 7);
            if Mt::ACTIVE {
                plain_lows += u32::from(yj < -ONE_Q22);
            }
        }
    } else {
        // Eq. 2's division by the largest sum, as a 32/16 DIVXS.W: bring m into [2^14, 2^15).
        let s = (i32::BITS - max.leading_zeros()) - 15;
        shift = s;
        let m_s = max >> s;
        for (oj, &yj) in o.iter_mut().zip(ys) {
            let y_s = yj >> s;
            *oj = if y_s <= -m_s {
                lows += 1;
                i16::MIN
            } else if y_s >= m_s {
                // (m' << 15) / m' = 32768 does not fit: the firmware tests for it first.
                highs += 1;
                i16::MAX
            } else {
                divides += 1;
                ((y_s << 15) / m_s) as i16
            };
        }
    }

    if Mt::ACTIVE {
        let tally = ForwardTally {
            n_in: n_in as u32,
            n_out: n_out as u32,
            new_max,
            plain,
            plain_lows,
            shift,
            divides,
            lows,
            highs,
        };
        charge_forward(meter, &tally);
    }

    ForwardOut {
        y,
        o,
        n_out: n_out as u8,
        win: win as u8,
    }
}

/// What one forward pass did, as the meter needs it.
struct ForwardTally {
    n_in: u32,
    n_out: u32,
    new_max: u32,
    plain: bool,
    /// Outputs clamped at the bottom in the plain branch (y_j < −2^22).
    plain_lows: u32,
    /// The normalising shift s (bitlen(m) − 15, 8 … 16), 0 in the plain branch.
    shift: u32,
    divides: u32,
    lows: u32,
    highs: u32,
}

/// Charges one forward pass: the blocks of `learner_forward` (see [`crate::cost`]), each with
/// the number of times it runs. Kept out of line so that the arithmetic compiles to the same
/// code with every meter.
#[inline(never)]
fn charge_forward<Mt: Meter>(meter: &mut Mt, t: &ForwardTally) {
    let (n, m) = (t.n_in, t.n_out);
    meter.charge(Op::FwdEntry, 1);
    meter.charge(Op::FwdRowSetup, m);
    meter.charge(Op::FwdMac, n * m);
    meter.charge(Op::FwdRowEnd, m);
    meter.charge(Op::FwdArgmaxInit, 1);
    meter.charge(Op::FwdArgmaxTest, m);
    meter.charge(Op::FwdArgmaxLoad, m - 1);
    meter.charge(Op::FwdNewMax, t.new_max);
    meter.charge(Op::FwdScaleTest, 1);
    if t.plain {
        meter.charge(Op::FwdPlainHead, m);
        meter.charge(Op::FwdPlainLow, t.plain_lows);
        meter.charge(Op::FwdPlainOut, m - t.plain_lows);
        meter.charge(Op::FwdPlainTail, m);
        meter.charge(Op::FwdPlainExit, 1);
    } else {
        // m >> 8 by byte moves, then s − 8 single shifts (the loop tests once more).
        let extra = t.shift - 8;
        meter.charge(Op::FwdNormSetup, 1);
        meter.charge(Op::FwdNormTest, extra + 1);
        meter.charge(Op::FwdNormShift, extra);
        meter.charge(Op::FwdNormReady, 1);
        meter.charge(Op::FwdNormHead, m);
        meter.charge(Op::FwdNormStepTest, (extra + 1) * m);
        meter.charge(Op::FwdNormStep, extra * m);
        meter.charge(Op::FwdNormLowTest, m);
        meter.charge(Op::FwdNormLow, t.lows);
        meter.charge(Op::FwdNormHighTest, m - t.lows);
        meter.charge(Op::FwdNormHigh, t.highs);
        meter.charge(Op::FwdNormDiv, t.divides);
        meter.charge(Op::FwdNormTail, m);
    }
    meter.charge(Op::FwdExit, 1);
}

/// What one update did, as the meter needs it.
struct UpdateTally {
    n_in: u32,
    n_out: u32,
    /// E ≤ T: the second bound test runs (punishment and most of the dead zone).
    low_test: bool,
    /// Outside the dead zone: (E < 0, Δ products below zero, clamps at the top, at the bottom).
    updated: Option<(bool, u32, u32, u32)>,
}

/// Charges one update: the blocks of `learner_update` (see [`crate::cost`]).
#[inline(never)]
fn charge_update<Mt: Meter>(meter: &mut Mt, t: &UpdateTally) {
    meter.charge(Op::UpdEntry, 1);
    meter.charge(Op::UpdLowTest, u32::from(t.low_test));
    if let Some((negative, neg_products, hi, lo)) = t.updated {
        let (n, m) = (t.n_in, t.n_out);
        meter.charge(Op::UpdSign, 1);
        meter.charge(Op::UpdNeg, u32::from(negative));
        meter.charge(Op::UpdDeltaSetup, 1);
        meter.charge(Op::DeltaHead, n);
        meter.charge(Op::DeltaPos, n - neg_products);
        meter.charge(Op::DeltaNeg, neg_products);
        meter.charge(Op::DeltaTail, n);
        meter.charge(Op::UpdRowsSetup, 1);
        meter.charge(Op::UpdRowHead, m);
        meter.charge(Op::UpdWeight, n * m);
        meter.charge(Op::UpdClampHi, hi);
        meter.charge(Op::UpdClampLo, lo);
        meter.charge(Op::UpdWinRowExit, 1);
        meter.charge(Op::UpdRowTail, m);
    }
    meter.charge(Op::UpdExit, 1);
}

/// The update of docs/design.md §2.4 on raw slices, with `delta` as the scratch for σ·Δ_i.
/// The caller guarantees `w.len() == x.len() * n_out` with `1 ≤ x.len() ≤ 256`,
/// `delta.len() >= x.len()` and `win < n_out`.
#[inline(always)]
pub(crate) fn update_core<Mt: Meter>(
    w: &mut [Q15],
    x: &[Q7],
    win: usize,
    e: i16,
    params: Params,
    delta: &mut [i16],
    meter: &mut Mt,
) -> UpdateKind {
    let n_in = x.len();
    let n_out = w.len() / n_in;
    meter.enter(Phase::Update);
    // The firmware tests E > T, then E ≥ −T.
    let low_test = e <= params.threshold;
    if e.unsigned_abs() <= params.threshold.unsigned_abs() {
        if Mt::ACTIVE {
            let tally = UpdateTally {
                n_in: n_in as u32,
                n_out: n_out as u32,
                low_test,
                updated: None,
            };
            charge_update(meter, &tally);
        }
        return UpdateKind::DeadZone;
    }
    let kind = if e > 0 {
        UpdateKind::Reward
    } else {
        UpdateKind::Punish
    };
    // σ·η: round-half-away-from-zero is odd, so σ·round(η·x/2^7) = round(σ·η·x/2^7).
    let signed_eta = if e > 0 {
        i32::from(params.eta)
    } else {
        -i32::from(params.eta)
    };

    let delta = &mut delta[..n_in];
    let mut neg_products = 0u32;
    for (d, xi) in delta.iter_mut().zip(x) {
        // |σ·η·x| ≤ 32767 · 128, so the rounded quotient fits in an i16.
        let p = signed_eta * i32::from(xi.to_bits());
        *d = round_half_away_shr7(p) as i16;
        if Mt::ACTIVE {
            neg_products += u32::from(p < 0);
        }
    }

    let (mut clamp_hi, mut clamp_lo) = (0u32, 0u32);
    for (j, row) in w.chunks_exact_mut(n_in).enumerate() {
        // |Δ| ≤ 32767, so w ± Δ saturated in i16 is exactly sat16(w ± Δ) of docs/design.md §2.4: the
        // winner's row adds, the others subtract, each a loop of saturating i16 arithmetic.
        let (hi, lo) = if j == win {
            apply_row::<Mt>(row, delta, true)
        } else {
            apply_row::<Mt>(row, delta, false)
        };
        clamp_hi += hi;
        clamp_lo += lo;
    }
    if Mt::ACTIVE {
        let tally = UpdateTally {
            n_in: n_in as u32,
            n_out: n_out as u32,
            low_test,
            updated: Some((e < 0, neg_products, clamp_hi, clamp_lo)),
        };
        charge_update(meter, &tally);
    }
    kind
}

/// Applies `delta` to one row, adding when `up` (the winner's row) and subtracting otherwise,
/// and, when the meter is active, counts the clamps at the top and at the bottom.
///
/// The counting runs on blocks of 16 lanes padded with zeros (a zero lane never clamps), so its
/// loop has a fixed trip count and vectorises even for short rows such as the default 13; a
/// clamp is a lane whose saturating result differs from the wrapping one, at the top when the
/// change was upward.
#[inline(always)]
fn apply_row<Mt: Meter>(row: &mut [Q15], delta: &[i16], up: bool) -> (u32, u32) {
    let (mut hi, mut lo) = (0u32, 0u32);
    if Mt::ACTIVE {
        for (wc, dc) in row.chunks(16).zip(delta.chunks(16)) {
            let (mut w, mut d) = ([0i16; 16], [0i16; 16]);
            for (wk, x) in w.iter_mut().zip(wc) {
                *wk = x.to_bits();
            }
            d[..dc.len()].copy_from_slice(dc);
            if !up {
                for dk in &mut d {
                    *dk = dk.wrapping_neg();
                }
            }
            let (mut h, mut l) = (0u16, 0u16);
            for k in 0..16 {
                let clamped = u16::from(w[k].saturating_add(d[k]) != w[k].wrapping_add(d[k]));
                let upward = u16::from(d[k] > 0);
                h += clamped & upward;
                l += clamped & (upward ^ 1);
            }
            hi += u32::from(h);
            lo += u32::from(l);
        }
    }
    if up {
        for (wi, &d) in row.iter_mut().zip(delta) {
            *wi = Q15::from_bits(wi.to_bits().saturating_add(d));
        }
    } else {
        for (wi, &d) in row.iter_mut().zip(delta) {
            *wi = Q15::from_bits(wi.to_bits().saturating_sub(d));
        }
    }
    (hi, lo)
}

/// The forward pass on a runtime-shaped network (used by the replay, docs/design.md §2.6): `w` holds
/// `shape.n_out()` rows of `shape.n_in()` weights.
///
/// # Errors
/// [`ShapeError::Length`] when a slice does not match the shape.
pub fn forward_slice<Mt: Meter>(
    shape: Shape,
    w: &[Q15],
    x: &[Q7],
    meter: &mut Mt,
) -> Result<ForwardOut, ShapeError> {
    check_len("weights", shape.n_weights(), w.len())?;
    check_len("x", shape.n_in(), x.len())?;
    Ok(forward_core(w, x, shape.n_out(), meter))
}

/// The update on a runtime-shaped network (used by the replay, docs/design.md §2.6).
///
/// # Errors
/// [`ShapeError::Length`] when a slice does not match the shape, [`ShapeError::Winner`] when
/// `win` is not an output.
pub fn update_slice<Mt: Meter>(
    shape: Shape,
    w: &mut [Q15],
    x: &[Q7],
    win: usize,
    e: i16,
    params: Params,
    meter: &mut Mt,
) -> Result<UpdateKind, ShapeError> {
    check_len("weights", shape.n_weights(), w.len())?;
    check_len("x", shape.n_in(), x.len())?;
    if win >= shape.n_out() {
        return Err(ShapeError::Winner {
            got: win,
            n_out: shape.n_out(),
        });
    }
    let mut delta = [0i16; MAX_INPUTS];
    Ok(update_core(w, x, win, e, params, &mut delta, meter))
}

fn check_len(what: &'static str, expected: usize, got: usize) -> Result<(), ShapeError> {
    if expected == got {
        Ok(())
    } else {
        Err(ShapeError::Length {
            what,
            expected,
            got,
        })
    }
}

/// A network of N inputs and M outputs with its weights, shape checked at compile time.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Network<const N: usize, const M: usize> {
    w: [[Q15; N]; M],
}

impl<const N: usize, const M: usize> Network<N, M> {
    /// Evaluating this constant fails to compile for a shape outside the no-overflow bound
    /// (N > 256 or N = 0) or outside 2–4 behaviours.
    const SHAPE_OK: () = assert!(
        N >= 1 && N <= MAX_INPUTS && M >= MIN_OUTPUTS && M <= MAX_OUTPUTS,
        "network shape out of range: need 1 <= N <= 256 inputs and 2 <= M <= 4 outputs"
    );

    /// The network's shape.
    pub const SHAPE: Shape = Shape {
        n_in: N as u16,
        n_out: M as u8,
    };

    /// A network with the given weights, one row of N per output.
    #[must_use]
    pub const fn new(weights: [[Q15; N]; M]) -> Self {
        let () = Self::SHAPE_OK;
        Self { w: weights }
    }

    /// A network with the given raw Q15 weights, one row of N per output.
    #[must_use]
    pub fn from_bits(weights: [[i16; N]; M]) -> Self {
        Self::new(weights.map(|row| row.map(Q15::from_bits)))
    }

    /// A network with every weight zero.
    #[must_use]
    pub const fn zeroed() -> Self {
        Self::new([[Q15::ZERO; N]; M])
    }

    /// The weights, one row of N per output.
    #[must_use]
    pub const fn weights(&self) -> &[[Q15; N]; M] {
        &self.w
    }

    /// The weights as one flat row-major slice (output-major, as stored on the H8).
    #[must_use]
    pub fn weights_flat(&self) -> &[Q15] {
        self.w.as_flattened()
    }

    pub(crate) fn weights_flat_mut(&mut self) -> &mut [Q15] {
        self.w.as_flattened_mut()
    }

    /// The forward pass of docs/design.md §2.3 on `x`.
    #[inline]
    pub fn forward<Mt: Meter>(&self, x: &[Q7; N], meter: &mut Mt) -> ForwardOut {
        forward_core(self.w.as_flattened(), x, M, meter)
    }

    /// The update of docs/design.md §2.4: evaluation `e` for input `x`, whose winner was `win`.
    ///
    /// # Errors
    /// [`ShapeError::Winner`] when `win ≥ M`.
    #[inline]
    pub fn update<Mt: Meter>(
        &mut self,
        x: &[Q7; N],
        win: usize,
        e: i16,
        params: Params,
        meter: &mut Mt,
    ) -> Result<UpdateKind, ShapeError> {
        if win >= M {
            return Err(ShapeError::Winner { got: win, n_out: M });
        }
        let mut delta = [0i16; N];
        Ok(update_core(
            self.w.as_flattened_mut(),
            x,
            win,
            e,
            params,
            &mut delta,
            meter,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cost::{H8Meter, NoopMeter};

    fn q7s<const N: usize>(v: [i8; N]) -> [Q7; N] {
        v.map(Q7::from_bits)
    }

    #[test]
    fn small_sums_are_shifted_to_q15() {
        // y_0 = 16384·64 = 2^20 (0.25), y_1 = −2^20: below 1.0, so O = y >> 7.
        let net = Network::<1, 2>::from_bits([[16384], [-16384]]);
        let f = net.forward(&q7s([64]), &mut NoopMeter);
        assert_eq!(f.y_bits(), &[1 << 20, -(1 << 20)]);
        assert_eq!(f.o_bits(), &[8192, -8192]);
        assert_eq!(f.win(), 0);
    }

    #[test]
    fn large_sums_are_divided_by_the_largest() {
        // y = [2^23, 2^22, −2^24]: m = 2^23, bitlen 24, s = 9, m' = 2^14.
        let net = Network::<2, 3>::from_bits([[32767, 32767], [16384, 16384], [-32768, -32768]]);
        let f = net.forward(&q7s([127, 127]), &mut NoopMeter);
        let y0 = 32767 * 127 * 2;
        assert_eq!(f.y_bits()[0], y0);
        assert_eq!(f.win(), 0);
        assert_eq!(
            f.o_bits()[0],
            i16::MAX,
            "the largest output saturates at 32767"
        );
        let s = 32 - y0.leading_zeros() - 15;
        let m_s = y0 >> s;
        let y1 = 16384 * 127 * 2;
        assert_eq!(f.o_bits()[1], (((y1 >> s) << 15) / m_s) as i16);
        assert_eq!(f.o_bits()[2], i16::MIN);
    }

    #[test]
    fn ties_go_to_the_lowest_index() {
        let net = Network::<1, 4>::from_bits([[5], [9], [9], [9]]);
        assert_eq!(net.forward(&q7s([1]), &mut NoopMeter).win(), 1);
    }

    #[test]
    fn reward_moves_winner_up_and_others_down() {
        let mut net = Network::<2, 2>::from_bits([[0, 0], [0, 0]]);
        let x = q7s([64, -64]);
        let p = Params::new(3277, 10).unwrap();
        let kind = net.update(&x, 1, 11, p, &mut NoopMeter).unwrap();
        assert_eq!(kind, UpdateKind::Reward);
        // Δ = round(3277·64/128) = round(1638.5) = 1639 (half away from zero).
        assert_eq!(net.weights()[1].map(|q| q.to_bits()), [1639, -1639]);
        assert_eq!(net.weights()[0].map(|q| q.to_bits()), [-1639, 1639]);
        assert_eq!(
            net.update(&x, 1, 10, p, &mut NoopMeter).unwrap(),
            UpdateKind::DeadZone
        );
        assert_eq!(
            net.update(&x, 1, -11, p, &mut NoopMeter).unwrap(),
            UpdateKind::Punish
        );
        assert_eq!(net.weights()[1].map(|q| q.to_bits()), [0, 0]);
    }

    #[test]
    fn saturation_clamps_weights() {
        let mut net = Network::<1, 2>::from_bits([[32000], [-32000]]);
        let p = Params::new(32767, 0).unwrap();
        net.update(&q7s([127]), 0, 1, p, &mut NoopMeter).unwrap();
        assert_eq!(net.weights()[0][0].to_bits(), i16::MAX);
        assert_eq!(net.weights()[1][0].to_bits(), i16::MIN);
    }

    #[test]
    fn a_bad_winner_is_an_error() {
        let mut net = Network::<1, 2>::zeroed();
        let err = net
            .update(&q7s([1]), 2, 100, Params::ARENA, &mut NoopMeter)
            .unwrap_err();
        assert_eq!(err, ShapeError::Winner { got: 2, n_out: 2 });
    }

    #[test]
    fn slice_api_checks_lengths() {
        let shape = Shape::new(3, 2).unwrap();
        let w = [Q15::ZERO; 6];
        assert!(forward_slice(shape, &w, &[Q7::ZERO; 3], &mut NoopMeter).is_ok());
        assert_eq!(
            forward_slice(shape, &w[..5], &[Q7::ZERO; 3], &mut NoopMeter),
            Err(ShapeError::Length {
                what: "weights",
                expected: 6,
                got: 5
            })
        );
        assert!(Shape::new(0, 2).is_err());
        assert!(Shape::new(257, 2).is_err());
        assert!(Shape::new(256, 4).is_ok());
        assert!(Shape::new(3, 1).is_err());
        assert!(Shape::new(3, 8).is_ok());
        assert!(Shape::new(3, 9).is_err());
    }

    #[test]
    fn forward_cost_of_13x4_matches_the_firmware() {
        // All-zero weights: y = 0, plain branch, no new maximum, no clamps. The firmware's
        // learner_forward takes 3 380 states for this on the emulated H8/300H (the emulator's
        // calibration test measures it): entry 152, four rows of 18 + 13 · 46 + 36, the argmax
        // 32 + 4 · 14 + 3 · 36, the scale test 44, four plain outputs of 40 + 36 + 6, the
        // branch's exit 6, the return 46.
        let net = Network::<13, 4>::zeroed();
        let mut m = H8Meter::new();
        net.forward(&[Q7::ZERO; 13], &mut m);
        assert_eq!(m.states(Phase::Forward), 3380);
        assert_eq!(m.count(Op::FwdMac), 13 * 4);
    }
}
