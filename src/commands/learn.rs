//! `h8swarm learn --replay FILE`: the learner core of docs/design.md §2.3–2.4 fed from JSON Lines, one
//! output line per step (docs/design.md §2.6), so another implementation can be compared bit for bit.
//!
//! Input: line 1 is the header
//! `{"n_in": N, "n_out": M, "eta": η, "threshold": T, "weights": [[w_1,1 … w_N,1], …]}` (one row
//! of N Q15 integers per output), then one line per step `{"x": [N Q7 integers], "e": E}`: the
//! forward pass on x, then the update with evaluation E for that x and its winner. Output, per
//! step: `{"y": [M], "o": [M], "win": j, "weights": [[…] after the update]}`.
//!
//! Choices where docs/design.md §2.6 is silent: lines holding only white space are skipped (they still
//! count for line numbers); unknown fields are errors, so a misspelt key never passes silently;
//! numbers must be integers (no fraction, no exponent); η and T must be 0 … 32767 (Q15 ≥ 0 and
//! a non-negative threshold); E may be any i16; M may be 2 to 8 (the learner core's bound; a
//! robot uses 2 or 4). `--states` adds the H8/300H states the step's forward pass and update
//! cost (`"states": {"forward": …, "update": …}`); without it the output is exactly docs/design.md §2.6's.
//!
//! Two engines compute the lines: `nn_q15` (the default; states from its H8 meter) and, with
//! `--on-core`, the robot firmware's own routines `learner_forward` and `learner_update` run on
//! the emulated H8/300H ([`robot_board::firmware_learner`]; states as the core counts them, each routine
//! from its first instruction to its RTS). The two print the same lines for any input.

use std::fmt;
use std::fs::File;
use std::io::{self, BufRead, BufReader, BufWriter, Read, Write};

use clap::Args;

use super::{Failure, write_failure};

use nn_q15::{H8Meter, Params, Phase, Q7, Q15, Shape, forward_slice, update_slice};
use robot_board::firmware::Firmware;
use robot_board::firmware_learner::{LearnerOnCore, OnCoreError};
use serde::Serialize;
use serde_json::{Map, Value};

/// A malformed input line: where, which field, what was wrong and what would be valid.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReplayError {
    /// 1-based line number.
    pub line: usize,
    /// The field, as a path such as `weights[2][5]`, when the problem is in one.
    pub field: Option<String>,
    /// What was wrong and what would be valid.
    pub message: String,
}

impl fmt::Display for ReplayError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.field {
            Some(field) => write!(f, "line {}: field `{}`: {}", self.line, field, self.message),
            None => write!(f, "line {}: {}", self.line, self.message),
        }
    }
}

impl std::error::Error for ReplayError {}

/// Why a replay stopped early.
#[derive(Debug)]
pub enum ReplayFailure {
    /// The input was malformed (exit status 2).
    Input(ReplayError),
    /// Reading the input failed (exit status 2).
    Io(io::Error),
    /// Writing the output failed (exit status 1; a closed pipe downstream ends the run).
    Output(io::Error),
    /// The firmware's routines could not be run on the core (exit status 1).
    Core(OnCoreError),
}

/// What computes the output lines.
#[derive(Clone, Debug)]
pub enum Engine {
    /// `nn_q15` (docs/design.md §2.3–2.4), states from its H8 meter.
    Model,
    /// The firmware's `learner_forward` and `learner_update` on the emulated H8/300H.
    OnCore(Box<Firmware>),
}

/// Every `?` on an I/O error in a replay is a write; reads are mapped to
/// [`ReplayFailure::Io`] where they happen.
impl From<io::Error> for ReplayFailure {
    fn from(e: io::Error) -> Self {
        ReplayFailure::Output(e)
    }
}

#[derive(Serialize)]
struct StepLine<'a> {
    y: &'a [i32],
    o: &'a [i16],
    win: usize,
    weights: Vec<&'a [i16]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    states: Option<States>,
}

