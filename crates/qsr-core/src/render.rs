//! SVG pictures of a calculus's partition (feature `svg`): every state filled in its own
//! colour and labelled at its most interior point, constraint curves drawn crisply, and the
//! reference entities marked. Used for the docs (`docs/calculi/`) and `qrm calculus render`.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::calculus::Calculus;
use crate::error::Result;
use crate::frame::FrameKind;
use crate::partition::Partition;
use crate::spec::Shape;

static FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");

/// Options for [`render_svg`].
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// `[x_min, x_max, y_min, y_max]` in normalised coordinates; `None` picks one that shows
    /// every bounded feature.
    pub window: Option<[f64; 4]>,
    /// Picture width in pixels.
    pub width: u32,
    /// Raster cells along x used to fill the states.
    pub resolution: usize,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            window: None,
            width: 640,
            resolution: 320,
        }
    }
}

/// Registers the bundled DejaVu Sans as plotters' `"sans-serif"` (idempotent): every plot
/// of qrm draws text with it, so no system font library is needed.
pub fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // The font is compiled in; registration cannot fail for it.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

fn palette(i: usize) -> RGBColor {
    // Tableau-20 style pastel pairs, then a golden-angle hue walk.
    const P: [(u8, u8, u8); 20] = [
        (174, 199, 232),
        (255, 187, 120),
        (152, 223, 138),
        (255, 152, 150),
        (197, 176, 213),
        (196, 156, 148),
        (247, 182, 210),
        (199, 199, 199),
        (219, 219, 141),
        (158, 218, 229),
        (120, 170, 220),
        (255, 210, 160),
        (190, 235, 180),
        (240, 190, 190),
        (220, 205, 235),
        (225, 200, 190),
        (250, 215, 230),
        (225, 225, 225),
        (235, 235, 175),
        (195, 235, 240),
    ];
    if i < P.len() {
        let (r, g, b) = P[i];
        RGBColor(r, g, b)
    } else {
        let h = (i as f64 * 137.508) % 360.0;
        let c = HSLColor(h / 360.0, 0.55, 0.8);
        let rgb = c.to_backend_color().rgb;
        RGBColor(rgb.0, rgb.1, rgb.2)
    }
}

fn default_window(calculus: &Calculus) -> [f64; 4] {
    match calculus.partition() {
        Partition::Raster(r) => r.window(),
        Partition::Constraints(_) => match calculus.frame() {
            FrameKind::BinaryOriented => [-2.0, 2.0, -2.0, 2.0],
            FrameKind::Ternary | FrameKind::Extended => [-2.2, 2.2, -1.6, 2.6],
        },
    }
}

/// Renders the partition of `calculus` as an SVG document.
///
/// # Errors
/// [`crate::QsrError::Spec`] for an empty window or zero resolution (and should plotters fail).
pub fn render_svg(calculus: &Calculus, options: &RenderOptions) -> Result<String> {
    register_font();
    let window = options.window.unwrap_or_else(|| default_window(calculus));
    let [x0, x1, y0, y1] = window;
    if !window.iter().all(|v| v.is_finite())
        || x1 <= x0
        || y1 <= y0
        || options.resolution == 0
        || options.width < 64
    {
        return Err(crate::error::spec_error(
            calculus.name(),
            format!(
                "cannot render window {window:?} at resolution {}",
                options.resolution
            ),
        ));
    }
    let nx = options.resolution;
    let cell = (x1 - x0) / nx as f64;
    let ny = ((y1 - y0) / cell).ceil() as usize;
    let mut grid = vec![0u16; nx * ny];
    for iy in 0..ny {
        for ix in 0..nx {
            let p =
                nalgebra::Point2::new(x0 + (ix as f64 + 0.5) * cell, y0 + (iy as f64 + 0.5) * cell);
            grid[iy * nx + ix] = calculus.classify_normalised(&p).0;
        }
    }
    let height = (f64::from(options.width) * (y1 - y0) / (x1 - x0)).round() as u32 + 40;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (options.width, height)).into_drawing_area();
        draw(&root, calculus, window, &grid, nx, ny, cell).map_err(|e| {
            crate::error::spec_error(calculus.name(), format!("rendering failed: {e}"))
        })?;
        root.present().map_err(|e| {
            crate::error::spec_error(calculus.name(), format!("rendering failed: {e}"))
        })?;
    }
    Ok(svg)
}

