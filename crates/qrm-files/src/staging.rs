//! An output directory, whole or not at all.

use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

use crate::{FileError, Result};

/// Staging directories of this process not yet committed: what [`remove_unfinished`] removes
/// when the process is stopped.
fn active() -> &'static Mutex<Vec<PathBuf>> {
    static ACTIVE: OnceLock<Mutex<Vec<PathBuf>>> = OnceLock::new();
    ACTIVE.get_or_init(Default::default)
}

/// Removes the staging directories of every [`Staging`] of this process not yet committed, and
/// returns them: what an interrupt handler calls before exiting (a `Drop` does not run then).
#[must_use = "say whether anything was removed"]
pub fn remove_unfinished() -> Vec<PathBuf> {
    let dirs: Vec<PathBuf> = active().lock().map(|l| l.clone()).unwrap_or_default();
    for d in &dirs {
        let _ = std::fs::remove_dir_all(d);
    }
    dirs
}

/// The process id a staging directory's name carries (`.<name>.partial-<pid>`), if it is one.
fn staging_pid(file_name: &str) -> Option<u32> {
    let (head, pid) = file_name.rsplit_once(".partial-")?;
    (head.starts_with('.') && head.len() > 1 && !pid.is_empty())
        .then(|| pid.parse().ok())
        .flatten()
}

/// Whether process `pid` is running on this machine: `None` where that cannot be told without
/// unsafe code (no `/proc`), and then nothing is removed.
fn process_is_alive(pid: u32) -> Option<bool> {
    let proc = Path::new("/proc");
    proc.join("self")
        .exists()
        .then(|| proc.join(pid.to_string()).exists())
}

/// Removes the staging directories in `dir` left by processes that no longer run (killed by
/// SIGKILL, an abort or a power cut, where no handler runs) and returns them.
fn remove_stale(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let own = std::process::id();
    let mut removed = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(staging_pid) else {
            continue;
        };
        let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
        if pid != own && is_dir && process_is_alive(pid) == Some(false) {
            let path = entry.path();
            if std::fs::remove_dir_all(&path).is_ok() {
                removed.push(path);
            }
        }
    }
    removed.sort();
    removed
}

/// An output directory written whole or not at all: results go into a hidden sibling
/// `.<name>.partial-<pid>` and are moved into `<name>` by [`Staging::commit`] once everything
/// succeeded. Dropped without a commit (an error, a panic) or removed by
/// [`remove_unfinished`], the staging directory is gone: nothing is left that a user could
/// take for a result. Files already in `<name>` from earlier runs stay unless this run writes
/// the same names.
///
/// A process stopped where no handler runs (SIGKILL, an abort) leaves its staging directory;
/// the next [`Staging`] made in the same directory removes every such directory whose process
/// no longer runs ([`Staging::removed_stale`] lists them, for the caller to say so). Where
/// running processes cannot be told (no `/proc`), none is removed.
#[derive(Debug)]
pub struct Staging {
    target: PathBuf,
    staging: PathBuf,
    committed: bool,
    stale: Vec<PathBuf>,
}

