//! One IR distance sensor: per-sensor spread, sample-and-hold refresh, read noise and spikes.
//!
//! See the crate docs for the model; this module holds the parameters ([`IrParams`]) and the
//! sensor ([`IrSensor`]).

use rand_core::Rng;
use seeding::Purpose;

use crate::curve::{
    NOMINAL_DV_80_TO_10CM_VOLTS, NOMINAL_V_80CM_VOLTS, effective_distance_mm, nominal_volts_checked,
};
use crate::error::SensorError;
use crate::rng::{StreamRng, counter_unit_f64, stream, uniform_f64, unit_f64};

/// Typical output at 80 cm, 0.4 V (GP2Y0A21YK / GP2D12 datasheets, electro-optical table).
pub const DATASHEET_V_80CM_TYP_VOLTS: f64 = 0.4;
/// Unit-to-unit spread of the output at 80 cm, ±0.15 V (docs/design.md §3.1: datasheet 0.25–0.55 V).
pub const DATASHEET_V_80CM_SPREAD_VOLTS: f64 = 0.15;
/// Smallest output difference between 80 cm and 10 cm, 1.75 V (docs/design.md §3.1, GP2D12 datasheet).
pub const DATASHEET_DV_80_TO_10CM_MIN_VOLTS: f64 = 1.75;
/// Largest output difference between 80 cm and 10 cm, 2.25 V (docs/design.md §3.1, GP2D12 datasheet).
pub const DATASHEET_DV_80_TO_10CM_MAX_VOLTS: f64 = 2.25;
/// Typical measuring period, 38.3 ms (docs/design.md §3.1; GP2Y0A21YK datasheet timing chart, T1).
pub const DATASHEET_PERIOD_MEAN_MS: f64 = 38.3;
/// Spread of the measuring period, ±9.6 ms (docs/design.md §3.1; GP2Y0A21YK datasheet timing chart).
pub const DATASHEET_PERIOD_SPREAD_MS: f64 = 9.6;
/// Cycle-to-cycle jitter of each refresh instant, ±0.4 ms (≈ 1 % of the period): an
/// assumption; the datasheet gives only the unit-to-unit spread of the period.
pub const DEFAULT_PERIOD_JITTER_MS: f64 = 0.4;
/// Read noise, Gaussian σ = 15 mV (docs/design.md §3.1).
pub const NOISE_SIGMA_VOLTS: f64 = 0.015;
/// Probability that one A/D sample lands in an output spike, 0.1 (docs/design.md §3.1: ~0.1 ms spikes
/// every ~1 ms).
pub const SPIKE_PROBABILITY: f64 = 0.1;
/// Smallest spike height, +150 mV (docs/design.md §3.1).
pub const SPIKE_MIN_VOLTS: f64 = 0.150;
/// Largest spike height, +200 mV (docs/design.md §3.1).
pub const SPIKE_MAX_VOLTS: f64 = 0.200;
/// The sensor's supply, Vcc = 5 V on the robot (datasheet: 4.5–5.5 V); its output stays within
/// 0 V … Vcc, so held values and reads are clamped to that range.
pub const SUPPLY_VOLTS: f64 = 5.0;
/// Supply current, 33 mA typical (50 mA maximum), drawn all the time: the sensor pulses its
/// IR LED every measuring period whether or not anyone reads it (Sharp GP2D12 datasheet,
/// electro-optical characteristics, "average dissipation current I_CC", L = 80 cm; the
/// GP2Y0A21YK gives 30 mA typical).
pub const SUPPLY_CURRENT_MA: f64 = 33.0;

/// Parameters of one IR sensor model. [`IrParams::datasheet`] gives the datasheet figures;
/// [`IrParams::ideal`] a noiseless nominal sensor for tests. Both take the MCU's clock, which
/// the crate has none of its own of (the robot's is the board's, docs/design.md §4.1).
///
/// Valid ranges (checked by [`IrParams::validate`] and [`IrSensor::new`]):
///
/// | field | valid |
/// |---|---|
/// | `clock_hz` | 1 000 000 ..= 100 000 000 |
/// | `v_80cm_min_volts`, `v_80cm_max_volts` | 0 ..= 1 V, min ≤ max |
/// | `dv_80_to_10cm_min_volts`, `dv_80_to_10cm_max_volts` | 0 < x ≤ 4 V, min ≤ max |
/// | `period_mean_ms` | 1 ..= 1000 ms |
/// | `period_spread_ms` | 0 ..= `period_mean_ms` − 1 ms (every interval ≥ 1 ms) |
/// | `period_jitter_ms` | 0 ..= `period_spread_ms` / 2 |
/// | `noise_sigma_volts` | 0 ..= 1 V |
/// | `spike_probability` | 0 ..= 1 |
/// | `spike_min_volts`, `spike_max_volts` | 0 ..= 1 V, min ≤ max |
#[derive(Clone, Debug, PartialEq)]
pub struct IrParams {
    /// MCU clock φ in Hz: the unit of time is one state, `1 / clock_hz` seconds.
    pub clock_hz: u32,
    /// Lower end of the per-sensor output at 80 cm (drawn uniformly in min..max).
    pub v_80cm_min_volts: f64,
    /// Upper end of the per-sensor output at 80 cm.
    pub v_80cm_max_volts: f64,
    /// Lower end of the per-sensor output difference V(10 cm) − V(80 cm) (drawn uniformly).
    pub dv_80_to_10cm_min_volts: f64,
    /// Upper end of the per-sensor output difference V(10 cm) − V(80 cm).
    pub dv_80_to_10cm_max_volts: f64,
    /// Centre of the range of refresh intervals.
    pub period_mean_ms: f64,
    /// Half-width of the range of refresh intervals: every interval lies in mean ± spread.
    pub period_spread_ms: f64,
    /// Largest deviation of one refresh instant from the sensor's own regular grid.
    pub period_jitter_ms: f64,
    /// Standard deviation of the Gaussian read noise.
    pub noise_sigma_volts: f64,
    /// Probability that one read lands in a spike.
    pub spike_probability: f64,
    /// Smallest spike height (added to the read).
    pub spike_min_volts: f64,
    /// Largest spike height.
    pub spike_max_volts: f64,
}

