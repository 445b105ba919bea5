//! Building once (issue 43, case 11): the README's release builds — the
//! command line, the C library, the Python package and the examples — ask
//! every crate aacmm-core is built from for the same features, so cargo
//! builds aacmm-core once for all four in one target directory. Each build
//! asked some shared crate for a feature of its own (clap: libc's `std`;
//! pyo3 and numpy: matrixmultiply's `cgemm`, syn's `extra-traits`; the
//! examples' dev-dependencies: the reference model, serde's `alloc`), and a
//! newcomer who followed every journey compiled aacmm-core four times.

use std::collections::{BTreeMap, BTreeSet};

/// The feature sets `cargo tree` resolves for each crate (`name vX.Y.Z`)
/// in the build of `args`; a crate built twice (for the host and the
/// target) has two.
fn features(args: &[&str]) -> BTreeMap<String, BTreeSet<String>> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let o = std::process::Command::new(cargo)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["tree", "--locked", "--prefix", "none", "-f", "{p} [{f}]"])
        .args(args)
        .output()
        .expect("cargo runs");
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "cargo tree {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let mut found: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for line in text.lines() {
        let (Some(open), Some(close)) = (line.rfind(" ["), line.rfind(']')) else {
            continue;
        };
        let mut words = line.split_whitespace();
        let crate_id = match (words.next(), words.next()) {
            (Some(name), Some(version)) => format!("{name} {version}"),
            _ => continue,
        };
        found
            .entry(crate_id)
            .or_default()
            .insert(line[open + 2..close].to_string());
    }
    found
}

#[test]
fn every_release_build_shares_one_build_of_the_core() {
    let core: BTreeSet<String> = features(&["-p", "aacmm-core", "-e", "normal,build"])
        .into_keys()
        .collect();
    assert!(core.iter().any(|c| c.starts_with("nalgebra ")), "{core:?}");
    let builds = [
        (
            "the command line",
            vec!["-p", "aacmm", "-e", "normal,build"],
        ),
        (
            "the C library",
            vec!["-p", "aacmm-capi", "-e", "normal,build"],
        ),
        (
            "the Python package",
            vec!["-p", "aacmm-python", "-e", "normal,build"],
        ),
        (
            "the examples",
            vec!["-p", "aacmm", "-e", "normal,build,dev"],
        ),
    ];
    let resolved: Vec<(&str, BTreeMap<String, BTreeSet<String>>)> = (builds.iter())
        .map(|(name, args)| (*name, features(args)))
        .collect();
    let (first, reference) = &resolved[0];
    let mut differ = Vec::new();
    for c in &core {
        for (name, build) in &resolved[1..] {
            if build.get(c) != reference.get(c) {
                differ.push(format!(
                    "{c}: {first} {:?}, {name} {:?}",
                    reference.get(c),
                    build.get(c)
                ));
            }
        }
    }
    assert!(
        differ.is_empty(),
        "crates aacmm-core is built from get other features in another release build, so \
         cargo builds aacmm-core again for it (ask for them in core/Cargo.toml or, for \
         proc-macros' dependencies, dh-macros/Cargo.toml):\n{}",
        differ.join("\n")
    );
}
