//! The README shows what the programs do: every block of `$ ` commands is
//! real output, and `compare_methods` without arguments prints its table's
//! rows.

fn readme() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap()
}

/// `cargo run --release --example compare_methods`, as the README gives it
/// (no arguments), prints one row per case and method of the README's table.
#[test]
fn compare_methods_defaults_are_the_readme_table() {
    let text = readme();
    assert!(text.contains("`cargo run --release --example compare_methods` ("));
    let rows = text
        .lines()
        .filter(|l| l.starts_with("| `--errors"))
        .count();
    let source = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/compare_methods.rs"
    ))
    .unwrap();
    let list = |name: &str| -> usize {
        let line = source
            .lines()
            .find(|l| l.starts_with(&format!("const {name}: &str = \"")))
            .unwrap_or_else(|| panic!("{name} in compare_methods.rs"));
        line.split('"').nth(1).unwrap().split(',').count()
    };
    assert_eq!(rows, list("DEFAULT_CASES") * list("DEFAULT_METHODS"));
}

/// A README's fenced block of `$ ` commands and what they print.
struct OutputBlock {
    /// `file:line` of the block's first command.
    at: String,
    /// Each command (continuation lines joined) and its output lines with
    /// their 0-based line numbers in the file.
    commands: Vec<(String, Vec<(usize, String)>)>,
}

/// Every fenced block whose first line is a `$ ` command.
fn output_blocks(file: &str, text: &str) -> Vec<OutputBlock> {
    let (mut blocks, mut lines) = (Vec::new(), text.lines().enumerate());
    while let Some((_, line)) = lines.next() {
        if !line.starts_with("```") {
            continue;
        }
        let mut block = OutputBlock {
            at: String::new(),
            commands: Vec::new(),
        };
        for (n, line) in lines.by_ref() {
            if line.starts_with("```") {
                break;
            }
            if let Some(command) = line.strip_prefix("$ ") {
                if block.commands.is_empty() {
                    block.at = format!("{file}:{}", n + 1);
                }
                block.commands.push((command.to_string(), Vec::new()));
            } else if let Some((command, output)) = block.commands.last_mut() {
                if command.ends_with('\\') && output.is_empty() {
                    command.pop();
                    command.push_str(line.trim_start());
                } else {
                    output.push((n, line.to_string()));
                }
            }
        }
        if !block.commands.is_empty() {
            blocks.push(block);
        }
    }
    blocks
}

/// A line with each duration (`2.3 ms`, `0.5 ms`) as `<t> ms` and, when it
/// has one, its spaces collapsed (a wider time shifts a table's columns):
/// wall times differ run to run, every other figure must not.
fn without_times(line: &str) -> String {
    let words: Vec<&str> = line.split_whitespace().collect();
    let mut timed = false;
    let mut out: Vec<String> = Vec::with_capacity(words.len());
    for (i, w) in words.iter().enumerate() {
        let unit = words
            .get(i + 1)
            .map(|u| u.trim_end_matches([',', ')', ';']));
        let number = w.trim_start_matches('(').parse::<f64>().is_ok();
        if number && unit == Some("ms") {
            timed = true;
            out.push("<t>".to_string());
        } else {
            out.push((*w).to_string());
        }
    }
    if timed {
        out.join(" ")
    } else {
        line.to_string()
    }
}

