//! `analyze`: one test from curves to the chapter's results (the `cablab analyze --json` object).
//!
//! Pipeline: validate → machine-compliance correction → zero offsets → orientation (a test
//! whose first motion is negative is mirrored for the fits and mirrored back for the report) →
//! segmentation → elastic window and stiffness on the first loading (eqs. (1)–(5)) → toe and
//! bend → per-cycle hysteresis → behaviour class → modulus (eqs. (6)–(7)) → three-point
//! large-deflection check.
//!
//! Three-point bending on sliding supports is geometrically nonlinear: the exact elastic
//! elastica is already 1.3 % softer than eq. (3) at w/l₀ = 0.036 (the chapter's 2 mm test over
//! 56 mm), a smooth softening that a straight-line analysis would take for a material threshold.
//! So the first loading of a three-point test is analysed against the elastica-corrected
//! deflection w* = w·ρ(w/l₀) ([`ThreePointElastica::corrected_deflection`]), in which a linear
//! elastic rod is exactly linear at any deflection: a bend found there is material (yield or a
//! piecewise threshold), and the slope is the exact (EI)_B (eq. (3) in the small-deflection
//! limit, where w* = w). Every position reported (window, yield, threshold, toe) is mapped back
//! to the punch deflection w; `large_deflection.small_deflection_stiffness` keeps what eq. (3)
//! gives on the same window. The first loading is analysed only up to where geometry alone
//! softens the force by 10 % ([`THREE_POINT_GEOMETRY_LIMIT`], w/l₀ ≈ 0.1, the rod turned by
//! ~17° at the supports) past contact: beyond that the idealisation of point supports the rod slides over
//! without friction is too far from a real rig for the correction to separate material from
//! geometry (dividing by ρ then amplifies every modelling error into a spurious stiffening).
//! A slack or gap before the punch meets the specimen is no deflection: when the first loading's
//! elastic line meets zero force beyond a twentieth of the small-deflection limit, w counts
//! from there (toe compensation, as ISO 178 and ASTM D790 do), for the correction, the limits
//! and the large-deflection check alike, and a note gives the contact.
//!
//! Rules of the behaviour class (`Behaviour`):
//! * every cycle's loading and unloading coincide and no residual deformation → reversible:
//!   `linear_elastic` without a bend in the first loading, `piecewise_linear_elastic` with one;
//! * a bend, loops that do not close and a significant residual deformation → `elastoplastic`;
//! * no unloading at all (a monotonic test): straight → `linear_elastic`; a bend →
//!   `elastoplastic`, with a warning that a reversible threshold cannot be ruled out;
//! * anything else (loops without a bend: friction, viscosity, drift) → `other`;
//! * holds whose response relaxes (falls after a loading ramp, recovers after an unloading
//!   one; at least two such holds, or the only hold, and no hold trending the other way) →
//!   `rate_dependent`, over any of the above ([`HoldRelaxation`]); without such holds, strokes
//!   at different rates whose stiffness near their reversals differs beyond what a drifting
//!   sensor explains ([`crate::rate`]) → `rate_dependent` over `other` and `elastoplastic`;
//! * an abrupt break (the response falls from 90 % of its maximum below [`BREAK_DROP`] of it
//!   within 5 samples or 2 % of the record, and stays there; in a cyclic record that breaks in
//!   a later, smaller cycle than its largest, the same from the peak of its last loading,
//!   [`last_loading_peak`]) → `broken`, whatever came before it (the yield point and stiffness
//!   are still reported).
//!
//! Noise: the response noise is modelled as AR(1) over the whole record
//! ([`crate::condition::serial_noise`] of response − k · control), so serially correlated
//! noise (a logger's filter, AR(1), decimated exports) neither narrows the stiffness interval
//! ([`crate::stats::linear_fit_ar1`], exact for the window's samples) nor moves the window,
//! fakes a hold's relaxation or a break. Does not classify rate dependence from a test run at
//! one rate without a hold of ≥ 20 samples (nothing in it shows one).
//!
//! A bend counts only where the slope falls by at least [`BEND_MIN_DROP`] and stays down to the
//! end of the envelope: a few per cent of seating softening or an extensometer slip, which a
//! quiet load cell makes statistically significant, is no yield. The yield point is the bend of
//! an `elastoplastic` (or unjudgeable) test, at the response the envelope carried there; a
//! reversible bend is reported as the piecewise threshold K_t instead. Three-point: the
//! automatic window stays within the small-deflection range when the first loading has an
//! elastic range there. Pure: numbers in, numbers out.

use crate::condition::{
    correct_compliance, glitches_with, noise_level, reversal_threshold_with, segment_with,
    zero_offsets_with, Branch, ChannelNoise, Offsets, Segment,
};
use crate::elastic::{
    auto_elastic_range_ar1, auto_elastic_range_searched, user_elastic_range, ElasticRange, Hinge,
};
use crate::elastica::ThreePointElastica;
use crate::hysteresis::{cycles, CycleInputs, CycleResult};
use crate::sectional::{
    modulus_from_stiffness, sectional, sectional_unit, stiffness_factor,
    three_point_peak_curvature, three_point_peak_moment, Geometry,
};
use crate::stats::linear_fit;
use crate::MeasureError;
use cablab_core::TestKind;
use serde::Serialize;
use std::collections::BTreeMap;

/// Three-point: the first loading is analysed up to the deflection where the exact elastica on
/// sliding supports is this fraction softer than eq. (3) (see the module doc).
pub const THREE_POINT_GEOMETRY_LIMIT: f64 = 0.1;

/// Options of [`analyze`].
#[derive(Debug, Clone, PartialEq)]
pub struct AnalyzeOptions {
    /// Poisson ratio for the torsion modulus, G = E/(2(1+ν)) (eq. (7)); 0.5 by default.
    pub nu: f64,
    /// User-set elastic window `(from, to)` in the kind's sectional control (SI: strain, 1/m,
    /// deflection m); automatic when None.
    pub fit_window: Option<(f64, f64)>,
    /// Unit of `fit_window` ([`FitWindowUnit::Control`] by default).
    pub fit_window_unit: FitWindowUnit,
    /// Machine compliance in control units per response unit (m/N for tension and three-point,
    /// rad/(N m) for torsion and pure bending), removed before anything else.
    pub compliance_m_per_n: Option<f64>,
    /// Remove the control and response offsets of the leading samples at rest (default true).
    pub zero_offsets: bool,
    /// Relative error of eq. (3) beyond which a three-point deflection counts as large (0.01).
    pub small_deflection_tolerance: f64,
    /// How the yield point is found ([`YieldMethod::Auto`] by default).
    pub yield_method: YieldMethod,
    /// A flat specimen's section b × h (sheet, strip, printed beam): when set, the moduli use
    /// its A, I and Saint-Venant J_t and the default offset its outer fibre, in place of the
    /// round section of `Geometry::diameter_m` (None by default).
    pub flat_section: Option<cablab_core::RectangularSection>,
    /// The record was cut short of the test's end (an extensometer taken off): a bend with
    /// fewer than max(5, a tenth of the first loading's) samples beyond it is not shown by the
    /// record, and is not taken as one (no yield, no threshold; false by default).
    pub cut_short: bool,
}

/// What the numbers of a user-set fit window are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FitWindowUnit {
    /// The kind's sectional control (strain, 1/m, or deflection m for three-point).
    #[default]
    Control,
    /// The response (N or N m), on the rise of the virgin envelope to its maximum.
    Response,
    /// Percent of the maximum response, on the rise of the virgin envelope to its maximum.
    PercentOfMax,
}

/// How the yield point is found (`--yield-method`, pipeline key `yield_method`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum YieldMethod {
    /// The bend of the virgin envelope: the first loading followed by every later loading
    /// beyond all earlier extremes, so a test whose amplitude grows step by step yields at
    /// the first loading beyond the previous maximum (`auto`).
    #[default]
    Auto,
    /// The bend of the first loading path only (`first-loading`; the method before the
    /// envelope).
    FirstLoading,
    /// Offset yield: where the virgin envelope meets the elastic line shifted by this offset
    /// in the kind's sectional control (strain for tension, 1/m for torsion and pure bending,
    /// m for three-point), e.g. `offset:0.002` (0.2 % strain) (`offset:<value>`).
    Offset(f64),
    /// Offset yield with the default offset of the kind ([`default_yield_offset`]: 0.2 %
    /// plastic strain at the surface, ISO 6892-1's Rp0.2) (`offset` without a value).
    OffsetDefault,
}

/// Plastic strain of the default offset yield: 0.2 % (ISO 6892-1 Rp0.2, ISO 527).
pub const DEFAULT_OFFSET_STRAIN: f64 = 0.002;

/// The default offset of [`YieldMethod::OffsetDefault`] in the kind's sectional control, and
/// how it was set: the analogue of ISO 6892-1's Rp0.2 for each kind, a plastic strain of
/// [`DEFAULT_OFFSET_STRAIN`] where the specimen strains most:
/// * tension: the axial strain ε = 0.002;
/// * pure bending: the surface strain (d/2) κ = 0.002, so κ = 0.004/d (1/m);
/// * torsion: the surface shear strain (d/2) K₃ = γ with the same von Mises equivalent plastic
///   strain, γ = √3 · 0.002, so K₃ = 2√3 · 0.002/d (1/m);
/// * three-point: the small-deflection peak surface strain (d/2) · 12 w/l₀² = 0.002, so
///   w = 0.002 l₀²/(6 d) (m).
///
/// Errors (with why) when the kind needs the diameter and it is not known.
pub fn default_yield_offset(kind: TestKind, geom: &Geometry) -> Result<(f64, String), String> {
    default_yield_offset_in(kind, geom, None)
}

/// [`default_yield_offset`] on a flat section b × h when `flat` is set: the outer fibre h/2 of
/// bending takes the place of d/2 (κ = 0.004/h, w = 0.002 l₀²/(6 h)), and in torsion the
/// largest surface shear strain per twist rate ([`cablab_core::RectangularSection::max_shear_strain_per_twist`],
/// c_γ) that of d/2 (K₃ = √3 · 0.002/c_γ).
pub fn default_yield_offset_in(
    kind: TestKind,
    geom: &Geometry,
    flat: Option<&cablab_core::RectangularSection>,
) -> Result<(f64, String), String> {
    let e = DEFAULT_OFFSET_STRAIN;
    if kind == TestKind::Tension {
        return Ok((e, "default: 0.2 % axial strain (ISO 6892-1 Rp0.2)".into()));
    }
    if let Some(s) = flat {
        let h = s.thickness_m;
        return match kind {
            TestKind::PureBending => Ok((
                2.0 * e / h,
                "default: 0.2 % surface strain of the flat section, curvature 2·0.002/h (ISO 6892-1 Rp0.2 analogue)".into(),
            )),
            TestKind::ThreePoint => Ok((
                e * geom.free_length_m.powi(2) / (6.0 * h),
                "default: 0.2 % small-deflection peak surface strain of the flat section, deflection 0.002·l0²/(6 h) (ISO 6892-1 Rp0.2 analogue)".into(),
            )),
            TestKind::Torsion => Ok((
                3f64.sqrt() * e / s.max_shear_strain_per_twist(),
                "default: largest surface shear strain of the flat section √3·0.2 % (von Mises equivalent of 0.2 % plastic strain; Saint-Venant, middle of the longer side) (ISO 6892-1 Rp0.2 analogue)".into(),
            )),
            _ => Err("no default offset for an unknown kind".into()),
        };
    }
    let Some(d) = geom.diameter_m.filter(|d| *d > 0.0) else {
        return Err(format!(
            "the default offset (0.2 % plastic strain at the surface) of a {} test needs the diameter: give it, or an explicit offset:<value>",
            kind.as_str()
        ));
    };
    match kind {
        TestKind::PureBending => Ok((
            2.0 * e / d,
            "default: 0.2 % surface strain, curvature 2·0.002/d (ISO 6892-1 Rp0.2 analogue)".into(),
        )),
        TestKind::Torsion => Ok((
            2.0 * 3f64.sqrt() * e / d,
            "default: surface shear strain √3·0.2 % (von Mises equivalent of 0.2 % plastic strain), twist 2√3·0.002/d (ISO 6892-1 Rp0.2 analogue)".into(),
        )),
        TestKind::ThreePoint => Ok((
            e * geom.free_length_m.powi(2) / (6.0 * d),
            "default: 0.2 % small-deflection peak surface strain, deflection 0.002·l0²/(6 d) (ISO 6892-1 Rp0.2 analogue)".into(),
        )),
        _ => Err("no default offset for an unknown kind".into()),
    }
}

impl YieldMethod {
    /// Contract spelling of the method actually used (JSON `yield.method`).
    pub fn as_str(self) -> &'static str {
        match self {
            YieldMethod::Auto => "envelope_bend",
            YieldMethod::FirstLoading => "first_loading_bend",
            YieldMethod::Offset(_) | YieldMethod::OffsetDefault => "offset",
        }
    }
}

impl std::str::FromStr for YieldMethod {
    type Err = String;
    /// `auto`, `first-loading` (or `first_loading`), `offset` (the kind's default offset,
    /// [`default_yield_offset`]), `offset:<value>` (value > 0).
    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim().to_lowercase();
        match t.as_str() {
            "auto" => return Ok(YieldMethod::Auto),
            "first-loading" | "first_loading" => return Ok(YieldMethod::FirstLoading),
            "offset" => return Ok(YieldMethod::OffsetDefault),
            _ => {}
        }
        if let Some(v) = t.strip_prefix("offset:") {
            if let Ok(x) = v.trim().parse::<f64>() {
                if x.is_finite() && x > 0.0 {
                    return Ok(YieldMethod::Offset(x));
                }
            }
        }
        Err(format!(
            "yield method {s:?}: expected auto, first-loading, offset (0.2 % plastic strain at the surface) or offset:<value> (value > 0 in the kind's sectional control, e.g. offset:0.002 for 0.2 % strain)"
        ))
    }
}

impl Default for AnalyzeOptions {
    fn default() -> Self {
        AnalyzeOptions {
            nu: 0.5,
            fit_window: None,
            fit_window_unit: FitWindowUnit::Control,
            compliance_m_per_n: None,
            zero_offsets: true,
            small_deflection_tolerance: 0.01,
            yield_method: YieldMethod::default(),
            flat_section: None,
            cut_short: false,
        }
    }
}

/// Behaviour class of a test (chapter Sect. 2.3/3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Behaviour {
    /// Straight and reversible (CFRP rods).
    LinearElastic,
    /// Reversible with a slope change at a threshold (Bowden cables, eq. (19)).
    PiecewiseLinearElastic,
    /// Yield, hardening, open loops, residual deformation (cables).
    Elastoplastic,
    /// The response depends on the loading rate: it relaxes toward zero at held control
    /// after a loading ramp and recovers after an unloading one (viscoelastic or viscoplastic;
    /// see [`HoldRelaxation::relaxes`]; takes precedence over the rate-independent classes),
    /// or, without such holds, strokes at different rates differ in stiffness near their
    /// reversals beyond what a drift explains while the loops do not close ([`crate::rate`];
    /// overrides `other` and `elastoplastic`).
    RateDependent,
    /// None of the above (friction loops, drift, rate dependence shown neither by a hold nor
    /// by strokes at different rates, or not enough data).
    Other,
    /// The specimen broke abruptly ([`Analysis::break_point`] says where; a gradual fall keeps
    /// its class and the warning); the class before the break is not judged.
    Broken,
}

