//! Writing result files: whole or not at all.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename, so a
/// failure or a kill never leaves a half-written file under the final name.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let name = path
        .file_name()
        .with_context(|| format!("{} is not a file path", path.display()))?;
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
        anyhow::Error::new(e).context(format!("writing {}", path.display()))
    })
}

/// Staging directories of this process not yet committed: removed when Ctrl-C stops it.
fn active() -> &'static std::sync::Mutex<Vec<std::path::PathBuf>> {
    static ACTIVE: std::sync::OnceLock<std::sync::Mutex<Vec<std::path::PathBuf>>> =
        std::sync::OnceLock::new();
    ACTIVE.get_or_init(Default::default)
}

/// An output directory written whole or not at all: results go into a hidden sibling
/// `.<name>.partial-<pid>` and are moved into `<name>` by [`Staging::commit`] once everything
/// succeeded. Dropped without a commit (an error, a panic) or stopped by Ctrl-C, the staging
/// directory is removed: nothing is left that a user could take for a result. Files already in
/// `<name>` from earlier runs stay unless this run writes the same names.
pub struct Staging {
    target: std::path::PathBuf,
    staging: std::path::PathBuf,
    committed: bool,
}

impl Staging {
    /// Creates the staging directory beside `out`.
    pub fn new(out: &Path) -> Result<Self> {
        let parent = match out.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => std::path::PathBuf::from("."),
        };
        let name = out
            .file_name()
            .with_context(|| format!("--out {} does not name a directory", out.display()))?;
        if out.is_file() {
            anyhow::bail!("--out {} is a file, not a directory", out.display());
        }
        std::fs::create_dir_all(&parent)
            .with_context(|| format!("creating {}", parent.display()))?;
        let staging = parent.join(format!(
            ".{}.partial-{}",
            name.to_string_lossy(),
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&staging);
        std::fs::create_dir_all(&staging)
            .with_context(|| format!("creating {}", staging.display()))?;
        if let Ok(mut list) = active().lock() {
            list.push(staging.clone());
        }
        Ok(Self {
            target: out.to_path_buf(),
            staging,
            committed: false,
        })
    }

    /// Where to write.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// Moves every file and folder written into the output directory (replacing ones of the
    /// same name) and removes the staging directory.
    pub fn commit(mut self) -> Result<()> {
        std::fs::create_dir_all(&self.target)
            .with_context(|| format!("creating {}", self.target.display()))?;
        let entries = std::fs::read_dir(&self.staging)
            .with_context(|| format!("reading {}", self.staging.display()))?;
        for entry in entries {
            let entry = entry.with_context(|| format!("reading {}", self.staging.display()))?;
            let to = self.target.join(entry.file_name());
            if to.is_dir() && entry.path().is_dir() {
                std::fs::remove_dir_all(&to)
                    .with_context(|| format!("replacing {}", to.display()))?;
            }
            std::fs::rename(entry.path(), &to)
                .with_context(|| format!("moving the result into {}", to.display()))?;
        }
        self.committed = true;
        let _ = std::fs::remove_dir_all(&self.staging);
        forget(&self.staging);
        Ok(())
    }
}

fn forget(staging: &Path) {
    if let Ok(mut list) = active().lock() {
        list.retain(|p| p != staging);
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.staging);
        }
        forget(&self.staging);
    }
}

/// Ctrl-C: say so, remove the staging directories of unfinished outputs, exit 130 (the shell
/// convention for SIGINT) — within a second, whatever the computation is doing.
pub fn install_interrupt_handler() {
    let _ = ctrlc::set_handler(|| {
        let dirs: Vec<std::path::PathBuf> = active().lock().map(|l| l.clone()).unwrap_or_default();
        for d in &dirs {
            let _ = std::fs::remove_dir_all(d);
        }
        if dirs.is_empty() {
            eprintln!("interrupted");
        } else {
            eprintln!("interrupted: the unfinished output was removed, nothing was written");
        }
        std::process::exit(130);
    });
}

/// A CSV table written through the `csv` crate, which quotes a field holding a comma, a quote
/// or a line break: a calculus or state label from a spec file may hold any of them, and
/// joined by hand with `,` such a label shifted every column after it (issue 19). Every row
/// must have the header's number of fields.
pub struct CsvTable(csv::Writer<Vec<u8>>);

impl CsvTable {
    /// A table with this header.
    ///
    /// # Errors
    /// Never for an in-memory table; kept for the csv crate's signature.
    pub fn new<I, S>(header: I) -> Result<Self>
    where
        I: IntoIterator<Item = S>,
        S: AsRef<[u8]>,
    {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(header).context("writing a CSV header")?;
        Ok(Self(w))
    }

    /// Appends a row.
    ///
    /// # Errors
    /// A row whose length differs from the header's.
    pub fn row<I, S>(&mut self, fields: I) -> Result<()>
    where
        I: IntoIterator<Item = S>,
        S: AsRef<[u8]>,
    {
        self.0.write_record(fields).context("writing a CSV row")
    }

    /// The table's text.
    ///
    /// # Errors
    /// As the csv crate's flush (not for memory).
    pub fn into_bytes(self) -> Result<Vec<u8>> {
        self.0
            .into_inner()
            .map_err(|e| anyhow::anyhow!("finishing a CSV table: {}", e.error()))
    }

    /// Writes the table to `path` atomically ([`write_atomic`]).
    ///
    /// # Errors
    /// As [`write_atomic`].
    pub fn write(self, path: &Path) -> Result<()> {
        write_atomic(path, &self.into_bytes()?)
    }
}

/// Writes a picture as `stem.svg` and `stem.png`, each atomically.
pub fn write_picture(stem: &Path, picture: &qrm_plot::Picture) -> Result<Vec<PathBuf>> {
    let svg = stem.with_extension("svg");
    let png = stem.with_extension("png");
    write_atomic(&svg, picture.svg.as_bytes())?;
    write_atomic(&png, &picture.png)?;
    Ok(vec![svg, png])
}
