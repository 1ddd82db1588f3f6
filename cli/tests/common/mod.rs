//! Running the `qrm` binary as a user does: arguments and stdin in; stdout, stderr, exit code
//! out.
#![allow(dead_code, clippy::unwrap_used)]

use std::ffi::OsStr;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

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

/// What one watched run of `qrm` did.
pub struct Run {
    /// Exit code (`None`: killed by a signal, e.g. past its time limit).
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
    /// Wall time to exit (or to the kill).
    pub took: Duration,
    /// Killed for running past its limit.
    pub timed_out: bool,
    /// Peak resident memory, polled from `/proc` (`VmHWM` is the kernel's own high-water
    /// mark, so a poll between peaks still sees the peak); `None` where there is no `/proc`.
    pub peak_bytes: Option<u64>,
}

/// Runs `qrm` with `args`, extra environment `env` and `stdin`, killing it past `limit`, and
/// watching its peak memory: the one runner of the tests that hold the binary to a time or a
/// memory bound (flags walked to extremes, bad inputs, network sizes).
pub fn run_within<A: AsRef<OsStr>>(
    args: &[A],
    env: &[(&str, &str)],
    stdin: &[u8],
    limit: Duration,
) -> Run {
    let t0 = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_qrm"))
        .args(args)
        .envs(env.iter().copied())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut pipe = child.stdin.take().unwrap();
    let input = stdin.to_vec();
    let writer = std::thread::spawn(move || {
        let _ = pipe.write_all(&input);
    });
    let drain = |mut r: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut b = Vec::new();
            let _ = r.read_to_end(&mut b);
            String::from_utf8_lossy(&b).into_owned()
        })
    };
    let out = drain(Box::new(child.stdout.take().unwrap()));
    let err = drain(Box::new(child.stderr.take().unwrap()));
    let status_file = format!("/proc/{}/status", child.id());
    let (mut peak, mut timed_out) = (None, false);
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if let Some(kb) = std::fs::read_to_string(&status_file).ok().and_then(|text| {
            text.lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        }) {
            peak = Some(peak.unwrap_or(0).max(kb * 1024));
        }
        if t0.elapsed() > limit {
            timed_out = true;
            let _ = child.kill();
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    let took = t0.elapsed();
    let _ = writer.join();
    Run {
        code: status.code(),
        stdout: out.join().unwrap(),
        stderr: err.join().unwrap(),
        took,
        timed_out,
        peak_bytes: peak,
    }
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
