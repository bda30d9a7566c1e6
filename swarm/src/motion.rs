//! Where a robot goes: each robot-step classified from the robot's positions (not from how much
//! it twitches), and the exploration quantities of docs/claims.md.
//!
//! A robot's centre is looked at once a step, at the step instants. From the last
//! [`HELD_STEPS`] + 1 positions a [`MotionTracker`] tells, at every step, which of four kinds of
//! motion the robot is in ([`MotionClass`]; the first that applies):
//!
//! * **held**: in place. Its positions over the last [`HELD_STEPS`] steps all lie within
//!   [`HELD_RADIUS_M`] of their mean (so a robot wedged against a wall that jitters or rocks
//!   counts however much path it racks up), or, sooner, its centre travelled less than
//!   [`STILL_PATH_M`] over the last [`LAG_STEPS`] steps (a robot pinned still is held from its
//!   20th still step, not its 100th);
//! * **exploring**: over the last [`LAG_STEPS`] steps its net displacement is at least
//!   [`PROGRESS_MIN`] of the path it drove: it gets somewhere;
//! * **shuttling**: less net displacement than that, and the path reversed at least once
//!   (a step pointing more than 90° away from the previous step that moved at least
//!   [`REVERSAL_STEP_MIN_M`]): forward and back;
//! * **circling**: less net displacement than that without a reversal: the path can only
//!   have come back by turning round (a loop, a figure of eight).
//!
//! The thresholds are argued in docs/claims.md. Besides the class, every step gives the
//! exploration quantities ([`MotionStep`]): the net displacement over the lag divided by the
//! lag (so that summed over steps it is the *net metres*, never more than the path: a straight
//! driver's are its path but for the lag's first steps, a shuttler's about none), the squared
//! displacement at the lags [`MSD_LAGS`] (their means are the mean squared displacement: growing as the lag for diffusion, as its square for
//! straight driving, not at all in confinement), and the **area covered**: the floor is cut
//! into square cells of [`CELL_M`] (about a body), and a step counts the cells the robot
//! enters that it had not been in for [`FRESH_STEPS`] steps (*fresh* cells) and those it had
//! never been in (*new* cells).
//!
//! The definitions these replace, kept for comparison (the tests show the robots that fool
//! them): *moving*, at least [`crate::collisions::MOVING_MIN_MM`] in a step, counts a shuttler
//! as moving all the time; *stuck*, less than 1 mm of path over 100 steps, never catches a
//! robot that jitters a millimetre a step in place.

use std::collections::HashMap;

/// Steps a robot's positions are looked back on to call it held.
pub const HELD_STEPS: usize = 100;
/// A robot whose positions over [`HELD_STEPS`] steps all lie within this distance of their
/// mean is held, metres: less than a free robot drives in one step (44–67 mm).
pub const HELD_RADIUS_M: f64 = 0.05;
/// A robot whose centre travelled less than this over [`LAG_STEPS`] steps is held, metres
/// (1 mm a step on average; a free robot drives about 1 m in that time).
pub const STILL_PATH_M: f64 = 0.02;
/// The lag of the net displacement, steps: 9 s in the arena, in which a free robot drives
/// about 1 m (more than half the arena's side) and a turning one goes once round.
pub const LAG_STEPS: usize = 20;
/// A robot whose net displacement over [`LAG_STEPS`] steps is at least this fraction of the
/// path it drove in them explores.
pub const PROGRESS_MIN: f64 = 0.2;
/// Steps shorter than this, metres, have no direction that counts for a reversal (a pressed
/// robot's jitter points anywhere).
pub const REVERSAL_STEP_MIN_M: f64 = 0.002;
/// The lags of the mean squared displacement, steps.
pub const MSD_LAGS: [usize; 3] = [1, 10, 100];
/// The side of a cell of the area covered, metres: about a body (0.23 m × 0.18 m); it divides
/// the paper's 1.8 m arena into 9 × 9 cells.
pub const CELL_M: f64 = 0.2;
/// A cell the robot enters counts as fresh when it had not been in it for this many steps.
pub const FRESH_STEPS: u32 = 100;