impl IrParams {
    /// The datasheet figures, time counted in states of the MCU's `clock_hz`.
    #[must_use]
    pub fn datasheet(clock_hz: u32) -> Self {
        Self {
            clock_hz,
            v_80cm_min_volts: DATASHEET_V_80CM_TYP_VOLTS - DATASHEET_V_80CM_SPREAD_VOLTS,
            v_80cm_max_volts: DATASHEET_V_80CM_TYP_VOLTS + DATASHEET_V_80CM_SPREAD_VOLTS,
            dv_80_to_10cm_min_volts: DATASHEET_DV_80_TO_10CM_MIN_VOLTS,
            dv_80_to_10cm_max_volts: DATASHEET_DV_80_TO_10CM_MAX_VOLTS,
            period_mean_ms: DATASHEET_PERIOD_MEAN_MS,
            period_spread_ms: DATASHEET_PERIOD_SPREAD_MS,
            period_jitter_ms: DEFAULT_PERIOD_JITTER_MS,
            noise_sigma_volts: NOISE_SIGMA_VOLTS,
            spike_probability: SPIKE_PROBABILITY,
            spike_min_volts: SPIKE_MIN_VOLTS,
            spike_max_volts: SPIKE_MAX_VOLTS,
        }
    }
}

fn check(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    valid: String,
) -> Result<(), SensorError> {
    // Written so that NaN fails too.
    if value >= lo && value <= hi {
        Ok(())
    } else {
        Err(SensorError::ParamOutOfRange { name, value, valid })
    }
}

impl IrParams {
    /// A nominal, noiseless sensor: no unit-to-unit spread (gain 1, offset 0, so it follows
    /// [`nominal_volts`](crate::nominal_volts) exactly), a fixed 38.3 ms period without jitter,
    /// no noise and no spikes. Its random phase remains. Time is counted in states of the
    /// MCU's `clock_hz`.
    #[must_use]
    pub fn ideal(clock_hz: u32) -> Self {
        Self {
            v_80cm_min_volts: NOMINAL_V_80CM_VOLTS,
            v_80cm_max_volts: NOMINAL_V_80CM_VOLTS,
            dv_80_to_10cm_min_volts: NOMINAL_DV_80_TO_10CM_VOLTS,
            dv_80_to_10cm_max_volts: NOMINAL_DV_80_TO_10CM_VOLTS,
            period_spread_ms: 0.0,
            period_jitter_ms: 0.0,
            noise_sigma_volts: 0.0,
            spike_probability: 0.0,
            ..Self::datasheet(clock_hz)
        }
    }

    /// Check every field against its range (see the table on [`IrParams`]); the error names
    /// the first field out of range and the valid range.
    pub fn validate(&self) -> Result<(), SensorError> {
        check(
            "clock_hz",
            f64::from(self.clock_hz),
            1e6,
            1e8,
            "1000000 ..= 100000000 Hz (the H8/3052F runs at up to 25 MHz)".into(),
        )?;
        check(
            "v_80cm_min_volts",
            self.v_80cm_min_volts,
            0.0,
            1.0,
            "0 ..= 1 V".into(),
        )?;
        check(
            "v_80cm_max_volts",
            self.v_80cm_max_volts,
            self.v_80cm_min_volts,
            1.0,
            format!("v_80cm_min_volts ({}) ..= 1 V", self.v_80cm_min_volts),
        )?;
        check(
            "dv_80_to_10cm_min_volts",
            self.dv_80_to_10cm_min_volts,
            f64::MIN_POSITIVE,
            4.0,
            "0 < x <= 4 V".into(),
        )?;
        check(
            "dv_80_to_10cm_max_volts",
            self.dv_80_to_10cm_max_volts,
            self.dv_80_to_10cm_min_volts,
            4.0,
            format!(
                "dv_80_to_10cm_min_volts ({}) ..= 4 V",
                self.dv_80_to_10cm_min_volts
            ),
        )?;
        check(
            "period_mean_ms",
            self.period_mean_ms,
            1.0,
            1000.0,
            "1 ..= 1000 ms".into(),
        )?;
        check(
            "period_spread_ms",
            self.period_spread_ms,
            0.0,
            self.period_mean_ms - 1.0,
            format!(
                "0 ..= period_mean_ms - 1 = {} ms (every interval must be >= 1 ms)",
                self.period_mean_ms - 1.0
            ),
        )?;
        check(
            "period_jitter_ms",
            self.period_jitter_ms,
            0.0,
            self.period_spread_ms / 2.0,
            format!(
                "0 ..= period_spread_ms / 2 = {} ms",
                self.period_spread_ms / 2.0
            ),
        )?;
        check(
            "noise_sigma_volts",
            self.noise_sigma_volts,
            0.0,
            1.0,
            "0 ..= 1 V".into(),
        )?;
        check(
            "spike_probability",
            self.spike_probability,
            0.0,
            1.0,
            "0 ..= 1".into(),
        )?;
        check(
            "spike_min_volts",
            self.spike_min_volts,
            0.0,
            1.0,
            "0 ..= 1 V".into(),
        )?;
        check(
            "spike_max_volts",
            self.spike_max_volts,
            self.spike_min_volts,
            1.0,
            format!("spike_min_volts ({}) ..= 1 V", self.spike_min_volts),
        )?;
        Ok(())
    }

