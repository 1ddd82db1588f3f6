#![no_main]
//! `cargo +nightly fuzz run classify_row` — the body is `qrm_tests::fuzz::classify_row` (also run over the
//! corpus by `tests/tests/fuzz_corpus.rs`).
libfuzzer_sys::fuzz_target!(|data: &[u8]| qrm_tests::fuzz::classify_row(data));
