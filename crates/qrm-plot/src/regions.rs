//! Partitions of a window into regions, cell by cell (salient region maps, raster calculi;
//! Figs 3.8–3.10), and points in the normalised frame of a reference pair over the EDC's
//! guides.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::canvas::{Drawn, both, pastel};
use crate::{Picture, Result};

/// What a salient-region map picture shows (Figs 3.8–3.10).
pub struct RegionPicture<'a> {
    /// `[x0, x1, y0, y1]` of the grid.
    pub window: [f64; 4],
    /// Cells along x and y.
    pub nx: usize,
    /// Cells along y.
    pub ny: usize,
    /// Region of every cell (`u32::MAX`: not drawn).
    pub cell_region: &'a [u32],
    /// Data points to overlay (black).
    pub points: &'a [[f64; 2]],
    /// Highlighted points (magenta), e.g. landmark F of Fig 3.10.
    pub highlight: &'a [[f64; 2]],
    /// Cells to shade dark (e.g. Algorithm 3's reachable area).
    pub shade: Option<&'a [bool]>,
    /// Labelled marks (red): reference landmarks.
    pub marks: &'a [([f64; 2], String)],
    /// Write each region's number at its centroid.
    pub numbers: bool,
}

/// The picture's cell size.
fn cell_size(p: &RegionPicture<'_>) -> (f64, f64) {
    let [x0, x1, y0, y1] = p.window;
    ((x1 - x0) / p.nx as f64, (y1 - y0) / p.ny as f64)
}

/// The regions' cells as rectangles, one per run of equal cells in a row (keeps the SVG
/// small), shaded cells darker.
fn region_rects(p: &RegionPicture<'_>) -> Vec<Rectangle<(f64, f64)>> {
    let [x0, _, y0, _] = p.window;
    let (dx, dy) = cell_size(p);
    let mut rects = Vec::new();
    for j in 0..p.ny {
        let mut i = 0;
        while i < p.nx {
            let c = j * p.nx + i;
            let r = p.cell_region[c];
            let shaded = p.shade.is_some_and(|s| s[c]);
            let mut e = i + 1;
            while e < p.nx
                && p.cell_region[j * p.nx + e] == r
                && p.shade.is_some_and(|s| s[j * p.nx + e]) == shaded
            {
                e += 1;
            }
            if r != u32::MAX {
                let base = pastel(r as usize);
                let colour = if shaded {
                    RGBColor(base.0 / 2, base.1 / 2, base.2 / 2)
                } else {
                    base
                };
                rects.push(Rectangle::new(
                    [
                        (x0 + i as f64 * dx, y0 + j as f64 * dy),
                        (x0 + e as f64 * dx, y0 + (j + 1) as f64 * dy),
                    ],
                    colour.filled(),
                ));
            }
            i = e;
        }
    }
    rects
}

/// The borders between cells of different regions.
fn region_borders(p: &RegionPicture<'_>) -> Vec<PathElement<(f64, f64)>> {
    let [x0, _, y0, _] = p.window;
    let (dx, dy) = cell_size(p);
    let mut lines = Vec::new();
    for j in 0..p.ny {
        for i in 0..p.nx {
            let c = j * p.nx + i;
            if i + 1 < p.nx && p.cell_region[c + 1] != p.cell_region[c] {
                let x = x0 + (i + 1) as f64 * dx;
                lines.push(PathElement::new(
                    vec![(x, y0 + j as f64 * dy), (x, y0 + (j + 1) as f64 * dy)],
                    BLACK.stroke_width(1),
                ));
            }
            if j + 1 < p.ny && p.cell_region[c + p.nx] != p.cell_region[c] {
                let y = y0 + (j + 1) as f64 * dy;
                lines.push(PathElement::new(
                    vec![(x0 + i as f64 * dx, y), (x0 + (i + 1) as f64 * dx, y)],
                    BLACK.stroke_width(1),
                ));
            }
        }
    }
    lines
}

/// Each region's index and the centroid of its cells.
fn region_centroids(p: &RegionPicture<'_>) -> Vec<(usize, (f64, f64))> {
    let [x0, _, y0, _] = p.window;
    let (dx, dy) = cell_size(p);
    let n = p
        .cell_region
        .iter()
        .filter(|&&r| r != u32::MAX)
        .max()
        .map_or(0, |&r| r as usize + 1);
    let mut acc = vec![(0.0, 0.0, 0usize); n];
    for (c, &r) in p.cell_region.iter().enumerate() {
        if r != u32::MAX {
            let a = &mut acc[r as usize];
            a.0 += x0 + ((c % p.nx) as f64 + 0.5) * dx;
            a.1 += y0 + ((c / p.nx) as f64 + 0.5) * dy;
            a.2 += 1;
        }
    }
    acc.iter()
        .enumerate()
        .filter(|(_, a)| a.2 > 0)
        .map(|(r, a)| (r, (a.0 / a.2 as f64, a.1 / a.2 as f64)))
        .collect()
}