/// The positions kept: the current one and [`HELD_STEPS`] before it.
const HISTORY: usize = HELD_STEPS + 1;

/// What kind of motion a robot-step is (see the module's documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MotionClass {
    /// Net displacement over the lag at least [`PROGRESS_MIN`] of the path.
    Exploring,
    /// Little net displacement, with a reversal.
    Shuttling,
    /// Little net displacement, without a reversal.
    Circling,
    /// In place.
    Held,
}

impl MotionClass {
    /// All four, in the order of their codes.
    pub const ALL: [MotionClass; 4] = [
        MotionClass::Exploring,
        MotionClass::Shuttling,
        MotionClass::Circling,
        MotionClass::Held,
    ];

    /// Its code in a recording's flags (two bits): 0 exploring, 1 shuttling, 2 circling,
    /// 3 held.
    #[must_use]
    pub const fn code(self) -> u8 {
        match self {
            MotionClass::Exploring => 0,
            MotionClass::Shuttling => 1,
            MotionClass::Circling => 2,
            MotionClass::Held => 3,
        }
    }

    /// Its name in the outputs.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            MotionClass::Exploring => "exploring",
            MotionClass::Shuttling => "shuttling",
            MotionClass::Circling => "circling",
            MotionClass::Held => "held",
        }
    }
}

/// One robot-step as the tracker sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionStep {
    /// The kind of motion.
    pub class: MotionClass,
    /// How far the centre moved in the step (straight line between the step instants), metres.
    pub step_m: f64,
    /// Net displacement over the last [`LAG_STEPS`] steps (fewer at the start of a run) divided
    /// by [`LAG_STEPS`], metres per step. Always by the whole lag: each step is then counted at
    /// most [`LAG_STEPS`] times over [`LAG_STEPS`], so a robot's net metres never exceed its
    /// path (divided by the shorter lag at the start, a robot that drove a few steps and stopped
    /// had its first steps counted up to 3.6 times).
    pub net_m: f64,
    /// Squared displacement over each of [`MSD_LAGS`], square metres, once the run is that
    /// long.
    pub sq_disp_m2: [Option<f64>; 3],
    /// Cells entered in the step that the robot had not been in for [`FRESH_STEPS`] steps
    /// (its first step counts the cell it started in too).
    pub fresh_cells: u32,
    /// Cells entered in the step that the robot had never been in.
    pub new_cells: u32,
}

/// A cell of the floor, packed into one key.
fn cell_of(x: f64, y: f64) -> u64 {
    let ix = (x / CELL_M).floor() as i32;
    let iy = (y / CELL_M).floor() as i32;
    (u64::from(ix as u32) << 32) | u64::from(iy as u32)
}

/// Distance between two points (their coordinates differ by at most a few hundred metres, so
/// the plain formula cannot overflow; `hypot`'s care costs five times as much).
fn dist(dx: f64, dy: f64) -> f64 {
    (dx * dx + dy * dy).sqrt()
}

/// One robot's recent positions and the cells it has been in.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MotionTracker {
    /// The last [`HISTORY`] positions, position `s` at `s % HISTORY`.
    ring: Vec<(f64, f64)>,
    /// The last [`LAG_STEPS`] steps: the step ending at position `s` at `s % LAG_STEPS`, its
    /// displacement and its length.
    steps: Vec<(f64, f64, f64)>,
    /// Positions recorded: the start is position 0, the end of step k position k + 1.
    seen: u32,
    /// The cell of the latest position.
    cell: u64,
    /// For every cell left, the last position number at which the robot was in it.
    left: HashMap<u64, u32>,
}

impl MotionTracker {
    /// A tracker that has seen nothing.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Position `s` (one of the last [`HISTORY`]).
    fn at(&self, s: u32) -> (f64, f64) {
        self.ring[s as usize % HISTORY]
    }

