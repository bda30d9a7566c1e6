//! Tests of the figures (`src/plot/`) through their public API: files written and valid,
//! output bytes deterministic, bad data and bad paths reported as errors.

// A test, example or bench may use the host's f64 functions (clippy.toml): it checks the
// models within tolerances, and its own output is not a promised result.
#![allow(clippy::disallowed_methods)]

use h8swarm::plot;
use swarm::experiment::Outline;

use std::path::{Path, PathBuf};

use plot::{
    ArenaFigure, LEARNING_SIZE_PX, LearningFigure, PlotError, Series, arena_figure, learning_figure,
};

/// A fresh, empty folder for one test's files.
fn out_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("plot")
        .join(test);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create test folder");
    dir
}

/// A series of `n` windows of 100 steps following `f`, with a band of ± `band`.
fn series(label: &str, dashed: bool, n: usize, band: f64, f: impl Fn(f64) -> f64) -> Series {
    let x: Vec<f64> = (0..n).map(|i| 50.0 + 100.0 * i as f64).collect();
    let mean: Vec<f64> = x.iter().map(|&x| f(x)).collect();
    Series {
        label: label.to_string(),
        dashed,
        lo: mean.iter().map(|m| m - band).collect(),
        hi: mean.iter().map(|m| m + band).collect(),
        x,
        mean,
        n: Vec::new(),
        repeats: 5,
    }
}

fn learning() -> LearningFigure {
    let wiggle = |x: f64| (x / 370.0).sin();
    LearningFigure {
        title: "Arena, 3 robots, 5 repeats".to_string(),
        x_label: "learning step".to_string(),
        d: vec![
            series("learning", false, 100, 25.0, |x| {
                600.0 - 250.0 * (-x / 2500.0).exp() + 8.0 * wiggle(x)
            }),
            series("learning off", true, 100, 30.0, |x| 390.0 + 6.0 * wiggle(x)),
            series("random walk", true, 100, 30.0, |x| 360.0 - 6.0 * wiggle(x)),
        ],
        collisions: vec![
            series("learning", false, 100, 0.05, |x| {
                0.1 + 0.9 * (-x / 2000.0).exp() + 0.02 * wiggle(x)
            }),
            series("learning off", true, 100, 0.08, |x| 0.7 + 0.03 * wiggle(x)),
            series("random walk", true, 100, 0.08, |x| 0.95 - 0.03 * wiggle(x)),
        ],
        more: Vec::new(),
        held: Vec::new(),
        markers: false,
    }
}

/// A rectangle's corners around `(x, y)` facing `theta`, 0.23 m × 0.18 m like the paper's robots.
fn body(x: f64, y: f64, theta: f64) -> [(f64, f64); 4] {
    let (c, s) = (theta.cos(), theta.sin());
    let at = |a: f64, b: f64| (x + a * c - b * s, y + a * s + b * c);
    [
        at(0.115, 0.09),
        at(-0.115, 0.09),
        at(-0.115, -0.09),
        at(0.115, -0.09),
    ]
}

/// `robots` robots circling inside a `side`-metre square for `steps` steps of 0.45 s.
fn arena(robots: usize, side: f64, steps: usize) -> ArenaFigure {
    let walls = vec![
        [(0.0, 0.0), (side, 0.0)],
        [(side, 0.0), (side, side)],
        [(side, side), (0.0, side)],
        [(0.0, side), (0.0, 0.0)],
    ];
    let mut paths = Vec::new();
    let mut outlines = Vec::new();
    for r in 0..robots {
        let phase = r as f64 * 2.399;
        let centre = (
            side * (0.3 + 0.4 * ((r * 7 % 11) as f64 / 10.0)),
            side * (0.3 + 0.4 * ((r * 3 % 7) as f64 / 6.0)),
        );
        let radius = 0.1 + 0.15 * ((r % 5) as f64 / 4.0);
        let pose = |k: usize| {
            let a = phase + k as f64 * 0.01;
            let p = (
                centre.0 + radius * a.cos() + 0.05 * (3.1 * a).sin(),
                centre.1 + radius * a.sin(),
            );
            (p, a + std::f64::consts::FRAC_PI_2)
        };
        paths.push((0..steps).map(|k| pose(k).0).collect());
        for k in [0, steps / 2, steps - 1] {
            let ((x, y), theta) = pose(k);
            outlines.push(Outline {
                robot: r,
                time_s: k as f64 * 0.45,
                corners: body(x, y, theta),
                heading: (theta.cos(), theta.sin()),
            });
        }
    }
    ArenaFigure {
        title: format!("Arena, {robots} robots"),
        walls,
        paths,
        outlines,
    }
}

