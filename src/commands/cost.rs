//! `h8swarm cost`: what one learner step costs on the H8/300H, measured by running the learner
//! with the H8 meter, and the RAM it holds.
//!
//! The learner runs `steps` steps on proximities drawn from a seeded generator (uniform 0–255 per
//! sensor, so every branch of the step is taken: rewards, punishments, dead zones, saturations);
//! its initial weights are drawn from the same stream, uniform in ±0.5. The stream is robot 0's
//! cost-input stream under the seed ([`swarm::seeds`], purpose `CostInputs`). The report gives the
//! minimum, mean and maximum states per phase and per step, their time at φ = 25 MHz, the share
//! of a step period that is, and the RAM items.

use std::fmt::Write as _;

use anyhow::{Context, Result, bail};
use clap::Args;
use nn_q15::{DynLearner, H8Meter, InputLayout, Params, Phase, Q15};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::Failure;

/// The robot's clock φ in Hz (the board's, `robot_board::board::CLOCK_HZ`; docs/design.md §4.1):
/// the firmware's states become microseconds at it.
fn phi_hz() -> f64 {
    f64::from(robot_board::board::CLOCK_HZ)
}

/// What to measure.
#[derive(Clone, Copy, Debug)]
pub struct CostConfig {
    /// Enabled behaviours M (2–4).
    pub outputs: usize,
    /// History depth H (0–8).
    pub history: usize,
    /// Whether the bias input is on.
    pub bias: bool,
    /// η as a Q15 integer.
    pub eta: i32,
    /// T in du.
    pub threshold: i32,
    /// Steps to run.
    pub steps: u32,
    /// Seed of the proximities and initial weights.
    pub seed: u64,
    /// Step period in seconds, for the CPU share.
    pub step_period_s: f64,
}

/// Minimum, mean and maximum of a per-step quantity.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Stats {
    /// Smallest value seen.
    pub min: u64,
    /// Mean over the steps.
    pub mean: f64,
    /// Largest value seen.
    pub max: u64,
}

/// Min, sum and max of a stream of values, kept as they come: a report over any number of
/// steps in constant memory.
#[derive(Clone, Copy, Debug)]
struct Running {
    min: u64,
    max: u64,
    sum: u128,
    n: u64,
}

impl Running {
    const EMPTY: Running = Running {
        min: u64::MAX,
        max: 0,
        sum: 0,
        n: 0,
    };

    fn add(&mut self, v: u64) {
        self.min = self.min.min(v);
        self.max = self.max.max(v);
        self.sum += u128::from(v);
        self.n += 1;
    }

    fn stats(&self) -> Stats {
        if self.n == 0 {
            return Stats {
                min: 0,
                mean: 0.0,
                max: 0,
            };
        }
        Stats {
            min: self.min,
            mean: self.sum as f64 / self.n as f64,
            max: self.max,
        }
    }
}

impl Stats {
    #[cfg(test)]
    fn of(values: &[u64]) -> Stats {
        let min = values.iter().copied().min().unwrap_or(0);
        let max = values.iter().copied().max().unwrap_or(0);
        let mean = if values.is_empty() {
            0.0
        } else {
            values.iter().sum::<u64>() as f64 / values.len() as f64
        };
        Stats { min, mean, max }
    }
}

/// One RAM item in the report.
#[derive(Clone, Debug, Serialize)]
pub struct RamLine {
    /// What the item holds.
    pub item: &'static str,
    /// Bytes on the H8.
    pub bytes: u32,
}

/// The measured cost.
#[derive(Clone, Debug, Serialize)]
pub struct CostReport {
    /// Inputs N.
    pub n_in: usize,
    /// Outputs M.
    pub n_out: usize,
    /// History depth H.
    pub history: usize,
    /// Bias input on.
    pub bias: bool,
    /// η (Q15 integer).
    pub eta: i32,
    /// T (du).
    pub threshold: i32,
    /// Steps measured.
    pub steps: u32,
    /// Seed.
    pub seed: u64,
    /// States of the input phase (D, E, the input vector).
    pub input_states: Stats,
    /// States of the update.
    pub update_states: Stats,
    /// States of the forward pass.
    pub forward_states: Stats,
    /// States of the whole step.
    pub step_states: Stats,
    /// Largest step time in microseconds at 25 MHz.
    pub step_max_us: f64,
    /// Largest step time as a share of the step period, in percent.
    pub cpu_share_max_percent: f64,
    /// Step period used for the share, seconds.
    pub step_period_s: f64,
    /// RAM items.
    pub ram: Vec<RamLine>,
    /// RAM total in bytes.
    pub ram_bytes: u32,
}

/// The most steps `cost` measures. The streamed statistics could hold 2^32 - 1, but a run of
/// that many would take over 400 times as long as one at this bound (the time at the bound:
/// docs/limits-and-failures.md).
pub const MAX_COST_STEPS: u32 = 10_000_000;