/// Runs one README command as a user would, from a scratch folder that sees
/// the repository's `examples/` (and writes `/tmp/…` inside itself): the
/// command line on the path; `cargo run --release --example NAME` as the
/// example this test profile built. Returns stdout and stderr, with the
/// scratch folder's path put back as the README writes it.
fn run_readme_command(command: &str, scratch: &std::path::Path) -> (String, String) {
    let root = env!("CARGO_MANIFEST_DIR");
    let tmp = format!("{}/tmp/", scratch.display());
    let bin = std::path::Path::new(env!("CARGO_BIN_EXE_aacmm"))
        .parent()
        .unwrap();
    let mut shell = command.replace("/tmp/", &tmp);
    if let Some(rest) = shell.strip_prefix("cargo run --release --example ") {
        let (name, args) = rest.split_once(' ').unwrap_or((rest, ""));
        let args = args.trim_start().strip_prefix("--").unwrap_or(args);
        let exe = bin.join("examples").join(name);
        shell = format!("{} {args}", exe.display());
    }
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg(&shell)
        .current_dir(scratch)
        .env(
            "PATH",
            format!(
                "{}:{}",
                bin.display(),
                std::env::var("PATH").unwrap_or_default()
            ),
        )
        .output()
        .expect("sh runs");
    let back = |s: &[u8]| {
        String::from_utf8_lossy(s)
            .replace(&tmp, "/tmp/")
            .replace(&format!("{root}/"), "")
    };
    (back(&o.stdout), back(&o.stderr))
}

/// A README line the command does not print: where, what, and the printed
/// line most like it (the longest common start), if any.
struct Drift {
    file: String,
    line: usize,
    readme: String,
    printed: Option<String>,
}

/// Whether a README line marks a cut: output left out there.
fn is_cut(line: &str) -> bool {
    matches!(line.trim(), "..." | "…")
}

/// Matches a command's README lines against what it printed, in order on
/// each stream: the lines that drifted, and per README line the printed
/// line it matched (stream, index), if any.
fn drifts(
    file: &str,
    expected: &[(usize, String)],
    out: &str,
    err: &str,
) -> (Vec<Drift>, Vec<Option<(usize, usize)>>) {
    let streams = [out.lines().collect::<Vec<_>>(), err.lines().collect()];
    let mut at = [0usize; 2];
    let mut found = Vec::new();
    let mut matched = vec![None; expected.len()];
    for (k, (n, line)) in expected.iter().enumerate() {
        if is_cut(line) {
            continue;
        }
        let line = without_times(line);
        let exact = (0..2).find_map(|s| {
            (streams[s][at[s]..].iter())
                .position(|r| without_times(r) == line)
                .map(|p| (s, p))
        });
        if let Some((s, p)) = exact {
            matched[k] = Some((s, at[s] + p));
            at[s] += p + 1;
            continue;
        }
        let common = |r: &str| {
            r.chars()
                .zip(line.chars())
                .take_while(|(a, b)| a == b)
                .count()
        };
        let near = (0..2)
            .flat_map(|s| (at[s]..streams[s].len()).map(move |p| (s, p)))
            .max_by_key(|&(s, p)| common(streams[s][p]))
            .filter(|&(s, p)| common(streams[s][p]) >= 12);
        if let Some((s, p)) = near {
            at[s] = p + 1;
        }
        found.push(Drift {
            file: file.to_string(),
            line: *n,
            readme: line.clone(),
            printed: near.map(|(s, p)| streams[s][p].to_string()),
        });
    }
    (found, matched)
}

/// Printed lines a README block leaves out without a cut (`...` or `…`)
/// where they would stand: a block shows the whole output or marks each
/// cut, so that a line the program added (or one the README lost) is
/// caught, not only one that changed. Blank lines are not content. `at`
/// names the block for the message.
fn omissions(
    at: &str,
    expected: &[(usize, String)],
    matched: &[Option<(usize, usize)>],
    out: &str,
    err: &str,
) -> Vec<String> {
    let streams = [out.lines().collect::<Vec<_>>(), err.lines().collect()];
    let mut missing = Vec::new();
    for (s, printed) in streams.iter().enumerate() {
        // The README lines (by position in the block) matched on this
        // stream, in order, with the printed line each matched.
        let on: Vec<(usize, usize)> = (matched.iter().enumerate())
            .filter_map(|(k, m)| m.filter(|m| m.0 == s).map(|m| (k, m.1)))
            .collect();
        let cut_between = |a: Option<usize>, b: Option<usize>| {
            let (lo, hi) = (a.map_or(0, |a| a + 1), b.unwrap_or(expected.len()));
            expected[lo.min(hi)..hi].iter().any(|(_, l)| is_cut(l))
        };
        let mut prev: Option<(usize, usize)> = None;
        for next in on.iter().copied().map(Some).chain([None]) {
            let first = prev.map_or(0, |p| p.1 + 1);
            let last = next.map_or(printed.len(), |n| n.1);
            let gap: Vec<&str> = (printed[first.min(last)..last].iter())
                .copied()
                .filter(|l| !l.trim().is_empty())
                .collect();
            if !gap.is_empty() && !cut_between(prev.map(|p| p.0), next.map(|n| n.0)) {
                missing.extend(gap.iter().map(|l| format!("{at}: left out: {l:?}")));
            }
            prev = next;
        }
    }
    missing
}

