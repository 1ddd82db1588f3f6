//! Plots for the study reports: each figure is drawn once, generically over the plotters
//! backend, and written as both `NAME.svg` and `NAME.png` (atomically: temporary file and
//! rename), with the bundled font so no system font library is needed.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

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
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            err: None,
            dashed: false,
        }
    }

    /// A dashed reference line.
    pub fn reference(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            err: None,
            dashed: true,
        }
    }

    /// With error bars.
    pub fn with_err(mut self, err: Vec<f64>) -> Self {
        self.err = Some(err);
        self
    }
}

type Drawn = std::result::Result<(), Box<dyn std::error::Error>>;

/// A line segment `(from, to)` in data coordinates.
pub type Segment = ((f64, f64), (f64, f64));

const SIZE: (u32, u32) = (760, 520);

fn colour(i: usize) -> RGBColor {
    const C: [RGBColor; 8] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
    ];
    C[i % C.len()]
}

/// Draws with `draw` into `stem.svg` and `stem.png`.
fn both(
    stem: &Path,
    draw: impl Fn(&DrawingArea<SVGBackend<'_>, Shift>) -> Drawn,
    draw_png: impl Fn(&DrawingArea<BitMapBackend<'_>, Shift>) -> Drawn,
) -> Result<Vec<PathBuf>> {
    both_sized(stem, SIZE, draw, draw_png)
}

/// [`both`] on a canvas of `size` pixels.
fn both_sized(
    stem: &Path,
    size: (u32, u32),
    draw: impl Fn(&DrawingArea<SVGBackend<'_>, Shift>) -> Drawn,
    draw_png: impl Fn(&DrawingArea<BitMapBackend<'_>, Shift>) -> Drawn,
) -> Result<Vec<PathBuf>> {
    qsr_core::register_font();
    let svg_path = stem.with_extension("svg");
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw(&root).map_err(|e| anyhow::anyhow!("drawing {}: {e}", svg_path.display()))?;
        root.present()
            .map_err(|e| anyhow::anyhow!("drawing {}: {e}", svg_path.display()))?;
    }
    crate::output::write_atomic(&svg_path, svg.as_bytes())?;
    let png_path = stem.with_extension("png");
    let name = png_path
        .file_name()
        .context("plot path has no file name")?
        .to_string_lossy()
        .into_owned();
    let tmp = png_path.with_file_name(format!(".{name}.tmp.png"));
    {
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
        draw_png(&root).map_err(|e| anyhow::anyhow!("drawing {}: {e}", png_path.display()))?;
        root.present()
            .map_err(|e| anyhow::anyhow!("writing {}: {e}", png_path.display()))?;
    }
    std::fs::rename(&tmp, &png_path).with_context(|| format!("writing {}", png_path.display()))?;
    Ok(vec![svg_path, png_path])
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
pub fn line_chart(
    stem: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<Vec<PathBuf>> {
    both(
        stem,
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
pub fn edc_scatter(
    stem: &Path,
    title: &str,
    pts: &[(f64, f64, f64)],
    colour_label: &str,
) -> Result<Vec<PathBuf>> {
    both(
        stem,
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
pub fn heatmap(
    stem: &Path,
    title: &str,
    labels: &[String],
    matrix: &[Vec<u64>],
) -> Result<Vec<PathBuf>> {
    both(
        stem,
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
    stem: &Path,
    title: &str,
    x_label: &str,
    edges: &[f64],
    groups: &[(String, Vec<f64>)],
) -> Result<Vec<PathBuf>> {
    anyhow::ensure!(edges.len() >= 2, "a histogram needs at least one bin");
    both(
        stem,
        |r| draw_hist(r, title, x_label, edges, groups),
        |r| draw_hist(r, title, x_label, edges, groups),
    )
}

/// A chart in metres on both axes.
type MetreChart<'a, DB> = ChartContext<
    'a,
    DB,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// A chart over a world's bounds with equal scales on both axes, and its half-width (m).
fn world_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    w: &sim2d::WorldSpec,
) -> std::result::Result<(MetreChart<'a, DB>, f64), DrawingAreaErrorKind<DB::ErrorType>>
where
    DB::ErrorType: 'static,
{
    let [x0, x1, y0, y1] = w.bounds;
    let (dx, dy) = (x1 - x0, y1 - y0);
    let (w_px, h_px) = root.dim_in_pixel();
    let aspect =
        f64::from(w_px.saturating_sub(60).max(1)) / f64::from(h_px.saturating_sub(60).max(1));
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let (hx, hy) = if dx / dy > aspect {
        (dx / 2.0, dx / aspect / 2.0)
    } else {
        (dy * aspect / 2.0, dy / 2.0)
    };
    let chart = ChartBuilder::on(root)
        .margin(12)
        .caption(title, ("sans-serif", 20))
        .x_label_area_size(30)
        .y_label_area_size(40)
        .build_cartesian_2d((cx - hx)..(cx + hx), (cy - hy)..(cy + hy))?;
    Ok((chart, hx))
}

/// [`world_chart`] with its axes drawn, and the pixels per metre (for discs drawn to scale).
fn world_axes<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    title: &str,
    w: &sim2d::WorldSpec,
) -> std::result::Result<(MetreChart<'a, DB>, f64), DrawingAreaErrorKind<DB::ErrorType>>
where
    DB::ErrorType: 'static,
{
    let (mut chart, hx) = world_chart(area, title, w)?;
    chart
        .configure_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .light_line_style(WHITE)
        .draw()?;
    let px_per_m = f64::from(area.dim_in_pixel().0.saturating_sub(60)) / (2.0 * hx);
    Ok((chart, px_per_m))
}

fn draw_scenario<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    w: &sim2d::WorldSpec,
    traj: &[(f64, f64)],
    rays: &[Segment],
) -> Drawn
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (mut chart, px_per_m) = world_axes(root, title, w)?;
    let disc = |r: f64| ((r * px_per_m).round() as i32).max(2);
    chart.draw_series(rays.iter().map(|(a, b)| {
        PathElement::new(
            vec![*a, *b],
            RGBColor(255, 170, 60).mix(0.35).stroke_width(1),
        )
    }))?;
    chart.draw_series(w.clutter.iter().map(|c| {
        Circle::new(
            (c.pos[0], c.pos[1]),
            disc(c.radius),
            RGBColor(160, 130, 100).mix(0.6).filled(),
        )
    }))?;
    chart.draw_series(w.walls.iter().map(|l| {
        PathElement::new(
            vec![(l.start[0], l.start[1]), (l.end[0], l.end[1])],
            RGBColor(90, 90, 90).stroke_width(4),
        )
    }))?;
    chart.draw_series(w.landmarks.iter().map(|l| {
        Circle::new(
            (l.pos[0], l.pos[1]),
            disc(l.radius),
            RGBColor(30, 130, 60).filled(),
        )
    }))?;
    chart.draw_series(std::iter::once(PathElement::new(
        traj.to_vec(),
        RGBColor(31, 119, 180).stroke_width(2),
    )))?;
    if let Some(&(x, y)) = traj.first() {
        chart.draw_series(std::iter::once(Circle::new(
            (x, y),
            5,
            RGBColor(31, 119, 180).filled(),
        )))?;
    }
    Ok(())
}

fn draw_runs<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    w: &sim2d::WorldSpec,
    drive: &[(f64, f64)],
    runs: &[(Vec<(f64, f64)>, bool)],
) -> Drawn
where
    DB::ErrorType: 'static,
{
    draw_scenario(root, title, w, drive, &[])?;
    // the same chart as draw_scenario (same title space, so the same mapping), drawn over it
    let (mut chart, _) = world_chart(root, title, w)?;
    for (i, (path, ok)) in runs.iter().enumerate() {
        let colour = if *ok {
            Palette99::pick(i).mix(0.8)
        } else {
            RGBColor(220, 30, 30).mix(0.9)
        };
        if *ok {
            chart.draw_series(std::iter::once(PathElement::new(
                path.clone(),
                colour.stroke_width(2),
            )))?;
        } else {
            // failures dashed, as in the thesis's Fig 4.9
            chart.draw_series(
                path.chunks(2)
                    .step_by(2)
                    .map(|c| PathElement::new(c.to_vec(), colour.stroke_width(2))),
            )?;
        }
        if let Some(&(x, y)) = path.first() {
            chart.draw_series(std::iter::once(Circle::new((x, y), 3, colour.filled())))?;
        }
    }
    Ok(())
}

/// Navigation runs over a scenario's world: the mapping drive (blue), successful runs
/// (solid, one colour each) and failed runs (dashed red), as in thesis Fig 4.9.
pub fn runs_map(
    stem: &Path,
    title: &str,
    world: &sim2d::WorldSpec,
    drive: &[(f64, f64)],
    runs: &[(Vec<(f64, f64)>, bool)],
) -> Result<Vec<PathBuf>> {
    both(
        stem,
        |r| draw_runs(r, title, world, drive, runs),
        |r| draw_runs(r, title, world, drive, runs),
    )
}

/// A scenario's world, the robot's true trajectory and some detection rays.
pub fn scenario_map(
    stem: &Path,
    title: &str,
    world: &sim2d::WorldSpec,
    traj: &[(f64, f64)],
    rays: &[Segment],
) -> Result<Vec<PathBuf>> {
    both(
        stem,
        |r| draw_scenario(r, title, world, traj, rays),
        |r| draw_scenario(r, title, world, traj, rays),
    )
}

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

fn pastel(i: usize) -> RGBColor {
    // golden-angle hues, light: many regions stay distinguishable
    let h = (i as f64 * 137.508) % 360.0;
    let (s, l) = (0.55, 0.78);
    let c = (1.0 - (2.0 * l - 1.0_f64).abs()) * s;
    let x = c * (1.0 - ((h / 60.0) % 2.0 - 1.0).abs());
    let (r, g, b) = match (h / 60.0) as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = l - c / 2.0;
    let to = |v: f64| ((v + m) * 255.0).round().clamp(0.0, 255.0) as u8;
    RGBColor(to(r), to(g), to(b))
}

fn draw_regions<DB: DrawingBackend>(
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
    // one rectangle per run of equal cells in a row keeps the SVG small
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
    chart.draw_series(rects)?;
    // region borders
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
    chart.draw_series(lines)?;
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
        chart.draw_series(
            acc.iter()
                .enumerate()
                .filter(|(_, a)| a.2 > 0)
                .map(|(r, a)| {
                    Text::new(
                        (r + 1).to_string(),
                        (a.0 / a.2 as f64, a.1 / a.2 as f64),
                        ("sans-serif", 13).into_font().color(&BLACK),
                    )
                }),
        )?;
    }
    Ok(())
}

/// A salient-region map with data overlaid.
pub fn region_map(stem: &Path, title: &str, picture: &RegionPicture<'_>) -> Result<Vec<PathBuf>> {
    both(
        stem,
        |r| draw_regions(r, title, picture),
        |r| draw_regions(r, title, picture),
    )
}

/// The EDC's line AB, the perpendiculars at A, B and the midpoint, and the unit circles about
/// A and B, in the normalised frame.
fn draw_edc_guides<DB: DrawingBackend>(
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
    stem: &Path,
    title: &str,
    observed: &[(f64, f64, f64)],
    inferred: &[(f64, f64, f64)],
) -> Result<Vec<PathBuf>> {
    both(
        stem,
        |r| draw_reference_pair(r, title, observed, inferred),
        |r| draw_reference_pair(r, title, observed, inferred),
    )
}

/// Okabe–Ito colours: distinguishable with every common colour-vision deficiency.
mod okabe_ito {
    use plotters::style::RGBColor;
    pub const ORANGE: RGBColor = RGBColor(230, 159, 0);
    pub const SKY_BLUE: RGBColor = RGBColor(86, 180, 233);
    pub const BLUISH_GREEN: RGBColor = RGBColor(0, 158, 115);
    pub const BLUE: RGBColor = RGBColor(0, 114, 178);
    pub const VERMILLION: RGBColor = RGBColor(213, 94, 0);
    pub const REDDISH_PURPLE: RGBColor = RGBColor(204, 121, 167);
}

/// What the demo's picture shows: the run over the world (left) and the learned calculus's
/// regions (right).
pub struct DemoPicture<'a> {
    /// Title of the world panel.
    pub title: String,
    /// The world.
    pub world: &'a sim2d::WorldSpec,
    /// The mapping drive (thin, light).
    pub drive: &'a [[f64; 2]],
    /// The navigation's trajectory.
    pub trajectory: &'a [[f64; 2]],
    /// Index ranges of `trajectory` spent searching for a link (inclusive).
    pub searches: &'a [[usize; 2]],
    /// The first plan's elements as triangles of their landmarks' positions.
    pub plan: &'a [[[f64; 2]; 3]],
    /// Positions of the links the plan searched for.
    pub links: &'a [[f64; 2]],
    /// Start position.
    pub start: [f64; 2],
    /// Goal landmark position.
    pub goal: [f64; 2],
    /// The learned calculus's regions, with the panel's title.
    pub regions: Option<(String, RegionPicture<'a>)>,
}

fn draw_demo<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, p: &DemoPicture<'_>) -> Drawn
where
    DB::ErrorType: 'static,
{
    use okabe_ito::{BLUE, BLUISH_GREEN, ORANGE, REDDISH_PURPLE, SKY_BLUE, VERMILLION};
    root.fill(&WHITE)?;
    let (w_px, _) = root.dim_in_pixel();
    let (left, right) = if p.regions.is_some() {
        root.split_horizontally(w_px * 64 / 100)
    } else {
        root.split_horizontally(w_px)
    };
    let w = p.world;
    let (mut chart, px_per_m) = world_axes(&left, &p.title, w)?;
    let disc = |r: f64| ((r * px_per_m).round() as i32).max(2);
    let pt = |q: &[f64; 2]| (q[0], q[1]);
    chart.draw_series(
        w.clutter
            .iter()
            .map(|c| Circle::new(pt(&c.pos), disc(c.radius), RGBColor(205, 190, 165).filled())),
    )?;
    chart
        .draw_series(w.walls.iter().map(|l| {
            PathElement::new(
                vec![pt(&l.start), pt(&l.end)],
                RGBColor(80, 80, 80).stroke_width(4),
            )
        }))?
        .label("walls")
        .legend(|(x, y)| {
            PathElement::new(
                vec![(x, y), (x + 16, y)],
                RGBColor(80, 80, 80).stroke_width(4),
            )
        });
    chart
        .draw_series(w.landmarks.iter().map(|l| {
            Circle::new(
                pt(&l.pos),
                disc(l.radius).max(3),
                RGBColor(120, 120, 120).filled(),
            )
        }))?
        .label("landmarks")
        .legend(|(x, y)| Circle::new((x + 8, y), 3, RGBColor(120, 120, 120).filled()));
    chart
        .draw_series(std::iter::once(PathElement::new(
            p.drive.iter().map(pt).collect::<Vec<_>>(),
            SKY_BLUE.stroke_width(1),
        )))?
        .label("mapping drive")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], SKY_BLUE.stroke_width(1)));
    chart
        .draw_series(p.plan.iter().map(|t| {
            Polygon::new(
                t.iter().map(pt).collect::<Vec<_>>(),
                BLUE.mix(0.12).filled(),
            )
        }))?
        .label("plan: map elements")
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 16, y + 5)], BLUE.mix(0.3).filled()));
    chart.draw_series(p.plan.iter().map(|t| {
        let mut v: Vec<(f64, f64)> = t.iter().map(pt).collect();
        v.push(pt(&t[0]));
        PathElement::new(v, BLUE.stroke_width(2))
    }))?;
    chart
        .draw_series(p.searches.iter().filter_map(|&[a, b]| {
            let seg = p
                .trajectory
                .get(a..=b.min(p.trajectory.len().saturating_sub(1)))?;
            Some(PathElement::new(
                seg.iter().map(pt).collect::<Vec<_>>(),
                ORANGE.stroke_width(4),
            ))
        }))?
        .label("searching for a link (POMDP arcs, circles)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], ORANGE.stroke_width(4)));
    chart
        .draw_series(std::iter::once(PathElement::new(
            p.trajectory.iter().map(pt).collect::<Vec<_>>(),
            BLACK.stroke_width(1),
        )))?
        .label("trajectory")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(1)));
    chart
        .draw_series(
            p.links
                .iter()
                .map(|q| TriangleMarker::new(pt(q), 7, VERMILLION.filled())),
        )?
        .label("links found")
        .legend(|(x, y)| TriangleMarker::new((x + 8, y), 6, VERMILLION.filled()));
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [
                (p.start[0] - 2.0, p.start[1] - 2.0),
                (p.start[0] + 2.0, p.start[1] + 2.0),
            ],
            BLUISH_GREEN.filled(),
        )))?
        .label("start")
        .legend(|(x, y)| Rectangle::new([(x + 3, y - 5), (x + 13, y + 5)], BLUISH_GREEN.filled()));
    chart
        .draw_series(std::iter::once(Circle::new(
            pt(&p.goal),
            8,
            REDDISH_PURPLE.filled(),
        )))?
        .label("goal landmark")
        .legend(|(x, y)| Circle::new((x + 8, y), 6, REDDISH_PURPLE.filled()));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()?;
    if let Some((title, regions)) = &p.regions {
        draw_regions(&right, title, regions)?;
    }
    Ok(())
}

/// The demo's picture (see [`DemoPicture`]).
pub fn demo_picture(stem: &Path, picture: &DemoPicture<'_>) -> Result<Vec<PathBuf>> {
    let size = if picture.regions.is_some() {
        (1240, 560)
    } else {
        SIZE
    };
    both_sized(
        stem,
        size,
        |r| draw_demo(r, picture),
        |r| draw_demo(r, picture),
    )
}
