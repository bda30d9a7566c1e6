//! The error and warning lines the guide shows, checked against the tool. Every line of a code
//! block, and every inline code span, in README.md, docs/**/*.md and the folders' READMEs that
//! begins `error:` or `warning:` must be registered in [`CASES`] with the command and input
//! that produce it; the test runs each command and checks that the tool prints that line on
//! standard error (a `...` or `…` in the doc stands for any text; a case may name the number
//! the doc shows for the process id) with the documented exit status. A doc line the test does
//! not know fails it, and so does a case that no doc shows any more. When a code block shows
//! the command (`$ h8swarm …` above the line), the case's command must be that one.

#[path = "common/guide.rs"]
mod guide;

use pulldown_cmark::{CodeBlockKind, Event, Parser, Tag, TagEnd};
use std::path::PathBuf;
use std::process::{Command, Stdio};

/// One documented diagnostic and how to make the tool print it.
struct Case {
    /// The line exactly as the docs show it.
    doc: &'static str,
    /// The arguments after `h8swarm`.
    args: &'static [&'static str],
    /// Files written into a fresh folder that is the working directory; `None` runs in the
    /// repository's root (for the committed images the docs name by their path).
    files: Option<&'static [(&'static str, &'static str)]>,
    /// The exit status the docs give for it.
    status: i32,
    /// The number the doc shows where the tool prints its process id.
    pid_shown_as: Option<&'static str>,
}

/// The first lines of a replay file: the header of `examples/replay-arena.jsonl`, then a step
/// whose fifth input is out of the Q7 range.
const BAD_REPLAY: &str = "{\"n_in\": 13, \"n_out\": 4, \"eta\": 3277, \"threshold\": 10, \
\"weights\": [[0,0,0,0,0,0,0,0,0,0,0,0,0],[0,0,0,0,0,0,0,0,0,0,0,0,0],\
[0,0,0,0,0,0,0,0,0,0,0,0,0],[0,0,0,0,0,0,0,0,0,0,0,0,0]]}\n\
{\"x\": [22, 106, -99, 55, 200, -25, 114, -15, -101, 22, -50, -116, 57], \"e\": 5}\n";

const CASES: &[Case] = &[
    // docs/limits-and-failures.md: the form of every failure.
    Case {
        doc: "error: …",
        args: &["run", "missing.toml"],
        files: Some(&[]),
        status: 2,
        pid_shown_as: None,
    },
    // docs/guide/run.md: a scenario file's mistakes, a crowd that does not fit, an output
    // folder that cannot be made.
    Case {
        doc: "error: scenario file `bad.toml`: line 3, column 1 (`etaa = 0.1`): unknown field `etaa`, expected one of `behaviours`, `eta`, `threshold`, `history`, `bias`, `save_every`",
        args: &["run", "bad.toml"],
        files: Some(&[("bad.toml", "[learner]\neta = 0.1\netaa = 0.1\n")]),
        status: 2,
        pid_shown_as: None,
    },
    Case {
        doc: "error: scenario file `bad.toml`: `learner.eta` = 1.5 is out of range: valid is 0 to 0.999969482421875",
        args: &["run", "bad.toml"],
        files: Some(&[("bad.toml", "[learner]\neta = 1.5\n")]),
        status: 2,
        pid_shown_as: None,
    },
    Case {
        doc: "error: placing the robots: 40 robots do not fit in the corridor 3 m x 0.22 m: at most 10 fit at a clearance of 0.05 m",
        args: &["run", "corridor", "--robots", "40"],
        files: Some(&[]),
        status: 2,
        pid_shown_as: None,
    },
    Case {
        doc: "error: cannot create the staging folder `/proc/.nope.partial-4242` beside the output folder: No such file or directory (os error 2)",
        args: &[
            "run",
            "arena",
            "--steps",
            "10",
            "--repeats",
            "1",
            "--out",
            "/proc/nope",
        ],
        files: Some(&[]),
        status: 1,
        pid_shown_as: Some("4242"),
    },
    // docs/energy-and-stack.md: the stack guard stops a program.
    Case {
        doc: "error: image `emu/tests/programs/stack/stack_deep.mot`: the core stopped: stack overflow at PC H'0002A8 in `descend` (`add.l #0xffffffd0,er7`): it moves SP from H'FFDF48 to H'FFDF18, 4 bytes below the stack's room H'FFDF1C-H'FFFF0F (the end of the program's data to its initial SP: 8180 bytes)",
        args: &["emu", "emu/tests/programs/stack/stack_deep.mot"],
        files: None,
        status: 125,
        pid_shown_as: None,
    },
    // docs/guide/emu.md: registers the chip does not model.
    Case {
        doc: "warning: image `…/unmodelled.mot`: PC H'000328 in start_dma: writes MAR0AR (H'FFFF20) of the DMA controller (DMAC), not modelled (the write is ignored)",
        args: &["emu", "emu/tests/programs/chip/unmodelled.mot"],
        files: None,
        status: 0,
        pid_shown_as: None,
    },
    Case {
        doc: "warning: image `…/unmodelled.mot`: PC H'000336 in flash_status: reads FLMCR1 (H'FFFF40) of the flash memory's program/erase control (flash), not modelled (it reads 0)",
        args: &["emu", "emu/tests/programs/chip/unmodelled.mot"],
        files: None,
        status: 0,
        pid_shown_as: None,
    },
    Case {
        doc: "warning: image `…/unmodelled.mot`: PC H'000348 in reserved: reads H'FFFF1C, a reserved I/O address, not modelled (it reads 0)",
        args: &["emu", "emu/tests/programs/chip/unmodelled.mot"],
        files: None,
        status: 0,
        pid_shown_as: None,
    },
    // docs/guide/cost-and-learn.md: a malformed replay line.
    Case {
        doc: "error: replay `bad.jsonl`: line 2: field `x[4]`: 200 is out of range for a Q7 input (i8): valid is -128 to 127",
        args: &["learn", "--replay", "bad.jsonl"],
        files: Some(&[("bad.jsonl", BAD_REPLAY)]),
        status: 2,
        pid_shown_as: None,
    },
];

