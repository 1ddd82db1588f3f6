//! One file, whole or not at all.

use std::io::Write;
use std::path::Path;

use crate::{FileError, Result};

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename, so a
/// failure or a kill never leaves a half-written file under the final name.
///
/// # Errors
/// [`FileError::Io`] naming the path; [`FileError::Path`] for a path without a file name.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(FileError::io("creating", &dir))?;
    let name = path
        .file_name()
        .ok_or_else(|| FileError::Path(format!("{} is not a file path", path.display())))?;
    let tmp = dir.join(format!(
        ".{}.tmp{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let write = || -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    };
    write().map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        FileError::io("writing", path)(e)
    })
}
