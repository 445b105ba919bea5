//! The reader targets: shipped files, mutated, parsed.

use aacmm_core::error::InputError;
use aacmm_core::io::{AngleUnit, parse_arm, parse_lengths, parse_points, parse_poses};
use aacmm_core::simulate::{SimError, parse_campaign};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestError, TestRng, TestRunner};

use crate::{Summary, Violation, no_panic};

/// A file reader under test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reader {
    /// `parse_arm` (arm TOML).
    Arm,
    /// `parse_campaign` (campaign TOML).
    Campaign,
    /// `parse_poses` (`point,q1..qn`), degrees.
    Poses,
    /// `parse_lengths` (`point_a,point_b,distance[,uncertainty]`).
    Lengths,
    /// `parse_points` (`point,x,y,z`).
    Points,
}

impl Reader {
    /// Every reader.
    pub const ALL: [Reader; 5] = [
        Reader::Arm,
        Reader::Campaign,
        Reader::Poses,
        Reader::Lengths,
        Reader::Points,
    ];

    /// The name used in messages (the "file" the text came from).
    pub fn file(self) -> &'static str {
        match self {
            Reader::Arm => "arm.toml",
            Reader::Campaign => "campaign.toml",
            Reader::Poses => "poses.csv",
            Reader::Lengths => "lengths.csv",
            Reader::Points => "points.csv",
        }
    }

    /// Valid files to start the mutations from: the shipped examples and a
    /// few written for the features they do not use.
    pub fn seeds(self) -> &'static [&'static str] {
        match self {
            Reader::Arm => &[
                include_str!("../../examples/paper-table-1.toml"),
                include_str!("../../examples/paper-campaign/true_arm.toml"),
                ARM_WITH_LIMITS,
                include_str!("../../examples/mukca/kinova-1/arm.toml"),
                include_str!("../../examples/mukca/panda-1/arm.toml"),
                ARM_WITH_HAYATI_AND_PRIOR,
            ],
            Reader::Campaign => &[include_str!("../../examples/paper-campaign/campaign.toml")],
            Reader::Poses => &[
                include_str!("../../examples/paper-campaign/poses.csv"),
                "point,q1,q2,q3,q4,q5,q6,q7\nA,1,2,3,4,5,6,7\nA,-1,2e1,3.5,4,5,6,7\n",
                "\u{feff}point,q1\r\n\"A\",1\r\n\"A,B\",2\r\n",
            ],
            Reader::Lengths => &[
                include_str!("../../examples/paper-campaign/lengths.csv"),
                "point_a,point_b,distance,uncertainty\nS1,S2,500.25,0.001\nS2,S3,1e2,0\n",
            ],
            Reader::Points => &[
                include_str!("../../examples/paper-campaign/sockets.csv"),
                "point,x,y,z\nA,1,2,3\n\"B\",-1e3,2.5,0\n",
            ],
        }
    }
}

const ARM_WITH_LIMITS: &str = "name = \"limits\"\nlength_unit = \"mm\"\nangle_unit = \"deg\"\n\
[[joint]]\ntheta = 0\nd = 400\na = 50\nalpha = -90\nlimits = [-180, 180]\n\
[[joint]]\ntheta = -90\nd = 0\na = 600\nalpha = 0\n\
[[joint]]\ntheta = 0\nd = 0\na = 50\nalpha = -90\nlimits = [-170.5, 170.5]\n\
[[joint]]\ntheta = 0\nd = 550\na = 0\nalpha = 90\n\
[[joint]]\ntheta = 0\nd = 0\na = 0\nalpha = -90\n\
[[joint]]\ntheta = 0\nd = 100\na = 0\nalpha = 0\n\
[probe]\nx = 0\ny = 0\nz = 100\n";

