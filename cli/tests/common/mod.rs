//! Running the `qrm` binary as a user does: arguments and stdin in; stdout, stderr, exit code
//! out.
#![allow(dead_code, clippy::unwrap_used)]

use std::io::Write;
use std::path::{Path, PathBuf};
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

/// A fresh empty directory under the temp dir, named for the test and this process.
pub fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("qrm-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
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

/// Builds the Go validator once; `None` (with a message) when Go or shared/ is missing outside CI.
pub fn mcapcheck() -> Option<PathBuf> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/tools/mcapcheck");
    let exe = Path::new(env!("CARGO_TARGET_TMPDIR")).join("mcapcheck");
    let have_go = Command::new("go")
        .arg("version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !src.is_dir() || !have_go {
        assert!(
            std::env::var("CI").is_err(),
            "CI must validate logs with the Go reader (go and shared/tools/mcapcheck needed)"
        );
        eprintln!("SKIPPED: Go MCAP validation (go or shared/tools/mcapcheck not found)");
        return None;
    }
    if !exe.exists() {
        let status = Command::new("go")
            .args(["build", "-o"])
            .arg(&exe)
            .arg(".")
            .current_dir(&src)
            .status()
            .unwrap();
        assert!(status.success(), "building mcapcheck");
    }
    Some(exe)
}
