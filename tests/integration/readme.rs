//! The README shows what the programs do: its `evaluate` block is real
//! output, and `compare_methods` without arguments prints its table's rows.

use crate::util::{aacmm, stdout};

fn readme() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap()
}

/// The fenced block that starts with `$ <command>`: the command, and its
/// lines.
fn block(readme: &str, command_start: &str) -> (String, Vec<String>) {
    let at = readme
        .find(command_start)
        .expect("the README shows the command");
    let end = at + readme[at..].find("\n```").expect("the block ends");
    let mut lines = readme[at..end].lines().map(str::to_string);
    let command = lines.next().unwrap();
    (command, lines.collect())
}

/// Every line of the README's `evaluate` block, `...` cuts aside, is a line
/// of the real output, in order (its "Across pairs" heading was not).
#[test]
fn evaluate_block_is_real_output() {
    let text = readme();
    let (command, lines) = block(&text, "$ aacmm evaluate ");
    let args: Vec<&str> = command.split_whitespace().skip(2).collect();
    let root = env!("CARGO_MANIFEST_DIR");
    let args: Vec<String> = args
        .iter()
        .map(|a| {
            if a.starts_with("examples/") {
                format!("{root}/{a}")
            } else {
                a.to_string()
            }
        })
        .collect();
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = aacmm(&args);
    assert!(o.status.success());
    let real = stdout(&o).replace(&format!("{root}/"), "");
    let mut rest = real.lines();
    for line in lines.iter().filter(|l| l.trim() != "...") {
        assert!(
            rest.any(|r| r == line),
            "README line not in the output (in order): {line:?}\n{real}"
        );
    }
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
