#![no_main]
//! `cargo +nightly fuzz run g2o` — the body is `qrm_tests::fuzz::g2o` (also run over the
//! corpus by `tests/tests/fuzz_corpus.rs`).
libfuzzer_sys::fuzz_target!(|data: &[u8]| qrm_tests::fuzz::g2o(data));
