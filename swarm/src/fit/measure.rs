//! [`measure`]: runs the controller (the firmware on the core, or the Rust model) on the rig,
//! and the other beside it when asked, and reports.
//!
//! With the model, the phases are the model's own accounting; RAM is its placement of the same
//! items and ROM the firmware image's size (the model has no image of its own).

use super::config::{
    FitConfig, FitError, PHASE_ADC, PHASE_FORWARD, PHASE_INPUT, PHASE_MOTORS, PHASE_OTHER,
    PHASE_SAVE, PHASE_TICKS, PHASE_UPDATE,
};
use super::firmware::measure_firmware;
use super::meter::{FitMeter, Measured, Rig};
use super::report::{FitReport, MemLine};
use super::verdict::report;
use crate::scenario::ControllerKind;
use robot_board::model::{Controller, PhaseStates};

/// Runs the model controller for `cfg.steps` step periods.
pub(super) fn measure_model(cfg: &FitConfig) -> Result<Measured, FitError> {
    let mut controller = Controller::new(cfg.controller.clone())?;
    let mut rig = Rig::new(cfg)?;
    let boot = controller.boot(&mut rig.mcu)?;
    // (the step's phases, the sleep's busy states, the sleep's ticks) for each step period:
    // the step and the sleep after it, up to the next step (the firmware's periods, too, run
    // from one step's tick to the next).
    let mut per_step: Vec<(PhaseStates, u64, u64)> = Vec::with_capacity(cfg.steps as usize);
    controller.sleep_until_step(&mut rig.mcu)?;
    let mut meter = FitMeter::new(&rig.mcu);
    let period_s = cfg.controller.step_period_s;
    for _ in 0..cfg.steps {
        rig.move_world();
        let step = controller.step(&mut rig.mcu)?;
        let sleep = controller.sleep_until_step(&mut rig.mcu)?;
        per_step.push((step.phases, sleep.busy_states, sleep.ticks));
        meter.period(&mut rig.mcu, period_s);
    }
    let isr = controller.isr_states().unwrap_or(0);
    let col = |f: &dyn Fn(&(PhaseStates, u64, u64)) -> u64| -> Vec<u64> {
        per_step.iter().map(f).collect()
    };
    // A step period: the step (with the ticks taken during it) and the sleep after it (its
    // ticks, SLEEP and main's test after each).
    let phases = vec![
        (PHASE_ADC.to_string(), col(&|s| s.0.adc)),
        (PHASE_INPUT.to_string(), col(&|s| s.0.input)),
        (PHASE_UPDATE.to_string(), col(&|s| s.0.update)),
        (PHASE_FORWARD.to_string(), col(&|s| s.0.forward)),
        (PHASE_MOTORS.to_string(), col(&|s| s.0.motors)),
        (PHASE_SAVE.to_string(), col(&|s| s.0.save)),
        (PHASE_TICKS.to_string(), col(&|s| s.2 * isr + s.0.isr)),
        (
            PHASE_OTHER.to_string(),
            col(&|s| s.0.main + s.1.saturating_sub(s.2 * isr)),
        ),
    ];
    let ram = controller
        .ram()
        .items()
        .iter()
        .map(|p| MemLine {
            item: p.name.clone(),
            addr: p.addr,
            bytes: p.bytes,
        })
        .collect();
    let busy = col(&|s| s.0.work() + s.0.isr + s.1);
    let energy = Some(meter.finish(&rig.mcu, busy.iter().sum()));
    Ok(Measured {
        source: "model".to_string(),
        boot_states: boot.states,
        phases,
        busy,
        ram,
        stack_high_water: None,
        stack: None,
        energy,
        unmodelled: Vec::new(),
    })
}

/// Runs the controller as [`FitConfig`] says and reports.
///
/// # Errors
/// [`FitError`] when the configuration is impossible, the image unusable or it stops.
pub fn measure(cfg: &FitConfig) -> Result<FitReport, FitError> {
    let run = |kind| match kind {
        ControllerKind::Firmware => measure_firmware(cfg),
        ControllerKind::Model => measure_model(cfg),
    };
    let main = run(cfg.kind)?;
    let other = if cfg.compare {
        Some(run(match cfg.kind {
            ControllerKind::Firmware => ControllerKind::Model,
            ControllerKind::Model => ControllerKind::Firmware,
        })?)
    } else {
        None
    };
    Ok(report(cfg, &main, other.as_ref()))
}