pub(crate) fn draw_regions<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    p: &RegionPicture<'_>,
) -> Drawn
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let [x0, x1, y0, y1] = p.window;
    let mut chart = ChartBuilder::on(root)
        .margin(12)
        .caption(title, ("sans-serif", 18))
        .x_label_area_size(36)
        .y_label_area_size(48)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .label_style(("sans-serif", 12))
        .draw()?;
    let (dx, dy) = ((x1 - x0) / p.nx as f64, (y1 - y0) / p.ny as f64);
    chart.draw_series(region_rects(p))?;
    chart.draw_series(region_borders(p))?;
    let inside = |q: &[f64; 2]| q[0] >= x0 && q[0] <= x1 && q[1] >= y0 && q[1] <= y1;
    chart.draw_series(
        p.points
            .iter()
            .filter(|q| inside(q))
            .map(|q| Circle::new((q[0], q[1]), 1, BLACK.filled())),
    )?;
    chart.draw_series(
        p.highlight
            .iter()
            .filter(|q| inside(q))
            .map(|q| Circle::new((q[0], q[1]), 3, RGBColor(220, 0, 220).filled())),
    )?;
    for (q, label) in p.marks {
        chart.draw_series(std::iter::once(Circle::new((q[0], q[1]), 5, RED.filled())))?;
        chart.draw_series(std::iter::once(Text::new(
            label.clone(),
            (q[0] + dx, q[1] + dy),
            ("sans-serif", 14).into_font().color(&RED),
        )))?;
    }
    if p.numbers {
        chart.draw_series(region_centroids(p).into_iter().map(|(r, at)| {
            Text::new(
                (r + 1).to_string(),
                at,
                ("sans-serif", 13).into_font().color(&BLACK),
            )
        }))?;
    }
    Ok(())
}

/// A salient-region map with data overlaid.
pub fn region_map(title: &str, picture: &RegionPicture<'_>) -> Result<Picture> {
    both(
        |r| draw_regions(r, title, picture),
        |r| draw_regions(r, title, picture),
    )
}

/// The EDC's line AB, the perpendiculars at A, B and the midpoint, and the unit circles about
/// A and B, in the normalised frame.
pub(crate) fn draw_edc_guides<DB: DrawingBackend>(
    chart: &mut ChartContext<
        '_,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    (x0, x1, y0, y1): (f64, f64, f64, f64),
    colour: RGBColor,
) -> Drawn
where
    DB::ErrorType: 'static,
{
    let style = colour.stroke_width(1);
    chart.draw_series(std::iter::once(PathElement::new(
        vec![(0.0, y0), (0.0, y1)],
        style,
    )))?;
    for y in [0.0, 0.5, 1.0] {
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(x0, y), (x1, y)],
            style,
        )))?;
    }
    for cy in [0.0, 1.0] {
        let circle: Vec<(f64, f64)> = (0..=120)
            .map(|k| f64::from(k) * std::f64::consts::TAU / 120.0)
            .map(|t| (t.cos(), cy + t.sin()))
            .collect();
        chart.draw_series(std::iter::once(PathElement::new(circle, style)))?;
    }
    Ok(())
}

fn draw_reference_pair<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    observed: &[(f64, f64, f64)],
    inferred: &[(f64, f64, f64)],
) -> Drawn
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let all = observed.iter().chain(inferred);
    let (mut x0, mut x1, mut y0, mut y1) = (-1.5f64, 1.5f64, -1.0f64, 2.0f64);
    for (x, y, _) in all {
        x0 = x0.min(*x);
        x1 = x1.max(*x);
        y0 = y0.min(*y);
        y1 = y1.max(*y);
    }
    let pad = 0.08 * (x1 - x0).max(y1 - y0);
    let (x0, x1, y0, y1) = (x0 - pad, x1 + pad, y0 - pad, y1 + pad);
    let mut chart = ChartBuilder::on(root)
        .margin(12)
        .caption(title, ("sans-serif", 18))
        .x_label_area_size(55)
        .y_label_area_size(50)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x in the frame of A→B (A at 0,0; B at 0,1)")
        .y_desc("y")
        .draw()?;
    // The EDC's lines and unit circles (every built-in point calculus is a merge of it).
    draw_edc_guides(&mut chart, (x0, x1, y0, y1), RGBColor(150, 150, 150))?;
    // Colour-blind-safe ramp from vermillion (p = 0) to blue (p = 1).
    let ramp = |p: f64| {
        let p = p.clamp(0.0, 1.0);
        let mix = |a: f64, b: f64| (a + (b - a) * p).round() as u8;
        RGBColor(mix(213.0, 0.0), mix(94.0, 114.0), mix(0.0, 178.0))
    };
    chart.draw_series(std::iter::once(Circle::new((0.0, 0.0), 5, BLACK.filled())))?;
    chart.draw_series(std::iter::once(Circle::new((0.0, 1.0), 5, BLACK.filled())))?;
    chart
        .draw_series(
            observed
                .iter()
                .map(|(x, y, p)| Circle::new((*x, *y), 6, ramp(*p).filled())),
        )?
        .label("observed (map belief)")
        .legend(|(x, y)| Circle::new((x, y), 5, RGBColor(0, 114, 178).filled()));
    chart
        .draw_series(
            inferred
                .iter()
                .map(|(x, y, p)| TriangleMarker::new((*x, *y), 8, ramp(*p).filled())),
        )?
        .label("hidden, inferred")
        .legend(|(x, y)| TriangleMarker::new((x, y), 7, RGBColor(0, 114, 178).filled()));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    chart.draw_series(std::iter::once(Text::new(
        "colour: probability of the true state, vermillion = 0 … blue = 1; black: A and B",
        (x0 + 0.02 * (x1 - x0), y0 + 0.06 * (y1 - y0)),
        ("sans-serif", 12),
    )))?;
    Ok(())
}

/// Every landmark in the frame of one reference pair: observed sets beside inferred ones,
/// coloured by the probability of the true state.
pub fn reference_pair(
    title: &str,
    observed: &[(f64, f64, f64)],
    inferred: &[(f64, f64, f64)],
) -> Result<Picture> {
    both(
        |r| draw_reference_pair(r, title, observed, inferred),
        |r| draw_reference_pair(r, title, observed, inferred),
    )
}