/// Width and height from a PNG's IHDR chunk, after checking the signature.
fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert!(
        bytes.len() > 33,
        "too short for a PNG: {} bytes",
        bytes.len()
    );
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR", "first chunk must be IHDR");
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    (be(&bytes[16..20]), be(&bytes[20..24]))
}

/// Checks that every tag opened in an XML text is closed in order; returns the root's name.
fn xml_root(text: &str) -> String {
    let mut stack: Vec<String> = Vec::new();
    let mut root = None;
    let mut rest = text;
    while let Some(open) = rest.find('<') {
        let close = rest[open..].find('>').expect("unterminated tag") + open;
        let tag = &rest[open + 1..close];
        assert!(
            !rest[..open].contains('>'),
            "stray '>' in text: {:?}",
            &rest[..open]
        );
        rest = &rest[close + 1..];
        if tag.starts_with('?') || tag.starts_with('!') {
            continue;
        }
        let name: String = tag
            .trim_start_matches('/')
            .chars()
            .take_while(|c| !c.is_whitespace() && *c != '/')
            .collect();
        if let Some(closing) = tag.strip_prefix('/') {
            assert_eq!(
                stack.pop().as_deref(),
                Some(closing.trim()),
                "mismatched </{closing}>"
            );
        } else if !tag.ends_with('/') {
            root.get_or_insert_with(|| name.clone());
            stack.push(name);
        } else {
            root.get_or_insert_with(|| name.clone());
        }
    }
    assert!(stack.is_empty(), "unclosed tags: {stack:?}");
    root.expect("no element at all")
}

#[test]
fn learning_figure_writes_a_png_and_an_svg_of_the_same_drawing() {
    let dir = out_dir("learning_files");
    let (png, svg) = (dir.join("fig7.png"), dir.join("fig7.svg"));
    learning_figure(&learning(), &png, &svg).expect("draw");

    let bytes = std::fs::read(&png).expect("read png");
    assert_eq!(png_size(&bytes), LEARNING_SIZE_PX);
    // A blank 1600 × 700 image compresses to a few kB; curves, bands and text take far more.
    assert!(
        bytes.len() > 40_000,
        "PNG suspiciously small: {} bytes",
        bytes.len()
    );

    let text = std::fs::read_to_string(&svg).expect("read svg");
    assert_eq!(xml_root(&text), "svg");
    let (w, h) = LEARNING_SIZE_PX;
    assert!(
        text.contains(&format!("width=\"{w}\" height=\"{h}\"")),
        "SVG size"
    );
    for label in [
        "Arena, 3 robots, 5 repeats",
        "learning step",
        "mean summed distance D (du)",
        "collisions per robot per window",
        "learning off",
        "random walk",
    ] {
        assert!(text.contains(label), "SVG lacks {label:?}");
    }
}

#[test]
fn svg_text_is_escaped() {
    let dir = out_dir("learning_escape");
    let mut fig = learning();
    fig.d[0].label = "learning <η = 0.1> & T = 10".to_string();
    fig.title = "corridor & arena".to_string();
    let svg = dir.join("fig.svg");
    learning_figure(&fig, &dir.join("fig.png"), &svg).expect("draw");
    let text = std::fs::read_to_string(&svg).expect("read svg");
    assert_eq!(xml_root(&text), "svg");
    assert!(text.contains("learning &lt;η = 0.1&gt; &amp; T = 10"));
    assert!(text.contains("corridor &amp; arena"));
}

#[test]
fn learning_figure_is_byte_identical_for_the_same_input() {
    let dir = out_dir("learning_deterministic");
    let fig = learning();
    let (png_a, svg_a) = (dir.join("a.png"), dir.join("a.svg"));
    let (png_b, svg_b) = (dir.join("b.png"), dir.join("b.svg"));
    learning_figure(&fig, &png_a, &svg_a).expect("draw a");
    learning_figure(&fig.clone(), &png_b, &svg_b).expect("draw b");
    assert!(
        std::fs::read(&png_a).unwrap() == std::fs::read(&png_b).unwrap(),
        "PNG bytes differ"
    );
    assert!(
        std::fs::read(&svg_a).unwrap() == std::fs::read(&svg_b).unwrap(),
        "SVG bytes differ"
    );

    // And the figure does depend on the data.
    let mut other = fig;
    other.collisions[0].mean[10] += 0.3;
    let png_c = dir.join("c.png");
    learning_figure(&other, &png_c, &dir.join("c.svg")).expect("draw c");
    assert!(std::fs::read(&png_a).unwrap() != std::fs::read(&png_c).unwrap());
}

