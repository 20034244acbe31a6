//! The four tests as the machine runs them, driven through a control path or a measured history.
//!
//! - `tension` and `torsion` (clamped ends, homogeneous straight rod): the state is uniform
//!   along the rod, Γ₃ = Δl/l₀ or K₃ = θ/l₀ with every other strain held at zero by the clamps, so
//!   the sectional law evaluated once per step *is* the rod solution (exact, not an approximation;
//!   `uniform_shortcuts_match_the_spatial_rod` in `tests/spatial.rs` replays elastoplastic cycles
//!   through the 3D rod [`crate::spatial::SpatialRod`] and gets the same numbers). Driven by
//!   [`crate::uniform`], the diagnosis's forward model too.
//! - `pure_bending` (one end rotated, both ends free to slide, no shear force): the rod is solved
//!   by [`simulate_path`] (node 0 clamped to remove rigid motion, end rotation prescribed at the
//!   other end, its position free: no force) — its answer is a uniform-curvature arc K = θ/l₀. For
//!   a homogeneous rod that is again a uniform state, so [`simulate_history`] (the calibration's
//!   hot loop) evaluates the law directly at K₁ = θ/l₀, Γ₃ = 0 (exact for laws without
//!   bending–axial coupling; the tests check both routes agree).
//! - `three_point`: half model (symmetry at mid-span: x = 0, θ = 0), rod of span/2 plus an
//!   overhang resting on a rigid support cylinder it slides over (bilateral normal penalty, optional
//!   regularised Coulomb friction), pushed by a rigid point or cylindrical punch that can only push
//!   (contact opens on unloading: an active set around Newton). A round punch acts on nodes
//!   (use elements shorter than the expected wrap length); supports act on segments, so the
//!   contact point slides continuously. Control: punch deflection w; response: total punch force.
//!   Penalty stiffness k = `penalty_factor`·EI/span³ (default 10⁷: deflection error ≈ 2.4·10⁻⁶ w).
//!
//! The rod-driven kinds start each step's Newton iteration from a predictor (the last two
//! committed steps extrapolated in the control; [`SolverOptions::predictor`]): about 2 Newton
//! iterations per three-point step instead of 3–4, the same equilibrium to 10⁻⁸.
//!
//! Every kind honours [`TestSetup::machine_compliance`]: the control is the machine's reading,
//! solved for the specimen's own deformation by the one series solver of [`crate::series`]
//! (with the law's tangent for the uniform states, with the secant of the rod's response for the
//! rod) — except three-point with a point punch, where the compliance is a spring in series with
//! the punch's penalty spring and the machine's reading drives the punch directly (exact: two
//! linear springs in series on one node).
//!
//! Does not: read files, choose laws or parameters (the caller builds the law).

use crate::planar::{PlanarRod, Punch, SolverOptions, Support};
use crate::series::{Failure, Series};
use crate::uniform::{is_uniform, UniformDriver};
use crate::RodError;
use cablab_core::TestKind;
use cablab_laws::Law;
use nalgebra::{Vector2, Vector3};
use serde::Serialize;

/// Geometry and numerical options of one simulated test.
#[derive(Debug, Clone, PartialEq)]
pub struct TestSetup {
    /// Which test.
    pub kind: TestKind,
    /// Free length between clamps, or the support span for `three_point`, m.
    pub free_length_m: f64,
    /// Elements along the rod (pure bending: the whole rod; three-point: the half model,
    /// mid-span to the rod end including the overhang).
    pub elements: usize,
    /// Punch radius, m (0 = point punch).
    pub punch_radius_m: f64,
    /// Support radius, m (0 = point supports).
    pub support_radius_m: f64,
    /// Coulomb friction coefficient at the supports (0 = frictionless).
    pub support_friction: f64,
    /// Machine compliance in series with the specimen (control per response unit: m/N for
    /// tension and three-point, rad/(N m) for torsion and pure bending; 0 = a rigid machine), for
    /// every kind. The control is then the machine's reading u = w + C·R(w): each step solves for
    /// the specimen's own deformation w.
    pub machine_compliance: f64,
    /// Rod (cable) radius, m: offsets the contact surfaces from the centreline (0 = centreline contact).
    pub rod_radius_m: f64,
    /// Rod length beyond each support (three-point), m; None = 0.15 × span, more where the
    /// history's deflection would pull the rod off its supports ([`default_overhang`]).
    pub overhang_m: Option<f64>,
    /// Contact penalty stiffness in units of EI/span³.
    pub penalty_factor: f64,
    /// Largest control increment the rod solver takes internally (sub-steps between samples); None = automatic.
    pub max_substep: Option<f64>,
    /// Control rate (control units per second) used to give path steps a time; None = 1 s per step.
    pub control_rate_per_s: Option<f64>,
    /// Record curvature and moment per element at every step (three-point and pure bending).
    pub record_span: bool,
    /// Newton controls.
    pub solver: SolverOptions,
}

