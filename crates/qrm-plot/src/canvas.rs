//! The canvas every picture is drawn on: one drawing function run twice, into an SVG string
//! and into an RGB buffer encoded as PNG, with the bundled font; and the colours shared by the
//! pictures.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::{Picture, PlotError, Result};

/// What a drawing function returns: plotters' errors are boxed, being generic over backends.
pub(crate) type Drawn = std::result::Result<(), Box<dyn std::error::Error>>;

/// The default canvas (pixels).
pub(crate) const SIZE: (u32, u32) = (760, 520);

/// The line colours of the charts (matplotlib's "tab10").
pub(crate) fn colour(i: usize) -> RGBColor {
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

/// Draws with `draw` on the default canvas, as SVG and PNG.
pub(crate) fn both(
    draw: impl Fn(&DrawingArea<SVGBackend<'_>, Shift>) -> Drawn,
    draw_png: impl Fn(&DrawingArea<BitMapBackend<'_>, Shift>) -> Drawn,
) -> Result<Picture> {
    both_sized(SIZE, draw, draw_png)
}

/// [`both`] on a canvas of `size` pixels. The PNG is encoded as plotters' bitmap backend
/// saves a file (the `image` crate's PNG encoder with its defaults), so a picture's bytes do
/// not depend on whether it went to a file or to memory.
pub(crate) fn both_sized(
    size: (u32, u32),
    draw: impl Fn(&DrawingArea<SVGBackend<'_>, Shift>) -> Drawn,
    draw_png: impl Fn(&DrawingArea<BitMapBackend<'_>, Shift>) -> Drawn,
) -> Result<Picture> {
    qsr_core::register_font();
    let failed = |what: &str, e: &dyn std::fmt::Display| PlotError::Draw(format!("{what}: {e}"));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw(&root).map_err(|e| failed("SVG", &e))?;
        root.present().map_err(|e| failed("SVG", &e))?;
    }
    let (w, h) = size;
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        draw_png(&root).map_err(|e| failed("PNG", &e))?;
        root.present().map_err(|e| failed("PNG", &e))?;
    }
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        &rgb,
        w,
        h,
        image::ColorType::Rgb8,
    )
    .map_err(|e| failed("PNG", &e))?;
    Ok(Picture { svg, png })
}

pub(crate) fn pastel(i: usize) -> RGBColor {
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

/// Okabe–Ito colours: distinguishable with every common colour-vision deficiency.
pub(crate) mod okabe_ito {
    use plotters::style::RGBColor;
    pub const ORANGE: RGBColor = RGBColor(230, 159, 0);
    pub const SKY_BLUE: RGBColor = RGBColor(86, 180, 233);
    pub const BLUISH_GREEN: RGBColor = RGBColor(0, 158, 115);
    pub const BLUE: RGBColor = RGBColor(0, 114, 178);
    pub const VERMILLION: RGBColor = RGBColor(213, 94, 0);
    pub const REDDISH_PURPLE: RGBColor = RGBColor(204, 121, 167);
}
