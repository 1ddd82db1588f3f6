//! Charts of a study's numbers: lines with error bars, a scatter over the EDC's guides, a
//! confusion heatmap, histograms.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::canvas::{Drawn, SIZE, both, colour};
use crate::regions::draw_edc_guides;
use crate::{Picture, PlotError, Result};

/// One line of a line chart.
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// Points `(x, y)`.
    pub points: Vec<(f64, f64)>,
    /// Optional ± error bar per point.
    pub err: Option<Vec<f64>>,
    /// Dashed (baselines, bounds).
    pub dashed: bool,
}

impl Series {
    /// A solid line.
    #[must_use]
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            err: None,
            dashed: false,
        }
    }

    /// A dashed reference line.
    #[must_use]
    pub fn reference(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            err: None,
            dashed: true,
        }
    }

    /// With error bars.
    #[must_use]
    pub fn with_err(mut self, err: Vec<f64>) -> Self {
        self.err = Some(err);
        self
    }
}

fn bounds(series: &[Series]) -> (f64, f64, f64, f64) {
    let mut b = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for s in series {
        for (i, (x, y)) in s.points.iter().enumerate() {
            let e = s.err.as_ref().map_or(0.0, |e| e[i]);
            b = (b.0.min(*x), b.1.max(*x), b.2.min(y - e), b.3.max(y + e));
        }
    }
    if !b.0.is_finite() {
        return (0.0, 1.0, 0.0, 1.0);
    }
    let pad = ((b.3 - b.2) * 0.05).max(1e-3);
    (b.0, b.1.max(b.0 + 1e-9), (b.2 - pad).min(0.0), b.3 + pad)
}

fn draw_lines<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    xl: &str,
    yl: &str,
    series: &[Series],
) -> Drawn
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (x0, x1, y0, y1) = bounds(series);
    let mut chart = ChartBuilder::on(root)
        .margin(12)
        .caption(title, ("sans-serif", 20))
        .x_label_area_size(40)
        .y_label_area_size(56)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(xl)
        .y_desc(yl)
        .label_style(("sans-serif", 13))
        .draw()?;
    for (i, s) in series.iter().enumerate() {
        let c = if s.dashed { BLACK } else { colour(i) };
        let style = c.stroke_width(2);
        if s.dashed {
            chart
                .draw_series(DashedLineSeries::new(s.points.iter().copied(), 6, 4, style))?
                .label(s.name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2))
                });
        } else {
            chart
                .draw_series(LineSeries::new(s.points.iter().copied(), style).point_size(3))?
                .label(s.name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2))
                });
        }
        if let Some(err) = &s.err {
            chart.draw_series(s.points.iter().zip(err).map(|((x, y), e)| {
                ErrorBar::new_vertical(*x, y - e, *y, y + e, c.stroke_width(1), 6)
            }))?;
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .position(SeriesLabelPosition::UpperLeft)
        .draw()?;
    Ok(())
}

/// A line chart (e.g. a metric against σ_N, one line per calculus).
pub fn line_chart(title: &str, x_label: &str, y_label: &str, series: &[Series]) -> Result<Picture> {
    both(
        |r| draw_lines(r, title, x_label, y_label, series),
        |r| draw_lines(r, title, x_label, y_label, series),
    )
}

fn draw_scatter<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    pts: &[(f64, f64, f64)],
    colour_label: &str,
) -> Drawn
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (x0, x1, y0, y1) = (-2.5, 2.5, -1.5, 2.5);
    let mut chart = ChartBuilder::on(root)
        .margin(12)
        .caption(title, ("sans-serif", 20))
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x (normalised)")
        .y_desc("y (normalised)")
        .draw()?;
    // The EDC's lines and circles, for orientation.
    draw_edc_guides(&mut chart, (x0, x1, y0, y1), RGBColor(120, 120, 120))?;
    let vmax = pts.iter().map(|p| p.2).fold(1e-9, f64::max);
    chart.draw_series(
        pts.iter()
            .filter(|(x, y, _)| (x0..x1).contains(x) && (y0..y1).contains(y))
            .map(|(x, y, v)| {
                Circle::new(
                    (*x, *y),
                    2,
                    HSLColor(0.66 * (1.0 - v / vmax), 0.8, 0.45).filled(),
                )
            }),
    )?;
    root.draw(&Text::new(
        format!("colour: {colour_label}, blue = 0 … red = {vmax:.0}"),
        (70, SIZE.1 as i32 - 18),
        ("sans-serif", 12),
    ))?;
    Ok(())
}