impl TestSetup {
    /// The fixture's contact radii (m) for the supports and the punch. A rounded contact sits
    /// on the rod's surface (half of `rod_diameter_m`, when known); point contacts stay on its
    /// centreline, the default.
    pub fn set_contact_radii(&mut self, support_m: f64, punch_m: f64, rod_diameter_m: Option<f64>) {
        self.support_radius_m = support_m;
        self.punch_radius_m = punch_m;
        if support_m > 0.0 || punch_m > 0.0 {
            self.rod_radius_m = 0.5 * rod_diameter_m.unwrap_or(0.0);
        }
    }

    /// Defaults: 40 elements, point punch and supports, frictionless, centreline contact,
    /// overhang 0.15 × span, penalty 10⁷ EI/span³, automatic sub-steps, no span records.
    pub fn new(kind: TestKind, free_length_m: f64) -> Self {
        TestSetup {
            kind,
            free_length_m,
            elements: 40,
            punch_radius_m: 0.0,
            support_radius_m: 0.0,
            support_friction: 0.0,
            machine_compliance: 0.0,
            rod_radius_m: 0.0,
            overhang_m: None,
            penalty_factor: 1e7,
            max_substep: None,
            control_rate_per_s: None,
            record_span: false,
            solver: SolverOptions::default(),
        }
    }

    fn validate(&self) -> Result<(), RodError> {
        let bad = |what: &str, v: f64| {
            RodError::InvalidSetup(format!("{what} must be finite and ≥ 0, got {v}"))
        };
        if !(self.free_length_m.is_finite() && self.free_length_m > 0.0) {
            return Err(RodError::InvalidSetup(format!(
                "free length / span must be positive, got {} m",
                self.free_length_m
            )));
        }
        for (name, v) in [
            ("punch radius", self.punch_radius_m),
            ("support radius", self.support_radius_m),
            ("support friction", self.support_friction),
            ("machine compliance", self.machine_compliance),
            ("rod radius", self.rod_radius_m),
            ("overhang", self.overhang_m.unwrap_or(0.0)),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(name, v));
            }
        }
        if !(self.penalty_factor.is_finite() && self.penalty_factor > 0.0) {
            return Err(RodError::InvalidSetup(format!(
                "penalty factor must be positive, got {}",
                self.penalty_factor
            )));
        }
        if let Some(m) = self.max_substep {
            if !(m.is_finite() && m > 0.0) {
                return Err(RodError::InvalidSetup(format!(
                    "max sub-step must be positive, got {m}"
                )));
            }
        }
        if self.kind == TestKind::Unknown {
            return Err(RodError::UnsupportedKind(self.kind));
        }
        Ok(())
    }
}

/// A simulated test: control and response per computed step (SI), plus what the diagnosis needs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SimCurve {
    /// The test kind.
    pub kind: TestKind,
    /// Control value per step: elongation m, twist rad, punch deflection m or end rotation rad.
    pub control: Vec<f64>,
    /// Response per step: axial force N, torque N m, punch force N or end moment N m.
    pub response: Vec<f64>,
    /// Time of each step, s.
    pub time_s: Vec<f64>,
    /// Three-point: whether the punch touches the rod at each step (empty for other kinds).
    pub punch_contact: Vec<bool>,
    /// Arc length of each element midpoint (three-point: from mid-span), m; empty unless `record_span`.
    pub span_s_m: Vec<f64>,
    /// Bending curvature K₁ per element at each step, 1/m; empty unless `record_span`.
    pub span_curvature_per_m: Vec<Vec<f64>>,
    /// Bending moment M₁ per element at each step, N m; empty unless `record_span`.
    pub span_moment_nm: Vec<Vec<f64>>,
    /// Newton iterations spent in total (0 for direct sectional evaluation).
    pub newton_iterations: usize,
}

