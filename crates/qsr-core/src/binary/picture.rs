//! A picture of a binary calculus's partition of directions, as SVG text (no dependencies:
//! rays, labels and the heading arrow are a handful of primitives).

use std::f64::consts::PI;
use std::fmt::Write as _;

use super::calculus::{BinaryCalculus, BinaryFamily};

/// The partition of directions about one point, heading up: rays and sector numbers for
/// OPRA (`i` of `i_j`), sector labels for STAR. `width` is the picture's side in pixels
/// (clamped to 64..=8192).
#[must_use]
pub fn render_binary_svg(c: &BinaryCalculus, width: u32) -> String {
    let w = f64::from(width.clamp(64, 8192));
    let (cx, cy) = (w / 2.0, w / 2.0 + w * 0.03);
    let r = w * 0.36;
    let font = (w / 40.0).max(8.0);
    // Screen coordinates of the direction `theta` (counter-clockwise from the heading, which
    // points up) at distance `d` from the point.
    let at = |theta: f64, d: f64| (cx - d * theta.sin(), cy - d * theta.cos());
    let mut s = String::new();
    let _ = write!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{w}" viewBox="0 0 {w} {w}" font-family="sans-serif">"##
    );
    let _ = write!(s, r##"<rect width="{w}" height="{w}" fill="white"/>"##);
    let _ = write!(
        s,
        r##"<text x="{:.1}" y="{:.1}" font-size="{:.1}" text-anchor="middle">{}</text>"##,
        w / 2.0,
        font * 1.6,
        font * 1.2,
        c.name()
    );
    let _ = write!(
        s,
        r##"<circle cx="{cx:.1}" cy="{cy:.1}" r="{r:.1}" fill="none" stroke="#bbb" stroke-dasharray="4 4"/>"##
    );
    write_sectors(&mut s, c, &at, [cx, cy, r, font]);
    // The heading (OPRA) or shared reference direction (STAR).
    let (hx, hy) = at(0.0, r * 0.45);
    let _ = write!(
        s,
        r##"<line x1="{cx:.1}" y1="{cy:.1}" x2="{hx:.1}" y2="{hy:.1}" stroke="black" stroke-width="3"/><polygon points="{hx:.1},{:.1} {:.1},{:.1} {:.1},{:.1}" fill="black"/><circle cx="{cx:.1}" cy="{cy:.1}" r="{:.1}" fill="black"/>"##,
        hy - font * 0.6,
        hx - font * 0.4,
        hy + font * 0.1,
        hx + font * 0.4,
        hy + font * 0.1,
        font * 0.3
    );
    let caption = match c.family() {
        BinaryFamily::Opra => "heading up; rays (even) and open sectors (odd), counter-clockwise",
        BinaryFamily::Star => {
            "reference direction up; half-open sectors own their clockwise edge; eq: same point"
        }
    };
    let _ = write!(
        s,
        r##"<text x="{:.1}" y="{:.1}" font-size="{:.1}" text-anchor="middle" fill="#555">{caption}</text>"##,
        w / 2.0,
        w - font * 0.8,
        font * 0.75
    );
    s.push_str("</svg>\n");
    s
}

/// The rays and sector labels of `c` about the point at (`cx`, `cy`), rays of length `r`,
/// labels of size `font`; `at(theta, d)` places a direction on the screen.
fn write_sectors(
    s: &mut String,
    c: &BinaryCalculus,
    at: &dyn Fn(f64, f64) -> (f64, f64),
    [cx, cy, r, font]: [f64; 4],
) {
    let m = c.partition().m();
    match c.family() {
        BinaryFamily::Opra => {
            for k in 0..2 * m {
                let theta = k as f64 * PI / m as f64;
                let (x, y) = at(theta, r);
                let _ = write!(
                    s,
                    r##"<line x1="{cx:.1}" y1="{cy:.1}" x2="{x:.1}" y2="{y:.1}" stroke="#1f77b4" stroke-width="2"/>"##
                );
                let (lx, ly) = at(theta, r + font * 1.2);
                let _ = write!(
                    s,
                    r##"<text x="{lx:.1}" y="{:.1}" font-size="{font:.1}" text-anchor="middle" fill="#1f77b4">{}</text>"##,
                    ly + font / 3.0,
                    2 * k
                );
                let (ox, oy) = at(theta + PI / (2.0 * m as f64), r * 0.72);
                let _ = write!(
                    s,
                    r##"<text x="{ox:.1}" y="{:.1}" font-size="{font:.1}" text-anchor="middle">{}</text>"##,
                    oy + font / 3.0,
                    2 * k + 1
                );
            }
        }
        BinaryFamily::Star => {
            for (k, label) in c.labels().iter().take(m).enumerate() {
                let edge = (2 * k + 1) as f64 * PI / m as f64;
                let (x, y) = at(edge, r);
                let _ = write!(
                    s,
                    r##"<line x1="{cx:.1}" y1="{cy:.1}" x2="{x:.1}" y2="{y:.1}" stroke="#1f77b4" stroke-width="2"/>"##
                );
                let (ox, oy) = at(2.0 * k as f64 * PI / m as f64, r * 0.75);
                let _ = write!(
                    s,
                    r##"<text x="{ox:.1}" y="{:.1}" font-size="{:.1}" text-anchor="middle">{}</text>"##,
                    oy + font / 3.0,
                    font * 0.8,
                    label
                );
            }
        }
    }
}