impl Behaviour {
    /// Contract spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            Behaviour::LinearElastic => "linear_elastic",
            Behaviour::PiecewiseLinearElastic => "piecewise_linear_elastic",
            Behaviour::Elastoplastic => "elastoplastic",
            Behaviour::RateDependent => "rate_dependent",
            Behaviour::Other => "other",
            Behaviour::Broken => "broken",
        }
    }

    /// The contract's four classes: a rate-dependent (or broken, when nothing was judged before
    /// the break) test is `other`.
    pub fn class(self) -> &'static str {
        match self {
            Behaviour::RateDependent | Behaviour::Broken => "other",
            b => b.as_str(),
        }
    }
}

/// The elastic stiffness of the test.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stiffness {
    /// (EA)_T, (GJ)_T or (EI)_B.
    pub value: f64,
    /// "N" or "N m^2".
    pub unit: &'static str,
    /// 95% interval (Student t on the slope).
    pub ci95: [f64; 2],
    /// Fit window `[from, to]` in the sectional control (strain, 1/m, or deflection m).
    pub window: [f64; 2],
    /// Unit of the window.
    pub window_unit: &'static str,
    /// Whether the window was found automatically.
    pub window_automatic: bool,
    /// R² of the fit.
    pub r2: f64,
    /// Samples in the window.
    pub n: usize,
    /// Doubts about this number (poor fit, few points, wide interval, implausible modulus,
    /// disagreement with the first unloading), also in the analysis' `warnings`.
    pub warnings: Vec<String>,
    /// The first unloading's initial stiffness with its interval, the cross-check of the
    /// first-loading value (a piecewise linear elastic specimen unloaded from beyond its
    /// threshold disagrees by design, without a warning: it unloads on its second slope; null
    /// when there is no unloading; three-point: in the
    /// elastica-corrected deflection, null when the unloading starts beyond the geometry limit
    /// where that correction is trusted).
    pub first_unloading: Option<UnloadingCheck>,
}

/// The first unloading's stiffness beside the first-loading one (issue 12.6).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnloadingCheck {
    /// Initial unloading stiffness of cycle 1, stiffness unit (the per-cycle
    /// `unloading_stiffness`).
    pub value: f64,
    /// Its 95 % interval (the same AR(1) noise model as the first-loading interval).
    pub ci95: [f64; 2],
    /// Samples fitted.
    pub n: usize,
    /// Whether the two 95 % intervals overlap; when they do not, a warning names both values.
    pub agrees: bool,
}

/// The yield point: the bend in the first loading path.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct YieldPoint {
    /// Sectional control at the bend (strain, 1/m, or deflection m for three-point).
    pub control: f64,
    /// Response at the bend (N or N m): the measured envelope there (interpolated), not
    /// the corner of the two-slope fit, so never above the test's maximum; for the offset
    /// method, where the envelope crosses the offset line.
    pub response: f64,
    /// 95% interval of `control` (profile likelihood of the bend).
    pub control_ci95: [f64; 2],
    /// Range of the measured `response` over that interval.
    pub response_ci95: [f64; 2],
    /// Machine control at the bend (m or rad).
    pub machine_control: f64,
    /// Three-point only: small-deflection peak curvature 12 w/l₀² at the bend, 1/m.
    pub peak_curvature: Option<f64>,
    /// Three-point only: peak moment F l₀/4 at the bend, N m.
    pub peak_moment: Option<f64>,
    /// How it was found: `envelope_bend`, `first_loading_bend` or `offset`.
    pub method: &'static str,
    /// The offset of the offset method (sectional control units), else null.
    pub offset: Option<f64>,
    /// How the offset was set: `given` (offset:<value>) or the default's rule
    /// ([`default_yield_offset`]); null for the other methods.
    pub offset_rule: Option<String>,
    /// Cycle the yield point lies in.
    pub cycle: usize,
    /// Branch the yield point lies in (`first_loading` or `reloading`).
    pub branch: Branch,
}

/// A break: after its maximum (or, in a cyclic test, after the peak of the last cycle, when
/// that fall is abrupt) the response falls below [`BREAK_DROP`] of it and stays there while
/// the control does not go back (a test to fracture; an unloading is no break).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BreakPoint {
    /// First sample (0-based complete row) below the drop level.
    pub sample: usize,
    /// Machine control at break (m or rad, original sign).
    pub machine_control: f64,
    /// Response just before the drop (N or N m, original sign).
    pub response_before: f64,
    /// Work to break, ∫ response d(machine control) from the start to the break, J.
    pub work_to_break: f64,
}

/// A sudden partial fall of the response on a loading branch while the control runs on: by at
/// least [`SUDDEN_DROP_SHARE`] of the largest response and 10 σ of its noise within
/// [`SUDDEN_DROP_SAMPLES`] samples, the response staying down (the median of the next
/// max(5, 0.5 % of the record) samples below the level halfway down the fall). A wire of a
/// cable, a composite's ply or a bundle of fibres failing while the rest carries on; a test
/// machine's software reports the first as its "break" (a CFRP flexure bar: 805.8 → 739.5 N in
/// two samples, 8 % of the load, its stress at break the file's own).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SuddenDrop {
    /// The last sample before the fall (0-based complete row).
    pub sample: usize,
    /// Machine control there (original sign).
    pub machine_control: f64,
    /// Response before and after the fall (original sign).
    pub response_before: f64,
    /// Response at the end of the fall.
    pub response_after: f64,
}

/// Smallest fall, as a share of the largest response, that is a [`SuddenDrop`].
pub const SUDDEN_DROP_SHARE: f64 = 0.05;

/// Most samples a [`SuddenDrop`]'s fall may take.
pub const SUDDEN_DROP_SAMPLES: usize = 3;

/// The sudden drops of an oriented test (see [`SuddenDrop`]) on its loading branches, before
/// `end` (where a break's own fall starts, else the record's length), as (last sample before,
/// first sample after): at most one per fall; the response must stay down while the control
/// runs on, not unload.
fn sudden_drops(
    cm: &[f64],
    rm: &[f64],
    sigma: f64,
    h: f64,
    segments: &[Segment],
    end: usize,
) -> Vec<(usize, usize)> {
    let n = rm.len().min(end);
    let top = rm.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v));
    let need = (SUDDEN_DROP_SHARE * top).max(10.0 * sigma);
    if !(top > 0.0 && need.is_finite()) {
        return Vec::new();
    }
    let loading = |i: usize| {
        segments.iter().any(|s| {
            s.start <= i
                && i < s.end
                && matches!(s.branch, Branch::FirstLoading | Branch::Reloading)
        })
    };
    let stay = (rm.len() / 200).max(5);
    let mut out = Vec::new();
    let mut i = 0;
    while i + 1 < n {
        let fall = (1..=SUDDEN_DROP_SAMPLES)
            .take_while(|m| i + m < n)
            .find(|&m| rm[i] - rm[i + m] >= need && cm[i + m] >= cm[i] - h);
        match fall {
            Some(m) if loading(i) && rm[i] > 0.0 => {
                // It stays down while the control still runs on (a cycle's reversal right
                // after a dip is an unloading, not a failure).
                let w = i + m..(i + m + stay).min(rm.len());
                let after = &rm[w.clone()];
                let down = after.len() >= 3
                    && crate::stats::median(after) < rm[i] - 0.5 * (rm[i] - rm[i + m])
                    && w.clone().all(|k| cm[k] >= cm[i + m] - h)
                    && !w.clone().any(|k| while_unloading(segments, k));
                if down {
                    // From the fall's own top (the response may still rise a sample into it).
                    let a = (i..i + m)
                        .max_by(|&x, &y| rm[x].total_cmp(&rm[y]))
                        .unwrap_or(i);
                    out.push((a, i + m));
                    i += m + stay;
                    continue;
                }
                i += 1;
            }
            _ => i += 1,
        }
    }
    out
}

/// Fraction of the maximum response the response must fall below, and stay below, after the
/// maximum for a break ([`BreakPoint`]).
pub const BREAK_DROP: f64 = 0.5;

/// Three-point: the punch is taken as off the rod where the force is within this many
/// standard deviations of the response noise of zero (the rate comparison, [`crate::rate`]).
const CONTACT_FLOOR_SIGMA: f64 = 5.0;

/// The largest response (in magnitude) of the test and where it occurs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MaxResponse {
    /// Response, N or N m (original sign).
    pub response: f64,
    /// Machine control there (m or rad, original sign).
    pub machine_control: f64,
    /// Sample (0-based complete row).
    pub sample: usize,
}

/// Reversible bilinear behaviour: threshold and the two stiffnesses (eq. (19)).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Piecewise {
    /// Threshold in the sectional control (K_t in 1/m for pure bending; deflection for three-point).
    pub threshold_control: f64,
    /// 95% interval of the threshold.
    pub threshold_ci95: [f64; 2],
    /// Response at the threshold (M_t or F_t).
    pub threshold_response: f64,
    /// Stiffness below the threshold ((EI)_B,1), stiffness unit.
    pub stiffness_1: f64,
    /// Stiffness above the threshold ((EI)_B,2; apparent, structural, for three-point), stiffness unit.
    pub stiffness_2: f64,
    /// Three-point only: small-deflection peak curvature at the threshold, 1/m (an estimate of K_t).
    pub threshold_peak_curvature: Option<f64>,
}

/// Three-point large-deflection check (see the module doc: the reported stiffness is already
/// the elastica-corrected one).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LargeDeflection {
    /// (EI)_B with the exact elastica on sliding supports (equal to `stiffness.value`), N m².
    pub corrected_stiffness: f64,
    /// (EI)_B that the small-deflection eq. (3) gives on the same window, N m² (lower than the
    /// corrected value by about the elastica's softening over the window).
    pub small_deflection_stiffness: f64,
    /// Largest w/l₀ in the fit window.
    pub window_w_over_span: f64,
    /// Largest w/l₀ in the test.
    pub max_w_over_span: f64,
    /// w/l₀ beyond which eq. (3) errs by more than the tolerance.
    pub small_deflection_limit: f64,
}

/// Toe (slack) region at the start of the first loading.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Toe {
    /// Sectional control where the slack ends.
    pub end_control: f64,
    /// Sectional control where the elastic line crosses zero response (toe offset).
    pub offset_control: f64,
}

/// Response change during a hold (relaxation or creep of the response at fixed control).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HoldRelaxation {
    /// Cycle of the hold.
    pub cycle: usize,
    /// First sample of the hold.
    pub start: usize,
    /// One past the last sample.
    pub end: usize,
    /// Mean machine control during the hold (original sign).
    pub control: f64,
    /// Mean response over the last tenth of the hold minus that over the first tenth.
    pub response_change: f64,
    /// Whether the response trends during the hold: the slope of a straight line through the
    /// hold's samples (against sample index) differs from zero by more than the normal
    /// quantile at α = 10⁻³ shared among the test's holds (Bonferroni) times its standard
    /// error under the record's AR(1) noise ([`crate::stats::linear_fit_ar1`]), so neither
    /// many elastic dwells nor correlated noise raise a false alarm.
    pub significant: bool,
    /// Whether a significant trend is relaxation: opposite to the control's move into the hold
    /// (the response falls at a hold after a loading ramp and rises after an unloading one). A
    /// sensor drift trends the same way at every hold.
    pub relaxes: bool,
}

/// Noise levels (σ) of the conditioned channels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Noise {
    /// Machine control σ (m or rad).
    pub control: f64,
    /// Response σ (N or N m).
    pub response: f64,
}

/// Characterisation of one test; serialises to the contract's `analyze --json` object
/// (`stiffness`, `modulus_pa`, `yield`, `cycles`, `behaviour`) plus extra keys. Every null
/// quantity has its reason in `why_by_key` under the quantity's key, and `why` is the same
/// reasons as one string ("yield: ...; modulus_pa: ..."), null when nothing is missing.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Analysis {
    /// Test kind.
    pub kind: TestKind,
    /// Elastic stiffness, or null.
    pub stiffness: Option<Stiffness>,
    /// Young's modulus from the stiffness, Pa, or null (no diameter).
    pub modulus_pa: Option<f64>,
    /// Yield point, or null.
    #[serde(rename = "yield")]
    pub yield_point: Option<YieldPoint>,
    /// Per-cycle hysteresis.
    pub cycles: Vec<CycleResult>,
    /// The contract's behaviour class (`linear_elastic`, `piecewise_linear_elastic`,
    /// `elastoplastic`, `other`): a broken test's class before the break, a rate-dependent
    /// test's `other`.
    #[serde(rename = "behaviour")]
    pub behaviour_class: &'static str,
    /// The behaviour class with cablab's own two beyond the contract's (`broken`,
    /// `rate_dependent`), as `behaviour_detail`.
    #[serde(rename = "behaviour_detail")]
    pub behaviour: Behaviour,
    /// Reversible bilinear threshold and stiffnesses, when the class is piecewise linear elastic.
    pub piecewise: Option<Piecewise>,
    /// Three-point large-deflection check.
    pub large_deflection: Option<LargeDeflection>,
    /// Toe region, when found.
    pub toe: Option<Toe>,
    /// Offsets removed.
    pub offsets: Option<Offsets>,
    /// Noise levels.
    pub noise: Noise,
    /// Cycles and branches.
    pub segments: Vec<Segment>,
    /// Response change in every hold after the initial rest (relaxation: rate dependence).
    pub holds: Vec<HoldRelaxation>,
    /// Stiffness near reversals against the strokes' rates (rate dependence without holds),
    /// when at least two strokes after the first loading can be compared.
    pub rate_effect: Option<crate::rate::RateEffect>,
    /// The largest response and its control.
    pub max_response: MaxResponse,
    /// Where the specimen broke, when it did.
    #[serde(rename = "break")]
    pub break_point: Option<BreakPoint>,
    /// Sudden partial falls of the response while the control runs on, before any break
    /// ([`SuddenDrop`]): a wire of a cable, a ply or a fibre bundle failing.
    pub sudden_drops: Vec<SuddenDrop>,
    /// Samples (0-based, complete rows) excluded from the fits as isolated glitches.
    pub excluded_samples: Vec<usize>,
    /// Warnings for the user: statements that a number above may be wrong.
    pub warnings: Vec<String>,
    /// Notes for the user: what the analysis did that casts no doubt on a number (the part
    /// of the curve analysed, where the specimen broke, no unloading to judge by).
    pub notes: Vec<String>,
    /// All reasons for null quantities as one string ("key: reason; ..."), or null.
    pub why: Option<String>,
    /// Reasons for null quantities, keyed by field name.
    pub why_by_key: BTreeMap<String, String>,
}