/// A Hayati joint (no `d`, `hbeta`) and a `[prior]` table of every form:
/// per kind, per class, per parameter.
const ARM_WITH_HAYATI_AND_PRIOR: &str = "name = \"hayati\"\nlength_unit = \"mm\"\n\
angle_unit = \"deg\"\n\
[[joint]]\ntheta = 0\nd = 400\na = 50\nalpha = -90\n\
[[joint]]\nmodel = \"hayati\"\ntheta = -90\nhbeta = 0.25\na = 600\nalpha = 0.2\n\
[[joint]]\nmodel = \"dh\"\ntheta = 0\nd = 0\na = 50\nalpha = -90\n\
[[joint]]\ntheta = 0\nd = 550\na = 0\nalpha = 90\n\
[[joint]]\ntheta = 0\nd = 0\na = 0\nalpha = -90\n\
[[joint]]\ntheta = 0\nd = 100\na = 0\nalpha = 0\n\
[probe]\nx = 0\ny = 0\nz = 100\n\
[prior]\nlength_mm = 1.0\nangle_deg = 0.5\ntheta_deg = 0.2\nd3_mm = 0.3\nhbeta2_deg = 0.1\n";

/// Tokens the mutations insert: numbers at and past the edges of `f64`,
/// separators, quotes, TOML syntax, units, odd characters.
pub const TOKENS: &[&str] = &[
    "nan",
    "NaN",
    "inf",
    "-inf",
    "+inf",
    "infinity",
    "1e309",
    "-1e309",
    "1e308",
    "-1e308",
    "1e-320",
    "4.9e-324",
    "0",
    "-0",
    "0.0",
    "1e300",
    "-1e300",
    "1e-300",
    "",
    ",",
    ",,",
    "\n",
    "\r\n",
    "\r",
    "\"",
    "\"\"",
    "'",
    "#",
    "=",
    "[",
    "]",
    "[[joint]]",
    "[probe]",
    "{",
    "}",
    "é",
    "\u{feff}",
    "\0",
    "\t",
    " ",
    "99999999999999999999999",
    "0x10",
    "+1",
    ".5",
    "1.",
    "1e",
    "-",
    "deg",
    "rad",
    "mm",
    "m",
    "in",
    "point",
    "q1",
    "q7",
    "q0",
    "distance",
    "uncertainty",
    "x",
    "theta",
    "alpha",
    "limits",
    "model",
    "\"hayati\"",
    "\"dh\"",
    "hbeta",
    "hbeta2",
    "[prior]",
    "length_mm",
    "angle_deg",
    "theta5_deg",
    "a5_mm",
    "length_unit",
    "angle_unit",
    "true",
    "[1, 2]",
    "[]",
    "1_000",
    "\u{202e}",
    "S1",
    "S2",
    "9223372036854775808",
    "-9223372036854775809",
    "1e-5",
    "360",
    "-180",
    "1.7976931348623157e308",
];

/// One mutation of a file's bytes. Positions are taken modulo the current
/// length, so every list of ops applies to every file.
#[derive(Clone, Debug)]
pub enum Op {
    /// XOR one byte.
    Flip(usize, u8),
    /// Insert a [`TOKENS`] entry.
    Insert(usize, usize),
    /// Delete up to `n` bytes.
    Delete(usize, u8),
    /// Duplicate a line.
    DupLine(usize),
    /// Delete a line.
    DelLine(usize),
    /// Swap two lines.
    SwapLines(usize, usize),
    /// Replace the `n`-th number-like run with a [`TOKENS`] entry.
    Number(usize, usize),
    /// Cut the file.
    Truncate(usize),
    /// Copy a piece of the file elsewhere.
    Splice(usize, u16, usize),
}

fn op() -> impl Strategy<Value = Op> {
    let t = 0..TOKENS.len();
    prop_oneof![
        (any::<usize>(), 1..=255u8).prop_map(|(a, x)| Op::Flip(a, x)),
        (any::<usize>(), t.clone()).prop_map(|(a, t)| Op::Insert(a, t)),
        (any::<usize>(), 1..=16u8).prop_map(|(a, n)| Op::Delete(a, n)),
        any::<usize>().prop_map(Op::DupLine),
        any::<usize>().prop_map(Op::DelLine),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Op::SwapLines(a, b)),
        (any::<usize>(), t).prop_map(|(n, t)| Op::Number(n, t)),
        any::<usize>().prop_map(Op::Truncate),
        (any::<usize>(), 1..=200u16, any::<usize>()).prop_map(|(a, n, b)| Op::Splice(a, n, b)),
    ]
}

fn lines(bytes: &[u8]) -> Vec<Vec<u8>> {
    bytes
        .split_inclusive(|&b| b == b'\n')
        .map(<[u8]>::to_vec)
        .collect()
}