/// Runs the learner with the H8 meter and collects the report.
///
/// # Errors
/// A configuration outside the learner's bounds, named with the valid range.
pub fn measure(cfg: &CostConfig) -> Result<CostReport> {
    if cfg.steps == 0 || cfg.steps > MAX_COST_STEPS {
        bail!(
            "--steps {}: valid is 1 to {MAX_COST_STEPS} (the statistics settle long before)",
            cfg.steps
        );
    }
    if !robot_board::model::step_period_ok(cfg.step_period_s) {
        bail!(
            "--step-period-s {}: valid is {}",
            swarm::terminal_text::number(cfg.step_period_s),
            robot_board::model::STEP_PERIOD_VALID
        );
    }
    let layout = InputLayout::new(cfg.history, cfg.bias).context("--history")?;
    let params = Params::new(cfg.eta, cfg.threshold).context("--eta/--threshold")?;
    let n_in = layout.n_inputs(cfg.outputs);
    let mut rng = ChaCha8Rng::seed_from_u64(swarm::seeds::robot_stream(
        cfg.seed,
        0,
        0,
        0,
        seeding::Purpose::CostInputs,
    ));
    let weights: Vec<Q15> = (0..n_in * cfg.outputs)
        .map(|_| Q15::from_bits(rng.random_range(-16384i16..=16384)))
        .collect();
    let mut learner =
        DynLearner::new(cfg.outputs, layout, params, &weights).with_context(|| {
            format!(
                "{} outputs with history {} makes a network the learner cannot hold",
                cfg.outputs, cfg.history
            )
        })?;

    // Streamed: constant memory whatever `--steps`.
    let mut per_phase = [Running::EMPTY; Phase::COUNT];
    let mut per_step = Running::EMPTY;
    for _ in 0..cfg.steps {
        let p: [u8; 4] = rng.random();
        let mut meter = H8Meter::new();
        learner.step(&p, &mut meter);
        for phase in Phase::ALL {
            per_phase[phase as usize].add(meter.states(phase));
        }
        per_step.add(meter.total_states());
    }
    let step_states = per_step.stats();
    let step_max_us = step_states.max as f64 / phi_hz() * 1e6;
    Ok(CostReport {
        n_in,
        n_out: cfg.outputs,
        history: cfg.history,
        bias: cfg.bias,
        eta: cfg.eta,
        threshold: cfg.threshold,
        steps: cfg.steps,
        seed: cfg.seed,
        input_states: per_phase[Phase::Input as usize].stats(),
        update_states: per_phase[Phase::Update as usize].stats(),
        forward_states: per_phase[Phase::Forward as usize].stats(),
        step_states,
        step_max_us,
        cpu_share_max_percent: step_max_us / (cfg.step_period_s * 1e6) * 100.0,
        step_period_s: cfg.step_period_s,
        ram: learner
            .ram_items()
            .iter()
            .map(|i| RamLine {
                item: i.name,
                bytes: i.bytes,
            })
            .collect(),
        ram_bytes: learner.ram_bytes(),
    })
}

/// The report as a readable table.
#[must_use]
pub fn render(r: &CostReport) -> String {
    let mut s = String::new();
    let us = |states: f64| states / phi_hz() * 1e6;
    let _ = writeln!(
        s,
        "h8swarm: learner cost on the H8/300H at {} MHz (1 state = {} ns), from the H8 meter",
        phi_hz() / 1e6,
        1e9 / phi_hz()
    );
    let _ = writeln!(
        s,
        "network {} inputs x {} outputs (history {}, bias {}), eta {} (Q15), T {}; {} steps, seed {}",
        r.n_in,
        r.n_out,
        r.history,
        if r.bias { "on" } else { "off" },
        r.eta,
        r.threshold,
        r.steps,
        r.seed
    );
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "{:<10} {:>10} {:>10} {:>10} {:>10}",
        "phase", "min", "mean", "max", "max µs"
    );
    for (name, st) in [
        ("input", r.input_states),
        ("update", r.update_states),
        ("forward", r.forward_states),
        ("step", r.step_states),
    ] {
        let _ = writeln!(
            s,
            "{:<10} {:>10} {:>10.1} {:>10} {:>10.1}",
            name,
            st.min,
            st.mean,
            st.max,
            us(st.max as f64)
        );
    }
    let _ = writeln!(
        s,
        "worst step: {:.1} µs = {:.4} % of a {} s step period",
        r.step_max_us, r.cpu_share_max_percent, r.step_period_s
    );
    let _ = writeln!(s);
    let _ = writeln!(s, "RAM on the H8 (bytes, words aligned to 2):");
    for line in &r.ram {
        let _ = writeln!(s, "  {:<52} {:>5}", line.item, line.bytes);
    }
    let _ = writeln!(
        s,
        "  {:<52} {:>5}  ({:.1} % of the 8 192-byte on-chip RAM)",
        "total",
        r.ram_bytes,
        f64::from(r.ram_bytes) / 8192.0 * 100.0
    );
    s
}