    /// Milliseconds to (fractional) states at this clock.
    fn ms_to_states(&self, ms: f64) -> f64 {
        ms * f64::from(self.clock_hz) / 1000.0
    }
}

/// One IR distance sensor on one analog pin.
///
/// Drive it with the MCU clock (states, non-decreasing) and the true distance the world sees.
/// [`sample`](Self::sample) is one A/D conversion's view of the pin; [`update`](Self::update)
/// advances the sample-and-hold without reading.
#[derive(Clone, Debug)]
pub struct IrSensor {
    params: IrParams,
    /// Per-sensor gain on the nominal curve.
    gain: f64,
    /// Per-sensor offset added after the gain, volts.
    offset_volts: f64,
    /// This sensor's own period, states.
    period_states: f64,
    /// Largest jitter of a refresh instant, states.
    jitter_states: f64,
    /// Instant of the grid's cycle 0, states (≥ `jitter_states`, so no instant is negative).
    grid_start_states: f64,
    /// Key of the counter-based jitter stream.
    jitter_key: u64,
    /// Index of the next refresh instant not yet passed.
    next_index: u64,
    /// Its instant, states.
    next_refresh_states: u64,
    /// Instant of the previous call, if any.
    last_call_states: Option<u64>,
    /// The output being held, once a measurement has been latched.
    held_volts: Option<f64>,
    noise_rng: StreamRng,
}

impl IrSensor {
    /// A sensor with parameters `params`, its randomness all drawn from `seed`.
    ///
    /// The spread (gain, offset), the own period and the phase are drawn here, once.
    pub fn new(params: IrParams, seed: u64) -> Result<Self, SensorError> {
        params.validate()?;

        let mut spread = stream(seed, Purpose::SensorSpread);
        let dv = uniform_f64(
            &mut spread,
            params.dv_80_to_10cm_min_volts,
            params.dv_80_to_10cm_max_volts,
        );
        let v80 = uniform_f64(
            &mut spread,
            params.v_80cm_min_volts,
            params.v_80cm_max_volts,
        );
        let gain = dv / NOMINAL_DV_80_TO_10CM_VOLTS;
        let offset_volts = v80 - gain * NOMINAL_V_80CM_VOLTS;

        let mut timing = stream(seed, Purpose::SensorTiming);
        // Own period inside mean ± (spread − 2·jitter), so that every interval, which is the
        // period plus the difference of two jitters, stays inside mean ± spread.
        let margin_ms = params.period_spread_ms - 2.0 * params.period_jitter_ms;
        let period_ms = uniform_f64(
            &mut timing,
            params.period_mean_ms - margin_ms,
            params.period_mean_ms + margin_ms,
        );
        let period_states = params.ms_to_states(period_ms);
        let jitter_states = params.ms_to_states(params.period_jitter_ms);
        // Sensors are not in phase: cycle 0 falls anywhere in the first period.
        let grid_start_states = jitter_states + period_states * unit_f64(&mut timing);
        let jitter_key = timing.next_u64();

        let mut sensor = Self {
            params,
            gain,
            offset_volts,
            period_states,
            jitter_states,
            grid_start_states,
            jitter_key,
            next_index: 0,
            next_refresh_states: 0,
            last_call_states: None,
            held_volts: None,
            noise_rng: stream(seed, Purpose::SensorNoise),
        };
        sensor.next_refresh_states = sensor.refresh_instant_states(0);
        Ok(sensor)
    }

    /// The instant of refresh `k`: `grid_start + k · period + jitter_k`, rounded to a state.
    fn refresh_instant_states(&self, k: u64) -> u64 {
        let u = counter_unit_f64(self.jitter_key, k);
        let t = self.grid_start_states
            + k as f64 * self.period_states
            + self.jitter_states * (2.0 * u - 1.0);
        // Non-negative by construction; `as` saturates at u64::MAX for absurdly late instants.
        t.round() as u64
    }

    /// Advance the sample-and-hold to `now_states` with the world's distance at that instant.
    ///
    /// If a refresh instant has passed since the previous call (or on the very first call,
    /// since the sensor was measuring before the emulation began), the held output becomes
    /// this sensor's curve at `distance_mm`. No noise is drawn. `distance_mm` is in mm; `None`
    /// means nothing hit (see [`NOTHING_HIT_MM`](crate::NOTHING_HIT_MM)).
    ///
    /// Errors (the sensor is left unchanged): NaN or negative distance; `now_states` earlier
    /// than the previous call's.
    pub fn update(&mut self, now_states: u64, distance_mm: Option<f64>) -> Result<(), SensorError> {
        let d_mm = effective_distance_mm(distance_mm)?;
        if let Some(last) = self.last_call_states
            && now_states < last
        {
            return Err(SensorError::TimeBackwards {
                now_states,
                last_states: last,
            });
        }
        self.last_call_states = Some(now_states);
        let due = now_states >= self.next_refresh_states;
        if due || self.held_volts.is_none() {
            self.held_volts = Some(self.curve_volts_checked(d_mm));
        }
        if due {
            self.skip_refreshes_up_to(now_states);
        }
        Ok(())
    }