/// The README files whose output blocks are checked: the main one and every
/// example's.
fn readme_files(root: &std::path::Path) -> Vec<String> {
    let mut files = vec!["README.md".to_string()];
    let mut examples: Vec<String> = std::fs::read_dir(root.join("examples"))
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().join("README.md").is_file())
        .map(|e| format!("examples/{}/README.md", e.file_name().to_string_lossy()))
        .collect();
    examples.sort();
    files.extend(examples);
    files
}

/// Every README output block — `$ ` commands with what they print, in
/// README.md and every example's README — is real output: each printed
/// line is a line the command prints, in order on its stream, wall times
/// aside, and every line the command prints is in the block unless a cut
/// (`...` or `…`) stands where it would be. CI runs this, so a block that
/// drifts fails; `AACMM_BLESS=1` rewrites each drifted line with the
/// printed line most like it (review the diff; lines left out are added
/// by hand).
#[test]
fn every_readme_output_block_is_real_output() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let (mut checked, mut all, mut left_out) = (0, Vec::new(), Vec::new());
    let files = readme_files(root);
    assert!(files.len() >= 3, "README files: {files:?}");
    for file in &files {
        let file = file.as_str();
        let text = std::fs::read_to_string(root.join(file)).unwrap();
        for (i, block) in output_blocks(file, &text).into_iter().enumerate() {
            let name = format!("readme-{}-{i}", file.replace('/', "-"));
            let scratch = crate::util::temp_dir(&name);
            std::os::unix::fs::symlink(root.join("examples"), scratch.join("examples")).unwrap();
            std::fs::create_dir_all(scratch.join("tmp")).unwrap();
            std::fs::create_dir_all(scratch.join("target")).unwrap();
            for (command, expected) in &block.commands {
                let (out, err) = run_readme_command(command, &scratch);
                let (found, matched) = drifts(file, expected, &out, &err);
                let missing = omissions(&block.at, expected, &matched, &out, &err);
                if !(found.is_empty() && missing.is_empty())
                    && std::env::var_os("AACMM_BLESS").is_none()
                {
                    eprintln!(
                        "{}: `{command}`\n--- stdout\n{out}\n--- stderr\n{err}",
                        block.at
                    );
                }
                all.extend(found);
                left_out.extend(missing);
                checked += 1;
            }
            // A README command writes under target/ or /tmp/ only: on a
            // clone, anything else lands in the repository's root.
            let mut stray: Vec<String> = (std::fs::read_dir(&scratch).unwrap())
                .filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| !["examples", "tmp", "target"].contains(&n.as_str()))
                .collect();
            stray.sort();
            left_out.extend(
                stray
                    .iter()
                    .map(|n| format!("{}: writes {n} into the repository's root", block.at)),
            );
        }
    }
    assert!(checked >= 10, "only {checked} README commands found");
    if std::env::var_os("AACMM_BLESS").is_some() {
        bless(root, &all);
        return;
    }
    let listed: Vec<String> = (all.iter())
        .map(|d| {
            format!(
                "{}:{}: README {:?}\n    printed {:?}",
                d.file,
                d.line + 1,
                d.readme,
                d.printed.as_deref().unwrap_or("(nothing like it)")
            )
        })
        .collect();
    assert!(
        all.is_empty() && left_out.is_empty(),
        "README output blocks drifted (AACMM_BLESS=1 rewrites them):\n{}\n\
         README output blocks leave out printed lines without a cut (`…`) there, or write \
         outside target/ and /tmp/:\n{}",
        listed.join("\n"),
        left_out.join("\n")
    );
}

