//! cablab-measure: from curves to numbers — sectional quantities, conditioning, cycles and
//! branches, the elastic stiffness fit, yield point, hysteresis per cycle, behaviour class, and
//! the campaign table (the chapter's Table 1).
//!
//! Plain slices in, numbers out: no files, no printing, no global state, no polars. Everything
//! is SI (the readers convert). The entry point for one test is [`analyze`]; its pieces are
//! public for reuse (one implementation each): [`sectional()`], [`noise_level`],
//! [`turning_points`], [`segment`], [`linear_fit`] (the project's single fitting routine),
//! [`campaign_table`] and its renderers.
//!
//! Module map: [`stats`] (line fit, quantiles) · [`sectional`] (eqs. (1)–(7)) · [`elastica`]
//! (large-deflection three-point) · [`condition`] (noise, offsets, compliance, turning points,
//! segmentation) · [`elastic`] (elastic window, toe, bend) · [`hysteresis`] (per cycle) ·
//! [`analysis`] (one test) · [`table`] (campaign statistics and renderings).

// `!(x > t)` is meant where it reads so: true for NaN as well (a number that failed stays
// out of a comparison that would admit it); clippy's `partial_cmp` rewrite hides that.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![warn(missing_docs)]

pub mod analysis;
pub mod condition;
pub mod elastic;
pub mod elastica;
pub mod hysteresis;
pub mod rate;
pub mod sectional;
pub mod stats;
pub mod table;
pub mod tone;

pub use analysis::{
    analyze, break_is_abrupt, default_yield_offset, last_loading_peak, Analysis, AnalyzeOptions,
    Behaviour, BreakPoint, FitWindowUnit, HoldRelaxation, LargeDeflection, MaxResponse, Noise,
    Piecewise, Stiffness, SuddenDrop, Toe, UnloadingCheck, YieldMethod, YieldPoint, BREAK_DROP,
    DEFAULT_OFFSET_STRAIN, THREE_POINT_GEOMETRY_LIMIT,
};
pub use condition::{
    correct_compliance, labels, noise_level, quantum, resolution, reversal_threshold, segment,
    segment_with, turning_points, zero_offsets, zero_offsets_with, Branch, ChannelNoise, Extremum,
    Label, Offsets, Segment, TurningPoint,
};
pub use elastic::{auto_elastic_range, hinge_fit, user_elastic_range, ElasticRange, Hinge};
pub use elastica::ThreePointElastica;
pub use hysteresis::CycleResult;
pub use sectional::{
    deg_to_rad, modulus_from_stiffness, sectional, sectional_unit, stiffness_from_slope,
    three_point_peak_curvature, three_point_peak_moment, Geometry,
};
pub use stats::{linear_fit, normal_quantile, student_t_quantile, Fit};
pub use table::{campaign_table, render_json, GroupStats, TableRow, GROUP_KEYS};

/// Everything that can go wrong while measuring, with a message that says what and where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeasureError {
    /// Two channels that must be parallel have different lengths.
    #[error("{what} have different lengths ({left} vs {right} samples)")]
    LengthMismatch {
        /// Which channels.
        what: &'static str,
        /// Length of the first.
        left: usize,
        /// Length of the second.
        right: usize,
    },
    /// Not enough samples for a step.
    #[error("too few samples for {what}: need at least {need}, got {got}")]
    TooFewSamples {
        /// Which step.
        what: &'static str,
        /// Minimum.
        need: usize,
        /// Given.
        got: usize,
    },
    /// A NaN or infinity in a channel.
    #[error("non-finite value in {channel} at sample {index}")]
    NonFinite {
        /// Channel name.
        channel: &'static str,
        /// Sample index (0-based).
        index: usize,
    },
    /// All x values equal.
    #[error("linear fit is degenerate: all control values are equal")]
    DegenerateFit,
    /// Free length not positive/finite.
    #[error("free length (span) must be positive and finite, got {0} m")]
    BadLength(f64),
    /// Diameter not positive/finite.
    #[error("diameter must be positive and finite, got {0} m")]
    BadDiameter(f64),
    /// Kind `unknown`.
    #[error("the test kind is unknown: give one of tension, torsion, three_point, pure_bending")]
    UnknownKind,
    /// Poisson ratio out of range.
    #[error("Poisson ratio must lie in (-1, 0.5], got {0}")]
    BadPoisson(f64),
    /// Compliance not finite.
    #[error("machine compliance must be finite, got {0}")]
    BadCompliance(f64),
    /// User window holds too few first-loading samples.
    #[error("fit window [{from}, {to}] holds {n} samples of the first loading; need at least 3")]
    WindowTooSmall {
        /// Window start (sectional control).
        from: f64,
        /// Window end.
        to: f64,
        /// Samples inside.
        n: usize,
    },
    /// No straight range between toe and bend.
    #[error("no straight elastic range between the toe and the bend of the first loading")]
    NoElasticRange,
    /// The control never moves beyond its noise.
    #[error("the control never moves beyond its noise: no first loading to analyse")]
    NoMotion,
    /// The control moves, but its first loading is too short to fit: it turns back (or jumps
    /// back) after a few samples.
    #[error("the first loading holds only {n} sample(s) (complete rows {from}–{to}) before the control turns back: too few to fit; a control that jumps back (a displacement counted from each phase's start) needs a continuous one named with --control")]
    ShortFirstLoading {
        /// Samples in the first loading.
        n: usize,
        /// Its first row (1-based complete row).
        from: usize,
        /// Its last row (1-based complete row).
        to: usize,
    },
}

#[cfg(test)]
mod accuracy_tests;
