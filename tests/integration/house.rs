//! House checks of the repository itself (issue 23), run by the README's
//! `cargo test --workspace`:
//!
//! - the layering of aacmm-core: a module references (`crate::m…`) only
//!   modules of its own rank or below ([`RANKS`]), and no two modules
//!   reference each other, directly or through others, inside a rank too
//!   ([`KNOWN_CYCLES`]);
//! - no function is over [`MAX_FN_LINES`] lines: a port of the tool that
//!   measured them (`fnlen.py`: comments and literals blanked, `fn` bodies
//!   brace-matched, test modules skipped), with the same figure for every
//!   function both see, and two corrections: a `;` inside the signature
//!   (`[T; N]`) does not make a function a declaration, and a test module
//!   with a visibility (`pub(crate) mod tests {`) is a test module;
//! - no string literal outside tests holds a run of more than
//!   [`MAX_SPACES_IN_TEXT`] spaces inside a line: a line continuation lost,
//!   which a user reads as a gap in a message or a command's help.
//!
//! Each check holds the exceptions found when it was written
//! ([`KNOWN_VIOLATIONS`], [`KNOWN_LONG`]) and demands that they equal what
//! it finds now: a new exception fails, and so does one that has been fixed
//! but is still listed, so the lists can only shrink.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The rank of every top-level module of aacmm-core (the first path segment
/// under `core/src`). A module may reference only modules of its own rank
/// or below.
///
/// Data flow one way, down this chain: the nouns (`domain`) and their files
/// (`io`) → data set
/// (`dataset`) → residual terms and measures of an arm (`residuals`,
/// `objective`, `metrics`, `simulate`) → the solver and what it identifies
/// (`calibrate`, `identify`, `hayati`) → the assessment and
/// its report (`session`, `report`). Nothing reaches back up: a residual
/// term that needed the solver's types, or a solver that needed the report,
/// could not be tested, reused or read without what comes after it. The
/// kernel (the generated D-H chains, and the autodiff and URDF models it is
/// checked against) and the ground floor (errors, options, parameters,
/// geometry, random numbers, tolerances, threads, damping, statistics,
/// memory) are libraries
/// that everything from the files to the solver uses, so they sit beneath
/// the chain and use nothing of it.
///
/// `tolerances`, `parallel`, `damping`, `objective` and `options` are the
/// modules a parallel refactor adds; ranked ahead so that they arrive in
/// their place.
const RANKS: &[(&str, u8)] = &[
    // 0: the ground floor, used by everything.
    ("error", 0),
    ("options", 0),
    ("params", 0),
    ("geometry", 0),
    ("random", 0),
    ("tolerances", 0),
    ("parallel", 0),
    ("damping", 0),
    ("stats", 0),
    ("memory", 0),
    ("simd", 0),
    // Every option's name in every front end's words.
    ("setting", 0),
    // 1: the kernel, and the reference models it is checked against.
    ("kernel", 1),
    ("reference_model", 1),
    ("urdf", 1),
    // What an arm is beyond its chain (masses, compliance, encoder
    // harmonics, expansion) and the poses it makes of readings: the
    // kernel's input, used by an arm (`domain`), the files, the data set
    // and the terms.
    ("corrections", 1),
    // 2: the nouns (an arm, the evidence recorded on it), and the files
    // they are read from and written to; the files use the nouns, never
    // the other way round.
    ("domain", 2),
    ("io", 2),
    // 3: the typed data set made of them.
    ("dataset", 3),
    // 4: what an arm makes of a data set: residual terms, their cost,
    // metrics, and the campaigns that produce data sets to test them on.
    ("residuals", 4),
    ("objective", 4),
    ("metrics", 4),
    ("simulate", 4),
    // 5: the solver, and what it identifies and plans.
    ("identify", 5),
    // The acceptance tests read the nouns (`domain`), kernel, metrics and
    // the sphere term's algebraic start; nothing above reads them yet.
    ("acceptance", 5),
    ("calibrate", 5),
    ("hayati", 5),
    ("plan", 5),
    // 6: the assessment of a calibration: data, no words or files.
    ("session", 6),
    // The prelude re-exports the front door of every rank, from the data
    // set to the session, so it sits on top with them; nothing in the
    // crate uses it (it is for programs), so nothing depends on its rank.
    ("prelude", 6),
    // 7: everything rendered and written of what the session found — the
    // text summary, the JSON, the HTML page, the files and the rule that no
    // output is overwritten silently: above the session, which returns
    // data and never needs its words.
    ("report", 7),
];

