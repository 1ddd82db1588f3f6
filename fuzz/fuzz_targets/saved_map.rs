#![no_main]
//! `cargo +nightly fuzz run saved_map` — the body is `qrm_tests::fuzz::saved_map` (also run over the
//! corpus by `tests/tests/fuzz_corpus.rs`).
libfuzzer_sys::fuzz_target!(|data: &[u8]| qrm_tests::fuzz::saved_map(data));
