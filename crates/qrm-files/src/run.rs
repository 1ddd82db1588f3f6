//! A study run's directory.

use std::path::{Path, PathBuf};

use studies::Ran;

use crate::{CsvTable, FileError, Result, write_atomic};

/// Writes a picture as `stem.svg` and `stem.png`, each atomically, and returns the two paths.
///
/// # Errors
/// As [`write_atomic`].
pub fn write_picture(stem: &Path, picture: &qrm_plot::Picture) -> Result<Vec<PathBuf>> {
    let svg = stem.with_extension("svg");
    let png = stem.with_extension("png");
    write_atomic(&svg, picture.svg.as_bytes())?;
    write_atomic(&png, &picture.png)?;
    Ok(vec![svg, png])
}

/// The files of a study run in `dir`: each table as CSV, each figure (SVG and PNG), each
/// attachment, the study's output file, report.md (with the run time and thread count when
/// `timing` gives them: an output holds no timings, the report of a run measured here may)
/// and config.toml. A name with a `/` (`hallway/cv`) goes into that subdirectory.
///
/// # Errors
/// [`FileError::Io`] naming the file; [`FileError::Plot`] for a figure that cannot be drawn.
pub fn write_run(dir: &Path, ran: &Ran, timing: Option<(f64, usize)>) -> Result<()> {
    let report = &ran.report;
    let place = |name: &str| -> Result<PathBuf> {
        let path = dir.join(name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(FileError::io("creating", parent))?;
        }
        Ok(path)
    };
    for t in &report.tables {
        let (header, rows) = t.csv_records();
        let mut csv = CsvTable::new(header)?;
        for r in rows {
            csv.row(r)?;
        }
        csv.write(&place(&format!("{}.csv", t.name))?)?;
    }
    for f in &report.figures {
        write_picture(&place(&f.name)?, &qrm_plot::figure(f)?)?;
    }
    for a in &report.attachments {
        write_atomic(&place(&a.name)?, a.bytes())?;
    }
    if let Some((name, text)) = &ran.output_file {
        write_atomic(&dir.join(name), text.as_bytes())?;
    }
    let mut md = report.to_markdown();
    if let Some((seconds, threads)) = timing {
        md.push_str(&format!("\nRun in {seconds:.1} s on {threads} threads.\n"));
    }
    write_atomic(&dir.join("report.md"), md.as_bytes())?;
    write_atomic(
        &dir.join("config.toml"),
        studies::config::to_toml(&ran.config)?.as_bytes(),
    )?;
    Ok(())
}