/// The issue's rules between top-level directories, as (files whose module
/// is one of these, may not reference these modules): the ranks must imply
/// them (checked by `the_ranks_imply_the_issues_rules`).
const ISSUE_RULES: &[(&[&str], &[&str])] = &[
    // core/src/{residuals*, dataset.rs, io/*, kernel/*} ↛ crate::calibrate;
    // domain/* was part of io/* when the rule was written.
    (
        &["residuals", "dataset", "domain", "io", "kernel"],
        &["calibrate"],
    ),
    // core/src/calibrate/*, core/src/identify.rs ↛ crate::report, crate::session
    (&["calibrate", "identify"], &["report", "session"]),
];

/// The references against the ranks found when the check was written, as
/// (file, referenced module): being removed. Must equal what the check
/// finds, so fix one and remove it here; never add one.
const KNOWN_VIOLATIONS: &[(&str, &str)] = &[];

/// The cycles between top-level modules found when the cycle check was
/// written, each as its modules in name order, being removed: must equal
/// what the check finds (a new cycle fails, and so does one broken but
/// left here); never add one. The last, {report, session}, went when what
/// the session writes moved above both; the text summary and the JSON
/// then moved into `report` too, which the session no longer reaches.
const KNOWN_CYCLES: &[&[&str]] = &[];

/// The longest a function's body may be, in lines (from its `{` to its `}`).
const MAX_FN_LINES: usize = 100;

/// The functions over [`MAX_FN_LINES`] when the check was written, as
/// (file, function name), one entry per function: all split since, so
/// empty. Must equal what the check finds; never add one.
const KNOWN_LONG: &[(&str, &str)] = &[];

/// The directories whose functions are measured: every crate's library and
/// binary sources that the issue names.
const FN_DIRS: &[&str] = &["core/src", "src", "capi/src", "python/src"];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

// ---------------------------------------------------------------------------
// Scanning Rust source roughly: enough for these checks, not a parser.

/// `src` with comments, string and char literals blanked to spaces, newlines
/// kept (so line numbers hold): `strip` of fnlen.py, char for char. An
/// unterminated raw string runs to the end of the file (where the Python
/// tool would loop).
fn blank(src: &str) -> Vec<char> {
    lex(src).0
}

/// [`blank`]'s text, and the spans of the ordinary (not raw) string
/// literals it blanked, quotes excluded.
fn lex(src: &str) -> (Vec<char>, Vec<(usize, usize)>) {
    let s: Vec<char> = src.chars().collect();
    let n = s.len();
    let mut out = Vec::with_capacity(n);
    let mut strings = Vec::new();
    let spaces = |out: &mut Vec<char>, part: &[char]| {
        out.extend(part.iter().map(|&c| if c == '\n' { '\n' } else { ' ' }));
    };
    let mut i = 0;
    while i < n {
        let c = s[i];
        if starts_with(&s, i, "//") {
            let j = find(&s, "\n", i).unwrap_or(n);
            spaces(&mut out, &s[i..j]);
            i = j;
        } else if starts_with(&s, i, "/*") {
            let j = find(&s, "*/", i + 2).map_or(n, |j| j + 2);
            spaces(&mut out, &s[i..j]);
            i = j;
        } else if c == '"' || starts_with(&s, i, "r#\"") || starts_with(&s, i, "r\"") {
            let j = if c == 'r' {
                // As the Python tool: the characters between `r` and the
                // first quote are taken for the hashes.
                let h = s[i + 1..].iter().position(|&c| c == '"').unwrap_or(0);
                let term: String = std::iter::once('"')
                    .chain(std::iter::repeat_n('#', h))
                    .collect();
                find(&s, &term, i + 2 + h).map_or(n, |j| j + h + 1)
            } else {
                let mut j = i + 1;
                while j < n && s[j] != '"' {
                    j += if s[j] == '\\' { 2 } else { 1 };
                }
                strings.push((i + 1, j.min(n)));
                (j + 1).min(n)
            };
            spaces(&mut out, &s[i..j]);
            i = j;
        } else if let Some(len) = char_literal(&s, i) {
            spaces(&mut out, &s[i..i + len]);
            i += len;
        } else {
            out.push(c);
            i += 1;
        }
    }
    (out, strings)
}

/// The length of the char literal at `i` as fnlen.py's `'(\\.|[^\\'])'`
/// sees one (`'x'`, `'\n'`; not `'\u{…}'`, and never a lifetime).
fn char_literal(s: &[char], i: usize) -> Option<usize> {
    let at = |k: usize| s.get(i + k).copied();
    if at(0) != Some('\'') {
        return None;
    }
    match (at(1), at(2), at(3)) {
        (Some('\\'), Some(c), Some('\'')) if c != '\n' => Some(4),
        (Some(c), Some('\''), _) if c != '\\' && c != '\'' => Some(3),
        _ => None,
    }
}

fn starts_with(s: &[char], at: usize, pat: &str) -> bool {
    (at..).zip(pat.chars()).all(|(k, p)| s.get(k) == Some(&p))
}

