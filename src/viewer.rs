//! The browser viewer's page (`h8swarm run --replay`): the runs' recorded planes
//! ([`swarm::recording`]) joined behind a header (JSON: the arena, the bodies, the sensors, the
//! runs, the learning curves) into one stream, compressed (gzip), encoded in base64 and written
//! into a copy of the viewer page (`assets/viewer.html`), so the page opens from the file
//! system with nothing else: no server, no network. The format, byte by byte, is in
//! `docs/viewer.md`; [`decode`] reads it back.

use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use swarm::output_error::OutputError;
use swarm::recording::{E_PLANE, MAGIC, PLANES, VERSION};

/// The viewer page, with `/*H8SWARM_REPLAY_DATA*/` where the data go.
pub const VIEWER_TEMPLATE: &str = include_str!("../assets/viewer.html");
/// Where the data go in [`VIEWER_TEMPLATE`].
pub const DATA_PLACEHOLDER: &str = "/*H8SWARM_REPLAY_DATA*/";

/// One recorded run in the header.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunHeader {
    /// `learning`, `learning-off` or `random-walk`.
    pub condition: String,
    /// The repeat.
    pub repeat: u32,
    /// Frames recorded.
    pub frames: u32,
    /// The frames that carry weights.
    pub weight_frames: Vec<u32>,
}

/// A sensor's mount on the body: where, facing which way.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MountHeader {
    /// Forward of the centre, metres.
    pub x_m: f64,
    /// Left of the centre, metres.
    pub y_m: f64,
    /// Facing, radians from the heading.
    pub angle_rad: f64,
}

/// A learning curve for the page: one condition's means over its repeats per window.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurveHeader {
    /// The condition.
    pub condition: String,
    /// Window centres, steps.
    pub x: Vec<f64>,
    /// Mean D, du.
    pub mean_d: Vec<f64>,
    /// Collisions per robot per window.
    pub collisions_per_robot: Vec<f64>,
    /// Held robot-steps, percent.
    pub held_percent: Vec<f64>,
    /// Net progress, mm per step (empty when no window has a value).
    pub net_mm: Vec<f64>,
}

/// The header of a replay: everything the page needs besides the frames.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// The format version.
    pub version: u16,
    /// The scenario's name.
    pub name: String,
    /// `square` or `corridor`.
    pub arena: String,
    /// The arena's width (x), metres.
    pub width_m: f64,
    /// The arena's height (y), metres.
    pub height_m: f64,
    /// One unit of a recorded position, metres.
    pub quantum_m: f64,
    /// Wall segments [x0, y0, x1, y1], metres.
    pub walls: Vec<[f64; 4]>,
    /// The body's length (along the heading) and width, metres.
    pub body_m: [f64; 2],
    /// The sensors, front, rear, left, right.
    pub sensors: Vec<MountHeader>,
    /// One du in metres (80/255 cm).
    pub du_m: f64,
    /// Robots recorded (the first of the run's).
    pub robots: usize,
    /// Robots in the run.
    pub run_robots: usize,
    /// Steps of a run.
    pub steps: u32,
    /// Steps between two frames.
    pub stride: u32,
    /// The step period, seconds.
    pub step_period_s: f64,
    /// `model` or `firmware`.
    pub controller: String,
    /// The master seed, carried as text (a JavaScript number holds integers exactly only up
    /// to 2^53).
    #[serde(with = "u64_text")]
    pub seed: u64,
    /// Weights layout: inputs N and outputs M (0 when none are recorded).
    pub weights_shape: [usize; 2],
    /// Behaviours enabled (2 or 4).
    pub behaviours: usize,
    /// The dead-zone threshold T, du.
    pub threshold: i32,
    /// The recorded runs, in the order of the data.
    pub runs: Vec<RunHeader>,
    /// The learning curves (all repeats).
    pub curves: Vec<CurveHeader>,
}

/// A `u64` as JSON text (`"18446744073709551615"`), so that no reader rounds it.
mod u64_text {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &u64, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&v.to_string())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
        let text = String::deserialize(d)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

