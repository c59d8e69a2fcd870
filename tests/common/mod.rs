//! Shared by the integration tests: `#[macro_use] mod common;` at the top of a test file.

/// `#[test]` natively, `#[wasm_bindgen_test]` on wasm32: each test body is written once and runs natively
/// (`cargo test`) and in wasm (Node and headless Chromium, see scripts/test.sh).
#[macro_export]
macro_rules! dual_test {
    ($($(#[$meta:meta])* fn $name:ident() $body:block)*) => {$(
        $(#[$meta])*
        #[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
        #[cfg_attr(not(target_arch = "wasm32"), test)]
        fn $name() $body
    )*};
}

/// `rel` inside the shared data folder (`POSEMFA_SHARED`, default `../shared` next to the crate), or `None` when
/// it is absent. Then the test `test` must return at once: this prints the line
/// `SKIPPED(needs ../shared): TEST (...)`, which scripts/test.sh counts as skipped instead of passed. With
/// `CI=true` an absent folder fails the test instead (the data must be there in CI).
///
/// The line goes straight to the process's stderr, past libtest's capture of `println!` / `eprintln!`, so it is
/// in the log even when the test passes.
/// The Blender fixtures' source population and comparisons (tests/formats.rs, tests/fbx_usd.rs).
#[allow(dead_code)]
pub mod blender;

/// A .glb taken apart and put together (tests/rig_glb_input.rs, tests/hostile_inputs.rs).
#[allow(dead_code)]
pub mod glb;

#[allow(dead_code)]
pub fn shared_dir(rel: &str, test: &str) -> Option<std::path::PathBuf> {
    use std::io::Write;
    let root = std::env::var_os("POSEMFA_SHARED")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    let dir = root.join(rel);
    if dir.is_dir() {
        return Some(dir);
    }
    let why = format!("{} is absent (POSEMFA_SHARED or ../shared)", dir.display());
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("{test}: {why}, and CI=true: the data tests must run in CI");
    }
    let _ = writeln!(std::io::stderr().lock(), "SKIPPED(needs ../shared): {test} ({why})");
    None
}