    /// Move `next_index` to the first refresh instant after `now_states`, in O(1) however long
    /// the gap: instants stay within `jitter + ½ state` of the regular grid.
    fn skip_refreshes_up_to(&mut self, now_states: u64) {
        let cycles = (now_states as f64 - self.grid_start_states) / self.period_states;
        let estimate = if cycles > 0.0 { cycles as u64 } else { 0 };
        let mut k = estimate.saturating_sub(1).max(self.next_index);
        // Jitter is below half a period, so the estimate is within two cycles of the answer;
        // the step bound only matters past 2^64 states, where instants saturate.
        let mut steps = 0;
        // Step back while the instant before k is still in the future ...
        while k > self.next_index && self.refresh_instant_states(k - 1) > now_states && steps < 8 {
            k -= 1;
            steps += 1;
        }
        // ... and forward while k itself has passed.
        while self.refresh_instant_states(k) <= now_states && steps < 16 {
            k = k.saturating_add(1);
            steps += 1;
        }
        self.next_index = k;
        self.next_refresh_states = self.refresh_instant_states(k);
    }

    /// One A/D sample of the pin at `now_states`: [`update`](Self::update), then the held
    /// output plus Gaussian noise and, with `spike_probability`, a spike; clamped to
    /// 0 ..= [`SUPPLY_VOLTS`]. The world calls it with the distance at the read instant.
    ///
    /// Errors as for [`update`](Self::update); on an error no noise is drawn.
    pub fn sample(
        &mut self,
        now_states: u64,
        distance_mm: Option<f64>,
    ) -> Result<f64, SensorError> {
        self.update(now_states, distance_mm)?;
        let held = self.held_volts.unwrap_or(0.0);
        Ok((held + self.read_noise_volts()).clamp(0.0, SUPPLY_VOLTS))
    }

    /// Draw one read's noise: σ·N(0,1), plus a uniform spike with `spike_probability`.
    fn read_noise_volts(&mut self) -> f64 {
        let gauss = crate::rng::standard_normal(&mut self.noise_rng);
        let mut noise = self.params.noise_sigma_volts * gauss;
        if unit_f64(&mut self.noise_rng) < self.params.spike_probability {
            noise += uniform_f64(
                &mut self.noise_rng,
                self.params.spike_min_volts,
                self.params.spike_max_volts,
            );
        }
        noise
    }

    fn curve_volts_checked(&self, d_mm: f64) -> f64 {
        (self.gain * nominal_volts_checked(d_mm) + self.offset_volts).clamp(0.0, SUPPLY_VOLTS)
    }

    /// This sensor's noiseless, un-held output at `distance_mm`: its gain and offset applied to
    /// the nominal curve, clamped to 0 ..= [`SUPPLY_VOLTS`]. Errors for NaN or negative
    /// distances.
    pub fn curve_volts(&self, distance_mm: Option<f64>) -> Result<f64, SensorError> {
        effective_distance_mm(distance_mm).map(|d| self.curve_volts_checked(d))
    }

    /// The output currently held (before read noise); `None` before the first call.
    #[must_use]
    pub fn held_volts(&self) -> Option<f64> {
        self.held_volts
    }

    /// The instant (states) of the next refresh: a call at or after it latches a new value.
    /// A world that wants the distance *at* the refresh instant can call
    /// [`update`](Self::update) exactly then.
    #[must_use]
    pub fn next_refresh_states(&self) -> u64 {
        self.next_refresh_states
    }

    /// This sensor's gain on the nominal curve (1 for a nominal sensor).
    #[must_use]
    pub fn gain(&self) -> f64 {
        self.gain
    }

    /// This sensor's offset in volts, added after the gain (0 for a nominal sensor).
    #[must_use]
    pub fn offset_volts(&self) -> f64 {
        self.offset_volts
    }

    /// This sensor's own refresh period (the centre of its intervals), in milliseconds.
    #[must_use]
    pub fn period_ms(&self) -> f64 {
        self.period_states * 1000.0 / f64::from(self.params.clock_hz)
    }

    /// The parameters the sensor was built with.
    #[must_use]
    pub fn params(&self) -> &IrParams {
        &self.params
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The MCU's φ these tests count in: the robot's 25 MHz (the crate has no clock of its own).
    const CLOCK_HZ: u32 = 25_000_000;
    use crate::curve::{FAR_BRANCH_MIN_MM, far_branch_cm_at_volts, nominal_volts};
    use proptest::prelude::*;

    const N_READS: usize = 100_000;

    fn mean_sd(xs: &[f64]) -> (f64, f64) {
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, var.sqrt())
    }

