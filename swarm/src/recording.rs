//! Recording a run for the browser viewer (`h8swarm run --replay`).
//!
//! A [`Recorder`] is handed each step of one run (condition and repeat) and keeps every
//! `stride`-th step as a **frame**: for every robot its pose, the behaviour its motors run, its
//! four readings in du, its bumper switches, E = D(t) − D(t−1), whether it is held and how it moves, whether it
//! saved a record, whether it is dead, and its CPU load; and every `weights_every`-th frame its
//! weights (when the controller's are readable). Frames go to a file of the run's own in the
//! staging folder as they are made, so recording holds no more memory than one frame.
//!
//! Each quantity goes to a file of its own (a *plane*: one value per robot per frame), so that
//! the page's writer (the CLI's `viewer` module) can lay a run out plane after plane, which
//! compresses about a third better than frame after frame. The format, byte by byte, is in
//! `docs/viewer.md`.
//!
//! Quantisation: positions in units of 1 mm (of the arena's side / 65 535 in arenas wider than
//! 65 m); headings in 1/256 of a turn (1.4°). x and y are stored as second differences over
//! the frames (a robot driving on gives about 0), headings as first differences, weights as
//! differences from the robot's previous snapshot (all wrapping), which gzip packs well. E is
//! stored only when frames skip steps (with a stride of 1 the page takes it from consecutive
//! D's). The output is a pure function of the runs: the same bytes for any thread count.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::output_error::OutputError;
use crate::robot::Condition;

/// The file's first four bytes (before compression).
pub const MAGIC: &[u8; 4] = b"H8RP";
/// Its format version.
pub const VERSION: u16 = 1;
/// The planes of a run, in the order of the data: (name, bytes per robot per frame). `e` is
/// left out when the stride is 1.
pub const PLANES: [(&str, usize); 11] = [
    ("x", 2),
    ("y", 2),
    ("heading", 1),
    ("flags", 1),
    ("bumpers", 1),
    ("p0", 1),
    ("p1", 1),
    ("p2", 1),
    ("p3", 1),
    ("e", 2),
    ("load", 1),
];

/// The position quantum for an arena of `width_m` × `height_m`: 1 mm, or the larger side over
/// 65 535 when that is coarser.
#[must_use]
pub fn quantum_m(width_m: f64, height_m: f64) -> f64 {
    (width_m.max(height_m) / 65535.0).max(0.001)
}
/// The index of E in [`PLANES`].
pub const E_PLANE: usize = 9;

/// Behaviour codes in a frame (the flags' low three bits).
pub mod behaviour {
    /// Both wheels forward, equal duty.
    pub const FORWARD: u8 = 0;
    /// Both wheels reverse.
    pub const BACKWARD: u8 = 1;
    /// Both forward, the left slower.
    pub const TURN_LEFT: u8 = 2;
    /// Both forward, the right slower.
    pub const TURN_RIGHT: u8 = 3;
    /// Anything else (coasting, braking, a dead robot).
    pub const OTHER: u8 = 4;
}

/// Flag bits of a frame besides the behaviour.
pub mod flag {
    /// Held in place ([`crate::motion`]).
    pub const HELD: u8 = 1 << 3;
    /// The robot wrote an EEPROM record in the step.
    pub const SAVED: u8 = 1 << 4;
    /// The robot's controller failed (`--keep-going`).
    pub const DEAD: u8 = 1 << 5;
    /// The two high bits: the step's motion class ([`crate::motion::MotionClass::code`]: 0
    /// exploring, 1 shuttling, 2 circling, 3 held), shifted by [`MOTION_SHIFT`].
    pub const MOTION: u8 = 0b1100_0000;
    /// Where the motion class sits in the flags.
    pub const MOTION_SHIFT: u32 = 6;
}

/// The behaviour code of a pair of wheel commands (see [`behaviour`]).
#[must_use]
pub fn behaviour_of(left: &world::WheelCommand, right: &world::WheelCommand) -> u8 {
    use world::Direction::{Forward, Reverse};
    match (left.direction, right.direction) {
        (Forward, Forward) if (left.duty - right.duty).abs() < 0.05 => behaviour::FORWARD,
        (Forward, Forward) if left.duty < right.duty => behaviour::TURN_LEFT,
        (Forward, Forward) => behaviour::TURN_RIGHT,
        (Reverse, Reverse) => behaviour::BACKWARD,
        _ => behaviour::OTHER,
    }
}

/// What one robot did in a step, as the recorder takes it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RobotStep {
    /// Centre, metres.
    pub x_m: f64,
    /// Centre, metres.
    pub y_m: f64,
    /// Heading, radians.
    pub heading_rad: f64,
    /// Behaviour code ([`behaviour`]).
    pub behaviour: u8,
    /// Bumpers front, rear, left, right.
    pub bumpers: [bool; 4],
    /// The four readings, du.
    pub p: [u8; 4],
    /// D(t), du.
    pub d: i16,
    /// Held now.
    pub held: bool,
    /// The class of its latest completed step (none before the first).
    pub motion: Option<crate::motion::MotionClass>,
    /// Saved a record in the step.
    pub saved: bool,
    /// Dead.
    pub dead: bool,
    /// CPU load over the step's period, percent.
    pub load_percent: f64,
}