impl SimCurve {
    fn new(kind: TestKind) -> Self {
        SimCurve {
            kind,
            control: Vec::new(),
            response: Vec::new(),
            time_s: Vec::new(),
            punch_contact: Vec::new(),
            span_s_m: Vec::new(),
            span_curvature_per_m: Vec::new(),
            span_moment_nm: Vec::new(),
            newton_iterations: 0,
        }
    }
}

/// Law-driven state machine behind both entry points.
enum Driver<'a> {
    /// Direct sectional evaluation of a uniform state.
    Uniform(UniformDriver<'a>),
    /// The rod solver.
    Rod {
        rod: Box<PlanarRod<'a>>,
        kind: TestKind,
        /// Control reached (the machine's reading).
        current: f64,
        max_substep: f64,
        /// Machine compliance (see [`TestSetup::machine_compliance`]).
        compliance: f64,
        /// The specimen's own control and the response at the last committed step.
        specimen: f64,
        response: f64,
        /// Secant stiffness of the last step (response per specimen control), the compliance
        /// iteration's first guess.
        stiffness: f64,
        /// The last committed step: its configuration change and its specimen control
        /// increment (0: none usable), the secant predictor of the next step.
        predictor: Predictor,
        /// The configuration at the start of the step being solved (restored on failure).
        saved: Vec<Vector3<f64>>,
    },
}

impl<'a> Driver<'a> {
    /// The rod of a rod-driven test whose control reaches `reach` at most (three-point: the
    /// overhang it needs, [`default_overhang`]).
    fn rod(
        setup: &TestSetup,
        law: &'a dyn Law,
        max_substep: Option<f64>,
        reach: f64,
    ) -> Result<Self, RodError> {
        let l = setup.free_length_m;
        let ei = law.elastic_tangent()[(3, 3)];
        match setup.kind {
            TestKind::PureBending => {
                let mut rod = PlanarRod::straight(law, l, setup.elements)?;
                rod.options = setup.solver;
                rod.prescribed[0] = [Some(0.0); 3];
                let n = rod.nodes() - 1;
                rod.prescribed[n][2] = Some(0.0);
                Ok(Driver::Rod {
                    rod: Box::new(rod),
                    kind: setup.kind,
                    current: 0.0,
                    max_substep: max_substep.or(setup.max_substep).unwrap_or(0.05),
                    compliance: setup.machine_compliance,
                    specimen: 0.0,
                    response: 0.0,
                    stiffness: ei / l,
                    predictor: Predictor::default(),
                    saved: Vec::new(),
                })
            }
            TestKind::ThreePoint => {
                let half = 0.5 * l;
                let overhang = setup
                    .overhang_m
                    .unwrap_or_else(|| default_overhang(l, reach));
                let mut rod = PlanarRod::straight(law, half + overhang, setup.elements)?;
                rod.options = setup.solver;
                rod.prescribed[0] = [Some(0.0), None, Some(0.0)];
                let k = setup.penalty_factor * ei / (l * l * l);
                let r_sup = setup.support_radius_m + setup.rod_radius_m;
                let mut sup = Support::new(
                    Vector2::new(half, -r_sup),
                    r_sup,
                    k,
                    setup.support_friction,
                    half,
                    Vector2::new(half, 0.0),
                );
                sup.k_tangent = k;
                rod.supports.push(sup);
                // A point punch is one linear spring on node 0 (its penalty k); the machine's
                // compliance C in series with it (2C on the half model, which carries R/2) is
                // another, so the machine's reading drives the punch through the two springs in
                // series, k/(1 + 2Ck): the same equilibrium as solving w + C·R(w) = u, without the
                // outer iteration. A round punch touches several nodes: the series solve.
                let r_punch = setup.punch_radius_m + setup.rod_radius_m;
                let c = setup.machine_compliance;
                let in_punch = r_punch == 0.0 && c > 0.0;
                let k_punch = if in_punch { k / (1.0 + 2.0 * c * k) } else { k };
                rod.punch = Some(Punch::new(0.0, r_punch, k_punch));
                Ok(Driver::Rod {
                    rod: Box::new(rod),
                    kind: setup.kind,
                    current: 0.0,
                    max_substep: max_substep.or(setup.max_substep).unwrap_or(0.005 * l),
                    compliance: if in_punch { 0.0 } else { c },
                    specimen: 0.0,
                    response: 0.0,
                    stiffness: 48.0 * ei / (l * l * l),
                    predictor: Predictor::default(),
                    saved: Vec::new(),
                })
            }
            other => Err(RodError::UnsupportedKind(other)),
        }
    }