/// What a negative loop area means. A passive specimen cannot return more energy than it
/// took, so ∮ F dx < 0 is never a dissipated energy:
/// - where the loading and unloading branches coincide within the noise
///   ([`CycleResult::loop_area_resolved`] false), the area is zero within resolution: a note;
/// - otherwise (resolved, or not judged) the unloading lies above the loading beyond the noise:
///   the control and the response are out of phase (sensor or filter lag, a drifting response
///   channel), the control is not the specimen's, or the two columns are exchanged (a real
///   Walter+Bai export labels force and displacement crosswise; ∮ x dF = −∮ F dx, so read the
///   other way round every such loop dissipates): a warning, since the area is then no measure
///   of anything.
///
/// Does not change the areas: they stay as measured.
fn negative_loops(cyc: &[CycleResult], warnings: &mut Vec<String>, notes: &mut Vec<String>) {
    let show = |v: &[&CycleResult]| {
        v.iter()
            .map(|c| format!("{} ({:.3e} J)", c.index, c.loop_area.unwrap_or(f64::NAN)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let negative: Vec<&CycleResult> = cyc
        .iter()
        .filter(|c| c.loop_area.is_some_and(|a| a < 0.0))
        .collect();
    let (within, beyond): (Vec<&CycleResult>, Vec<&CycleResult>) = negative
        .into_iter()
        .partition(|c| c.loop_area_resolved == Some(false));
    if !within.is_empty() {
        notes.push(format!(
            "loop area negative in cycle(s) {} but within resolution: the loading and unloading branches coincide within the noise, so no energy is dissipated that the data can resolve (read as 0; a passive specimen cannot return more energy than it took)",
            show(&within)
        ));
    }
    if !beyond.is_empty() {
        warnings.push(format!(
            "loop area negative beyond the noise in cycle(s) {}: a passive specimen cannot return more energy than it took, so the unloading lying above the loading means the control and response are out of phase (sensor or filter lag, a drifting response channel), the control is not the specimen's, or the two columns are exchanged (labelled crosswise: read the other way round, each of these loops would dissipate what it shows as negative; check which column holds the force with `cablab inspect`, then --control/--response); the area is not a dissipated energy",
            show(&beyond)
        ));
    }
}

/// Joins per-key reasons into one "key: reason; key: reason" string (None when empty).
pub(crate) fn join_why(map: &BTreeMap<String, String>) -> Option<String> {
    (!map.is_empty()).then(|| {
        map.iter()
            .map(|(k, v)| format!("{k}: {v}"))
            .collect::<Vec<_>>()
            .join("; ")
    })
}

fn check_finite(channel: &'static str, v: &[f64]) -> Result<(), MeasureError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(MeasureError::NonFinite { channel, index }),
        None => Ok(()),
    }
}

/// Characterises one test (see module doc). `control` is the machine control in SI (elongation
/// m, twist rad, deflection m, end rotation rad), `response` the force (N) or moment (N m),
/// `time_s` the optional time stamps.
pub fn analyze(
    kind: TestKind,
    geom: &Geometry,
    time_s: Option<&[f64]>,
    control: &[f64],
    response: &[f64],
    opts: &AnalyzeOptions,
) -> Result<Analysis, MeasureError> {
    if kind == TestKind::Unknown {
        return Err(MeasureError::UnknownKind);
    }
    geom.validate()?;
    if !(opts.nu > -1.0 && opts.nu <= 0.5) {
        return Err(MeasureError::BadPoisson(opts.nu));
    }
    if control.len() != response.len() {
        return Err(MeasureError::LengthMismatch {
            what: "control and response",
            left: control.len(),
            right: response.len(),
        });
    }
    if let Some(t) = time_s {
        if t.len() != control.len() {
            return Err(MeasureError::LengthMismatch {
                what: "time and control",
                left: t.len(),
                right: control.len(),
            });
        }
        check_finite("time", t)?;
    }
    check_finite("control", control)?;
    check_finite("response", response)?;
    if control.len() < 10 {
        return Err(MeasureError::TooFewSamples {
            what: "a test",
            need: 10,
            got: control.len(),
        });
    }
    let mut warnings = Vec::new();
    let mut notes: Vec<String> = Vec::new();
    let mut why = BTreeMap::new();

    // A clock that does not run forward cannot time holds: judge them by sample index instead
    // (and say so), rather than fail later with a symptom.
    let time_s = match time_s {
        Some(t) => {
            let back = t.windows(2).filter(|w| w[1] < w[0]).count();
            if back > 0 || t[t.len() - 1] <= t[0] {
                warnings.push(format!(
                    "the time column does not run forward ({}): holds are judged by sample index",
                    if back > 0 {
                        format!("it decreases {back} time(s)")
                    } else {
                        "it is constant".to_string()
                    }
                ));
                None
            } else {
                Some(t)
            }
        }
        None => None,
    };

    let mut c = match opts.compliance_m_per_n {
        Some(k) if k.is_finite() => correct_compliance(control, response, k),
        Some(k) => return Err(MeasureError::BadCompliance(k)),
        None => control.to_vec(),
    };
    // A compliance at least the whole of what the record measures, from its start to its
    // largest response, leaves the specimen nothing: its control runs backwards under load.
    if let Some(k) = opts.compliance_m_per_n.filter(|k| *k > 0.0) {
        let kp = (0..response.len())
            .max_by(|&a, &b| response[a].abs().total_cmp(&response[b].abs()))
            .unwrap_or(0);
        let (dc, dr) = (control[kp] - control[0], response[kp] - response[0]);
        let measured = dc / dr;
        if dr != 0.0 && measured > 0.0 && k >= measured {
            warnings.push(format!(
                "the machine compliance given, {k:.4e}, is at least the whole compliance the record measures from its start to its largest response ({measured:.4e}, control per response): taken off, it leaves the specimen no deformation, and the control runs backwards under load"
            ));
        }
    }
    let mut r = response.to_vec();
    // Each channel's noise scales are computed once per state of its samples (as read, after
    // glitches are replaced, after the offsets are taken off) and handed to every step.
    let (mut cn, mut rn) = (ChannelNoise::of(&c), ChannelNoise::of(&r));
    // Isolated glitches (one sample off in one channel) are excluded from every fit: replaced,
    // in this copy only, by the mean of their neighbours.
    let mut excluded: Vec<usize> = glitches_with(&r, &c, rn.jitter, cn.noise);
    let in_control = glitches_with(&c, &r, cn.jitter, rn.noise);
    for &i in &excluded {
        r[i] = 0.5 * (r[i - 1] + r[i + 1]);
    }
    for &i in &in_control {
        c[i] = 0.5 * (c[i - 1] + c[i + 1]);
    }
    if !excluded.is_empty() {
        rn = ChannelNoise::of(&r);
    }
    if !in_control.is_empty() {
        cn = ChannelNoise::of(&c);
    }
    if !excluded.is_empty() || !in_control.is_empty() {
        let show = |v: &[usize]| {
            v.iter()
                .take(5)
                .map(|i| i.to_string())
                .collect::<Vec<_>>()
                .join(", ")
                + if v.len() > 5 { ", ..." } else { "" }
        };
        warnings.push(format!(
            "{} isolated glitch sample(s) excluded from the analysis (response at samples [{}], control at samples [{}]; 0-based complete rows)",
            excluded.len() + in_control.len(),
            show(&excluded),
            show(&in_control)
        ));
    }
    excluded.extend(in_control);
    excluded.sort_unstable();
    excluded.dedup();
    let peak_before = r
        .iter()
        .filter(|v| v.is_finite())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let offsets = opts
        .zero_offsets
        .then(|| zero_offsets_with(&mut c, &mut r, cn, rn));
    // Without an initial rest the response's zero is where a straight line through its first
    // samples starts: a preload or a seating force there becomes the zero of every force that
    // follows (the cycles' peaks, the yield), unlike the file's own maximum. Said when it moves
    // them by more than 2 % of the largest response (a real MTS 793 fatigue export starting at
    // −33 N, 3.4 %: every cycle's peak above the file's maximum).
    if let Some(o) = offsets.filter(|o| o.preload.is_some()) {
        let p = o.preload.unwrap_or_default();
        notes.push(format!(
            "the record starts loaded, at {p:.4e} {} ({:.1} % of its largest value), without a rest before it: a preload, kept in the responses as the file records them (testXpert, Bluehill and TestSuite tare before the preload); {}; the yield's offset line starts where the elastic line meets zero. Were the load cell not tared, every response would read high by that much",
            kind.response_unit(),
            100.0 * p.abs() / peak_before.max(f64::MIN_POSITIVE),
            if o.absolute_control {
                "the control is kept as recorded too, since the first loading's elastic line meets zero load at its zero (it counts from zero load, not from the preload)".to_string()
            } else {
                format!("the control counts from its start ({:.4e} in the file, SI), where the preload was reached", o.control)
            }
        ));
    }
    if let Some(o) = offsets.filter(|o| o.samples_at_rest == 0) {
        if peak_before > 0.0 && o.response.abs() > 0.02 * peak_before {
            warnings.push(format!(
                "the response's zero is taken {:.4e} {} from the file's (a straight line through its first samples: the record starts without a rest), {:.0} % of its largest value: the cycles' peaks and the yield are counted from it, the maximum response is the file's own; a preload is then not in the forces reported",
                o.response,
                kind.response_unit(),
                100.0 * o.response.abs() / peak_before
            ));
        }
    }
    if offsets.is_some() {
        (cn, rn) = (ChannelNoise::of(&c), ChannelNoise::of(&r));
    }
    let noise = Noise {
        control: cn.noise,
        response: rn.noise,
    };

    let segments = segment_with(time_s, &c, &r, cn, rn)?;
    // Orientation of the first loading.
    let first_idx: Vec<usize> = segments
        .iter()
        .filter(|s| s.branch == Branch::FirstLoading)
        .flat_map(|s| s.start..s.end)
        .collect();
    if first_idx.len() < 10 {
        let (lo, hi) = c
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        return Err(match (first_idx.first(), first_idx.last()) {
            (Some(&a), Some(&b)) if hi - lo > 10.0 * cn.noise.max(f64::MIN_POSITIVE) => {
                MeasureError::ShortFirstLoading {
                    n: first_idx.len(),
                    from: a + 1,
                    to: b + 1,
                }
            }
            _ => MeasureError::NoMotion,
        });
    }
    let last_first = *first_idx.last().unwrap_or(&0);
    let sign = if c[last_first] >= c[first_idx[0]] {
        1.0
    } else {
        -1.0
    };
    let cm: Vec<f64> = c.iter().map(|v| sign * v).collect();
    let rm: Vec<f64> = r.iter().map(|v| sign * v).collect();
    // The reversal threshold of the oriented control: a sign flip changes no second
    // difference's magnitude, nor the range, so the control's jitter serves as it is.
    let h_cm = reversal_threshold_with(&cm, cn.jitter);
    let xs = sectional(kind, geom, &cm);
    let l0 = geom.free_length_m;
    let three = kind == TestKind::ThreePoint;
    // Three-point: the first loading in the elastica-corrected deflection (module doc).
    let elastica = three.then(ThreePointElastica::new);
    let geometry_limit = elastica.as_ref().map_or(f64::INFINITY, |t| {
        t.small_deflection_limit(THREE_POINT_GEOMETRY_LIMIT)
    });
    // Three-point toe compensation (ISO 178, ASTM D790): a slack or gap before the punch meets
    // the specimen is no deflection, so the elastica correction counts from contact (`toe`,
    // oriented stroke, 0 when there is none worth moving the origin for).
    let toe_w = match &elastica {
        Some(tab) => {
            let limit_w = tab.small_deflection_limit(opts.small_deflection_tolerance) * l0;
            let toe_w = toe_before_contact(&xs, &rm, &first_idx, geometry_limit * l0, limit_w);
            if toe_w > 0.0 {
                notes.push(format!(
                    "three-point: the punch meets the specimen at w = {toe_w:.4e} m (w/l0 = {:.4}), where the first loading's elastic line meets zero force; the deflection counts from there (toe compensation), as the elastica correction and the small-deflection limit require",
                    toe_w / l0
                ));
            }
            toe_w
        }
        None => 0.0,
    };
    let to_fit_x = |w: f64| -> Option<f64> {
        match &elastica {
            Some(tab) => tab
                .corrected_deflection((w - toe_w) / l0)
                .map(|v| toe_w + v * l0),
            None => Some(w),
        }
    };
    let from_fit_x = |x: f64| -> f64 {
        match &elastica {
            Some(tab) => tab
                .deflection_from_corrected((x - toe_w) / l0)
                .map_or(x, |v| toe_w + v * l0),
            None => x,
        }
    };
    // The virgin envelope: the first loading, then every later loading from where it passes
    // all earlier extremes by more than the reversal threshold (module doc of `condition`).
    let env_idx: Vec<usize> = match opts.yield_method {
        YieldMethod::FirstLoading => first_idx.clone(),
        _ => virgin_envelope(&segments, &cm, &first_idx, h_cm),
    };
    let mut fx: Vec<f64> = Vec::with_capacity(env_idx.len());
    let mut fw: Vec<f64> = Vec::with_capacity(env_idx.len());
    for &i in &env_idx {
        match to_fit_x(xs[i]).filter(|_| (xs[i] - toe_w).abs() / l0 <= geometry_limit) {
            Some(v) => {
                fx.push(v);
                fw.push(xs[i]);
            }
            None => {
                notes.push(format!(
                    "three-point: the first loading is analysed up to w/l0 = {geometry_limit:.3}, where geometry alone softens the force by {:.0} % (beyond it the sliding-support correction is not reliable)",
                    100.0 * THREE_POINT_GEOMETRY_LIMIT
                ));
                break;
            }
        }
    }
    let fy: Vec<f64> = env_idx[..fx.len()].iter().map(|&i| rm[i]).collect();

    let factor = stiffness_factor(kind, geom);
    // A window in response units or in % of the maximum response becomes the control span
    // of the virgin envelope's samples from the first at or above its lower end to the last
    // at or below its upper end before the maximum.
    let fit_window = match (opts.fit_window, opts.fit_window_unit) {
        (Some((a, b)), FitWindowUnit::Response | FitWindowUnit::PercentOfMax) => {
            let top_k = (0..fy.len())
                .max_by(|&i, &j| fy[i].total_cmp(&fy[j]))
                .unwrap_or(0);
            let scale = match opts.fit_window_unit {
                FitWindowUnit::PercentOfMax => fy[top_k] / 100.0,
                _ => sign,
            };
            let (lo, hi) = ((a * scale).min(b * scale), (a * scale).max(b * scale));
            let i0 = (0..=top_k).find(|&i| fy[i] >= lo);
            let i1 = (0..=top_k).rev().find(|&i| fy[i] <= hi);
            match (i0, i1) {
                (Some(i0), Some(i1)) if i1 > i0 => {
                    Some((sign * from_fit_x(fx[i0]), sign * from_fit_x(fx[i1])))
                }
                _ => {
                    return Err(MeasureError::WindowTooSmall {
                        from: a,
                        to: b,
                        n: 0,
                    })
                }
            }
        }
        (w, _) => w,
    };
    // The response noise's serial correlation, measured over the whole record on the residual
    // series response − k · control (k: the steepest straight piece of the virgin envelope,
    // so control noise seen through the slope counts too; the series is piecewise linear in
    // time wherever the test is, which the lag-k second differences do not see). Its σ, scaled
    // to the virgin envelope's own noise level (a load cell reads a cable's stick-slip louder
    // at higher loads), is the prior σ of the stiffness interval, with the degrees of freedom
    // of a MAD of second differences (about 0.37 as efficient as a standard deviation, over
    // differences with Σρ² = 1.94, and fewer independent samples by the long-run factor).
    // The first loading's break search serves both segmentations of it (white here, with the
    // record's φ for the elastic window below).
    let breaks = crate::elastic::BreakSearch::new(&fx, &fy);
    let serial = {
        let seg = breaks.segment(3, 0.0);
        let k = seg.slopes.iter().copied().fold(0.0f64, f64::max);
        let z: Vec<f64> = xs.iter().zip(&rm).map(|(x, y)| y - k * x).collect();
        let (sn, lr) = crate::condition::serial_noise_and_level(&z);
        let z_env: Vec<f64> = env_idx[..fx.len()].iter().map(|&i| z[i]).collect();
        let le = noise_level(&z_env);
        let scale = if lr > 0.0 && le > 0.0 { le / lr } else { 1.0 };
        let dof = 0.19 * z_env.len().min(z.len()) as f64 / sn.long_run_factor();
        (sn, sn.sigma * scale, dof)
    };
    let mut user_bounds = (f64::NEG_INFINITY, f64::INFINITY);
    let elastic: Option<ElasticRange> = match fit_window {
        Some((a, b)) => {
            let (ma, mb) = (sign * a, sign * b);
            let map = |v: f64| to_fit_x(v).unwrap_or(v);
            user_bounds = (map(ma).min(map(mb)), map(ma).max(map(mb)));
            let mut e =
                user_elastic_range(&fx, &fy, map(ma), map(mb)).map_err(|err| match err {
                    // Name the window as the user gave it.
                    MeasureError::WindowTooSmall { n, .. } => {
                        MeasureError::WindowTooSmall { from: a, to: b, n }
                    }
                    other => other,
                })?;
            // Report the window as given.
            e.window = [ma.min(mb), ma.max(mb)];
            Some(e)
        }
        None => match auto_elastic_range_searched(&fx, &fy, serial.0.phi, Some(&breaks)) {
            Ok(e) => Some(off_the_elastic_line(
                e,
                (&fx, &fy),
                serial.0.phi,
                &breaks,
                |v| sign * from_fit_x(v),
                factor,
                &mut notes,
            )),
            Err(e) => {
                why.insert(
                    "stiffness".into(),
                    format!("no elastic range found on the first loading: {e}"),
                );
                None
            }
        },
    };
    // Three-point: the automatic window stays within the small-deflection range (see
    // `small_deflection_window`); the slope of the wider window widens the interval.
    let (elastic, wider_slope) = match (elastic, &elastica) {
        (Some(e), Some(tab)) if e.automatic => {
            let limit = tab.small_deflection_limit(opts.small_deflection_tolerance) * l0;
            let (e, wider) = small_deflection_window(
                e,
                (&fx, &fy, &fw),
                serial.0.phi,
                (limit, l0),
                &mut warnings,
            );
            (Some(e), wider)
        }
        (e, _) => (e, None),
    };
    let stiffness = elastic.as_ref().map(|e| {
        let win = if e.automatic {
            [from_fit_x(e.window[0]), from_fit_x(e.window[1])]
        } else {
            e.window
        };
        let w = if sign > 0.0 { win } else { [-win[1], -win[0]] };
        // Serially correlated noise carries fewer independent samples than it numbers: the
        // interval is that of AR(1) errors with the record's φ over the samples' positions in
        // the record (`linear_fit_ar1`; the plain one for white noise).
        let (a, b) = e.window_idx;
        let k: Vec<usize> = (a..b)
            .filter(|&k| user_bounds.0 <= fx[k] && fx[k] <= user_bounds.1)
            .collect();
        let pick = |v: &[f64]| k.iter().map(|&j| v[j]).collect::<Vec<f64>>();
        let pos: Vec<usize> = k.iter().map(|&j| env_idx[j]).collect();
        let ci = crate::stats::linear_fit_ar1(
            &pick(&fx),
            &pick(&fy),
            &pos,
            serial.0.phi,
            Some((serial.1, serial.2)),
        )
        .map_or(e.fit.slope_ci95, |f| f.slope_ci95);
        Stiffness {
            value: e.fit.slope * factor,
            unit: kind.stiffness_unit(),
            ci95: [ci[0] * factor, ci[1] * factor],
            window: w,
            window_unit: sectional_unit(kind),
            window_automatic: e.automatic,
            r2: e.fit.r2,
            n: e.fit.n,
            warnings: Vec::new(),
            first_unloading: None,
        }
    });
    let stiffness = stiffness.map(|mut s| {
        if let Some(k) = wider_slope {
            let v = k * factor;
            s.ci95 = [s.ci95[0].min(v), s.ci95[1].max(v)];
        }
        s
    });
    let first_rise = fy.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v))
        - fy.iter().fold(f64::INFINITY, |m, &v| m.min(v));
    let stiffness = match stiffness {
        Some(s) => match refuse_stiffness(&s, first_rise, noise.response) {
            Some(reason) => {
                why.insert("stiffness".into(), reason);
                None
            }
            None => Some(s),
        },
        None => None,
    };
    let mut stiffness = stiffness;
    if let Some(s) = stiffness.as_mut() {
        s.warnings = stiffness_doubts(s);
        if let Some(e) = elastic.as_ref().filter(|e| e.automatic) {
            s.warnings.extend(stiff_start(&fx, &fy, e, serial.0.phi));
        }
        warnings.extend(s.warnings.iter().map(|w| format!("stiffness: {w}")));
    }

    // The section of the moduli: a stated flat b × h before the round diameter.
    let section = match (opts.flat_section, geom.diameter_m) {
        (Some(f), _) => Some((
            f.modulus_from_stiffness(kind, stiffness.as_ref().map_or(0.0, |s| s.value), opts.nu),
            format!(
                "a flat section of {:.3} × {:.3} mm (width × thickness)",
                f.width_m * 1e3,
                f.thickness_m * 1e3
            ),
        )),
        (None, Some(d)) => Some((
            modulus_from_stiffness(
                kind,
                d,
                stiffness.as_ref().map_or(0.0, |s| s.value),
                opts.nu,
            ),
            format!("a diameter of {:.3} mm", d * 1e3),
        )),
        (None, None) => None,
    };
    // A sectional control no solid reaches: a strain beyond 20 (2000 %, where elastomers break
    // below 10), a surface strain of that size in torsion or bending, a deflection beyond the
    // span. A locale-mangled export whose numbers lost their decimal mark part-way read as a
    // strain of 5·10⁵ and an elongation of 30 km, after the reader's warnings only.
    let reach = xs
        .iter()
        .filter(|v| v.is_finite())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let surface = match kind {
        TestKind::Tension => Some((reach, "strain")),
        TestKind::Torsion | TestKind::PureBending => {
            geom.diameter_m.map(|d| (reach * 0.5 * d, "surface strain"))
        }
        TestKind::ThreePoint => Some((reach / l0, "deflection per span")),
        TestKind::Unknown => None,
    };
    if let Some((v, what)) = surface.filter(|(v, w)| {
        *v > if *w == "deflection per span" {
            1.0
        } else {
            PLAUSIBLE_STRAIN
        }
    }) {
        warnings.push(format!(
            "the {what} reaches {v:.3e}, beyond what any specimen can (a strain of {PLAUSIBLE_STRAIN:.0} is 2000 %; a deflection beyond the span): check the control's unit, the length, and the reader's warnings (a locale switch part-way, a column in another unit); every value from this control is suspect"
        ));
    }
    let modulus_pa = match (&stiffness, section) {
        (Some(_), Some((m, what))) => {
            if let Some(e) =
                m.filter(|e| !(PLAUSIBLE_MODULUS_PA.0..=PLAUSIBLE_MODULUS_PA.1).contains(e))
            {
                warnings.push(format!(
                    "modulus_pa: {e:.3e} Pa for {what} lies outside {:.0e}–{:.0e} Pa, the range of solids from soft elastomers to diamond: check the kind, the channels (control and response swapped?), their units and the section",
                    PLAUSIBLE_MODULUS_PA.0,
                    PLAUSIBLE_MODULUS_PA.1
                ));
            }
            m
        }
        (None, _) => {
            why.insert("modulus_pa".into(), "no stiffness".into());
            None
        }
        (_, None) => {
            why.insert(
                "modulus_pa".into(),
                "the diameter is not known (give --diameter-mm, or --width-mm and --thickness-mm for a flat section)"
                    .into(),
            );
            None
        }
    };

    let per_control = match kind {
        TestKind::ThreePoint => 1.0,
        _ => 1.0 / geom.free_length_m,
    };
    // The toe (slack) of the first loading, sectional: where it ends and where the elastic line
    // meets zero response.
    let toe_ref = elastic.as_ref().and_then(|e| {
        e.toe.map(|t| {
            let end = from_fit_x(t.knee_x);
            (end, from_fit_x(e.fit.x_intercept().unwrap_or(t.knee_x)))
        })
    });
    let control_resolution = crate::condition::resolution(&c);
    let mut cyc = cycles(&CycleInputs {
        control: &cm,
        sectional: &xs,
        response: &rm,
        segments: &segments,
        stiffness_factor: factor,
        three_point: three,
        sectional_per_control: per_control,
        control_resolution,
        zero_sectional: toe_ref.map_or(0.0, |t| t.1),
        toe_end_control: toe_ref.map_or(f64::NEG_INFINITY, |t| t.0 / per_control),
        serial: crate::condition::SerialNoise {
            sigma: serial.1,
            ..serial.0
        },
    });

    // First loading against first unloading (issue 12.6): both are the elastic stiffness of
    // an elastic or elastoplastic specimen; intervals that do not overlap mean the first
    // loading was not (a toe or seating not separated from the window, slack, damage).
    // Three-point: the unloading in the elastica-corrected deflection (in which an elastic
    // rod is linear, as the loading side's window), from its peak while the punch still
    // pushes, and only when the peak lies within the geometry limit where that correction is
    // trusted (w/l₀ ≈ 0.1, [`THREE_POINT_GEOMETRY_LIMIT`]). The part of a longer unloading
    // that returns into the small-deflection range is no elastic unloading: on the demo's
    // Bowden cables bent to 15 mm it is the frictional tail before contact is lost, 6× softer
    // than the loading.
    // The sectional control in which a rate-independent elastic specimen is linear (for
    // three-point, the elastica-corrected deflection).
    let fit_xs: Vec<f64> = xs.iter().map(|&v| to_fit_x(v).unwrap_or(v)).collect();
    if let Some(s) = stiffness.as_mut() {
        let top = match &elastica {
            Some(_) => to_fit_x(toe_w + geometry_limit * l0).unwrap_or(f64::INFINITY),
            None => f64::INFINITY,
        };
        let check = first_unloading_fit(
            &segments,
            &fit_xs,
            top,
            &rm,
            serial.0.phi,
            (serial.1, serial.2),
        );
        if let Some(f) = check {
            let (lo, hi) = (f.slope_ci95[0] * factor, f.slope_ci95[1] * factor);
            let agrees = lo <= s.ci95[1] && s.ci95[0] <= hi;
            s.first_unloading = Some(UnloadingCheck {
                value: f.slope * factor,
                ci95: [lo, hi],
                n: f.n,
                agrees,
            });
            if !agrees {
                let w = format!(
                    "the first-loading stiffness {:.4e} {u} (95 % [{:.4e}, {:.4e}]) and the first unloading's {:.4e} {u} (95 % [{lo:.4e}, {hi:.4e}]) disagree beyond their intervals: a toe, seating or slack in the first loading, or damage at the first peak; the first-loading value is reported",
                    s.value,
                    s.ci95[0],
                    s.ci95[1],
                    f.slope * factor,
                    u = s.unit,
                );
                warnings.push(format!("stiffness: {w}"));
                s.warnings.push(w);
            }
        }
    }

    // Behaviour. Knee positions back from the fitting control to the sectional one.
    let unmap = |h: Hinge| Hinge {
        knee_x: from_fit_x(h.knee_x),
        knee_x_ci95: [from_fit_x(h.knee_x_ci95[0]), from_fit_x(h.knee_x_ci95[1])],
        ..h
    };
    let bend: Option<Hinge> = elastic
        .as_ref()
        .and_then(|e| material_bend(e.bend?, &fx, &fy))
        .map(unmap);
    // A record cut short (an extensometer taken off while the test went on): a bend with fewer
    // than max(5, a tenth of the first loading's) samples beyond it is where the record stops,
    // not a bend it shows.
    let mut bend_cut = None;
    let bend = match bend {
        Some(b) if opts.cut_short => {
            let beyond = fw.iter().filter(|v| v.abs() > b.knee_x.abs()).count();
            if beyond < (fw.len() / 10).max(5) {
                bend_cut = Some(format!(
                    "the record is cut short (see the warnings) {beyond} sample(s) past a bend of the first loading: not taken as a bend (a yield or a threshold) the record shows"
                ));
                None
            } else {
                Some(b)
            }
        }
        other => other,
    };
    // Only an unloading from beyond the bend says whether the bend is reversible: an elastic
    // loop before it (ISO 6892-1 Annex, ASTM E111 modulus loops) closes whatever follows.
    let judged: Vec<&CycleResult> = cyc
        .iter()
        .filter(|c| c.coincide.is_some())
        .filter(|c| bend.is_none_or(|b| c.peak_sectional > b.knee_x))
        .collect();
    let reversible = !judged.is_empty()
        && judged
            .iter()
            .all(|c| c.coincide == Some(true) && c.residual_significant != Some(true));
    let set = bend.and_then(|b| set_below_bend(&segments, &first_idx, (&xs, &rm), b));
    if let Some((cycle, level, by)) = set {
        notes.push(format!(
            "cycle {cycle} unloads from beyond the bend without reaching zero (between two loads: no residual to judge), but at {level:.4e} below the bend its control lies {by:.4e} past the first loading's: a permanent set, so the bend is a yield, not a reversible threshold"
        ));
    }
    let reversible = reversible && set.is_none();
    let permanent = set.is_some() || cyc.iter().any(|c| c.residual_significant == Some(true));
    // A slope that is not positive is no elastic behaviour (a response against its control that
    // no sign convention explains, warned above): `other`, not `linear_elastic`.
    let positive = stiffness.as_ref().is_some_and(|s| s.value > 0.0);
    let behaviour = if judged.is_empty() {
        notes.push(
            if cyc.iter().any(|c| c.coincide.is_some()) {
                "no unloading from beyond the bend to judge its reversibility by (the loops before it close, as elastic loops do)"
            } else {
                "no unloading to judge reversibility by"
            }
            .into(),
        );
        monotonic_class(bend.is_some(), positive, &mut warnings)
    } else if reversible && positive {
        if bend.is_some() {
            Behaviour::PiecewiseLinearElastic
        } else {
            Behaviour::LinearElastic
        }
    } else if bend.is_some() && permanent {
        Behaviour::Elastoplastic
    } else {
        Behaviour::Other
    };
    if behaviour == Behaviour::LinearElastic {
        let from = elastic
            .as_ref()
            .and_then(|e| e.toe.as_ref())
            .map_or(f64::NEG_INFINITY, |t| t.knee_x);
        warnings.extend(curved_first_loading(&fw, &fy, from));
    }

    let machine_of = |x: f64| if three { x } else { x * l0 };
    let yield_point = match (bend, behaviour) {
        (Some(b), Behaviour::Elastoplastic | Behaviour::Other) => {
            let ci = if sign > 0.0 {
                b.knee_x_ci95
            } else {
                [-b.knee_x_ci95[1], -b.knee_x_ci95[0]]
            };
            // The response the specimen carried at the bend (not where the two hinge lines
            // meet, which lies above a rounded knee: see `response_on_envelope`).
            let on = |x: f64| response_on_envelope(&fw, &fy, x);
            let chord = on(b.knee_x);
            let ends = [on(b.knee_x_ci95[0]), on(b.knee_x_ci95[1])];
            // The samples the response is read from carry the response's noise: 2σ either
            // side (a torsion log at 2.3 % noise: the chord at the bend 4 % above the truth,
            // its interval ending at the point itself).
            let pad = 2.0 * rn.noise;
            let mut cy_ = [
                ends[0].min(ends[1]).min(chord) - pad,
                ends[0].max(ends[1]).max(chord) + pad,
            ];
            // Between two sparse samples the chord cuts the corner (a load-controlled test
            // logged at 10 Hz: 300.7 N, then 320 N past the bend; the chord said 302.7 N where
            // the specimen yielded at 314 N, its interval 0.4 N wide). The curve there lies
            // between the chord and the two slopes drawn from the samples; where that span is
            // beyond the response's noise, the yield is its middle and the interval holds it.
            let ky = match corner_above_chord(&fw, &fy, b.knee_x, b.slope_before, b.slope_after) {
                Some(top) if top - chord > pad => {
                    cy_[1] = cy_[1].max(top + pad);
                    0.5 * (chord + top)
                }
                _ => chord,
            };
            let cy = if sign > 0.0 { cy_ } else { [-cy_[1], -cy_[0]] };
            let (cycle, branch) = label_at(&segments, &env_idx, &fw, b.knee_x);
            Some(YieldPoint {
                control: sign * b.knee_x,
                response: sign * ky,
                control_ci95: ci,
                response_ci95: cy,
                machine_control: sign * machine_of(b.knee_x),
                peak_curvature: three.then(|| sign * three_point_peak_curvature(b.knee_x, l0)),
                peak_moment: three.then(|| sign * three_point_peak_moment(ky, l0)),
                method: opts.yield_method.as_str(),
                offset: None,
                offset_rule: None,
                cycle,
                branch,
            })
        }
        (Some(_), _) => {
            why.insert(
                "yield".into(),
                "the bend in the first loading is reversible: reported as the piecewise threshold"
                    .into(),
            );
            None
        }
        (None, _) => {
            let reason = match (&bend_cut, elastic.is_some()) {
                (Some(cut), _) => cut.as_str(),
                (None, true) => "no bend in the virgin loading path beyond the noise",
                (None, false) => "no elastic range on the first loading",
            };
            why.insert("yield".into(), reason.into());
            None
        }
    };
    // The offset method replaces the bend (whatever the class: the user asked for it).
    let offset = match opts.yield_method {
        YieldMethod::Offset(v) => Some(Ok((v, "given".to_string()))),
        YieldMethod::OffsetDefault => Some(default_yield_offset_in(
            kind,
            geom,
            opts.flat_section.as_ref(),
        )),
        _ => None,
    };
    let yield_point = match (offset, &elastic) {
        (Some(Err(reason)), _) => {
            why.insert("yield".into(), format!("offset yield: {reason}"));
            None
        }
        // A reversible bend is a threshold, not a yield: an offset line crosses the curve above
        // it all the same (a Bowden cable's second slope), which is no plastic strain.
        (Some(Ok(_)), Some(_)) if behaviour == Behaviour::PiecewiseLinearElastic => {
            why.insert(
                "yield".into(),
                "offset yield: the bend is reversible (piecewise linear elastic: the unloading retraces the loading), so the offset line's crossing is no plastic strain; the threshold is reported under piecewise".into(),
            );
            None
        }
        (Some(Ok((v, rule))), Some(e)) => {
            why.remove("yield");
            match offset_yield(&fx, &fy, &e.fit, v, e.window_idx.0) {
                Some((x, y, xr, yr)) => {
                    let (xs_, xr_) = (from_fit_x(x), [from_fit_x(xr[0]), from_fit_x(xr[1])]);
                    let (cycle, branch) = label_at(&segments, &env_idx, &fw, xs_);
                    let ci = if sign > 0.0 { xr_ } else { [-xr_[1], -xr_[0]] };
                    Some(YieldPoint {
                        control: sign * xs_,
                        response: sign * y,
                        control_ci95: ci,
                        // The elastic line's slope interval moves the crossing along the
                        // curve; the response's own noise widens it (a 0-wide interval
                        // excluded every truth).
                        response_ci95: {
                            let z = 1.96 * noise.response;
                            let (lo, hi) = (yr[0] - z, yr[1] + z);
                            if sign > 0.0 {
                                [lo, hi]
                            } else {
                                [-hi, -lo]
                            }
                        },
                        machine_control: sign * machine_of(xs_),
                        peak_curvature: three.then(|| sign * three_point_peak_curvature(xs_, l0)),
                        peak_moment: three.then(|| sign * three_point_peak_moment(y, l0)),
                        method: opts.yield_method.as_str(),
                        offset: Some(v),
                        offset_rule: Some(rule),
                        cycle,
                        branch,
                    })
                }
                None => {
                    why.insert(
                        "yield".into(),
                        format!(
                            "the virgin envelope never falls below the elastic line offset by {v}"
                        ),
                    );
                    None
                }
            }
        }
        (Some(Ok(_)), None) => {
            why.insert("yield".into(), "offset yield: no elastic line".into());
            None
        }
        _ => yield_point,
    };
    let max_response = {
        let k = (0..r.len())
            .max_by(|&a, &b| r[a].abs().total_cmp(&r[b].abs()))
            .unwrap_or(0);
        MaxResponse {
            response: response[k],
            machine_control: control[k],
            sample: k,
        }
    };
    let found_break = find_break(&cm, &rm, serial.0.sigma, h_cm)
        .filter(|&(j, _, _)| !relaxed_while_held(&segments, &rm, j))
        .filter(|&(j, _, _)| !while_unloading(&segments, j));
    let break_point = found_break.map(|(j, work, _)| BreakPoint {
        sample: j,
        machine_control: control[j],
        response_before: response[j - 1],
        work_to_break: work,
    });
    // Glitches only on the broken pieces' signal (a fatigue coupon's four, all after it broke)
    // touch no result: a note, not a warning.
    if let Some(b) = &break_point {
        if !excluded.is_empty() && excluded.iter().all(|&i| i >= b.sample) {
            if let Some(k) = warnings
                .iter()
                .position(|w| w.contains("isolated glitch sample(s) excluded"))
            {
                let w = warnings.remove(k);
                notes.push(format!(
                    "{w}, all after the break at sample {}: the broken pieces' signal, which no result uses",
                    b.sample
                ));
            }
        }
    }
    // Cycles after the cycle a specimen broke in are its pieces and the actuator ringing after
    // the fracture (an MTS three-point export: three "cycles" of ±0.5 mm at zero force, one of
    // them a negative loop with a hint that the columns were exchanged): not reported.
    if let Some((j, _, _)) = found_break {
        let broke_in = segments
            .iter()
            .find(|s| s.start <= j && j < s.end)
            .map(|s| s.cycle);
        if let Some(cb) = broke_in {
            let before = cyc.len();
            cyc.retain(|c| c.index <= cb);
            // The cycle it broke in has no closed loop and no residual of the specimen: its
            // "unloading" is the fracture's fall.
            for c in cyc.iter_mut().filter(|c| c.index == cb) {
                let why = "the specimen broke in this cycle: its unloading is the fracture's fall";
                for (key, v) in [
                    ("loop_area", &mut c.loop_area),
                    ("residual", &mut c.residual),
                    ("unloading_stiffness", &mut c.unloading_stiffness),
                ] {
                    if v.take().is_some() || c.why_by_key.contains_key(key) {
                        c.why_by_key.insert(key.into(), why.into());
                    }
                }
                c.loop_area_resolved = None;
                c.residual_significant = None;
                c.why = join_why(&c.why_by_key);
            }
            if cyc.len() < before {
                notes.push(format!(
                    "{} cycle(s) after the break (in cycle {cb}) are not reported: the specimen is broken there",
                    before - cyc.len()
                ));
            }
        }
    }
    let falls = sudden_drops(
        &cm,
        &rm,
        serial.0.sigma,
        h_cm,
        &segments,
        // Before the break's own fall: its last sample at 90 % of the peak it fell from.
        found_break
            .filter(|_| break_point.is_some())
            .map_or(rm.len(), |(j, _, k)| {
                (k..j).rev().find(|&i| rm[i] >= 0.9 * rm[k]).unwrap_or(k) + 1
            }),
    );
    if let Some(&(a, b)) = falls.first() {
        notes.push(format!(
            "the response falls suddenly while the control runs on{}: first after sample {a} (control {:.4e}), {:.5e} → {:.5e}, {:.1} % of the largest response in {} sample{} (a wire, a ply or a fibre bundle failing while the rest carries on?)",
            if falls.len() > 1 {
                format!(" {} times", falls.len())
            } else {
                String::new()
            },
            control[a],
            response[a],
            response[b],
            100.0 * (response[a] - response[b]).abs() / max_response.response.abs(),
            b - a,
            if b - a > 1 { "s" } else { "" }
        ));
    }
    let drops: Vec<SuddenDrop> = falls
        .into_iter()
        .map(|(a, b)| SuddenDrop {
            sample: a,
            machine_control: control[a],
            response_before: response[a],
            response_after: response[b],
        })
        .collect();
    // A specimen that broke: the peak of the cycle it broke in is where its response peaked
    // before the break, not the punch or crosshead running on over the broken pieces (a bone's
    // cycle peak read 1.08 N at the end of the stroke, its maximum 19.65 N).
    if let Some(b) = &break_point {
        for cy in cyc.iter_mut() {
            let before: Vec<usize> = segments
                .iter()
                .filter(|s| s.cycle == cy.index)
                .flat_map(|s| s.start..s.end.min(b.sample))
                .collect();
            let reaches_past = segments
                .iter()
                .any(|s| s.cycle == cy.index && s.end > b.sample);
            if let (true, Some(&k)) = (
                reaches_past,
                before.iter().max_by(|&&i, &&j| rm[i].total_cmp(&rm[j])),
            ) {
                cy.peak_control = cm[k];
                cy.peak_sectional = xs[k];
                cy.peak_response = rm[k];
            }
        }
    }
    negative_loops(&cyc, &mut warnings, &mut notes);
    if let (Some(b), Some((_, _, k))) = (&break_point, found_break) {
        let top = rm.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v));
        let of = if rm[k] < top {
            let cycle = segments
                .iter()
                .find(|s| s.start <= k && k < s.end)
                .map_or(0, |s| s.cycle);
            format!("the peak of its last loading (cycle {cycle}, not its largest)")
        } else {
            "its maximum".to_string()
        };
        notes.push(format!(
            "the specimen broke at sample {} (control {:.4e}): the response fell below {:.0} % of {of} and stayed there",
            b.sample,
            b.machine_control,
            100.0 * BREAK_DROP
        ));
    }
    let piecewise = match (bend, behaviour) {
        (Some(b), Behaviour::PiecewiseLinearElastic) => Some(Piecewise {
            threshold_control: sign * b.knee_x,
            threshold_ci95: if sign > 0.0 {
                b.knee_x_ci95
            } else {
                [-b.knee_x_ci95[1], -b.knee_x_ci95[0]]
            },
            threshold_response: sign * b.knee_y,
            stiffness_1: b.slope_before * factor,
            stiffness_2: b.slope_after * factor,
            threshold_peak_curvature: three
                .then(|| sign * three_point_peak_curvature(b.knee_x, l0)),
        }),
        _ => None,
    };
    // A reversible bilinear specimen unloaded from beyond its threshold starts its unloading
    // on the second slope: the first-unloading check then measures stiffness_2, not a flaw
    // of the first loading, and its warning is withdrawn when the unloading lies nearer
    // stiffness_2 than stiffness_1 (the check stays in the JSON, `agrees` false).
    if let (Some(p), Some(s)) = (&piecewise, stiffness.as_mut()) {
        let second = s.first_unloading.as_ref().is_some_and(|u| {
            !u.agrees && (u.value - p.stiffness_2).abs() < (u.value - p.stiffness_1).abs()
        });
        if second {
            let is_check = |w: &String| w.contains("and the first unloading's");
            s.warnings.retain(|w| !is_check(w));
            warnings.retain(|w| !is_check(w));
        }
    }
    let toe = elastic.as_ref().and_then(|e| {
        e.toe.map(|t| Toe {
            end_control: sign * from_fit_x(t.knee_x),
            offset_control: sign * from_fit_x(e.fit.x_intercept().unwrap_or(t.knee_x)),
        })
    });

    // An abrupt break overrides the class (the yield and the threshold above were judged
    // without it). A gradual fall (a wire sliding through three-point supports, necking) keeps
    // its class and the break warning.
    let before_break = behaviour;
    let behaviour = if found_break.is_some_and(|(j, _, k)| break_is_abrupt(&rm, k, j)) {
        Behaviour::Broken
    } else {
        behaviour
    };

    let large_deflection = match (&elastica, &elastic, &stiffness) {
        (Some(tab), Some(e), Some(st)) => {
            let limit = tab.small_deflection_limit(opts.small_deflection_tolerance);
            let (a, b) = e.window_idx;
            let wmax = fw[a..b]
                .iter()
                .fold(0.0f64, |m, v| m.max((v - toe_w).abs()))
                / l0;
            let test_max = xs.iter().fold(0.0f64, |m, v| m.max((v - toe_w).abs())) / l0;
            if test_max > limit {
                warnings.push(format!(
                    "three-point test reaches w/l0 = {test_max:.4}, beyond the small-deflection range (w/l0 <= {limit:.4}): the stiffness is corrected by the exact elastica, but the peak curvature/moment estimates are not accurate there"
                ));
            }
            match linear_fit(&fw[a..b], &fy[a..b]) {
                Ok(f) => Some(LargeDeflection {
                    corrected_stiffness: st.value,
                    small_deflection_stiffness: f.slope * factor,
                    window_w_over_span: wmax,
                    max_w_over_span: test_max,
                    small_deflection_limit: limit,
                }),
                Err(err) => {
                    why.insert("large_deflection".into(), format!("eq. (3) fit: {err}"));
                    None
                }
            }
        }
        (Some(_), _, _) => {
            why.insert("large_deflection".into(), "no stiffness".into());
            None
        }
        _ => None,
    };
    let mut holds = hold_relaxation(
        &segments,
        (&c, &r),
        (3.0 * cn.noise).max(control_resolution),
        serial.0.phi,
        (serial.1, serial.2),
    );
    // A hold after the specimen broke holds its pieces: what the load cell reads there is no
    // material's relaxation (a testXpert Invar export, stopped after its fracture, was
    // "rate dependent" from it).
    if let Some((j, _, _)) = found_break {
        let after = holds.iter().filter(|h| h.start >= j).count();
        if after > 0 {
            holds.retain(|h| h.start < j);
            notes.push(format!(
                "{after} hold(s) after the break at sample {} are not judged for relaxation (the specimen is broken there)",
                j + 1
            ));
        }
    }
    // Rate dependence: every hold that trends relaxes, and two do (or the only one): a viscous
    // specimen relaxes after loading and recovers after unloading; a drift trends one way at
    // every hold, whatever the control did before it; one hold's fluke among several is not a
    // material.
    let trending: Vec<&HoldRelaxation> = holds.iter().filter(|h| h.significant).collect();
    let rate_dependent = trending.iter().all(|h| h.relaxes)
        && (trending.len() >= 2 || (holds.len() == 1 && trending.len() == 1));
    if rate_dependent {
        warnings.push("the response relaxes during holds: the material is rate dependent (viscous); rate-independent results are approximate".into());
    } else if trending.iter().any(|h| h.relaxes) && trending.iter().all(|h| h.relaxes) {
        warnings.push(format!(
            "the response relaxes during {} of {} holds: possibly rate dependent",
            trending.len(),
            holds.len()
        ));
    } else if !trending.is_empty() {
        warnings.push(format!(
            "the response trends during {} hold(s), not all toward relaxation: a drifting sensor or an unsteady rig",
            trending.len()
        ));
    }
    // Without holds (or with holds that do not show it): the stiffness near reversals against
    // the stroke's rate (`crate::rate`), for a test whose loops do not close (`other`:
    // friction, viscosity or drift; `elastoplastic`: a viscous first loading bends and its
    // unloading ends at a positive control, as plasticity's does).
    // Slopes in `fit_xs` (three-point: strokes reversing at different deflections would
    // otherwise differ by geometry alone), rates in the sectional control (linear in the
    // machine's: `fit_xs` would turn one machine speed into rates that fall with the
    // deflection). Three-point: in contact only, and strokes from the same deflection only
    // (`crate::rate`; the punch is off the rod where the force is within 5 σ of zero).
    let rate_effect = crate::rate::rate_effect(&crate::rate::RateInputs {
        segments: &segments,
        time_s,
        control: &fit_xs,
        rate_control: &xs,
        response: &rm,
        contact_floor: three.then_some(CONTACT_FLOOR_SIGMA * serial.0.sigma),
        phi: serial.0.phi,
        prior: (serial.1, serial.2),
    });
    let by_rate = !rate_dependent
        && matches!(behaviour, Behaviour::Other | Behaviour::Elastoplastic)
        && rate_effect.as_ref().is_some_and(|e| e.rate_dependent);
    if let (true, Some(e)) = (by_rate, &rate_effect) {
        let show = |t: &crate::rate::RateTrend| {
            format!(
                "{} strokes {:.3e} at rate {:.3e} vs {:.3e} at {:.3e} ({:.1} standard errors)",
                if t.rising { "rising" } else { "falling" },
                t.slopes[0],
                t.rates[0],
                t.slopes[1],
                t.rates[1],
                t.z
            )
        };
        warnings.push(format!(
            "the response depends on the rate: near their reversals strokes at different rates differ in stiffness beyond what a drift explains ({}; slopes in response per sectional control, {}): the material is rate dependent (viscous); rate-independent results are approximate{}",
            e.trends.iter().map(show).collect::<Vec<_>>().join("; "),
            sectional_unit(kind),
            if yield_point.is_some() {
                ", and the yield point may be the viscous softening of the first loading"
            } else {
                ""
            }
        ));
    }
    let behaviour = if (rate_dependent || by_rate) && behaviour != Behaviour::Broken {
        Behaviour::RateDependent
    } else {
        behaviour
    };
    // Report cycles in the original orientation.
    let cycles_out: Vec<CycleResult> = cyc
        .into_iter()
        .map(|mut c| {
            c.residual = c.residual.map(|v| sign * v);
            c.contact_loss_control = c.contact_loss_control.map(|v| sign * v);
            c.peak_control *= sign;
            c.peak_sectional *= sign;
            c.peak_response *= sign;
            c
        })
        .collect();

    let behaviour_class = match behaviour {
        Behaviour::Broken => before_break.class(),
        other => other.class(),
    };
    Ok(Analysis {
        behaviour_class,
        kind,
        stiffness,
        modulus_pa,
        yield_point,
        cycles: cycles_out,
        behaviour,
        piecewise,
        large_deflection,
        toe,
        offsets,
        noise,
        segments,
        holds,
        rate_effect,
        max_response,
        break_point,
        sudden_drops: drops,
        excluded_samples: excluded,
        warnings,
        notes,
        why: join_why(&why),
        why_by_key: why,
    })
}

