//! Observation files: our CSV, the UTIAS MRCLAM directory format, and g2o/Victoria Park
//! `LANDMARK` lines. Every loader returns time-ordered [`Scan`]s (one per robot and time
//! stamp) and, where the format has it, the [`GroundTruth`].
//!
//! | format | file(s) | one scan is |
//! |---|---|---|
//! | `csv` | `t,robot,landmark,x,y,cxx,cxy,cyy` (robot frame, m, m²), header required | rows with equal `(t, robot)` |
//! | `mrclam` | a directory with `Barcodes.dat`, `Landmark_Groundtruth.dat`, `Robot{1..5}_Measurement.dat` | measurements of one robot with one time stamp |
//! | `g2o` | lines `LANDMARK pose lm x y cxx cxy cyy` (other tags ignored) | landmarks seen from one pose |
//!
//! MRCLAM measurements are range-bearing; the covariance comes from a [`RangeBearingNoise`]
//! (the dataset gives none). Robot-to-robot sightings (barcodes of subjects 1–5) and unknown
//! barcodes are skipped and counted.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{PqrmError, Result};
use crate::metrics::GroundTruth;
use crate::observation::{LandmarkId, Observation, Scan};

/// Scans plus whatever reference the format carries.
#[derive(Debug, Clone, Default)]
pub struct Dataset {
    /// Scans sorted by time, then robot.
    pub scans: Vec<Scan>,
    /// Surveyed landmark positions, when the format has them.
    pub truth: Option<GroundTruth>,
    /// Lines or measurements skipped on purpose (e.g. robot-to-robot sightings).
    pub skipped: usize,
}

/// Noise model for range-bearing sensors without per-measurement covariances.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RangeBearingNoise {
    /// Range standard deviation (m).
    pub sigma_range: f64,
    /// Bearing standard deviation (rad).
    pub sigma_bearing: f64,
}

impl RangeBearingNoise {
    /// The default for MRCLAM: median absolute errors of ~0.1 m and ~0.006 rad (dataset
    /// README) are the medians of Gaussians with σ = median/0.6745 ≈ 0.15 m and 0.009 rad;
    /// we round the bearing up to 0.01 rad. How wrong this is, is measured by
    /// [`crate::study::noise_check`] against the surveyed inter-landmark distances.
    pub const MRCLAM: Self = Self {
        sigma_range: 0.15,
        sigma_bearing: 0.01,
    };

    /// The largest bearing σ taken (rad): beyond a full turn a bearing is uniform whatever σ.
    pub const MAX_SIGMA_BEARING: f64 = std::f64::consts::TAU;