    fn apply_control(rod: &mut PlanarRod<'_>, kind: TestKind, c: f64) {
        match kind {
            TestKind::PureBending => {
                let n = rod.nodes() - 1;
                rod.prescribed[n][2] = Some(c);
            }
            _ => {
                if let Some(p) = rod.punch.as_mut() {
                    p.tip_y_m = -c;
                }
            }
        }
    }

    /// Move the control to `target` over `dt` seconds; returns the response.
    fn step_to(
        &mut self,
        target: f64,
        dt: f64,
        step: usize,
        iterations: &mut usize,
    ) -> Result<f64, RodError> {
        match self {
            Driver::Uniform(u) => u.step_to(target, dt, step),
            Driver::Rod {
                rod,
                kind,
                current,
                max_substep,
                compliance,
                specimen,
                response,
                stiffness,
                predictor,
                saved,
            } => {
                let from = *current;
                let total = target - from;
                let n_sub = ((total.abs() / *max_substep).ceil() as usize).max(1);
                let mut h = total / n_sub as f64;
                let mut c = from;
                let mut cuts = 0;
                // The predictor is a shortcut: not with support friction (a predicted slip of the
                // stick spring, as stiff as the contact penalty, sends Newton through a return
                // mapping the committed start never sees; it failed to converge on coarse rods),
                // and a step that fails from it is first retried from the committed configuration.
                let frictionless = rod.supports.iter().all(|s| s.mu == 0.0);
                let mut predicted = rod.options.predictor && frictionless;
                let max_cuts = rod.options.max_bisections;
                let tiny = 1e-12 * total.abs().max(*max_substep);
                loop {
                    let remaining = target - c;
                    let last = remaining.abs() <= h.abs() + tiny;
                    let next = if last { target } else { c + h };
                    saved.clone_from(&rod.q);
                    let frac = if total != 0.0 {
                        (next - c) / total
                    } else {
                        1.0
                    };
                    let solved = if *compliance > 0.0 {
                        Self::solve_compliant(
                            rod,
                            *kind,
                            next - c,
                            dt * frac,
                            step,
                            (*compliance, *specimen, *response, *stiffness),
                            predicted.then_some(&*predictor),
                        )
                    } else {
                        if predicted {
                            predictor.predict(&mut rod.q, next - *specimen);
                        }
                        Self::apply_control(rod, *kind, next);
                        rod.solve(dt * frac, step).map(|it| (it, next))
                    };
                    match solved {
                        Ok((it, w)) => {
                            *iterations += it;
                            if rod.punch_force_sens().is_some() {
                                // Dropped (None from then on) where the step cannot be
                                // differentiated; the caller sees it.
                                rod.sens_step(dt * frac);
                            }
                            rod.commit();
                            let r = Self::response(rod, *kind);
                            if (w - *specimen).abs() > 1e-12 * max_substep.abs() {
                                let k = (r - *response) / (w - *specimen);
                                if k.is_finite() && k > 0.0 {
                                    *stiffness = k;
                                }
                            }
                            predictor.record(saved, &rod.q, w - *specimen);
                            *specimen = w;
                            *response = r;
                            c = next;
                            if last {
                                break;
                            }
                        }
                        Err(e) => {
                            rod.q.clone_from(saved);
                            Self::apply_control(rod, *kind, *specimen);
                            if predicted {
                                predicted = false;
                                continue;
                            }
                            cuts += 1;
                            if cuts > max_cuts || total == 0.0 {
                                return Err(e);
                            }
                            h *= 0.5;
                        }
                    }
                }
                *current = target;
                Ok(Self::response(rod, *kind))
            }
        }
    }