/// `cost --eta`: the learning rate as a real number (`0.001`, `1e-3`: anything with a decimal
/// point or an exponent; 0 to 32767/32768, rounded to Q15 as a scenario's `learner.eta` is) or
/// as a Q15 integer (`33`: a whole number, 0 to 32767). Both name the same η: `0.001` is 33.
///
/// # Errors
/// Anything else, saying both forms.
pub fn parse_eta(text: &str) -> Result<i32, String> {
    let t = text.trim();
    let valid = "give a real number from 0 to 0.99997 (e.g. 0.001) or a Q15 integer from 0 to 32767 (e.g. 33)";
    if t.contains(['.', 'e', 'E']) {
        let v: f64 = t
            .parse()
            .map_err(|_| format!("`{t}` is not a learning rate: {valid}"))?;
        // Taken when its Q15 value (rounded to nearest) is 0 to 32767: 0.99997 is 32767.
        let q15 = (v * 32768.0).round();
        if !(v.is_finite() && v >= 0.0 && q15 <= 32767.0) {
            return Err(format!(
                "`{}` is out of range: {valid}",
                swarm::terminal_text::printable(t)
            ));
        }
        Ok(q15 as i32)
    } else {
        match t.parse::<i64>() {
            Ok(v) if (0..=32767).contains(&v) => Ok(v as i32),
            Ok(_) => Err(format!("`{t}` is out of range: {valid}")),
            Err(_) => Err(format!("`{t}` is not a learning rate: {valid}")),
        }
    }
}

/// Options of `h8swarm cost`.
#[derive(Args, Debug)]
pub struct CostArgs {
    /// Enabled behaviours M: 2 (corridor) to 4 (arena).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u8).range(2..=4))]
    outputs: u8,
    /// History depth H: delayed copies of the four proximities (0 to 8).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(0..=8))]
    history: u8,
    /// Add the bias input +127.
    #[arg(long)]
    bias: bool,
    /// Learning rate η: a real number (0.001, as scenarios give it) or a Q15 integer (33);
    /// 0.001 = 33, 0.1 = 3277.
    #[arg(long, default_value_t = 33, value_parser = parse_eta)]
    eta: i32,
    /// Dead-zone threshold T in distance units.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(i32).range(0..=32767))]
    threshold: i32,
    /// Steps to measure (at most 10 000 000; the statistics settle long before).
    #[arg(long, default_value_t = 10_000, value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_COST_STEPS)))]
    steps: u32,
    /// Seed of the proximities and initial weights.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Step period in seconds for the CPU share (0.45 s in the arena, 0.60 s in the corridor).
    #[arg(long, default_value_t = 0.45)]
    step_period_s: f64,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
}

impl Default for CostArgs {
    fn default() -> Self {
        Self {
            outputs: 4,
            history: 1,
            bias: false,
            eta: 33,
            threshold: 10,
            steps: 10_000,
            seed: 1,
            step_period_s: 0.45,
            json: false,
        }
    }
}

/// `h8swarm cost`: measures and prints the report (text or JSON).
///
/// # Errors
/// Bad settings ([`Failure::Input`]), an output that cannot be written ([`Failure::Tool`]).
pub fn command(args: &CostArgs) -> Result<(), Failure> {
    let cfg = CostConfig {
        outputs: usize::from(args.outputs),
        history: usize::from(args.history),
        bias: args.bias,
        eta: args.eta,
        threshold: args.threshold,
        steps: args.steps,
        seed: args.seed,
        step_period_s: args.step_period_s,
    };
    let report = measure(&cfg).map_err(Failure::Input)?;
    let text = if args.json {
        serde_json::to_string_pretty(&report).map_err(|e| Failure::Tool(e.into()))? + "\n"
    } else {
        render(&report)
    };
    super::write_text(&text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eta_is_a_real_number_or_a_q15_integer() {
        assert_eq!(parse_eta("0.001"), Ok(33));
        assert_eq!(parse_eta("1e-3"), Ok(33));
        assert_eq!(parse_eta("33"), Ok(33));
        assert_eq!(parse_eta("0.1"), Ok(3277));
        assert_eq!(parse_eta("0"), Ok(0));
        // The largest the message offers is taken; one just above is not.
        assert_eq!(parse_eta("0.99997"), Ok(32767));
        assert!(parse_eta("0.99999").is_err());
        assert!(parse_eta("-0.0001").is_err());
        assert_eq!(parse_eta("32767"), Ok(32767));
        for bad in ["1.0", "32768", "-1", "-0.5", "nan", "inf", "x", ""] {
            let e = parse_eta(bad).unwrap_err();
            assert!(e.contains("0.001") && e.contains("33"), "{bad}: {e}");
        }
    }

    #[test]
    fn streamed_statistics_equal_those_of_the_whole_list() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for len in [0usize, 1, 2, 17, 1000] {
            let values: Vec<u64> = (0..len).map(|_| rng.random_range(0..1u64 << 40)).collect();
            let mut r = Running::EMPTY;
            values.iter().for_each(|&v| r.add(v));
            let (a, b) = (r.stats(), Stats::of(&values));
            assert_eq!((a.min, a.max), (b.min, b.max), "{len}");
            assert!((a.mean - b.mean).abs() <= b.mean * 1e-12, "{len}");
        }
    }
}