#[test]
fn single_point_and_flat_series_are_drawn() {
    let dir = out_dir("learning_degenerate");
    let mut fig = learning();
    fig.d = vec![series("one window", false, 1, 0.0, |_| 5.0)];
    fig.collisions = vec![series("flat", true, 20, 0.0, |_| 0.0)];
    let png = dir.join("fig.png");
    learning_figure(&fig, &png, &dir.join("fig.svg")).expect("draw");
    assert_eq!(png_size(&std::fs::read(&png).unwrap()), LEARNING_SIZE_PX);
}

/// Runs `learning_figure` on a broken figure and checks that it fails and writes nothing.
fn learning_error(test: &str, fig: &LearningFigure) -> PlotError {
    let dir = out_dir(test);
    let (png, svg) = (dir.join("fig.png"), dir.join("fig.svg"));
    let err = learning_figure(fig, &png, &svg).expect_err("bad data must be refused");
    assert!(
        !png.exists() && !svg.exists(),
        "nothing may be written for bad data"
    );
    err
}

#[test]
fn non_finite_values_are_errors_naming_the_series() {
    for (field, value) in [
        ("mean", f64::NAN),
        ("lo", f64::INFINITY),
        ("hi", f64::NEG_INFINITY),
        ("x", f64::NAN),
    ] {
        let mut fig = learning();
        let s = &mut fig.collisions[1];
        match field {
            "mean" => s.mean[7] = value,
            "lo" => s.lo[7] = value,
            "hi" => s.hi[7] = value,
            _ => s.x[7] = value,
        }
        let err = learning_error("learning_nan", &fig);
        let message = err.to_string();
        assert!(
            matches!(&err, PlotError::BadValue { panel: "collisions", index: 1, label, field: f, at: 7, .. }
                if label == "learning off" && *f == field),
            "{field}: {err:?}"
        );
        assert!(
            message.contains("learning off") && message.contains(field),
            "{message}"
        );
    }
}

#[test]
fn empty_and_missing_series_are_errors() {
    let mut fig = learning();
    fig.d[2] = series("random walk", true, 0, 1.0, |_| 0.0);
    let err = learning_error("learning_empty", &fig);
    assert!(
        matches!(&err, PlotError::EmptySeries { panel: "D", index: 2, label } if label == "random walk"),
        "{err:?}"
    );
    assert!(err.to_string().contains("random walk"));

    let mut fig = learning();
    fig.collisions.clear();
    let err = learning_error("learning_no_series", &fig);
    assert!(
        matches!(
            err,
            PlotError::NoSeries {
                panel: "collisions"
            }
        ),
        "{err:?}"
    );
}