/// What to record of an experiment's runs (`h8swarm run --replay`): the frames' options, the
/// repeats recorded (of every condition) and the first robots recorded.
#[derive(Clone, Debug)]
pub struct ReplayPlan {
    /// How each recorded run is recorded.
    pub opts: RecordOptions,
    /// The repeats recorded, in increasing order.
    pub repeats: Vec<u32>,
    /// The first robots recorded.
    pub robots: usize,
}

/// What to record.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecordOptions {
    /// Keep every this many steps (at least 1).
    pub stride: u32,
    /// Weights every this many frames (at least 1).
    pub weights_every: u32,
}

impl RecordOptions {
    /// Every step for runs up to 5 000 steps, else a stride that keeps about 5 000 frames;
    /// weights about 20 times a run.
    #[must_use]
    pub fn for_steps(steps: u32, stride: Option<u32>) -> Self {
        let stride = stride.unwrap_or_else(|| steps.div_ceil(5000)).max(1);
        let frames = steps.div_ceil(stride);
        Self {
            stride,
            weights_every: frames.div_ceil(20).max(1),
        }
    }
}

/// One run's recorder.
#[derive(Debug)]
pub struct Recorder {
    opts: RecordOptions,
    quantum_m: f64,
    frames: u32,
    weight_frames: Vec<u32>,
    last_d: Vec<Option<i16>>,
    prev: Vec<(u16, u16, u8)>,
    prev_step: Vec<(u16, u16)>,
    prev_weights: Vec<Vec<i16>>,
    planes: Vec<BufWriter<std::fs::File>>,
    weights_out: BufWriter<std::fs::File>,
    paths: Vec<PathBuf>,
}

/// Where a run's planes (in the order of [`PLANES`], `e` included) and its weights (last) go
/// in the staging folder.
#[must_use]
pub fn part_paths(stage: &Path, condition: Condition, repeat: u32) -> Vec<PathBuf> {
    PLANES
        .iter()
        .map(|(name, _)| name.to_string())
        .chain(std::iter::once("weights".to_string()))
        .map(|plane| stage.join(format!(".replay-{}-{repeat}-{plane}.bin", condition.name())))
        .collect()
}

impl Recorder {
    /// A recorder for a run in an arena of `width_m` × `height_m`, writing to `paths` (as
    /// [`part_paths`] gives them).
    ///
    /// # Errors
    /// A file that cannot be created (an output error).
    pub fn new(
        opts: RecordOptions,
        (width_m, height_m): (f64, f64),
        paths: Vec<PathBuf>,
    ) -> Result<Self> {
        if paths.len() != PLANES.len() + 1 {
            bail!("a recorder needs {} files", PLANES.len() + 1);
        }
        let create = |p: &Path| {
            std::fs::File::create(p)
                .map(BufWriter::new)
                .map_err(anyhow::Error::new)
                .context(OutputError::cannot_write(p))
        };
        let mut planes = Vec::with_capacity(PLANES.len());
        for p in &paths[..PLANES.len()] {
            planes.push(create(p)?);
        }
        Ok(Self {
            weights_out: create(&paths[PLANES.len()])?,
            planes,
            opts,
            quantum_m: quantum_m(width_m, height_m),
            frames: 0,
            weight_frames: Vec::new(),
            last_d: Vec::new(),
            prev: Vec::new(),
            prev_step: Vec::new(),
            prev_weights: Vec::new(),
            paths,
        })
    }

