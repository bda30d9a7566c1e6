//! The replay viewer in a real browser: `h8swarm run --replay` writes `replay.html`, Debian's
//! Chromium opens it headless from the file system, and the page is driven through the DevTools
//! protocol (a WebSocket; `tungstenite`). Checked: it loads with no console error or exception;
//! the robots it draws at a step are where the simulation had them (the truth comes from
//! stepping the same run through the library, not from the file); scrubbing lands on the frame
//! asked for; the inspector shows the selected robot's readings; model and firmware robots,
//! arena and corridor. The frame rate at 1 000 robots is measured and printed (a speed figure,
//! not an assertion).
//!
//! Skips, saying so, where no Chromium is installed (`H8SWARM_CHROMIUM` names one; else
//! `chromium`, `chromium-browser` on the PATH); `.ci/run` installs Debian's.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use swarm::experiment::Swarm;
use swarm::motion::{MotionClass, MotionTracker};
use swarm::robot::Condition;
use swarm::scenario::Scenario;

fn chromium() -> Option<PathBuf> {
    if let Ok(p) = std::env::var("H8SWARM_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|d| ["chromium", "chromium-browser"].map(|n| d.join(n)))
        .find(|p| p.is_file())
}

fn temp_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("viewer")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&str], out: &Path) {
    let o = Command::new(env!("CARGO_BIN_EXE_h8swarm"))
        .args(args)
        .args(["--replay", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A headless Chromium with a DevTools endpoint; killed when dropped.
struct Browser {
    child: Child,
    port: u16,
    _profile: PathBuf,
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Browser {
    fn start(exe: &Path, profile: PathBuf) -> Browser {
        let mut child = Command::new(exe)
            .args([
                "--headless=new",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--window-size=1400,1000",
                "--remote-debugging-port=0",
                "--remote-allow-origins=*",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg("about:blank")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start chromium");
        let stderr = child.stderr.take().unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                if let Some(rest) = line.split("DevTools listening on ws://127.0.0.1:").nth(1) {
                    let port: u16 = rest.split('/').next().unwrap().parse().unwrap();
                    let _ = tx.send(port);
                }
            }
        });
        let port = rx
            .recv_timeout(Duration::from_secs(60))
            .expect("chromium printed no DevTools address");
        Browser {
            child,
            port,
            _profile: profile,
        }
    }

    /// A new tab showing `url`; its DevTools WebSocket.
    fn open(&self, url: &str) -> Tab {
        let mut s = TcpStream::connect(("127.0.0.1", self.port)).unwrap();
        let path = format!("/json/new?{url}");
        write!(
            s,
            "PUT {path} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nConnection: close\r\n\r\n",
            self.port
        )
        .unwrap();
        // Chromium keeps the connection open: read the headers, then Content-Length bytes.
        let mut r = BufReader::new(s);
        let mut length = 0usize;
        loop {
            let mut line = String::new();
            r.read_line(&mut line).unwrap();
            let line = line.trim_end();
            if line.is_empty() {
                break;
            }
            if let Some(v) = line.to_ascii_lowercase().strip_prefix("content-length:") {
                length = v.trim().parse().unwrap();
            }
        }
        let mut body = vec![0u8; length];
        r.read_exact(&mut body).unwrap();
        let target: Value = serde_json::from_slice(&body).unwrap();
        let ws = target["webSocketDebuggerUrl"].as_str().unwrap().to_string();
        let (socket, _) = tungstenite::connect(ws).expect("connect to the tab");
        let mut tab = Tab {
            socket,
            next_id: 1,
            events: Vec::new(),
        };
        tab.call("Runtime.enable", json!({}));
        tab
    }
}

struct Tab {
    socket: tungstenite::WebSocket<tungstenite::stream::MaybeTlsStream<TcpStream>>,
    next_id: u64,
    events: Vec<Value>,
}

impl Tab {
    fn call(&mut self, method: &str, params: Value) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        let msg = json!({"id": id, "method": method, "params": params}).to_string();
        self.socket
            .send(tungstenite::Message::Text(msg.into()))
            .unwrap();
        loop {
            let m = self.socket.read().expect("read from the tab");
            let tungstenite::Message::Text(text) = m else {
                continue;
            };
            let v: Value = serde_json::from_str(&text).unwrap();
            if v["id"] == id {
                return v;
            }
            self.events.push(v);
        }
    }

    /// Evaluates `expr` (awaiting a promise) and returns its value.
    fn eval(&mut self, expr: &str) -> Value {
        let r = self.call(
            "Runtime.evaluate",
            json!({"expression": expr, "awaitPromise": true, "returnByValue": true}),
        );
        assert!(
            r["result"]["exceptionDetails"].is_null(),
            "{expr}: {}",
            r["result"]["exceptionDetails"]
        );
        r["result"]["result"]["value"].clone()
    }

    /// Console errors and warnings, and exceptions, seen so far.
    fn complaints(&self) -> Vec<String> {
        self.events
            .iter()
            .filter_map(|e| match e["method"].as_str() {
                Some("Runtime.exceptionThrown") => Some(e["params"].to_string()),
                Some("Runtime.consoleAPICalled")
                    if matches!(e["params"]["type"].as_str(), Some("error" | "warning")) =>
                {
                    Some(e["params"].to_string())
                }
                _ => None,
            })
            .collect()
    }
}

/// Waits until the page's recording is loaded (or failed).
fn ready(tab: &mut Tab) {
    let t0 = Instant::now();
    loop {
        let v = tab.eval(
            "typeof h8 === 'object' && h8.ready ? h8.ready.then(() => h8.runs().length) : -1",
        );
        if v.as_i64().unwrap_or(-1) >= 0 {
            return;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the page never got ready"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// The robots' poses at step `k` of the learning run's repeat 0, from the library.
/// Each robot's pose (x, y, heading) at a step instant.
type Poses = Vec<(f64, f64, f64)>;

/// Where the robots are at step `k`'s instant, and the motion class of each one's step
/// before it (none at step 0), as the run's own trackers classify them.
fn truth(
    s: &Scenario,
    images: Option<&swarm::robot::Images>,
    k: u32,
) -> (Poses, Vec<Option<MotionClass>>) {
    let mut swarm = Swarm::new(s, Condition::Learning, 0, false, images).unwrap();
    let mut trackers = vec![MotionTracker::new(); s.robots];
    let mut classes = vec![None; s.robots];
    for (i, t) in trackers.iter_mut().enumerate() {
        let p = swarm.world().pose(i).unwrap();
        t.start(p.x_m, p.y_m);
    }
    for step in 0..=k {
        swarm.step().unwrap();
        if step > 0 {
            for (i, t) in trackers.iter_mut().enumerate() {
                let p = swarm.world().pose(i).unwrap();
                classes[i] = Some(t.record(p.x_m, p.y_m).class);
            }
        }
    }
    let poses = (0..s.robots)
        .map(|i| {
            let p = swarm.world().pose(i).unwrap();
            (p.x_m, p.y_m, p.heading_rad)
        })
        .collect();
    (poses, classes)
}

fn angle_gap(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    d.min(std::f64::consts::TAU - d)
}

/// Opens a run's page, checks the drawing at step `k` against the truth, scrubbing, the
/// inspector, and that nothing complained.
fn check_page(browser: &Browser, dir: &Path, s: &Scenario, k: u32, controller: &str) {
    let url = format!("file://{}", dir.join("replay.html").display());
    let mut tab = browser.open(&url);
    ready(&mut tab);
    let header = tab.eval("h8.header()");
    assert_eq!(header["controller"], controller);
    assert_eq!(header["robots"].as_u64().unwrap() as usize, s.robots);
    let runs = tab.eval("h8.runs()");
    let want_runs = if s.controls.random_walk { 3 } else { 1 };
    assert_eq!(runs.as_array().unwrap().len(), want_runs, "{runs}");
    assert_eq!(
        tab.eval(&format!("h8.setRun(0); h8.setFrame({k}); h8.step()")),
        k
    );
    let drawn = tab.eval("h8.drawn()");
    let images = swarm::robot::Images::load(s).unwrap();
    let (truth, classes) = truth(s, images.as_ref(), k);
    for (i, (x, y, h)) in truth.iter().enumerate() {
        let d = &drawn[i];
        let (dx, dy, dh) = (
            d["x_m"].as_f64().unwrap(),
            d["y_m"].as_f64().unwrap(),
            d["heading_rad"].as_f64().unwrap(),
        );
        assert!(
            (dx - x).abs() < 0.0015 && (dy - y).abs() < 0.0015,
            "robot {i} at step {k}: drawn at ({dx:.4}, {dy:.4}), was at ({x:.4}, {y:.4})"
        );
        assert!(
            angle_gap(dh, *h) < 0.03,
            "robot {i} at step {k}: drawn heading {dh:.3}, was {h:.3}"
        );
    }
    // Scrubbing: the timeline's input moves the frame, the label follows.
    let frames = runs[0]["frames"].as_u64().unwrap();
    for f in [0, frames / 2, frames - 1] {
        let got = tab.eval(&format!(
            "(() => {{ const s = document.getElementById('scrub'); s.value = '{f}'; s.dispatchEvent(new Event('input')); return [h8.frame(), h8.where()]; }})()"
        ));
        assert_eq!(got[0], f);
        let step = f * u64::from(header["stride"].as_u64().unwrap() as u32);
        assert!(
            got[1]
                .as_str()
                .unwrap()
                .starts_with(&format!("step {step} of")),
            "{got}"
        );
    }
    // The inspector: click-free selection through the API, then the panel's text.
    tab.eval(&format!("h8.setFrame({k}); h8.select(1)"));
    let rec = tab.eval(&format!("h8.recorded({k}, 1)"));
    let insp = tab.eval("h8.inspector()");
    assert!(
        insp["title"].as_str().unwrap().starts_with("robot 1 ("),
        "{insp}"
    );
    let p: Vec<String> = rec["p"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.to_string())
        .collect();
    let facts = insp["facts"].as_str().unwrap();
    assert!(facts.contains(&p.join(" / ")), "{insp} {rec}");
    // The motion class the run gave robot 1's last step, and where it went.
    let want = classes[1].map_or("(from the first step on)", MotionClass::name);
    assert!(facts.contains(&format!("motion     {want}")), "{facts}");
    assert!(
        facts.contains("net, path  ") && facts.contains("cells      "),
        "{facts}"
    );
    // A click on robot 1's drawn centre selects it too.
    tab.eval("h8.select(-1)");
    let picked = tab.eval(
        "(() => { const c = document.getElementById('arena'); const r = c.getBoundingClientRect(); const d = h8.drawnPx()[1]; c.dispatchEvent(new MouseEvent('click', {clientX: r.left + d[0], clientY: r.top + d[1]})); return h8.selected(); })()",
    );
    assert_eq!(picked, 1);
    let complaints = tab.complaints();
    assert!(complaints.is_empty(), "{complaints:?}");
    assert!(tab.eval("h8.errors()").as_array().unwrap().is_empty());
}

#[test]
fn the_viewer_shows_the_run_as_recorded() {
    let Some(exe) = chromium() else {
        eprintln!("SKIPPED: no Chromium (install Debian's `chromium`, or set H8SWARM_CHROMIUM)");
        return;
    };
    let root = temp_dir("shows");
    let browser = Browser::start(&exe, root.join("profile"));
    // Model robots in the arena (10 robots), every step recorded.
    let arena = root.join("arena");
    run(
        &[
            "run",
            "arena",
            "--robots",
            "10",
            "--steps",
            "120",
            "--repeats",
            "1",
        ],
        &arena,
    );
    let s = Scenario::arena()
        .with_overrides(Some(10), Some(120), Some(1), None)
        .unwrap();
    check_page(&browser, &arena, &s, 77, "model");
    // The corridor, with a stride: frame 20 is step 40.
    let corridor = root.join("corridor");
    run(
        &[
            "run",
            "corridor",
            "--steps",
            "100",
            "--repeats",
            "1",
            "--replay-stride",
            "2",
        ],
        &corridor,
    );
    let s = Scenario::corridor()
        .with_overrides(None, Some(100), Some(1), None)
        .unwrap();
    let url = format!("file://{}", corridor.join("replay.html").display());
    let mut tab = browser.open(&url);
    ready(&mut tab);
    assert_eq!(tab.eval("h8.setFrame(20); h8.step()"), 40);
    let drawn = tab.eval("h8.drawn()");
    for (i, (x, y, _)) in truth(&s, None, 40).0.iter().enumerate() {
        let (dx, dy) = (
            drawn[i]["x_m"].as_f64().unwrap(),
            drawn[i]["y_m"].as_f64().unwrap(),
        );
        assert!((dx - x).abs() < 0.0015 && (dy - y).abs() < 0.0015, "{i}");
    }
    assert!(tab.complaints().is_empty(), "{:?}", tab.complaints());
    // Firmware robots (3), learning only.
    let fw = root.join("firmware");
    run(
        &[
            "run",
            "scenarios/arena-learning-only.toml",
            "--controller",
            "firmware",
            "--steps",
            "60",
            "--repeats",
            "1",
        ],
        &fw,
    );
    let mut s = Scenario::load("scenarios/arena-learning-only.toml")
        .unwrap()
        .with_overrides(None, Some(60), Some(1), None)
        .unwrap();
    s.controller.kind = swarm::scenario::ControllerKind::Firmware;
    check_page(&browser, &fw, &s, 41, "firmware");
    // The largest seed, and one robot of three recorded: the title says both as they are (the
    // seed once came out as 18446744073709552000, through a JavaScript number).
    let big = root.join("big-seed");
    run(
        &[
            "run",
            "arena",
            "--steps",
            "20",
            "--repeats",
            "1",
            "--seed",
            "18446744073709551615",
            "--replay-robots",
            "1",
        ],
        &big,
    );
    let url = format!("file://{}", big.join("replay.html").display());
    let mut tab = browser.open(&url);
    ready(&mut tab);
    let title = tab.eval("document.getElementById('title').textContent");
    let title = title.as_str().unwrap();
    assert!(
        title.contains("seed 18446744073709551615") && title.contains("1 of 3 robots recorded"),
        "{title}"
    );
    assert!(tab.complaints().is_empty(), "{:?}", tab.complaints());
}

/// 1 000 robots: the page loads and draws; its drawing rate is measured and printed.
#[test]
fn a_thousand_robots_play() {
    let Some(exe) = chromium() else {
        eprintln!("SKIPPED: no Chromium (install Debian's `chromium`, or set H8SWARM_CHROMIUM)");
        return;
    };
    let root = temp_dir("thousand");
    let browser = Browser::start(&exe, root.join("profile"));
    let dir = root.join("run");
    run(
        &[
            "run",
            "scenarios/arena-learning-only.toml",
            "--robots",
            "1000",
            "--steps",
            "40",
            "--repeats",
            "1",
        ],
        &dir,
    );
    let url = format!("file://{}", dir.join("replay.html").display());
    let mut tab = browser.open(&url);
    ready(&mut tab);
    let fps = tab.eval("h8.select(500); h8.measureFps(40)");
    let fps = fps.as_f64().unwrap();
    eprintln!(
        "viewer: 1 000 robots, {fps:.1} frames drawn per second (trails, rays, inspector, curves)"
    );
    assert!(fps.is_finite() && fps > 0.0);
    assert!(tab.complaints().is_empty(), "{:?}", tab.complaints());
}
