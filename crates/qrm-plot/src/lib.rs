//! # qrm-plot — the figures of qrm, drawn once
//!
//! A study's report holds the *data* of its figures ([`studies::Figure`]); this crate draws
//! them, and the pictures of calculi, sites and region maps that the commands show, into an
//! SVG string and PNG bytes ([`Picture`]). It writes nothing: the command line writes the two
//! files atomically beside the report.
//!
//! ## Why a crate of its own
//! - **The command line stays thin.** Drawing was a fifth of the `qrm` binary's code; a front
//!   end now asks for a picture and writes it.
//! - **Same bytes everywhere.** The SVG and the PNG come from one drawing function run on two
//!   backends, with the bundled font ([`qsr_core::register_font`]), so a figure does not
//!   depend on the machine's fonts or on who asked for it.
//!
//! ## Layout
//! | module | what |
//! |---|---|
//! | [`charts`] | line charts with error bars, the EDC scatter (Fig 2.8), confusion heatmaps (Fig 2.9), histograms |
//! | [`sites`] | a simulated site from above: a scenario's run, navigation runs (Fig 4.9), the demo's picture |
//! | [`regions`] | region maps cell by cell (Figs 3.8–3.10), a reference pair's frame |
//! | [`figure`](mod@figure) | a study's [`studies::Figure`] drawn by its kind |
//!
//! ## Naming rule
//! A public function is named after what it draws (`line_chart`, `region_map`) and returns a
//! [`Picture`]; `draw_*` functions draw on a plotters area and stay inside the crate.
//!
//! ## Errors
//! [`PlotError::Invalid`]: data that cannot be drawn (a histogram without a bin);
//! [`PlotError::Draw`]: plotters or the PNG encoder failed.
//!
//! ```
//! let series = [qrm_plot::Series::line("error", vec![(0.0, 1.0), (1.0, 0.5)])];
//! let p = qrm_plot::line_chart("Error rate", "σ (m)", "rate", &series)?;
//! assert!(p.svg.starts_with("<svg") && p.png.starts_with(b"\x89PNG"));
//! # Ok::<(), qrm_plot::PlotError>(())
//! ```

mod canvas;
pub mod charts;
pub mod figure;
pub mod regions;
pub mod sites;

pub use charts::{Series, edc_scatter, heatmap, histogram, line_chart};
pub use figure::figure;
pub use regions::{RegionPicture, reference_pair, region_map};
pub use sites::{DemoPicture, Segment, demo_picture, runs_map, scenario_map};

/// A drawn picture: the same drawing as SVG text and as PNG bytes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Picture {
    /// `NAME.svg`.
    pub svg: String,
    /// `NAME.png`.
    pub png: Vec<u8>,
}

/// What can go wrong drawing.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlotError {
    /// The data cannot be drawn.
    #[error("cannot draw: {0}")]
    Invalid(String),
    /// plotters or the PNG encoder failed.
    #[error("drawing {0}")]
    Draw(String),
}

/// Shorthand for `Result<T, PlotError>`.
pub type Result<T> = std::result::Result<T, PlotError>;
