//! The hand-over from a read record to the physics: the complete rows of time, control and
//! response as SI slices, and the specimen geometry resolved from flags, else from the file's
//! metadata, else an error that says what is missing.
//!
//! Does not read files (see `cablab_ingest`) and does no physics (see `cablab_measure`).

use anyhow::{anyhow, bail, Result};
use cablab_core::{RectangularSection, Role, TestKind};
use cablab_ingest::{ReadOptions, TestRecord};

/// One test's curve: the complete rows (time, control and response all numbers), SI.
#[derive(Debug, Clone, Default)]
pub struct Curve {
    /// Time, s (None when the file has no time column).
    pub time_s: Option<Vec<f64>>,
    /// Machine control: elongation m, twist rad, deflection m or end rotation rad.
    pub control: Vec<f64>,
    /// Response: force N or moment N m.
    pub response: Vec<f64>,
    /// Rows of the main block that were dropped as incomplete.
    pub dropped_rows: usize,
    /// Rows that repeat the row before them exactly, time included (kept, counted).
    pub repeated_rows: usize,
    /// The record's row of each sample kept (an index into every channel of the record).
    pub rows: Vec<usize>,
    /// The curve was cut before the record's end (an extensometer taken off): the test went on
    /// beyond its last sample, so a bend at its very end is no yield it can show.
    pub cut_short: bool,
}

impl Curve {
    /// Ends the curve before sample `i` (an extensometer taken off there), marking it
    /// [`Curve::cut_short`].
    pub fn cut_at(&mut self, i: usize) {
        self.control.truncate(i);
        self.response.truncate(i);
        if let Some(t) = self.time_s.as_mut() {
            t.truncate(i);
        }
        self.rows.truncate(i);
        self.cut_short = true;
    }

    /// A steady tone on the response ([`cablab_measure::tone::pick_up`]: mains hum, a pump's
    /// or a fan's vibration), said with its frequency and its size: the diagnosis counts it in
    /// the noise floor at its RMS, and a lab may want to find its source. With a time column the
    /// frequency is in Hz as logged, and when it is where 50 or 60 Hz mains land after the
    /// logger's rate folds them (within half a percent of that rate), it says so.
    pub fn tone_note(&self, kind: TestKind) -> Option<String> {
        let tone = cablab_measure::tone::pick_up(&self.response, &self.control)?;
        let peak = self.response.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let cycles = tone.omega / std::f64::consts::TAU;
        // The logger's rate: the mean step over the record, which time stamps rounded to the
        // millisecond do not bias (93.74 Hz written as 0.011 s steps), unless pauses make it
        // differ from the median step by a tenth.
        let rate = self
            .time_s
            .as_deref()
            .filter(|t| t.len() > 1)
            .and_then(|t| {
                let median = median_step(t);
                let mean = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
                let dt = if (mean / median - 1.0).abs() < 0.1 {
                    mean
                } else {
                    median
                };
                (dt > 0.0).then(|| 1.0 / dt)
            });
        let at = match rate {
            Some(fs) => {
                let f = cycles * fs;
                let mains = [50.0, 60.0].into_iter().find(|&m: &f64| {
                    let alias = (m - (m / fs).round() * fs).abs();
                    (alias - f).abs() < 0.005 * fs
                });
                match mains {
                    Some(m) if (f - m).abs() < 0.005 * fs => format!("{f:.2} Hz: {m:.0} Hz mains hum"),
                    Some(m) => format!(
                        "{f:.2} Hz as logged: {m:.0} Hz mains hum, folded by the logger's {fs:.2} Hz rate"
                    ),
                    None => format!("{f:.2} Hz as logged (or that plus a multiple of the logger's {fs:.2} Hz rate)"),
                }
            }
            None => format!("{cycles:.3} cycles per sample"),
        };
        Some(format!(
            "a steady tone on the response at {at}, {} {} RMS ({:.2} % of the largest response): the diagnosis counts it in the noise floor at its RMS, beside the random noise",
            cablab_report::text::fmt_num(tone.rms(), 3),
            kind.response_unit(),
            100.0 * tone.rms() / peak.max(f64::MIN_POSITIVE),
        ))
    }

    /// The warning for rows that repeat the one before them, time stamp included: the same
    /// sample written again (a logger's repeated record, a workbook's formula rows all showing
    /// one cached value). They carry no measurement of their own: a record of fewer than three
    /// distinct rows is refused ([`curve`]); otherwise they stay (every later stage sees the
    /// rows as written) and the warning says the fits count them.
    pub fn repeated_rows_warning(&self) -> Option<String> {
        (self.repeated_rows > 0).then(|| {
            format!(
                "{} row(s) repeat the row before them exactly (time, control and response): the same sample written again, counted by the fits as if measured ({} distinct rows of {})",
                self.repeated_rows,
                self.control.len() - self.repeated_rows,
                self.control.len()
            )
        })
    }
}

/// The error for a record without a control channel, naming the strain columns (read as
/// ratios by their names, such as DIC's `exx--1`) that could be it: a strain symbol is never
/// taken as the control unasked (an `exx` may be the axial or the transverse strain).
fn no_control(rec: &TestRecord) -> anyhow::Error {
    let file = &rec.provenance.path;
    let strains: Vec<String> = rec
        .channels
        .iter()
        .filter(|c| {
            c.role == Role::Other && c.dimension == Some(cablab_ingest::units::Dimension::Ratio)
        })
        .map(|c| format!("'{}'", c.name))
        .collect();
    // The other columns with what their units make of them: a unit stated by mistake (a
    // pipeline's `units = { Deflection = "mm2" }`) turns the deflection into an area, and the
    // error said only that no control was found.
    let others: Vec<String> = rec
        .channels
        .iter()
        .filter(|c| {
            c.role == Role::Other && c.dimension != Some(cablab_ingest::units::Dimension::Ratio)
        })
        .take(6)
        .map(|c| match c.dimension {
            Some(d) if !c.unit.is_empty() => format!("'{}' in {} ({d:?})", c.name, c.unit),
            _ if !c.unit.is_empty() => format!("'{}' in {}", c.name, c.unit),
            _ => format!("'{}' (no unit)", c.name),
        })
        .collect();
    if strains.is_empty() && !others.is_empty() {
        anyhow!(
            "{file}: no control channel (displacement, angle or rotation) was found among its columns {}: a column whose unit is not a length or an angle is not taken (check a unit given with --unit or a pipeline's `units`); name the control with --control",
            others.join(", ")
        )
    } else if strains.is_empty() {
        anyhow!("{file}: no control channel (displacement, angle or rotation) was found; name one with --control")
    } else {
        anyhow!(
            "{file}: no control channel (displacement, angle or rotation) was found; the file has strain columns ({}): name the axial one with --control",
            strains.join(", ")
        )
    }
}

/// The error for a record without a response channel, naming a force or moment column that
/// holds no number at all (every cell empty, `nan` or a no-data code): the reader keeps such a
/// column but gives it no role, and "no response channel was found" sent a user looking for a
/// naming problem.
fn no_response(rec: &TestRecord) -> anyhow::Error {
    use cablab_ingest::units::Dimension;
    let file = &rec.provenance.path;
    let empty: Vec<String> = (0..rec.channels.len())
        .filter(|&k| {
            matches!(
                rec.channels[k].dimension,
                Some(Dimension::Force | Dimension::Torque)
            ) && rec.channels[k].role == Role::Other
        })
        .filter(|&k| {
            rec.values(k)
                .is_some_and(|v| !v.iter().any(|x| x.is_finite()))
        })
        .map(|k| format!("'{}'", rec.channels[k].name))
        .collect();
    if empty.is_empty() {
        anyhow!("{file}: no response channel (force, torque or moment) was found; name one with --response")
    } else {
        anyhow!(
            "{file}: no response channel (force, torque or moment) with any number in it: {} {} none (every cell empty, nan or a no-data code); the export may have lost the channel",
            empty.join(", "),
            if empty.len() == 1 { "holds" } else { "hold" }
        )
    }
}

/// Extract the complete rows of a record. Errors name the file and the missing role.
pub fn curve(rec: &TestRecord) -> Result<Curve> {
    let file = &rec.provenance.path;
    let control = rec
        .role_values(Role::Control)
        .ok_or_else(|| no_control(rec))?;
    let response = rec
        .role_values(Role::Response)
        .ok_or_else(|| no_response(rec))?;
    let time = rec.role_values(Role::Time);
    let mut c = Curve::default();
    let mut t_out = time.as_ref().map(|_| Vec::new());
    for i in 0..control.len() {
        let ti = time.as_ref().map(|t| t[i]);
        let ok = control[i].is_finite() && response[i].is_finite() && ti.is_none_or(f64::is_finite);
        // The same time, control and response as the row before: the sample repeated.
        let repeat = ok
            && ti.is_some()
            && c.control.last() == Some(&control[i])
            && c.response.last() == Some(&response[i])
            && t_out.as_ref().and_then(|v| v.last()) == ti.as_ref();
        if repeat {
            c.repeated_rows += 1;
        }
        if ok {
            c.rows.push(i);
            c.control.push(control[i]);
            c.response.push(response[i]);
            if let (Some(v), Some(t)) = (t_out.as_mut(), ti) {
                v.push(t);
            }
        } else {
            c.dropped_rows += 1;
        }
    }
    c.time_s = t_out;
    let distinct = c.control.len() - c.repeated_rows;
    if distinct < 3 {
        bail!(
            "{file}: only {distinct} complete rows (time, control and response all numbers){}; a test needs more",
            if c.repeated_rows > 0 {
                format!(
                    " once {} that repeat the row before them exactly are set aside",
                    c.repeated_rows
                )
            } else {
                String::new()
            }
        );
    }
    Ok(c)
}

/// Correlation below which a response is taken to run against its control: a passive specimen's
/// force or moment rises with its elongation, twist, deflection or rotation over any cyclic
/// record (hysteresis, holds and drift lower the correlation, they do not reverse it).
pub const OPPOSITE_SIGNS_CORRELATION: f64 = -0.5;

/// Share of the range box (control range × response range) above which the area the path
/// encloses, ∮ (r − r̄) dc in the file's own signs, counts as energy taken up: a passive
/// specimen logged in opposite sign conventions encloses none (elastic) or a negative area.
pub const LOOP_SHARE_AGAINST_FLIP: f64 = 0.02;

/// A response recorded in the opposite sign convention to its control (a tensile force logged
/// negative against a positive elongation, a crosshead counted downwards): the Pearson
/// correlation of the two over the complete rows is below [`OPPOSITE_SIGNS_CORRELATION`] while
/// the loops, in the file's signs, take up no energy (enclosed area at most
/// [`LOOP_SHARE_AGAINST_FLIP`] of the range box). The channel that counts negative is reversed
/// ([`reverse_the_negative`]: the travel counted downwards, the force logged negative; the
/// response when that does not tell), so that every stiffness comes out positive and a force
/// logged positive keeps its sign, and the note (first) says so; a record whose response does not
/// follow its control (noise, a random file) is left alone. A response that runs against its
/// control while its loops do take up energy is no passive specimen's in either sign
/// convention (a response a quarter period or more out of phase: a soft specimen driven fast,
/// where the grip's inertia, ∝ −ü, dominates): left as it is, with the warning (second).
pub fn align_response_sign(curve: &mut Curve) -> (Option<String>, Option<String>) {
    let n = curve.control.len();
    if n < 3 {
        return (None, None);
    }
    let (c, r) = (&curve.control, &curve.response);
    let Some(rho) = correlation(c, r) else {
        return (None, None);
    };
    if rho.is_nan() {
        return (None, None);
    }
    if rho >= OPPOSITE_SIGNS_CORRELATION {
        return first_loading_against(curve, rho);
    }
    // The first loading, up to the response's largest magnitude, rising with its control says
    // the signs agree, whatever the rest does: a specimen that breaks while the control runs
    // on (a bone bent to fracture, the punch travelling 148 rows past it while the force falls
    // back) correlates against its control over the whole record.
    if let Some(first) =
        first_loading_correlation(c, r).filter(|f| *f >= -OPPOSITE_SIGNS_CORRELATION)
    {
        return (
            Some(format!(
                "the response falls as the control rises over the whole record (correlation {rho:.2}) but rises with it up to its largest magnitude (correlation {first:.2}): the signs agree, and what follows the peak (a break, a softening the control runs on through) is not reversed"
            )),
            None,
        );
    }
    let mr = r.iter().sum::<f64>() / n as f64;
    let area: f64 = (1..n)
        .map(|i| 0.5 * (r[i] + r[i - 1] - 2.0 * mr) * (c[i] - c[i - 1]))
        .sum();
    let (lo_c, hi_c) = c
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let (lo_r, hi_r) = r
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let share = area / ((hi_c - lo_c) * (hi_r - lo_r));
    if share > LOOP_SHARE_AGAINST_FLIP {
        return (
            None,
            Some(format!(
                "the response falls as the control rises (correlation {rho:.2}) while its loops take up energy in the file's own signs (enclosed area {:.0} % of the range box): no sign convention makes this a passive specimen's response — it lags or leads its control by a quarter period or more, as when the grip's inertia dominates a soft specimen driven fast; the stiffness and the loop areas are not the specimen's",
                100.0 * share
            )),
        );
    }
    let which = reverse_the_negative(curve);
    (
        Some(format!(
            "the response falls as the control rises (correlation {rho:.2}): the two channels count in opposite sign conventions (a tensile force logged negative, a travel counted downwards), so {which} and the stiffness is positive"
        )),
        None,
    )
}

/// Of two channels that count in opposite sign conventions, reverse the one that runs negative
/// ([`runs_negative`]): a travel counted downwards under a force logged positive is the
/// travel's convention, and the forces, moments and yield points are the file's own; a force
/// logged negative in tension is the force's. The response when that does not tell (a two-sided
/// cyclic record, where either will do). Says which, for the note.
fn reverse_the_negative(curve: &mut Curve) -> &'static str {
    let control_only = runs_negative(&curve.control) && !runs_negative(&curve.response);
    let v = if control_only {
        &mut curve.control
    } else {
        &mut curve.response
    };
    for x in v.iter_mut() {
        *x = -*x;
    }
    if control_only {
        "the control's sign is reversed (the response keeps the file's)"
    } else {
        "the response's sign is reversed"
    }
}

/// [`align_response_sign`] where the whole record does not say (correlation `rho` above
/// [`OPPOSITE_SIGNS_CORRELATION`]) but the first loading does: a test that softens after its
/// peak (a notched concrete beam cracking, EN 14651: the force falls back towards zero over a
/// deflection many times the peak's) correlates its control with the falling force over most
/// of the record. From the start to the response's largest magnitude, the two run against each
/// other (correlation below [`FIRST_LOADING_AGAINST`] over at least 10 samples): the response is
/// reversed, and the note says so. A real MTS 793 export logged the beam's opening positive and
/// its force negative (correlation −0.79 to the peak, −0.37 over the record); read as they were,
/// EI came out from the softening branch, 93 % low.
fn first_loading_against(curve: &mut Curve, rho: f64) -> (Option<String>, Option<String>) {
    let Some(first) = first_loading_correlation(&curve.control, &curve.response) else {
        return (None, None);
    };
    if first >= OPPOSITE_SIGNS_CORRELATION {
        return (None, None);
    }
    let which = reverse_the_negative(curve);
    (
        Some(format!(
            "the response falls as the control rises up to its largest magnitude (correlation {first:.2} there, {rho:.2} over the whole record, which softens after its peak): the two channels count in opposite sign conventions, so {which} and the stiffness is positive"
        )),
        None,
    )
}