#[derive(Serialize)]
struct States {
    forward: u64,
    update: u64,
}

struct Header {
    shape: Shape,
    params: Params,
    weights: Vec<Q15>,
}

/// The learner a replay runs on.
enum Running {
    Model(Header),
    OnCore(Box<LearnerOnCore>, Shape),
}

impl Running {
    fn shape(&self) -> Shape {
        match self {
            Running::Model(h) => h.shape,
            Running::OnCore(_, shape) => *shape,
        }
    }
}

fn start(h: Header, engine: &Engine) -> Result<Running, ReplayFailure> {
    match engine {
        Engine::Model => Ok(Running::Model(h)),
        Engine::OnCore(fw) => {
            let mut core = LearnerOnCore::new(fw).map_err(ReplayFailure::Core)?;
            let weights: Vec<i16> = h.weights.iter().map(|w| w.to_bits()).collect();
            core.setup(
                h.shape.n_in(),
                h.shape.n_out(),
                h.params.eta().to_bits(),
                h.params.threshold(),
                &weights,
            )
            .map_err(ReplayFailure::Core)?;
            Ok(Running::OnCore(Box::new(core), h.shape))
        }
    }
}

const HEADER_FIELDS: &str = "n_in, n_out, eta, threshold, weights";
const STEP_FIELDS: &str = "x, e";

/// Runs a replay from `input` to `out`. Returns the number of steps replayed.
///
/// # Errors
/// [`ReplayFailure::Input`] for the first malformed line (everything before it has been
/// written), [`ReplayFailure::Io`] when reading fails, [`ReplayFailure::Output`] when writing does.
pub fn run(
    input: &mut dyn BufRead,
    out: &mut dyn Write,
    with_states: bool,
    engine: &Engine,
) -> Result<usize, ReplayFailure> {
    let mut buf = Vec::new();
    let mut line_no = 0usize;
    let mut header: Option<Running> = None;
    let mut steps = 0usize;
    loop {
        buf.clear();
        // At most one byte more than a line may hold, so that a line without end (`/dev/zero`)
        // is refused instead of filling the memory.
        let limit = MAX_LINE_BYTES as u64 + 1;
        if Read::take(&mut *input, limit)
            .read_until(b'\n', &mut buf)
            .map_err(ReplayFailure::Io)?
            == 0
        {
            break;
        }
        line_no += 1;
        if buf.len() > MAX_LINE_BYTES {
            return Err(ReplayFailure::Input(ReplayError {
                line: line_no,
                field: None,
                message: format!(
                    "longer than {MAX_LINE_BYTES} bytes without a line end: a header of 256 x 8 \
                     weights needs about 16 KB; give one JSON object per line"
                ),
            }));
        }
        let text = std::str::from_utf8(&buf).map_err(|e| {
            ReplayFailure::Input(ReplayError {
                line: line_no,
                field: None,
                message: format!("not valid UTF-8 (byte {})", e.valid_up_to() + 1),
            })
        })?;
        if text.trim().is_empty() {
            continue;
        }
        let obj = parse_object(text, line_no).map_err(ReplayFailure::Input)?;
        match header.as_mut() {
            None => {
                let h = parse_header(&obj, line_no).map_err(ReplayFailure::Input)?;
                header = Some(start(h, engine)?);
            }
            Some(running) => {
                let (x, e) =
                    parse_step(&obj, line_no, running.shape()).map_err(ReplayFailure::Input)?;
                match running {
                    Running::Model(h) => replay_step(h, &x, e, out, with_states)?,
                    Running::OnCore(core, shape) => {
                        replay_step_on_core(core, *shape, &x, e, out, with_states)?;
                    }
                }
                steps += 1;
            }
        }
    }
    if header.is_none() {
        return Err(ReplayFailure::Input(ReplayError {
            line: line_no.max(1),
            field: None,
            message: format!(
                "no header: the first non-blank line must be {{\"n_in\": N, \"n_out\": M, \
                 \"eta\": η, \"threshold\": T, \"weights\": [[…], …]}} (fields {HEADER_FIELDS})"
            ),
        }));
    }
    out.flush()?;
    Ok(steps)
}