    /// Records where the robot starts (before its first step).
    pub fn start(&mut self, x: f64, y: f64) {
        self.ring = vec![(x, y); HISTORY];
        self.steps = vec![(0.0, 0.0, 0.0); LAG_STEPS];
        self.seen = 1;
        self.cell = cell_of(x, y);
        self.left.clear();
    }

    /// Whether [`MotionTracker::start`] was called.
    #[must_use]
    pub fn started(&self) -> bool {
        self.seen > 0
    }

    /// Records where the robot is at the end of its next step and says what the step was.
    /// Without a start, the first position recorded is the start and the step is still.
    pub fn record(&mut self, x: f64, y: f64) -> MotionStep {
        if self.seen == 0 {
            self.start(x, y);
        }
        let s = self.seen;
        let prev = self.at(s - 1);
        let (dx, dy) = (x - prev.0, y - prev.1);
        let step_m = dist(dx, dy);
        self.ring[s as usize % HISTORY] = (x, y);
        self.steps[s as usize % LAG_STEPS] = (dx, dy, step_m);
        self.seen += 1;
        let lag = (s as usize).min(LAG_STEPS) as u32;
        let back = self.at(s - lag);
        let net = dist(x - back.0, y - back.1);
        // The lag's steps in order, from the oldest.
        let mut path = 0.0;
        let mut reversals = 0u32;
        let mut heading: Option<(f64, f64)> = None;
        // The ring from the oldest of them on, wrapping round (no division per step).
        let first = (s - lag + 1) as usize % LAG_STEPS;
        let (tail, head) = self.steps.split_at(first);
        for &(ex, ey, len) in head.iter().chain(tail).take(lag as usize) {
            path += len;
            if len >= REVERSAL_STEP_MIN_M {
                if let Some(h) = heading
                    && h.0 * ex + h.1 * ey < 0.0
                {
                    reversals += 1;
                }
                heading = Some((ex, ey));
            }
        }
        let still = path < STILL_PATH_M * f64::from(lag) / LAG_STEPS as f64;
        let class = if still || self.in_disc(s) {
            MotionClass::Held
        } else if net >= PROGRESS_MIN * path {
            MotionClass::Exploring
        } else if reversals > 0 {
            MotionClass::Shuttling
        } else {
            MotionClass::Circling
        };
        let sq_disp_m2 = MSD_LAGS.map(|l| {
            (s as usize >= l).then(|| {
                let p = self.at(s - l as u32);
                let (dx, dy) = (x - p.0, y - p.1);
                dx * dx + dy * dy
            })
        });
        let (mut fresh_cells, mut new_cells) = (0, 0);
        if s == 1 {
            // The cell it started in is entered with the first step.
            fresh_cells += 1;
            new_cells += 1;
        }
        let c = cell_of(x, y);
        if c != self.cell {
            self.left.insert(self.cell, s - 1);
            match self.left.get(&c) {
                None => {
                    fresh_cells += 1;
                    new_cells += 1;
                }
                Some(&last) if s - last > FRESH_STEPS => fresh_cells += 1,
                Some(_) => {}
            }
            self.cell = c;
        }
        MotionStep {
            class,
            step_m,
            net_m: net / LAG_STEPS as f64,
            sq_disp_m2,
            fresh_cells,
            new_cells,
        }
    }

    /// Whether positions `s − HELD_STEPS ..= s` all lie within [`HELD_RADIUS_M`] of their mean.
    fn in_disc(&self, s: u32) -> bool {
        if (s as usize) < HELD_STEPS {
            return false;
        }
        // Two points within the radius of one point are within twice it of each other: a robot
        // whose first and last positions, or last two lag ends, are further apart is not held
        // (most moving robots, decided without the mean).
        let (a, b) = (self.at(s - HELD_STEPS as u32), self.at(s));
        let c = self.at(s - LAG_STEPS as u32);
        let far = |p: (f64, f64), q: (f64, f64)| dist(p.0 - q.0, p.1 - q.1) > 2.0 * HELD_RADIUS_M;
        if far(a, b) || far(c, b) || far(a, c) {
            return false;
        }
        let n = HISTORY as f64;
        let (sx, sy) = self
            .ring
            .iter()
            .fold((0.0, 0.0), |(a, b), p| (a + p.0, b + p.1));
        let (mx, my) = (sx / n, sy / n);
        let r2 = HELD_RADIUS_M * HELD_RADIUS_M;
        self.ring.iter().all(|p| {
            let (dx, dy) = (p.0 - mx, p.1 - my);
            dx * dx + dy * dy <= r2
        })
    }