fn find(s: &[char], pat: &str, from: usize) -> Option<usize> {
    (from..s.len()).find(|&i| starts_with(s, i, pat))
}

fn is_word(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

fn skip_space(s: &[char], mut i: usize) -> usize {
    while i < s.len() && s[i].is_whitespace() {
        i += 1;
    }
    i
}

fn word_end(s: &[char], mut i: usize) -> usize {
    while i < s.len() && is_word(s[i]) {
        i += 1;
    }
    i
}

/// The index of the `}` that closes the `{` at `open` (the end of the
/// source if none does).
fn closing(s: &[char], open: usize) -> usize {
    let mut depth = 0usize;
    for (k, &c) in s.iter().enumerate().skip(open) {
        match c {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    return k;
                }
            }
            _ => {}
        }
    }
    s.len()
}

fn line_of(s: &[char], at: usize) -> usize {
    s[..at].iter().filter(|&&c| c == '\n').count() + 1
}

/// A `#[cfg(test)] mod NAME` declaration: with a body (`Some(span)`, from
/// the attribute to the closing brace) or in its own file (`None`).
struct TestModule {
    name: String,
    body: Option<(usize, usize)>,
}

/// The `#[cfg(test)]` modules of blanked source. As fnlen.py's
/// `#\[cfg\(test\)\]\s*mod\s+\w+\s*\{`, and also with a visibility before
/// `mod` (`pub(crate) mod tests {`, which the Python tool counts as code).
fn test_modules(s: &[char]) -> Vec<TestModule> {
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(at) = find(s, "#[cfg(test)]", from) {
        from = at + 1;
        let mut i = skip_space(s, at + "#[cfg(test)]".len());
        if starts_with(s, i, "pub") && !s.get(i + 3).copied().is_some_and(is_word) {
            i = skip_space(s, i + 3);
            if s.get(i) == Some(&'(') {
                match s[i..].iter().position(|&c| c == ')') {
                    Some(k) => i = skip_space(s, i + k + 1),
                    None => continue,
                }
            }
        }
        if !starts_with(s, i, "mod") || !s.get(i + 3).copied().is_some_and(char::is_whitespace) {
            continue;
        }
        let name_start = skip_space(s, i + 3);
        let name_end = word_end(s, name_start);
        if name_end == name_start {
            continue;
        }
        let name: String = s[name_start..name_end].iter().collect();
        let after = skip_space(s, name_end);
        match s.get(after) {
            Some('{') => out.push(TestModule {
                name,
                body: Some((at, closing(s, after))),
            }),
            Some(';') => out.push(TestModule { name, body: None }),
            _ => {}
        }
    }
    out
}

