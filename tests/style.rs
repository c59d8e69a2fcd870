//! The Rust code is as `cargo fmt` writes it (rustfmt.toml: lines of at most 120 characters), so that a diff
//! shows what changed and not how it was wrapped. A failure lists the files to format: run `cargo fmt`.
#![cfg(not(target_arch = "wasm32"))]

use std::process::Command;

#[test]
fn the_code_is_formatted_by_cargo_fmt() {
    let out = Command::new(env!("CARGO"))
        .args(["fmt", "--all", "--check", "--", "--files-with-diff"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !stderr.contains("not installed") && !stderr.contains("no such command"),
        "rustfmt is missing: `rustup component add rustfmt` (scripts/setup.sh does it)\n{stderr}"
    );
    let files = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "not formatted as `cargo fmt` writes them (run `cargo fmt`):\n{files}{stderr}");
}