    /// Distinct cells the robot has been in at the ends of steps `from..` (and at its start
    /// when `from` is 0), exact.
    #[must_use]
    pub fn cells_since(&self, from: u32) -> u32 {
        if self.seen == 0 {
            return 0;
        }
        // Position s is the end of step s − 1.
        let from_pos = from + 1;
        let earlier = self
            .left
            .iter()
            .filter(|&(&c, &last)| c != self.cell && (from == 0 || last >= from_pos))
            .count();
        earlier as u32 + 1
    }

    /// Distinct cells the robot has been in over the run.
    #[must_use]
    pub fn cells_visited(&self) -> u32 {
        if self.seen == 0 {
            return 0;
        }
        self.left.keys().filter(|&&c| c != self.cell).count() as u32 + 1
    }
}

/// One robot's record over a whole run: how far it went (path and net metres), how often it
/// collided, how its steps were classified, and its held spells. A **held spell** is a run of
/// steps classified [`MotionClass::Held`]; its **onset** is its first held step. A spell is
/// **lasting** when it holds for at least `lasting_steps` steps in a row, or until the run ends.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotTally {
    /// Distance its centre moved, summed step to step (the path), metres.
    pub distance_m: f64,
    /// Net metres: its net displacement over the lag per step ([`MotionStep::net_m`]), summed
    /// over the steps, metres.
    pub net_m: f64,
    /// Collisions counted for its behaviours.
    pub collisions: u64,
    /// Steps in which it moved at least [`crate::collisions::MOVING_MIN_MM`] (a reference).
    pub moving_steps: u32,
    /// Its steps by class, in the order of [`MotionClass::ALL`].
    pub class_steps: [u32; 4],
    /// Distance moved in the run's last window, metres.
    pub last_window_distance_m: f64,
    /// Net metres in the run's last window.
    pub last_window_net_m: f64,
    /// Collisions in the run's last window.
    pub last_window_collisions: u64,
    /// Distinct cells ([`CELL_M`]) it was in over the run's last window (set at the end).
    pub last_window_cells: u32,
    /// Distinct cells it was in over the run (set at the end).
    pub cells_visited: u32,
    /// Onset step of its first lasting held spell, if it had one.
    pub first_lasting_held_step: Option<u32>,
    /// Whether it was held at the run's last step.
    pub ends_held: bool,
    /// The class of its latest step.
    pub last_class: Option<MotionClass>,
    /// The current spell: its onset and how many steps it has lasted.
    spell: Option<(u32, u32)>,
    lasting_steps: u32,
}

impl RobotTally {
    /// An empty record; spells of at least `lasting_steps` held steps are lasting.
    #[must_use]
    pub fn new(lasting_steps: u32) -> Self {
        Self {
            distance_m: 0.0,
            net_m: 0.0,
            collisions: 0,
            moving_steps: 0,
            class_steps: [0; 4],
            last_window_distance_m: 0.0,
            last_window_net_m: 0.0,
            last_window_collisions: 0,
            last_window_cells: 0,
            cells_visited: 0,
            first_lasting_held_step: None,
            ends_held: false,
            last_class: None,
            spell: None,
            lasting_steps: lasting_steps.max(1),
        }
    }

    /// Steps it spent in class `c`.
    #[must_use]
    pub fn steps_in(&self, c: MotionClass) -> u32 {
        self.class_steps[c.code() as usize]
    }