    /// One step of the machine's control by `du` with compliance `C` in series: find the
    /// specimen's control w with w + C·R(w) = u ([`Series`], secant slopes: every trial
    /// re-solves the rod from the committed state, so history-dependent laws see one step; the
    /// first trial's Newton iteration starts from `predictor`'s configuration, if given).
    /// Returns the Newton iterations and w.
    fn solve_compliant(
        rod: &mut PlanarRod<'_>,
        kind: TestKind,
        du: f64,
        dt: f64,
        step: usize,
        (c, w0, r0, k0): (f64, f64, f64, f64),
        mut predictor: Option<&Predictor>,
    ) -> Result<(usize, f64), RodError> {
        let u = w0 + c * r0 + du;
        let tol = (1e-8 * (u.abs() + du.abs())).max(f64::MIN_POSITIVE);
        let mut total = 0;
        let solved = Series { a: 1.0, c }.solve(u, du, (w0, r0, k0), tol, |w| {
            // The first trial starts from the predicted configuration, later ones from the
            // previous trial's equilibrium (closer still).
            if let Some(p) = predictor.take() {
                p.predict(&mut rod.q, w - w0);
            }
            Self::apply_control(rod, kind, w);
            total += rod.solve(dt, step)?;
            Ok((Self::response(rod, kind), None))
        });
        match solved {
            Ok(s) => Ok((total, s.x)),
            Err(Failure::Eval(e)) => Err(e),
            Err(Failure::NotConverged) => Err(RodError::NotConverged {
                step,
                iterations: total,
                residual: f64::NAN,
                reason: "machine compliance: the specimen's deflection did not converge".into(),
            }),
        }
    }

    fn response(rod: &PlanarRod<'_>, kind: TestKind) -> f64 {
        match kind {
            TestKind::PureBending => rod.residual(rod.nodes() - 1)[2],
            _ => 2.0 * rod.punch.as_ref().map_or(0.0, |p| p.force_n),
        }
    }

    fn record(&self, curve: &mut SimCurve, record_span: bool) {
        let Driver::Rod { rod, kind, .. } = self else {
            return;
        };
        if *kind == TestKind::ThreePoint {
            curve
                .punch_contact
                .push(rod.punch.as_ref().is_some_and(|p| p.in_contact()));
        }
        if record_span {
            if curve.span_s_m.is_empty() {
                curve.span_s_m = (0..rod.l0.len())
                    .map(|e| rod.s_ref[e] + 0.5 * rod.l0[e])
                    .collect();
            }
            curve
                .span_curvature_per_m
                .push(rod.strain.iter().map(|s| s[2]).collect());
            curve
                .span_moment_nm
                .push(rod.stress.iter().map(|s| s[2]).collect());
        }
    }
}

/// Predictor of the next step's configuration from the last two committed steps (changes
/// `dq`, `dq_prev` of the configuration over specimen control increments `dw`, `dw_prev`):
/// quadratic extrapolation in the control (linear when only one step is usable), used only when
/// the coming increment `dw_next` goes in the same direction as the last ones and is at most
/// 1.5 times the last (no prediction across a reversal, where the response turns). Newton then
/// starts near the new equilibrium; where it converges to is unchanged.
#[derive(Debug, Default)]
struct Predictor {
    dq: Vec<Vector3<f64>>,
    dw: f64,
    dq_prev: Vec<Vector3<f64>>,
    dw_prev: f64,
}

impl Predictor {
    /// Record a committed step from `before` to `after` over the specimen control increment `dw`.
    fn record(&mut self, before: &[Vector3<f64>], after: &[Vector3<f64>], dw: f64) {
        std::mem::swap(&mut self.dq, &mut self.dq_prev);
        self.dw_prev = self.dw;
        self.dq.clear();
        self.dq.extend(after.iter().zip(before).map(|(a, b)| a - b));
        self.dw = dw;
    }

