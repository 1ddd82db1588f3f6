#![no_main]
//! `cargo +nightly fuzz run spec_json` — the body is `qrm_tests::fuzz::spec_json` (also run over the
//! corpus by `tests/tests/fuzz_corpus.rs`).
libfuzzer_sys::fuzz_target!(|data: &[u8]| qrm_tests::fuzz::spec_json(data));