/// The correlation of the response with its control from the start to the response's largest
/// magnitude, when that stretch holds at least 10 samples.
fn first_loading_correlation(c: &[f64], r: &[f64]) -> Option<f64> {
    let peak = (0..r.len())
        .filter(|&i| r[i].is_finite())
        .max_by(|&a, &b| r[a].abs().total_cmp(&r[b].abs()))?;
    if peak < 10 {
        return None;
    }
    correlation(&c[..=peak], &r[..=peak]).filter(|f| !f.is_nan())
}

/// Pearson's correlation of `r` on `c` from the least-squares line: the sign of the slope, the
/// root of r² (0 for a flat response, which is no evidence either way); `None` when no line fits.
fn correlation(c: &[f64], r: &[f64]) -> Option<f64> {
    cablab_measure::linear_fit(c, r)
        .ok()
        .map(|l| l.slope.signum() * l.r2.max(0.0).sqrt())
}

/// [`align_response_sign`] for a record read as `kind`, except for a strain control in tension
/// that falls as the force rises: no sign convention is at work there but, far more likely, the
/// transverse strain (Poisson's contraction: DIC's `exx` and `eyy` swap with the camera's axes,
/// as between two files of one CCFatigue series) taken for the axial one, whose (EA) would come
/// out about 1/ν too large once reversed. It is not reversed; the warning says so and names the
/// file's strain columns that rise with the force. (note, warning) as `align_response_sign`.
pub fn align_response_sign_of(
    rec: &TestRecord,
    kind: TestKind,
    curve: &mut Curve,
) -> (Option<String>, Option<String>) {
    let compressed = compression_in_tension(kind, curve);
    let (note, warning) = align_sign_of(rec, kind, curve);
    (note, warning.or(compressed))
}

/// A record read as tension whose control and response both run negative ([`runs_negative`]:
/// the travel closing, the force pushing): a compression test, or tension logged in a
/// compression sign convention. Nothing is reversed (the stiffness comes out positive either
/// way); the warning says what the values' signs mean, since cablab has no compression kind and
/// a compression record's yield and "break" are buckling and crushing, not a tensile
/// specimen's.
fn compression_in_tension(kind: TestKind, curve: &Curve) -> Option<String> {
    (kind == TestKind::Tension
        && curve.control.len() >= 3
        && runs_negative(&curve.control)
        && runs_negative(&curve.response))
    .then(|| {
        "read as tension, but the control and the response both run negative (the travel \
             closing, the force pushing): a compression test, or tension logged in a compression \
             sign convention — cablab evaluates tension, so the forces and elongations are \
             reported with the file's signs and a compression record's yield is not a tensile one"
            .to_string()
    })
}

fn align_sign_of(
    rec: &TestRecord,
    kind: TestKind,
    curve: &mut Curve,
) -> (Option<String>, Option<String>) {
    if kind != TestKind::Tension || !strain_control(rec) {
        return align_response_sign(curve);
    }
    let rho = |c: &[f64], r: &[f64]| correlation(c, r).unwrap_or(0.0);
    let against = rho(&curve.control, &curve.response);
    if against.is_nan() || against >= OPPOSITE_SIGNS_CORRELATION {
        return (None, None);
    }
    let ci = rec.channel_index(Role::Control);
    let force = rec.role_values(Role::Response).unwrap_or_default();
    let rising: Vec<String> = (0..rec.channels.len())
        .filter(|&k| {
            Some(k) != ci
                && rec.channels[k].role == Role::Other
                && rec.channels[k].dimension == Some(cablab_ingest::units::Dimension::Ratio)
        })
        .filter(|&k| {
            let v = rec.values(k).unwrap_or_default();
            let (x, y) = finite_pairs(&v, &force);
            x.len() >= 3 && rho(&x, &y) > -OPPOSITE_SIGNS_CORRELATION
        })
        .map(|k| format!("'{}'", rec.channels[k].name))
        .collect();
    let name = ci.map(|i| rec.channels[i].name.clone()).unwrap_or_default();
    (
        None,
        Some(format!(
            "the strain '{name}' falls as the force rises (correlation {against:.2}): a transverse strain (Poisson's contraction), not the axial one, most likely — its (EA) would be about 1/ν too large; it is not reversed{}",
            if rising.is_empty() {
                "; name the axial strain with --control".to_string()
            } else {
                format!(
                    "; the file's {} rise{} with the force: name the axial one with --control",
                    rising.join(", "),
                    if rising.len() == 1 { "s" } else { "" }
                )
            }
        )),
    )
}

/// Geometry from the caller (SI: m, settled where flags and pipelines are parsed), else from the
/// record's metadata, and the flat section b × h the moduli use when there is one. The length is
/// required; the section is optional (moduli need it). See [`geometry_noted`] for what else the
/// file can settle and the notes that say so.
pub fn geometry(
    rec: &TestRecord,
    kind: TestKind,
    length_m: Option<f64>,
    diameter_m: Option<f64>,
    flat: Option<RectangularSection>,
) -> Result<(cablab_measure::Geometry, Option<RectangularSection>)> {
    geometry_noted(rec, kind, length_m, diameter_m, flat).map(|(g, f, _)| (g, f))
}

/// Whether the record's control is a curvature (1/m, 1/mm).
pub fn curvature_control(rec: &TestRecord) -> bool {
    rec.channel_index(Role::Control)
        .and_then(|i| rec.channels[i].dimension)
        == Some(cablab_ingest::units::Dimension::Curvature)
}

/// Whether the record's control is a surface shear strain (a ratio or an angle named as a
/// shear strain: a torsional extensometer's `Shear Strain (deg)`).
pub fn shear_strain_control(rec: &TestRecord) -> bool {
    use cablab_ingest::units::Dimension as D;
    rec.channel_index(Role::Control).is_some_and(|i| {
        matches!(rec.channels[i].dimension, Some(D::Ratio | D::Angle))
            && shear_named(&rec.channels[i].name)
    })
}

/// Whether the record's control is a dimensionless strain (mm/mm, %, µm/m, ...).
pub fn strain_control(rec: &TestRecord) -> bool {
    rec.channel_index(Role::Control)
        .and_then(|i| rec.channels[i].dimension)
        == Some(cablab_ingest::units::Dimension::Ratio)
}

/// [`geometry`] with the notes to print next to the results when the file settled something:
/// - a free length (or gauge length) from the file's metadata;
/// - for tension with a strain control and no length anywhere: l₀ = 1 m, which only carries the
///   strain (elongation = ε l₀, and (EA) = dF/dε does not depend on l₀); likewise for torsion
///   with a surface shear strain control ((GJ) = T r / γ) and pure bending with a curvature;
/// - the section, first match wins: a diameter given; a flat b × h given (`flat`); the file's
///   diameter; for torsion and bending the file's flat b × h (testXpert `Specimen thickness` and
///   `Specimen width`, the sdata Numisheet id `T1.409W17.91`; see [`flat_section_note`]); for
///   tension the file's cross-section area (testXpert `Cross-section 6.3812 mm²`, else
///   thickness × width) as the equivalent round diameter d = √(4A/π), so that E = (EA)/A uses
///   the stated area (a stated area is the measured S₀ of ISO 6892-1, preferred to b h).
///
/// A diameter and a flat section both given is an error (one section, one modulus). Does not
/// take a flat section's (GJ) or (EI) from an equivalent diameter: they come from I = b h³/12
/// and Saint-Venant's J_t (`cablab_core::RectangularSection`).
pub fn geometry_noted(
    rec: &TestRecord,
    kind: TestKind,
    length_m: Option<f64>,
    diameter_m: Option<f64>,
    flat: Option<RectangularSection>,
) -> Result<(
    cablab_measure::Geometry,
    Option<RectangularSection>,
    Vec<String>,
)> {
    let file = &rec.provenance.path;
    // Without a control there is nothing a length would convert: say that first.
    if rec.channel_index(Role::Control).is_none() {
        return Err(no_control(rec));
    }
    let mut notes = Vec::new();
    let what = if kind == TestKind::ThreePoint {
        "support span"
    } else if length_m.is_none() && rec.extensometer_gauge_length().is_some() {
        "extensometer's gauge length"
    } else {
        "free length"
    };
    let free_length_m = match (length_m, rec.specimen.free_length_m) {
        (Some(l), _) if l.is_finite() && l > 0.0 => l,
        (Some(l), _) => bail!("{file}: the {what} must be positive, got {l} m"),
        (None, Some(l)) => {
            notes.push(format!(
                "the {what} {:.4} mm is the file's own (its metadata{})",
                l * 1e3,
                if what.starts_with("extensometer") {
                    ""
                } else {
                    "; with an extensometer, the gauge length"
                }
            ));
            l
        }
        (None, None) if kind == TestKind::Tension && strain_control(rec) => {
            notes.push(
                "no free length given: a strain control needs none, (EA) = dF/dε (l₀ = 1 m only carries the strain)"
                    .into(),
            );
            1.0
        }
        (None, None) if kind == TestKind::Torsion && shear_strain_control(rec) => {
            notes.push(
                "no free length given: a surface shear strain control needs none, (GJ) = T r / γ (l₀ = 1 m only carries the twist θ = 2 γ l₀ / d)"
                    .into(),
            );
            1.0
        }
        (None, None) if kind == TestKind::PureBending && curvature_control(rec) => {
            notes.push(
                "no free length given: a curvature control needs none, (EI) = dM/dκ (l₀ = 1 m only carries the curvature)"
                    .into(),
            );
            1.0
        }
        (None, None) => bail!(
            "{file}: the {what} is missing: the file's metadata does not give it; pass --length-mm"
        ),
    };
    if let Some(f) = &flat {
        if diameter_m.is_some() {
            bail!("{file}: give either a diameter or a flat section (width × thickness), not both");
        }
        if !(f.width_m.is_finite()
            && f.width_m > 0.0
            && f.thickness_m.is_finite()
            && f.thickness_m > 0.0)
        {
            bail!(
                "{file}: the flat section's width and thickness must be positive, got {} × {} m",
                f.width_m,
                f.thickness_m
            );
        }
        notes.push(flat_section_note(kind, f, "given"));
        let g = cablab_measure::Geometry {
            free_length_m,
            diameter_m: None,
        };
        return Ok((g, flat, notes));
    }
    let mut flat_out = None;
    let diameter_m = match (diameter_m, rec.specimen.diameter_m, rec.cross_section_m2) {
        (Some(d), _, _) if d.is_finite() && d > 0.0 => Some(d),
        (Some(d), _, _) => bail!("{file}: the diameter must be positive, got {d} m"),
        (None, Some(d), _) => Some(d),
        (None, None, Some(a)) if kind == TestKind::Tension => {
            let d = (4.0 * a / std::f64::consts::PI).sqrt();
            // Where the area came from when it is the metadata's b × h (no stated area).
            let from = match &rec.flat_section {
                Some((f, from)) if (f.area() - a).abs() <= 1e-9 * a && from.starts_with('\'') => {
                    format!(", b × h from {from}")
                }
                _ => String::new(),
            };
            notes.push(format!(
                "the modulus uses the cross-section {:.4} mm² from the file's metadata{from} (as the equivalent round diameter {:.4} mm; tension only)",
                a * 1e6,
                d * 1e3
            ));
            Some(d)
        }
        (None, None, _) => {
            if let Some((f, from)) = &rec.flat_section {
                notes.push(flat_section_note(kind, f, &format!("from {from}")));
                flat_out = Some(*f);
            }
            None
        }
    };
    Ok((
        cablab_measure::Geometry {
            free_length_m,
            diameter_m,
        },
        flat_out,
        notes,
    ))
}

/// The note that says which flat section b × h the moduli use, where it came from (`from`:
/// "given", "from the metadata's thickness and width", ...) and which section quantity the
/// kind's modulus divides by.
pub fn flat_section_note(kind: TestKind, f: &RectangularSection, from: &str) -> String {
    let q = match kind {
        TestKind::Tension => format!("A = b h = {:.4} mm²", f.area() * 1e6),
        TestKind::Torsion => format!(
            "Saint-Venant's torsion constant of the rectangle J_t = {:.4} mm⁴ (not the polar moment)",
            f.torsion_constant() * 1e12
        ),
        TestKind::ThreePoint | TestKind::PureBending => format!(
            "I = b h³/12 = {:.4} mm⁴ (bending about the width: the thickness lies in the plane of bending)",
            f.second_moment() * 1e12
        ),
        TestKind::Unknown => "no section quantity for an unknown kind".into(),
    };
    format!(
        "the moduli use the flat section {:.4} × {:.4} mm (width × thickness, {from}): {q}",
        f.width_m * 1e3,
        f.thickness_m * 1e3
    )
}

/// Whether a channel's name says shear (a torsional extensometer's "Shear Strain", German
/// "Schubverzerrung"/"Gleitung", ...).
fn shear_named(name: &str) -> bool {
    let n = name.to_lowercase();
    [
        "shear",
        "schub",
        "gleitung",
        "cisaillement",
        "cizalla",
        "taglio",
    ]
    .iter()
    .any(|w| n.contains(w))
}