/// The initial straight part of cycle 1's first unloading run (sectional `x`, response `y`,
/// while the response is still positive; none when the run starts above `top`;
/// [`crate::elastic::initial_window`]) fitted with the AR(1) interval of the record's noise
/// (`phi`, `prior` σ and its degrees of freedom).
fn first_unloading_fit(
    segments: &[Segment],
    x: &[f64],
    top: f64,
    y: &[f64],
    phi: f64,
    prior: (f64, f64),
) -> Option<crate::stats::Fit> {
    let s = segments
        .iter()
        .find(|s| s.cycle == 1 && s.branch == Branch::Unloading)?;
    let b = s.end;
    let a = crate::hysteresis::turn_of(x, s.start.saturating_sub(1), b);
    if !(x[a] <= top) {
        return None;
    }
    let pos_end = (a..b).find(|&i| y[i] <= 0.0).unwrap_or(b);
    let (p, q) = crate::elastic::initial_window(&x[a..pos_end], &y[a..pos_end], phi)?;
    let pos: Vec<usize> = (a + p..a + q).collect();
    crate::stats::linear_fit_ar1(&x[a + p..a + q], &y[a + p..a + q], &pos, phi, Some(prior)).ok()
}

/// Response change over each hold that is not the initial rest (see [`HoldRelaxation`];
/// `tol` the control's stillness, three noise σ or its resolution if larger; `phi` and
/// `prior` the record's AR(1) noise, as for the stiffness interval).
fn hold_relaxation(
    segments: &[Segment],
    (control, response): (&[f64], &[f64]),
    tol: f64,
    phi: f64,
    prior: (f64, f64),
) -> Vec<HoldRelaxation> {
    let held: Vec<&Segment> = segments
        .iter()
        .filter(|s| s.branch == Branch::Hold && s.start > 0 && s.end - s.start >= 20)
        .collect();
    let alpha = 1e-3 / held.len().max(1) as f64;
    let z = crate::stats::normal_quantile(1.0 - alpha / 2.0);
    // A hold's band reaches into the ramps on either side (it is one reversal threshold
    // wide): only its core, where the control is within its noise or resolution of the
    // hold's median, is still; the ramps' ends would otherwise pass for relaxation.
    held.into_iter()
        .filter_map(|s| {
            let med = crate::stats::median(&control[s.start..s.end]);
            let still = |i: &usize| (control[*i] - med).abs() <= tol;
            let a = (s.start..s.end).find(still)?;
            let b = (s.start..s.end).rev().find(still)? + 1;
            (b >= a + 20).then_some((s, a, b))
        })
        .map(|(s, a, b)| {
            let s = &Segment {
                start: a,
                end: b,
                ..*s
            };
            let y = &response[s.start..s.end];
            let b = (y.len() / 10).max(3);
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            let change = mean(&y[y.len() - b..]) - mean(&y[..b]);
            let idx: Vec<f64> = (0..y.len()).map(|i| i as f64).collect();
            let pos: Vec<usize> = (s.start..s.end).collect();
            let significant = match crate::stats::linear_fit_ar1(&idx, y, &pos, phi, Some(prior)) {
                Ok(f) if f.slope_se > 0.0 => f.slope.abs() > z * f.slope_se,
                Ok(f) => f.slope != 0.0,
                Err(_) => false,
            };
            // The control's move into the hold: from the start of the segment before it.
            let before = segments
                .iter()
                .rev()
                .find(|p| p.end <= s.start && p.branch != Branch::Hold)
                .map_or(0, |p| p.start);
            let into = control[s.start] - control[before];
            HoldRelaxation {
                cycle: s.cycle,
                start: s.start,
                end: s.end,
                control: mean(&control[s.start..s.end]),
                response_change: change,
                significant,
                relaxes: significant && change * into < 0.0,
            }
        })
        .collect()
}

