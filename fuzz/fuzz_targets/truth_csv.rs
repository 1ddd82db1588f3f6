#![no_main]
//! `cargo +nightly fuzz run truth_csv` — the body is `qrm_tests::fuzz::truth_csv` (also run over the
//! corpus by `tests/tests/fuzz_corpus.rs`).
libfuzzer_sys::fuzz_target!(|data: &[u8]| qrm_tests::fuzz::truth_csv(data));
