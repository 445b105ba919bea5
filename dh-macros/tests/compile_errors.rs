//! Mistakes in a `dh_chain!` invocation are compile errors pointing at the
//! offending token, not panics of the macro.

#[test]
fn user_errors_carry_spans() {
    let t = trybuild::TestCases::new();
    t.compile_fail("tests/ui/*.rs");
}