/// Young's moduli outside this range (Pa) are no solid's: from soft elastomers (~0.1 MPa) to
/// diamond (~1.2 TPa). A modulus outside is reported with a warning, not refused.
pub const PLAUSIBLE_MODULUS_PA: (f64, f64) = (1e5, 1.2e12);

/// The largest strain (dimensionless) a specimen can show: 20, i.e. 2000 % (elastomers break
/// below 10). A control beyond it is warned as misread.
pub const PLAUSIBLE_STRAIN: f64 = 20.0;

/// Fewest samples a stiffness is computed from.
pub const MIN_STIFFNESS_SAMPLES: usize = 5;

/// Why a stiffness must not be printed at all, if so: fewer than [`MIN_STIFFNESS_SAMPLES`]
/// samples in the window, or a first loading whose response never rises beyond 10 σ of its
/// noise (a flat response: any slope is noise). A 95 % interval that contains zero is a doubt
/// next to the number ([`stiffness_doubts`]), not a refusal: with serially correlated noise a
/// short window's honest interval can be that wide while the slope is still the best estimate.
fn refuse_stiffness(s: &Stiffness, first_rise: f64, sigma_r: f64) -> Option<String> {
    if !(first_rise > 10.0 * sigma_r) {
        return Some(format!(
            "the response does not rise beyond its noise over the first loading (range {first_rise:.3e}, noise σ {sigma_r:.3e}): a flat response has no stiffness"
        ));
    }
    if s.n < MIN_STIFFNESS_SAMPLES {
        return Some(format!(
            "the elastic window holds only {} samples; a stiffness needs at least {MIN_STIFFNESS_SAMPLES}",
            s.n
        ));
    }
    None
}

