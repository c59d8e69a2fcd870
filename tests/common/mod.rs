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
