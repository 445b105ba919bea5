//! The committed header `include/aacmm.h` is what cbindgen generates from
//! the sources now. `AACMM_BLESS=1 cargo test -p aacmm-capi --test header`
//! rewrites it after an intended change of the API.

use std::path::Path;

fn generate() -> String {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("cbindgen.toml");
    // The crate root: cbindgen follows its `mod` declarations. Parsing
    // sources (not `cargo metadata`) keeps the test offline and fast.
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(dir.join("src/lib.rs"))
        .generate()
        .expect("cbindgen generates the header");
    let mut out = Vec::new();
    bindings.write(&mut out);
    String::from_utf8(out).expect("the header is UTF-8")
}

#[test]
fn header_is_current() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("include/aacmm.h");
    let generated = generate();
    if std::env::var_os("AACMM_BLESS").is_some() {
        std::fs::write(&path, &generated).expect("write include/aacmm.h");
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed != generated {
        let line = committed
            .lines()
            .zip(generated.lines())
            .position(|(a, b)| a != b)
            .unwrap_or_else(|| committed.lines().count().min(generated.lines().count()))
            + 1;
        panic!(
            "capi/include/aacmm.h is stale (first difference at line {line}); regenerate it \
             with `AACMM_BLESS=1 cargo test -p aacmm-capi --test header` and commit it"
        );
    }
}
