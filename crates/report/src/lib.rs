//! cablab-report: SVG plots (plotters, SVG backend only) and one self-contained HTML report per
//! campaign.
//!
//! The crate is deliberately decoupled from the analysis crates: it defines small view models
//! (plain numbers and strings, SI units) that the pipeline fills from the measure and diagnose
//! results, and turns them into SVG strings and an HTML string. It does no I/O, reads no fonts
//! (only the generic `sans-serif`/`serif`/`monospace` families are named), uses no clock and no
//! randomness: identical input gives identical bytes. Every string that came from an input is
//! escaped before it reaches SVG or HTML.
//!
//! Modules: [`curve`] (per-test curve with fit, yield, loops, simulated and residual panel),
//! [`gap`] (where / which / how far views of the sim-to-real gap, residual along the span),
//! [`campaign`] (stiffness scatter per specimen type, Table 1 and Table 2 style tables),
//! [`grid`] (one table model and number formatter for md, tex, csv and html), [`html`] (the
//! report document), [`words`] (the diagnosis in plain words), [`style`] (sizes, greyscale-safe palette), [`text`]
//! (escaping and number formatting).

#![warn(missing_docs)]

mod axes;
pub mod campaign;
pub mod curve;
pub mod gap;
pub mod grid;
pub mod html;
pub mod style;
pub mod text;
pub mod words;

pub use campaign::{
    campaign_stiffness_svg, mean_sd, overlay_svg, parameter_table, results_table, series_table,
    stiffness_axis_label, stiffness_table, OverlayView, ParameterRow, SeriesStat, SpecimenResult,
    StiffnessGroup, StiffnessRow, StiffnessView,
};
pub use curve::{axis_labels, curve_svg, BranchKind, CurveView, CycleSeries, FitLine};
pub use gap::{
    gap_waterfall_svg, gap_where_svg, gap_which_svg, span_residual_svg, CandidateBar, SpanResidual,
};
pub use grid::{fmt_plain, Cell, CsvLocale, Grid};
pub use html::{render_html, Block, ReportDoc, Table, TestSection};
pub use text::escape_html;
pub use words::{diagnosis_words, DiagnosisSummary};

/// What can go wrong while drawing a plot.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReportError {
    /// x and y of a series have different lengths.
    #[error("{what}: x has {x_len} values but y has {y_len}")]
    LengthMismatch {
        /// Which series.
        what: String,
        /// Number of x values.
        x_len: usize,
        /// Number of y values.
        y_len: usize,
    },
    /// The simulated curve is not on the measured control history point for point.
    #[error(
        "simulated curve has {simulated} points but the measured cycles have {measured}: \
         simulate on the measured control history to get a residual panel"
    )]
    SimulatedLength {
        /// Points in the simulated curve.
        simulated: usize,
        /// Points in all measured cycles together.
        measured: usize,
    },
    /// Nothing finite to plot.
    #[error("nothing to plot: {what} has no finite values")]
    NoData {
        /// What was empty.
        what: String,
    },
    /// plotters failed (should not happen with the in-memory SVG backend).
    #[error("drawing failed: {0}")]
    Draw(String),
}