impl Staging {
    /// Creates the staging directory beside `out`.
    ///
    /// # Errors
    /// [`FileError::Path`] when `out` is a file or has no name; [`FileError::Io`] when the
    /// directories cannot be made.
    pub fn new(out: &Path) -> Result<Self> {
        let parent = match out.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let name = out.file_name().ok_or_else(|| {
            FileError::Path(format!("--out {} does not name a directory", out.display()))
        })?;
        if out.is_file() {
            return Err(FileError::Path(format!(
                "--out {} is a file, not a directory",
                out.display()
            )));
        }
        std::fs::create_dir_all(&parent).map_err(FileError::io("creating", &parent))?;
        let stale = remove_stale(&parent);
        let staging = parent.join(format!(
            ".{}.partial-{}",
            name.to_string_lossy(),
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&staging);
        std::fs::create_dir_all(&staging).map_err(FileError::io("creating", &staging))?;
        if let Ok(mut list) = active().lock() {
            list.push(staging.clone());
        }
        Ok(Self {
            target: out.to_path_buf(),
            staging,
            committed: false,
            stale,
        })
    }

    /// The staging directories of dead processes that [`Staging::new`] removed beside this one.
    #[must_use]
    pub fn removed_stale(&self) -> &[PathBuf] {
        &self.stale
    }

    /// Where to write.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// Moves every file and folder written into the output directory (replacing ones of the
    /// same name) and removes the staging directory.
    ///
    /// # Errors
    /// [`FileError::Io`] naming the entry that could not be moved.
    pub fn commit(mut self) -> Result<()> {
        std::fs::create_dir_all(&self.target).map_err(FileError::io("creating", &self.target))?;
        let entries =
            std::fs::read_dir(&self.staging).map_err(FileError::io("reading", &self.staging))?;
        for entry in entries {
            let entry = entry.map_err(FileError::io("reading", &self.staging))?;
            let to = self.target.join(entry.file_name());
            if to.is_dir() && entry.path().is_dir() {
                std::fs::remove_dir_all(&to).map_err(FileError::io("replacing", &to))?;
            }
            std::fs::rename(entry.path(), &to)
                .map_err(FileError::io("moving the result into", &to))?;
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

/// One file filled by a writer that wants a path (an MCAP log), moved to its name by
/// [`StagedFile::commit`]: whole or not at all, and removed on Ctrl-C like a [`Staging`]
/// directory (it is written inside one, beside the target).
#[derive(Debug)]
pub struct StagedFile {
    stage: Staging,
    file: PathBuf,
    target: PathBuf,
}

impl StagedFile {
    /// Stages `path`.
    ///
    /// # Errors
    /// [`FileError::Path`] when `path` is a directory or names none; as [`Staging::new`].
    pub fn new(path: &Path) -> Result<Self> {
        let name = path.file_name().filter(|_| !path.is_dir()).ok_or_else(|| {
            FileError::Path(format!("{} is a directory, not a file", path.display()))
        })?;
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let stage = Staging::new(&dir.join(format!(".{}.file", name.to_string_lossy())))?;
        Ok(Self {
            file: stage.path().join(name),
            stage,
            target: path.to_path_buf(),
        })
    }

    /// Where the writer writes.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.file
    }

    /// As [`Staging::removed_stale`].
    #[must_use]
    pub fn removed_stale(&self) -> &[PathBuf] {
        self.stage.removed_stale()
    }

    /// Moves the file to its name (replacing what was there).
    ///
    /// # Errors
    /// [`FileError::Io`] naming the target.
    pub fn commit(self) -> Result<()> {
        std::fs::rename(&self.file, &self.target)
            .map_err(FileError::io("moving the result into", &self.target))?;
        drop(self.stage);
        Ok(())
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests: a panic is the failure report
mod tests {
    use super::*;

    #[test]
    fn a_dropped_stage_leaves_nothing_and_a_committed_one_replaces_only_its_names() {
        let root = std::env::temp_dir().join(format!("qrm-files-stage-{}", std::process::id()));
        let out = root.join("out");
        std::fs::create_dir_all(&out).unwrap();
        std::fs::write(out.join("old.txt"), "old").unwrap();
        std::fs::write(out.join("a.txt"), "before").unwrap();
        {
            let s = Staging::new(&out).unwrap();
            std::fs::write(s.path().join("a.txt"), "half").unwrap();
        } // an error: dropped without a commit
        assert_eq!(
            std::fs::read_to_string(out.join("a.txt")).unwrap(),
            "before"
        );
        let s = Staging::new(&out).unwrap();
        std::fs::write(s.path().join("a.txt"), "after").unwrap();
        let staged = s.path().to_path_buf();
        s.commit().unwrap();
        assert_eq!(std::fs::read_to_string(out.join("a.txt")).unwrap(), "after");
        assert_eq!(std::fs::read_to_string(out.join("old.txt")).unwrap(), "old");
        assert!(!staged.exists());
        let names: Vec<_> = std::fs::read_dir(&root).unwrap().collect();
        assert_eq!(names.len(), 1, "only `out` is left beside it");
        std::fs::remove_dir_all(&root).unwrap();
    }

    /// Issue 39: a run killed by SIGKILL left `.out.partial-PID` for ever (the name carries the
    /// PID, so no later run matched it).
    #[test]
    fn regression_a_dead_processs_staging_directory_is_removed_by_the_next_run_beside_it() {
        let root = std::env::temp_dir().join(format!("qrm-files-stale-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(&root).unwrap();
        // A process that has exited: its PID no longer runs.
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let stale = root.join(format!(".run.partial-{dead}"));
        std::fs::create_dir_all(stale.join("figures")).unwrap();
        std::fs::write(stale.join("figures/half.svg"), "<svg").unwrap();
        // One of a running process (this one's parent), and things that only look alike.
        let parent = std::os::unix::process::parent_id();
        let live = root.join(format!(".other.partial-{parent}"));
        std::fs::create_dir_all(&live).unwrap();
        let file = root.join(format!(".notes.partial-{dead}"));
        std::fs::write(&file, "a file, not a staging directory").unwrap();
        let user = root.join(format!("run.partial-{dead}"));
        std::fs::create_dir_all(&user).unwrap();

        let s = Staging::new(&root.join("next")).unwrap();
        if process_is_alive(dead).is_some() {
            assert_eq!(s.removed_stale(), std::slice::from_ref(&stale));
            assert!(!stale.exists());
        }
        assert!(live.exists() && file.exists() && user.exists());
        drop(s);
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn staging_names_are_told_apart_from_others() {
        assert_eq!(staging_pid(".run.partial-42"), Some(42));
        assert_eq!(staging_pid("..x.file.partial-7"), Some(7));
        assert_eq!(staging_pid("run.partial-42"), None);
        assert_eq!(staging_pid(".partial-42"), None);
        assert_eq!(staging_pid(".run.partial-"), None);
        assert_eq!(staging_pid(".run.partial-4x"), None);
    }

    #[test]
    fn unfinished_stages_are_removed_on_request() {
        let out = std::env::temp_dir().join(format!("qrm-files-int-{}", std::process::id()));
        let s = Staging::new(&out).unwrap();
        let staged = s.path().to_path_buf();
        assert!(remove_unfinished().contains(&staged));
        assert!(!staged.exists());
        drop(s);
        assert!(!out.exists());
    }

    #[test]
    fn a_staged_file_appears_whole_on_commit_and_not_at_all_when_dropped() {
        let root = std::env::temp_dir().join(format!("qrm-files-file-{}", std::process::id()));
        std::fs::create_dir_all(&root).unwrap();
        let target = root.join("run.mcap");
        {
            let f = StagedFile::new(&target).unwrap();
            std::fs::write(f.path(), "half").unwrap();
        } // an error: dropped without a commit
        assert!(!target.exists());
        let f = StagedFile::new(&target).unwrap();
        std::fs::write(f.path(), "whole").unwrap();
        f.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "whole");
        // nothing but the file is left beside it
        let names: Vec<_> = std::fs::read_dir(&root)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["run.mcap"]);
        assert!(matches!(StagedFile::new(&root), Err(FileError::Path(_))));
        std::fs::remove_dir_all(&root).unwrap();
    }
}
