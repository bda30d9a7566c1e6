//! One learner step (forward pass + update) for 13×4 and 64×4, with the no-op meter and with the
//! H8 meter, next to a plain-`i32` reference loop of the same step in the same group, so the
//! ratios are read from one run.
//!
//! Targets: the unmetered step within 1.5× of the reference; the H8 meter under 2× the
//! unmetered step.
//!
//! Every variant walks the same 1 024 pre-drawn (x, E) pairs; E is uniform in −40 … 40, so with
//! T = 10 about three steps in four update the weights (reward or punishment) and one in four
//! falls in the dead zone.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use nn_q15::{H8Meter, Meter, Network, NoopMeter, Params, Q7, Q15};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const PAIRS: usize = 1024;
const ETA: i32 = 3277;
const T: i32 = 10;

struct Data<const N: usize, const M: usize> {
    w: [[i16; N]; M],
    xs: Vec<[i8; N]>,
    es: Vec<i16>,
}

fn data<const N: usize, const M: usize>() -> Data<N, M> {
    let mut rng = ChaCha8Rng::seed_from_u64(2008);
    let mut w = [[0i16; N]; M];
    for row in &mut w {
        for v in row.iter_mut() {
            *v = rng.random_range(-16384..=16384);
        }
    }
    let xs = (0..PAIRS).map(|_| rng.random()).collect();
    let es = (0..PAIRS).map(|_| rng.random_range(-40..=40)).collect();
    Data { w, xs, es }
}

/// The same step in plain `i32`: y, argmax, O (docs/design.md §2.3), then the update (docs/design.md §2.4).
/// Deliberately the naive indexed loops a C programmer would write first.
#[inline(never)]
#[allow(clippy::needless_range_loop)]
fn reference_step<const N: usize, const M: usize>(
    w: &mut [[i32; N]; M],
    x: &[i32; N],
    e: i32,
) -> (usize, [i32; M]) {
    let mut y = [0i32; M];
    for j in 0..M {
        let mut acc = 0;
        for i in 0..N {
            acc += w[j][i] * x[i];
        }
        y[j] = acc;
    }
    let mut win = 0;
    for j in 1..M {
        if y[j] > y[win] {
            win = j;
        }
    }
    let m = y[win];
    let mut o = [0i32; M];
    if m < 1 << 22 {
        for j in 0..M {
            o[j] = (y[j] >> 7).clamp(-32768, 32767);
        }
    } else {
        let s = 32 - m.leading_zeros() - 15;
        let ms = m >> s;
        for j in 0..M {
            let ys = y[j] >> s;
            o[j] = if ys <= -ms {
                -32768
            } else {
                ((ys << 15) / ms).min(32767)
            };
        }
    }
    if e.abs() > T {
        let se = if e > 0 { ETA } else { -ETA };
        for j in 0..M {
            let sign = if j == win { 1 } else { -1 };
            for i in 0..N {
                let p = se * x[i];
                let d = if p >= 0 {
                    (p + 64) >> 7
                } else {
                    -((-p + 64) >> 7)
                };
                w[j][i] = (w[j][i] + sign * d).clamp(-32768, 32767);
            }
        }
    }
    (win, o)
}

#[inline(never)]
fn learner_step<const N: usize, const M: usize, Mt: Meter>(
    net: &mut Network<N, M>,
    x: &[Q7; N],
    e: i16,
    meter: &mut Mt,
) -> usize {
    let params = Params::new(ETA, T).expect("valid parameters");
    let f = net.forward(x, meter);
    let _ = black_box(net.update(x, f.win(), e, params, meter));
    f.win()
}

fn bench_shape<const N: usize, const M: usize>(c: &mut Criterion, name: &str) {
    let d = data::<N, M>();
    let xq: Vec<[Q7; N]> = d.xs.iter().map(|x| x.map(Q7::from_bits)).collect();

    // The reference must be the same step: check it bit for bit before timing anything.
    {
        let mut w = d.w.map(|row| row.map(i32::from));
        let mut net = Network::<N, M>::new(d.w.map(|row| row.map(Q15::from_bits)));
        for (k, ((x, xk), &e)) in d.xs.iter().zip(&xq).zip(&d.es).enumerate() {
            let (win, o) = reference_step(&mut w, &x.map(i32::from), i32::from(e));
            let f = net.forward(xk, &mut NoopMeter);
            assert_eq!(win, f.win(), "{name} step {k}: winner");
            let o_q: Vec<i32> = f.o_bits().iter().map(|&v| i32::from(v)).collect();
            assert_eq!(o.to_vec(), o_q, "{name} step {k}: outputs");
            let params = Params::new(ETA, T).expect("valid parameters");
            net.update(xk, f.win(), e, params, &mut NoopMeter)
                .expect("winner is an output");
        }
        let ours = net.weights().map(|row| row.map(|q| i32::from(q.to_bits())));
        assert_eq!(ours, w, "{name}: weights after {PAIRS} steps");
    }

    let mut group = c.benchmark_group(format!("learner_step/{name}"));

    group.bench_function("i32_reference", |b| {
        let mut w = d.w.map(|row| row.map(i32::from));
        let xs: Vec<[i32; N]> = d.xs.iter().map(|x| x.map(i32::from)).collect();
        let mut k = 0;
        b.iter(|| {
            k = (k + 1) % PAIRS;
            black_box(reference_step(
                &mut w,
                black_box(&xs[k]),
                i32::from(d.es[k]),
            ))
        });
    });

    group.bench_function("nn_q15_noop_meter", |b| {
        let mut net = Network::<N, M>::new(d.w.map(|row| row.map(Q15::from_bits)));
        let mut k = 0;
        b.iter(|| {
            k = (k + 1) % PAIRS;
            black_box(learner_step(
                &mut net,
                black_box(&xq[k]),
                d.es[k],
                &mut NoopMeter,
            ))
        });
    });

    group.bench_function("nn_q15_h8_meter", |b| {
        let mut net = Network::<N, M>::new(d.w.map(|row| row.map(Q15::from_bits)));
        let mut meter = H8Meter::new();
        let mut k = 0;
        b.iter(|| {
            k = (k + 1) % PAIRS;
            black_box(learner_step(
                &mut net,
                black_box(&xq[k]),
                d.es[k],
                &mut meter,
            ))
        });
        black_box(meter.total_states());
    });
    group.finish();
}

fn benches(c: &mut Criterion) {
    bench_shape::<13, 4>(c, "13x4");
    bench_shape::<64, 4>(c, "64x4");
}

criterion_group!(learner, benches);
criterion_main!(learner);
