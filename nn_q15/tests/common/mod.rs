//! What nn_q15's integration tests share: the number of property cases, and a reference model of
//! the learner written from docs/design.md §2 and from the control flow of the firmware's
//! routines (firmware/learner.c), without the crate's code: sums in i64, the outputs of Eq. 2,
//! the update, the input vector, and how many times each basic block of the firmware runs.
#![allow(dead_code)] // each test file uses part of it

use nn_q15::cost::Op;
use nn_q15::{Phase, SENSORS};

/// Cases per property: `PROPTEST_CASES` when set, 10 000 otherwise (as in `proptests`).
///
/// # Panics
/// When `PROPTEST_CASES` is set but is not a whole number from 1 up.
#[must_use]
pub fn cases() -> u32 {
    match std::env::var_os("PROPTEST_CASES") {
        None => 10_000,
        Some(v) => match v.to_str().and_then(|s| s.trim().parse::<u32>().ok()) {
            Some(n) if n > 0 => n,
            _ => panic!(
                "PROPTEST_CASES = {v:?} is not a number of cases: give a whole number from 1 up"
            ),
        },
    }
}

// ---------------------------------------------------------------------------------------------
// Numbers: i64 throughout.

/// y_j = Σ_i w_ij · x_i; `w` row-major, one row of `n` per output.
#[must_use]
pub fn sums(w: &[i16], x: &[i8], n: usize) -> Vec<i64> {
    w.chunks(n)
        .map(|row| {
            row.iter()
                .zip(x)
                .map(|(&wi, &xi)| i64::from(wi) * i64::from(xi))
                .sum()
        })
        .collect()
}

/// The index of the largest sum, ties to the lowest.
#[must_use]
pub fn argmax(y: &[i64]) -> usize {
    let mut best = 0;
    for j in 1..y.len() {
        if y[j] > y[best] {
            best = j;
        }
    }
    best
}

/// The normalising shift: the smallest s with (m >> s) < 2^15, found by counting.
#[must_use]
pub fn shift_for(m: i64) -> u32 {
    let mut s = 0;
    while (m >> s) >= 1 << 15 {
        s += 1;
    }
    s
}

/// O_j of docs/design.md §2.3 step 3.
#[must_use]
pub fn outputs(y: &[i64]) -> Vec<i16> {
    let m = *y.iter().max().unwrap();
    if m < 1 << 22 {
        return y.iter().map(|&v| (v >> 7).max(-32768) as i16).collect();
    }
    let s = shift_for(m);
    let ms = m >> s;
    y.iter()
        .map(|&v| {
            let vs = v >> s;
            if vs <= -ms {
                -32768
            } else {
                ((vs << 15) / ms).min(32767) as i16
            }
        })
        .collect()
}

/// σ·Δ_i = round_half_away_from_zero(σ·η·x_i / 2^7), exactly, in integers.
#[must_use]
pub fn signed_delta(sigma: i64, eta: i16, x: i8) -> i64 {
    let p = sigma * i64::from(eta) * i64::from(x);
    p.signum() * ((p.abs() + 64) / 128)
}

/// The update of docs/design.md §2.4 on `w`; `Some(σ)` outside the dead zone.
pub fn update(w: &mut [i16], x: &[i8], win: usize, e: i16, eta: i16, t: i16) -> Option<i64> {
    if i32::from(e).abs() <= i32::from(t) {
        return None;
    }
    let sigma = if e > 0 { 1 } else { -1 };
    for (j, row) in w.chunks_mut(x.len()).enumerate() {
        let s = if j == win { 1 } else { -1 };
        for (wi, &xi) in row.iter_mut().zip(x) {
            *wi = (i64::from(*wi) + s * signed_delta(sigma, eta, xi)).clamp(-32768, 32767) as i16;
        }
    }
    Some(sigma)
}

// ---------------------------------------------------------------------------------------------
// How often each block of the firmware's routines runs, from their control flow.

/// Runs of each block, indexed by `op as usize`.
pub type Counts = [u64; Op::COUNT];

/// States of one run of `op`: its instruction forms' states from the cost table, summed here.
#[must_use]
pub fn block_states(op: Op) -> u64 {
    op.spec().insns.iter().map(|i| u64::from(i.states())).sum()
}

/// States of `counts`: the cost table applied.
#[must_use]
pub fn states_of(counts: &Counts) -> u64 {
    nn_q15::cost::Op::ALL
        .iter()
        .map(|&op| counts[op as usize] * block_states(op))
        .sum()
}

