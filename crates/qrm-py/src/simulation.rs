//! `qrm.sim.run`: a thin wrapper of `sim2d` scenarios.

use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{files_err, invalid, sim_err, study_err};

/// Runs a scenario (pqrm-100, qlink-200, hallway, field) from a seed. Returns the frames: dicts
/// {"t", "pose": (x, y, theta), "ids", "xy" (n, 2), "cov" (n, 3) = [cxx, cxy, cyy]} in the robot
/// frame, plus "angles" and "ranges" (inf = no return) when `lidar` is set.
#[pyfunction]
#[pyo3(signature = (scenario, seed, *, lidar = false))]
pub(crate) fn simulate<'py>(
    py: Python<'py>,
    scenario: &str,
    seed: u64,
    lidar: bool,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let name = scenario.to_owned();
    let frames = crate::pool::detach(py, || {
        sim2d::scenario(&name, seed, None).and_then(|sc| sc.run(seed, lidar))
    })
    .map_err(sim_err)?;
    let mut out = Vec::with_capacity(frames.len());
    for f in &frames {
        let d = PyDict::new(py);
        d.set_item("t", f.t)?;
        d.set_item("pose", (f.pose.x, f.pose.y, f.pose.theta))?;
        d.set_item(
            "ids",
            f.detections
                .iter()
                .map(|x| i64::from(x.id))
                .collect::<Vec<_>>()
                .into_pyarray(py),
        )?;
        let xy: Vec<Vec<f64>> = f.detections.iter().map(|x| x.xy.to_vec()).collect();
        let cov: Vec<Vec<f64>> = f
            .detections
            .iter()
            .map(|x| vec![x.cov[0][0], x.cov[0][1], x.cov[1][1]])
            .collect();
        let xy = if xy.is_empty() {
            PyArray2::zeros(py, [0, 2], false)
        } else {
            PyArray2::from_vec2(py, &xy).map_err(|e| invalid(e.to_string()))?
        };
        let cov = if cov.is_empty() {
            PyArray2::zeros(py, [0, 3], false)
        } else {
            PyArray2::from_vec2(py, &cov).map_err(|e| invalid(e.to_string()))?
        };
        d.set_item("xy", xy)?;
        d.set_item("cov", cov)?;
        if let Some(s) = &f.scan {
            d.set_item("angles", s.angles.clone().into_pyarray(py))?;
            d.set_item("ranges", s.ranges.clone().into_pyarray(py))?;
        }
        out.push(d);
    }
    Ok(out)
}

/// Runs a scenario and writes the recording `qrm sim` writes into `out` (observations.csv,
/// truth.csv, world.toml, run.mcap, scenario.svg/png), whole or not at all
/// (`studies::simulation`, files through `qrm-files`). `detector` is "ideal" or "lidar";
/// `world` a TOML world file replacing the scenario's. Returns the names written.
#[pyfunction]
#[pyo3(signature = (scenario, seed, out, *, detector = "ideal", lidar = true, landmark_radius = None, world = None))]
#[allow(clippy::too_many_arguments)] // a Python signature of keyword arguments
pub(crate) fn sim_record(
    py: Python<'_>,
    scenario: &str,
    seed: u64,
    out: std::path::PathBuf,
    detector: &str,
    lidar: bool,
    landmark_radius: Option<f64>,
    world: Option<std::path::PathBuf>,
) -> PyResult<Vec<String>> {
    use studies::simulation::{Detector, Simulation, read_world};
    let detector = match detector {
        "ideal" => Detector::Ideal,
        "lidar" => Detector::Lidar,
        other => {
            return Err(invalid(format!(
                "unknown detector `{other}` (ideal or lidar)"
            )));
        }
    };
    let world = world
        .as_deref()
        .map(read_world)
        .transpose()
        .map_err(study_err)?;
    let sim = Simulation {
        scenario: scenario.to_owned(),
        seed,
        world,
        landmark_radius,
        detector,
        lidar,
    };
    sim.check().map_err(study_err)?;
    crate::pool::detach(py, || {
        let run = sim.run().map_err(study_err)?;
        let products = run.products().map_err(study_err)?;
        let stage = qrm_files::Staging::new(&out).map_err(files_err)?;
        qrm_files::write_products(stage.path(), &products).map_err(files_err)?;
        let written = crate::study_runner::files_under(stage.path());
        stage.commit().map_err(files_err)?;
        Ok(written)
    })
}