    /// Move `q` (the committed configuration) to the predicted one for the increment `dw_next`.
    fn predict(&self, q: &mut [Vector3<f64>], dw_next: f64) {
        let r = dw_next / self.dw;
        if self.dq.len() != q.len() || !(r > 0.0 && r <= 1.5) {
            return;
        }
        // Newton form through w_n − dw_prev − dw, w_n − dw, w_n: first divided differences
        // dq/dw and dq_prev/dw_prev, second their difference over dw + dw_prev.
        let rp = self.dw_prev / self.dw;
        let quad = self.dq_prev.len() == q.len() && rp > 0.0 && (0.25..=4.0).contains(&rp);
        // q(w_n + x) = q_n + x·s₁ + x (x + dw)·s₂ with s₁ = dq/dw,
        // s₂ = (dq/dw − dq_prev/dw_prev)/(dw + dw_prev).
        let x = dw_next;
        let c2 = if quad {
            x * (x + self.dw) / (self.dw + self.dw_prev)
        } else {
            0.0
        };
        for (i, qi) in q.iter_mut().enumerate() {
            let s1 = self.dq[i] / self.dw;
            *qi += s1 * x;
            if quad {
                *qi += (s1 - self.dq_prev[i] / self.dw_prev) * c2;
            }
        }
    }
}

/// The largest |control| of a history.
fn reach(control: &[f64]) -> f64 {
    control.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// The rod beyond each support of a three-point test when the setup does not give it:
/// 0.15 × the span `l`, or, where a deflection of `w_max` pulls more than that over the
/// supports, 1.5 × the slide-in of a straight half-span at that deflection,
/// √((l/2)² + w²) − l/2, plus 0.05 × the span (the bent rod's arc is longer than the chord).
/// The same 0.15 × span up to w ≈ 0.27 × span, so histories within that reach are replayed
/// on the same mesh as always; beyond it the rod no longer slides off its supports (a real
/// specimen is longer than the span; its overhang carries no load).
pub fn default_overhang(l: f64, w_max: f64) -> f64 {
    let slide = (0.5 * l).hypot(w_max) - 0.5 * l;
    (0.15 * l).max(1.5 * slide + 0.05 * l)
}

fn check_values(name: &str, v: &[f64]) -> Result<(), RodError> {
    if v.is_empty() {
        return Err(RodError::InvalidInput(format!("{name} is empty")));
    }
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(RodError::InvalidInput(format!(
            "{name}[{i}] is not a finite number ({})",
            v[i]
        )));
    }
    Ok(())
}

/// Simulate a test driving its control variable piecewise linearly through `path` (SI: elongation
/// m, twist rad, punch deflection m, end rotation rad), starting unloaded at control 0.
///
/// Steps: each segment is cut into equal steps of at most `max_increment` (default: 1/100 of the
/// largest |path value|, and for three-point at most 0.5 % of the span). One output entry per
/// step; when `path[0]` is 0 the first entry is the unloaded start. Tension and torsion use the
/// exact uniform sectional state; pure bending and three-point bending run the rod.
pub fn simulate_path(
    setup: &TestSetup,
    law: &dyn Law,
    path: &[f64],
    max_increment: Option<f64>,
) -> Result<SimCurve, RodError> {
    setup.validate()?;
    check_values("path", path)?;
    let scale = path.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut inc = max_increment.unwrap_or(if scale > 0.0 { scale / 100.0 } else { 1.0 });
    if setup.kind == TestKind::ThreePoint && max_increment.is_none() {
        inc = inc.min(0.005 * setup.free_length_m);
    }
    if !(inc.is_finite() && inc > 0.0) {
        return Err(RodError::InvalidInput(format!(
            "max increment must be positive, got {inc}"
        )));
    }
    let mut driver = match setup.kind {
        TestKind::Tension | TestKind::Torsion => {
            Driver::Uniform(UniformDriver::new(setup, law, scale))
        }
        _ => Driver::rod(setup, law, Some(inc), scale)?,
    };
    let mut curve = SimCurve::new(setup.kind);
    let mut c = 0.0;
    let mut t = 0.0;
    let mut step = 0usize;
    let mut iterations = 0usize;
    let dt_for = |dc: f64| setup.control_rate_per_s.map_or(1.0, |r| dc.abs() / r);
    if path[0] == 0.0 {
        let r = driver.step_to(0.0, 0.0, step, &mut iterations)?;
        curve.control.push(0.0);
        curve.response.push(r);
        curve.time_s.push(0.0);
        driver.record(&mut curve, setup.record_span);
        step += 1;
    }
    for &target in path {
        let seg = target - c;
        let n = ((seg.abs() / inc).ceil() as usize).max(if seg == 0.0 { 0 } else { 1 });
        let start = c;
        for k in 1..=n {
            let next = if k == n {
                target
            } else {
                start + seg * k as f64 / n as f64
            };
            let dt = dt_for(next - c);
            let r = driver.step_to(next, dt, step, &mut iterations)?;
            t += dt;
            c = next;
            curve.control.push(next);
            curve.response.push(r);
            curve.time_s.push(t);
            driver.record(&mut curve, setup.record_span);
            step += 1;
        }
    }
    curve.newton_iterations = iterations;
    Ok(curve)
}