/// A diagnostic line the guide shows.
struct Shown {
    /// `file:line`.
    at: String,
    text: String,
    /// The `$ …` command shown above it in the same code block, without the `$ `.
    command: Option<String>,
}

/// Whether a line (trimmed) is one of the tool's diagnostics: `error:` or `warning:` and a
/// message (the bare words, as prose names them, are not).
fn is_diagnostic(line: &str) -> bool {
    ["error:", "warning:"].iter().any(|p| {
        line.strip_prefix(p)
            .is_some_and(|rest| !rest.trim().is_empty())
    })
}

/// Every diagnostic line the guide's files show, in code blocks and inline code.
fn shown() -> Vec<Shown> {
    let root = guide::root();
    let mut out = Vec::new();
    for file in guide::files() {
        let text = std::fs::read_to_string(root.join(&file)).expect("a guide file reads");
        let line_of = |offset: usize| text[..offset].matches('\n').count() + 1;
        let mut block: Option<(usize, String, bool)> = None;
        for (event, range) in Parser::new_ext(&text, guide::options()).into_offset_iter() {
            match event {
                Event::Start(Tag::CodeBlock(kind)) => {
                    // The body starts on the line after a fence, on the block's line otherwise.
                    let fenced = matches!(kind, CodeBlockKind::Fenced(_));
                    block = Some((line_of(range.start), String::new(), fenced));
                }
                Event::Text(t) if block.is_some() => {
                    if let Some((_, body, _)) = block.as_mut() {
                        body.push_str(&t);
                    }
                }
                Event::End(TagEnd::CodeBlock) => {
                    let (first, body, fenced) = block.take().expect("a block was open");
                    let mut command = None;
                    for (i, line) in body.lines().enumerate() {
                        let line = line.trim();
                        if let Some(c) = line.strip_prefix("$ ") {
                            command = Some(c.trim().to_string());
                        } else if is_diagnostic(line) {
                            let n = first + i + usize::from(fenced);
                            out.push(Shown {
                                at: format!("{}:{n}", file.display()),
                                text: line.to_string(),
                                command: command.clone(),
                            });
                        }
                    }
                }
                Event::Code(c) if is_diagnostic(c.trim()) => out.push(Shown {
                    at: format!("{}:{}", file.display(), line_of(range.start)),
                    text: c.trim().to_string(),
                    command: None,
                }),
                _ => {}
            }
        }
    }
    out
}

/// Whether `actual` is the line `doc` shows, reading `...` and `…` in `doc` as any text.
fn matches(doc: &str, actual: &str) -> bool {
    let doc = doc.replace("...", "…");
    let parts: Vec<&str> = doc.split('…').collect();
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if parts.len() == 1 {
        return actual == doc;
    }
    if !actual.starts_with(first) || actual.len() < first.len() + last.len() {
        return false;
    }
    let mut rest = &actual[first.len()..];
    for middle in &parts[1..parts.len() - 1] {
        match rest.find(middle) {
            Some(at) => rest = &rest[at + middle.len()..],
            None => return false,
        }
    }
    rest.ends_with(last)
}