    /// Records step `k`: what the tracker said of it, the collisions counted for it, and
    /// whether it is in the last window.
    pub fn record(&mut self, k: u32, m: &MotionStep, collisions: u64, last: bool) {
        self.distance_m += m.step_m;
        self.net_m += m.net_m;
        self.collisions += collisions;
        if m.step_m * 1000.0 >= crate::collisions::MOVING_MIN_MM {
            self.moving_steps += 1;
        }
        self.class_steps[m.class.code() as usize] += 1;
        if last {
            self.last_window_distance_m += m.step_m;
            self.last_window_net_m += m.net_m;
            self.last_window_collisions += collisions;
        }
        self.last_class = Some(m.class);
        let held = m.class == MotionClass::Held;
        self.ends_held = held;
        if held {
            let (onset, steps) = self.spell.map_or((k, 1), |(o, n)| (o, n + 1));
            self.spell = Some((onset, steps));
            if steps >= self.lasting_steps && self.first_lasting_held_step.is_none() {
                self.first_lasting_held_step = Some(onset);
            }
        } else {
            self.spell = None;
        }
    }

    /// Whether it is held now (at the latest step recorded).
    #[must_use]
    pub fn held_now(&self) -> bool {
        self.spell.is_some()
    }

    /// Closes the run: a spell still going at the end is lasting; the cells come from the
    /// robot's tracker, the last window from step `last_from` on.
    pub fn finish(&mut self, tracker: &MotionTracker, last_from: u32) {
        if let Some((onset, _)) = self.spell
            && self.first_lasting_held_step.is_none()
        {
            self.first_lasting_held_step = Some(onset);
        }
        self.cells_visited = tracker.cells_visited();
        self.last_window_cells = tracker.cells_since(last_from);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The definitions this module replaces, as they were (`collisions.rs` before): a
    /// robot-step is *moving* when the centre moved at least 5 mm in it; a robot is *stuck*
    /// when over the last 100 steps its motors drove and its centre's path summed less than
    /// 1 mm.
    mod old {
        pub fn moving(step_m: f64) -> bool {
            step_m * 1000.0 >= crate::collisions::MOVING_MIN_MM
        }

        #[derive(Default)]
        pub struct Stuck {
            steps: Vec<f64>,
        }

        impl Stuck {
            /// Records a step's path (the motors always drove); whether the robot is stuck.
            pub fn record(&mut self, step_m: f64) -> bool {
                self.steps.push(step_m);
                let n = self.steps.len();
                n >= 100 && self.steps[n - 100..].iter().sum::<f64>() < 0.001
            }
        }
    }

    /// What a trajectory's steps (after a run-in of `skip` steps) came out as, with the old
    /// definitions beside them.
    #[derive(Debug, Default)]
    struct Verdict {
        steps: usize,
        by_class: HashMap<MotionClass, usize>,
        old_moving: usize,
        old_stuck: usize,
        path_m: f64,
        net_m: f64,
        fresh_cells: u32,
    }

    impl Verdict {
        fn share(&self, c: MotionClass) -> f64 {
            *self.by_class.get(&c).unwrap_or(&0) as f64 / self.steps as f64
        }
    }

    fn judge(points: &[(f64, f64)], skip: usize) -> Verdict {
        let mut t = MotionTracker::new();
        let mut old = old::Stuck::default();
        t.start(points[0].0, points[0].1);
        let mut v = Verdict::default();
        for (k, &(x, y)) in points[1..].iter().enumerate() {
            let m = t.record(x, y);
            let stuck = old.record(m.step_m);
            if k < skip {
                continue;
            }
            v.steps += 1;
            *v.by_class.entry(m.class).or_default() += 1;
            v.old_moving += usize::from(old::moving(m.step_m));
            v.old_stuck += usize::from(stuck);
            v.path_m += m.step_m;
            v.net_m += m.net_m;
            v.fresh_cells += m.fresh_cells;
        }
        v
    }

    /// 600 positions: the start and 599 steps.
    const N: usize = 600;

    fn rng() -> ChaCha8Rng {
        ChaCha8Rng::seed_from_u64(7)
    }

    /// A robot wedged in place that jitters 0.4–1 mm a step (the robot): the old
    /// stuck detector never fires (its path sums 40–100 mm per 100 steps); held throughout.
    #[test]
    fn a_robot_jittering_in_place_is_held_though_never_stuck() {
        let mut r = rng();
        // Rocked to either side of where it is wedged by 0.2-0.5 mm: steps of 0.4-1 mm.
        let pts: Vec<(f64, f64)> = (0..N)
            .map(|k| {
                let side = if k % 2 == 0 { 1.0 } else { -1.0 };
                let off: f64 = side * r.random_range(0.0002..0.0005);
                let a: f64 = r.random_range(-0.3..0.3);
                (1.0 + off * libm::cos(a), 1.0 + off * libm::sin(a))
            })
            .collect();
        let v = judge(&pts, 100);
        assert_eq!(v.old_stuck, 0, "the old detector is fooled");
        assert_eq!(v.share(MotionClass::Held), 1.0, "{v:?}");
        // Held from its 20th step on (the still rule), not its 100th.
        let early = judge(&pts[..=25], 20);
        assert_eq!(early.share(MotionClass::Held), 1.0, "{early:?}");
    }

    /// The corridor's jam: a robot pressed against the end wall that rocks 7 cm a step
    /// (forward into the wall, pushed back): moving 100 % and never stuck by the old
    /// definitions; held once it has rocked for 100 steps (shuttling before).
    #[test]
    fn a_robot_rocking_against_a_wall_is_held() {
        let pts: Vec<(f64, f64)> = (0..N)
            .map(|k| (2.8 - if k % 2 == 0 { 0.0 } else { 0.07 }, 0.11))
            .collect();
        let v = judge(&pts, 100);
        assert_eq!(v.old_moving, v.steps, "the old moving metric is fooled");
        assert_eq!(v.old_stuck, 0);
        assert_eq!(v.share(MotionClass::Held), 1.0, "{v:?}");
        let early = judge(&pts[..=60], 20);
        assert_eq!(early.share(MotionClass::Shuttling), 1.0, "{early:?}");
        assert!(v.net_m < 0.01 * v.path_m, "no net metres: {v:?}");
    }

    /// A shuttler: three steps of 5 cm forward, three back, over and over (the issue's
    /// learning robots). Moving every step, never stuck, and collisions per metre moved would
    /// count its metres; it is shuttling, and its net metres are nearly none.
    #[test]
    fn a_shuttler_is_shuttling_though_always_moving() {
        let pts: Vec<(f64, f64)> = (0..N)
            .map(|k| {
                let phase = k % 6;
                let along = if phase <= 3 { phase } else { 6 - phase };
                (0.5 + 0.05 * along as f64, 0.9)
            })
            .collect();
        let v = judge(&pts, 100);
        assert_eq!(v.old_moving, v.steps, "the old moving metric is fooled");
        assert_eq!(v.old_stuck, 0);
        assert_eq!(v.share(MotionClass::Shuttling), 1.0, "{v:?}");
        assert!(v.net_m < 0.1 * v.path_m, "{v:?}");
        // Its cells are the same few all the time: nothing fresh after the run-in.
        assert_eq!(v.fresh_cells, 0, "{v:?}");
    }

    /// A robot that keeps turning: the slow wheel at 0.3 of the fast one on a 16 cm track
    /// turns on a radius of 0.08 · 1.3 / 0.7 = 14.9 cm, its centre at 0.65 of 0.15 m/s, 4.4 cm
    /// a 0.45 s step.
    #[test]
    fn a_circling_robot_is_circling() {
        let r = 0.149;
        let dtheta = 0.044 / r;
        let pts: Vec<(f64, f64)> = (0..N)
            .map(|k| {
                let a = dtheta * k as f64;
                (0.9 + r * libm::cos(a), 0.9 + r * libm::sin(a))
            })
            .collect();
        let v = judge(&pts, 100);
        assert_eq!(v.old_moving, v.steps, "the old moving metric is fooled");
        assert_eq!(v.share(MotionClass::Circling), 1.0, "{v:?}");
        assert!(v.net_m < 0.2 * v.path_m, "{v:?}");
    }

    /// A robot that drives five steps and stops: its net metres are its path (dividing the
    /// start's net displacement by the shorter lag counted its first steps up to 3.6 times: 0.72
    /// net metres against 0.3 m of path).
    #[test]
    fn net_metres_never_exceed_the_path() {
        let pts: Vec<(f64, f64)> = (0..N).map(|k| (0.06 * k.min(5) as f64, 0.3)).collect();
        let v = judge(&pts, 0);
        assert!((v.path_m - 0.3).abs() < 1e-9, "{v:?}");
        assert!(v.net_m <= v.path_m + 1e-12, "{v:?}");
        // Each step counted 20 times over 20: exactly its path once the lag has passed.
        assert!((v.net_m - v.path_m).abs() < 1e-9, "{v:?}");
    }

    /// A straight line at 6 cm a step explores; its net metres are its path but for the lag's
    /// first steps (step k < 20 adds k/20 of a step: 9.5 steps short in all).
    #[test]
    fn a_straight_line_explores() {
        let pts: Vec<(f64, f64)> = (0..N).map(|k| (0.06 * k as f64, 0.3)).collect();
        let v = judge(&pts, 0);
        assert_eq!(v.share(MotionClass::Exploring), 1.0, "{v:?}");
        let ramp = (LAG_STEPS - 1) as f64 / 2.0 * 0.06;
        assert!((v.net_m - (v.path_m - ramp)).abs() < 1e-9, "{v:?}");
        // A new cell every 0.2 m: 0.06 m a step over 600 steps is 36 m, 180 cells.
        assert!((178..=181).contains(&v.fresh_cells), "{v:?}");
    }

    /// Sliding along a wall: 3 cm a step along it, pressed against it with a little jitter
    /// across: explores (the old moving metric agrees; the point is that the new one does not
    /// call it held or shuttling).
    #[test]
    fn sliding_along_a_wall_explores() {
        let mut r = rng();
        let pts: Vec<(f64, f64)> = (0..N)
            .map(|k| {
                let along = (0.03 * k as f64) % 3.2;
                let x = if (0.03 * k as f64) % 6.4 < 3.2 {
                    0.1 + along
                } else {
                    3.3 - along
                };
                (x, 0.09 + r.random_range(-0.001..0.001))
            })
            .collect();
        let v = judge(&pts, 100);
        // Turning back at the far end is a reversal in a net-progress span: a step or two.
        assert!(v.share(MotionClass::Exploring) > 0.9, "{v:?}");
        assert_eq!(v.share(MotionClass::Held), 0.0, "{v:?}");
    }

    /// A random walk: 5 cm steps in directions drawn anew each step. Never held; its mean
    /// squared displacement grows as the lag (diffusion: 10 times the lag, 10 times the MSD),
    /// where a straight driver's grows as its square and a confined robot's not at all.
    #[test]
    fn a_random_walk_is_never_held_and_diffuses() {
        let mut r = rng();
        let mut p = (0.0, 0.0);
        let mut pts = vec![p];
        for _ in 1..20 * N {
            let a: f64 = r.random_range(0.0..std::f64::consts::TAU);
            p = (p.0 + 0.05 * libm::cos(a), p.1 + 0.05 * libm::sin(a));
            pts.push(p);
        }
        let mut t = MotionTracker::new();
        t.start(pts[0].0, pts[0].1);
        let mut msd = [0.0; 3];
        let mut n = 0.0;
        let mut held = 0;
        for &(x, y) in &pts[1..] {
            let m = t.record(x, y);
            held += usize::from(m.class == MotionClass::Held);
            if let [Some(a), Some(b), Some(c)] = m.sq_disp_m2 {
                msd[0] += a;
                msd[1] += b;
                msd[2] += c;
                n += 1.0;
            }
        }
        assert_eq!(held, 0);
        let ratio = |a: f64, b: f64| (b / n) / (a / n);
        // 0.05² = 0.0025 m² a step; 10 and 100 steps: 10 and 100 times that.
        assert!((msd[0] / n - 0.0025).abs() < 1e-9);
        assert!((ratio(msd[0], msd[1]) - 10.0).abs() < 1.5, "{msd:?}");
        assert!((ratio(msd[1], msd[2]) - 10.0).abs() < 2.5, "{msd:?}");
        let v = judge(&pts[..N], 100);
        // An isotropic random walk's net displacement over 20 steps is about 0.2 of its path:
        // it lies on the line between exploring and turning back; never held.
        assert_eq!(v.share(MotionClass::Held), 0.0);
        assert!(v.share(MotionClass::Exploring) > 0.3, "{v:?}");
        assert!(v.net_m > 0.1 * v.path_m, "{v:?}");
    }

    #[test]
    fn cells_are_counted_exactly() {
        let mut t = MotionTracker::new();
        t.start(0.05, 0.05);
        // Cells along x: 0, 0, 1, 2, 1, 0 (positions after steps 0..6).
        let xs = [0.1, 0.25, 0.45, 0.3, 0.1, 0.15];
        let got: Vec<(u32, u32)> = xs
            .iter()
            .map(|&x| {
                let m = t.record(x, 0.05);
                (m.fresh_cells, m.new_cells)
            })
            .collect();
        assert_eq!(got, [(1, 1), (1, 1), (1, 1), (0, 0), (0, 0), (0, 0)]);
        assert_eq!(t.cells_visited(), 3);
        assert_eq!(t.cells_since(0), 3);
        // Steps 3.. (positions 4..): cells 1, 0, 0.
        assert_eq!(t.cells_since(3), 2);
        assert_eq!(t.cells_since(5), 1);
        // Back in a cell after more than FRESH_STEPS steps: fresh, not new.
        for _ in 0..FRESH_STEPS {
            t.record(0.1, 0.05);
        }
        let m = t.record(0.3, 0.05);
        assert_eq!((m.fresh_cells, m.new_cells), (1, 0));
    }

    fn step(class: MotionClass, step_m: f64) -> MotionStep {
        MotionStep {
            class,
            step_m,
            net_m: if class == MotionClass::Exploring {
                step_m
            } else {
                0.0
            },
            sq_disp_m2: [None; 3],
            fresh_cells: 0,
            new_cells: 0,
        }
    }

    #[test]
    fn a_tally_finds_the_first_lasting_spell_and_its_onset() {
        let mut t = RobotTally::new(50);
        // Steps 0..200 explore; held at 200..230 (too short); exploring again; held from 400
        // on, lasting once held 50 times.
        for k in 0..600u32 {
            let held = (200..230).contains(&k) || k >= 400;
            let m = if held {
                step(MotionClass::Held, 0.0)
            } else {
                step(MotionClass::Exploring, 0.05)
            };
            t.record(k, &m, u64::from(k == 10), k >= 500);
        }
        assert_eq!(t.first_lasting_held_step, Some(400));
        assert!(t.ends_held && t.held_now());
        assert_eq!(t.steps_in(MotionClass::Held), 30 + 200);
        assert_eq!(t.steps_in(MotionClass::Exploring), 370);
        assert_eq!(t.collisions, 1);
        assert_eq!(t.last_window_collisions, 0);
        assert_eq!(t.moving_steps, 370);
        assert!((t.distance_m - 0.05 * 370.0).abs() < 1e-9);
        assert!((t.net_m - 0.05 * 370.0).abs() < 1e-9);
        assert_eq!(t.last_window_distance_m, 0.0);
        // A spell too short to be lasting still is, when the run ends in it.
        let mut end = RobotTally::new(500);
        for k in 0..300u32 {
            let c = if k >= 250 {
                MotionClass::Held
            } else {
                MotionClass::Shuttling
            };
            end.record(k, &step(c, 0.01), 0, false);
        }
        assert_eq!(end.first_lasting_held_step, None);
        end.finish(&MotionTracker::new(), 250);
        assert_eq!(end.first_lasting_held_step, Some(250));
        assert_eq!(end.cells_visited, 0);
    }
}