/// The first unloading from beyond the first loading's bend `b` (sectional control `x`, oriented
/// response `y`) that passes below the bend's response without nearing zero (load-controlled
/// cycles between two loads, which leave no residual at zero load to judge), when its control
/// at the response halfway between its lowest and the bend's lies past the first loading's at
/// that response by more than a quarter of the latter: (cycle, that response, the set). A
/// reversible threshold's unloading retraces the first loading below its bend; a yielded
/// specimen's runs parallel to it, shifted by its plastic deformation.
fn set_below_bend(
    segments: &[Segment],
    first_idx: &[usize],
    (x, y): (&[f64], &[f64]),
    b: Hinge,
) -> Option<(usize, f64, f64)> {
    let yb = b.knee_y;
    if !(yb > 0.0) {
        return None;
    }
    segments
        .iter()
        .filter(|s| s.branch == Branch::Unloading && s.end > s.start + 2)
        .filter(|s| x[s.start] > b.knee_x)
        .find_map(|s| {
            let low = y[s.start..s.end]
                .iter()
                .fold(f64::INFINITY, |m, &v| m.min(v));
            if low <= 0.1 * yb || low >= 0.9 * yb {
                return None;
            }
            let level = 0.5 * (low + yb);
            let ku = (s.start..s.end).find(|&k| y[k] <= level)?;
            let xu = x[ku];
            let xl = x[*first_idx.iter().find(|&&i| y[i] >= level)?];
            let by = xu - xl;
            // A plastic set unloads elastically, parallel to the first loading's elastic line:
            // its secant from the peak to the level at least 0.7 as steep as that line's
            // secant to the bend (a silicone's Mullins-softened unloading: 0.49). A softened elastomer's unloading (Mullins, viscous lag) is
            // flatter: it may still return to zero, so it says nothing here.
            // Never steeper than the hinge's own slope before the bend: where a hold swallowed
            // the start of a sparse first ramp (10 samples a second under load control), the
            // secant from the branch's first sample, already at a third of the bend, was 1.6×
            // the elastic line's slope and every unloading "too flat" to be elastic.
            let elastic = (b.knee_y / (b.knee_x - x[first_idx[0]])).min(b.slope_before);
            let unloading = (y[s.start] - y[ku]) / (x[s.start] - xu);
            (by > 0.25 * xl.abs() && unloading >= 0.7 * elastic).then_some((s.cycle, level, by))
        })
}

/// Share of the first loading's rise within which its response counts as carrying no load
/// ([`unloaded_start`]).
const UNLOADED_SHARE: f64 = 0.05;

/// The automatic window `e` of the first loading (`x`, `y`), or a better one when it is not on
/// the specimen's elastic line, with a note saying why:
/// - the window lies before the load is taken up ([`unloaded_start`]): the window is searched
///   beyond it;
/// - then, the record's noise reads as so serially correlated (φ ≥ 0.99: a force control's
///   wobble, a furnace's drift) that no bend stands out under it, and the window lies on a part
///   at most a third as steep as a straight piece of the white segmentation that carries at
///   least a fifth of the rise (its plastic part): the white-noise window is taken.
fn off_the_elastic_line(
    e: ElasticRange,
    (x, y): (&[f64], &[f64]),
    phi: f64,
    breaks: &crate::elastic::BreakSearch,
    control_at: impl Fn(f64) -> f64,
    factor: f64,
    notes: &mut Vec<String>,
) -> ElasticRange {
    let mut e = e;
    if let Some(s) = unloaded_start(x, y, &e) {
        if let Ok(mut later) = auto_elastic_range_ar1(&x[s..], &y[s..], phi) {
            if later.fit.slope > 0.0 {
                notes.push(format!(
                    "the first loading takes up no load until the control reaches {:.4e} (its response stays within {:.0} % of its rise while the control advances: a thermal or settling phase, slack, or seating), and the automatic window found before it had slope {:.4e}: the window is searched beyond it",
                    control_at(x[s]),
                    100.0 * UNLOADED_SHARE,
                    e.fit.slope * factor,
                ));
                later.window_idx = (later.window_idx.0 + s, later.window_idx.1 + s);
                e = later;
            }
        }
    }
    if phi >= 0.99 {
        let seg = breaks.segment(3, 0.0);
        let rise = y.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v)) - y[0];
        let mut bounds = vec![0];
        bounds.extend(seg.breaks.iter().copied());
        bounds.push(x.len());
        let steep = seg
            .slopes
            .iter()
            .zip(bounds.windows(2))
            .filter(|(&k, w)| w[1] - w[0] >= 10 && k * (x[w[1] - 1] - x[w[0]]) >= 0.2 * rise)
            .map(|(&k, _)| k)
            .fold(0.0f64, f64::max);
        if rise > 0.0 && e.fit.slope < steep / 3.0 {
            if let Ok(white) = auto_elastic_range_searched(x, y, 0.0, Some(breaks)) {
                if white.fit.slope >= steep / 3.0 {
                    notes.push(format!(
                        "the record's noise reads as strongly serially correlated (lag-1 φ = {phi:.3}: a wobble of the control loop or a drift rather than noise), under which the first loading's bend does not stand out; the window it gave, {:.4e} .. {:.4e}, has slope {:.4e}, under a third of the first loading's steepest straight piece ({:.4e}): the window is the white-noise one",
                        control_at(e.window[0]),
                        control_at(e.window[1]),
                        e.fit.slope * factor,
                        steep * factor,
                    ));
                    e = white;
                }
            }
        }
    }
    e
}

/// Where the first loading (`x`, `y`) starts to take up load, when the automatic window `e`
/// lies before it: the window's line rises by less than [`UNLOADED_SHARE`] of the loading's
/// rise to its peak, or falls, and the response is still within that share of its start at a
/// later sample before the peak. Returns that last sample. A hot tensile bar held at a small
/// force while it heats (its extensometer running on with the thermal strain) makes such a
/// start: seen on an HBM catman export, whose window fell on the heating (slope −1.2e4 N
/// against the bar's 2.3e6 N).
fn unloaded_start(x: &[f64], y: &[f64], e: &ElasticRange) -> Option<usize> {
    let kp = (0..y.len()).max_by(|&i, &j| y[i].total_cmp(&y[j]).then(j.cmp(&i)))?;
    let rise = y[kp] - y[0];
    let (a, b) = e.window_idx;
    if !(rise > 0.0) || b == 0 || b > kp {
        return None;
    }
    let window_rise = e.fit.slope * (x[b - 1] - x[a]);
    if window_rise >= UNLOADED_SHARE * rise {
        return None;
    }
    let s = (b..kp)
        .rev()
        .find(|&i| y[i] <= y[0] + UNLOADED_SHARE * rise)?;
    (kp - s >= 10).then_some(s)
}

/// Largest share of the first loading's peak response at which an automatic window may end
/// before [`stiff_start`] looks past it.
pub const STIFF_START_SHARE: f64 = 0.1;

/// The automatic window `e` on the first loading (`x`, `y`) when it is only the loading's stiff
/// start: it ends below [`STIFF_START_SHARE`] of the peak response, and past it a straight
/// stretch at least three times as long, over at least three times the response, with r² ≥ 0.99
/// and a slope below 0.8 × the window's, runs on to the bend. An extensometer's knife edges
/// seating, or a preload settling, make such a start; a piecewise-elastic law's first slope does
/// too (which the window then rightly is), so nothing is changed: the warning gives the other
/// stretch's range, in percent of the peak as `--fit-window` takes it, and its slope. Seen on a
/// real Bluehill aluminium export (17 samples up to 6 % of the peak, E 167 GPa; the stretch after
/// it, 6–36 %, 78 GPa). The steel 1045 extensometer record's window (0–0.05 % strain, E 313 GPa
/// for the reference's 250) reaches 18 % of its peak on a curve that softens throughout: not
/// this case, and not warned this way.
fn stiff_start(x: &[f64], y: &[f64], e: &ElasticRange, phi: f64) -> Option<String> {
    let peak = y.iter().fold(0.0f64, |m, v| m.max(*v));
    let (a, b) = e.window_idx;
    if !(peak > 0.0) || b < 1 || b > y.len() || y[b - 1] > STIFF_START_SHARE * peak {
        return None;
    }
    let (rx, ry) = (&x[b..], &y[b..]);
    if rx.len() < 30 {
        return None;
    }
    let next = auto_elastic_range_ar1(rx, ry, phi).ok()?;
    let (c, d) = next.window_idx;
    let span = |lo: usize, hi: usize, v: &[f64]| v[hi - 1] - v[lo];
    let longer = next.fit.n >= 3 * e.fit.n && span(c, d, ry) >= 3.0 * span(a, b, y);
    let ratio = next.fit.slope / e.fit.slope;
    if !(longer && next.fit.r2 >= 0.99 && ratio < 0.8 && ratio > 0.0) {
        return None;
    }
    let pct = |v: f64| (100.0 * v / peak).round();
    let (q0, q1) = (pct(ry[c]), pct(ry[d - 1]));
    Some(format!(
        "the automatic window ends at {:.0} % of the first loading's peak response: it is the \
         loading's stiff start (an extensometer seating, a preload settling, or a first elastic \
         slope); the longer straight stretch after it, {q0:.0}–{q1:.0} % of the peak ({} samples, \
         r² {:.4}), has {ratio:.2} × its slope: if the start is not the specimen's, pass \
         --fit-window {q0:.0}%,{q1:.0}%",
        pct(y[b - 1]),
        next.fit.n,
        next.fit.r2,
    ))
}