    #[test]
    fn ideal_sensor_follows_the_nominal_curve() {
        let mut s = IrSensor::new(IrParams::ideal(CLOCK_HZ), 7).unwrap();
        assert_eq!(s.gain(), 1.0);
        assert!(s.offset_volts().abs() < 1e-15);
        for d in [0.0, 10.0, 50.0, 80.0, 100.0, 333.3, 800.0, 5000.0] {
            let want = nominal_volts(Some(d)).unwrap();
            assert!((s.curve_volts(Some(d)).unwrap() - want).abs() < 1e-12);
        }
        assert!(s.held_volts().is_none());
        let v = s.sample(0, Some(300.0)).unwrap();
        assert!((v - nominal_volts(Some(300.0)).unwrap()).abs() < 1e-12);
        assert_eq!(s.held_volts(), Some(v));
        assert!((s.period_ms() - 38.3).abs() < 1e-9);
    }

    #[test]
    fn hold_is_constant_between_refreshes() {
        let mut s = IrSensor::new(IrParams::ideal(CLOCK_HZ), 11).unwrap();
        let near = s.curve_volts(Some(150.0)).unwrap();
        let far = s.curve_volts(Some(600.0)).unwrap();
        assert_eq!(s.sample(0, Some(150.0)).unwrap(), near);
        let t1 = s.next_refresh_states();
        assert!(t1 > 0);
        // Up to the state before the refresh, the old value is held whatever the distance.
        for t in [1, t1 / 2, t1 - 1] {
            assert_eq!(s.sample(t, Some(600.0)).unwrap(), near, "at {t}");
        }
        assert_eq!(s.next_refresh_states(), t1);
        // At the refresh instant the new distance is latched.
        assert_eq!(s.sample(t1, Some(600.0)).unwrap(), far);
        let t2 = s.next_refresh_states();
        assert_eq!(t2 - t1, 957_500, "38.3 ms at 25 MHz");
        assert_eq!(s.sample(t2 - 1, None).unwrap(), far);
        assert_eq!(s.sample(t2, None).unwrap(), s.curve_volts(None).unwrap());
    }

    #[test]
    fn spread_matches_the_datasheet() {
        // 2 000 sensors; V80 ~ U[0.25, 0.55] (sd 0.0866 V), ΔV ~ U[1.75, 2.25] (sd 0.144 V).
        // Tolerance on the means: 4 standard errors, sd / sqrt(2000).
        let n = 2000;
        let (mut v80s, mut dvs) = (Vec::new(), Vec::new());
        for seed in 0..n {
            let s = IrSensor::new(IrParams::datasheet(CLOCK_HZ), seed).unwrap();
            let v80 = s.curve_volts(Some(800.0)).unwrap();
            let dv = s.curve_volts(Some(100.0)).unwrap() - v80;
            assert!(
                (0.25 - 1e-12..=0.55 + 1e-12).contains(&v80),
                "seed {seed}: V80 {v80}"
            );
            assert!(
                (1.75 - 1e-12..=2.25 + 1e-12).contains(&dv),
                "seed {seed}: dV {dv}"
            );
            v80s.push(v80);
            dvs.push(dv);
        }
        let se = |width: f64| 4.0 * width / 12f64.sqrt() / (n as f64).sqrt();
        let (m80, _) = mean_sd(&v80s);
        let (mdv, _) = mean_sd(&dvs);
        assert!((m80 - 0.40).abs() < se(0.3), "mean V80 {m80}");
        assert!((mdv - 2.00).abs() < se(0.5), "mean dV {mdv}");
        let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        // Uniform: the extremes of 2 000 draws come within 1 % of the width of each end.
        assert!(min(&v80s) < 0.253 && max(&v80s) > 0.547);
        assert!(min(&dvs) < 1.755 && max(&dvs) > 2.245);
    }

    /// Noise statistics over 100 000 reads of one sensor held at 30 cm (no refresh: time stays
    /// at 0), default parameters. Residuals above 75 mV (5 σ, halfway to the smallest spike)
    /// are spikes: a Gaussian read passes 5 σ with probability 2.9e-7 and a spike falls below
    /// it only if its Gaussian part is below −5 σ, so the split misclassifies ~0.03 reads.
    /// Tolerances are 4 standard errors of each estimate at this sample size.
    #[test]
    fn noise_statistics_over_100k_reads() {
        let mut s = IrSensor::new(IrParams::datasheet(CLOCK_HZ), 2024).unwrap();
        s.update(0, Some(300.0)).unwrap();
        let held = s.held_volts().unwrap();
        assert!(held > 0.5 && held < 4.0, "far from the clamps: {held}");
        let (mut gauss, mut spikes) = (Vec::new(), Vec::new());
        for _ in 0..N_READS {
            let r = s.sample(0, Some(300.0)).unwrap() - held;
            if r > 0.075 {
                spikes.push(r)
            } else {
                gauss.push(r)
            }
        }
        let n = N_READS as f64;
        let rate = spikes.len() as f64 / n;
        let rate_tol = 4.0 * (0.1f64 * 0.9 / n).sqrt(); // 0.0038
        let (g_mean, g_sd) = mean_sd(&gauss);
        let ng = gauss.len() as f64;
        let mean_tol = 4.0 * 0.015 / ng.sqrt(); // ≈ 0.2 mV
        let sd_tol = 4.0 * 0.015 / (2.0 * ng).sqrt(); // ≈ 0.14 mV
        let (s_mean, _) = mean_sd(&spikes);
        // A spike's residual is U[0.15, 0.2] + N(0, σ): sd = sqrt(0.05²/12 + σ²) = 20.8 mV.
        let s_tol = 4.0 * ((0.05f64.powi(2) / 12.0) + 0.015f64.powi(2)).sqrt()
            / (spikes.len() as f64).sqrt();
        eprintln!(
            "noise: {} reads, gaussian mean {:+.4} mV sd {:.4} mV (n {}), spike rate {:.5}, \
             spike mean {:.3} mV (tolerances {:.3} mV, {:.3} mV, {:.5}, {:.3} mV)",
            N_READS,
            g_mean * 1e3,
            g_sd * 1e3,
            gauss.len(),
            rate,
            s_mean * 1e3,
            mean_tol * 1e3,
            sd_tol * 1e3,
            rate_tol,
            s_tol * 1e3
        );
        assert!((rate - 0.1).abs() < rate_tol, "spike rate {rate}");
        assert!(g_mean.abs() < mean_tol, "gaussian mean {g_mean}");
        assert!((g_sd - 0.015).abs() < sd_tol, "gaussian sd {g_sd}");
        assert!((s_mean - 0.175).abs() < s_tol, "spike mean {s_mean}");
    }

