#![no_main]
//! `cargo +nightly fuzz run world` — the body is `qrm_tests::fuzz::world` (also run over the
//! corpus by `tests/tests/fuzz_corpus.rs`).
libfuzzer_sys::fuzz_target!(|data: &[u8]| qrm_tests::fuzz::world(data));