fn add(c: &mut Counts, op: Op, n: u64) {
    c[op as usize] += n;
}

/// `learner_forward` on sums `y` of `n` inputs each (firmware/learner.c): the sums' loops, the
/// argmax loop, then the plain branch (max < 2^22) or the normalising one.
#[must_use]
pub fn forward_counts(y: &[i64], n: usize) -> Counts {
    let mut c = [0; Op::COUNT];
    let m = y.len() as u64;
    add(&mut c, Op::FwdEntry, 1);
    // do { x, n, acc = 0; do { MAC } while (--n); store } while (--j): M rows of N MACs.
    add(&mut c, Op::FwdRowSetup, m);
    add(&mut c, Op::FwdMac, m * n as u64);
    add(&mut c, Op::FwdRowEnd, m);
    // max = y0; for (j = 1; j < M; j++) { load; if (v > max) new max }: the test runs M times.
    add(&mut c, Op::FwdArgmaxInit, 1);
    add(&mut c, Op::FwdArgmaxTest, m);
    add(&mut c, Op::FwdArgmaxLoad, m - 1);
    let mut max = y[0];
    for &v in &y[1..] {
        if v > max {
            max = v;
            add(&mut c, Op::FwdNewMax, 1);
        }
    }
    add(&mut c, Op::FwdScaleTest, 1);
    if max < 1 << 22 {
        for &v in y {
            add(&mut c, Op::FwdPlainHead, 1);
            if v < -(1 << 22) {
                add(&mut c, Op::FwdPlainLow, 1);
            } else {
                add(&mut c, Op::FwdPlainOut, 1);
            }
            add(&mut c, Op::FwdPlainTail, 1);
        }
        add(&mut c, Op::FwdPlainExit, 1);
    } else {
        // max >>= 8; while (max >= 32768) { max >>= 1; s8++; }
        add(&mut c, Op::FwdNormSetup, 1);
        let mut mm = max >> 8;
        let mut s8 = 0u64;
        loop {
            add(&mut c, Op::FwdNormTest, 1);
            if mm < 32768 {
                break;
            }
            mm >>= 1;
            s8 += 1;
            add(&mut c, Op::FwdNormShift, 1);
        }
        add(&mut c, Op::FwdNormReady, 1);
        for &v in y {
            add(&mut c, Op::FwdNormHead, 1);
            // v >>= 8, then s8 single shifts; the loop's test runs once more than it shifts.
            add(&mut c, Op::FwdNormStepTest, s8 + 1);
            add(&mut c, Op::FwdNormStep, s8);
            let vs = (v >> 8) >> s8;
            add(&mut c, Op::FwdNormLowTest, 1);
            if vs <= -mm {
                add(&mut c, Op::FwdNormLow, 1);
            } else {
                add(&mut c, Op::FwdNormHighTest, 1);
                if vs >= mm {
                    add(&mut c, Op::FwdNormHigh, 1);
                } else {
                    add(&mut c, Op::FwdNormDiv, 1);
                }
            }
            add(&mut c, Op::FwdNormTail, 1);
        }
    }
    add(&mut c, Op::FwdExit, 1);
    c
}