/// Points in the normalised frame over the EDC partition, coloured by a value (Fig 2.8).
pub fn edc_scatter(title: &str, pts: &[(f64, f64, f64)], colour_label: &str) -> Result<Picture> {
    both(
        |r| draw_scatter(r, title, pts, colour_label),
        |r| draw_scatter(r, title, pts, colour_label),
    )
}

fn draw_heatmap<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    labels: &[String],
    m: &[Vec<u64>],
) -> Drawn
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let n = labels.len();
    let max = m.iter().flatten().copied().max().unwrap_or(1).max(1) as f64;
    let mut chart = ChartBuilder::on(root)
        .margin(12)
        .caption(title, ("sans-serif", 20))
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0..n, 0..n)?;
    let lx = labels.to_vec();
    let ly = labels.to_vec();
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("maximum-likelihood state")
        .y_desc("true state")
        .x_labels(n)
        .y_labels(n)
        .x_label_formatter(&move |i| lx.get(*i).cloned().unwrap_or_default())
        .y_label_formatter(&move |i| ly.get(*i).cloned().unwrap_or_default())
        .label_style(("sans-serif", 11))
        .draw()?;
    chart.draw_series(
        (0..n)
            .flat_map(|t| (0..n).map(move |p| (t, p)))
            .map(|(t, p)| {
                let v = m[t][p] as f64;
                // Log scale so off-diagonal structure shows beside the diagonal.
                let shade = if v > 0.0 {
                    0.15 + 0.85 * (v.ln_1p() / max.ln_1p())
                } else {
                    0.0
                };
                let c = RGBColor(
                    255 - (200.0 * shade) as u8,
                    255 - (160.0 * shade) as u8,
                    255 - (60.0 * shade) as u8,
                );
                Rectangle::new([(p, t), (p + 1, t + 1)], c.filled())
            }),
    )?;
    Ok(())
}

/// A confusion matrix `[true][ml]` on a log colour scale (Fig 2.9).
pub fn heatmap(title: &str, labels: &[String], matrix: &[Vec<u64>]) -> Result<Picture> {
    both(
        |r| draw_heatmap(r, title, labels, matrix),
        |r| draw_heatmap(r, title, labels, matrix),
    )
}

fn draw_hist<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    xl: &str,
    edges: &[f64],
    groups: &[(String, Vec<f64>)],
) -> Drawn
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let nb = edges.len() - 1;
    let hist: Vec<Vec<f64>> = groups
        .iter()
        .map(|(_, v)| {
            let mut h = vec![0.0; nb];
            for x in v {
                let b = edges
                    .partition_point(|e| e <= x)
                    .saturating_sub(1)
                    .min(nb - 1);
                h[b] += 1.0;
            }
            let total = v.len().max(1) as f64;
            h.iter().map(|c| c / total).collect()
        })
        .collect();
    let ymax = hist.iter().flatten().copied().fold(0.01, f64::max) * 1.1;
    let mut chart = ChartBuilder::on(root)
        .margin(12)
        .caption(title, ("sans-serif", 20))
        .x_label_area_size(40)
        .y_label_area_size(56)
        .build_cartesian_2d(edges[0]..edges[nb], 0.0..ymax)?;
    chart
        .configure_mesh()
        .x_desc(xl)
        .y_desc("fraction")
        .label_style(("sans-serif", 13))
        .draw()?;
    let g = groups.len() as f64;
    for (gi, (name, _)) in groups.iter().enumerate() {
        let c = colour(gi);
        chart
            .draw_series((0..nb).map(|b| {
                let w = (edges[b + 1] - edges[b]) / g;
                let x = edges[b] + w * gi as f64;
                Rectangle::new([(x, 0.0), (x + w * 0.9, hist[gi][b])], c.mix(0.8).filled())
            }))?
            .label(name.clone())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], c.filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()?;
    Ok(())
}

/// Normalised histograms of several groups over common bin edges (Figs 2.14, 2.15).
pub fn histogram(
    title: &str,
    x_label: &str,
    edges: &[f64],
    groups: &[(String, Vec<f64>)],
) -> Result<Picture> {
    if edges.len() < 2 {
        return Err(PlotError::Invalid(
            "a histogram needs at least one bin".into(),
        ));
    }
    both(
        |r| draw_hist(r, title, x_label, edges, groups),
        |r| draw_hist(r, title, x_label, edges, groups),
    )
}