/// The `.rs` files under `dir` (relative to the workspace root), as
/// `/`-separated paths relative to it, sorted.
fn rust_files(dir: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_string()];
    while let Some(d) = todo.pop() {
        let entries =
            std::fs::read_dir(root().join(&d)).unwrap_or_else(|e| panic!("cannot list {d}: {e}"));
        for entry in entries {
            let entry = entry.expect("a directory entry");
            let name = entry.file_name().into_string().expect("UTF-8 file name");
            let path = format!("{d}/{name}");
            let kind = entry.file_type().expect("a file type");
            if kind.is_dir() {
                todo.push(path);
            } else if name.ends_with(".rs") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

fn read(path: &str) -> String {
    std::fs::read_to_string(root().join(path)).unwrap_or_else(|e| panic!("cannot read {path}: {e}"))
}

// ---------------------------------------------------------------------------
// The layering of aacmm-core.

/// The `crate::` references of blanked source: the first segment after
/// `crate::` (for a group, `crate::{a::X, b}`, one per item) and its line.
fn crate_references(s: &[char]) -> Vec<(String, usize)> {
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(at) = find(s, "crate::", from) {
        from = at + "crate::".len();
        // `$crate::` in a macro is the macro's crate, and `foocrate::` no
        // reference.
        if at > 0 && (is_word(s[at - 1]) || s[at - 1] == '$') {
            continue;
        }
        let line = line_of(s, at);
        let i = skip_space(s, from);
        if s.get(i) == Some(&'{') {
            // Each top-level item of the group starts after `{` or a `,`.
            let end = closing(s, i);
            let mut depth = 0;
            let mut item_start = true;
            for k in i..end {
                match s[k] {
                    '{' => {
                        depth += 1;
                        item_start = depth == 1;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 1 => item_start = true,
                    c if item_start && depth == 1 && is_word(c) => {
                        let name: String = s[k..word_end(s, k)].iter().collect();
                        out.push((name, line_of(s, k)));
                        item_start = false;
                    }
                    c if !c.is_whitespace() => item_start = false,
                    _ => {}
                }
            }
        } else {
            let end = word_end(s, i);
            if end > i {
                out.push((s[i..end].iter().collect(), line));
            }
        }
    }
    out
}

fn rank(module: &str) -> Option<u8> {
    RANKS.iter().find(|(m, _)| *m == module).map(|&(_, r)| r)
}

/// The top-level module of a file under `core/src`: its first path segment
/// (`core/src/calibrate/lm.rs` → `calibrate`); `None` for the crate root.
fn module_of(file: &str) -> Option<&str> {
    let rest = file.strip_prefix("core/src/").expect("a file of core/src");
    let first = rest.split('/').next().unwrap();
    match first {
        "lib.rs" => None,
        _ => Some(first.strip_suffix(".rs").unwrap_or(first)),
    }
}

/// The items the crate root re-exports (`pub use m::{A, b as c};`), by the
/// name they have there, with the module they come from: `crate::A` is a
/// reference to `m`.
fn root_reexports(lib: &[char]) -> BTreeMap<String, String> {
    let text: String = lib.iter().collect();
    let mut out = BTreeMap::new();
    for stmt in text.split(';') {
        let Some(path) = stmt.trim().strip_prefix("pub use ") else {
            continue;
        };
        let (module, items) = path.split_once("::").expect("pub use m::…");
        let items = items.trim().trim_start_matches('{').trim_end_matches('}');
        for item in items.split(',').map(str::trim).filter(|i| !i.is_empty()) {
            let name = item.rsplit([' ', ':']).next().unwrap();
            out.insert(name.to_string(), module.trim().to_string());
        }
    }
    out
}

/// A non-test source file of aacmm-core, blanked.
struct CoreFile {
    path: String,
    src: Vec<char>,
}

/// The non-test sources of aacmm-core, with their `#[cfg(test)] mod … {…}`
/// blocks blanked and without the files of `#[cfg(test)] mod …;`.
fn core_files() -> Vec<CoreFile> {
    let mut files: Vec<CoreFile> = rust_files("core/src")
        .into_iter()
        .map(|path| {
            let src = blank(&read(&path));
            CoreFile { path, src }
        })
        .collect();
    let mut test_paths = Vec::new();
    for f in &mut files {
        // A module's children live in its directory: `m/` for `m.rs`.
        let dir = match f.path.rsplit_once('/') {
            Some((dir, "lib.rs" | "mod.rs")) => dir.to_string(),
            _ => f.path.trim_end_matches(".rs").to_string(),
        };
        for t in test_modules(&f.src) {
            match t.body {
                Some((start, end)) => {
                    for c in &mut f.src[start..end] {
                        if *c != '\n' {
                            *c = ' ';
                        }
                    }
                }
                None => {
                    test_paths.push(format!("{dir}/{}.rs", t.name));
                    test_paths.push(format!("{dir}/{}/", t.name));
                }
            }
        }
    }
    files.retain(|f| {
        !test_paths
            .iter()
            .any(|t| f.path == *t || f.path.starts_with(t.as_str()))
    });
    files
}

/// A reference against the ranks: `file:line` references `crate::target`.
struct Violation {
    file: String,
    line: usize,
    module: String,
    target: String,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (r, s) = (rank(&self.target).unwrap(), rank(&self.module).unwrap());
        write!(
            f,
            "{}:{} imports crate::{}, rank {r} > rank {s} of {}: move the item down to a module \
             of rank ≤ {s}, or the code that needs it up to one of rank ≥ {r}",
            self.file, self.line, self.target, self.module
        )
    }
}

/// The top-level modules of `files`, and the items the crate root
/// re-exports with the module each comes from.
fn modules_and_reexports(files: &[CoreFile]) -> (BTreeSet<&str>, BTreeMap<String, String>) {
    let lib = files
        .iter()
        .find(|f| f.path == "core/src/lib.rs")
        .expect("core/src/lib.rs");
    let modules = files.iter().filter_map(|f| module_of(&f.path)).collect();
    (modules, root_reexports(&lib.src))
}

/// The references of `files` against the ranks, and the problems that stop
/// the check (a module without a rank, a reference it cannot place).
fn violations(files: &[CoreFile]) -> (Vec<Violation>, Vec<String>) {
    let (modules, reexports) = modules_and_reexports(files);
    let mut problems: Vec<String> = modules
        .iter()
        .filter(|m| rank(m).is_none())
        .map(|m| {
            format!(
                "core/src/{m}: a module without a rank; give it one in RANKS \
                 (tests/integration/house.rs), where it stands in the data chain"
            )
        })
        .collect();
    let mut found = Vec::new();
    for f in files {
        // The crate root is the façade over every module (its `pub use`
        // lines), above all ranks.
        let Some(module) = module_of(&f.path) else {
            continue;
        };
        let Some(own) = rank(module) else { continue };
        for (name, line) in crate_references(&f.src) {
            let target = if modules.contains(name.as_str()) || rank(&name).is_some() {
                name
            } else if let Some(m) = reexports.get(&name) {
                m.clone()
            } else {
                problems.push(format!(
                    "{}:{line}: crate::{name} is neither a module of aacmm-core nor re-exported \
                     by its root; give the module a rank in RANKS",
                    f.path
                ));
                continue;
            };
            match rank(&target) {
                None => problems.push(format!(
                    "{}:{line}: crate::{target} has no rank; give it one in RANKS",
                    f.path
                )),
                Some(r) if r > own => found.push(Violation {
                    file: f.path.clone(),
                    line,
                    module: module.to_string(),
                    target,
                }),
                Some(_) => {}
            }
        }
    }
    (found, problems)
}

#[test]
fn core_modules_reference_only_their_rank_or_below() {
    let (found, problems) = violations(&core_files());
    assert!(problems.is_empty(), "\n{}\n", problems.join("\n"));
    let known: BTreeSet<(&str, &str)> = KNOWN_VIOLATIONS.iter().copied().collect();
    assert_eq!(
        known.len(),
        KNOWN_VIOLATIONS.len(),
        "KNOWN_VIOLATIONS lists one twice"
    );
    let now: BTreeSet<(&str, &str)> = found
        .iter()
        .map(|v| (v.file.as_str(), v.target.as_str()))
        .collect();
    let new: Vec<String> = found
        .iter()
        .filter(|v| !known.contains(&(v.file.as_str(), v.target.as_str())))
        .map(Violation::to_string)
        .collect();
    let fixed: Vec<String> = known
        .difference(&now)
        .map(|(file, target)| {
            format!(
                "{file} no longer references crate::{target}: remove it from KNOWN_VIOLATIONS \
                 (tests/integration/house.rs)"
            )
        })
        .collect();
    let all: Vec<String> = found.iter().map(Violation::to_string).collect();
    assert!(
        new.is_empty() && fixed.is_empty(),
        "\nthe layering of aacmm-core (RANKS in tests/integration/house.rs):\n{}\n\n\
         every reference against the ranks found:\n{}\n",
        new.iter()
            .chain(&fixed)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n"),
        all.join("\n")
    );
}

/// Which top-level modules each module references (itself left out), with
/// the first `file:line` of each reference; the crate root, the façade
/// over every module, is none of them.
fn module_graph(files: &[CoreFile]) -> BTreeMap<String, BTreeMap<String, String>> {
    let (modules, reexports) = modules_and_reexports(files);
    let mut graph: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
    for f in files {
        let Some(module) = module_of(&f.path) else {
            continue;
        };
        for (name, line) in crate_references(&f.src) {
            let target = if modules.contains(name.as_str()) {
                name
            } else if let Some(m) = reexports.get(&name) {
                m.clone()
            } else {
                // An unplaceable reference is a problem the ranks' check
                // reports.
                continue;
            };
            if target != module {
                (graph.entry(module.to_string()).or_default())
                    .entry(target)
                    .or_insert_with(|| format!("{}:{line}", f.path));
            }
        }
    }
    graph
}

/// The strongly connected components of more than one module (the cycles),
/// each sorted, in the order of their first module: every module of one
/// reaches every other through references.
fn cycles(graph: &BTreeMap<String, BTreeMap<String, String>>) -> Vec<Vec<String>> {
    let reach = |from: &str| {
        let mut seen = BTreeSet::new();
        let mut todo = vec![from.to_string()];
        while let Some(m) = todo.pop() {
            for t in graph.get(&m).into_iter().flat_map(BTreeMap::keys) {
                if seen.insert(t.clone()) {
                    todo.push(t.clone());
                }
            }
        }
        seen
    };
    let reached: BTreeMap<&String, BTreeSet<String>> =
        graph.keys().map(|m| (m, reach(m))).collect();
    let mut out: Vec<Vec<String>> = Vec::new();
    for (m, r) in &reached {
        let component: Vec<String> = (reached.iter())
            .filter(|(n, rn)| *n == m || (r.contains(n.as_str()) && rn.contains(m.as_str())))
            .map(|(n, _)| n.to_string())
            .collect();
        if component.len() > 1 && !out.contains(&component) {
            out.push(component);
        }
    }
    out
}

/// A cycle with the references that close it, `a → b (file:line)`.
fn describe_cycle(graph: &BTreeMap<String, BTreeMap<String, String>>, cycle: &[String]) -> String {
    let refs: Vec<String> = (cycle.iter())
        .flat_map(|a| {
            cycle.iter().filter_map(move |b| {
                let at = graph.get(a)?.get(b)?;
                Some(format!("{a} → {b} ({at})"))
            })
        })
        .collect();
    format!("{{{}}}: {}", cycle.join(", "), refs.join("; "))
}

#[test]
fn core_modules_reference_each_other_in_no_cycle() {
    let graph = module_graph(&core_files());
    let found = cycles(&graph);
    let known: Vec<Vec<String>> = (KNOWN_CYCLES.iter())
        .map(|c| c.iter().map(|m| m.to_string()).collect())
        .collect();
    let new: Vec<String> = (found.iter())
        .filter(|c| !known.contains(c))
        .map(|c| {
            format!(
                "a cycle between modules: {}; move what both need down to a module beneath \
                 them",
                describe_cycle(&graph, c)
            )
        })
        .collect();
    let gone: Vec<String> = (known.iter())
        .filter(|c| !found.contains(c))
        .map(|c| {
            format!(
                "{{{}}} is no longer a cycle: remove it from KNOWN_CYCLES \
                 (tests/integration/house.rs)",
                c.join(", ")
            )
        })
        .collect();
    assert!(
        new.is_empty() && gone.is_empty(),
        "\n{}\n",
        new.iter()
            .chain(&gone)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n")
    );
}

/// The cycle check finds a cycle inside one rank and one through a third
/// module, names the references that close it, and nothing in a chain.
#[test]
fn the_cycle_check_sees_cycles_of_any_length() {
    let graph: BTreeMap<String, BTreeMap<String, String>> = [
        (
            "calibrate",
            &[("identify", "c.rs:1"), ("plan", "c.rs:2")][..],
        ),
        (
            "identify",
            &[("calibrate", "i.rs:3"), ("residuals", "i.rs:4")],
        ),
        ("plan", &[("identify", "p.rs:5")]),
        ("report", &[("session", "r.rs:6")]),
        ("session", &[("report", "s.rs:7"), ("residuals", "s.rs:8")]),
        ("residuals", &[("io", "x.rs:9")]),
    ]
    .into_iter()
    .map(|(m, refs)| {
        let refs = refs.iter().map(|(t, at)| (t.to_string(), at.to_string()));
        (m.to_string(), refs.collect())
    })
    .collect();
    let found = cycles(&graph);
    let names: Vec<Vec<&str>> = (found.iter())
        .map(|c| c.iter().map(String::as_str).collect())
        .collect();
    assert_eq!(
        names,
        [
            vec!["calibrate", "identify", "plan"],
            vec!["report", "session"]
        ]
    );
    assert_eq!(
        describe_cycle(&graph, &found[1]),
        "{report, session}: report → session (r.rs:6); session → report (s.rs:7)"
    );
}

#[test]
fn the_ranks_imply_the_issues_rules() {
    for (modules, banned) in ISSUE_RULES {
        for m in *modules {
            for b in *banned {
                let (rm, rb) = (rank(m).unwrap(), rank(b).unwrap());
                assert!(rm < rb, "{m} (rank {rm}) may reference {b} (rank {rb})");
            }
        }
    }
    let names: BTreeSet<&str> = RANKS.iter().map(|(m, _)| *m).collect();
    assert_eq!(names.len(), RANKS.len(), "a module ranked twice");
}

#[test]
fn the_layering_scan_sees_code_not_comments_strings_or_tests() {
    let src = r##"
use crate::domain::Arm;
use crate::{dataset::DataSet, kernel::{A, B}, params};
// use crate::comment;
/// [`x`](crate::doc)
/* crate::block */
pub(crate) fn f() -> crate::report::R {
    let s = "crate::string";
    let r = r#"crate::raw"#;
    $crate::macro_crate::x;
    foocrate::not_one;
    crate::calibrate::OptionError::new()
}
#[cfg(test)]
mod tests {
    use crate::session::Problem;
}
#[cfg(test)]
pub(crate) mod more_tests {
    fn g() { crate::simulate::simulate(); }
}
"##;
    let mut s = blank(src);
    for t in test_modules(&s) {
        let (a, b) = t.body.expect("inline test modules");
        s[a..b].iter_mut().for_each(|c| *c = ' ');
    }
    let refs = crate_references(&s);
    let names: Vec<(&str, usize)> = refs.iter().map(|(n, l)| (n.as_str(), *l)).collect();
    assert_eq!(
        names,
        [
            ("domain", 2),
            ("dataset", 3),
            ("kernel", 3),
            ("params", 3),
            ("report", 7),
            ("calibrate", 12)
        ]
    );
}

#[test]
fn a_file_module_of_cfg_test_is_test_code() {
    let s = blank("#[cfg(test)]\nmod tests;\n#[cfg(test)] pub mod t2 { fn x() {} }\nmod real;\n");
    let t: Vec<(String, bool)> = test_modules(&s)
        .into_iter()
        .map(|t| (t.name, t.body.is_some()))
        .collect();
    assert_eq!(t, [("tests".to_string(), false), ("t2".to_string(), true)]);
}

#[test]
fn the_crate_roots_reexports_name_their_module() {
    let r = root_reexports(&blank(
        "pub use calibrate::{Method, calibrate as run};\npub use domain::Arm;\nuse x::Y;\n",
    ));
    let r: Vec<(&str, &str)> = r.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
    assert_eq!(
        r,
        [
            ("Arm", "domain"),
            ("Method", "calibrate"),
            ("run", "calibrate")
        ]
    );
}

// ---------------------------------------------------------------------------
// Function length: fnlen.py in Rust.

/// A function with a body: its name, the line of `fn`, and its body's lines.
#[derive(Debug, PartialEq)]
struct Function {
    name: String,
    line: usize,
    lines: usize,
}

/// The functions of `src` outside `#[cfg(test)] mod … {}` blocks, as
/// fnlen.py measures them: from `fn NAME` to the first `{` (none when a `;`
/// comes first: a declaration), brace-matched; the body's lines are the
/// newlines between its braces plus one.
fn functions(src: &str) -> Vec<Function> {
    let s = blank(src);
    let tests: Vec<(usize, usize)> = test_modules(&s).iter().filter_map(|t| t.body).collect();
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(at) = find(&s, "fn", from) {
        from = at + 2;
        // `\bfn\s+(\w+)`
        if at > 0 && is_word(s[at - 1]) {
            continue;
        }
        let name_start = skip_space(&s, at + 2);
        if name_start == at + 2 {
            continue;
        }
        let name_end = word_end(&s, name_start);
        if name_end == name_start {
            continue;
        }
        from = name_end;
        let Some(open) = body_start(&s, name_end) else {
            continue;
        };
        if tests.iter().any(|&(a, b)| a <= at && at <= b) {
            continue;
        }
        let close = closing(&s, open);
        out.push(Function {
            name: s[name_start..name_end].iter().collect(),
            line: line_of(&s, at),
            lines: s[open..close].iter().filter(|&&c| c == '\n').count() + 1,
        });
    }
    out
}

/// Where the body of the `fn` whose signature starts at `from` opens: the
/// first `{` outside parentheses and brackets; `None` for a declaration (a
/// `;` first). fnlen.py takes the first `;` anywhere, so a `[T; N]` in the
/// signature hides the function from it (108 lines of
/// `analysed_open_directions`, with `base: [usize; 2]`, when this was
/// written).
fn body_start(s: &[char], from: usize) -> Option<usize> {
    let mut depth = 0usize;
    for (k, &c) in s.iter().enumerate().skip(from) {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth = depth.saturating_sub(1),
            '{' if depth == 0 => return Some(k),
            ';' if depth == 0 => return None,
            _ => {}
        }
    }
    None
}

/// The files fnlen.py measures under `dir`: not in a directory whose path
/// contains `/tests` or `/target`, nor named `tests.rs`.
fn measured_files(dir: &str) -> Vec<String> {
    rust_files(dir)
        .into_iter()
        .filter(|f| {
            let (parent, name) = f.rsplit_once('/').unwrap();
            !parent.contains("/tests") && !parent.contains("/target") && name != "tests.rs"
        })
        .collect()
}

#[test]
fn no_function_is_over_100_lines() {
    let mut long: Vec<(String, Function)> = Vec::new();
    for dir in FN_DIRS {
        for file in measured_files(dir) {
            for f in functions(&read(&file)) {
                if f.lines > MAX_FN_LINES {
                    long.push((file.clone(), f));
                }
            }
        }
    }
    // Multisets: two long functions of one name in one file are two entries.
    let mut known: BTreeMap<(&str, &str), usize> = BTreeMap::new();
    for &k in KNOWN_LONG {
        *known.entry(k).or_default() += 1;
    }
    let mut new = Vec::new();
    for (file, f) in &long {
        match known.get_mut(&(file.as_str(), f.name.as_str())) {
            Some(n) if *n > 0 => *n -= 1,
            _ => new.push(format!(
                "{file}:{} fn {} is {} lines (limit {MAX_FN_LINES}): split it",
                f.line, f.name, f.lines
            )),
        }
    }
    let fixed: Vec<String> = known
        .iter()
        .filter(|(_, n)| **n > 0)
        .map(|((file, name), _)| {
            format!(
                "fn {name} in {file} is no longer over {MAX_FN_LINES} lines: remove it from \
                 KNOWN_LONG (tests/integration/house.rs)"
            )
        })
        .collect();
    let all: Vec<String> = long
        .iter()
        .map(|(file, f)| format!("{} {} {file}:{}", f.lines, f.name, f.line))
        .collect();
    assert!(
        new.is_empty() && fixed.is_empty(),
        "\nfunction length (KNOWN_LONG in tests/integration/house.rs):\n{}\n\n\
         every function over {MAX_FN_LINES} lines found:\n{}\n",
        new.iter()
            .chain(&fixed)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n"),
        all.join("\n")
    );
}

/// The port measures what fnlen.py measures: braces in strings, raw strings,
/// char literals and comments do not count, a nested function is measured
/// on its own and within its parent, a declaration is none, a test module's
/// functions are skipped. Where it deliberately differs (a `[T; N]` in the
/// signature, a `pub(crate)` test module) the tool's own figure is said.
#[test]
fn the_port_measures_as_fnlen_py() {
    let src = r##"fn strings() {
    let a = "{ not a brace";
    let b = r#"} nor "this" {"#;
    let c = '{';
    let d = '\'';
    // }
    /* { */
}

pub fn outer<'a>(x: &'a str) -> usize {
    fn inner() -> u8 {
        1
    }
    x.len() + inner() as usize
}