/// Doubts about a stiffness that is printed: a negative value, a 95 % interval that contains
/// zero, a poor straight-line fit (r² < 0.99), few samples (< 20), a wide interval (half-width
/// > 5 % of the value).
fn stiffness_doubts(s: &Stiffness) -> Vec<String> {
    let mut out = Vec::new();
    if s.ci95[0] <= 0.0 && s.ci95[1] >= 0.0 {
        out.push(format!(
            "the 95 % interval [{:.4e}, {:.4e}] {} contains zero: the slope is not distinguishable from none",
            s.ci95[0], s.ci95[1], s.unit
        ));
    }
    if !(s.value > 0.0) {
        out.push(format!(
            "the elastic slope is not positive ({:.4e} {})",
            s.value, s.unit
        ));
    }
    if s.r2 < 0.99 {
        out.push(format!("poor straight-line fit (r² = {:.3})", s.r2));
    }
    if s.n < 20 {
        out.push(format!("fitted on only {} samples", s.n));
    }
    let half = 0.5 * (s.ci95[1] - s.ci95[0]);
    if s.value != 0.0 && half > 0.05 * s.value.abs() {
        out.push(format!(
            "wide 95 % interval (±{:.1} % of the value)",
            100.0 * half / s.value.abs()
        ));
    }
    out
}

/// Indices of the virgin envelope: the first loading, then each later loading from its first
/// sample beyond every earlier extreme (by more than the reversal threshold, so noise on a
/// repeated amplitude adds nothing) to its end. `cm` is the oriented control, `h` its reversal
/// threshold.
fn virgin_envelope(segments: &[Segment], cm: &[f64], first_idx: &[usize], h: f64) -> Vec<usize> {
    let mut out = first_idx.to_vec();
    let mut top = first_idx
        .iter()
        .map(|&i| cm[i])
        .fold(f64::NEG_INFINITY, f64::max);
    for s in segments.iter().filter(|s| s.branch == Branch::Reloading) {
        // Earlier extremes include everything before this segment.
        let before = cm[..s.start]
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        top = top.max(before);
        if let Some(j) = (s.start..s.end).find(|&j| cm[j] > top + h) {
            // Join where the reloading reaches the previous extreme.
            let from = (s.start..j)
                .rev()
                .find(|&k| cm[k] <= top)
                .map_or(j, |k| k + 1);
            out.extend(from..s.end);
            top = cm[s.start..s.end].iter().copied().fold(top, f64::max);
        }
    }
    out
}

/// Share of the small-deflection limit a slack before contact must reach for the three-point
/// deflection to be counted from contact: below it, counting from zero stroke moves the
/// elastica correction's slope by less than about 0.1 % of the tolerance's softening.
const TOE_SHARE_OF_LIMIT: f64 = 0.05;

/// Three-point: the oriented stroke where the first loading's elastic line meets zero force
/// (the punch meets the specimen after a slack or gap), found on the uncorrected first loading
/// within the geometry limit `reach_w`; 0 when that is not beyond [`TOE_SHARE_OF_LIMIT`] of the
/// small-deflection limit `limit_w` or no elastic range is found. The x-intercept of the
/// uncorrected line differs from the corrected one's by the elastica's softening over the
/// window (≤ 1 % of the window's stroke), which moves the corrected slope by far less.
fn toe_before_contact(
    xs: &[f64],
    rm: &[f64],
    first_idx: &[usize],
    reach_w: f64,
    limit_w: f64,
) -> f64 {
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for &i in first_idx {
        if xs[i].abs() > reach_w {
            break;
        }
        x.push(xs[i]);
        y.push(rm[i]);
    }
    let reach = x.iter().fold(0.0f64, |m, v| m.max(*v));
    crate::elastic::auto_elastic_range(&x, &y)
        .ok()
        .and_then(|e| e.fit.x_intercept())
        .filter(|w| w.is_finite() && *w > TOE_SHARE_OF_LIMIT * limit_w && *w < reach)
        .unwrap_or(0.0)
}

/// Fewest samples of a three-point window moved into the small-deflection range.
const MIN_SMALL_DEFLECTION_SAMPLES: usize = 20;

/// Three-point: an automatic elastic window `e` that reaches beyond the small-deflection limit
/// (`limit_w`, punch deflection in m, where eq. (3) errs by the tolerance) is found again on
/// the part of the envelope within the limit, when that part holds an elastic range of at
/// least [`MIN_SMALL_DEFLECTION_SAMPLES`] samples; the toe and the bend stay those
/// of the whole envelope. Returns the range and, when the window was moved, the slope of the
/// wider window: the reported interval must span it, since the two differ by the choice of
/// window (on a real MTS export of a PLA beam, 5.63·10⁻² N m² ± 0.15 % at w/l₀ = 0.03–0.065
/// against 5.0–5.3·10⁻² from lines within 10–50 % of the maximum). A warning says so when the
/// wider slope lies outside the interval (where the elastica correction holds, as on the
/// virtual lab's rods, the two agree and nothing is said); a window that cannot be moved is
/// kept with a warning that it lies beyond the limit.
///
/// Does not touch a user-set window.
fn small_deflection_window(
    e: ElasticRange,
    (fx, fy, fw): (&[f64], &[f64], &[f64]),
    phi: f64,
    (limit_w, l0): (f64, f64),
    warnings: &mut Vec<String>,
) -> (ElasticRange, Option<f64>) {
    let (a, b) = e.window_idx;
    // The punch touches the specimen where the elastic line meets zero force: a slack or a
    // gap before contact (a real Shimadzu flexure export: 0.63 mm of travel before the force
    // rises, on a 20 mm span) is no deflection, so the limit counts from there.
    let reach = fw.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let contact = e
        .fit
        .x_intercept()
        .filter(|w| w.is_finite() && *w > 0.0 && *w < reach)
        .unwrap_or(0.0);
    let top = fw[a..b]
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs() - contact));
    if !(top > limit_w) {
        return (e, None);
    }
    let m = fw
        .iter()
        .position(|v| v.abs() - contact > limit_w)
        .unwrap_or(fw.len());
    let inner = (m >= MIN_SMALL_DEFLECTION_SAMPLES)
        .then(|| auto_elastic_range_ar1(&fx[..m], &fy[..m], phi).ok())
        .flatten()
        .filter(|f| f.fit.n >= MIN_SMALL_DEFLECTION_SAMPLES && f.fit.slope > 0.0);
    let (top, limit) = (top / l0, limit_w / l0);
    match inner {
        Some(f) => {
            let wider = e.fit.slope;
            // Said only where the choice matters: the wider window's slope lies outside the
            // interval of the window within the limit.
            if !(f.fit.slope_ci95[0]..=f.fit.slope_ci95[1]).contains(&wider) {
                warnings.push(format!(
                    "stiffness: the automatic window reached w/l0 = {top:.4}, beyond the small-deflection limit {limit:.4}; it is fitted within the limit instead, and its 95 % interval spans the slope of the wider window ({:+.1} %)",
                    100.0 * (wider / f.fit.slope - 1.0)
                ));
            }
            (
                ElasticRange {
                    window_idx: f.window_idx,
                    window: f.window,
                    fit: f.fit,
                    ..e
                },
                Some(wider),
            )
        }
        None => {
            warnings.push(format!(
                "stiffness: the automatic window reaches w/l0 = {top:.4}, beyond the small-deflection limit {limit:.4}, and no elastic range lies within the limit: the value rests on the elastica correction and on idealised sliding supports"
            ));
            (e, None)
        }
    }
}

/// A warning when a `linear_elastic` test's first loading (the envelope `x`, `y`, rising, from
/// `from` on: past a toe) is not straight: the slopes over the thirds of its control range
/// differ by more than a factor [`CURVED_RATIO`] and by more than 3 standard errors. A textile strip's pull
/// (a real Bluehill export) runs 1.44, 0.80, 1.3, 1.68 N/mm along it; its window at 273–320 %
/// strain and the label `linear_elastic` came with no word.
fn curved_first_loading(x: &[f64], y: &[f64], from: f64) -> Option<String> {
    let keep: Vec<usize> = (0..x.len().min(y.len()))
        .filter(|&i| x[i].is_finite() && y[i].is_finite() && x[i] >= from)
        .collect();
    let (lo, hi) = keep
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &i| {
            (a.min(x[i]), b.max(x[i]))
        });
    if keep.len() < 30 || !(hi > lo) {
        return None;
    }
    let third = |k: usize| -> Option<crate::stats::Line> {
        let (a, b) = (
            lo + (hi - lo) * k as f64 / 3.0,
            lo + (hi - lo) * (k + 1) as f64 / 3.0,
        );
        let (xs, ys): (Vec<f64>, Vec<f64>) = keep
            .iter()
            .filter(|&&i| x[i] >= a && x[i] <= b)
            .map(|&i| (x[i], y[i]))
            .unzip();
        (xs.len() >= 10)
            .then(|| crate::stats::line_fit(&xs, &ys).ok())
            .flatten()
    };
    let fits: Vec<crate::stats::Line> = (0..3).filter_map(third).collect();
    if fits.len() < 3 || fits.iter().any(|f| !(f.slope > 0.0)) {
        return None;
    }
    let (i_lo, f_lo) = fits
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.slope.total_cmp(&b.1.slope))?;
    let (i_hi, f_hi) = fits
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.slope.total_cmp(&b.1.slope))?;
    let ratio = f_hi.slope / f_lo.slope;
    let apart =
        f_hi.slope - f_lo.slope > 3.0 * (f_hi.slope_se.powi(2) + f_lo.slope_se.powi(2)).sqrt();
    let word = |i: usize| ["first", "second", "last"][i];
    (ratio > CURVED_RATIO && apart).then(|| {
        format!(
            "behaviour: the first loading is not straight: its slope is {:.3e} over the {} third of its control range and {:.3e} over the {} ({:.2} times); `linear_elastic` says only that it was not seen to yield, and the stiffness holds for its window only",
            f_lo.slope,
            word(i_lo),
            f_hi.slope,
            word(i_hi),
            ratio
        )
    })
}

/// Slopes over a first loading's thirds that differ by more than this factor make it "not
/// straight" ([`curved_first_loading`]): past a toe, a stiffening that the toe did not take up
/// shows as about 1.45 between the first and last thirds of a pull whose slope triples.
const CURVED_RATIO: f64 = 1.3;

/// Class of a test without any unloading (a monotonic test, to break or not): straight →
/// `linear_elastic`; a material bend (see [`bend_is_material`]) after an elastic range →
/// `elastoplastic`, with a warning that reversibility was assumed away (a monotonic test cannot
/// tell yield from a reversible threshold; tension tests to break are the usual case); no
/// stiffness → `other`.
fn monotonic_class(bend: bool, stiffness: bool, warnings: &mut Vec<String>) -> Behaviour {
    match (bend, stiffness) {
        (false, true) => Behaviour::LinearElastic,
        (true, true) => {
            warnings.push("behaviour: a monotonic test that bends is classed elastoplastic (the bend taken as yield); without an unloading it cannot be told from a reversible threshold".into());
            Behaviour::Elastoplastic
        }
        _ => Behaviour::Other,
    }
}

/// Least slope drop of a bend that is reported (yield or piecewise threshold): the slope after
/// the knee, and the secant from the knee to the end of the analysed envelope, must both be at
/// most 1 − this of the elastic slope.
pub const BEND_MIN_DROP: f64 = 0.2;

/// Whether a bend found on the envelope (x = fitting control, y = response) is a material
/// threshold: the slope falls by at least [`BEND_MIN_DROP`] at the knee *and stays down*: the
/// secant from the knee to the last sample of the envelope is also at most 1 − [`BEND_MIN_DROP`]
/// of the elastic slope.
///
/// A statistically significant slope change is not enough on a real export: with a load cell
/// resolving 10⁻⁴ of its range, a 4 % softening of a machine angle that includes the grips'
/// seating (a real Partner torsion export, linear within 0.5 % on its extensometer) or a short
/// slip of the extensometer, after which the curve runs on parallel to the elastic line, passes
/// any noise test. Neither is yield. Does not judge reversibility (that is the class's job).
fn bend_is_material(b: &Hinge, x: &[f64], y: &[f64]) -> bool {
    let k0 = b.slope_before;
    if !(k0 > 0.0) || !(b.slope_after <= (1.0 - BEND_MIN_DROP) * k0) {
        return false;
    }
    // The envelope's farthest sample beyond the knee.
    let Some(j) = (0..x.len())
        .filter(|&i| x[i] > b.knee_x)
        .max_by(|&i, &j| x[i].total_cmp(&x[j]))
    else {
        return false;
    };
    let ky = response_on_envelope(x, y, b.knee_x);
    let secant = (y[j] - ky) / (x[j] - b.knee_x);
    secant <= (1.0 - BEND_MIN_DROP) * k0
}

/// The bend of the envelope (x = fitting control, y = response) that is material (see
/// [`bend_is_material`]): the first one found, or, when that is too slight (a few per cent of
/// correlated noise or seating), the next one beyond its knee, judged against the elastic
/// slope before the first (one retry: the break search fits at most three lines, so a slight
/// first break can hide the real yield further on; on generated logs with AR(1) noise the
/// first break was a 2 % slope change at 65 % of the yield load).
fn material_bend(first: Hinge, x: &[f64], y: &[f64]) -> Option<Hinge> {
    if bend_is_material(&first, x, y) {
        return Some(first);
    }
    let idx: Vec<usize> = (0..x.len()).filter(|&i| x[i] >= first.knee_x).collect();
    if idx.len() < 10 {
        return None;
    }
    let xs: Vec<f64> = idx.iter().map(|&i| x[i]).collect();
    let ys: Vec<f64> = idx.iter().map(|&i| y[i]).collect();
    let (_, next, _) = crate::elastic::find_toe_and_bend(&xs, &ys);
    let next = next?;
    let judged = Hinge {
        slope_before: first.slope_before,
        ..next
    };
    bend_is_material(&judged, x, y).then_some(next)
}

/// The measured response of the envelope (x = control, y = response) at control `at`: the
/// polyline through the samples, interpolated on the first pair (in sample order) that brackets
/// `at` (the nearest sample when none does). This is where the specimen was at the bend; the
/// knee of a hinge fit is where its two straight lines meet, which lies above a rounded
/// (gradual) yield by up to the whole rounding: a real machine-travel export of a steel bar
/// gave a "yield" 2.8 % above the test's maximum force. A local straight line through several
/// samples would cut a sharp corner, and on a sparse (digitised) curve span half of it.
fn response_on_envelope(x: &[f64], y: &[f64], at: f64) -> f64 {
    match bracket(x, at) {
        Some(j) if x[j] != x[j - 1] => {
            y[j - 1] + (y[j] - y[j - 1]) * (at - x[j - 1]) / (x[j] - x[j - 1])
        }
        Some(j) => 0.5 * (y[j - 1] + y[j]),
        None => (0..x.len())
            .min_by(|&a, &b| (x[a] - at).abs().total_cmp(&(x[b] - at).abs()))
            .map_or(f64::NAN, |k| y[k]),
    }
}