/// `learner_update(e)` on weights `w` (before the update), input `x` and winner `win`.
#[must_use]
pub fn update_counts(w: &[i16], x: &[i8], win: usize, e: i16, eta: i16, t: i16) -> Counts {
    let mut c = [0; Op::COUNT];
    add(&mut c, Op::UpdEntry, 1);
    // if (e <= t && e >= -t) return: the second test runs only when the first holds.
    if e <= t {
        add(&mut c, Op::UpdLowTest, 1);
        if e >= -t {
            add(&mut c, Op::UpdExit, 1);
            return c;
        }
    }
    add(&mut c, Op::UpdSign, 1);
    let seta = if e > 0 {
        i32::from(eta)
    } else {
        add(&mut c, Op::UpdNeg, 1);
        -i32::from(eta)
    };
    add(&mut c, Op::UpdDeltaSetup, 1);
    let mut d = Vec::with_capacity(x.len());
    for &xi in x {
        add(&mut c, Op::DeltaHead, 1);
        let p = seta * i32::from(xi);
        if p >= 0 {
            add(&mut c, Op::DeltaPos, 1);
        } else {
            add(&mut c, Op::DeltaNeg, 1);
        }
        add(&mut c, Op::DeltaTail, 1);
        // σ·Δ_i: (p + 64) >> 7 for p ≥ 0, −((64 − p) >> 7) below.
        let p = i64::from(p);
        d.push(if p >= 0 {
            (p + 64) >> 7
        } else {
            -((64 - p) >> 7)
        });
    }
    add(&mut c, Op::UpdRowsSetup, 1);
    for (j, row) in w.chunks(x.len()).enumerate() {
        add(&mut c, Op::UpdRowHead, 1);
        let s = if j == win { 1 } else { -1 };
        for (&wi, &di) in row.iter().zip(&d) {
            add(&mut c, Op::UpdWeight, 1);
            // ADD.W / SUB.W overflows (BVC not taken) past either rail.
            let v = i64::from(wi) + s * di;
            if v > 32767 {
                add(&mut c, Op::UpdClampHi, 1);
            } else if v < -32768 {
                add(&mut c, Op::UpdClampLo, 1);
            }
        }
        if j == win {
            add(&mut c, Op::UpdWinRowExit, 1);
        }
        add(&mut c, Op::UpdRowTail, 1);
    }
    add(&mut c, Op::UpdExit, 1);
    c
}

/// The blocks of `learner_step` itself (the phase `input`), for a step with evaluation `e`
/// (`started`: not the first step), history depth `h`, the bias input or not, and `m` outputs.
#[must_use]
pub fn input_counts(started: bool, e: i16, h: usize, bias: bool, m: usize) -> Counts {
    let mut c = [0; Op::COUNT];
    add(&mut c, Op::InEntry, 1);
    add(&mut c, Op::InStartedTest, 1);
    if started {
        add(&mut c, Op::InEval, 1);
    }
    add(&mut c, Op::InHistoryTest, 1);
    if h != 0 {
        add(&mut c, Op::InHistorySetup, 1);
        add(&mut c, Op::InHistoryByte, (SENSORS * h) as u64);
    }
    add(&mut c, Op::InReadings, 1);
    add(&mut c, Op::InOutputsSetup, 1);
    add(&mut c, Op::InOutput, m as u64);
    add(&mut c, Op::InEvalScale, 1);
    let e3 = e >> 3;
    if e3 > 127 {
        add(&mut c, Op::InEvalHigh, 1);
    } else {
        add(&mut c, Op::InEvalLowTest, 1);
        if e3 < -128 {
            add(&mut c, Op::InEvalLow, 1);
        }
    }
    add(&mut c, Op::InEvalStore, 1);
    if bias {
        add(&mut c, Op::InBias, 1);
    }
    add(&mut c, Op::InForwardCall, 1);
    add(&mut c, Op::InExit, 1);
    c
}

/// The per-phase counts a meter should hold, in `Phase::ALL` order.
pub type PhaseCounts = [Counts; Phase::COUNT];

/// Compares a meter's counts and states with `expected`, phase by phase and block by block.
///
/// # Errors
/// A message naming the first phase and block that differ.
pub fn compare_meter(meter: &nn_q15::H8Meter, expected: &PhaseCounts) -> Result<(), String> {
    for (k, &phase) in Phase::ALL.iter().enumerate() {
        for &op in &Op::ALL {
            let (got, want) = (meter.count_in(phase, op), expected[k][op as usize]);
            if got != want {
                return Err(format!(
                    "phase {}: block {op:?} charged {got} times, the count says {want}",
                    phase.name()
                ));
            }
        }
        let (got, want) = (meter.states(phase), states_of(&expected[k]));
        if got != want {
            return Err(format!(
                "phase {}: {got} states, the count says {want}",
                phase.name()
            ));
        }
    }
    let want: Vec<u64> = expected.iter().map(states_of).collect();
    if meter.phase_states().as_slice() != want.as_slice() {
        return Err(format!(
            "phase_states {:?}, the count says {want:?}",
            meter.phase_states()
        ));
    }
    if meter.total_states() != want.iter().sum::<u64>() {
        return Err(format!(
            "total_states {}, the count says {}",
            meter.total_states(),
            want.iter().sum::<u64>()
        ));
    }
    for &op in &Op::ALL {
        let want: u64 = expected.iter().map(|c| c[op as usize]).sum();
        if meter.count(op) != want {
            return Err(format!(
                "count({op:?}) = {}, the count says {want}",
                meter.count(op)
            ));
        }
    }
    Ok(())
}