/// Writes the viewer page `html` with `header` and the runs' part files (per run in the
/// header's order, its planes then its weights, as [`swarm::recording::part_paths`] names
/// them; `e` is skipped when the stride is 1), removing the parts.
///
/// # Errors
/// A part that cannot be read, or the page that cannot be written (output errors).
pub fn write_viewer(html: &Path, header: &Header, parts: &[Vec<PathBuf>]) -> Result<()> {
    let write = || -> Result<()> {
        let (before, after) = VIEWER_TEMPLATE
            .split_once(DATA_PLACEHOLDER)
            .context("the viewer template has no data placeholder")?;
        let mut file = BufWriter::new(std::fs::File::create(html)?);
        file.write_all(before.as_bytes())?;
        let b64 = base64::write::EncoderWriter::new(
            &mut file,
            &base64::engine::general_purpose::STANDARD,
        );
        let mut gz = flate2::write::GzEncoder::new(b64, flate2::Compression::new(2));
        let json = serde_json::to_vec(header)?;
        gz.write_all(MAGIC)?;
        gz.write_all(&VERSION.to_le_bytes())?;
        gz.write_all(&(json.len() as u32).to_le_bytes())?;
        gz.write_all(&json)?;
        for run in parts {
            for (i, p) in run.iter().enumerate() {
                if i == E_PLANE && header.stride == 1 {
                    continue;
                }
                let mut f =
                    std::fs::File::open(p).with_context(|| format!("reading `{}`", p.display()))?;
                std::io::copy(&mut f, &mut gz)?;
            }
        }
        let mut b64 = gz.finish()?;
        b64.finish()?;
        drop(b64);
        file.write_all(after.as_bytes())?;
        file.flush()?;
        for p in parts.iter().flatten() {
            std::fs::remove_file(p)?;
        }
        Ok(())
    };
    write().context(OutputError::cannot_write(html))
}

/// One robot in one decoded frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DecodedRobot {
    /// Centre, metres (quantised).
    pub x_m: f64,
    /// Centre, metres (quantised).
    pub y_m: f64,
    /// Heading, radians in [0, 2π) (quantised).
    pub heading_rad: f64,
    /// Flags: behaviour code and [`swarm::recording::flag`] bits.
    pub flags: u8,
    /// Bumper bits (front, rear, left, right from bit 0).
    pub bumpers: u8,
    /// Readings, du.
    pub p: [u8; 4],
    /// E, du.
    pub e: i16,
    /// CPU load, 0.1 % units.
    pub load: u8,
}

/// A decoded replay: the header and per run its frames (robots in order) and weight snapshots.
#[derive(Clone, Debug, PartialEq)]
pub struct Decoded {
    /// The header.
    pub header: Header,
    /// Per run, per frame, per robot.
    pub frames: Vec<Vec<Vec<DecodedRobot>>>,
    /// Per run, per weight snapshot, per robot: N × M weights.
    pub weights: Vec<Vec<Vec<Vec<i16>>>>,
}