/// Replay a measured control history sample by sample (`control[i]` reached at `time_s[i]`),
/// starting unloaded at control 0 (the approach to `control[0]` takes no time). One output entry
/// per sample. Tension, torsion and pure bending: direct sectional evaluation of the uniform state
/// (exact for a homogeneous rod; [`crate::replay_uniform`] is the same without the curve, the
/// calibration's hot loop). Three-point: the rod, with internal sub-steps of at most
/// `setup.max_substep` (default 0.5 % of the span). Machine compliance in series for every kind.
pub fn simulate_history(
    setup: &TestSetup,
    law: &dyn Law,
    control: &[f64],
    time_s: &[f64],
) -> Result<SimCurve, RodError> {
    setup.validate()?;
    check_values("control", control)?;
    check_values("time_s", time_s)?;
    if control.len() != time_s.len() {
        return Err(RodError::InvalidInput(format!(
            "control has {} samples but time_s has {}",
            control.len(),
            time_s.len()
        )));
    }
    let mut driver = if is_uniform(setup.kind) {
        let scale = control.iter().fold(0.0f64, |m, u| m.max(u.abs()));
        Driver::Uniform(UniformDriver::new(setup, law, scale))
    } else {
        Driver::rod(setup, law, None, reach(control))?
    };
    let mut curve = SimCurve::new(setup.kind);
    curve.control.reserve(control.len());
    curve.response.reserve(control.len());
    let mut iterations = 0usize;
    for (i, (&c, &t)) in control.iter().zip(time_s).enumerate() {
        let dt = if i == 0 {
            0.0
        } else {
            (t - time_s[i - 1]).max(0.0)
        };
        let r = driver.step_to(c, dt, i, &mut iterations)?;
        curve.control.push(c);
        curve.response.push(r);
        curve.time_s.push(t);
        driver.record(&mut curve, setup.record_span);
    }
    curve.newton_iterations = iterations;
    Ok(curve)
}