/// The control in the kind's machine variable, where the file gives a strain:
/// - tension, a strain ε (extensometer, DIC; mm/mm, %, µm/m): the elongation ε l₀, so that the
///   analysis' sectional strain u/l₀ is ε itself and (EA) = dF/dε;
/// - torsion, a surface shear strain γ (a torsional extensometer's "Shear Strain", in degrees or
///   dimensionless): γ = r θ / l₀, so the twist θ = 2 γ l₀ / d (needs the diameter);
/// - pure bending, a curvature κ (a moment–curvature record): the end rotation κ l₀, so that the
///   analysis' κ_B = θ_B / l₀ is κ itself and (EI) = dM/dκ;
/// - any other strain as the control (a strain in bending, an axial strain against a torque): an
///   error naming the column: it is not the kind's control and no factor makes it one.
///
/// Returns the note that says what was done. Does not touch a control in the kind's own
/// variable.
pub fn sectional_control(
    rec: &TestRecord,
    kind: TestKind,
    geom: &cablab_measure::Geometry,
    flat: Option<&RectangularSection>,
    curve: &mut Curve,
) -> Result<Option<String>> {
    use cablab_ingest::units::Dimension as D;
    let file = &rec.provenance.path;
    let Some(i) = rec.channel_index(Role::Control) else {
        return Ok(None);
    };
    let c = &rec.channels[i];
    let show = show(c);
    let shear = shear_named(&c.name);
    match (c.dimension, kind) {
        (Some(D::Ratio), TestKind::Tension) if !shear => {
            let l = geom.free_length_m;
            for x in &mut curve.control {
                *x *= l;
            }
            Ok(Some(format!(
                "the control {show} is a strain ε, the sectional strain itself: (EA) = dF/dε, with no division by a length"
            )))
        }
        (Some(D::Ratio | D::Angle), TestKind::Torsion) if shear => {
            if let (None, Some(f)) = (geom.diameter_m, flat) {
                let c_g = f.max_shear_strain_per_twist();
                let k = geom.free_length_m / c_g;
                for x in &mut curve.control {
                    *x *= k;
                }
                return Ok(Some(format!(
                    "the control {show} is the largest surface shear strain of the flat section, γ = c_γ θ / l₀ (Saint-Venant, middle of the longer side; c_γ = {:.4} mm for {:.4} × {:.4} mm): taken as the twist θ = γ l₀ / c_γ",
                    c_g * 1e3,
                    f.width_m * 1e3,
                    f.thickness_m * 1e3
                )));
            }
            let Some(d) = geom.diameter_m else {
                bail!(
                    "{file}: the control {show} is a surface shear strain γ = r θ / l₀, not a twist angle; the twist θ = 2 γ l₀ / d needs the diameter: pass --diameter-mm (or name the twist angle with --control)"
                );
            };
            let k = 2.0 * geom.free_length_m / d;
            for x in &mut curve.control {
                *x *= k;
            }
            Ok(Some(format!(
                "the control {show} is a surface shear strain γ = r θ / l₀: taken as the twist θ = 2 γ l₀ / d (l₀ = {:.4} mm, d = {:.4} mm), so (GJ) = T r / γ",
                geom.free_length_m * 1e3,
                d * 1e3
            )))
        }
        (Some(D::Curvature), TestKind::PureBending) => {
            // The analysis takes the kind's control as the end rotation θ_B and divides by l₀
            // (κ_B = θ_B / l₀, eq. (4)): a curvature is that quotient already.
            let l = geom.free_length_m;
            for x in &mut curve.control {
                *x *= l;
            }
            Ok(Some(format!(
                "the control {show} is the curvature κ itself: (EI) = dM/dκ, with no division by a length"
            )))
        }
        (Some(D::Ratio), _) => bail!(
            "{file}: the control {show} is a {}strain, not the control of a {} test ({}); name the control with --control",
            if shear { "shear " } else { "" },
            kind.as_str(),
            match kind {
                TestKind::Tension => "an elongation or an axial strain",
                TestKind::Torsion => "a twist angle or a surface shear strain",
                TestKind::ThreePoint => "the punch deflection",
                _ => "the end rotation or the curvature",
            }
        ),
        _ => Ok(None),
    }
}

/// A warning when the control has no unit, was taken as metres, and so taken moves the
/// specimen farther than any test of its kind does: beyond its free length in tension (a strain
/// of 100 %), beyond half the span in three-point bending. Such a travel is almost surely in
/// millimetres (CCFatigue's `Machine_Displacement`, mm by its convention, written without a
/// unit); the stiffness would otherwise be a thousand times off with only the "no unit" line
/// beside it. The warning says what the millimetre reading would be and how to state it.
///
/// An angle control taken as radians is judged the same way: a torsion test whose surface
/// shear strain γ = θ r / l₀ would pass 500 % (wires twisted to fracture, ISO 7800, reach about
/// 100–300 %), a pure-bending test whose ends would turn by more than a full turn. Such an
/// angle is almost surely in degrees.
pub fn unitless_control_warning(
    rec: &TestRecord,
    kind: TestKind,
    geom: &cablab_measure::Geometry,
) -> Option<String> {
    let i = rec.channel_index(Role::Control)?;
    let ch = &rec.channels[i];
    if !ch.unit.is_empty() || ch.dimension.is_some() {
        return None;
    }
    let (lo, hi) = rec
        .values(i)?
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let l0 = geom.free_length_m;
    let range = hi - lo;
    let as_degrees = |what: String| {
        format!(
            "the control '{}' has no unit and, taken as radians, turns by {:.4} rad ({:.1} turns): {what}; if it is in degrees ({:.4} rad), state --unit '{}=deg'",
            ch.name,
            range,
            range / std::f64::consts::TAU,
            range.to_radians(),
            ch.name
        )
    };
    match kind {
        TestKind::Torsion => {
            let gamma = range * 0.5 * geom.diameter_m? / l0;
            return (gamma.is_finite() && gamma > 5.0).then(|| {
                as_degrees(format!(
                    "a surface shear strain of {:.0} % over the {:.4} mm length, which no torsion test reaches",
                    100.0 * gamma,
                    l0 * 1e3
                ))
            });
        }
        TestKind::PureBending => {
            return (range.is_finite() && range > std::f64::consts::TAU).then(|| {
                as_degrees(
                    "more than a full turn, which no bending rig turns a specimen's end by".into(),
                )
            });
        }
        _ => {}
    }
    let (limit, what, word) = match kind {
        TestKind::Tension => (1.0, "free length", "tension"),
        TestKind::ThreePoint => (0.5, "support span", "three-point bending"),
        _ => return None,
    };
    let share = range / l0;
    (share.is_finite() && share > limit).then(|| {
        format!(
            "the control '{}' has no unit and, taken as metres, moves {:.4} m, {:.0} % of the {:.4} mm {what}: no {word} test goes that far; if it is in mm ({:.3} %), state --unit '{}=mm'",
            ch.name,
            range,
            100.0 * share,
            l0 * 1e3,
            0.1 * share,
            ch.name
        )
    })
}

/// In tension, an extensometer's travel chosen as the control beside the same extensometer's
/// strain (see [`same_extensometer_strain`]) with no gauge length in the metadata: the strain
/// becomes the control (the roles are swapped in `rec`) and the note says why. `inspect` and
/// `analyze` both apply it, so that both show the control the analysis uses.
pub fn prefer_extensometer_strain(rec: &mut TestRecord, kind: TestKind) -> Option<String> {
    if kind != TestKind::Tension || rec.extensometer_gauge_length().is_some() {
        return None;
    }
    let i = rec.channel_index(Role::Control)?;
    let (k, gauge) = same_extensometer_strain(rec, i)?;
    let travel = show(&rec.channels[i]);
    rec.channels[i].role = Role::Other;
    rec.channels[k].role = Role::Control;
    Some(format!(
        "the stiffness comes from {}, the extensometer's own strain: it is the travel {travel} over a {:.2} mm gauge length, which the file does not state otherwise; the travel over the free length would not be the strain",
        show(&rec.channels[k]),
        gauge * 1e3
    ))
}

/// The file's strain channel that is the specimen-mounted travel `i` over one gauge length, and
/// that length (m): a strain-named ratio channel whose ratio to the travel is one number (the
/// middle half of the ratios within 2 % of their median) over the samples beyond a fifth of the
/// largest strain. `None` when the travel is no specimen-mounted length or no channel is so.
pub fn same_extensometer_strain(rec: &TestRecord, i: usize) -> Option<(usize, f64)> {
    use cablab_ingest::units::Dimension as D;
    let c = &rec.channels[i];
    if c.dimension != Some(D::Length) || rec.mount(i) != cablab_ingest::Mount::Specimen {
        return None;
    }
    let travel = rec.values(i)?;
    (0..rec.channels.len()).find_map(|k| {
        let o = &rec.channels[k];
        if k == i
            || o.role != Role::Other
            || o.dimension != Some(D::Ratio)
            || !cablab_ingest::strain_by_name(&o.name)
            || shear_named(&o.name)
        {
            return None;
        }
        let strain = rec.values(k)?;
        let top = strain
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let mut ratios: Vec<f64> = travel
            .iter()
            .zip(&strain)
            .filter(|(t, e)| t.is_finite() && e.is_finite() && e.abs() > 0.2 * top)
            .map(|(t, e)| t / e)
            .collect();
        if ratios.len() < 10 {
            return None;
        }
        ratios.sort_by(f64::total_cmp);
        let n = ratios.len();
        let (q1, med, q3) = (ratios[n / 4], ratios[n / 2], ratios[3 * n / 4]);
        (med > 0.0 && q1 >= 0.98 * med && q3 <= 1.02 * med).then_some((k, med))
    })
}

/// A warning when the control is an extensometer's travel whose own strain channel says its
/// gauge length, and the length the travel is divided by is another (the travel chosen with
/// `--control` over the free length): (EA) is off by their ratio.
pub fn gauge_length_warning(
    rec: &TestRecord,
    kind: TestKind,
    geom: &cablab_measure::Geometry,
) -> Option<String> {
    let i = rec.channel_index(Role::Control)?;
    if let Some(w) = gauge_not_length(rec, i, geom) {
        return Some(w);
    }
    if kind != TestKind::Tension {
        return None;
    }
    let (k, gauge) = same_extensometer_strain(rec, i)?;
    let ratio = geom.free_length_m / gauge;
    ((ratio - 1.0).abs() > 0.02).then(|| {
        format!(
            "the travel {} is divided by {:.2} mm, but the file's {} is that travel over {:.2} mm, its gauge length: (EA) comes out {ratio:.2} × the specimen's; pass --control '{}' (or --length-mm {:.2})",
            show(&rec.channels[i]),
            geom.free_length_m * 1e3,
            show(&rec.channels[k]),
            gauge * 1e3,
            rec.channels[k].name,
            gauge * 1e3
        )
    })
}

/// A warning when the length a travel `i` not known to be measured on the specimen (the
/// crosshead, an actuator) is divided by is the file's gauge length while the file also states a
/// different plain length (`TestRecord::gauge_beside_length`): which one the travel
/// spans is not written down, and the stiffness scales with it (a Bluehill CSV with `Length 32
/// mm` and `Gauge length 25 mm`: (EA) 22 % low had the length been the 32 mm between the grips).
fn gauge_not_length(rec: &TestRecord, i: usize, geom: &cablab_measure::Geometry) -> Option<String> {
    if rec.mount(i) == cablab_ingest::Mount::Specimen
        || rec.channels[i].dimension != Some(cablab_ingest::units::Dimension::Length)
    {
        return None;
    }
    let (g, gkv, l, lkv) = rec.gauge_beside_length()?;
    ((geom.free_length_m / g - 1.0).abs() < 1e-9).then(|| {
        format!(
            "the travel {} is divided by the file's '{gkv}' (an extensometer's gauge length), but \
             the file also says '{lkv}', and the travel is not known to be measured on the \
             specimen: over {} mm the stiffness would be {:.2} × this one; pass --length-mm with \
             the length the travel spans (between the grips)",
            show(&rec.channels[i]),
            cablab_report::text::fmt_num(l * 1e3, 4),
            l / g,
        )
    })
}

/// A warning when a length or diameter given (a flag, a pipeline's value) is not the file's own
/// (its metadata) by more than 1 %: every sectional value then rests on the given one. A
/// campaign's value for a file of several specimens (a sheet each, side by side) comes from one
/// of them, and a typo is a number silently off. Not said of an extensometer's gauge length
/// given where the metadata's length is the clamps' (the given one is then right). A diameter
/// given for a tension test whose file states only its cross-section is checked against that
/// area.
pub fn given_geometry_warning(
    rec: &TestRecord,
    kind: TestKind,
    length_m: Option<f64>,
    diameter_m: Option<f64>,
) -> Vec<String> {
    let off = |given: f64, own: f64| (given / own - 1.0).abs() > 0.01;
    let mut out = Vec::new();
    // A control that is already the sectional variable (a strain in tension, a curvature in
    // pure bending, a surface shear strain in torsion) takes no length: a given one changes
    // nothing the file's would give.
    let length_free = match kind {
        TestKind::Tension => strain_control(rec),
        TestKind::PureBending => curvature_control(rec),
        TestKind::Torsion => shear_strain_control(rec),
        _ => false,
    };
    if let (Some(l), Some(own), false) = (length_m, rec.specimen.free_length_m, length_free) {
        let gauge = rec.extensometer_gauge_length().map(|(g, _, _)| g);
        if off(l, own) && gauge.is_none_or(|g| off(l, g)) {
            let what = if kind == TestKind::ThreePoint {
                "support span"
            } else {
                "length"
            };
            out.push(format!(
                "the {what} given, {:.4} mm, is not the file's own {:.4} mm (its metadata): the stiffness and every sectional value use the given one; were the file right, (EA), (GJ) or (EI) would be off by the ratio of the two ({:.3}; cubed in three-point)",
                l * 1e3,
                own * 1e3,
                l / own
            ));
        }
    }
    if let (Some(d), Some(own)) = (diameter_m, rec.specimen.diameter_m) {
        if off(d, own) {
            out.push(format!(
                "the diameter given, {:.4} mm, is not the file's own {:.4} mm (its metadata): the moduli use the given one (E scales with 1/d², G and the bending moduli with 1/d⁴)",
                d * 1e3,
                own * 1e3
            ));
        }
    }
    // A tension test's stated cross-section (testXpert's `S0`, Bluehill's `Area`), which the
    // modulus uses when no diameter is given.
    if let (Some(d), None, Some(a), TestKind::Tension) = (
        diameter_m,
        rec.specimen.diameter_m,
        rec.cross_section_m2,
        kind,
    ) {
        let given = std::f64::consts::PI * d * d / 4.0;
        if off(given, a) {
            out.push(format!(
                "the diameter given, {:.4} mm ({:.4} mm²), is not the file's own cross-section {:.4} mm² (its metadata; a round diameter of {:.4} mm): the modulus uses the given one, {:.3}× the file's E",
                d * 1e3,
                given * 1e6,
                a * 1e6,
                (4.0 * a / std::f64::consts::PI).sqrt() * 1e3,
                a / given
            ));
        }
    }
    out
}

/// A modulus the file states as a result of the machine's software (Bluehill's `Modulus
/// (Automatic Young's)`, testXpert's `E-Modul`), in Pa, with the metadata key it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct StatedModulus {
    /// The metadata key, as written.
    pub key: String,
    /// The value, Pa.
    pub pa: f64,
}

/// The modulus the file's metadata states for `kind`'s modulus (a shear modulus for torsion,
/// Young's otherwise): [`cablab_ingest::stated_modulus`].
pub fn stated_modulus(rec: &TestRecord, kind: TestKind) -> Option<StatedModulus> {
    cablab_ingest::stated_modulus(&rec.metadata, kind == TestKind::Torsion)
        .map(|(pa, key)| StatedModulus { key, pa })
}

/// How far a modulus (Pa) may differ from the one the file states before it is warned.
pub const STATED_MODULUS_TOLERANCE: f64 = 0.05;