trait T {
    fn declared(&self) -> [u8; 4];
    fn provided(&self) {}
}

fn array_argument(v: [usize; 2]) -> usize {
    v[0]
        + v[1]
}

#[cfg(test)]
mod tests {
    fn helper() {
        let _ = 1;
    }
}

#[cfg(test)]
pub(crate) mod more_tests {
    fn helper2() {
    }
}
"##;
    let functions = functions(src);
    let found: Vec<(&str, usize, usize)> = functions
        .iter()
        .map(|f| (f.name.as_str(), f.line, f.lines))
        .collect();
    // `python3 fnlen.py` on this source: 8 strings :1, 6 outer :10, 3 inner
    // :11, 1 provided :19, and 2 helper2 :36; it misses array_argument.
    assert_eq!(
        found,
        [
            ("strings", 1, 8),
            ("outer", 10, 6),
            ("inner", 11, 3),
            ("provided", 19, 1),
            ("array_argument", 22, 4),
        ]
    );
}

// ---------------------------------------------------------------------------
// Text a user reads.

/// More spaces than this between two characters of one line inside a string
/// literal are a line continuation lost: a `\` at a line's end taken out
/// and the next line's indentation left in the text, so that a message
/// reads "would absorb them                  whole" (two such were found
/// when this check was written, a refusal and a command's `--help`, with
/// runs of 18 and 22). Text laid out in columns (`"stated (mm):         {}"`)
/// has runs of up to 9.
const MAX_SPACES_IN_TEXT: usize = 12;

