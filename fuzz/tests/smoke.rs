//! The fuzz targets for a few seconds, as part of `cargo test --workspace`:
//! `AACMM_FUZZ_READER_CASES` and `AACMM_FUZZ_CALIBRATE_CASES` make the run
//! longer (the binary `aacmm-fuzz` is the tool for long runs).

use aacmm_fuzz::{Reader, cases_from_env, check_reader, run_degenerate, run_readers};

#[test]
fn readers_survive_mutated_files() {
    let s = run_readers(cases_from_env("AACMM_FUZZ_READER_CASES", 3000), 1, 1000);
    assert!(s.violations.is_empty(), "{:#?}", s.violations);
    assert!(s.cases >= 3000);
    // The mutations reach both outcomes of every reader.
    for r in Reader::ALL {
        for outcome in ["ok", "error at a line"] {
            let key = format!("{r:?}: {outcome}");
            assert!(
                s.outcomes.contains_key(&key),
                "no `{key}` in {:?}",
                s.outcomes
            );
        }
    }
}

#[test]
fn unmutated_seeds_are_accepted() {
    for r in Reader::ALL {
        for seed in r.seeds() {
            assert_eq!(
                check_reader(r, seed.as_bytes()),
                Ok("ok".to_string()),
                "{r:?}: {seed}"
            );
        }
    }
}

#[test]
fn degenerate_calibrations_do_not_panic() {
    let s = run_degenerate(cases_from_env("AACMM_FUZZ_CALIBRATE_CASES", 12), 1, 12);
    assert!(s.violations.is_empty(), "{:#?}", s.violations);
}