fn replay_step_on_core(
    core: &mut LearnerOnCore,
    shape: Shape,
    x: &[Q7],
    e: i16,
    out: &mut dyn Write,
    with_states: bool,
) -> Result<(), ReplayFailure> {
    let xs: Vec<i8> = x.iter().map(|v| v.to_bits()).collect();
    let forward = core.forward(&xs).map_err(ReplayFailure::Core)?;
    let update = core.update(e).map_err(ReplayFailure::Core)?;
    let raw = core.weights();
    let line = StepLine {
        y: &forward.y,
        o: &forward.o,
        win: forward.win,
        weights: raw.chunks(shape.n_in()).collect(),
        states: with_states.then_some(States {
            forward: forward.states,
            update,
        }),
    };
    write_line(out, &line)?;
    Ok(())
}

fn replay_step(
    h: &mut Header,
    x: &[Q7],
    e: i16,
    out: &mut dyn Write,
    with_states: bool,
) -> io::Result<()> {
    let mut meter = H8Meter::new();
    // The shape and lengths were validated while parsing, so neither call can fail; a failure
    // would still be reported, never unwrapped.
    let forward = forward_slice(h.shape, &h.weights, x, &mut meter).map_err(invalid_data)?;
    update_slice(
        h.shape,
        &mut h.weights,
        x,
        forward.win(),
        e,
        h.params,
        &mut meter,
    )
    .map_err(invalid_data)?;
    let raw: Vec<i16> = h.weights.iter().map(|w| w.to_bits()).collect();
    let line = StepLine {
        y: forward.y_bits(),
        o: forward.o_bits(),
        win: forward.win(),
        weights: raw.chunks(h.shape.n_in()).collect(),
        states: with_states.then(|| States {
            forward: meter.states(Phase::Forward),
            update: meter.states(Phase::Update),
        }),
    };
    write_line(out, &line)
}

/// Writes `line` as one JSON line: rendered first, then written, so that a write error keeps
/// its kind (a closed pipe stays BrokenPipe, which ends the command quietly), where
/// serde_json's writer would wrap it.
fn write_line(out: &mut dyn Write, line: &impl serde::Serialize) -> io::Result<()> {
    let mut bytes = serde_json::to_vec(line).map_err(io::Error::other)?;
    bytes.push(b'\n');
    out.write_all(&bytes)
}

fn invalid_data(e: nn_q15::ShapeError) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, e.to_string())
}

fn parse_object(text: &str, line: usize) -> Result<Map<String, Value>, ReplayError> {
    match serde_json::from_str::<Value>(text) {
        Ok(Value::Object(map)) => match negative_zero_not_an_integer(text) {
            // One rule for every number of the format: an integer, written without a fraction
            // or an exponent. The fields refuse the others; the parsed value cannot tell
            // `-0.0` or `-0e0` from the integer `-0`, so those are refused here, as written.
            Some(token) => Err(ReplayError {
                line,
                field: None,
                message: format!(
                    "`{}` is not an integer: every number in a replay line is written without a fraction or an exponent",
                    swarm::terminal_text::printable(token)
                ),
            }),
            None => Ok(map),
        },
        Ok(other) => Err(ReplayError {
            line,
            field: None,
            message: format!("expected a JSON object, found {}", kind(&other)),
        }),
        Err(e) => Err(ReplayError {
            line,
            field: None,
            message: format!("bad JSON: {e}"),
        }),
    }
}

