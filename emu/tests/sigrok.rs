//! A client nobody here wrote reads the pin traces: `sigrok-cli` (Debian's package) decodes a
//! VCD file of ten robot firmware steps with five EEPROM saves. Its I²C decoder must give the device
//! address, the page address and the bytes of every record page the emulator's EEPROMs took
//! (and the weights the firmware held in RAM); its PWM decoder must find each step's duty and
//! period as the ITU's registers set them. Skipped, with a message, when `sigrok-cli` is not
//! installed (CI installs it).

use std::collections::BTreeMap;
use std::process::Command;
use std::sync::Arc;

use h8_3052f::mcu::Mcu;
use h8_3052f::periph::itu::PwmWave;
use h8_3052f::trace::{PinTrace, Signal};
use h8_3052f::vcd::{VcdInfo, write_vcd};
use h8300h::bus::Bus;
use robot_board::board::{RobotBoard, RobotConfig, robot_mcu};
use robot_board::firmware::{ConfigBlock, FLAG_RANDOM_WALK, Firmware, FirmwareController};

mod boards;
use boards::Wandering;

/// What the emulator knows of one traced step.
struct Step {
    /// When sensing began (the ADST write) and when the work ended (SLEEP).
    sensing: u64,
    asleep: u64,
    /// The motors' PWM from the end of the step's work on.
    waves: (PwmWave, PwmWave),
    /// Pages written in the step, per device: (device address, page index) -> the page's
    /// bytes in the EEPROM after the step.
    pages: BTreeMap<(u8, usize), Vec<u8>>,
    /// The weights in RAM after the step (big-endian i16, as the firmware stores them).
    weights: Vec<u8>,
}

struct Traced {
    trace: PinTrace,
    steps: Vec<Step>,
    /// The next step's sensing: the end of the last traced behaviour.
    end: u64,
    clock_hz: u32,
    vcd: std::path::PathBuf,
}

const PAGE: usize = 64;

/// Firmware with a save every second step and random behaviours; steps 1 to 10 traced.
fn traced() -> Traced {
    let fw = Firmware::robot().unwrap();
    let mut mcu = robot_mcu(Wandering, &RobotConfig::default()).unwrap();
    let block = ConfigBlock {
        save_every: 2,
        flags: FLAG_RANDOM_WALK,
        ..ConfigBlock::ARENA
    };
    let mut c = FirmwareController::start(&fw, &mut mcu, Some(&block)).unwrap();
    c.run_to_sensing(&mut mcu).unwrap();
    c.run_to_sleep(&mut mcu).unwrap();
    mcu.start_trace(c.cpu().sleeping());
    c.record_phases(Arc::new(fw.symbols.clone()), mcu.now());
    let net_w = fw.symbols.addr("net_w").unwrap();
    let n_in = fw.symbols.addr("net_n_in").unwrap();
    let n_out = fw.symbols.addr("net_n_out").unwrap();
    let counts = |mcu: &Mcu<RobotBoard<Wandering>>| -> Vec<(u8, Vec<u32>)> {
        mcu.board()
            .eeproms()
            .devices()
            .iter()
            .map(|d| (d.address(), d.write_counts().to_vec()))
            .collect()
    };
    let mut steps = Vec::new();
    for _ in 0..10 {
        let before = counts(&mcu);
        let sensing = c.run_to_sensing(&mut mcu).unwrap();
        c.run_to_sleep(&mut mcu).unwrap();
        let asleep = mcu.now();
        let mut pages = BTreeMap::new();
        for ((dev, b), (_, a)) in before.iter().zip(counts(&mcu)) {
            for (page, (x, y)) in b.iter().zip(&a).enumerate() {
                if x != y {
                    let mut buf = vec![0u8; PAGE];
                    mcu.board_mut()
                        .eeproms_mut()
                        .device_mut(*dev)
                        .unwrap()
                        .read(asleep, (page * PAGE) as u16, &mut buf)
                        .unwrap();
                    pages.insert((*dev, page), buf);
                }
            }
        }
        let w = robot_board::firmware::peek_be::<_, 4>(&mcu, net_w) as u32;
        let n =
            robot_board::firmware::peek_be::<_, 2>(&mcu, n_in) as u32 * u32::from(mcu.peek(n_out));
        let weights = (0..2 * n).map(|i| mcu.peek(w + i)).collect();
        let wave = |mcu: &mut Mcu<RobotBoard<Wandering>>, ch| mcu.tioca(ch).wave.unwrap();
        let waves = (wave(&mut mcu, 1), wave(&mut mcu, 2));
        steps.push(Step {
            sensing,
            asleep,
            waves,
            pages,
            weights,
        });
    }
    let end = c.run_to_sensing(&mut mcu).unwrap();
    let phases = c.take_phases();
    let trace = mcu.finish_trace().unwrap();
    // One file per call: the tests run on threads of one process, and each removes its own.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let vcd =
        std::env::temp_dir().join(format!("h8swarm-sigrok-{}-{call}.vcd", std::process::id()));
    write_vcd(
        std::fs::File::create(&vcd).unwrap(),
        &trace,
        Some(&phases),
        &VcdInfo {
            source: "sigrok test".into(),
        },
    )
    .unwrap();
    Traced {
        trace,
        steps,
        end,
        clock_hz: mcu.clock_hz(),
        vcd,
    }
}