/// Where `text` (a literal's) has more than [`MAX_SPACES_IN_TEXT`] spaces
/// between two characters of one line, the first of them not the `n` of a
/// `\n` escape (indentation after an escaped newline is text laid out on
/// purpose).
fn lost_continuation(text: &[char]) -> Option<usize> {
    let mut k = 0;
    while k < text.len() {
        let run = text[k..].iter().take_while(|&&c| c == ' ').count();
        if run > MAX_SPACES_IN_TEXT && k > 0 && k + run < text.len() {
            let before = text[k - 1];
            let escaped_newline = before == 'n' && k >= 2 && text[k - 2] == '\\';
            if !before.is_whitespace() && !escaped_newline && !text[k + run].is_whitespace() {
                return Some(k);
            }
        }
        k += run.max(1);
    }
    None
}

/// The lost continuations of `src`'s string literals outside its test
/// modules, by line.
fn lost_continuations(src: &str) -> Vec<usize> {
    let s: Vec<char> = src.chars().collect();
    let (blanked, strings) = lex(src);
    let tests: Vec<(usize, usize)> = test_modules(&blanked)
        .iter()
        .filter_map(|t| t.body)
        .collect();
    strings
        .into_iter()
        .filter(|&(a, _)| !tests.iter().any(|&(t0, t1)| t0 <= a && a <= t1))
        .filter_map(|(a, b)| lost_continuation(&s[a..b]).map(|k| line_of(&s, a + k)))
        .collect()
}

#[test]
fn no_text_holds_a_lost_line_continuation() {
    let mut found = Vec::new();
    for dir in FN_DIRS {
        for file in measured_files(dir) {
            for line in lost_continuations(&read(&file)) {
                found.push(format!("{file}:{line}"));
            }
        }
    }
    assert!(
        found.is_empty(),
        "string literals with a run of spaces inside a line (a `\\` at a line's end lost?): {found:?}"
    );
}

#[test]
fn the_continuation_scan_sees_text_not_layout_comments_or_tests() {
    let src = r##"
fn f() {
    let lost = "would absorb them                whole";
    let kept = "one line \
                the next";
    let table = "a\n                b  stated (mm):         {}";
    let raw = r#"x                y"#;
    // "a comment                with spaces"
    let tail = "ends in spaces                ";
    let c = '"'; let after = "after a quote char                here";
}
#[cfg(test)]
mod tests {
    const T: &str = "aligned                columns";
}
"##;
    assert_eq!(lost_continuations(src), [3, 10]);
}