/// The first number in the JSON text `text` that is a negative zero written with a fraction or
/// an exponent (`-0.0`, `-0e0`; strings skipped), if any.
fn negative_zero_not_an_integer(text: &str) -> Option<&str> {
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'"' => {
                // Skip the string, escapes included.
                i += 1;
                while i < b.len() && b[i] != b'"' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
                i += 1;
            }
            b'-' | b'0'..=b'9' => {
                let start = i;
                while i < b.len() && matches!(b[i], b'-' | b'+' | b'.' | b'e' | b'E' | b'0'..=b'9')
                {
                    i += 1;
                }
                let token = &text[start..i];
                if token.starts_with('-')
                    && token.contains(['.', 'e', 'E'])
                    && token.parse::<f64>().is_ok_and(|v| v == 0.0)
                {
                    return Some(token);
                }
            }
            _ => i += 1,
        }
    }
    None
}

fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

fn check_fields(
    obj: &Map<String, Value>,
    line: usize,
    allowed: &[&str],
    listing: &str,
) -> Result<(), ReplayError> {
    // serde_json's map is ordered by key, so the first unknown field reported is deterministic.
    match obj.keys().find(|k| !allowed.contains(&k.as_str())) {
        Some(k) => Err(ReplayError {
            line,
            field: Some(k.clone()),
            message: format!("unknown field: valid fields here are {listing}"),
        }),
        None => Ok(()),
    }
}

fn field<'a>(
    obj: &'a Map<String, Value>,
    line: usize,
    name: &str,
) -> Result<&'a Value, ReplayError> {
    obj.get(name).ok_or_else(|| ReplayError {
        line,
        field: Some(name.to_owned()),
        message: "missing".to_owned(),
    })
}

/// The longest line read (1 MiB): far more than the largest valid line (a header of 256 × 8
/// weights of at most 7 characters each is about 16 KB).
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// An integer in `lo ..= hi`, described as `what` in errors.
fn int_in(
    v: &Value,
    line: usize,
    path: &str,
    lo: i64,
    hi: i64,
    what: &str,
) -> Result<i64, ReplayError> {
    let err = |message: String| ReplayError {
        line,
        field: Some(path.to_owned()),
        message,
    };
    let n = match v {
        Value::Number(n) => n,
        other => {
            return Err(err(format!(
                "expected an integer ({what}, {lo} to {hi}), found {}",
                kind(other)
            )));
        }
    };
    // `-0` is a JSON integer, but serde_json reads it as the float -0.0.
    let negative_zero = n.as_f64().is_some_and(|f| f == 0.0 && f.is_sign_negative());
    let i = n.as_i64().or(negative_zero.then_some(0)).ok_or_else(|| {
        err(format!(
            "{n} is not an integer in range ({what}: valid is {lo} to {hi})"
        ))
    })?;
    if i < lo || i > hi {
        return Err(err(format!(
            "{i} is out of range for {what}: valid is {lo} to {hi}"
        )));
    }
    Ok(i)
}

fn array<'a>(
    v: &'a Value,
    line: usize,
    path: &str,
    len: usize,
    what: &str,
) -> Result<&'a [Value], ReplayError> {
    let err = |message: String| ReplayError {
        line,
        field: Some(path.to_owned()),
        message,
    };
    match v {
        Value::Array(a) if a.len() == len => Ok(a),
        Value::Array(a) => Err(err(format!(
            "expected {len} values ({what}), found {}",
            a.len()
        ))),
        other => Err(err(format!(
            "expected an array of {len} values ({what}), found {}",
            kind(other)
        ))),
    }
}