/// One annotation: (first sample, last sample, text). Samples are states: the VCD's
/// timestamps (4 a state at 25 MHz) downsampled by 4.
type Annotation = (u64, u64, String);

/// Runs `sigrok-cli` with a decoder on the trace; `None` when it is not installed.
fn sigrok(
    vcd: &std::path::Path,
    channels: &str,
    decoder: &str,
    rows: &str,
) -> Option<Vec<Annotation>> {
    let out = match Command::new("sigrok-cli")
        .args(["-l", "0", "-i"])
        .arg(vcd)
        .args([
            "-I",
            "vcd:downsample=4",
            "-C",
            channels,
            "-P",
            decoder,
            "-A",
            rows,
            "--protocol-decoder-samplenum",
        ])
        .output()
    {
        Ok(out) => out,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return None,
        Err(e) => panic!("sigrok-cli: {e}"),
    };
    assert!(
        out.status.success(),
        "sigrok-cli failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let mut v: Vec<Annotation> = text
        .lines()
        .map(|l| {
            let (span, rest) = l.split_once(' ').unwrap();
            let (a, b) = span.split_once('-').unwrap();
            let text = rest.split_once(": ").unwrap().1.to_string();
            (a.parse().unwrap(), b.parse().unwrap(), text)
        })
        .collect();
    v.sort_by_key(|a| a.0);
    Some(v)
}

/// Says the test did not run, on the process's standard error itself (the test harness
/// captures `eprintln!`, and would show nothing for a test that passes).
fn skip() {
    use std::io::Write as _;
    let _ = writeln!(
        std::io::stderr(),
        "SKIPPED: sigrok-cli is not installed (Debian package sigrok-cli; .ci/run installs it)"
    );
}

/// A decoded I²C write: when it started, the device, the data bytes after the address.
#[derive(Debug)]
struct Write {
    at: u64,
    device: u8,
    data: Vec<u8>,
}

fn byte(text: &str, prefix: &str) -> Option<u8> {
    text.strip_prefix(prefix)
        .map(|h| u8::from_str_radix(h.trim(), 16).unwrap())
}

#[test]
fn sigrok_decodes_the_eeprom_saves_as_the_emulator_wrote_them() {
    let t = traced();
    let Some(ann) = sigrok(
        &t.vcd,
        "SCL,SDA",
        "i2c:scl=SCL:sda=SDA",
        "i2c=start:repeat-start:stop:address-write:address-read:data-write:data-read",
    ) else {
        return skip();
    };
    // Every START the decoder saw is an SDA fall while SCL is high, at that state.
    let sda_falls: Vec<u64> = t
        .trace
        .changes_of(Signal::Sda)
        .filter(|c| !c.level)
        .map(|c| c.t)
        .collect();
    let mut writes: Vec<Write> = Vec::new();
    let mut current: Option<Write> = None;
    for (a, _, text) in &ann {
        if text == "Start" || text == "Start repeat" {
            assert!(sda_falls.contains(a), "START at {a} is no SDA fall");
            assert!(
                t.trace.level_at(Signal::Scl, *a),
                "START at {a} with SCL low"
            );
            writes.extend(current.take());
        } else if text == "Stop" {
            writes.extend(current.take());
        } else if let Some(d) = byte(text, "Address write: ") {
            current = Some(Write {
                at: *a,
                device: d,
                data: Vec::new(),
            });
        } else if let Some(b) = byte(text, "Data write: ") {
            current
                .as_mut()
                .expect("data after an address")
                .data
                .push(b);
        }
    }
    writes.extend(current.take());
    // Page writes (acknowledge polling sends the address alone).
    let pages: Vec<&Write> = writes.iter().filter(|w| w.data.len() > 2).collect();
    let mut saves = 0;
    for s in &t.steps {
        let in_step: Vec<&&Write> = pages
            .iter()
            .filter(|w| w.at >= s.sensing && w.at < s.asleep)
            .collect();
        assert_eq!(
            in_step.len(),
            s.pages.len(),
            "pages written in the step: sigrok {in_step:?}, EEPROMs {:?}",
            s.pages.keys().collect::<Vec<_>>()
        );
        if s.pages.is_empty() {
            continue;
        }
        saves += 1;
        let mut body = Vec::new();
        for w in &in_step {
            assert!(w.device == 0x50 || w.device == 0x51, "{:#x}", w.device);
            let addr = usize::from(u16::from_be_bytes([w.data[0], w.data[1]]));
            let bytes = &w.data[2..];
            assert!(addr % PAGE + bytes.len() <= PAGE, "one page per write");
            let page = s
                .pages
                .get(&(w.device, addr / PAGE))
                .unwrap_or_else(|| panic!("{:#x} page {} not written", w.device, addr / PAGE));
            assert_eq!(bytes, &page[addr % PAGE..addr % PAGE + bytes.len()]);
            if addr >= PAGE {
                body.extend_from_slice(bytes);
            } else {
                // The commit block names the record: "HK", version 1.
                assert_eq!(&bytes[..4], b"HK\x01\x00");
            }
        }
        // One chip per save, body pages before the commit page.
        assert!(in_step.windows(2).all(|p| p[0].device == p[1].device));
        let last = in_step.last().unwrap();
        assert_eq!(u16::from_be_bytes([last.data[0], last.data[1]]), 0);
        // The body: sequence (4), length (2), the weights as the firmware held them, CRC (2).
        let len = usize::from(u16::from_be_bytes([body[4], body[5]]));
        assert_eq!(len, s.weights.len());
        assert_eq!(&body[6..6 + len], &s.weights[..]);
        assert_eq!(body.len(), 6 + len + 2);
    }
    assert_eq!(saves, 5, "a save every second step over ten steps");
    // The two chips take turns.
    let chips: Vec<u8> = t
        .steps
        .iter()
        .filter_map(|s| s.pages.keys().next().map(|k| k.0))
        .collect();
    assert!(chips.windows(2).all(|p| p[0] != p[1]), "{chips:?}");
    let _ = std::fs::remove_file(&t.vcd);
}

#[test]
fn sigrok_finds_each_behaviours_duty_and_period() {
    let t = traced();
    let mut duties = std::collections::BTreeSet::new();
    let mut pulsed = 0;
    for (signal, pick) in [("TIOCA1", 0usize), ("TIOCA2", 1usize)] {
        let Some(ann) = sigrok(
            &t.vcd,
            signal,
            &format!("pwm:data={signal}"),
            "pwm=duty-cycle:period",
        ) else {
            return skip();
        };
        for (k, s) in t.steps.iter().enumerate() {
            let wave = if pick == 0 { s.waves.0 } else { s.waves.1 };
            let until = t.steps.get(k + 1).map_or(t.end, |n| n.sensing);
            // Whole PWM periods inside the behaviour (from the end of the step's work to the
            // next step's sensing).
            let inside: Vec<&Annotation> = ann
                .iter()
                .filter(|a| a.0 >= s.asleep && a.1 <= until)
                .collect();
            let expected = 100.0 * wave.high_states as f64 / wave.period_states as f64;
            duties.insert((expected * 1000.0).round() as u64);
            if wave.high_states == 0 || wave.high_states >= wave.period_states {
                // A steady level: no period to decode.
                assert!(inside.is_empty(), "{signal} step {k}: {inside:?}");
                continue;
            }
            let period_us = wave.period_states as f64 * 1e6 / f64::from(t.clock_hz);
            let (mut n_duty, mut n_period) = (0u64, 0u64);
            for (_, _, text) in &inside {
                if let Some(p) = text.strip_suffix('%') {
                    let got: f64 = p.parse().unwrap();
                    assert!(
                        (got - expected).abs() < 1e-4,
                        "{signal} step {k}: {got} vs {expected}"
                    );
                    n_duty += 1;
                } else {
                    assert_eq!(*text, format!("{period_us:.1} μs"), "{signal} step {k}");
                    n_period += 1;
                }
            }
            // Every whole period of the behaviour (but the first, from its first rising edge).
            let whole = (until - s.asleep) / wave.period_states;
            assert!(
                n_duty + 2 >= whole && n_duty <= whole,
                "{n_duty} of {whole}"
            );
            assert_eq!(n_duty, n_period);
            pulsed += 1;
        }
    }
    // Random behaviours over ten steps: more than one duty came up, and the decoder was
    // checked on some behaviours with pulses.
    assert!(duties.len() >= 2, "{duties:?}");
    assert!(pulsed >= 2, "{pulsed} behaviours with pulses");
    let _ = std::fs::remove_file(&t.vcd);
}