/// Applies `ops` to `seed`.
pub fn mutate(seed: &str, ops: &[Op]) -> Vec<u8> {
    let mut b = seed.as_bytes().to_vec();
    for op in ops {
        let at = |p: usize, b: &[u8]| if b.is_empty() { 0 } else { p % (b.len() + 1) };
        match *op {
            Op::Flip(p, x) => {
                if !b.is_empty() {
                    let i = p % b.len();
                    b[i] ^= x;
                }
            }
            Op::Insert(p, t) => {
                let i = at(p, &b);
                b.splice(i..i, TOKENS[t].bytes());
            }
            Op::Delete(p, n) => {
                let i = at(p, &b);
                let j = (i + n as usize).min(b.len());
                b.drain(i..j);
            }
            Op::DupLine(l) | Op::DelLine(l) => {
                let mut ls = lines(&b);
                if !ls.is_empty() {
                    let i = l % ls.len();
                    if matches!(op, Op::DupLine(_)) {
                        let line = ls[i].clone();
                        ls.insert(i, line);
                    } else {
                        ls.remove(i);
                    }
                    b = ls.concat();
                }
            }
            Op::SwapLines(x, y) => {
                let mut ls = lines(&b);
                if !ls.is_empty() {
                    let n = ls.len();
                    ls.swap(x % n, y % n);
                    b = ls.concat();
                }
            }
            Op::Number(n, t) => {
                let runs = number_runs(&b);
                if !runs.is_empty() {
                    let (i, j) = runs[n % runs.len()];
                    b.splice(i..j, TOKENS[t].bytes());
                }
            }
            Op::Truncate(p) => {
                let i = at(p, &b);
                b.truncate(i);
            }
            Op::Splice(p, n, q) => {
                if !b.is_empty() {
                    let i = p % b.len();
                    let j = (i + n as usize).min(b.len());
                    let piece = b[i..j].to_vec();
                    let k = at(q, &b);
                    b.splice(k..k, piece);
                }
            }
        }
    }
    b
}

/// Byte ranges of maximal runs of `[0-9.eE+-]` that contain a digit.
fn number_runs(b: &[u8]) -> Vec<(usize, usize)> {
    let num = |c: u8| c.is_ascii_digit() || b".eE+-".contains(&c);
    let mut runs = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if num(b[i]) {
            let j = (i..b.len()).find(|&j| !num(b[j])).unwrap_or(b.len());
            if b[i..j].iter().any(u8::is_ascii_digit) {
                runs.push((i, j));
            }
            i = j;
        } else {
            i += 1;
        }
    }
    runs
}

/// Whether an input error is located: it names `file` first and, when it
/// has a line, `file:line`.
fn located(e: &InputError, file: &str) -> Result<String, String> {
    let text = e.to_string();
    if e.file() != file || !text.starts_with(file) {
        return Err(format!("error does not start with `{file}`: {text}"));
    }
    match e.line() {
        Some(l) if !text.starts_with(&format!("{file}:{l}: ")) => Err(format!(
            "error with line {l} does not name `{file}:{l}`: {text}"
        )),
        Some(_) => Ok("error at a line".into()),
        // Which kinds: the message with its digits blanked, cut short.
        None => {
            let kind: String = text[file.len()..]
                .chars()
                .map(|c| if c.is_ascii_digit() { '#' } else { c })
                .take(45)
                .collect();
            Ok(format!("error for the whole file{kind}"))
        }
    }
}

fn finite(values: impl IntoIterator<Item = f64>, what: &str) -> Result<(), String> {
    match values.into_iter().find(|v| !v.is_finite()) {
        Some(v) => Err(format!("accepted a non-finite {what}: {v}")),
        None => Ok(()),
    }
}