    /// Spike heights alone (σ = 0): every read is either exactly the held value or the held
    /// value plus a height in [150, 200] mV, uniform: mean 175 mV within 4 standard errors,
    /// extremes within 1 % of the width of each end.
    #[test]
    fn spike_heights_are_uniform_in_range() {
        let params = IrParams {
            noise_sigma_volts: 0.0,
            ..IrParams::datasheet(CLOCK_HZ)
        };
        let mut s = IrSensor::new(params, 99).unwrap();
        let mut heights = Vec::new();
        s.update(0, Some(500.0)).unwrap();
        let held = s.held_volts().unwrap();
        for _ in 0..N_READS {
            let r = s.sample(0, Some(500.0)).unwrap() - held;
            if r != 0.0 {
                assert!((0.15 - 1e-12..=0.2 + 1e-12).contains(&r), "height {r}");
                heights.push(r);
            }
        }
        let n = heights.len() as f64;
        assert!((n / N_READS as f64 - 0.1).abs() < 4.0 * (0.09 / N_READS as f64).sqrt());
        let (mean, _) = mean_sd(&heights);
        assert!(
            (mean - 0.175).abs() < 4.0 * 0.05 / 12f64.sqrt() / n.sqrt(),
            "mean {mean}"
        );
        let lo = heights.iter().copied().fold(1.0, f64::min);
        let hi = heights.iter().copied().fold(0.0, f64::max);
        assert!(lo < 0.1505 && hi > 0.1995, "{lo} {hi}");
    }

    /// Per-sensor periods and phases over 2 000 sensors: every period inside
    /// 38.3 ± (9.6 − 0.8) ms, mean within 4 standard errors (sd = 17.6 ms / √12); the first
    /// refresh, as a fraction of the period after the jitter margin, uniform on [0, 1)
    /// (mean 0.5 within 4 · 0.2887 / √2000).
    #[test]
    fn per_sensor_periods_and_phases() {
        let n = 2000;
        let (mut periods, mut phases) = (Vec::new(), Vec::new());
        for seed in 0..n {
            let s = IrSensor::new(IrParams::datasheet(CLOCK_HZ), seed).unwrap();
            let p = s.period_ms();
            assert!(
                (29.5 - 1e-9..=47.1 + 1e-9).contains(&p),
                "seed {seed}: {p} ms"
            );
            let first_ms = s.next_refresh_states() as f64 / 25_000.0;
            assert!(
                first_ms >= 0.0 && first_ms <= p + 0.8 + 1e-4,
                "seed {seed}: {first_ms}"
            );
            periods.push(p);
            phases.push(first_ms / (p + 0.8));
        }
        let (mean, sd) = mean_sd(&periods);
        let tol = 4.0 * 17.6 / 12f64.sqrt() / (n as f64).sqrt();
        eprintln!(
            "periods over {n} sensors: mean {mean:.3} ms, sd {sd:.3} ms (tolerance {tol:.3})"
        );
        assert!((mean - 38.3).abs() < tol, "mean period {mean}");
        let (pm, _) = mean_sd(&phases);
        assert!(
            (pm - 0.5).abs() < 4.0 * 0.2887 / (n as f64).sqrt(),
            "mean phase {pm}"
        );
    }

