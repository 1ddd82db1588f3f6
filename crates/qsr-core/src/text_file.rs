//! Reading an input file as text, bounded: every file qrm reads goes through here, so a
//! device (`/dev/zero`), a directory or a runaway file is an `io::Error` naming the cause,
//! never an endless read or an allocation abort (issue 17).

use std::io::Read;
use std::path::Path;

/// The largest input file read (1 GiB: MRCLAM's largest file is tens of MB).
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// Reads `path` as UTF-8 text of at most `max_bytes` bytes.
///
/// # Errors
/// `io::Error` when the file cannot be opened, is a directory or a device, is larger than
/// `max_bytes`, or is not UTF-8.
pub fn read_text(path: &Path, max_bytes: u64) -> std::io::Result<String> {
    String::from_utf8(read_bytes(path, max_bytes)?).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        )
    })
}

/// Reads a stream (stdin) as UTF-8 text of at most `max_bytes` bytes: an endless stream
/// (`< /dev/zero`) ends with an error instead of growing.
///
/// # Errors
/// `io::Error` when the stream fails, is larger than `max_bytes`, or is not UTF-8.
pub fn read_stream(stream: impl Read, max_bytes: u64) -> std::io::Result<String> {
    let mut text = String::new();
    stream
        .take(max_bytes.saturating_add(1))
        .read_to_string(&mut text)?;
    if text.len() as u64 > max_bytes {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("more than {max_bytes} bytes"),
        ));
    }
    Ok(text)
}

/// Reads `path` as bytes (a binary log) of at most `max_bytes` bytes.
///
/// # Errors
/// As [`read_text`], without the UTF-8 check.
pub fn read_bytes(path: &Path, max_bytes: u64) -> std::io::Result<Vec<u8>> {
    use std::io::{Error, ErrorKind};
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if meta.is_dir() {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            "is a directory, not a file",
        ));
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_char_device() || t.is_block_device() {
            return Err(Error::new(
                ErrorKind::InvalidInput,
                "is a device, not a file",
            ));
        }
    }
    let mut bytes = Vec::new();
    file.take(max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(Error::new(
            ErrorKind::InvalidData,
            format!("larger than {max_bytes} bytes, the most an input file may be"),
        ));
    }
    Ok(bytes)
}

/// A value quoted in an error message: whole when short, else its first 60 characters and
/// how long it was (a 2 MB name must not become 2 MB of stderr).
#[must_use]
pub fn shorten(value: &str) -> String {
    const KEEP: usize = 60;
    match value.char_indices().nth(KEEP) {
        None => value.to_owned(),
        Some((cut, _)) => format!("{}… ({} bytes)", &value[..cut], value.len()),
    }
}

/// Writes `bytes` to `path` whole or not at all: beside it under a name of this process, then
/// renamed over it (a reader never sees half a file); makes the parent directory.
///
/// # Errors
/// The I/O error of creating, writing or renaming.
pub fn write_whole(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent)?;
    }
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(format!(".tmp{}", std::process::id()));
    let tmp = std::path::PathBuf::from(tmp);
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}