/// The modulus found here against the one the file states ([`stated_modulus`]): a warning when
/// they differ by more than [`STATED_MODULUS_TOLERANCE`] (the machine's software fitted another
/// range, or took another section or length: the two numbers are not the same thing, and a
/// reader comparing reports must know which is which), a note when they agree.
pub fn stated_modulus_check(
    stated: Option<&StatedModulus>,
    modulus_pa: Option<f64>,
) -> Option<(bool, String)> {
    let (st, ours) = (stated?, modulus_pa.filter(|m| m.is_finite() && *m > 0.0)?);
    let off = ours / st.pa - 1.0;
    let gpa = |p: f64| p / 1e9;
    Some(if off.abs() > STATED_MODULUS_TOLERANCE {
        (
            true,
            format!(
                "modulus: {:.1} GPa here, the file states {:.1} GPa ('{}'): {:+.1} %. The machine's software fitted another range or method, or used another section or length; compare its modulus window with the fit window here before comparing the numbers",
                gpa(ours),
                gpa(st.pa),
                st.key,
                100.0 * off
            ),
        )
    } else {
        (
            false,
            format!(
                "modulus: {:.1} GPa here agrees with the {:.1} GPa the file states ('{}') within {:.1} %",
                gpa(ours),
                gpa(st.pa),
                st.key,
                100.0 * off.abs()
            ),
        )
    })
}

/// An angle control read modulo a turn (an encoder's 0–360°, or ±180°: 359.3° then 0°) is
/// unwrapped: where it steps by a full turn give or take 5 of its median steps (a turn over 20
/// of them) while the response does not move (within 3 × its median step), the turn is taken
/// off from there on, and the note says where. Before, the twist fell back by a turn at
/// each wrap: the loops came out negative and the stiffness fit stopped there.
pub fn unwrap_turns(rec: &TestRecord, curve: &mut Curve) -> Option<String> {
    let ci = rec.channel_index(Role::Control)?;
    let ch = &rec.channels[ci];
    if ch.dimension != Some(cablab_ingest::units::Dimension::Angle) || curve.control.len() < 10 {
        return None;
    }
    let c = curve.control.clone();
    let r = &curve.response;
    let (mc, mr) = (median_step(&c), median_step(r));
    let turn = std::f64::consts::TAU;
    if turn <= 20.0 * mc {
        return None;
    }
    let mut offset = 0.0;
    let mut wraps = Vec::new();
    for i in 1..c.len() {
        // The step from the unwrapped sample before; a wrap leaves a step of a turn that,
        // taken off, is an ordinary step (a turning point may fall on the wrap).
        let jump = c[i] + offset - curve.control[i - 1];
        let turns = (jump / turn).round();
        if turns.abs() == 1.0
            && (jump - turns * turn).abs() <= 5.0 * mc
            && (r[i] - r[i - 1]).abs() <= 3.0 * mr
        {
            offset -= turns * turn;
            wraps.push(i + 1);
        }
        curve.control[i] = c[i] + offset;
    }
    (!wraps.is_empty()).then(|| {
        let factor = ch.factor.max(f64::MIN_POSITIVE);
        format!(
            "the control {} is read modulo a turn ({} {}): it wraps at complete row{} {}, and is unwrapped there (a turn added or taken off from that row on: the twist counted on)",
            show(ch),
            (turn / factor * 1e6).round() / 1e6,
            if ch.unit.is_empty() { ch.si_unit.as_str() } else { ch.unit.as_str() },
            if wraps.len() > 1 { "s" } else { "" },
            wraps.iter().map(|w| w.to_string()).collect::<Vec<_>>().join(", ")
        )
    })
}

/// A warning when the control jumps between two samples while the response does not move
/// back to where the record started (a step over 20 × the median step and 5 % of the control's
/// range, landing within 5 % of the range of the first sample, the response's step within 3 × its
/// median): a displacement counted from each phase's start (CellScale UniVert's
/// `Displacement_mm` back to 0 from the preload to the stretch), not the specimen's travel. It
/// names the file's other channels of the control's dimension that run on there.
pub fn control_reset_warning(rec: &TestRecord, curve: &Curve) -> Option<String> {
    let (c, r) = (&curve.control, &curve.response);
    if c.len() < 10 {
        return None;
    }
    let (mc, mr) = (median_step(c), median_step(r));
    let (lo, hi) = c
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    // Back to where the record started (within 5 % of the range), from away from it.
    let near_start = |v: f64| (v - c[0]).abs() <= 0.05 * (hi - lo);
    // Against the motion on both sides: the control ran one way, jumps the other, and runs
    // on the first way again (a fast sweep through its start is no reset).
    let i = (2..c.len() - 1).find(|&i| {
        let (before, jump, after) = (c[i - 1] - c[i - 2], c[i] - c[i - 1], c[i + 1] - c[i]);
        let dc = jump.abs();
        before * jump < 0.0
            && after * jump < 0.0
            && dc > 20.0 * mc
            && dc > 0.05 * (hi - lo)
            && near_start(c[i])
            && !near_start(c[i - 1])
            && (r[i] - r[i - 1]).abs() <= 3.0 * mr
    })?;
    let ci = rec.channel_index(Role::Control)?;
    let ch = &rec.channels[ci];
    // The other channels, on the same complete rows, that do not jump there.
    let rows = &curve.rows;
    let others: Vec<String> = (0..rec.channels.len())
        .filter(|&k| {
            k != ci
                && rec.channels[k].role == Role::Other
                && rec.channels[k].dimension.is_some()
                && rec.channels[k].dimension == ch.dimension
        })
        .filter(|&k| {
            let Some(v) = rec.values(k) else { return false };
            let v: Vec<f64> = rows.iter().map(|&j| v[j]).collect();
            v.len() == c.len()
                && v.iter().all(|x| x.is_finite())
                && (v[i] - v[i - 1]).abs() <= 3.0 * median_step(&v)
        })
        .map(|k| show(&rec.channels[k]))
        .collect();
    let factor = ch.factor.max(f64::MIN_POSITIVE);
    Some(format!(
        "the control {} jumps from {} to {} {} between complete rows {i} and {} while the response does not move: it is counted from each phase's start, not the specimen's travel{}",
        show(ch),
        (c[i - 1] / factor * 1e6).round() / 1e6,
        (c[i] / factor * 1e6).round() / 1e6,
        if ch.unit.is_empty() { ch.si_unit.as_str() } else { ch.unit.as_str() },
        i + 1,
        match others.first() {
            Some(o) => format!(
                "; {} runs on there: --control '{}'",
                others.join(", "),
                o.trim_start_matches('\'').split('\'').next().unwrap_or_default()
            ),
            None => String::new(),
        }
    ))
}

/// The median of the nonzero steps between consecutive samples of `v` (0 when none).
fn median_step(v: &[f64]) -> f64 {
    let d: Vec<f64> = v
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 0.0)
        .collect();
    let m = cablab_measure::stats::median(&d);
    if m.is_nan() {
        0.0
    } else {
        m
    }
}

/// A specimen-mounted control (an extensometer's travel or strain) that jumps back in one sample
/// while the response goes on (the step over 20 × the control's median step and a quarter of
/// the range it had reached, against its motion until then; the response's step within a tenth
/// of its range; the control not back within that quarter in the rest of the record): the
/// extensometer was taken off or slipped, as a clip-on is before fracture. What follows is no
/// measurement of the specimen — a real Bluehill export in Polish reads −0.133 after 0.044,
/// which made the strain look transverse (correlation −0.64 over the whole record) and the rest
/// of the test dozens of reversed cycles with a loop area of −24 J. The curve is cut at the
/// control's farthest reach before the jump (a slip that starts a few samples earlier goes too)
/// and a warning names the row and the channels that run on.
pub fn extensometer_removed(rec: &TestRecord, curve: &mut Curve) -> Option<String> {
    let ci = rec.channel_index(Role::Control)?;
    if rec.mount(ci) != cablab_ingest::Mount::Specimen {
        return None;
    }
    let (c, r) = (&curve.control, &curve.response);
    let n = c.len().min(r.len());
    if n < 20 {
        return None;
    }
    let mc = median_step(&c[..n]);
    let (rlo, rhi) = r[..n]
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    // A control that never moves has no step to compare a jump with.
    if mc <= 0.0 {
        return None;
    }
    let (mut lo, mut hi) = (c[0], c[0]);
    let mut cut = None;
    for i in 1..n {
        let reach = hi - lo;
        let jump = c[i] - c[i - 1];
        // The motion until then: the way the control went from its start.
        let motion = c[i - 1] - c[0];
        if reach > 0.0
            && jump * motion < 0.0
            && jump.abs() > 20.0 * mc
            && jump.abs() > 0.25 * reach
            && (r[i] - r[i - 1]).abs() <= 0.1 * (rhi - rlo)
        {
            // Not back: the control stays a quarter of the reach away from where it jumped.
            let gap = 0.25 * reach;
            if c[i..n]
                .iter()
                .all(|&v| (v - c[i - 1]) * motion.signum() < -gap)
            {
                cut = Some(i);
                break;
            }
        }
        lo = lo.min(c[i]);
        hi = hi.max(c[i]);
    }
    let jump = cut?;
    // A slip that starts a few samples before the jump (0.904, 0.903, 0.894, 0.896, 0.881, then
    // 0.775 %) is cut too: from the last sample at the control's farthest reach, when that lies
    // within the last 20 samples before the jump.
    let sign = (c[jump - 1] - c[0]).signum();
    let far = (0..jump)
        .rev()
        .take(20)
        .max_by(|&a, &b| (sign * c[a]).total_cmp(&(sign * c[b])))
        .filter(|&k| (0..jump).all(|j| sign * c[j] <= sign * c[k]));
    let i = far.map_or(jump, |k| k + 1);
    let ch = &rec.channels[ci];
    let factor = ch.factor.max(f64::MIN_POSITIVE);
    let raw = rec.values(ci).unwrap_or_default();
    let at = |j: usize| {
        curve
            .rows
            .get(j)
            .and_then(|&k| raw.get(k))
            .map_or(f64::NAN, |v| v / factor)
    };
    let (from, to) = (at(jump - 1), at(jump));
    let row = curve.rows.get(jump).map_or(jump + 1, |&k| k + 1);
    let others: Vec<String> = (0..rec.channels.len())
        .filter(|&k| {
            k != ci
                && rec.channels[k].role == Role::Other
                && rec.channels[k].dimension == Some(cablab_ingest::units::Dimension::Length)
        })
        .map(|k| show(&rec.channels[k]))
        .collect();
    let total = n;
    curve.cut_at(i);
    Some(format!(
        "the extensometer {} jumps from {} to {} {} at data row {row} (complete row {}) while the response goes on, and does not come back: taken off or slipped; the analysis ends at its farthest reach before it ({i} of {total} complete rows), the rest of the test is not analysed{}",
        show(ch),
        (from * 1e6).round() / 1e6,
        (to * 1e6).round() / 1e6,
        if ch.unit.is_empty() { ch.si_unit.as_str() } else { ch.unit.as_str() },
        jump + 1,
        if others.is_empty() {
            String::new()
        } else {
            format!(" ({} runs on to the end: --control to analyse it)", others.join(", "))
        }
    ))
}

/// The control, when it is measured on the specimen, and the first travel of the machine's
/// (crosshead, actuator) beside it: their channel indices.
fn specimen_control_and_crosshead(rec: &TestRecord) -> Option<(usize, usize)> {
    let ci = rec.channel_index(Role::Control)?;
    if rec.mount(ci) != cablab_ingest::Mount::Specimen {
        return None;
    }
    let ki = (0..rec.channels.len()).find(|&k| {
        k != ci
            && rec.channels[k].dimension == Some(cablab_ingest::units::Dimension::Length)
            && rec.mount(k) == cablab_ingest::Mount::Machine
    })?;
    Some((ci, ki))
}

/// Channel `k`'s SI values on the curve's rows (NaN where a cell is missing).
fn on_curve_rows(rec: &TestRecord, curve: &Curve, k: usize) -> Option<Vec<f64>> {
    let raw = rec.values(k)?;
    Some(
        curve
            .rows
            .iter()
            .map(|&j| raw.get(j).copied().unwrap_or(f64::NAN))
            .collect(),
    )
}

/// A warning when a specimen-mounted control starts to follow the crosshead: over the first
/// loading, at one sample its rate against the file's crosshead (machine travel) rises at least
/// 5× and stays at least 3× what it was, while the force goes on rising against the crosshead
/// as before (its rate within a factor 2). That is no material's doing (a yield bends the force
/// against the crosshead) but the software's: Bluehill continues `Strain 1` from the crosshead
/// once the clip-on extensometer is taken off, without a jump (a real flat-coupon export: after
/// a 20 s pause at 0.19 % strain the strain ran 33× faster against the crosshead, 1/26 mm, the
/// specimen's length; read as it was, a yield at 9,193 N on a coupon linear to 15,366 N). The
/// curve is cut there, as for an extensometer that jumps back ([`extensometer_removed`]).
pub fn strain_follows_crosshead(rec: &TestRecord, curve: &mut Curve) -> Option<String> {
    let (ci, ki) = specimen_control_and_crosshead(rec)?;
    let x = on_curve_rows(rec, curve, ki)?;
    let (c, r) = (&curve.control, &curve.response);
    let n = c.len().min(r.len()).min(x.len());
    // The first loading: to the response's largest magnitude.
    let peak = (0..n)
        .filter(|&i| r[i].is_finite())
        .max_by(|&a, &b| r[a].abs().total_cmp(&r[b].abs()))?;
    let w = (peak / 50).max(5);
    if peak < 4 * w || x[..=peak].iter().any(|v| !v.is_finite()) {
        return None;
    }
    let sx = (x[peak] - x[0]).signum();
    let rate = |a: usize, b: usize| {
        let dx = sx * (x[b] - x[a]);
        (dx > 0.0).then(|| ((c[b] - c[a]) / dx, (r[b] - r[a]) / dx))
    };
    // The control's rate against the crosshead that a continuation from the crosshead gives: 1
    // (the curve's control is a travel, a strain already times the length,
    // [`sectional_control`]), when that length is the file's own (else the strain was
    // multiplied by a stand-in and the rate is not judged).
    let judged = match rec.channels[ci].dimension {
        Some(cablab_ingest::units::Dimension::Ratio) => {
            rec.extensometer_gauge_length().is_some() || rec.specimen.free_length_m.is_some()
        }
        Some(cablab_ingest::units::Dimension::Length) => true,
        _ => false,
    };
    // The window pair with the largest rise of the control's rate, the force's kept.
    let mut best: Option<(f64, usize, f64, f64)> = None;
    for i in w..=peak - w {
        let (Some((a, fa)), Some((b, fb))) = (rate(i - w, i), rate(i, i + w)) else {
            continue;
        };
        if a * b <= 0.0 || fa * fb <= 0.0 {
            continue;
        }
        let rise = b / a;
        let kept = fb / fa;
        // The software continues the strain as crosshead over the specimen's length (a travel
        // as the crosshead itself): where the file states that length, the new rate must be
        // it. A yield point's Lüders band running through the gauge length makes the strain
        // race ahead too, at many times that rate, and the hardening after it brings the force
        // rate back to half the elastic one (a real steel 1045 export, 30× the crosshead's
        // strain rate: its whole plastic range was cut off as an "extensometer taken off").
        let continues = !judged || (0.7..=1.4).contains(&b);
        if rise >= 5.0
            && (0.5..=2.0).contains(&kept)
            && continues
            && best.is_none_or(|bb| rise > bb.0)
        {
            best = Some((rise, i, a, b));
        }
    }
    let (_, i, a, b) = best?;
    // The sample where the control's own steps turn to the new rate (between the two means).
    let mid = (b / a).sqrt();
    let s = (i - w + 1..=i + w).find(|&j| {
        let dx = sx * (x[j] - x[j - 1]);
        dx > 0.0 && (c[j] - c[j - 1]) / dx / a >= mid
    })?;
    // And it stays: to the peak, the control runs at least 3× its earlier rate.
    let (after, _) = rate(s - 1, peak)?;
    if after / a < 3.0 {
        return None;
    }
    let total = n;
    let f_max = r[peak];
    let row = curve.rows.get(s).map_or(s + 1, |&k| k + 1);
    curve.cut_at(s);
    Some(format!(
        "the control {} follows the crosshead {} from data row {row} on: its rate against it rises {:.0}× at once while the force goes on rising against the crosshead as before — no yield, but the extensometer taken off and the software continuing the strain from the crosshead; the analysis ends there ({s} of {total} complete rows), the rest of the test is not analysed (the response goes on to {:.4e} {})",
        show(&rec.channels[ci]),
        show(&rec.channels[ki]),
        b / a,
        f_max,
        rec.channels[rec.channel_index(Role::Response)?].si_unit
    ))
}