    /// 10 000 consecutive refresh intervals of one sensor. Interval k is P + e_{k+1} − e_k with
    /// e uniform in ±J (J = 0.4 ms), rounded to states:
    /// - every interval lies in [P − 2J, P + 2J] ± 1 state, inside the datasheet's 28.7–47.9 ms;
    /// - the mean telescopes to P + (e_n − e_0)/n: within (2J + 1 state)/n of P, exactly;
    /// - the variance is 2J²/3; its estimate from n 1-dependent squared differences has a
    ///   relative standard error of √(0.8·J⁴/n) / (2J²/3) = 1.342/√n (4 of them allowed);
    /// - the triangular ends are reached: the extremes come within 0.2 J of P ± 2J (each end
    ///   is missed by all 10 000 intervals with probability e^-50).
    #[test]
    fn refresh_intervals_match_the_model() {
        for seed in [3u64, 4, 5] {
            let mut s = IrSensor::new(IrParams::datasheet(CLOCK_HZ), seed).unwrap();
            let p_states = s.period_ms() * 25_000.0;
            let j_states = DEFAULT_PERIOD_JITTER_MS * 25_000.0;
            let n = 10_000;
            let mut intervals = Vec::with_capacity(n);
            let mut t = s.next_refresh_states();
            s.update(t, Some(200.0)).unwrap();
            for _ in 0..n {
                let next = s.next_refresh_states();
                intervals.push((next - t) as f64);
                s.update(next, Some(200.0)).unwrap();
                t = next;
            }
            for &iv in &intervals {
                assert!(
                    iv >= p_states - 2.0 * j_states - 1.0 && iv <= p_states + 2.0 * j_states + 1.0
                );
                assert!((28.7 * 25_000.0..=47.9 * 25_000.0).contains(&iv), "{iv}");
            }
            let (mean, sd) = mean_sd(&intervals);
            assert!(
                (mean - p_states).abs() <= (2.0 * j_states + 1.0) / n as f64,
                "mean {mean} vs {p_states}"
            );
            let var_ratio = sd * sd / (2.0 * j_states * j_states / 3.0);
            assert!(
                (var_ratio - 1.0).abs() < 4.0 * 1.342 / (n as f64).sqrt(),
                "variance ratio {var_ratio}"
            );
            let lo = intervals.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = intervals.iter().copied().fold(0.0, f64::max);
            assert!(lo < p_states - 1.8 * j_states && hi > p_states + 1.8 * j_states);
            eprintln!(
                "seed {seed}: P {:.4} ms, {n} intervals: mean {:.4} ms, sd {:.4} ms (model {:.4}), \
                 min {:.4}, max {:.4} ms",
                p_states / 25e3,
                mean / 25e3,
                sd / 25e3,
                (2.0f64 / 3.0).sqrt() * DEFAULT_PERIOD_JITTER_MS,
                lo / 25e3,
                hi / 25e3
            );
        }
    }

    /// Pooled over 500 sensors × 200 intervals (the model's whole distribution): every interval
    /// inside the datasheet's 38.3 ± 9.6 ms; the pooled mean is 38.3 ms within 4 standard
    /// errors of the per-sensor period's mean (17.6 ms / √12 / √500 = 0.227 ms; the jitter's
    /// contribution to a sensor's mean is below 1e-5 ms).
    #[test]
    fn pooled_refresh_intervals_match_the_datasheet() {
        let mut all = Vec::new();
        for seed in 1000..1500u64 {
            let mut s = IrSensor::new(IrParams::datasheet(CLOCK_HZ), seed).unwrap();
            let mut t = s.next_refresh_states();
            s.update(t, None).unwrap();
            for _ in 0..200 {
                let next = s.next_refresh_states();
                all.push((next - t) as f64 / 25_000.0);
                s.update(next, None).unwrap();
                t = next;
            }
        }
        let lo = all.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = all.iter().copied().fold(0.0, f64::max);
        assert!(lo >= 28.7 && hi <= 47.9, "{lo} {hi}");
        let (mean, sd) = mean_sd(&all);
        eprintln!(
            "pooled intervals: n {}, mean {mean:.3} ms, sd {sd:.3} ms, min {lo:.3}, max {hi:.3} ms",
            all.len()
        );
        assert!(
            (mean - 38.3).abs() < 4.0 * 17.6 / 12f64.sqrt() / 500f64.sqrt(),
            "{mean}"
        );
    }

    #[test]
    fn schedule_does_not_depend_on_when_the_caller_looks() {
        let mut often = IrSensor::new(IrParams::datasheet(CLOCK_HZ), 17).unwrap();
        let mut rarely = often.clone();
        let end = 25_000_000u64 * 60; // one minute
        let mut t = 0;
        while t <= end {
            often.update(t, Some(300.0)).unwrap();
            t += 25_000; // every millisecond
        }
        rarely.update(0, Some(300.0)).unwrap();
        rarely.update(end, Some(300.0)).unwrap();
        assert_eq!(often.next_refresh_states(), rarely.next_refresh_states());
        // And jumping to the end of time does not hang or panic.
        rarely.update(u64::MAX, None).unwrap();
        assert!(rarely.sample(u64::MAX, Some(1.0)).unwrap().is_finite());
    }

    #[test]
    fn same_seed_same_readings_different_seed_different() {
        let run = |seed: u64| {
            let mut s = IrSensor::new(IrParams::datasheet(CLOCK_HZ), seed).unwrap();
            (0..2000u64)
                .map(|i| s.sample(i * 6_650, Some(100.0 + (i % 700) as f64)).unwrap())
                .collect::<Vec<f64>>()
        };
        let a = run(1);
        assert_eq!(a, run(1));
        let b = run(2);
        assert_ne!(a, b);
        // Not just a shifted copy: most reads differ.
        assert!(a.iter().zip(&b).filter(|(x, y)| x != y).count() > 1900);
    }