type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

fn draw(
    root: &DrawingArea<SVGBackend<'_>, Shift>,
    calculus: &Calculus,
    [x0, x1, y0, y1]: [f64; 4],
    grid: &[u16],
    nx: usize,
    ny: usize,
    cell: f64,
) -> DrawResult {
    root.fill(&WHITE)?;
    let title = format!("{} — {} states", calculus.name(), calculus.n_states());
    let mut chart = ChartBuilder::on(root)
        .margin(6)
        .caption(title, ("sans-serif", 18))
        .build_cartesian_2d(x0..x1, y0..y1)?;

    let rects = label_runs(grid, nx, ny, [x0, x1, y0, y1], cell);
    chart.draw_series(
        rects
            .into_iter()
            .map(|(xa, ya, xb, yb, s)| Rectangle::new([(xa, ya), (xb, yb)], palette(s).filled())),
    )?;

    // Constraint curves, clipped to the window.
    for run in curve_runs(calculus, [x0, x1, y0, y1]) {
        chart.draw_series(LineSeries::new(run, BLACK.stroke_width(1)))?;
    }

    // Reference entities.
    let marker =
        |x: f64, y: f64, name: &str| -> Vec<DynElement<'static, SVGBackend<'_>, (f64, f64)>> {
            vec![
                Circle::new((x, y), 4, BLACK.filled()).into_dyn(),
                Text::new(
                    name.to_owned(),
                    (x + 0.05, y + 0.05),
                    ("sans-serif", 14).into_font(),
                )
                .into_dyn(),
            ]
        };
    match calculus.frame() {
        FrameKind::Ternary => {
            chart.draw_series(marker(0.0, 0.0, "A"))?;
            chart.draw_series(marker(0.0, 1.0, "B"))?;
        }
        FrameKind::BinaryOriented => {
            chart.draw_series(marker(0.0, 0.0, "A"))?;
            chart.draw_series(LineSeries::new(
                [(0.0, 0.0), (0.0, 0.5)],
                BLACK.stroke_width(3),
            ))?;
        }
        FrameKind::Extended => {
            for x in [-0.4, 0.4] {
                chart.draw_series(LineSeries::new([(x, 0.0), (x, 1.0)], BLACK.stroke_width(4)))?;
            }
        }
    }

    let best = label_cells(grid, nx, ny, calculus.n_states());
    let style =
        TextStyle::from(("sans-serif", 13).into_font()).pos(Pos::new(HPos::Center, VPos::Center));
    for (s, b) in best.iter().enumerate() {
        if let Some((_, i)) = b {
            let (ix, iy) = (i % nx, i / nx);
            let p = (x0 + (ix as f64 + 0.5) * cell, y0 + (iy as f64 + 0.5) * cell);
            chart.draw_series(std::iter::once(Text::new(
                calculus.labels()[s].clone(),
                p,
                style.clone(),
            )))?;
        }
    }
    Ok(())
}

/// The constraint curves of a constraint calculus as the runs of points inside `window`
/// (two or more points each).
fn curve_runs(calculus: &Calculus, [x0, x1, y0, y1]: [f64; 4]) -> Vec<Vec<(f64, f64)>> {
    let Partition::Constraints(c) = calculus.partition() else {
        return Vec::new();
    };
    let inside = |p: &(f64, f64)| p.0 >= x0 && p.0 <= x1 && p.1 >= y0 && p.1 <= y1;
    let mut runs = Vec::new();
    for shape in c.shapes() {
        let pts: Vec<(f64, f64)> = match *shape {
            Shape::Line { a, b, c } => clip_line(a, b, c, [x0, x1, y0, y1]),
            Shape::Circle { center, radius } => (0..=360)
                .map(|k| {
                    let t = f64::from(k).to_radians();
                    (center[0] + radius * t.cos(), center[1] + radius * t.sin())
                })
                .collect(),
        };
        runs.extend(
            pts.split(|p| !inside(p))
                .filter(|run| run.len() >= 2)
                .map(<[(f64, f64)]>::to_vec),
        );
    }
    runs
}