#[test]
fn mismatched_lengths_and_unordered_x_are_errors() {
    let mut fig = learning();
    fig.d[0].hi.pop();
    let err = learning_error("learning_lengths", &fig);
    assert!(
        matches!(
            err,
            PlotError::LengthMismatch {
                panel: "D",
                index: 0,
                x: 100,
                mean: 100,
                lo: 100,
                hi: 99,
                ..
            }
        ),
        "{err:?}"
    );

    let mut fig = learning();
    fig.d[1].x[5] = fig.d[1].x[4];
    let err = learning_error("learning_order", &fig);
    assert!(
        matches!(
            err,
            PlotError::NotIncreasing {
                panel: "D",
                index: 1,
                at: 5,
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn unwritable_paths_are_errors_naming_the_path() {
    let dir = out_dir("learning_paths");
    let missing = dir.join("no such folder");

    let png = missing.join("fig.png");
    let err = learning_figure(&learning(), &png, &dir.join("fig.svg")).expect_err("png");
    assert!(
        matches!(&err, PlotError::Write { path, .. } if *path == png),
        "{err:?}"
    );
    assert!(
        err.to_string().contains(&png.display().to_string()),
        "{err}"
    );

    let svg = missing.join("fig.svg");
    let err = learning_figure(&learning(), &dir.join("ok.png"), &svg).expect_err("svg");
    assert!(
        matches!(&err, PlotError::Write { path, .. } if *path == svg),
        "{err:?}"
    );
    assert!(
        err.to_string().contains(&svg.display().to_string()),
        "{err}"
    );

    // A folder where the file should be.
    let err = learning_figure(&learning(), &dir.join("ok.png"), &dir).expect_err("dir");
    assert!(
        matches!(&err, PlotError::Write { path, .. } if path == &dir),
        "{err:?}"
    );

    let jpg = dir.join("fig.jpg");
    let err = learning_figure(&learning(), &jpg, &dir.join("fig.svg")).expect_err("jpg");
    assert!(
        matches!(&err, PlotError::NotPng { path } if *path == jpg),
        "{err:?}"
    );
    assert!(!jpg.exists());
}

#[test]
fn arena_figure_writes_a_png_shaped_like_the_arena() {
    let dir = out_dir("arena_files");
    let square = dir.join("square.png");
    arena_figure(&arena(3, 1.8, 2000), &square).expect("draw square");
    let bytes = std::fs::read(&square).unwrap();
    let (w, h) = png_size(&bytes);
    assert!(
        bytes.len() > 40_000,
        "PNG suspiciously small: {} bytes",
        bytes.len()
    );
    // Square arena: the chart left of the legend is about as wide as it is tall.
    assert!(
        (900..1600).contains(&w) && (800..1300).contains(&h),
        "{w} × {h}"
    );

    let mut corridor = arena(3, 1.0, 500);
    corridor.walls = vec![
        [(0.0, 0.0), (3.0, 0.0)],
        [(3.0, 0.0), (3.0, 0.22)],
        [(3.0, 0.22), (0.0, 0.22)],
        [(0.0, 0.22), (0.0, 0.0)],
    ];
    for path in &mut corridor.paths {
        for p in path.iter_mut() {
            *p = (p.0 * 2.0, 0.11);
        }
    }
    corridor.outlines.clear();
    let wide = dir.join("corridor.png");
    arena_figure(&corridor, &wide).expect("draw corridor");
    let (w, h) = png_size(&std::fs::read(&wide).unwrap());
    assert!(
        w > 2 * h,
        "a 3 m × 0.22 m corridor should give a wide image: {w} × {h}"
    );
}

#[test]
fn arena_figure_is_byte_identical_for_the_same_input() {
    let dir = out_dir("arena_deterministic");
    let fig = arena(5, 1.8, 1500);
    let (a, b) = (dir.join("a.png"), dir.join("b.png"));
    arena_figure(&fig, &a).expect("draw a");
    arena_figure(&fig.clone(), &b).expect("draw b");
    assert!(
        std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
        "PNG bytes differ"
    );
}

#[test]
fn a_hundred_robot_arena_renders() {
    let dir = out_dir("arena_hundred");
    let png = dir.join("swarm.png");
    arena_figure(&arena(100, 6.0, 10_000), &png).expect("draw");
    let bytes = std::fs::read(&png).unwrap();
    png_size(&bytes);
    assert!(bytes.len() > 40_000);
}

/// Runs `arena_figure` on a broken figure and checks that it fails and writes nothing.
fn arena_error(test: &str, fig: &ArenaFigure) -> PlotError {
    let png = out_dir(test).join("fig.png");
    let err = arena_figure(fig, &png).expect_err("bad data must be refused");
    assert!(!png.exists(), "nothing may be written for bad data");
    err
}

#[test]
fn bad_arena_data_are_errors_naming_the_item() {
    let mut fig = arena(3, 1.8, 100);
    fig.paths[2][40].1 = f64::NAN;
    let err = arena_error("arena_nan_path", &fig);
    assert!(
        err.to_string().contains("path of robot 2, point 40"),
        "{err}"
    );

    let mut fig = arena(3, 1.8, 100);
    fig.walls[1][0].0 = f64::INFINITY;
    let err = arena_error("arena_inf_wall", &fig);
    assert!(err.to_string().contains("wall 1"), "{err}");

    let mut fig = arena(3, 1.8, 100);
    fig.outlines[4].time_s = f64::NAN;
    let err = arena_error("arena_nan_time", &fig);
    assert!(err.to_string().contains("outline 4, time_s"), "{err}");

    let mut fig = arena(3, 1.8, 100);
    fig.outlines[0].heading = (0.0, 0.0);
    let err = arena_error("arena_zero_heading", &fig);
    assert!(
        matches!(err, PlotError::ZeroHeading { index: 0 }),
        "{err:?}"
    );

    let mut fig = arena(3, 1.8, 100);
    fig.outlines[1].robot = 3;
    let err = arena_error("arena_unknown_robot", &fig);
    assert!(
        matches!(
            err,
            PlotError::UnknownRobot {
                index: 1,
                robot: 3,
                robots: 3
            }
        ),
        "{err:?}"
    );

    let empty = ArenaFigure {
        title: "empty".to_string(),
        walls: Vec::new(),
        paths: vec![Vec::new(); 3],
        outlines: Vec::new(),
    };
    let err = arena_error("arena_empty", &empty);
    assert!(matches!(err, PlotError::NothingToDraw), "{err:?}");
}

#[test]
fn arena_paths_may_be_empty_and_unnormalised_headings_are_accepted() {
    let dir = out_dir("arena_sparse");
    let mut fig = arena(3, 1.8, 100);
    fig.paths[1].clear();
    fig.outlines[0].heading = (3.0, 4.0);
    let png = dir.join("fig.png");
    arena_figure(&fig, &png).expect("draw");
    png_size(&std::fs::read(&png).unwrap());
}

#[test]
fn unwritable_arena_path_is_an_error_naming_it() {
    let dir = out_dir("arena_paths");
    let png = dir.join("missing").join("fig.png");
    let err = arena_figure(&arena(3, 1.8, 100), &png).expect_err("missing folder");
    assert!(
        matches!(&err, PlotError::Write { path, .. } if *path == png),
        "{err:?}"
    );
    assert!(
        err.to_string().contains(&png.display().to_string()),
        "{err}"
    );

    let svg = dir.join("fig.svg");
    let err = arena_figure(&arena(3, 1.8, 100), &svg).expect_err("not png");
    assert!(matches!(err, PlotError::NotPng { .. }), "{err:?}");
}

/// Seeded random sweeps over valid inputs (including extreme magnitudes and tiny spans): every
/// valid figure must be drawn, with no panic, no hang and no error. Seeded generators rather
/// than proptest keep this file on the root package's existing dependencies.
mod sweeps {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    const CASES: u64 = 24;

    /// A value anywhere in the accepted range, with the small scales well represented.
    fn value(rng: &mut ChaCha8Rng) -> f64 {
        match rng.random_range(0..4) {
            0 => 0.0,
            1 => rng.random_range(-1.0..1.0),
            2 => rng.random_range(0.0..1000.0),
            _ => rng.random_range(-plot::MAX_ABS_VALUE..plot::MAX_ABS_VALUE),
        }
    }

    fn label(rng: &mut ChaCha8Rng) -> String {
        let chars: Vec<char> = "abcXYZ η<&> 0123".chars().collect();
        let n = rng.random_range(0..30);
        (0..n)
            .map(|_| chars[rng.random_range(0..chars.len())])
            .collect()
    }

    fn random_series(rng: &mut ChaCha8Rng) -> Series {
        let n = rng.random_range(1..40);
        let mut x: Vec<f64> = Vec::with_capacity(n);
        for _ in 0..n {
            let step = match rng.random_range(0..3) {
                0 => rng.random_range(1e-9..1e-3),
                1 => rng.random_range(0.5..2.0),
                _ => rng.random_range(1e3..1e6),
            };
            let next = x.last().map_or_else(
                || rng.random_range(-1e6..1e6),
                |&prev: &f64| (prev + step).max(prev.next_up()),
            );
            x.push(next);
        }
        Series {
            label: label(rng),
            dashed: rng.random(),
            mean: (0..n).map(|_| value(rng)).collect(),
            lo: (0..n).map(|_| value(rng)).collect(),
            hi: (0..n).map(|_| value(rng)).collect(),
            n: if rng.random() {
                Vec::new()
            } else {
                (0..n).map(|_| rng.random_range(1..6)).collect()
            },
            repeats: 5,
            x,
        }
    }

    fn coord(rng: &mut ChaCha8Rng) -> f64 {
        match rng.random_range(0..3) {
            0 => rng.random_range(-2.0..2.0),
            1 => rng.random_range(-plot::MAX_ABS_COORD_M..plot::MAX_ABS_COORD_M),
            _ => rng.random_range(-1e-9..1e-9),
        }
    }

    fn point(rng: &mut ChaCha8Rng) -> (f64, f64) {
        (coord(rng), coord(rng))
    }

    fn random_arena(rng: &mut ChaCha8Rng) -> ArenaFigure {
        let robots = rng.random_range(1..6);
        ArenaFigure {
            title: label(rng),
            walls: (0..rng.random_range(0..6))
                .map(|_| [point(rng), point(rng)])
                .collect(),
            paths: (0..robots)
                .map(|_| (0..rng.random_range(0..50)).map(|_| point(rng)).collect())
                .collect(),
            outlines: (0..rng.random_range(0..8))
                .map(|_| Outline {
                    robot: rng.random_range(0..robots),
                    time_s: rng.random_range(-1e9..1e9),
                    corners: [point(rng), point(rng), point(rng), point(rng)],
                    heading: (rng.random_range(-1.0..1.0), rng.random_range(0.01..1.0)),
                })
                .collect(),
        }
    }

    #[test]
    fn random_valid_learning_figures_are_drawn() {
        let dir = out_dir("sweep_learning");
        for case in 0..CASES {
            let mut rng = ChaCha8Rng::seed_from_u64(case);
            let fig = LearningFigure {
                title: label(&mut rng),
                x_label: label(&mut rng),
                d: (0..rng.random_range(1..4))
                    .map(|_| random_series(&mut rng))
                    .collect(),
                collisions: (0..rng.random_range(1..4))
                    .map(|_| random_series(&mut rng))
                    .collect(),
                more: Vec::new(),
                held: Vec::new(),
                markers: rng.random(),
            };
            let result = learning_figure(&fig, &dir.join("fig.png"), &dir.join("fig.svg"));
            assert!(result.is_ok(), "case {case}: {result:?}");
        }
    }

    #[test]
    fn random_valid_arena_figures_are_drawn() {
        let dir = out_dir("sweep_arena");
        for case in 0..CASES {
            let mut rng = ChaCha8Rng::seed_from_u64(case);
            let fig = random_arena(&mut rng);
            let result = arena_figure(&fig, &dir.join("fig.png"));
            let nothing = fig.walls.is_empty()
                && fig.outlines.is_empty()
                && fig.paths.iter().all(Vec::is_empty);
            if nothing {
                assert!(
                    matches!(result, Err(PlotError::NothingToDraw)),
                    "case {case}: {result:?}"
                );
            } else {
                assert!(result.is_ok(), "case {case}: {result:?}");
            }
        }
    }
}

#[test]
fn six_panels_with_the_held_overlay_and_side_by_side_arenas_are_drawn() {
    let dir = out_dir("four_panels");
    let mut fig = learning();
    let panel = |caption: &str, series: &[Series], held_overlay| h8swarm::plot::Panel {
        caption: caption.into(),
        y_label: "y".into(),
        series: series.to_vec(),
        held_overlay,
    };
    fig.more = vec![
        panel("Collisions per metre", &fig.collisions, true),
        panel("Contact time", &fig.d, false),
    ];
    fig.held = fig
        .collisions
        .iter()
        .map(|s| Series {
            mean: s.mean.iter().map(|m| 50.0 * m).collect(),
            lo: s.lo.iter().map(|m| 50.0 * m).collect(),
            hi: s.hi.iter().map(|m| 50.0 * m).collect(),
            ..s.clone()
        })
        .collect();
    let (png, svg) = (dir.join("fig.png"), dir.join("fig.svg"));
    learning_figure(&fig, &png, &svg).expect("draw");
    let (w, h2) = png_size(&std::fs::read(&png).unwrap());
    assert_eq!(w, LEARNING_SIZE_PX.0);
    assert!(h2 > LEARNING_SIZE_PX.1 + 400, "a second row: {h2}");
    fig.more.push(panel("Gap CV", &fig.d, false));
    fig.more.push(panel("Moving", &fig.d, false));
    fig.markers = true;
    learning_figure(&fig, &png, &svg).expect("draw");
    let (_, h3) = png_size(&std::fs::read(&png).unwrap());
    assert!(h3 > h2 + 400, "a third row: {h3} after {h2}");
    let svg_text = std::fs::read_to_string(&svg).unwrap();
    assert!(svg_text.contains("held robot-steps"), "the right-hand axis");
    let panels = dir.join("arena.png");
    h8swarm::plot::arena_figure_panels(&[arena(3, 1.8, 200), arena(3, 1.8, 200)], &panels)
        .expect("draw panels");
    let (pw, _) = png_size(&std::fs::read(&panels).unwrap());
    let single = dir.join("one.png");
    arena_figure(&arena(3, 1.8, 200), &single).expect("draw one");
    let (sw, _) = png_size(&std::fs::read(&single).unwrap());
    assert_eq!(pw, 2 * sw);
}

/// A robot that reverses (forward, then backward along almost the same line) near the left
/// wall: every pixel its path colours lies inside the walls. Drawn as one wide polyline,
/// plotters' mitre joins made spikes reaching past the wall.
#[test]
fn arena_paths_stay_inside_the_walls() {
    let side = 1.8;
    let walls = vec![
        [(0.0, 0.0), (side, 0.0)],
        [(side, 0.0), (side, side)],
        [(side, side), (0.0, side)],
        [(0.0, side), (0.0, 0.0)],
    ];
    let path: Vec<(f64, f64)> = (0..40)
        .map(|i| (0.15 + 0.25 * f64::from(i % 2), 0.9 + 0.002 * f64::from(i)))
        .collect();
    let fig = |path: Vec<(f64, f64)>| ArenaFigure {
        title: "reversals".into(),
        walls: walls.clone(),
        paths: vec![path],
        outlines: Vec::new(),
    };
    let (size, with) = plot::render_arena(&fig(path)).expect("draw");
    let (size2, without) = plot::render_arena(&fig(Vec::new())).expect("draw");
    assert_eq!(size, size2, "the same layout with and without the path");
    let (w, h) = (size.0 as usize, size.1 as usize);
    let px = |img: &[u8], x: usize, y: usize| {
        let i = (y * w + x) * 3;
        (img[i], img[i + 1], img[i + 2])
    };
    // The walls: columns and rows with many pixels of the wall colour.
    let wall = |x: usize, y: usize| px(&without, x, y) == (40, 40, 40);
    let cols: Vec<usize> = (0..w)
        .filter(|&x| (0..h).filter(|&y| wall(x, y)).count() > 100)
        .collect();
    let rows: Vec<usize> = (0..h)
        .filter(|&y| (0..w).filter(|&x| wall(x, y)).count() > 100)
        .collect();
    let (x0, x1) = (cols[0], *cols.last().unwrap());
    let (y0, y1) = (rows[0], *rows.last().unwrap());
    assert!(
        x1 > x0 + 500 && y1 > y0 + 500,
        "walls found: {x0}..{x1} x {y0}..{y1}"
    );
    let mut drawn = 0;
    for y in 0..h {
        for x in 0..w {
            if px(&with, x, y) != px(&without, x, y) {
                drawn += 1;
                assert!(
                    (x0..=x1).contains(&x) && (y0..=y1).contains(&y),
                    "path pixel ({x}, {y}) outside the walls {x0}..{x1} x {y0}..{y1}"
                );
            }
        }
    }
    assert!(drawn > 1000, "the path was drawn: {drawn} pixels");
}

/// The corridor's space-time figure draws, and refuses bad data.
#[test]
fn the_space_time_figure_is_drawn() {
    let dir = out_dir("spacetime");
    let paths: Vec<Vec<(f64, f64)>> = (0..3)
        .map(|r| {
            (0..500)
                .map(|k| {
                    let k = f64::from(k);
                    (
                        k,
                        0.5 + f64::from(r) * 0.9 + 0.2 * (k / 40.0 + f64::from(r)).sin(),
                    )
                })
                .collect()
        })
        .collect();
    let fig = plot::SpaceTimeFigure {
        title: "corridor".into(),
        length_m: 3.0,
        body_m: 0.23,
        paths,
    };
    let png = dir.join("st.png");
    plot::spacetime_figure(&fig, &png).expect("draw");
    assert_eq!(
        png_size(&std::fs::read(&png).unwrap()),
        plot::SPACETIME_SIZE_PX
    );
    let mut bad = fig.clone();
    bad.paths[1][7].1 = f64::NAN;
    assert!(matches!(
        plot::spacetime_figure(&bad, &png),
        Err(PlotError::ArenaBadValue { .. })
    ));
    let empty = plot::SpaceTimeFigure {
        paths: vec![Vec::new()],
        ..fig
    };
    assert!(matches!(
        plot::spacetime_figure(&empty, &png),
        Err(PlotError::NothingToDraw)
    ));
}

/// The SVG's rotated axis titles: (x, y, font size, angle, text).
fn axis_titles(svg: &str) -> Vec<(f64, f64, f64, u32, String)> {
    let mut out = Vec::new();
    let mut rest = svg;
    while let Some(at) = rest.find("<text ") {
        rest = &rest[at..];
        let end = rest.find("</text>").unwrap();
        let element = &rest[..end];
        rest = &rest[end..];
        let attr = |name: &str| -> Option<&str> {
            let k = element.find(&format!(" {name}=\""))? + name.len() + 3;
            Some(&element[k..k + element[k..].find('"')?])
        };
        let Some(transform) = attr("transform") else {
            continue;
        };
        let angle: u32 = transform
            .trim_start_matches("rotate(")
            .split(',')
            .next()
            .unwrap()
            .trim()
            .parse()
            .unwrap();
        let num = |name| attr(name).unwrap().parse::<f64>().unwrap();
        let text = element[element.find('>').unwrap() + 1..].trim().to_string();
        out.push((num("x"), num("y"), num("font-size"), angle, text));
    }
    out
}

/// The right-hand axis title of a panel with the held overlay keeps clear of the y-axis title
/// of the panel beside it: at least one and a half letters' height between the two (they were
/// 22 px apart at a 15 px font, reading as one label running into the next panel).
#[test]
fn a_right_axis_title_keeps_clear_of_the_next_panel_s() {
    let dir = out_dir("axis_titles");
    let mut fig = learning();
    let panel = |caption: &str, series: &[Series], held_overlay| h8swarm::plot::Panel {
        caption: caption.into(),
        y_label: "% of robot time".into(),
        series: series.to_vec(),
        held_overlay,
    };
    fig.more = vec![
        panel("Collisions per net metre", &fig.collisions, true),
        panel("Contact time", &fig.d, false),
    ];
    fig.held = fig.collisions.clone();
    let (png, svg) = (dir.join("fig.png"), dir.join("fig.svg"));
    learning_figure(&fig, &png, &svg).expect("draw");
    let titles = axis_titles(&std::fs::read_to_string(&svg).unwrap());
    let right: Vec<_> = titles.iter().filter(|t| t.3 == 90).collect();
    assert_eq!(right.len(), 2, "two panels carry the overlay: {titles:?}");
    let mut checked = 0;
    for r in right {
        for l in titles.iter().filter(|t| t.3 == 270 && t.0 > r.0) {
            // Side by side when their vertical spans overlap.
            if (l.1 - r.1).abs() < 200.0 {
                assert!(
                    l.0 - r.0 >= 1.5 * r.2,
                    "`{}` at x = {} and `{}` at x = {}: {} px apart at a {} px font",
                    r.4,
                    r.0,
                    l.4,
                    l.0,
                    l.0 - r.0,
                    r.2
                );
                checked += 1;
            }
        }
    }
    assert_eq!(
        checked, 1,
        "the bottom-left panel has a neighbour: {checked}"
    );
}

/// A point that rests on fewer repeats than the condition ran is drawn as an open circle with
/// its count, the legend says so, and no band is drawn through it (learning off's collisions
/// per metre were drawn as 0.00 with a zero-width band where 3 of 5 repeats had a value).
#[test]
fn points_resting_on_fewer_repeats_are_marked_and_have_no_band() {
    let dir = out_dir("partial_points");
    let polygons = |fig: &LearningFigure| -> usize {
        let (png, svg) = (dir.join("fig.png"), dir.join("fig.svg"));
        learning_figure(fig, &png, &svg).expect("draw");
        std::fs::read_to_string(&svg)
            .unwrap()
            .matches("<polygon")
            .count()
    };
    let mut fig = learning();
    fig.d.truncate(1);
    fig.collisions.truncate(1);
    let full = polygons(&fig);
    // One point in the middle of the collisions curve rests on 3 of 5 repeats: its band is cut
    // in two.
    let k = fig.collisions[0].x.len() / 2;
    let mut n = vec![5; fig.collisions[0].x.len()];
    n[k] = 3;
    fig.collisions[0].n = n;
    assert_eq!(
        polygons(&fig),
        full + 1,
        "the band cut in two at the partial point"
    );
    let svg = std::fs::read_to_string(dir.join("fig.svg")).unwrap();
    assert!(
        svg.contains("open circle: a window in which fewer repeats"),
        "the note"
    );
    assert!(svg.contains(">\n3\n</text>"), "its count beside it");
    // Every point partial: no band at all for that curve.
    fig.collisions[0].n = vec![3; fig.collisions[0].x.len()];
    assert_eq!(polygons(&fig), full - 1);
    // A count per point or none.
    fig.collisions[0].n = vec![3; 2];
    let err = learning_figure(&fig, &dir.join("x.png"), &dir.join("x.svg")).unwrap_err();
    assert!(matches!(err, PlotError::CountMismatch { .. }), "{err:?}");
}