/// Runs a case; its standard error's lines, with the process id written as the doc shows it,
/// and its exit status.
fn run(case: &Case, n: usize) -> (Vec<String>, Option<i32>) {
    let dir = match case.files {
        None => guide::root(),
        Some(files) => {
            let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("doc_errors_{n}"));
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).expect("a fresh folder");
            for (name, text) in files {
                std::fs::write(dir.join(name), text).expect("an input file");
            }
            dir
        }
    };
    let child = Command::new(env!("CARGO_BIN_EXE_h8swarm"))
        .args(case.args)
        .current_dir(&dir)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    let pid = child.id().to_string();
    let output = child.wait_with_output().expect("the binary runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    let lines = stderr
        .lines()
        .map(|l| match case.pid_shown_as {
            Some(shown) => l.replace(&pid, shown),
            None => l.to_string(),
        })
        .collect();
    (lines, output.status.code())
}

#[test]
fn every_error_line_the_guide_shows_is_registered_and_printed_by_the_tool() {
    let shown = shown();
    let mut problems = Vec::new();
    for s in &shown {
        let known: Vec<&Case> = CASES.iter().filter(|c| c.doc == s.text).collect();
        if known.is_empty() {
            problems.push(format!(
                "{}: shows `{}`, which tests/doc_errors.rs does not know: add a case with the command and input that print it",
                s.at, s.text
            ));
        }
        if let Some(command) = &s.command {
            for c in &known {
                let registered = format!("h8swarm {}", c.args.join(" "));
                if *command != registered {
                    problems.push(format!(
                        "{}: the doc runs `{command}`, the test `{registered}`",
                        s.at
                    ));
                }
            }
        }
    }
    for (n, case) in CASES.iter().enumerate() {
        if !shown.iter().any(|s| s.text == case.doc) {
            problems.push(format!(
                "no doc shows `{}` any more: remove its case",
                case.doc
            ));
            continue;
        }
        let (lines, status) = run(case, n);
        if !lines.iter().any(|l| matches(case.doc, l)) {
            problems.push(format!(
                "`h8swarm {}` does not print `{}`; it prints:\n  {}",
                case.args.join(" "),
                case.doc,
                lines.join("\n  ")
            ));
        }
        if status != Some(case.status) {
            problems.push(format!(
                "`h8swarm {}` exits with {status:?}, the docs say {}",
                case.args.join(" "),
                case.status
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn elisions_stand_for_any_text_and_nothing_else_does() {
    assert!(matches("error: a … c", "error: a b c"));
    assert!(matches("error: a ... c", "error: a  c"));
    assert!(matches("error: …", "error: anything"));
    assert!(matches("warning: `…/x.mot`: y", "warning: `emu/x.mot`: y"));
    assert!(!matches("error: a … c", "error: a b d"));
    assert!(!matches("error: a … c", "warning: a b c"));
    assert!(!matches("error: exact", "error: exact and more"));
    assert!(!matches("error: ab…ba", "error: aba"));
    assert!(is_diagnostic("error: …") && is_diagnostic("warning: x"));
    assert!(!is_diagnostic("error:") && !is_diagnostic("warning: ") && !is_diagnostic("errors: x"));
}

/// The scan finds diagnostics where the guide shows them, and the command above them.
#[test]
fn the_scan_reads_this_guide() {
    let shown = shown();
    let at = |text: &str| shown.iter().find(|s| s.text.starts_with(text));
    let unmodelled = at("warning: image `…/unmodelled.mot`: PC H'000328").expect("emu.md's");
    assert!(
        unmodelled.at.starts_with("docs/guide/emu.md:"),
        "{}",
        unmodelled.at
    );
    assert_eq!(
        unmodelled.command.as_deref(),
        Some("h8swarm emu emu/tests/programs/chip/unmodelled.mot")
    );
    let line: usize = unmodelled.at.rsplit(':').next().unwrap().parse().unwrap();
    let text = std::fs::read_to_string(guide::root().join("docs/guide/emu.md")).unwrap();
    assert!(
        text.lines()
            .nth(line - 1)
            .unwrap()
            .starts_with("warning: image")
    );
    assert!(
        at("error: …").is_some(),
        "limits-and-failures.md's inline form"
    );
}
