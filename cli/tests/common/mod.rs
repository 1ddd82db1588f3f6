//! Running the `qrm` binary as a user does: arguments and stdin in; stdout, stderr, exit code
//! out.
#![allow(dead_code, clippy::unwrap_used)]

use std::io::Write;
use std::process::{Command, Output, Stdio};

/// Runs `qrm` with `args`, feeding `stdin`.
pub fn qrm(args: &[&str], stdin: &str) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_qrm"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(stdin.as_bytes())
        .unwrap();
    child.wait_with_output().unwrap()
}

/// Runs `qrm` and returns its stdout, failing the test (with stderr) when it fails.
pub fn ok(args: &[&str], stdin: &str) -> String {
    let out = qrm(args, stdin);
    assert!(
        out.status.success(),
        "qrm {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}
