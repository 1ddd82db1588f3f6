//! Helpers shared by the integration tests.
#![allow(dead_code)]

use qsr_core::{Calculus, Point2, Shape};

/// Distance from a normalised point to the nearest constraint curve of a calculus
/// (infinite for raster calculi).
pub fn boundary_distance(c: &Calculus, q: &Point2<f64>) -> f64 {
    c.spec()
        .constraints
        .iter()
        .map(|k| match k.shape {
            Shape::Line { a, b, c } => (a * q.x + b * q.y + c).abs() / a.hypot(b),
            Shape::Circle { center, radius } => {
                ((q.x - center[0]).hypot(q.y - center[1]) - radius).abs()
            }
        })
        .fold(f64::INFINITY, f64::min)
}

/// A point exactly on (or within `offset` of) one of the EDC curves, which include the
/// curves of every coarser point calculus.
pub fn near_edc_curve(which: usize, t: f64, offset: f64) -> Point2<f64> {
    match which % 6 {
        0 => Point2::new(offset, t),
        1 => Point2::new(t, offset),
        2 => Point2::new(t, 0.5 + offset),
        3 => Point2::new(t, 1.0 + offset),
        4 => Point2::new((1.0 + offset) * t.cos(), (1.0 + offset) * t.sin()),
        _ => Point2::new((1.0 + offset) * t.cos(), 1.0 + (1.0 + offset) * t.sin()),
    }
}