/// Rewrites each drifted line that has a printed line like it.
fn bless(root: &std::path::Path, drifts: &[Drift]) {
    let mut files: Vec<&str> = drifts.iter().map(|d| d.file.as_str()).collect();
    files.dedup();
    for file in files {
        let text = std::fs::read_to_string(root.join(file)).unwrap();
        let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
        for d in drifts.iter().filter(|d| d.file == file) {
            if let Some(p) = &d.printed {
                lines[d.line] = p.clone();
            }
        }
        std::fs::write(root.join(file), lines.join("\n") + "\n").unwrap();
    }
}

/// The completeness check: a printed line a block leaves out fails unless
/// a cut stands where it would be — at the start, between lines or at the
/// end, on either stream; blank lines are not content.
#[test]
fn a_block_that_leaves_out_a_line_fails_unless_a_cut_stands_there() {
    let lines = |l: &[&str]| -> Vec<(usize, String)> {
        l.iter()
            .enumerate()
            .map(|(i, s)| (i, s.to_string()))
            .collect()
    };
    let check = |block: &[&str], out: &str, err: &str| {
        let expected = lines(block);
        let (drifted, matched) = drifts("R.md", &expected, out, err);
        assert!(drifted.is_empty());
        omissions("R.md:1", &expected, &matched, out, err)
    };
    let (out, err) = ("a\nb\n\nc\n", "time: 1.0 ms\n");
    assert!(check(&["a", "b", "c", "time: 2.0 ms"], out, err).is_empty());
    assert_eq!(
        check(&["a", "c", "time: 2.0 ms"], out, err),
        ["R.md:1: left out: \"b\""]
    );
    assert!(check(&["a", "…", "c", "time: 2.0 ms"], out, err).is_empty());
    // The other stream's line is left out too, at the end.
    assert_eq!(
        check(&["a", "b", "c"], out, err),
        ["R.md:1: left out: \"time: 1.0 ms\""]
    );
    assert!(check(&["a", "b", "c", "..."], out, err).is_empty());
    // Leading lines need a cut before the first line shown.
    assert_eq!(check(&["c", "time: 2.0 ms"], out, err).len(), 2);
    assert!(check(&["…", "c", "time: 2.0 ms"], out, err).is_empty());
}

/// What the README says of a default or a command is what the program
/// does: `plan --hedge` is 0 unless given (the library's default, the
/// help's), and `calibrate`'s one-line help names every kind of data it
/// fits (touches, reference lengths, reference positions).
#[test]
fn the_readme_and_the_help_state_the_programs_defaults() {
    let text = readme();
    let library = aacmm_core::plan::PlanSettings::new(1, aacmm_core::plan::Measure::Touches).hedge;
    assert_eq!(library, 0.0);
    assert!(
        text.contains("`--hedge τ` counts each candidate noisier by its leverage (0 by\ndefault"),
        "the README's plan section states --hedge's default"
    );
    let help = crate::util::aacmm(&["plan", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout).into_owned();
    let hedge = help
        .split("--hedge")
        .nth(1)
        .expect("plan --help shows --hedge");
    let hedge = &hedge[..hedge.find("\n  -").unwrap_or(hedge.len())];
    assert!(hedge.contains("[default: 0]"), "{hedge}");
    let top = crate::util::aacmm(&["--help"]);
    let top = String::from_utf8_lossy(&top.stdout).into_owned();
    let line = (top.lines())
        .find(|l| l.trim_start().starts_with("calibrate "))
        .expect("aacmm --help lists calibrate");
    for kind in ["touches", "reference lengths", "reference positions"] {
        assert!(line.contains(kind), "{line}");
    }
}