/// Shortest and longest gauge length a specimen-mounted strain and the machine's travel may imply
/// between them before [`strain_against_travel`] says one of their units is wrong (m): a clip-on
/// extensometer's 10 mm less a tenth, a 20 m rope.
pub const IMPLIED_GAUGE_M: (f64, f64) = (1e-3, 20.0);

/// A warning when a specimen-mounted strain control and the machine's travel cannot both be
/// right: over the first loading (to the response's largest magnitude) the travel rises by
/// Δu while the strain rises by Δε, so the length between the grips would be Δu/Δε (the load
/// train's compliance only lengthens it), and that is outside [`IMPLIED_GAUGE_M`]. A real
/// Bluehill CSV whose `Strain (%)` values were 1000× what the unit says (8 % where the 50 mm
/// bar had stretched 1.9 µm) implied 0.02 mm: its EA came out 1000× low and its yield at 555 %
/// strain, without a word.
pub fn strain_against_travel(rec: &TestRecord, curve: &Curve) -> Option<String> {
    let (ci, ki) = specimen_control_and_crosshead(rec)?;
    if rec.channels[ci].dimension != Some(cablab_ingest::units::Dimension::Ratio) {
        return None;
    }
    // The channels as the file has them (the curve's control may be an elongation by now).
    let (u, c) = (
        on_curve_rows(rec, curve, ki)?,
        on_curve_rows(rec, curve, ci)?,
    );
    let r = &curve.response;
    let n = c.len().min(r.len()).min(u.len());
    let peak = (0..n)
        .filter(|&i| r[i].is_finite())
        .max_by(|&a, &b| r[a].abs().total_cmp(&r[b].abs()))?;
    if peak < 10 {
        return None;
    }
    let (du, de) = (u[peak] - u[0], c[peak] - c[0]);
    if !(du.is_finite() && de.is_finite()) || de.abs() < 1e-9 || du.abs() < 1e-12 {
        return None;
    }
    let l = (du / de).abs();
    if (IMPLIED_GAUGE_M.0..=IMPLIED_GAUGE_M.1).contains(&l) {
        return None;
    }
    Some(format!(
        "the strain {} rises by {:.4e} while the machine's travel {} rises by {:.4e} m up to the \
         largest response: together they make the specimen {} mm long between the grips, which \
         no specimen is — one of the two channels' units is wrong (a strain logged in per mille \
         or ×1000, a travel in µm); the stiffness and the strains come from {} as read",
        show(&rec.channels[ci]),
        de,
        show(&rec.channels[ki]),
        du,
        cablab_report::text::fmt_num(l * 1e3, 3),
        show(&rec.channels[ci]),
    ))
}

/// Where the rod model stops describing a record: after the response's largest magnitude, when
/// the control runs on from there without turning back (by more than 5 % of its range: a
/// fixture's jitter after a fracture is no unloading) while
/// the response falls by more than a tenth of that peak and 10 σ of its noise — a tensile
/// specimen necking or breaking, a wire or a bone failing, none of which the geometrically
/// exact rod (uniform section, no fracture) has. Three-point bending softens by geometry after
/// its peak, which the rod does have: there only a fall below half the peak (a break) counts.
/// A cyclic record that broke in a later, smaller cycle than its largest (a fatigue block whose
/// amplitude rises and falls) is cut the same way at the peak of its last loading
/// ([`cablab_measure::last_loading_peak`]), when that peak reaches a quarter of the largest and the
/// response is then gone: below half the peak within max(5, 2 % of the record) samples.
/// The sample after the peak (the diagnosis covers the record before it) and what the note
/// says; None for a record that unloads after its peak or does not fall (every cyclic protocol
/// that ends unloaded, every record that ends at its peak).
pub fn diagnosable_end(kind: TestKind, curve: &Curve) -> Option<(usize, String)> {
    let (c, r) = (&curve.control, &curve.response);
    let n = c.len().min(r.len());
    let k = (0..n)
        .filter(|&i| r[i].is_finite() && c[i].is_finite())
        .max_by(|&a, &b| r[a].abs().total_cmp(&r[b].abs()))?;
    let (lo, hi) = c[..n]
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let back = 0.05 * (hi - lo);
    let sigma = cablab_measure::noise_level(&r[..n]);
    let sign = r[k].signum();
    // The fall after the peak at `p`, while the control runs on in `dir`: its lowest response
    // (times `sign`), when the control never turns back from there.
    let fall_after = |p: usize, dir: f64| -> Option<f64> {
        if p < 10 || n - p < 3 || dir == 0.0 {
            return None;
        }
        let mut far = c[p] * dir;
        let on = c[p..n].iter().all(|&v| {
            far = far.max(v * dir);
            v * dir >= far - back
        });
        on.then(|| {
            r[p..n]
                .iter()
                .filter(|v| v.is_finite())
                .fold(f64::INFINITY, |m, &v| m.min(v * sign))
        })
    };
    let dir = (c[k] - c[0]).signum();
    let broke = |p: usize, low: f64| {
        let peak = r[p] * sign;
        let fall = peak - low;
        let enough = if kind == TestKind::ThreePoint {
            low < 0.5 * peak
        } else {
            fall > 0.1 * peak
        };
        enough && fall > 10.0 * sigma
    };
    let end = fall_after(k, dir)
        .filter(|&low| broke(k, low))
        .map(|low| (k, low))
        .or_else(|| {
            // A cyclic record that broke in a later, smaller cycle than its largest (a fatigue
            // block's falling amplitude): the peak of its last loading, when it reaches a
            // quarter of the largest and the response is then gone (below half that peak)
            // within max(5, 2 % of the record) samples of its last 90 %.
            let oriented: Vec<f64> = c[..n].iter().map(|v| v * dir).collect();
            let signed: Vec<f64> = r[..n].iter().map(|v| v * sign).collect();
            let p = cablab_measure::last_loading_peak(&oriented, &signed, back)?;
            let peak = r[p] * sign;
            if p == k || peak < 0.25 * r[k].abs() {
                return None;
            }
            let low = fall_after(p, dir)?;
            let gone = (p..n).find(|&i| signed[i] < 0.5 * peak)?;
            (low < 0.5 * peak && broke(p, low) && cablab_measure::break_is_abrupt(&signed, p, gone))
                .then_some((p, low))
        });
    let (p, low) = end?;
    let peak = r[p] * sign;
    let of = if p == k {
        "its largest value after it"
    } else {
        "the peak of its last loading (a later cycle than its largest) after that peak"
    };
    let what = match kind {
        TestKind::Tension => "necking or fracture",
        _ => "a failure or fracture",
    };
    Some((
        p + 1,
        format!(
            "the response falls to {:.0} % of {of} while the control runs on ({what}, which the rod model does not have): the diagnosis covers the record up to that peak ({} of {n} samples)",
            (100.0 * low / peak).max(0.0),
            p + 1
        ),
    ))
}

/// The curve before sample `end` (a copy).
pub fn curve_before(curve: &Curve, end: usize) -> Curve {
    let mut c = curve.clone();
    c.cut_at(end);
    c.cut_short = curve.cut_short;
    c
}

/// Millimetres (as flags give lengths) to metres.
fn mm(v: Option<f64>) -> Option<f64> {
    v.map(|x| x * 1e-3)
}

/// One test file named on the command line (`analyze`, `diagnose`), handed over to the physics:
/// read with `t`'s reader flags, [`check`]ed, its geometry from `t`'s flags (mm → m here) or
/// the file's metadata ([`geometry`]) and its complete rows ([`curve`]). Warnings and notes are
/// pushed to `said` as they arise, so those gathered before a failure can be shown with the
/// error.
///
/// Does not condition, segment or analyse the curve.
pub fn read_test(
    path: &std::path::Path,
    t: &crate::cli::TestArgs,
    roles: Option<RoleCheck>,
    said: &mut Remarks,
) -> Result<ReadTest> {
    let (kind, mut rec) = match t.kind {
        Some(k) => {
            let kind = TestKind::from(k);
            let opts = read_options(&t.reader, Some(kind))?;
            (kind, cablab_ingest::read_path(path, &opts)?)
        }
        None => {
            let (kind, reason) = kind_of_file(path, &t.reader, said)?;
            // Read again as that kind: the channel roles are assigned as with `--kind` (the
            // reader takes the kind into the role assignment), the reason kept the file's.
            let opts = read_options(&t.reader, Some(kind))?;
            let mut rec = cablab_ingest::read_path(path, &opts)?;
            rec.kind_reason = reason;
            (kind, rec)
        }
    };
    check(&mut rec, kind, t.force_kind, roles, said)?;
    let (geom, flat, notes) = geometry_noted(
        &rec,
        kind,
        mm(t.length_mm),
        mm(t.diameter_mm),
        flat_given(t.width_mm, t.thickness_mm),
    )?;
    said.notes.extend(notes);
    said.warnings
        .extend(unitless_control_warning(&rec, kind, &geom));
    said.warnings
        .extend(gauge_length_warning(&rec, kind, &geom));
    // A flag that contradicts the file's own geometry is an error unless forced
    // (CONTRACT.md), as a contradicting --kind is.
    let contradicted = given_geometry_warning(&rec, kind, mm(t.length_mm), mm(t.diameter_mm));
    if !contradicted.is_empty() && !t.force_geometry {
        bail!(
            "{}: {}. If the file is right, leave the flag out; if the flag is right, pass --force-geometry",
            rec.provenance.path,
            contradicted.join("; ")
        );
    }
    said.warnings.extend(contradicted);
    let mut curve = curve(&rec)?;
    said.notes.extend(unwrap_turns(&rec, &mut curve));
    said.notes.extend(sectional_control(
        &rec,
        kind,
        &geom,
        flat.as_ref(),
        &mut curve,
    )?);
    said.warnings.extend(extensometer_removed(&rec, &mut curve));
    said.warnings
        .extend(strain_follows_crosshead(&rec, &mut curve));
    said.warnings.extend(strain_against_travel(&rec, &curve));
    said.warnings.extend(control_reset_warning(&rec, &curve));
    let (note, warning) = align_response_sign_of(&rec, kind, &mut curve);
    said.notes.extend(note);
    said.warnings.extend(warning);
    said.warnings.extend(curve.repeated_rows_warning());
    said.notes.extend(curve.tone_note(kind));
    Ok(ReadTest {
        rec,
        kind,
        geom,
        flat,
        curve,
    })
}

/// The kind a kind word in `path`'s file name gives `rec` (read from that file), with its control
/// channel's dimension to judge it by (`init::kind_from_name`); else the Bluehill method type of
/// the folder it is in (`init::kind_from_bluehill_folder`).
pub fn kind_from_file_name(
    rec: &TestRecord,
    path: &std::path::Path,
) -> Option<crate::commands::init::Sourced<TestKind>> {
    let control = rec
        .channel_index(cablab_core::Role::Control)
        .and_then(|i| rec.channels[i].dimension);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    crate::commands::init::kind_from_name(&name, control)
        .or_else(|| crate::commands::init::kind_from_bluehill_folder(path))
}

/// The kind of a file read without `--kind`, as `cablab run PATH...` and `cablab init` find it:
/// the file's own word (its test-type metadata, its channels' units), else a kind its name
/// states; an error naming the file when neither does. Where it came from goes to the notes and
/// is returned beside the kind.
pub fn kind_of_file(
    path: &std::path::Path,
    reader: &crate::cli::ReaderArgs,
    said: &mut Remarks,
) -> Result<(TestKind, String)> {
    let rec = cablab_ingest::read_path(path, &read_options(reader, None)?)?;
    if rec.kind != TestKind::Unknown {
        said.notes.push(format!(
            "{}: kind {} from the file ({})",
            path.display(),
            rec.kind.as_str(),
            rec.kind_reason
        ));
        return Ok((rec.kind, rec.kind_reason));
    }
    match kind_from_file_name(&rec, path) {
        Some(k) => {
            said.notes.push(format!(
                "{}: kind {} from the {}",
                path.display(),
                k.value.as_str(),
                k.from
            ));
            Ok((k.value, format!("the {}", k.from)))
        }
        // A compression test is said as such: no kind of cablab's fits it.
        None => match rec.compression_evidence() {
            Some(e) => bail!(
                "{}: {e} says compression, which cablab does not evaluate (its kinds: tension, \
                 torsion, three-point, pure-bending); give --kind to analyse it as one of them \
                 anyway",
                path.display()
            ),
            None => bail!(
                "{}: the file does not say which test it is (no test-type metadata, no channel \
                 units that tell, no kind in its name): give --kind tension, torsion, three-point \
                 or pure-bending",
                path.display()
            ),
        },
    }
}

/// A test read by [`read_test`]: the record, its geometry, the flat section b × h the moduli use
/// (when there is one: `AnalyzeOptions::flat_section`) and its complete rows.
pub struct ReadTest {
    /// The record as read.
    pub rec: TestRecord,
    /// The kind: `--kind`, else the file's ([`kind_of_file`]).
    pub kind: TestKind,
    /// Free length and round diameter.
    pub geom: cablab_measure::Geometry,
    /// The flat section, when the moduli use one.
    pub flat: Option<RectangularSection>,
    /// The complete rows, control in the kind's machine variable.
    pub curve: Curve,
}

/// A flat section from a width and a thickness in mm (flags, pipeline keys); both or none.
pub fn flat_given(width_mm: Option<f64>, thickness_mm: Option<f64>) -> Option<RectangularSection> {
    match (width_mm, thickness_mm) {
        (Some(b), Some(h)) => Some(RectangularSection {
            width_m: b * 1e-3,
            thickness_m: h * 1e-3,
        }),
        _ => None,
    }
}