    /// Takes step `k` of every robot; keeps it when `k` is a multiple of the stride. `weights`
    /// is asked for only when a weight snapshot is due (and then once per robot).
    ///
    /// # Errors
    /// A file that cannot be written.
    pub fn step(
        &mut self,
        k: u32,
        robots: &[RobotStep],
        weights: &mut dyn FnMut(usize) -> Option<Vec<i16>>,
    ) -> Result<()> {
        let n = robots.len();
        if self.last_d.len() != n {
            self.last_d = vec![None; n];
            self.prev = vec![(0, 0, 0); n];
            self.prev_step = vec![(0, 0); n];
        }
        let e: Vec<i16> = robots
            .iter()
            .zip(&mut self.last_d)
            .map(|(r, last)| {
                let e = last.map_or(0, |l| r.d.saturating_sub(l));
                *last = Some(r.d);
                e
            })
            .collect();
        if !k.is_multiple_of(self.opts.stride) {
            return Ok(());
        }
        let q = |v: f64| (v / self.quantum_m).round().clamp(0.0, 65535.0) as u16;
        let turn = std::f64::consts::TAU;
        let now: Vec<(u16, u16, u8)> = robots
            .iter()
            .map(|r| {
                (
                    q(r.x_m),
                    q(r.y_m),
                    ((r.heading_rad.rem_euclid(turn) / turn * 256.0).round() as i64 & 0xFF) as u8,
                )
            })
            .collect();
        let mut bufs: Vec<Vec<u8>> = PLANES
            .iter()
            .map(|(_, w)| Vec::with_capacity(n * w))
            .collect();
        for (((c, p), r), d) in now
            .iter()
            .zip(&self.prev)
            .zip(robots)
            .zip(&mut self.prev_step)
        {
            let step = (c.0.wrapping_sub(p.0), c.1.wrapping_sub(p.1));
            bufs[0].extend_from_slice(&step.0.wrapping_sub(d.0).to_le_bytes());
            bufs[1].extend_from_slice(&step.1.wrapping_sub(d.1).to_le_bytes());
            *d = step;
            bufs[2].push(c.2.wrapping_sub(p.2));
            bufs[3].push(
                (r.behaviour & 7)
                    | if r.held { flag::HELD } else { 0 }
                    | r.motion.map_or(0, |m| m.code() << flag::MOTION_SHIFT)
                    | if r.saved { flag::SAVED } else { 0 }
                    | if r.dead { flag::DEAD } else { 0 },
            );
            bufs[4].push(
                r.bumpers
                    .iter()
                    .enumerate()
                    .fold(0u8, |b, (i, &on)| b | (u8::from(on) << i)),
            );
            for s in 0..4 {
                bufs[5 + s].push(r.p[s]);
            }
            bufs[10].push((r.load_percent * 10.0).round().clamp(0.0, 255.0) as u8);
        }
        if self.opts.stride > 1 {
            for e in &e {
                bufs[9].extend_from_slice(&e.to_le_bytes());
            }
        }
        for (i, (buf, out)) in bufs.iter().zip(&mut self.planes).enumerate() {
            out.write_all(buf)
                .map_err(anyhow::Error::new)
                .with_context(|| OutputError::cannot_write(&self.paths[i]))?;
        }
        self.prev = now;
        if self.frames.is_multiple_of(self.opts.weights_every) {
            let mut all = Vec::new();
            for i in 0..n {
                match weights(i) {
                    Some(w) => all.push(w),
                    None => {
                        all.clear();
                        break;
                    }
                }
            }
            if all.len() == n && n > 0 {
                if self.prev_weights.len() != n {
                    self.prev_weights = all.iter().map(|w| vec![0; w.len()]).collect();
                }
                let mut bytes = Vec::new();
                for (w, prev) in all.iter().zip(&mut self.prev_weights) {
                    prev.resize(w.len(), 0);
                    for (v, p) in w.iter().zip(prev.iter_mut()) {
                        bytes.extend_from_slice(&v.wrapping_sub(*p).to_le_bytes());
                        *p = *v;
                    }
                }
                self.weights_out
                    .write_all(&bytes)
                    .map_err(anyhow::Error::new)
                    .with_context(|| OutputError::cannot_write(&self.paths[PLANES.len()]))?;
                self.weight_frames.push(self.frames);
            }
        }
        self.frames += 1;
        Ok(())
    }

    /// Flushes the files; returns the run's frame count and the frames with weights.
    ///
    /// # Errors
    /// A file that cannot be written.
    pub fn finish(mut self) -> Result<(u32, Vec<u32>)> {
        for (i, out) in self
            .planes
            .iter_mut()
            .chain(std::iter::once(&mut self.weights_out))
            .enumerate()
        {
            out.flush()
                .map_err(anyhow::Error::new)
                .with_context(|| OutputError::cannot_write(&self.paths[i]))?;
        }
        Ok((self.frames, self.weight_frames))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn behaviours_follow_the_wheels() {
        use world::{Direction, WheelCommand};
        let w = |duty, direction| WheelCommand { duty, direction };
        let f = |d| w(d, Direction::Forward);
        assert_eq!(behaviour_of(&f(1.0), &f(1.0)), behaviour::FORWARD);
        assert_eq!(behaviour_of(&f(0.3), &f(1.0)), behaviour::TURN_LEFT);
        assert_eq!(behaviour_of(&f(1.0), &f(0.3)), behaviour::TURN_RIGHT);
        let r = w(1.0, Direction::Reverse);
        assert_eq!(behaviour_of(&r, &r), behaviour::BACKWARD);
        let c = w(0.0, Direction::Coast);
        assert_eq!(behaviour_of(&c, &c), behaviour::OTHER);
    }

    #[test]
    fn strides_keep_about_5000_frames() {
        assert_eq!(RecordOptions::for_steps(2000, None).stride, 1);
        assert_eq!(RecordOptions::for_steps(10_000, None).stride, 2);
        assert_eq!(RecordOptions::for_steps(1_000_000, None).stride, 200);
        assert_eq!(RecordOptions::for_steps(10_000, Some(7)).stride, 7);
        assert_eq!(RecordOptions::for_steps(100, None).weights_every, 5);
    }
}