/// One rectangle `(x0, y0, x1, y1, state)` per run of equal labels in a row of the raster.
fn label_runs(
    grid: &[u16],
    nx: usize,
    ny: usize,
    [x0, _, y0, y1]: [f64; 4],
    cell: f64,
) -> Vec<(f64, f64, f64, f64, usize)> {
    let mut rects = Vec::new();
    for iy in 0..ny {
        let mut start = 0;
        for ix in 1..=nx {
            if ix == nx || grid[iy * nx + ix] != grid[iy * nx + start] {
                let s = grid[iy * nx + start];
                let ya = y0 + iy as f64 * cell;
                rects.push((
                    x0 + start as f64 * cell,
                    ya,
                    x0 + ix as f64 * cell,
                    (ya + cell).min(y1),
                    usize::from(s),
                ));
                start = ix;
            }
        }
    }
    rects
}

/// Where each state's label goes: its most interior cell (largest chamfer distance to
/// another state or the window edge), as (distance, cell index).
fn label_cells(grid: &[u16], nx: usize, ny: usize, n_states: usize) -> Vec<Option<(u32, usize)>> {
    let dist = chamfer(grid, nx, ny);
    let mut best: Vec<Option<(u32, usize)>> = vec![None; n_states];
    for (i, (&s, &d)) in grid.iter().zip(&dist).enumerate() {
        let slot = &mut best[usize::from(s)];
        if slot.is_none_or(|(bd, _)| d > bd) {
            *slot = Some((d, i));
        }
    }
    best
}

/// Two-pass 3-4 chamfer distance to the nearest cell of another label or the window edge.
fn chamfer(grid: &[u16], nx: usize, ny: usize) -> Vec<u32> {
    let big = u32::MAX / 2;
    let mut d = vec![big; nx * ny];
    for iy in 0..ny {
        for ix in 0..nx {
            let s = grid[iy * nx + ix];
            let edge = ix == 0 || iy == 0 || ix + 1 == nx || iy + 1 == ny;
            let differs = (ix > 0 && grid[iy * nx + ix - 1] != s)
                || (ix + 1 < nx && grid[iy * nx + ix + 1] != s)
                || (iy > 0 && grid[(iy - 1) * nx + ix] != s)
                || (iy + 1 < ny && grid[(iy + 1) * nx + ix] != s);
            if edge || differs {
                d[iy * nx + ix] = 0;
            }
        }
    }
    let idx = |x: usize, y: usize| y * nx + x;
    for iy in 0..ny {
        for ix in 0..nx {
            let mut v = d[idx(ix, iy)];
            if ix > 0 {
                v = v.min(d[idx(ix - 1, iy)] + 3);
            }
            if iy > 0 {
                v = v.min(d[idx(ix, iy - 1)] + 3);
                if ix > 0 {
                    v = v.min(d[idx(ix - 1, iy - 1)] + 4);
                }
                if ix + 1 < nx {
                    v = v.min(d[idx(ix + 1, iy - 1)] + 4);
                }
            }
            d[idx(ix, iy)] = v;
        }
    }
    for iy in (0..ny).rev() {
        for ix in (0..nx).rev() {
            let mut v = d[idx(ix, iy)];
            if ix + 1 < nx {
                v = v.min(d[idx(ix + 1, iy)] + 3);
            }
            if iy + 1 < ny {
                v = v.min(d[idx(ix, iy + 1)] + 3);
                if ix + 1 < nx {
                    v = v.min(d[idx(ix + 1, iy + 1)] + 4);
                }
                if ix > 0 {
                    v = v.min(d[idx(ix - 1, iy + 1)] + 4);
                }
            }
            d[idx(ix, iy)] = v;
        }
    }
    d
}

/// The part of the line `a·x + b·y + c = 0` inside the window, sampled densely.
fn clip_line(a: f64, b: f64, c: f64, [x0, x1, y0, y1]: [f64; 4]) -> Vec<(f64, f64)> {
    let n = 200;
    if b.abs() > a.abs() {
        (0..=n)
            .map(|k| {
                let x = x0 + (x1 - x0) * f64::from(k) / f64::from(n);
                (x, -(a * x + c) / b)
            })
            .collect()
    } else {
        (0..=n)
            .map(|k| {
                let y = y0 + (y1 - y0) * f64::from(k) / f64::from(n);
                (-(b * y + c) / a, y)
            })
            .collect()
    }
}