    /// Checks both σs before any file is read, so a bad flag is blamed, not a line of the
    /// recording (issue 39: `--sigma-range 1e308` was reported as a non-finite covariance
    /// at `Robot1_Measurement.dat:5`, and 2⁶⁴ as coinciding landmarks).
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`] naming the field and its value.
    pub fn validate(&self) -> Result<()> {
        let range_ok = self.sigma_range.is_finite()
            && (0.0..=crate::observation::MAX_DISTANCE_M).contains(&self.sigma_range);
        if !range_ok {
            return Err(PqrmError::InvalidConfig(format!(
                "sigma_range = {:?} m: the range noise must be finite, >= 0 and at most {:e} m",
                self.sigma_range,
                crate::observation::MAX_DISTANCE_M
            )));
        }
        let bearing_ok = self.sigma_bearing.is_finite()
            && (0.0..=Self::MAX_SIGMA_BEARING).contains(&self.sigma_bearing);
        if !bearing_ok {
            return Err(PqrmError::InvalidConfig(format!(
                "sigma_bearing = {:?} rad: the bearing noise must be finite, >= 0 and at most 2π",
                self.sigma_bearing
            )));
        }
        Ok(())
    }
}

fn read(path: &Path) -> Result<String> {
    qsr_core::text_file::read_text(path, qsr_core::text_file::MAX_INPUT_BYTES).map_err(|source| {
        PqrmError::Io {
            path: path.to_path_buf(),
            source,
        }
    })
}

fn parse_err(path: &Path, line: usize, reason: impl Into<String>) -> PqrmError {
    PqrmError::Parse {
        path: path.to_path_buf(),
        line,
        reason: reason.into(),
    }
}

/// Finite numbers only: NaN or infinity in a recording is a defect of the file, named with
/// its line, never a value passed on.
/// `names` names the columns in errors (`field k` beyond them).
/// Columns of our observation CSV.
const CSV_COLUMNS: [&str; 8] = ["t", "robot", "landmark", "x", "y", "cxx", "cxy", "cyy"];
/// Values of a g2o `LANDMARK` line.
const G2O_COLUMNS: [&str; 7] = ["pose", "landmark", "x", "y", "cxx", "cxy", "cyy"];

fn numbers(path: &Path, lineno: usize, fields: &[&str], names: &[&str]) -> Result<Vec<f64>> {
    let name = |k: usize| {
        names
            .get(k)
            .map_or_else(|| format!("field {}", k + 1), |n| (*n).to_owned())
    };
    fields
        .iter()
        .enumerate()
        .map(|(k, f)| match f.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(parse_err(
                path,
                lineno,
                format!("{}: `{}` is not a finite number", name(k), shown(f)),
            )),
            Err(_) => Err(parse_err(
                path,
                lineno,
                format!("{}: `{}` is not a number", name(k), shown(f)),
            )),
        })
        .collect()
}

/// A field as quoted in an error: at most 40 characters (a 2 MB field is not echoed whole).
pub(crate) fn shown(field: &str) -> String {
    const MAX: usize = 40;
    match field.char_indices().nth(MAX) {
        None => field.to_owned(),
        Some((cut, _)) => format!("{}… ({} bytes)", &field[..cut], field.len()),
    }
}

/// Groups `(t, robot, observation, line)` rows into validated scans sorted by time then
/// robot; a landmark seen twice in one scan is an error naming both lines of `path`.
fn group(rows: Vec<(f64, u32, Observation, usize)>, path: &Path) -> Result<Vec<Scan>> {
    let mut rows = rows;
    rows.sort_by(|a, b| {
        a.0.total_cmp(&b.0)
            .then(a.1.cmp(&b.1))
            .then(a.2.id.cmp(&b.2.id))
            .then(a.3.cmp(&b.3))
    });
    let mut scans = Vec::new();
    let mut i = 0;
    while i < rows.len() {
        let (t, robot) = (rows[i].0, rows[i].1);
        let mut j = i;
        while j < rows.len() && rows[j].0 == t && rows[j].1 == robot {
            j += 1;
        }
        if let Some(w) = rows[i..j].windows(2).find(|w| w[0].2.id == w[1].2.id) {
            return Err(parse_err(
                path,
                w[1].3,
                format!(
                    "landmark {} appears twice in the scan at t = {t} of robot {robot} (first on \
                     line {})",
                    w[1].2.id, w[0].3
                ),
            ));
        }
        scans.push(Scan::new(
            t,
            robot,
            rows[i..j].iter().map(|r| r.2).collect(),
        )?);
        i = j;
    }
    Ok(scans)
}

/// A numeric field that must be an id: an integer in `0..=u32::MAX` (no saturating cast
/// that would turn `-6.7`, `NaN` or `1e10` into a real landmark's id).
fn id_field(path: &Path, line: usize, field: &str, v: f64) -> Result<u32> {
    if v.is_finite() && v >= 0.0 && v.fract() == 0.0 && v <= f64::from(u32::MAX) {
        Ok(v as u32)
    } else {
        Err(parse_err(
            path,
            line,
            format!("{field} must be an integer in 0..={}, got {v}", u32::MAX),
        ))
    }
}

/// Reads our observation CSV.
///
/// # Errors
/// [`PqrmError::Io`]; [`PqrmError::Parse`] naming the line for a wrong header, a wrong field
/// count or a bad number; observation errors (bad covariance, duplicate landmark in a scan)
/// are reported with the line too.
pub fn read_csv(path: &Path) -> Result<Dataset> {
    parse_csv(&read(path)?, path)
}

/// As [`read_csv`], from text already read (`path` names it in errors): the entry point
/// the fuzz targets drive.
///
/// # Errors
/// As [`read_csv`] without the I/O.
pub fn parse_csv(text: &str, path: &Path) -> Result<Dataset> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let header = lines
        .next()
        .map(|(_, l)| l.trim().to_owned())
        .unwrap_or_default();
    if header.replace(' ', "") != "t,robot,landmark,x,y,cxx,cxy,cyy" {
        return Err(parse_err(
            path,
            1,
            format!("expected the header `t,robot,landmark,x,y,cxx,cxy,cyy`, found `{header}`"),
        ));
    }
    let mut rows = Vec::new();
    for (i, line) in lines {
        let lineno = i + 1;
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != 8 {
            return Err(parse_err(
                path,
                lineno,
                format!("expected 8 fields, found {}", f.len()),
            ));
        }
        let v = numbers(path, lineno, &f, &CSV_COLUMNS)?;
        let (robot, id) = (v[1], v[2]);
        if robot < 0.0
            || robot.fract() != 0.0
            || id < 0.0
            || id.fract() != 0.0
            || id > f64::from(u32::MAX)
        {
            return Err(parse_err(
                path,
                lineno,
                "robot and landmark must be non-negative integers",
            ));
        }
        let obs = Observation::new(
            LandmarkId(id as u32),
            [v[3], v[4]],
            [[v[5], v[6]], [v[6], v[7]]],
        )
        .map_err(|e| parse_err(path, lineno, e.to_string()))?;
        if !v[0].is_finite() {
            return Err(parse_err(path, lineno, "time is not finite"));
        }
        rows.push((v[0], robot as u32, obs, lineno));
    }
    if rows.is_empty() {
        return Err(parse_err(
            path,
            1,
            "no observations: the file has a header and nothing else",
        ));
    }
    Ok(Dataset {
        scans: group(rows, path)?,
        truth: None,
        skipped: 0,
    })
}

/// Writes scans as our observation CSV (the format [`read_csv`] reads and the simulator
/// writes).
///
/// # Errors
/// I/O errors of the writer.
pub fn write_csv(scans: &[Scan], out: &mut impl Write) -> std::io::Result<()> {
    writeln!(out, "t,robot,landmark,x,y,cxx,cxy,cyy")?;
    for s in scans {
        for o in &s.observations {
            writeln!(
                out,
                "{},{},{},{},{},{},{},{}",
                s.t, s.robot, o.id.0, o.mean[0], o.mean[1], o.cov[0][0], o.cov[0][1], o.cov[1][1]
            )?;
        }
    }
    Ok(())
}

/// Reads a truth CSV `landmark,x,y` (header required).
///
/// # Errors
/// [`PqrmError::Io`], [`PqrmError::Parse`].
pub fn read_truth_csv(path: &Path) -> Result<GroundTruth> {
    parse_truth_csv(&read(path)?, path)
}

/// As [`read_truth_csv`], from text already read (`path` names it in errors): the entry point
/// the fuzz targets drive.
///
/// # Errors
/// As [`read_truth_csv`] without the I/O.
pub fn parse_truth_csv(text: &str, path: &Path) -> Result<GroundTruth> {
    let mut truth = GroundTruth::default();
    // A landmark surveyed twice would silently keep the last position.
    let mut lines: BTreeMap<u32, usize> = BTreeMap::new();
    let header = text.lines().next().unwrap_or_default().trim();
    if header.replace(' ', "") != "landmark,x,y" {
        return Err(parse_err(
            path,
            1,
            format!(
                "expected the header `landmark,x,y`, found `{}`",
                shown(header)
            ),
        ));
    }
    for (i, line) in text.lines().enumerate().skip(1) {
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != 3 {
            return Err(parse_err(path, i + 1, "expected `landmark,x,y`"));
        }
        let v = numbers(path, i + 1, &f, &["landmark", "x", "y"])?;
        let id = id_field(path, i + 1, "landmark", v[0])?;
        if !v[1].is_finite() || !v[2].is_finite() {
            return Err(parse_err(path, i + 1, "bad landmark position"));
        }
        if let Some(first) = lines.insert(id, i + 1) {
            return Err(parse_err(
                path,
                i + 1,
                format!(
                    "landmark {id} is surveyed twice (lines {first} and {})",
                    i + 1
                ),
            ));
        }
        truth.positions.insert(LandmarkId(id), [v[1], v[2]]);
    }
    if truth.positions.is_empty() {
        return Err(parse_err(path, 1, "no surveyed landmark after the header"));
    }
    Ok(truth)
}

/// Non-comment lines of a MRCLAM `.dat` file split on whitespace, with line numbers.
fn dat_rows(path: &Path, names: &[&str]) -> Result<Vec<(usize, Vec<f64>)>> {
    let text = read(path)?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let f: Vec<&str> = t.split_whitespace().collect();
        out.push((i + 1, numbers(path, i + 1, &f, names)?));
    }
    Ok(out)
}

/// MRCLAM's `Landmark_Groundtruth.dat`: `subject x y x_std y_std`, each subject once.
fn read_mrclam_truth(gt: &Path) -> Result<GroundTruth> {
    let mut truth = GroundTruth::default();
    for (line, v) in dat_rows(gt, &["subject", "x", "y", "x_std", "y_std"])? {
        if v.len() < 3 {
            return Err(parse_err(gt, line, "expected `subject x y ...`"));
        }
        let id = id_field(gt, line, "subject", v[0])?;
        if truth.positions.contains_key(&LandmarkId(id)) {
            return Err(parse_err(
                gt,
                line,
                format!("subject {id} is surveyed twice"),
            ));
        }
        truth.positions.insert(LandmarkId(id), [v[1], v[2]]);
    }
    Ok(truth)
}

/// MRCLAM's `Barcodes.dat`: `subject barcode`, as barcode → subject.
fn read_mrclam_barcodes(bc: &Path) -> Result<BTreeMap<u32, u32>> {
    let mut barcode_to_subject = BTreeMap::new();
    for (line, v) in dat_rows(bc, &["subject", "barcode"])? {
        if v.len() != 2 {
            return Err(parse_err(bc, line, "expected `subject barcode`"));
        }
        barcode_to_subject.insert(
            id_field(bc, line, "barcode", v[1])?,
            id_field(bc, line, "subject", v[0])?,
        );
    }
    Ok(barcode_to_subject)
}

/// Reads a MRCLAM dataset directory; the surveyed positions become the truth.
///
/// # Errors
/// [`PqrmError::Io`] for a missing file, [`PqrmError::Parse`] for malformed lines,
/// [`PqrmError::InvalidConfig`] for a negative noise.
pub fn read_mrclam(dir: &Path, noise: RangeBearingNoise) -> Result<Dataset> {
    noise.validate()?;
    let file = |name: &str| -> PathBuf { dir.join(name) };
    let truth = read_mrclam_truth(&file("Landmark_Groundtruth.dat"))?;
    let barcode_to_subject = read_mrclam_barcodes(&file("Barcodes.dat"))?;
    let mut rows = Vec::new();
    let mut skipped = 0;
    let mut found_any = false;
    for robot in 1..=5u32 {
        let path = file(&format!("Robot{robot}_Measurement.dat"));
        if !path.exists() {
            continue;
        }
        found_any = true;
        for (line, v) in dat_rows(&path, &["time", "barcode", "range", "bearing"])? {
            if v.len() != 4 {
                return Err(parse_err(
                    &path,
                    line,
                    "expected `time barcode range bearing`",
                ));
            }
            if !v[0].is_finite() {
                return Err(parse_err(&path, line, "time is not finite"));
            }
            let barcode = id_field(&path, line, "barcode", v[1])?;
            let subject = barcode_to_subject.get(&barcode).copied();
            match subject {
                Some(s) if truth.positions.contains_key(&LandmarkId(s)) => {
                    let obs = Observation::from_range_bearing(
                        LandmarkId(s),
                        v[2],
                        v[3],
                        noise.sigma_range,
                        noise.sigma_bearing,
                    )
                    .map_err(|e| parse_err(&path, line, e.to_string()))?;
                    rows.push((v[0], robot, obs, line));
                }
                _ => skipped += 1,
            }
        }
    }
    if !found_any {
        return Err(PqrmError::Io {
            path: file("Robot1_Measurement.dat"),
            source: std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "no RobotN_Measurement.dat in the directory",
            ),
        });
    }
    if rows.is_empty() {
        return Err(parse_err(
            &file("Robot1_Measurement.dat"),
            1,
            format!(
                "no measurement of a surveyed landmark in any RobotN_Measurement.dat ({skipped} \
                 skipped: robots or unknown barcodes)"
            ),
        ));
    }
    // A robot occasionally reports the same landmark twice in one frame: keep the first.
    rows.sort_by(|a, b| {
        a.0.total_cmp(&b.0)
            .then(a.1.cmp(&b.1))
            .then(a.2.id.cmp(&b.2.id))
    });
    let before = rows.len();
    rows.dedup_by(|b, a| a.0 == b.0 && a.1 == b.1 && a.2.id == b.2.id);
    skipped += before - rows.len();
    Ok(Dataset {
        scans: group(rows, dir)?,
        truth: Some(truth),
        skipped,
    })
}

/// Reads g2o / Victoria Park `LANDMARK pose lm x y cxx cxy cyy` lines; each pose is a scan
/// at time `pose`.
///
/// # Errors
/// [`PqrmError::Io`], [`PqrmError::Parse`].
pub fn read_g2o(path: &Path) -> Result<Dataset> {
    parse_g2o(&read(path)?, path)
}

/// As [`read_g2o`], from text already read (`path` names it in errors): the entry point
/// the fuzz targets drive.
///
/// # Errors
/// As [`read_g2o`] without the I/O.
pub fn parse_g2o(text: &str, path: &Path) -> Result<Dataset> {
    let mut rows = Vec::new();
    let mut skipped = 0;
    for (i, line) in text.lines().enumerate() {
        let f: Vec<&str> = line.split_whitespace().collect();
        match f.first() {
            Some(&"LANDMARK") => {
                if f.len() != 8 {
                    return Err(parse_err(
                        path,
                        i + 1,
                        format!("LANDMARK needs 7 values, found {}", f.len() - 1),
                    ));
                }
                let v = numbers(path, i + 1, &f[1..], &G2O_COLUMNS)?;
                if !v[0].is_finite() {
                    return Err(parse_err(path, i + 1, "pose is not finite"));
                }
                let obs = Observation::new(
                    LandmarkId(id_field(path, i + 1, "landmark", v[1])?),
                    [v[2], v[3]],
                    [[v[4], v[5]], [v[5], v[6]]],
                )
                .map_err(|e| parse_err(path, i + 1, e.to_string()))?;
                rows.push((v[0], 0, obs, i + 1));
            }
            None => {}
            Some(_) => skipped += 1,
        }
    }
    if rows.is_empty() {
        return Err(parse_err(
            path,
            1,
            format!(
                "no `LANDMARK pose id x y cxx cxy cyy` line among {} lines: not a g2o landmark file?",
                text.lines().count()
            ),
        ));
    }
    Ok(Dataset {
        scans: group(rows, path)?,
        truth: None,
        skipped,
    })
}
