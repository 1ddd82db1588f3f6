//! A map drawn for a notebook: how sure it is. The histogram of P(ML) over its sets (the
//! probability of each set's most likely state) says at a glance whether the map is decided
//! (a tall bar near 1) or still hedging, which is what a user looks at a map for first.

use plotters::prelude::*;

/// Bins of P(ML): 1/Q … 1 in ten equal steps would hide the mass near 1, so the edges follow
/// `pqrm::calibration::EDGES` (fine near 1, where most sets of a good map are).
const EDGES: [f64; 9] = pqrm::calibration::EDGES;

/// The P(ML) histogram of `p_ml` as SVG text, titled `title`.
pub(crate) fn p_ml_histogram(title: &str, p_ml: &[f64]) -> Result<String, String> {
    qsr_core::register_font();
    let mut counts = [0usize; EDGES.len() - 1];
    for &p in p_ml {
        let bin = EDGES[1..]
            .iter()
            .position(|&hi| p < hi)
            .unwrap_or(counts.len() - 1);
        counts[bin] += 1;
    }
    let top = counts.iter().copied().max().unwrap_or(0).max(1) as f64;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (480, 260)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 15))
            .margin(8)
            .x_label_area_size(36)
            .y_label_area_size(48)
            .build_cartesian_2d(0f64..counts.len() as f64, 0f64..top * 1.1)
            .map_err(|e| e.to_string())?;
        let labels: Vec<String> = EDGES[..counts.len()]
            .iter()
            .map(|e| format!("≥{e}"))
            .collect();
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(counts.len())
            .x_label_formatter(&|x| {
                labels
                    .get(x.floor().max(0.0) as usize)
                    .cloned()
                    .unwrap_or_default()
            })
            .x_desc("P(most likely state)")
            .y_desc("sets")
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(counts.iter().enumerate().map(|(i, &n)| {
                Rectangle::new(
                    [(i as f64 + 0.1, 0.0), (i as f64 + 0.9, n as f64)],
                    RGBColor(70, 120, 180).filled(),
                )
            }))
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}
