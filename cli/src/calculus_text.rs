//! Configurations classified from stdin, for the ternary and binary calculus commands. Below
//! both command modules.

use std::io::{BufRead, Read, Write};

use anyhow::{Context, Result};

/// A line as quoted in an error: at most 60 characters (a 2 MB line is not echoed whole).
fn shown(text: &str) -> String {
    match text.char_indices().nth(60) {
        None => text.to_owned(),
        Some((cut, _)) => format!("{}… ({} bytes)", &text[..cut], text.len()),
    }
}

/// Reads configurations from stdin, one per line (blank lines and `#` comments skipped), and
/// prints one label per line — only once every line classified, so a bad line leaves no
/// partial output.
pub fn classify_stdin(
    out: &mut impl Write,
    label_of: impl Fn(&[f64]) -> Result<String, qsr_core::QsrError>,
) -> Result<()> {
    let stdin = std::io::stdin();
    let mut labels = String::new();
    // Capped like every input file: an endless line (`< /dev/zero`) ends instead of growing.
    let capped = stdin.lock().take(qsr_core::text_file::MAX_INPUT_BYTES);
    for (i, line) in capped.lines().enumerate() {
        let lineno = i + 1;
        let line = line.with_context(|| format!("reading stdin line {lineno}"))?;
        let text = line.trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let row: Vec<f64> = text
            .split_whitespace()
            .map(str::parse::<f64>)
            .collect::<Result<_, _>>()
            .with_context(|| {
                format!("line {lineno}: `{}` is not a list of numbers", shown(text))
            })?;
        let label = label_of(&row).with_context(|| format!("line {lineno}: `{}`", shown(text)))?;
        labels.push_str(&label);
        labels.push('\n');
    }
    out.write_all(labels.as_bytes())?;
    Ok(())
}