/// Parses `bytes` with `reader`: `Ok(outcome)` when the rules hold (no
/// panic; finite values, or a located error), else what broke.
pub fn check_reader(reader: Reader, bytes: &[u8]) -> Result<String, String> {
    let file = reader.file();
    // The file readers turn bytes into text first (and refuse invalid UTF-8
    // with a located error); the parsers take text, so invalid bytes become
    // U+FFFD.
    let text = String::from_utf8_lossy(bytes);
    let text = text.as_ref();
    no_panic(|| match reader {
        Reader::Arm => match parse_arm(text, file) {
            Ok((arm, _)) => {
                finite(arm.params.to_vec(), "parameter")?;
                finite(arm.limits.iter().flatten().flatten().copied(), "limit")?;
                Ok("ok".into())
            }
            Err(e) => located(&e, file),
        },
        Reader::Campaign => match parse_campaign(text, file) {
            Ok((arm, s)) => {
                finite(arm.params.to_vec(), "parameter")?;
                finite(
                    [
                        s.encoder_noise_deg,
                        s.probe_noise_mm,
                        s.min_pose_separation_deg,
                    ],
                    "setting",
                )?;
                Ok("ok".into())
            }
            Err(SimError::Input(e)) => located(&e, file),
            // A setting's error names the setting; `read_campaign`'s
            // callers add the file.
            Err(SimError::Setting { .. }) => Ok("setting error".into()),
            Err(e) => {
                let text = e.to_string();
                if text.starts_with(file) {
                    Ok("error for the whole file".into())
                } else {
                    Err(format!("campaign error does not name `{file}`: {text}"))
                }
            }
        },
        Reader::Poses => match parse_poses(text, file, AngleUnit::Deg, None) {
            Ok((poses, _)) => {
                finite(poses.readings().iter().copied(), "reading")?;
                if poses.readings().len() != poses.len() * poses.joints()
                    || poses.lines().len() != poses.len()
                {
                    return Err("rows, labels and lines disagree".into());
                }
                Ok("ok".into())
            }
            Err(e) => located(&e, file),
        },
        Reader::Lengths => match parse_lengths(text, file) {
            Ok(l) => {
                finite(l.iter().map(|l| l.distance), "distance")?;
                finite(l.iter().filter_map(|l| l.uncertainty), "uncertainty")?;
                Ok("ok".into())
            }
            Err(e) => located(&e, file),
        },
        Reader::Points => match parse_points(text, file) {
            Ok(p) => {
                finite(p.iter().flat_map(|(_, x)| *x), "coordinate")?;
                Ok("ok".into())
            }
            Err(e) => located(&e, file),
        },
    })
    .and_then(|r| r)
}

pub(crate) fn runner(cases: u64, seed: u64) -> TestRunner {
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    let config = Config {
        cases: u32::try_from(cases).unwrap_or(u32::MAX),
        failure_persistence: None,
        max_shrink_iters: 2000,
        ..Config::default()
    };
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &key))
}

/// Runs `cases` mutated files through every reader (in turn), from `seed`,
/// in chunks: a violation is shrunk, recorded, and the run goes on with the
/// next chunk.
pub fn run_readers(cases: u64, seed: u64, chunk: u64) -> Summary {
    let mut summary = Summary::default();
    let chunk = chunk.max(1);
    let mut done = 0;
    let mut k = 0;
    while done < cases {
        let n = chunk.min(cases - done);
        let mut runner = runner(n, seed.wrapping_mul(1_000_003).wrapping_add(k));
        let strategy = (
            0..Reader::ALL.len(),
            any::<usize>(),
            proptest::collection::vec(op(), 0..8),
        );
        let outcomes = std::cell::RefCell::new(Summary::default());
        let result = runner.run(&strategy, |(r, s, ops)| {
            let reader = Reader::ALL[r];
            let seeds = reader.seeds();
            let bytes = mutate(seeds[s % seeds.len()], &ops);
            let mut o = outcomes.borrow_mut();
            o.cases += 1;
            match check_reader(reader, &bytes) {
                Ok(outcome) => {
                    o.count(&format!("{:?}: {outcome}", reader));
                    Ok(())
                }
                Err(problem) => Err(TestCaseError::fail(problem)),
            }
        });
        let o = outcomes.into_inner();
        summary.cases += o.cases;
        for (key, v) in o.outcomes {
            *summary.outcomes.entry(key).or_default() += v;
        }
        if let Err(TestError::Fail(problem, (r, s, ops))) = result {
            let reader = Reader::ALL[r];
            let seeds = reader.seeds();
            let bytes = mutate(seeds[s % seeds.len()], &ops);
            summary.violations.push(Violation {
                target: format!("{reader:?}"),
                input: format!("{:?}", String::from_utf8_lossy(&bytes)),
                problem: problem.to_string(),
            });
        }
        done += n;
        k += 1;
    }
    summary
}
