//! Pictures of a simulated site from above: a scenario's run with its detection rays, the
//! navigation runs of the field experiment (Fig 4.9), and the demo's run beside the learned
//! calculus's regions.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::canvas::{Drawn, SIZE, both, both_sized, okabe_ito};
use crate::regions::{RegionPicture, draw_regions};
use crate::{Picture, Result};

/// A line segment `(from, to)` in data coordinates.
pub type Segment = ((f64, f64), (f64, f64));

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
    title: &str,
    world: &sim2d::WorldSpec,
    drive: &[(f64, f64)],
    runs: &[(Vec<(f64, f64)>, bool)],
) -> Result<Picture> {
    both(
        |r| draw_runs(r, title, world, drive, runs),
        |r| draw_runs(r, title, world, drive, runs),
    )
}

/// A scenario's world, the robot's true trajectory and some detection rays.
pub fn scenario_map(
    title: &str,
    world: &sim2d::WorldSpec,
    traj: &[(f64, f64)],
    rays: &[Segment],
) -> Result<Picture> {
    both(
        |r| draw_scenario(r, title, world, traj, rays),
        |r| draw_scenario(r, title, world, traj, rays),
    )
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

/// The run over the site: the plan's map elements, the searches, the trajectory, the links
/// found, the start and the goal.
fn draw_run<DB: DrawingBackend>(chart: &mut MetreChart<'_, DB>, p: &DemoPicture<'_>) -> Drawn
where
    DB::ErrorType: 'static,
{
    use okabe_ito::{BLUE, BLUISH_GREEN, ORANGE, REDDISH_PURPLE, VERMILLION};
    let pt = |q: &[f64; 2]| (q[0], q[1]);
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
    Ok(())
}

fn draw_demo<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, p: &DemoPicture<'_>) -> Drawn
where
    DB::ErrorType: 'static,
{
    use okabe_ito::SKY_BLUE;
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
    draw_run(&mut chart, p)?;
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
pub fn demo_picture(picture: &DemoPicture<'_>) -> Result<Picture> {
    let size = if picture.regions.is_some() {
        (1240, 560)
    } else {
        SIZE
    };
    both_sized(size, |r| draw_demo(r, picture), |r| draw_demo(r, picture))
}
