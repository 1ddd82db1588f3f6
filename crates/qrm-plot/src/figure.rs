//! A study's figure drawn by its kind: the one place that maps [`studies::Plot`] to a picture,
//! so the command line and any other front end draw a report alike.

use studies::{Figure, Plot};

use crate::charts::{Series, edc_scatter, heatmap, histogram, line_chart};
use crate::regions::{RegionPicture, reference_pair, region_map};
use crate::sites::{DemoPicture, demo_picture, runs_map, scenario_map};
use crate::{Picture, Result};

/// Draws a study's figure by its kind.
///
/// # Errors
/// [`crate::PlotError`] for data that cannot be drawn.
pub fn figure(f: &Figure) -> Result<Picture> {
    match &f.plot {
        Plot::Histogram { edges, groups } => histogram(&f.title, &f.x_label, edges, groups),
        Plot::Lines { series } => {
            let series: Vec<Series> = series.iter().map(series_of).collect();
            line_chart(&f.title, &f.x_label, &f.y_label, &series)
        }
        Plot::EdcScatter {
            points,
            colour_label,
        } => edc_scatter(&f.title, points, colour_label),
        Plot::Heatmap { labels, matrix } => heatmap(&f.title, labels, matrix),
        Plot::Regions {
            window,
            nx,
            ny,
            cell_region,
            points,
            shade,
            marks,
            numbers,
        } => {
            let picture = RegionPicture {
                window: *window,
                nx: *nx,
                ny: *ny,
                cell_region,
                points,
                highlight: &[],
                shade: shade.as_deref(),
                marks,
                numbers: *numbers,
            };
            region_map(&f.title, &picture)
        }
        Plot::Site { world, drive, runs } => {
            let runs: Vec<(Vec<(f64, f64)>, bool)> =
                runs.iter().map(|r| (r.points.clone(), r.reached)).collect();
            runs_map(&f.title, world, drive, &runs)
        }
        Plot::Scenario {
            world,
            trajectory,
            rays,
        } => scenario_map(&f.title, world, trajectory, rays),
        Plot::ReferencePair { observed, inferred } => reference_pair(&f.title, observed, inferred),
        Plot::Navigation(n) => navigation(&f.title, n),
    }
}

/// A study's line as the chart's series: a reference line, or a line with error bars.
fn series_of(l: &studies::report::Line) -> Series {
    let s = if l.reference {
        Series::reference(l.name.clone(), l.points.clone())
    } else {
        Series::line(l.name.clone(), l.points.clone())
    };
    match &l.err {
        Some(e) => s.with_err(e.clone()),
        None => s,
    }
}

/// The demo's navigation picture, with the learned calculus's regions beside it.
fn navigation(title: &str, n: &studies::report::NavigationPicture) -> Result<Picture> {
    let panel = n.regions.as_ref().map(|r| {
        (
            r.title.clone(),
            RegionPicture {
                window: r.window,
                nx: r.nx,
                ny: r.ny,
                cell_region: &r.cell_region,
                points: &[],
                highlight: &[],
                shade: None,
                marks: &r.marks,
                numbers: true,
            },
        )
    });
    demo_picture(&DemoPicture {
        title: title.to_owned(),
        world: &n.world,
        drive: &n.drive,
        trajectory: &n.trajectory,
        searches: &n.searches,
        plan: &n.plan,
        links: &n.links,
        start: n.start,
        goal: n.goal,
        regions: panel,
    })
}
