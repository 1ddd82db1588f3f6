#![no_main]
//! `cargo +nightly fuzz run study_config` — the body is `qrm_tests::fuzz::study_config` (also
//! run over the corpus by `tests/tests/fuzz_corpus.rs`).
libfuzzer_sys::fuzz_target!(|data: &[u8]| qrm_tests::fuzz::study_config(data));