/// Which channel-role checks [`check`] runs ([`check_roles`]).
#[derive(Debug, Clone, Copy)]
pub struct RoleCheck {
    /// The control column was named (flag or pipeline): it is kept as given.
    pub control_given: bool,
    /// A machine compliance is removed from the control (no note on crosshead travel).
    pub compliance_given: bool,
}

/// The checks a read record passes before any physics, in this order: the reader's warnings
/// are taken over, the declared kind is checked against the file's own evidence
/// ([`check_kind`]) and, with `roles`, the channel roles are checked and a tension control
/// possibly moved to the extensometer ([`check_roles`]). Every command that reads a test of a
/// declared kind (`analyze`, `diagnose`, `run`) goes through here. Warnings and notes (the
/// reader's notes included) are pushed to `said` as they arise.
pub fn check(
    rec: &mut TestRecord,
    kind: TestKind,
    force_kind: bool,
    roles: Option<RoleCheck>,
    said: &mut Remarks,
) -> Result<()> {
    said.warnings
        .extend(rec.warnings.iter().map(|w| w.located()));
    said.notes.extend(rec.notes.iter().map(|w| w.located()));
    said.warnings.extend(check_kind(rec, kind, force_kind)?);
    if kind == TestKind::Tension {
        if let Some(e) = rec.compression_evidence() {
            said.warnings.push(format!(
                "{e} says compression: analysed as tension as declared, but a compression test's stiffness (seating, buckling, strand splay in a cable) is not the tension stiffness (EA)"
            ));
        }
    }
    if let Some(r) = roles {
        let r = check_roles(rec, kind, r.control_given, r.compliance_given)?;
        said.append(r);
    }
    Ok(())
}

/// What the steps before the physics say next to the results, in two lists: `warnings`, the
/// statements that a number may be wrong (a unit assumed, a machine travel as the control, a
/// kind forced against the file), and `notes`, provenance that casts no doubt on a number (the
/// length from the metadata, the section used, the specimen-mounted control, the block read).
///
/// Does not decide what the analysis says: `cablab_measure::Analysis` keeps its own two lists.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Remarks {
    /// Statements that a number may be wrong.
    pub warnings: Vec<String>,
    /// Where a number came from; no doubt on it.
    pub notes: Vec<String>,
}

impl Remarks {
    /// Appends `other`'s warnings and notes after this one's.
    pub fn append(&mut self, mut other: Remarks) {
        self.warnings.append(&mut other.warnings);
        self.notes.append(&mut other.notes);
    }
}

/// Reader options from the command line's reader flags.
pub fn read_options(r: &crate::cli::ReaderArgs, kind: Option<TestKind>) -> Result<ReadOptions> {
    let format = match &r.format {
        Some(f) => Some(f.parse().map_err(|e| anyhow!("--format: {e}"))?),
        None => None,
    };
    let mut units = Vec::new();
    for u in &r.units {
        let (col, unit) = u.rsplit_once('=').ok_or_else(|| {
            anyhow!("--unit '{u}': expected COLUMN=UNIT, e.g. --unit 'Displacement=mm'")
        })?;
        units.push((col.trim().to_string(), unit.trim().to_string()));
    }
    Ok(ReadOptions {
        format,
        block: r.block,
        sheet: r.sheet.clone(),
        time: r.time.clone(),
        control: r.control.clone(),
        response: r.response.clone(),
        kind,
        units,
        lenient: false,
    })
}

/// A measured test as the calibration and the diagnosis see it: zero offsets removed (as the
/// characterisation does: an untared load cell is conditioning, not an unmodelled effect),
/// cycle/branch labels from the one segmenter, time stamps (sample index when the file has
/// none). Returns the test and the offsets taken off. Conditions the curve itself; the run
/// hands over what the characterisation found instead ([`diag_test_from`]).
pub fn diag_test(
    kind: TestKind,
    geom: &cablab_measure::Geometry,
    curve: &Curve,
    specimen: Option<String>,
    rod_setup: Option<cablab_rod::TestSetup>,
) -> Result<(cablab_diagnose::DiagTest, cablab_measure::Offsets)> {
    diag_test_from(kind, geom, curve, specimen, rod_setup, None).map(|(t, o, _)| (t, o))
}

/// The offsets and segments a characterisation found on a curve, for [`diag_test_from`].
#[derive(Debug, Clone, Copy)]
pub struct Conditioned<'a> {
    /// The zero offsets it took off.
    pub offsets: cablab_measure::Offsets,
    /// Its cycles and branches.
    pub segments: &'a [cablab_measure::Segment],
}

impl<'a> Conditioned<'a> {
    /// What `an` (the characterisation of `curve`, with the machine compliance `compliance`
    /// removed when given) found, when it conditioned the very samples [`diag_test`] would:
    /// offsets taken off, no compliance removed, no glitch replaced, and the holds timed by
    /// the same clock (the file's time when it runs forward, else none: the characterisation
    /// then times by sample index where [`diag_test`] would use the backward clock). None
    /// otherwise: the diagnosis' test is conditioned from the curve itself.
    pub fn by(
        an: &'a cablab_measure::Analysis,
        curve: &Curve,
        compliance: Option<f64>,
    ) -> Option<Conditioned<'a>> {
        let clock_ok = curve
            .time_s
            .as_deref()
            .is_none_or(|t| t.windows(2).all(|w| w[1] >= w[0]) && t.last() > t.first());
        match an.offsets {
            Some(offsets) if compliance.is_none() && an.excluded_samples.is_empty() && clock_ok => {
                Some(Conditioned {
                    offsets,
                    segments: &an.segments,
                })
            }
            _ => None,
        }
    }
}

/// The signs that bring a three-point test to the rod's convention, where the punch pushes
/// into the rod and both the deflection and the force are positive: the sign of the control at
/// its largest magnitude and of the response at its largest magnitude (offsets off). Machines
/// differ: an MTS 793 export of a flexure fixture logs both negative (the crosshead moves down,
/// the load cell is in compression); others log one of them negative. The rod's punch is
/// one-sided, so a test replayed in a file's negative convention lifts off and simulates no
/// force at all. (1, 1) for the other kinds, whose laws are odd.
pub fn three_point_signs(kind: TestKind, control: &[f64], response: &[f64]) -> (f64, f64) {
    if kind != TestKind::ThreePoint {
        return (1.0, 1.0);
    }
    (sign_at_peak(control), sign_at_peak(response))
}

/// A channel that runs negative: its most negative reading more than twice as far from zero as
/// its most positive one (a one-sided test in a negative convention; not a two-sided cycle, nor a
/// preload or a rebound of the other sign).
fn runs_negative(v: &[f64]) -> bool {
    let (lo, hi) = v
        .iter()
        .filter(|x| x.is_finite())
        .fold((0.0f64, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    -lo > 2.0 * hi
}

/// The sign of a channel's reading of largest magnitude (+1 for an empty or all-zero one), so
/// that a small opposite excursion (a preload, a rebound) does not decide it.
fn sign_at_peak(v: &[f64]) -> f64 {
    let peak = v
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .fold(0.0f64, |m, x| if x.abs() > m.abs() { x } else { m });
    if peak < 0.0 {
        -1.0
    } else {
        1.0
    }
}

/// [`diag_test`], with the offsets and segments of the characterisation when given (`cond`,
/// see [`Conditioned::by`]): the same test, bit for bit, without conditioning the curve again.
/// Also returns the signs applied to the control and the response ([`three_point_signs`]): the
/// test's response times the second, plus the response offset, is the file's.
pub fn diag_test_from(
    kind: TestKind,
    geom: &cablab_measure::Geometry,
    curve: &Curve,
    specimen: Option<String>,
    rod_setup: Option<cablab_rod::TestSetup>,
    cond: Option<Conditioned>,
) -> Result<(
    cablab_diagnose::DiagTest,
    cablab_measure::Offsets,
    (f64, f64),
)> {
    let n = curve.control.len();
    let time_s = curve
        .time_s
        .clone()
        .unwrap_or_else(|| (0..n).map(|i| i as f64).collect());
    let (control, response, offsets, labels) = match cond {
        Some(c) => {
            // `zero_offsets` subtracts in place: the same operation on the same samples.
            let control = curve
                .control
                .iter()
                .map(|v| v - c.offsets.control)
                .collect();
            let response = curve
                .response
                .iter()
                .map(|v| v - c.offsets.response)
                .collect();
            (
                control,
                response,
                c.offsets,
                cablab_measure::labels(c.segments, n),
            )
        }
        None => {
            let mut control = curve.control.clone();
            let mut response = curve.response.clone();
            let offsets = cablab_measure::zero_offsets(&mut control, &mut response);
            let segments = cablab_measure::segment(Some(&time_s), &control, &response)?;
            let labels = cablab_measure::labels(&segments, n);
            (control, response, offsets, labels)
        }
    };
    let (mut control, mut response): (Vec<f64>, Vec<f64>) = (control, response);
    let signs = three_point_signs(kind, &control, &response);
    if signs.0 < 0.0 {
        control.iter_mut().for_each(|v| *v = -*v);
    }
    if signs.1 < 0.0 {
        response.iter_mut().for_each(|v| *v = -*v);
    }
    let labels = labels
        .into_iter()
        .map(|l| cablab_diagnose::SegLabel {
            cycle: l.cycle,
            branch: l.branch,
        })
        .collect();
    Ok((
        cablab_diagnose::DiagTest {
            kind,
            free_length_m: geom.free_length_m,
            diameter_m: geom.diameter_m,
            time_s,
            control,
            response,
            labels,
            specimen,
            rod_setup,
        },
        offsets,
        signs,
    ))
}

/// The declared kind checked against the file's own evidence ([`TestRecord::kind_conflict`]):
/// a contradiction is an error naming the evidence, unless `force` (then it is returned as a
/// warning to print next to the results).
///
/// Does not infer a kind: the declared one is kept or refused.
pub fn check_kind(rec: &TestRecord, kind: TestKind, force: bool) -> Result<Option<String>> {
    let Some(evidence) = rec.kind_conflict(kind) else {
        return Ok(None);
    };
    let file = &rec.provenance.path;
    if force {
        return Ok(Some(format!(
            "analysed as {} although the file says otherwise ({evidence}); forced",
            kind.as_str()
        )));
    }
    if rec.kind_reason != cablab_ingest::record::KIND_SET_BY_FLAG {
        // Inferred from one part of the file, contradicted by another.
        let four_point = ["4-point", "four-point", "four point", "vierpunkt"]
            .iter()
            .any(|w| rec.kind_reason.to_lowercase().contains(w));
        bail!(
            "{file}: the file contradicts itself on its kind: it reads as {} ({}), but {evidence}. Give the kind with --kind{}",
            kind.as_str(),
            rec.kind_reason,
            if four_point {
                "; a four-point bending test of force against deflection is none of cablab's kinds: its pure bending is moment against end rotation or curvature (the middle span of a four-point test, M = F a / 2 with a the support-to-load distance), and three_point's formulas do not hold for four loading points"
            } else {
                ""
            }
        )
    }
    bail!(
        "{file}: declared kind {} contradicts the file: {evidence}. If the file is right, give its kind; if the kind is right, pass --force-kind (in a pipeline: force_kind = true under [kinds.{}])",
        kind.as_str(),
        kind.as_str()
    )
}

/// A channel as messages name it: `'Strain' (mm/mm)`, `'displacement' (no unit)`.
fn show(c: &cablab_ingest::Channel) -> String {
    format!(
        "'{}' ({})",
        c.name,
        if c.unit.is_empty() {
            "no unit"
        } else {
            &c.unit
        }
    )
}

/// A length channel named as the specimen's (testXpert's `Standard travel` beside a crosshead
/// channel) that moves one for one with a machine travel channel of the file: least-squares
/// slope within 3 % of 1 and r ≥ 0.999 over the rows where both are numbers. An extensometer
/// over a gauge length moves less than the crosshead (the rest of the specimen and the load
/// train stretch too: 0.56 of it on a testXpert 316L export); one that moves as much is the
/// crosshead by another name (a testXpert Invar export: `Standard travel` equal to `Crosshead
/// absolute` within 0.01 mm, r = 0.99998; its modulus 81 GPa for Invar's 140). Returns the
/// evidence.
fn moves_with_crosshead(rec: &TestRecord, i: usize) -> Option<String> {
    use cablab_ingest::units::Dimension;
    if rec.channels[i].dimension != Some(Dimension::Length) {
        return None;
    }
    let xi = rec.values(i)?;
    (0..rec.channels.len())
        .filter(|&k| k != i)
        .filter(|&k| rec.channels[k].dimension == Some(Dimension::Length))
        .filter(|&k| rec.mount(k) == cablab_ingest::Mount::Machine)
        .find_map(|k| {
            let xk = rec.values(k)?;
            let (a, b) = finite_pairs(&xk, &xi);
            if a.len() < 20 {
                return None;
            }
            let fit = cablab_measure::stats::linear_fit(&a, &b).ok()?;
            let r = fit.r2.max(0.0).sqrt();
            ((fit.slope - 1.0).abs() <= 0.03 && r >= 0.999).then(|| {
                format!(
                    "it moves one for one with the machine travel '{}' (slope {:.3}, r = {:.5}): an extensometer over a gauge length moves less than the crosshead, so this is the crosshead's travel by another name",
                    rec.channels[k].name, fit.slope, r
                )
            })
        })
}

/// The samples where both `x` and `y` are numbers, as two columns.
fn finite_pairs(x: &[f64], y: &[f64]) -> (Vec<f64>, Vec<f64>) {
    x.iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a, *b))
        .unzip()
}

/// Words of a file name that say its displacement is the machine's (the `mechanical_testing`
/// pair `…_machine.csv` / `…_extensometer.csv`, `…_crosshead…`).
const MACHINE_FILE_WORDS: &[&str] = &["machine", "crosshead", "traverse", "actuator", "stroke"];

/// Where the control of a tension test measures, with the evidence: the channel's name
/// ([`TestRecord::mount`]), else the file name for a control whose name does not say.
pub fn control_mount(rec: &TestRecord, i: usize) -> (cablab_ingest::Mount, Option<String>) {
    use cablab_ingest::Mount;
    let m = rec.mount(i);
    if m == Mount::Specimen {
        if let Some(words) = moves_with_crosshead(rec, i) {
            return (Mount::Machine, Some(words));
        }
    }
    if m != Mount::Unknown {
        return (m, None);
    }
    let stem = rec
        .provenance
        .path
        .rsplit(['/', '\\'])
        .next()
        .unwrap_or_default()
        .to_lowercase();
    let other_mounted = (0..rec.channels.len()).any(|k| k != i && rec.mount(k) == Mount::Specimen);
    match MACHINE_FILE_WORDS.iter().find(|w| stem.contains(*w)) {
        Some(w) => (Mount::Machine, Some(format!("the file name says '{w}'"))),
        None if other_mounted => (
            Mount::Machine,
            Some("the file has a specimen-mounted channel beside it".into()),
        ),
        None => (Mount::Unknown, None),
    }
}

