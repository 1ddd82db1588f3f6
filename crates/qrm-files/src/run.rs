//! A study run's directory.

use std::path::{Path, PathBuf};

use studies::{Attachment, Figure, Products, Ran, Table};

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
    write_parts(dir, &report.tables, &report.figures, &report.attachments)?;
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

/// A job's files in `dir` (`qrm sim`'s run, a calibration, a salient region map): each table
/// as CSV, each figure (SVG and PNG), each attachment, as [`write_run`] writes a study's.
///
/// # Errors
/// As [`write_run`].
pub fn write_products(dir: &Path, products: &Products) -> Result<()> {
    write_parts(
        dir,
        &products.tables,
        &products.figures,
        &products.attachments,
    )
}

/// Tables, figures and attachments in `dir`; a name with a `/` goes into that subdirectory.
fn write_parts(
    dir: &Path,
    tables: &[Table],
    figures: &[Figure],
    attachments: &[Attachment],
) -> Result<()> {
    let place = |name: &str| -> Result<PathBuf> {
        let path = dir.join(name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(FileError::io("creating", parent))?;
        }
        Ok(path)
    };
    for t in tables {
        let (header, rows) = t.csv_records();
        let mut csv = CsvTable::new(header)?;
        for r in rows {
            csv.row(r)?;
        }
        csv.write(&place(&format!("{}.csv", t.name))?)?;
    }
    for f in figures {
        write_picture(&place(&f.name)?, &qrm_plot::figure(f)?)?;
    }
    for a in attachments {
        write_atomic(&place(&a.name)?, a.bytes())?;
    }
    Ok(())
}