fn parse_header(obj: &Map<String, Value>, line: usize) -> Result<Header, ReplayError> {
    check_fields(
        obj,
        line,
        &["n_in", "n_out", "eta", "threshold", "weights"],
        HEADER_FIELDS,
    )?;
    let n_in = int_in(
        field(obj, line, "n_in")?,
        line,
        "n_in",
        1,
        nn_q15::MAX_INPUTS as i64,
        "the number of inputs N",
    )?;
    let n_out = int_in(
        field(obj, line, "n_out")?,
        line,
        "n_out",
        nn_q15::MIN_OUTPUTS as i64,
        nn_q15::MAX_OUTPUTS as i64,
        "the number of outputs M (a robot enables 2 or 4 behaviours; the learner takes up to 8)",
    )?;
    let eta = int_in(
        field(obj, line, "eta")?,
        line,
        "eta",
        0,
        32767,
        "a Q15 learning rate ≥ 0",
    )?;
    let threshold = int_in(
        field(obj, line, "threshold")?,
        line,
        "threshold",
        0,
        32767,
        "a threshold T in du ≥ 0",
    )?;
    // Both ranges were checked above, so these conversions and constructors cannot fail.
    let (n_in, n_out) = (n_in as usize, n_out as usize);
    let shape = Shape::new(n_in, n_out).map_err(|e| ReplayError {
        line,
        field: Some("n_in".to_owned()),
        message: e.to_string(),
    })?;
    let params = Params::new(eta as i32, threshold as i32).map_err(|e| ReplayError {
        line,
        field: Some("eta".to_owned()),
        message: e.to_string(),
    })?;
    let rows = array(
        field(obj, line, "weights")?,
        line,
        "weights",
        n_out,
        "one row per output (n_out)",
    )?;
    let mut weights = Vec::with_capacity(n_in * n_out);
    for (j, row) in rows.iter().enumerate() {
        let path = format!("weights[{j}]");
        for (i, v) in array(row, line, &path, n_in, "one weight per input (n_in)")?
            .iter()
            .enumerate()
        {
            let w = int_in(
                v,
                line,
                &format!("weights[{j}][{i}]"),
                -32768,
                32767,
                "a Q15 weight (i16)",
            )?;
            weights.push(Q15::from_bits(w as i16));
        }
    }
    Ok(Header {
        shape,
        params,
        weights,
    })
}

fn parse_step(
    obj: &Map<String, Value>,
    line: usize,
    shape: Shape,
) -> Result<(Vec<Q7>, i16), ReplayError> {
    check_fields(obj, line, &["x", "e"], STEP_FIELDS)?;
    let xs = array(
        field(obj, line, "x")?,
        line,
        "x",
        shape.n_in(),
        "one input per n_in",
    )?;
    let mut x = Vec::with_capacity(xs.len());
    for (i, v) in xs.iter().enumerate() {
        let xi = int_in(v, line, &format!("x[{i}]"), -128, 127, "a Q7 input (i8)")?;
        x.push(Q7::from_bits(xi as i8));
    }
    let e = int_in(
        field(obj, line, "e")?,
        line,
        "e",
        -32768,
        32767,
        "an evaluation E (i16)",
    )?;
    Ok((x, e as i16))
}

/// Options of `h8swarm learn`.
#[derive(Args, Debug)]
pub struct LearnArgs {
    /// The replay file (JSON Lines), or `-` for standard input.
    #[arg(long, value_name = "FILE")]
    replay: String,
    /// Add the H8/300H states of each step's forward pass and update to every output line.
    #[arg(long)]
    states: bool,
    /// Run the robot firmware's own learner routines on the emulated H8/300H instead of
    /// nn_q15 (the same lines; with --states, the states the core counts).
    #[arg(long)]
    on_core: bool,
}