/// Reads the replay out of a viewer page written by [`write_viewer`].
///
/// # Errors
/// A page without data, or data that do not decode.
pub fn decode(html: &str) -> Result<Decoded> {
    let start = html
        .find("id=\"replay-data\"")
        .and_then(|i| html[i..].find('>').map(|j| i + j + 1))
        .context("no replay-data element")?;
    let end = html[start..]
        .find("</script>")
        .map(|j| start + j)
        .context("replay-data not closed")?;
    let b64: String = html[start..end]
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect();
    use base64::Engine as _;
    let gz = base64::engine::general_purpose::STANDARD.decode(b64)?;
    let mut raw = Vec::new();
    flate2::read::GzDecoder::new(&gz[..]).read_to_end(&mut raw)?;
    if raw.len() < 10 || &raw[..4] != MAGIC {
        bail!("not an h8swarm replay");
    }
    let len = u32::from_le_bytes(raw[6..10].try_into()?) as usize;
    let header: Header = serde_json::from_slice(raw.get(10..10 + len).context("short header")?)?;
    let mut at = 10 + len;
    let n = header.robots;
    let [ni, no] = header.weights_shape;
    let mut all_frames = Vec::new();
    let mut all_weights = Vec::new();
    for run in &header.runs {
        let f = run.frames as usize;
        let mut planes: Vec<&[u8]> = Vec::new();
        for (i, (_, w)) in PLANES.iter().enumerate() {
            if i == E_PLANE && header.stride == 1 {
                planes.push(&[]);
                continue;
            }
            let len = f * n * w;
            planes.push(raw.get(at..at + len).context("short plane")?);
            at += len;
        }
        let u16_at = |plane: &[u8], j: usize| u16::from_le_bytes([plane[2 * j], plane[2 * j + 1]]);
        let mut frames = Vec::with_capacity(f);
        let mut prev = vec![(0u16, 0u16, 0u8); n];
        let mut step = vec![(0u16, 0u16); n];
        let mut last_d: Vec<Option<i16>> = vec![None; n];
        for fi in 0..f {
            let robots: Vec<DecodedRobot> = (0..n)
                .map(|i| {
                    let j = fi * n + i;
                    step[i].0 = step[i].0.wrapping_add(u16_at(planes[0], j));
                    step[i].1 = step[i].1.wrapping_add(u16_at(planes[1], j));
                    let x = prev[i].0.wrapping_add(step[i].0);
                    let y = prev[i].1.wrapping_add(step[i].1);
                    let h = prev[i].2.wrapping_add(planes[2][j]);
                    prev[i] = (x, y, h);
                    let p = [0, 1, 2, 3].map(|s| planes[5 + s][j]);
                    let d: i16 = p.iter().map(|&v| i16::from(v)).sum();
                    let e = if header.stride == 1 {
                        last_d[i].map_or(0, |l| d - l)
                    } else {
                        u16_at(planes[E_PLANE], j) as i16
                    };
                    last_d[i] = Some(d);
                    DecodedRobot {
                        x_m: f64::from(x) * header.quantum_m,
                        y_m: f64::from(y) * header.quantum_m,
                        heading_rad: f64::from(h) / 256.0 * std::f64::consts::TAU,
                        flags: planes[3][j],
                        bumpers: planes[4][j],
                        p,
                        e,
                        load: planes[10][j],
                    }
                })
                .collect();
            frames.push(robots);
        }
        let mut snaps: Vec<Vec<Vec<i16>>> = Vec::new();
        for _ in &run.weight_frames {
            let mut per_robot = Vec::with_capacity(n);
            for i in 0..n {
                let w = raw.get(at..at + 2 * ni * no).context("short weights")?;
                at += 2 * ni * no;
                let before = snaps.last().map(|s| &s[i]);
                per_robot.push(
                    w.chunks_exact(2)
                        .enumerate()
                        .map(|(k, c)| {
                            let d = i16::from_le_bytes([c[0], c[1]]);
                            before.map_or(d, |b| b[k].wrapping_add(d))
                        })
                        .collect(),
                );
            }
            snaps.push(per_robot);
        }
        all_frames.push(frames);
        all_weights.push(snaps);
    }
    if at != raw.len() {
        bail!("{} bytes left over after the last run", raw.len() - at);
    }
    Ok(Decoded {
        header,
        frames: all_frames,
        weights: all_weights,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use swarm::recording::{RecordOptions, Recorder, RobotStep, flag, part_paths, quantum_m};
    use swarm::robot::Condition;

    fn robot(i: usize, k: u32) -> RobotStep {
        let t = f64::from(k);
        RobotStep {
            x_m: 0.2 + 0.01 * t + 0.3 * i as f64,
            y_m: 1.7 - 0.005 * t,
            heading_rad: 0.1 * t - 3.0,
            behaviour: (k % 5) as u8,
            bumpers: [k.is_multiple_of(2), false, i == 1, k.is_multiple_of(3)],
            p: [k as u8, 255, 7, (i * 40) as u8],
            d: k as i16 + 262 + 40 * i as i16,
            held: i == 0 && k > 4,
            motion: (k > 0).then(|| swarm::motion::MotionClass::ALL[(k as usize + i) % 4]),
            saved: k == 6,
            dead: false,
            load_percent: 0.37 * t,
        }
    }

    /// Frames written and read back, with a stride of 1 (E taken from consecutive D's) and of
    /// 2 (E stored): every field within its quantisation, weights at their frames.
    #[test]
    fn frames_round_trip() {
        for stride in [1u32, 2] {
            let dir =
                std::env::temp_dir().join(format!("h8swarm-rec-{}-{stride}", std::process::id()));
            std::fs::create_dir_all(&dir).unwrap();
            let paths = part_paths(&dir, Condition::Learning, 0);
            let opts = RecordOptions {
                stride,
                weights_every: 3,
            };
            let mut rec = Recorder::new(opts, (1.8, 1.8), paths.clone()).unwrap();
            for k in 0..20 {
                let robots: Vec<RobotStep> = (0..3).map(|i| robot(i, k)).collect();
                rec.step(k, &robots, &mut |i| {
                    Some(vec![i as i16 * (k as i16 + 1); 6])
                })
                .unwrap();
            }
            let (frames, weight_frames) = rec.finish().unwrap();
            let want_frames = 20 / stride;
            assert_eq!(frames, want_frames);
            assert_eq!(
                weight_frames,
                (0..want_frames).filter(|f| f % 3 == 0).collect::<Vec<_>>()
            );
            let header = Header {
                version: VERSION,
                name: "t".into(),
                arena: "square".into(),
                width_m: 1.8,
                height_m: 1.8,
                quantum_m: quantum_m(1.8, 1.8),
                walls: vec![],
                body_m: [0.23, 0.18],
                sensors: vec![],
                du_m: 0.8 / 255.0,
                robots: 3,
                run_robots: 3,
                steps: 20,
                stride,
                step_period_s: 0.45,
                controller: "model".into(),
                seed: 1,
                weights_shape: [3, 2],
                behaviours: 4,
                threshold: 10,
                runs: vec![RunHeader {
                    condition: "learning".into(),
                    repeat: 0,
                    frames,
                    weight_frames,
                }],
                curves: vec![],
            };
            let html = dir.join("replay.html");
            write_viewer(&html, &header, std::slice::from_ref(&paths)).unwrap();
            assert!(paths.iter().all(|p| !p.exists()), "parts removed");
            let d = decode(&std::fs::read_to_string(&html).unwrap()).unwrap();
            std::fs::remove_dir_all(&dir).unwrap();
            assert_eq!(d.header, header);
            assert_eq!(d.frames[0].len(), want_frames as usize);
            for (f, frame) in d.frames[0].iter().enumerate() {
                let k = stride * f as u32;
                for (i, got) in frame.iter().enumerate() {
                    let want = robot(i, k);
                    assert!((got.x_m - want.x_m).abs() <= 0.0005 + 1e-12, "{k} {i}");
                    assert!((got.y_m - want.y_m).abs() <= 0.0005 + 1e-12);
                    let tau = std::f64::consts::TAU;
                    let dh = (got.heading_rad - want.heading_rad.rem_euclid(tau)).rem_euclid(tau);
                    assert!(dh.min(tau - dh) <= std::f64::consts::PI / 256.0 + 1e-12);
                    assert_eq!(got.flags & 7, want.behaviour);
                    assert_eq!(got.flags & flag::HELD != 0, want.held);
                    assert_eq!(
                        (got.flags & flag::MOTION) >> flag::MOTION_SHIFT,
                        want.motion.map_or(0, swarm::motion::MotionClass::code)
                    );
                    assert_eq!(got.flags & flag::SAVED != 0, want.saved);
                    assert_eq!(got.p, want.p);
                    let bits = want
                        .bumpers
                        .iter()
                        .enumerate()
                        .fold(0, |b, (s, &on)| b | (u8::from(on) << s));
                    assert_eq!(got.bumpers, bits);
                    // D rises by 1 a step: E is 1 but at the very first step.
                    assert_eq!(got.e, if k == 0 { 0 } else { 1 }, "stride {stride}");
                    let load = (want.load_percent * 10.0).round().min(255.0) as u8;
                    assert_eq!(got.load, load);
                }
            }
            let snaps = d.weights[0].len();
            assert_eq!(snaps, want_frames.div_ceil(3) as usize);
            // Snapshot 1 is of frame 3, step 3 · stride.
            let k1 = 3 * stride as i16;
            assert_eq!(d.weights[0][1][2], vec![2 * (k1 + 1); 6]);
        }
    }
}