/// The channel roles checked before any physics: a control or response in the wrong units (a
/// time, a force or torque as the control; a time, length or angle as the response) or a
/// control that is the time column itself is an error naming the columns and their units.
/// For tension, the output says where the stiffness comes from: a specimen-mounted control
/// (extensometer travel or strain, which the reader ranks first: ISO 6892-1 / ISO 527) is named
/// as such; a machine travel (by its name, or by the file name, or because the file has a
/// specimen-mounted channel beside it) is flagged unless a machine compliance is removed.
/// `control_given` (the control was chosen with `--control`) is said in the flag.
/// Returns what to print next to the results: the specimen-mounted control as a note, the
/// machine travel as a warning ((EA) is then a lower bound).
///
/// Does not choose the control: the reader does (`cablab_ingest`), for `inspect` and `analyze`
/// alike.
pub fn check_roles(
    rec: &mut TestRecord,
    kind: TestKind,
    control_given: bool,
    compliance_given: bool,
) -> Result<Remarks> {
    use cablab_ingest::units::Dimension as D;
    let file = rec.provenance.path.clone();
    let mut said = Remarks::default();
    let ci = rec.channel_index(Role::Control);
    let ri = rec.channel_index(Role::Response);
    if let Some(i) = ci {
        let c = &rec.channels[i];
        match c.dimension {
            Some(D::Time) => bail!(
                "{file}: the control column {} is a time, not a displacement or angle; name the control with --control",
                show(c)
            ),
            Some(D::Force | D::Torque) => bail!(
                "{file}: the control column {} is a {} — control and response look swapped{}; name them with --control and --response",
                show(c),
                if c.dimension == Some(D::Force) { "force" } else { "torque or moment" },
                ri.map(|r| format!(" (response {})", show(&rec.channels[r]))).unwrap_or_default()
            ),
            _ => {}
        }
    }
    if let Some(i) = ri {
        let c = &rec.channels[i];
        if let Some(d @ (D::Time | D::Length | D::Angle)) = c.dimension {
            let what = match d {
                D::Time => "a time",
                D::Length => "a length",
                _ => "an angle",
            };
            bail!(
                "{file}: the response column {} is {what}, not a force or moment; name the response with --response",
                show(c)
            );
        }
    }
    // A control that is the clock.
    if let (Some(i), Some(t)) = (ci, rec.channel_index(Role::Time)) {
        if let (Some(cv), Some(tv)) = (rec.values(i), rec.values(t)) {
            let (cf, tf) = finite_pairs(&cv, &tv);
            let pairs: Vec<(f64, f64)> = cf.into_iter().zip(tf).collect();
            let range = pairs
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p.1), hi.max(p.1))
                });
            let span = range.1 - range.0;
            if pairs.len() >= 3
                && span > 0.0
                && pairs.iter().all(|(a, b)| (a - b).abs() <= 1e-9 * span)
            {
                bail!(
                    "{file}: the control column {} holds the same values as the time column {}: it is a clock, not a displacement or angle; name the control with --control",
                    show(&rec.channels[i]),
                    show(&rec.channels[t])
                );
            }
        }
    }
    // An extensometer's travel beside the same extensometer's strain (MTS TestSuite's
    // `Extensometer (mm)` and `Strain (mm/mm)`) with no gauge length in the metadata: the strain
    // carries the gauge length, the travel would be divided by whatever length is given (the
    // free length between the clamps, 4.9 × the 50.8 mm gauge in a real ASTM D3039 export).
    // Unless the travel was asked for, the strain is the control.
    if !control_given {
        said.notes.extend(prefer_extensometer_strain(rec, kind));
    }
    let ci = rec.channel_index(Role::Control);
    if kind == TestKind::Tension {
        if let Some(i) = ci {
            use cablab_ingest::Mount;
            let (mount, evidence) = control_mount(rec, i);
            let machine: Vec<String> = (0..rec.channels.len())
                .filter(|&k| k != i && rec.mount(k) == Mount::Machine)
                .map(|k| show(&rec.channels[k]))
                .collect();
            match mount {
                Mount::Specimen => said.notes.push(format!(
                    "the stiffness comes from the specimen-mounted {} (ISO 6892-1 / ISO 527){}",
                    show(&rec.channels[i]),
                    if machine.is_empty() {
                        String::new()
                    } else {
                        format!(
                            ", not from the machine travel {} (it includes the load train's compliance)",
                            machine.join(", ")
                        )
                    }
                )),
                Mount::Machine if !compliance_given => said.warnings.push(format!(
                    "the stiffness comes from the machine travel {}{}: it includes the compliance of the load train (grips, frame), so (EA) is a lower bound; {}",
                    show(&rec.channels[i]),
                    match (evidence, control_given) {
                        (Some(e), true) => format!(" ({e}; chosen with --control)"),
                        (Some(e), false) => format!(" ({e})"),
                        (None, true) => " (chosen with --control)".into(),
                        (None, false) => String::new(),
                    },
                    // Name the file's own specimen-mounted channel when it has one.
                    match (0..rec.channels.len())
                        .find(|&k| k != i && rec.mount(k) == Mount::Specimen)
                    {
                        Some(k) => format!(
                            "the file's specimen-mounted {} gives the specimen's own: pass --control '{}' (or give --compliance)",
                            show(&rec.channels[k]),
                            rec.channels[k].name
                        ),
                        None => "use a specimen-mounted extensometer or give --compliance".into(),
                    }
                )),
                _ => {}
            }
        }
    }
    // Torsion on the machine's angle while the file has a torsional extensometer's surface
    // shear strain (an Instron torsion "Partner" export: `Shear Strain ( deg )` beside
    // `Angle ( deg )`): the angle adds the grips' and the drive's twist and rests on the free
    // length given, the shear strain is the specimen's own over its gauge (ASTM E143).
    if kind == TestKind::Torsion {
        if let Some(i) = ci {
            let c = &rec.channels[i];
            // A torsional extensometer by what it measures (`Shear Strain`) or by what it is
            // (an MTS TestSuite export's `Torsional Epsilon 3550 Torsion` in degrees beside the
            // actuator's `Torsional Angle`: Epsilon's axial–torsional extensometer).
            let mounted = |k: usize| {
                shear_named(&rec.channels[k].name) || rec.mount(k) == cablab_ingest::Mount::Specimen
            };
            if !mounted(i) && c.dimension == Some(D::Angle) {
                if let Some(k) = (0..rec.channels.len()).find(|&k| {
                    let o = &rec.channels[k];
                    k != i
                        && o.role == Role::Other
                        && mounted(k)
                        && matches!(o.dimension, Some(D::Angle | D::Ratio))
                }) {
                    said.warnings.push(format!(
                        "the stiffness comes from the angle {}{}: it adds the grips' and the machine's twist to the specimen's and rests on the free length; the file's torsional extensometer {} measures the specimen's own shear strain over its gauge: pass --control '{}' (with the diameter)",
                        show(c),
                        if control_given { " (chosen with --control)" } else { "" },
                        show(&rec.channels[k]),
                        rec.channels[k].name
                    ));
                }
            }
        }
    }
    Ok(said)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(bytes: &[u8], name: &str, kind: TestKind) -> TestRecord {
        let opts = ReadOptions {
            kind: Some(kind),
            ..Default::default()
        };
        cablab_ingest::read_bytes(bytes, name, &opts).unwrap()
    }

    /// A Bluehill export (its layout: metadata lines `key,"value",unit` above the table) with
    /// one metadata line for the modulus.
    fn bluehill_with(key: &str, value: &str, unit: &str) -> Vec<u8> {
        let mut s = format!(
            "Specimen number (included),1\n{key},\"{value}\",{unit}\nThickness,\"2.00000\",mm\n\
             Width,\"10.00000\",mm\n\nTime,Extension,Load\n(s),(mm),(N)\n"
        );
        for i in 0..40 {
            let x = 0.001 * i as f64;
            s.push_str(&format!(
                "\"{:.3}\",\"{x:.5}\",\"{:.3}\"\n",
                0.1 * i as f64,
                4e4 * x
            ));
        }
        s.into_bytes()
    }

    /// The modulus a file states is read from its metadata with its unit, thousands separators
    /// told from the decimal one, and not read when the separators are ambiguous, when it has no
    /// unit, when the key is a bound of the software's window, or when it is the other kind's
    /// modulus.
    #[test]
    fn a_stated_modulus_is_read_with_its_unit_and_never_guessed() {
        let get = |key: &str, value: &str, unit: &str, kind: TestKind| {
            stated_modulus(&read(&bluehill_with(key, value, unit), "m.csv", kind), kind)
                .map(|m| m.pa)
        };
        let t = TestKind::Tension;
        let close = |a: Option<f64>, b: f64| a.is_some_and(|a| (a / b - 1.0).abs() < 1e-12);
        assert!(close(
            get("Modulus (Automatic Young's)", "242,370.29658", "MPa", t),
            242.37029658e9
        ));
        assert!(close(get("E-Modul", "210000", "MPa", t), 210e9));
        assert!(close(get("E-Modul", "1.234.567,8", "kPa", t), 1.2345678e9));
        assert!(close(get("Young's modulus", "210,5", "GPa", t), 210.5e9));
        // The unit in the key, and a group prefix.
        assert!(close(get("E-Modul [GPa]", "210", "", t), 210e9));
        assert!(close(
            get(
                "Modulus (Automatic Young's) : Modulus (Automatic Young's)",
                "30000.00000",
                "MPa",
                t
            ),
            30e9
        ));
        assert_eq!(get("Secant modulus", "200", "GPa", t), None);
        assert_eq!(get("E-Modul", "1,23,4", "GPa", t), None);
        assert!(close(
            get("Shear modulus", "80", "GPa", TestKind::Torsion),
            80e9
        ));
        assert_eq!(get("E-Modul", "210.000", "MPa", t), None);
        assert_eq!(get("E-Modul", "210000", "", t), None);
        assert_eq!(get("Modulus start stress", "10", "MPa", t), None);
        assert_eq!(get("Shear modulus", "80", "GPa", t), None);
        assert_eq!(
            get("Young's modulus", "210", "GPa", TestKind::Torsion),
            None
        );
    }

    /// More than 5 % apart is a warning that names both numbers and the key; within it, a note.
    #[test]
    fn a_modulus_off_the_stated_one_is_warned() {
        let st = StatedModulus {
            key: "Modulus (Automatic Young's)".into(),
            pa: 242.4e9,
        };
        let (warn, w) = stated_modulus_check(Some(&st), Some(261.8e9)).unwrap();
        assert!(warn, "{w}");
        assert!(
            w.starts_with("modulus: 261.8 GPa here, the file states 242.4 GPa ('Modulus (Automatic Young's)'): +8.0 %"),
            "{w}"
        );
        let (warn, n) = stated_modulus_check(Some(&st), Some(250.0e9)).unwrap();
        assert!(!warn && n.contains("within 3.1 %"), "{n}");
        assert!(stated_modulus_check(None, Some(250e9)).is_none());
        assert!(stated_modulus_check(Some(&st), None).is_none());
    }

    /// A tension log on the machine travel whose time stamp repeats once: the reader's warning
    /// comes first; the role check, when asked for, adds the crosshead note after it, and no
    /// note when a compliance is removed.
    #[test]
    fn check_gathers_the_reader_warnings_then_the_role_notes() {
        let bytes =
            b"Time (s),Crosshead (mm),Force (N)\n0,0,0\n0.1,0.01,2\n0.1,0.02,4\n0.3,0.03,6\n";
        let rec = read(bytes, "t.csv", TestKind::Tension);
        let run = |roles: Option<RoleCheck>| {
            let mut said = Remarks::default();
            check(&mut rec.clone(), TestKind::Tension, false, roles, &mut said).unwrap();
            assert!(said.notes.is_empty(), "{said:?}");
            said.warnings
        };
        let reader_only = run(None);
        assert_eq!(reader_only.len(), 1, "{reader_only:?}");
        assert!(reader_only[0].contains("not strictly increasing"));
        let with_roles = run(Some(RoleCheck {
            control_given: false,
            compliance_given: false,
        }));
        assert_eq!(with_roles.len(), 2, "{with_roles:?}");
        assert_eq!(with_roles[0], reader_only[0]);
        assert!(with_roles[1].contains("machine travel"), "{with_roles:?}");
        let compliance_removed = run(Some(RoleCheck {
            control_given: false,
            compliance_given: true,
        }));
        assert_eq!(compliance_removed, reader_only);
    }

    /// A torsion log declared tension: refused naming the evidence; forced, the contradiction
    /// is a warning.
    #[test]
    fn a_contradicted_kind_is_refused_unless_forced() {
        let bytes = b"Time (s),Angle (deg),Torque (N m)\n0,0,0\n1,1,0.1\n2,2,0.2\n3,3,0.3\n";
        let mut rec = read(bytes, "t.csv", TestKind::Tension);
        let mut said = Remarks::default();
        let e = check(&mut rec, TestKind::Tension, false, None, &mut said).unwrap_err();
        assert!(e.to_string().contains("contradicts the file"), "{e}");
        assert!(said.warnings.is_empty(), "{said:?}");
        check(&mut rec, TestKind::Tension, true, None, &mut said).unwrap();
        let w = &said.warnings;
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("forced"), "{w:?}");
    }

    /// A tension log with an extensometer beside the crosshead: the specimen-mounted control is
    /// a note (provenance), not a warning; the same file on the crosshead (named with
    /// `--control`) is a warning; the reader's note on the first-row specimen column goes to
    /// the notes too.
    #[test]
    fn provenance_is_a_note_and_a_machine_travel_a_warning() {
        let bytes = b"Time (s),Crosshead (mm),Extensometer (mm),Force (N),Gauge length (mm)\n0,0,0,0,50\n1,0.01,0.001,2,\n2,0.02,0.002,4,\n3,0.03,0.003,6,\n";
        let rec = read(bytes, "t.csv", TestKind::Tension);
        let mut said = Remarks::default();
        let roles = Some(RoleCheck {
            control_given: false,
            compliance_given: false,
        });
        check(&mut rec.clone(), TestKind::Tension, false, roles, &mut said).unwrap();
        assert!(said.warnings.is_empty(), "{said:?}");
        assert_eq!(said.notes.len(), 2, "{said:?}");
        assert!(said.notes[0].contains("first data row only"), "{said:?}");
        assert!(
            said.notes[1].contains("specimen-mounted 'Extensometer' (mm)"),
            "{said:?}"
        );
        let opts = ReadOptions {
            kind: Some(TestKind::Tension),
            control: Some("Crosshead".into()),
            ..Default::default()
        };
        let mut rec = cablab_ingest::read_bytes(bytes, "t.csv", &opts).unwrap();
        let mut said = Remarks::default();
        let roles = Some(RoleCheck {
            control_given: true,
            compliance_given: false,
        });
        check(&mut rec, TestKind::Tension, false, roles, &mut said).unwrap();
        assert_eq!(said.warnings.len(), 1, "{said:?}");
        assert!(said.warnings[0].contains("lower bound"), "{said:?}");
        assert_eq!(said.notes.len(), 1, "{said:?}");
    }

    /// A torsion log of three cycles (rest, ramps, dwells, a yield-like bend) with noise and
    /// offsets on both channels: 6,000 samples, time stamps when `clock`.
    fn cyclic_curve(clock: bool) -> Curve {
        let mut c = vec![0.0; 200];
        for a in [0.02, 0.04, 0.06] {
            c.extend((0..800).map(|i| a * i as f64 / 800.0));
            c.extend(std::iter::repeat_n(a, 200));
            c.extend((0..800).map(|i| a * (1.0 - i as f64 / 800.0)));
        }
        let mut plastic = 0.0f64;
        let mut last = 0.0;
        let response: Vec<f64> = c
            .iter()
            .enumerate()
            .map(|(i, &x)| {
                // Elastic up to 0.03 rad of elastic twist, then a tenth of the slope.
                let trial = 50.0 * (x - plastic);
                if trial > 1.5 && x > last {
                    plastic = x - 0.03;
                }
                last = x;
                let r = 50.0 * (x - plastic);
                let noise = 0.01 * ((i as f64 * 12.9898).sin() * 43_758.545).fract();
                0.3 + r + noise
            })
            .collect();
        let control: Vec<f64> = c
            .iter()
            .enumerate()
            .map(|(i, x)| 0.001 + x + 1e-5 * ((i as f64 * 78.233).sin() * 43_758.545).fract())
            .collect();
        Curve {
            time_s: clock.then(|| (0..control.len()).map(|i| 0.01 * i as f64).collect()),
            control,
            response,
            dropped_rows: 0,
            repeated_rows: 0,
            rows: vec![],
            cut_short: false,
        }
    }

    /// A 60 Hz hum logged at 100 Hz shows at 40 Hz: the note names the mains it came from and its
    /// size; without a time column it gives the frequency per sample; a curve without a tone
    /// gets no note.
    #[test]
    fn a_mains_hum_on_the_response_is_noted_with_its_source() {
        assert_eq!(cyclic_curve(true).tone_note(TestKind::Torsion), None);
        for clock in [true, false] {
            let mut c = cyclic_curve(clock);
            for (i, r) in c.response.iter_mut().enumerate() {
                *r += 0.02 * (std::f64::consts::TAU * 60.0 * 0.01 * i as f64 + 0.3).sin();
            }
            let note = c.tone_note(TestKind::Torsion).expect("a tone");
            let rms: f64 = note
                .split(" N m RMS")
                .next()
                .and_then(|h| h.rsplit(' ').next())
                .and_then(|v| v.parse().ok())
                .expect("an RMS in N m");
            assert!((rms / (0.02 / 2f64.sqrt()) - 1.0).abs() < 0.02, "{note}");
            if clock {
                assert!(
                    note.contains("40.00 Hz as logged: 60 Hz mains hum, folded by the logger's 100.00 Hz rate"),
                    "{note}"
                );
            } else {
                assert!(note.contains("0.400 cycles per sample"), "{note}");
            }
        }
    }

    /// The diagnosis' test built from the characterisation's offsets and segments is the test
    /// conditioned from the curve itself, bit for bit, with and without a time column; a
    /// compliance removed, a glitch replaced or a clock that runs backwards make the
    /// characterisation's conditioning another curve's, and it is not handed over.
    #[test]
    fn the_characterisations_conditioning_is_the_diagnosis_test_s() {
        let geom = cablab_measure::Geometry {
            free_length_m: 0.05,
            diameter_m: Some(2e-3),
        };
        let kind = TestKind::Torsion;
        let glitched = {
            let mut c = cyclic_curve(true);
            c.response[3000] += 40.0;
            c
        };
        let backwards = {
            let mut c = cyclic_curve(true);
            c.time_s.as_mut().unwrap().swap(100, 101);
            c
        };
        let cases = [
            ("time", cyclic_curve(true), None, true),
            ("no time", cyclic_curve(false), None, true),
            ("compliance", cyclic_curve(true), Some(1e-4), false),
            ("glitch", glitched, None, false),
            ("backward clock", backwards, None, false),
        ];
        for (name, curve, compliance, reused) in cases {
            let opts = cablab_measure::AnalyzeOptions {
                compliance_m_per_n: compliance,
                ..Default::default()
            };
            let an = cablab_measure::analyze(
                kind,
                &geom,
                curve.time_s.as_deref(),
                &curve.control,
                &curve.response,
                &opts,
            )
            .unwrap();
            assert!(an.segments.len() > 6, "{name}: {:?}", an.segments);
            let cond = Conditioned::by(&an, &curve, compliance);
            assert_eq!(cond.is_some(), reused, "{name}");
            let (a, oa, _) = diag_test_from(kind, &geom, &curve, None, None, cond).unwrap();
            let (b, ob) = diag_test(kind, &geom, &curve, None, None).unwrap();
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&a.control), bits(&b.control), "{name}");
            assert_eq!(bits(&a.response), bits(&b.response), "{name}");
            assert_eq!(bits(&a.time_s), bits(&b.time_s), "{name}");
            assert_eq!(a.labels, b.labels, "{name}");
            assert_eq!(
                (
                    oa.control.to_bits(),
                    oa.response.to_bits(),
                    oa.samples_at_rest
                ),
                (
                    ob.control.to_bits(),
                    ob.response.to_bits(),
                    ob.samples_at_rest
                ),
                "{name}"
            );
            if reused {
                assert!(oa.samples_at_rest > 0, "{name}: {oa:?}");
            }
        }
    }

    /// A response that does not follow its control (a random file, a flat record) keeps its
    /// sign; one that runs against it is reversed, the note giving the correlation.
    /// The record the rod model describes ends at a peak the response falls from while the
    /// control runs on (necking, a fracture); not after an unloading, not at a three-point
    /// rod's geometric softening (which the rod has), but at a three-point break.
    #[test]
    fn the_diagnosis_ends_where_the_specimen_necks_or_breaks() {
        let curve = |c: Vec<f64>, r: Vec<f64>| Curve {
            control: c,
            response: r,
            ..Default::default()
        };
        // Tension: rising to 100 at sample 60, then falling to 70 while the control runs on.
        let c: Vec<f64> = (0..100).map(|i| 1e-4 * i as f64).collect();
        let r: Vec<f64> = (0..100)
            .map(|i| {
                if i <= 60 {
                    100.0 * (i as f64 / 60.0).sqrt()
                } else {
                    100.0 - 0.75 * (i - 60) as f64
                }
            })
            .collect();
        let (end, why) = diagnosable_end(TestKind::Tension, &curve(c.clone(), r.clone())).unwrap();
        assert_eq!(end, 61);
        assert!(
            why.contains("necking or fracture") && why.contains("(61 of 100 samples)"),
            "{why}"
        );
        // The same fall after the control turned back (an unloading): the model has it.
        let back: Vec<f64> = (0..100)
            .map(|i| {
                if i <= 60 {
                    c[i]
                } else {
                    c[60] - 1e-5 * (i - 60) as f64
                }
            })
            .collect();
        assert_eq!(
            diagnosable_end(TestKind::Tension, &curve(back, r.clone())),
            None
        );
        // Three-point: a fall to 70 % is geometry; to 20 %, a break.
        assert_eq!(
            diagnosable_end(TestKind::ThreePoint, &curve(c.clone(), r)),
            None
        );
        let broken: Vec<f64> = (0..100)
            .map(|i| if i <= 60 { i as f64 } else { 10.0 })
            .collect();
        let (end, why) = diagnosable_end(TestKind::ThreePoint, &curve(c, broken)).unwrap();
        assert_eq!(end, 61);
        assert!(why.contains("a failure or fracture"), "{why}");
    }

    /// A fatigue block: ten sine cycles whose amplitude rises and falls, the specimen breaking
    /// at the peak of its eighth (smaller than the fifth's): the diagnosis ends at that peak.
    /// The same record without the break (it ends unloaded), or with a gradual fall over the
    /// last loading instead of a fracture, is diagnosed to its end.
    #[test]
    fn a_cyclic_record_that_breaks_in_a_smaller_cycle_ends_at_that_peak() {
        let curve = |c: Vec<f64>, r: Vec<f64>| Curve {
            control: c,
            response: r,
            ..Default::default()
        };
        let per = 200usize;
        let amp =
            |i: usize| 1.0 + 0.6 * (std::f64::consts::PI * i as f64 / (10 * per) as f64).sin();
        // Minimum at 0, peaks at the middle of each cycle.
        let c: Vec<f64> = (0..10 * per)
            .map(|i| amp(i) * 0.5 * (1.0 - (std::f64::consts::TAU * i as f64 / per as f64).cos()))
            .collect();
        let r: Vec<f64> = c.iter().map(|&x| 100.0 * x).collect();
        assert_eq!(
            diagnosable_end(TestKind::Tension, &curve(c.clone(), r.clone())),
            None
        );
        // Ending in an unloading whose response falls from 30 % of the largest to zero over
        // the last 4 % of the control's travel (a piecewise-linear cable, stiff near zero, as
        // the demo's Bowden pure-bending tests end): no break.
        let top = c.iter().fold(0.0f64, |m, &v| m.max(v));
        let knee = 0.04 * top;
        let stiff: Vec<f64> = c
            .iter()
            .map(|&x| {
                if x < knee {
                    30.0 * top * x / knee
                } else {
                    30.0 * top + 70.0 * (x - knee) / 0.96
                }
            })
            .collect();
        assert_eq!(
            diagnosable_end(TestKind::PureBending, &curve(c.clone(), stiff)),
            None
        );
        let peak8 = (7 * per..8 * per)
            .max_by(|&a, &b| c[a].total_cmp(&c[b]))
            .unwrap();
        // Broken: the control jumps on, the force is gone.
        let mut cb = c[..=peak8].to_vec();
        let mut rb = r[..=peak8].to_vec();
        cb.extend((1..40).map(|i| c[peak8] + 0.05 * i as f64));
        rb.extend((1..40).map(|i| 0.3 * ((i * 7) % 5) as f64));
        let (end, why) =
            diagnosable_end(TestKind::Tension, &curve(cb.clone(), rb.clone())).unwrap();
        assert_eq!(end, peak8 + 1, "{why}");
        assert!(why.contains("the peak of its last loading"), "{why}");
        // Three-point takes the same fracture.
        assert_eq!(
            diagnosable_end(TestKind::ThreePoint, &curve(cb, rb)).map(|e| e.0),
            Some(peak8 + 1)
        );
        // A gradual fall (over 100 samples) while the control runs on: not cut.
        let mut rg = r[..=peak8].to_vec();
        let mut cg = c[..=peak8].to_vec();
        cg.extend((1..100).map(|i| c[peak8] + 0.005 * i as f64));
        rg.extend((1..100).map(|i| r[peak8] * (1.0 - 0.0095 * i as f64)));
        assert_eq!(diagnosable_end(TestKind::Tension, &curve(cg, rg)), None);
    }

    #[test]
    fn only_a_response_that_runs_against_its_control_is_reversed() {
        let c: Vec<f64> = (0..200).map(|i| (i as f64 * 0.1).sin()).collect();
        let noise: Vec<f64> = (0..200).map(|i| ((i * 7919) % 101) as f64 - 50.0).collect();
        let mut random = Curve {
            control: c.clone(),
            response: noise.clone(),
            ..Default::default()
        };
        assert_eq!(align_response_sign(&mut random), (None, None));
        assert_eq!(random.response, noise);
        let mut against = Curve {
            control: c.clone(),
            response: c.iter().map(|x| -3.0 * x + 0.01).collect(),
            ..Default::default()
        };
        let note = align_response_sign(&mut against).0.unwrap();
        assert!(note.contains("correlation -1.00"), "{note}");
        assert!(note.contains("the response's sign is reversed"), "{note}");
        assert!(against
            .response
            .iter()
            .zip(&c)
            .all(|(r, x)| (r - (3.0 * x - 0.01)).abs() < 1e-12));
        // A tension test whose travel counts downwards under a force logged positive (a TestSuite
        // export's `_Extension`): the travel is reversed, the forces stay the file's.
        let travel: Vec<f64> = (0..200).map(|i| -1e-5 * i as f64).collect();
        let force: Vec<f64> = travel.iter().map(|u| -8e6 * u + 0.3).collect();
        let mut down = Curve {
            control: travel.clone(),
            response: force.clone(),
            ..Default::default()
        };
        let note = align_response_sign(&mut down).0.unwrap();
        assert!(note.contains("the control's sign is reversed"), "{note}");
        assert_eq!(down.response, force);
        assert!(down.control.iter().zip(&travel).all(|(a, b)| *a == -b));
        // The force logged negative under a rising travel: the force is reversed.
        let mut neg = Curve {
            control: force.clone(),
            response: travel.clone(),
            ..Default::default()
        };
        assert!(align_response_sign(&mut neg)
            .0
            .unwrap()
            .contains("the response's sign is reversed"));
        assert!(neg.response.iter().all(|v| *v >= 0.0));
    }

    /// Tension read from a record whose two channels both run negative (a compression test, a
    /// compression sign convention) is warned about, and nothing is reversed; one negative
    /// channel is a sign convention (reversed, no warning), and other kinds are not tension.
    #[test]
    fn both_channels_negative_in_tension_is_warned_about() {
        let travel: Vec<f64> = (0..50).map(|i| -1e-5 * i as f64).collect();
        let force: Vec<f64> = travel.iter().map(|u| 9e5 * u).collect();
        let pushed = Curve {
            control: travel.clone(),
            response: force.clone(),
            ..Default::default()
        };
        let w = compression_in_tension(TestKind::Tension, &pushed).unwrap();
        assert!(w.contains("both run negative"), "{w}");
        assert_eq!(compression_in_tension(TestKind::Torsion, &pushed), None);
        let mut pulled = pushed.clone();
        pulled.response.iter_mut().for_each(|v| *v = -*v);
        assert_eq!(compression_in_tension(TestKind::Tension, &pulled), None);
    }

    /// A three-point test in any sign convention is turned to the rod's (deflection and force
    /// positive), each channel by the sign at its largest magnitude, so that a small opposite
    /// excursion (a preload, a rebound) does not decide it; other kinds keep the file's signs.
    #[test]
    fn three_point_signs_follow_each_channels_peak() {
        let up = [0.0, 0.1, 0.5, 1.0, 0.4, -0.05];
        let down: Vec<f64> = up.iter().map(|v| -v).collect();
        let k = TestKind::ThreePoint;
        assert_eq!(three_point_signs(k, &up, &up), (1.0, 1.0));
        assert_eq!(three_point_signs(k, &down, &down), (-1.0, -1.0));
        assert_eq!(three_point_signs(k, &down, &up), (-1.0, 1.0));
        assert_eq!(
            three_point_signs(TestKind::PureBending, &down, &down),
            (1.0, 1.0)
        );
        assert_eq!(three_point_signs(k, &[], &[0.0]), (1.0, 1.0));
    }
}