/// The first pair of consecutive samples of `x` (in sample order) that brackets `at`: the index
/// of the second.
fn bracket(x: &[f64], at: f64) -> Option<usize> {
    (1..x.len()).find(|&j| (x[j - 1] - at) * (x[j] - at) <= 0.0)
}

/// The highest the envelope (x = control, y = response, rising) can run at control `at` between
/// the two samples that bracket it (as [`response_on_envelope`] finds them), given that it rises
/// no more steeply than `before` after the first and no less steeply than `after` before the
/// second: where the two lines drawn from the samples meet, or lower. `None` where no pair
/// brackets `at` or the slopes do not bend down (`after` ≥ `before`).
fn corner_above_chord(x: &[f64], y: &[f64], at: f64, before: f64, after: f64) -> Option<f64> {
    if !(after < before) {
        return None;
    }
    let j = bracket(x, at)?;
    let (x0, y0, x1, y1) = (x[j - 1], y[j - 1], x[j], y[j]);
    if !(x1 > x0) {
        return None;
    }
    let top = (y0 + before * (at - x0)).min(y1 - after * (x1 - at));
    let chord = y0 + (y1 - y0) * (at - x0) / (x1 - x0);
    Some(top.max(chord))
}

/// Cycle and branch of the envelope sample nearest to the sectional control `x`.
fn label_at(segments: &[Segment], env_idx: &[usize], fw: &[f64], x: f64) -> (usize, Branch) {
    let k = (0..fw.len())
        .min_by(|&a, &b| (fw[a] - x).abs().total_cmp(&(fw[b] - x).abs()))
        .unwrap_or(0);
    let i = env_idx.get(k).copied().unwrap_or(0);
    segments
        .iter()
        .find(|s| s.start <= i && i < s.end)
        .map_or((1, Branch::FirstLoading), |s| (s.cycle, s.branch))
}

/// Offset yield on the envelope (x, y) from the elastic `fit`: the first crossing, after the
/// window start `from`, of y below the line y = a + k (x − offset), interpolated; with the
/// crossings of the lines whose slopes are the ends of the slope's 95 % interval (through the
/// same zero crossing) as the ranges of x and y.
fn offset_yield(
    x: &[f64],
    y: &[f64],
    fit: &crate::stats::Fit,
    offset: f64,
    from: usize,
) -> Option<(f64, f64, [f64; 2], [f64; 2])> {
    let x0 = fit.x_intercept()?;
    let cross = |k: f64| -> Option<(f64, f64)> {
        let g = |i: usize| y[i] - k * (x[i] - x0 - offset);
        let j = (from.max(1)..x.len()).find(|&j| g(j) <= 0.0 && g(j - 1) > 0.0)?;
        let (g0, g1) = (g(j - 1), g(j));
        let t = g0 / (g0 - g1);
        Some((
            x[j - 1] + t * (x[j] - x[j - 1]),
            y[j - 1] + t * (y[j] - y[j - 1]),
        ))
    };
    let (xc, yc) = cross(fit.slope)?;
    let a = cross(fit.slope_ci95[0]).unwrap_or((xc, yc));
    let b = cross(fit.slope_ci95[1]).unwrap_or((xc, yc));
    Some((
        xc,
        yc,
        [a.0.min(b.0).min(xc), a.0.max(b.0).max(xc)],
        [a.1.min(b.1).min(yc), a.1.max(b.1).max(yc)],
    ))
}

/// The break of an oriented test (`cm`, `rm`: control and response with the first motion
/// positive; `sigma` the response noise's marginal σ, robust to serial correlation,
/// [`crate::condition::serial_noise`]): the first sample after the response maximum from which
/// the response stays down, judged so that correlated noise cannot fake it:
/// * the maximum stands clear of the noise (above 10 σ);
/// * the drop is sustained: from the break sample on, the median over the next
///   max(5, 1 % of the record) samples (or all that remain, at least 3) is below
///   [`BREAK_DROP`] of the maximum, and below it by 10 σ;
/// * the response never comes back above 0.8 of the maximum, and from the maximum to the
///   drop the control only advances: it never goes back from the furthest value it reached
///   by more than its reversal threshold `h` (an unloading is no break, also one from beyond
///   the maximum: a three-point rod bent plastically softens by geometry, so its force peaks
///   early and a cycle to a larger deflection unloads below half that peak while the
///   deflection is still beyond the peak's).
///
/// When the maximum has no such break after it, the peak of the record's last loading
/// ([`last_loading_peak`]) is judged the same way, if it reaches a quarter of the maximum and the
/// response falls from 90 % of it to the drop level within max(5, 2 % of the record) samples:
/// a cyclic test that broke in a later, smaller cycle than its largest (a fatigue block's
/// falling amplitude).
///
/// The break sample is the first sample of that sustained stretch below the drop level.
/// Returns it and the work ∫ rm d(cm) up to it.
fn find_break(cm: &[f64], rm: &[f64], sigma: f64, h: f64) -> Option<(usize, f64, usize)> {
    let n = rm.len();
    let k = (0..n).max_by(|&a, &b| rm[a].total_cmp(&rm[b]))?;
    let from = |k: usize| break_after(cm, rm, sigma, h, k).map(|(j, work)| (j, work, k));
    from(k).or_else(|| {
        // A cyclic test that broke in a later cycle than its largest (a fatigue block whose
        // amplitude rises and falls, a wire that fails at the end of a campaign of cycles):
        // the peak of the record's last loading, when it is a quarter of the maximum or more
        // and the response is gone from it within the abrupt-break samples (a gradual fall at
        // the end of a cyclic record is left alone).
        let k2 = last_loading_peak(cm, rm, h)?;
        if k2 == k || rm[k2] < 0.25 * rm[k] {
            return None;
        }
        from(k2).filter(|&(j, _, _)| break_is_abrupt(rm, k2, j))
    })
}

/// The first sample of the record's last advance (`control` with its first motion positive):
/// the final stretch in which the control never goes back from the furthest value it reached
/// by more than `back`. Missing samples are skipped.
fn last_advance(control: &[f64], back: f64) -> usize {
    let mut low = f64::INFINITY;
    let mut i = control.len();
    while i > 0 {
        let v = control[i - 1];
        if v.is_finite() {
            if v > low + back {
                break;
            }
            low = low.min(v);
        }
        i -= 1;
    }
    i
}

/// The largest response of the record's last loading (`control`, `response` with the first
/// motion positive): the peak within its [`last_advance`] (allowing back-offs of `back`),
/// when the control rose into that peak by a tenth of its range up to the peak or more (not of
/// the whole record's: a fatigue coupon's actuator ran on over the broken pieces from 14 to
/// 30 mm, and the last cycle's 1 mm rise was too small against that). None when the record
/// ends in an unloading (whose last stretch within `back` is no advance).
pub fn last_loading_peak(control: &[f64], response: &[f64], back: f64) -> Option<usize> {
    let n = control.len().min(response.len());
    let s = last_advance(&control[..n], back);
    let k = (s..n)
        .filter(|&i| response[i].is_finite())
        .max_by(|&a, &b| response[a].total_cmp(&response[b]))?;
    let (lo, hi) = control[..=k]
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let from = control[s..=k]
        .iter()
        .filter(|v| v.is_finite())
        .fold(f64::INFINITY, |m, &v| m.min(v));
    (control[k] - from >= 0.1 * (hi - lo)).then_some(k)
}

/// [`find_break`] from the response peak at `k`.
fn break_after(cm: &[f64], rm: &[f64], sigma: f64, h: f64, k: usize) -> Option<(usize, f64)> {
    let n = rm.len();
    let top = rm[k];
    if !(top > 0.0 && top > 10.0 * sigma) {
        return None;
    }
    let level = BREAK_DROP * top;
    let d = (n / 100).max(5);
    let sustained = |j: usize| -> bool {
        let end = (j + d).min(n);
        if end - j < 3 {
            return false;
        }
        let m = crate::stats::median(&rm[j..end]);
        m < level && m < top - 10.0 * sigma
    };
    let j = (k + 1..n).find(|&j| rm[j] < level && sustained(j))?;
    let stays = rm[j..].iter().all(|&v| v < 0.8 * top);
    let mut furthest = cm[k];
    let onward = cm[k..=j].iter().all(|&v| {
        furthest = furthest.max(v);
        v >= furthest - h
    });
    if !(stays && onward) {
        return None;
    }
    let work = (0..j)
        .map(|i| 0.5 * (rm[i] + rm[i + 1]) * (cm[i + 1] - cm[i]))
        .sum();
    Some((j, work))
}

/// Whether the fall to the break level at sample `j` happened in an unloading the segmentation
/// found: the control had turned back by more than its reversal threshold before `j` (a test
/// unloaded after necking: a hot tensile bar's force falls from 5,300 to 400 N over 6 s while
/// its extensometer comes back 0.06 mm, which the break's own test, from the maximum to `j`
/// only, did not see). A fracture falls before the control turns back.
fn while_unloading(segments: &[Segment], j: usize) -> bool {
    segments
        .iter()
        .any(|s| s.branch == Branch::Unloading && s.start <= j && j < s.end)
}

/// Whether the fall to the break level at sample `j` happened during a hold (a segment where
/// the control stands still): a hold's stress relaxation (a ramp–hold test of soft tissue: the
/// force halves in 110 samples at a constant extension), not a break, unless the response is
/// gone within 3 samples of its last high (below a tenth of the maximum: a fracture while held).
fn relaxed_while_held(segments: &[Segment], rm: &[f64], j: usize) -> bool {
    let held = segments
        .iter()
        .any(|s| s.branch == Branch::Hold && s.start <= j && j < s.end);
    if !held {
        return false;
    }
    let top = rm[..j].iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v));
    let last_high = (0..j).rev().find(|&i| rm[i] >= 0.9 * top).unwrap_or(0);
    let gone = j - last_high <= 3 && rm[j] < 0.1 * top;
    !gone
}

/// Whether the response fell from 90 % of the peak at `k` (the maximum, or the last cycle's
/// peak the break came from) to the break level at `j` within max(5, 2 % of the record)
/// samples: a fracture, not a gradual loss of load (`rm` oriented: the peak positive). The
/// diagnosis' cut at a fracture (`bridge::diagnosable_end`) judges with the same rule.
pub fn break_is_abrupt(rm: &[f64], k: usize, j: usize) -> bool {
    let last_high = (k..j).rev().find(|&i| rm[i] >= 0.9 * rm[k]).unwrap_or(k);
    j - last_high <= (rm.len() / 50).max(5)
}

#[cfg(test)]
mod flat_section_tests {
    use super::*;
    use cablab_core::RectangularSection;

    /// The default offset on a flat b × h section: outer fibre h/2 in bending (κ = 0.004/h,
    /// w = 0.002 l₀²/(6h)), Saint-Venant's largest shear strain in torsion (thin strip: γ = K₃ h).
    #[test]
    fn default_offset_uses_the_flat_sections_outer_fibre() {
        let g = Geometry {
            free_length_m: 0.04,
            diameter_m: None,
        };
        let strip = RectangularSection {
            width_m: 1.0,
            thickness_m: 2e-3,
        };
        let off = |k| default_yield_offset_in(k, &g, Some(&strip)).unwrap().0;
        assert!((off(TestKind::PureBending) - 2.0).abs() < 1e-12);
        assert!((off(TestKind::ThreePoint) - 0.002 * 0.04f64.powi(2) / (6.0 * 2e-3)).abs() < 1e-15);
        assert!((off(TestKind::Torsion) / (3f64.sqrt() * 0.002 / 2e-3) - 1.0).abs() < 1e-9);
        assert!((off(TestKind::Tension) - 0.002).abs() < 1e-15);
        // Without a section or a diameter, bending has no default.
        assert!(default_yield_offset_in(TestKind::PureBending, &g, None).is_err());
    }
}

#[cfg(test)]
mod stiff_start_tests {
    use super::*;

    /// A first loading with a stiff start: slope 2.1 k up to 4 % of the peak, then k to a bend at
    /// 60 % and a plastic slope after it (a Bluehill aluminium test's extensometer seating).
    fn seated(start_share: f64) -> (Vec<f64>, Vec<f64>) {
        let (k, peak) = (1.0e6, 1000.0);
        let y1 = start_share * peak;
        let x1 = y1 / (2.1 * k);
        let x2 = x1 + (0.6 * peak - y1) / k;
        let n = 600;
        let x: Vec<f64> = (0..n).map(|i| 1.6e-3 * i as f64 / n as f64).collect();
        let y = x
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                let clean = if v < x1 {
                    2.1 * k * v
                } else if v < x2 {
                    y1 + k * (v - x1)
                } else {
                    0.6 * peak + 0.05 * k * (v - x2)
                };
                clean + 0.2 * (((i * 7919) % 101) as f64 / 50.0 - 1.0)
            })
            .collect();
        (x, y)
    }

    /// The stiff start is warned about with the stretch after it (its range in percent of the
    /// peak, as `--fit-window` takes it, and its slope over the window's); a first loading whose
    /// window reaches past a tenth of the peak is not.
    #[test]
    fn a_window_on_the_stiff_start_names_the_stretch_after_it() {
        let (x, y) = seated(0.04);
        let e = auto_elastic_range_ar1(&x, &y, 0.0).unwrap();
        let w = stiff_start(&x, &y, &e, 0.0).expect("a stiff start");
        assert!(w.contains("--fit-window"), "{w}");
        let ratio: f64 = w
            .split(" × its slope")
            .next()
            .and_then(|h| h.rsplit(' ').next())
            .and_then(|r| r.parse().ok())
            .unwrap();
        assert!((ratio - 1.0 / 2.1).abs() < 0.05, "{w}");
        let (x, y) = seated(0.3);
        let e = auto_elastic_range_ar1(&x, &y, 0.0).unwrap();
        assert_eq!(stiff_start(&x, &y, &e, 0.0), None);
    }

    /// A window on a first loading's unloaded start (the force wandering about a preload while
    /// the control runs on 0.5 %, then an elastic rise of slope 2e8 to 4000 over 200 samples,
    /// then hardening) is moved past the last sample within 5 % of the rise (15 samples into
    /// it), with a note; a window on the elastic rise is left alone.
    #[test]
    fn a_window_before_the_load_is_taken_up_is_moved_past_it() {
        let mut x: Vec<f64> = (0..400).map(|i| 5e-3 * i as f64 / 400.0).collect();
        let mut y: Vec<f64> = (0..400)
            .map(|i| 120.0 - 100.0 * (i as f64 / 400.0) + 3.0 * ((i * 7) % 5) as f64)
            .collect();
        for i in 1..=300 {
            let v = 5e-3 + 1e-7 * i as f64;
            let f = (2e8 * (v - 5e-3)).min(4000.0 + 2e7 * (v - 5e-3 - 2e-5));
            x.push(v);
            y.push(20.0 + f + 3.0 * ((i * 7) % 5) as f64);
        }
        let search = crate::elastic::BreakSearch::new(&x, &y);
        let on_heating = user_elastic_range(&x, &y, 1e-3, 4e-3).unwrap();
        let s = unloaded_start(&x, &y, &on_heating).expect("an unloaded start");
        assert!((410..=418).contains(&s), "{s}");
        let mut notes = Vec::new();
        let e = off_the_elastic_line(on_heating, (&x, &y), 0.0, &search, |v| v, 1.0, &mut notes);
        assert!((e.fit.slope / 2e8 - 1.0).abs() < 0.02, "{:?}", e.fit);
        assert!(notes[0].contains("takes up no load"), "{notes:?}");
        let on_rise = user_elastic_range(&x, &y, 5.0e-3, 5.2e-3).unwrap();
        assert_eq!(unloaded_start(&x, &y, &on_rise), None);
    }
}