    #[test]
    fn bad_parameters_are_errors_naming_the_parameter() {
        type Edit = fn(&mut IrParams);
        let cases: [(&str, Edit); 22] = [
            ("clock_hz", |p| p.clock_hz = 0),
            ("clock_hz", |p| p.clock_hz = 200_000_000),
            ("v_80cm_min_volts", |p| p.v_80cm_min_volts = -0.1),
            ("v_80cm_min_volts", |p| p.v_80cm_min_volts = f64::NAN),
            ("v_80cm_max_volts", |p| p.v_80cm_max_volts = 0.2),
            ("dv_80_to_10cm_min_volts", |p| {
                p.dv_80_to_10cm_min_volts = 0.0
            }),
            ("dv_80_to_10cm_max_volts", |p| {
                p.dv_80_to_10cm_max_volts = 1.0
            }),
            ("dv_80_to_10cm_max_volts", |p| {
                p.dv_80_to_10cm_max_volts = f64::INFINITY
            }),
            ("period_mean_ms", |p| p.period_mean_ms = 0.0),
            ("period_mean_ms", |p| p.period_mean_ms = -38.3),
            ("period_mean_ms", |p| p.period_mean_ms = f64::NAN),
            ("period_spread_ms", |p| p.period_spread_ms = -1.0),
            ("period_spread_ms", |p| p.period_spread_ms = 38.0),
            ("period_jitter_ms", |p| p.period_jitter_ms = 5.0),
            ("period_jitter_ms", |p| p.period_jitter_ms = -0.1),
            ("noise_sigma_volts", |p| p.noise_sigma_volts = -0.015),
            ("noise_sigma_volts", |p| p.noise_sigma_volts = f64::NAN),
            ("spike_probability", |p| p.spike_probability = 1.5),
            ("spike_probability", |p| p.spike_probability = -0.1),
            ("spike_min_volts", |p| p.spike_min_volts = -0.15),
            ("spike_max_volts", |p| p.spike_max_volts = 0.1),
            ("spike_max_volts", |p| p.spike_max_volts = f64::NAN),
        ];
        for (name, edit) in cases {
            let mut p = IrParams::datasheet(CLOCK_HZ);
            edit(&mut p);
            match IrSensor::new(p, 0) {
                Err(e @ SensorError::ParamOutOfRange { name: got, .. }) => {
                    assert_eq!(got, name);
                    let msg = e.to_string();
                    assert!(msg.contains(name) && msg.contains("valid is"), "{msg}");
                }
                other => panic!("{name}: expected an error, got {other:?}"),
            }
        }
        assert!(IrParams::datasheet(CLOCK_HZ).validate().is_ok());
        assert!(IrParams::ideal(CLOCK_HZ).validate().is_ok());
    }

    #[test]
    fn bad_calls_are_errors_and_change_nothing() {
        let mut s = IrSensor::new(IrParams::datasheet(CLOCK_HZ), 5).unwrap();
        s.sample(1_000, Some(200.0)).unwrap();
        let before = s.clone();
        let err = s.sample(999, Some(200.0)).unwrap_err();
        assert_eq!(
            err,
            SensorError::TimeBackwards {
                now_states: 999,
                last_states: 1_000
            }
        );
        assert!(err.to_string().contains("999"));
        assert!(matches!(
            s.sample(2_000, Some(f64::NAN)),
            Err(SensorError::BadDistance { .. })
        ));
        assert!(matches!(
            s.update(2_000, Some(-3.0)),
            Err(SensorError::BadDistance { .. })
        ));
        // The failed calls drew no noise and moved no clock.
        let mut reference = before;
        for t in [1_000, 5_000_000, 9_000_000] {
            assert_eq!(s.sample(t, Some(250.0)), reference.sample(t, Some(250.0)));
        }
    }

    #[test]
    fn fold_back_ambiguity_holds_for_every_sensor() {
        for seed in 0..50 {
            let s = IrSensor::new(IrParams::datasheet(CLOCK_HZ), seed).unwrap();
            let v5 = s.curve_volts(Some(50.0)).unwrap();
            // The same affine map on both branches keeps the nominal twin at 12.17 cm.
            let twin_mm = far_branch_cm_at_volts(nominal_volts(Some(50.0)).unwrap()) * 10.0;
            assert!(twin_mm > 100.0);
            assert!((s.curve_volts(Some(twin_mm)).unwrap() - v5).abs() < 1e-9);
        }
    }

    proptest! {
        #[test]
        fn every_sensor_far_branch_is_decreasing(seed: u64, a in 80.0f64..10_000.0, b in 80.0f64..10_000.0) {
            prop_assume!(a != b);
            let s = IrSensor::new(IrParams::datasheet(CLOCK_HZ), seed).unwrap();
            let (near, far) = if a < b { (a, b) } else { (b, a) };
            let (vn, vf) = (s.curve_volts(Some(near)).unwrap(), s.curve_volts(Some(far)).unwrap());
            // Strict unless both clamp at 0 V (a low-offset sensor, far away).
            prop_assert!(vn > vf || (vn == 0.0 && vf == 0.0), "{vn} {vf}");
            prop_assert!(near >= FAR_BRANCH_MIN_MM);
        }

        #[test]
        fn reads_stay_on_the_supply_range(
            seed: u64,
            steps in proptest::collection::vec((0u64..2_000_000, proptest::option::of(0.0f64..1e6)), 1..50),
        ) {
            let mut s = IrSensor::new(IrParams::datasheet(CLOCK_HZ), seed).unwrap();
            let mut t = 0u64;
            for (dt, d) in steps {
                t += dt;
                let v = s.sample(t, d).unwrap();
                prop_assert!((0.0..=SUPPLY_VOLTS).contains(&v));
            }
        }
    }
}