/// `h8swarm learn`: replays the file (or standard input) to standard output.
///
/// # Errors
/// A malformed or unreadable input ([`Failure::Input`]), a failure of the core or of the
/// output ([`Failure::Tool`]).
pub fn command(args: &LearnArgs) -> Result<(), Failure> {
    let stdin = io::stdin();
    let mut input: Box<dyn BufRead> = if args.replay == "-" {
        Box::new(stdin.lock())
    } else {
        let file = File::open(&args.replay).map_err(|e| {
            Failure::Input(anyhow::anyhow!(
                "cannot open replay file `{}`: {e} (give a JSON Lines file, or - for standard input)",
                args.replay
            ))
        })?;
        Box::new(BufReader::new(file))
    };
    let stdout = io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let engine = if args.on_core {
        let fw = robot_board::firmware::Firmware::robot()
            .map_err(|e| Failure::Tool(anyhow::Error::new(e).context("the built-in firmware")))?;
        Engine::OnCore(Box::new(fw))
    } else {
        Engine::Model
    };
    let result = run(&mut input, &mut out, args.states, &engine);
    // Whatever happened, the lines already produced are delivered.
    let flushed = out.flush();
    match result {
        Ok(_) => flushed.or_else(write_failure),
        Err(ReplayFailure::Input(e)) => Err(Failure::Input(
            anyhow::Error::new(e).context(format!("replay `{}`", args.replay)),
        )),
        Err(ReplayFailure::Core(e)) => Err(Failure::Tool(
            anyhow::Error::new(e).context(format!("replay `{}` on the core", args.replay)),
        )),
        Err(ReplayFailure::Output(e)) => write_failure(e),
        Err(ReplayFailure::Io(e)) => Err(Failure::Input(
            anyhow::Error::new(e).context(format!("reading replay `{}`", args.replay)),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn replay(input: &str) -> (String, Result<usize, String>) {
        let mut out = Vec::new();
        let r = run(&mut input.as_bytes(), &mut out, false, &Engine::Model).map_err(|e| match e {
            ReplayFailure::Input(e) => e.to_string(),
            ReplayFailure::Io(e) => format!("io: {e}"),
            ReplayFailure::Output(e) => format!("output: {e}"),
            ReplayFailure::Core(e) => format!("core: {e}"),
        });
        (String::from_utf8(out).unwrap(), r)
    }

    const HEADER: &str = r#"{"n_in": 2, "n_out": 2, "eta": 3277, "threshold": 10, "weights": [[100, -200], [300, 400]]}"#;

    #[test]
    fn one_step_by_hand() {
        let input = format!("{HEADER}\n{{\"x\": [64, -64], \"e\": 20}}\n");
        let (out, r) = replay(&input);
        assert_eq!(r, Ok(1));
        // y0 = 100·64 − 200·(−64) = 19200; y1 = 300·64 − 400·64 = −6400; O = y >> 7.
        // Reward for output 0: Δ = round(3277·64/128) = 1639, Δ' = −1639.
        assert_eq!(
            out,
            "{\"y\":[19200,-6400],\"o\":[150,-50],\"win\":0,\"weights\":[[1739,-1839],[-1339,2039]]}\n"
        );
    }

    #[test]
    fn errors_name_line_and_field() {
        let cases = [
            (
                format!("{HEADER}\n{{\"x\": [64, 200], \"e\": 0}}\n"),
                "line 2: field `x[1]`: 200 is out of range for a Q7 input (i8): valid is -128 to 127",
            ),
            (
                format!("{HEADER}\n{{\"x\": [64], \"e\": 0}}\n"),
                "line 2: field `x`: expected 2 values (one input per n_in), found 1",
            ),
            (
                format!("{HEADER}\n\n{{\"x\": [1, 2]}}\n"),
                "line 3: field `e`: missing",
            ),
            (
                format!("{HEADER}\n{{\"x\": [1, 2], \"e\": 40000}}\n"),
                "line 2: field `e`: 40000 is out of range for an evaluation E (i16): valid is -32768 to 32767",
            ),
            (
                format!("{HEADER}\n{{\"x\": [1, 2], \"e\": 1, \"z\": 0}}\n"),
                "line 2: field `z`: unknown field: valid fields here are x, e",
            ),
            (
                format!("{HEADER}\n{{\"x\": [1.5, 2], \"e\": 1}}\n"),
                "line 2: field `x[0]`: 1.5 is not an integer in range (a Q7 input (i8): valid is -128 to 127)",
            ),
            (
                format!("{HEADER}\n[1]\n"),
                "line 2: expected a JSON object, found an array",
            ),
            (
                r#"{"n_in": 0, "n_out": 2, "eta": 1, "threshold": 1, "weights": []}"#.to_owned(),
                "line 1: field `n_in`: 0 is out of range for the number of inputs N: valid is 1 to 256",
            ),
            (
                r#"{"n_in": 1, "n_out": 2, "eta": -1, "threshold": 1, "weights": []}"#.to_owned(),
                "line 1: field `eta`: -1 is out of range for a Q15 learning rate ≥ 0: valid is 0 to 32767",
            ),
            (
                r#"{"n_in": 1, "n_out": 2, "eta": 1, "threshold": 1, "weights": [[1], [40000]]}"#
                    .to_owned(),
                "line 1: field `weights[1][0]`: 40000 is out of range for a Q15 weight (i16): valid is -32768 to 32767",
            ),
            (
                r#"{"n_in": 1, "n_out": 2, "eta": 1, "threshold": 1, "weights": [[1]]}"#.to_owned(),
                "line 1: field `weights`: expected 2 values (one row per output (n_out)), found 1",
            ),
            (String::new(), "line 1: no header"),
        ];
        for (input, expected) in cases {
            let (_, r) = replay(&input);
            let msg = r.unwrap_err();
            assert!(msg.starts_with(expected), "{msg}\nexpected: {expected}");
        }
    }

    #[test]
    fn bad_json_reports_the_line_and_keeps_earlier_output() {
        let input = format!("{HEADER}\n{{\"x\": [1, 2], \"e\": 0}}\n{{\"x\": [1, 2\n");
        let (out, r) = replay(&input);
        assert_eq!(out.lines().count(), 1, "the good step was written");
        assert!(r.unwrap_err().starts_with("line 3: bad JSON"));
    }

    #[test]
    fn minus_zero_is_the_integer_zero() {
        let (a, ra) = replay(&format!("{HEADER}\n{{\"x\": [1, 2], \"e\": -0}}\n"));
        let (b, rb) = replay(&format!("{HEADER}\n{{\"x\": [1, 2], \"e\": 0}}\n"));
        ra.unwrap();
        rb.unwrap();
        assert_eq!(a, b);
        // Numbers written with a fraction or an exponent are refused, whatever their value: one
        // rule (`-0.0` and `-0e0` were once taken as 0 where `0.0` was refused).
        for bad in ["-1.0", "0.0", "-0.0", "-0e0", "0E0", "1e1", "-0.0e-5"] {
            let (_, r) = replay(&format!("{HEADER}\n{{\"x\": [1, 2], \"e\": {bad}}}\n"));
            let e = r.unwrap_err();
            assert!(e.contains("is not an integer"), "{bad}: {e}");
        }
        // A string may hold what looks like a number.
        assert_eq!(
            negative_zero_not_an_integer(r#"{"a": "-0.0", "b": [1, -0]}"#),
            None
        );
        assert_eq!(
            negative_zero_not_an_integer(r#"{"a": "x\"-0.0", "b": -0e3}"#),
            Some("-0e3")
        );
    }

    #[test]
    fn a_line_without_end_is_refused_not_held() {
        // An endless run of one byte (as `/dev/zero` gives): refused at the bound, after
        // reading only the bound.
        let mut endless = std::io::BufReader::new(std::io::repeat(b' '));
        let mut out = Vec::new();
        let e = run(&mut endless, &mut out, false, &Engine::Model).unwrap_err();
        let ReplayFailure::Input(e) = e else {
            panic!("not an input error: {e:?}")
        };
        assert_eq!(e.line, 1);
        assert!(
            e.message.contains("longer than 1048576 bytes"),
            "{}",
            e.message
        );
    }
}