/// [`simulate_history`] of a three-point test with forward sensitivities of the response
/// (the punch force) to the law's parameters ([`Law::sens_params`] of the bending component, in
/// that order, `d_ei[j]` = ∂EI/∂p_j of the law's elastic bending stiffness, which scales the
/// contact penalties) and, with `compliance_column`, to the machine compliance, and with
/// `friction_column` to the supports' friction coefficient (after the compliance's), each
/// named as the diagnosis names it (`compliance`, `support_friction`): tangent-linear
/// through each converged step ([`PlanarRod::sens_step`]), one replay instead of one per
/// parameter. `Ok(None)` where the rod cannot differentiate the replay (another kind, a law
/// without sensitivities or with shear or axial channels that are not plain linear ones, a
/// round punch with machine compliance in series, a rough support whose anchor left the
/// element in contact during a step, a state a law does not differentiate); the caller then
/// differentiates numerically. Errors as [`simulate_history`]'s.
pub fn simulate_history_sens(
    setup: &TestSetup,
    law: &dyn Law,
    control: &[f64],
    time_s: &[f64],
    d_ei: &[f64],
    (compliance_column, friction_column): (bool, bool),
) -> Result<Option<(SimCurve, crate::uniform::ReplaySens)>, RodError> {
    setup.validate()?;
    check_values("control", control)?;
    check_values("time_s", time_s)?;
    if setup.kind != TestKind::ThreePoint {
        return Ok(None);
    }
    let Some(params) = law.sens_params(3) else {
        return Ok(None);
    };
    if control.len() != time_s.len() || d_ei.len() != params.len() {
        return Err(RodError::InvalidInput(format!(
            "control has {} samples, time_s {}; the law has {} sensitivity parameters, d_ei {}",
            control.len(),
            time_s.len(),
            params.len(),
            d_ei.len()
        )));
    }
    // The penalties as `Driver::rod` sets them: k = f·EI/L³ at the supports; at a point punch
    // with compliance C in series, k/(1 + 2Ck).
    let l = setup.free_length_m;
    let ei = law.elastic_tangent()[(3, 3)];
    let k_per_ei = setup.penalty_factor / (l * l * l);
    let k = k_per_ei * ei;
    let c = setup.machine_compliance;
    let point_punch = setup.punch_radius_m + setup.rod_radius_m == 0.0;
    if !point_punch && (c > 0.0 || compliance_column) {
        return Ok(None);
    }
    let g = 1.0 + 2.0 * c * k;
    let mut d_k_support: Vec<f64> = d_ei.iter().map(|d| k_per_ei * d).collect();
    let mut d_k_punch: Vec<f64> = d_k_support.iter().map(|d| d / (g * g)).collect();
    if compliance_column {
        d_k_support.push(0.0);
        d_k_punch.push(-2.0 * k * k / (g * g));
    }
    let mut d_mu = vec![0.0; d_k_punch.len()];
    if friction_column {
        d_k_support.push(0.0);
        d_k_punch.push(0.0);
        d_mu.push(1.0);
    }
    let ncol = d_k_punch.len();
    let mut driver = Driver::rod(setup, law, None, reach(control))?;
    let Driver::Rod { rod, .. } = &mut driver else {
        return Ok(None);
    };
    if !rod.enable_sens(&d_k_punch, &d_k_support, &d_mu) {
        return Ok(None);
    }
    let mut curve = SimCurve::new(setup.kind);
    let mut columns = vec![vec![0.0; control.len()]; ncol];
    let mut iterations = 0usize;
    for (i, (&u, &t)) in control.iter().zip(time_s).enumerate() {
        let dt = if i == 0 {
            0.0
        } else {
            (t - time_s[i - 1]).max(0.0)
        };
        let r = driver.step_to(u, dt, i, &mut iterations)?;
        curve.control.push(u);
        curve.response.push(r);
        curve.time_s.push(t);
        let Driver::Rod { rod, .. } = &driver else {
            return Ok(None);
        };
        // A point that needed no step (the control did not move) keeps the last derivatives.
        let Some(d) = rod.punch_force_sens() else {
            return Ok(None);
        };
        for (col, &v) in columns.iter_mut().zip(d) {
            col[i] = 2.0 * v;
        }
    }
    curve.newton_iterations = iterations;
    let mut params = params;
    if compliance_column {
        params.push("compliance".into());
    }
    if friction_column {
        params.push("support_friction".into());
    }
    Ok(Some((
        curve,
        crate::uniform::ReplaySens { params, columns },
    )))
}

/// Node positions (x m, y m, θ rad) of the deformed rod after replaying `path` in a rod-driven test
/// (pure bending or three-point); used to inspect the deformed shape (e.g. the pure-bending arc).
pub fn deformed_shape(
    setup: &TestSetup,
    law: &dyn Law,
    path: &[f64],
) -> Result<Vec<Vector3<f64>>, RodError> {
    setup.validate()?;
    check_values("path", path)?;
    let mut driver = Driver::rod(setup, law, setup.max_substep, reach(path))?;
    let mut iterations = 0;
    for (i, &c) in path.iter().enumerate() {
        driver.step_to(c, 1.0, i, &mut iterations)?;
    }
    match driver {
        Driver::Rod { rod, .. } => Ok(rod.q.clone()),
        Driver::Uniform(_) => Err(RodError::UnsupportedKind(setup.kind)),
    }
}
