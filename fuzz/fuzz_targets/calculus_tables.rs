#![no_main]
//! `cargo +nightly fuzz run calculus_tables` — the body is `qrm_tests::fuzz::calculus_tables` (also run over the
//! corpus by `tests/tests/fuzz_corpus.rs`).
libfuzzer_sys::fuzz_target!(|data: &[u8]| qrm_tests::fuzz::calculus_tables(data));
