//! Cross-crate tests of qrm live in `tests/tests/`; this library only holds helpers they
//! share: where the workspace, the `qrm` binary and `shared/` are.

use std::path::PathBuf;

/// The workspace root.
#[must_use]
pub fn workspace_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(PathBuf::from)
        .unwrap_or_default()
}

/// `shared/` beside the checkout (oracles, data), if present.
#[must_use]
pub fn shared_dir() -> Option<PathBuf> {
    let dir = workspace_root().parent()?.join("shared");
    dir.is_dir().then_some(dir)
}
