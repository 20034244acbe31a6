//! The law registry the CLI (`cablab simulate --law … --param …`) and the calibration use: law
//! names, each law's parameters with units, defaults and bounds as data ([`param_specs`]), and
//! [`build`] turning a name and a parameter map into one [`Law`].
//!
//! Laws (SI parameters; `S`, `Y`, `H` stand for the kind's stiffness, strength and hardening names:
//! tension `EA` (N), `F_y` (N), `H` (N); torsion `GJ` (N m²), `M_y` (N m), `HI` (N m²);
//! three_point and pure_bending `EI` (N m²), `M_y` (N m), `HI` (N m²)):
//! - `linear`: `S` (required); chapter eq. (16).
//! - `piecewise_linear` (alias `piecewise_elasticity`): `S1`, `S2`, threshold `K_t` (1/m)
//!   (`Gamma_t` (-) in tension); eq. (19). In bending: `EI1`, `EI2`, `K_t`.
//! - `elastoplastic` (alias `plasticity`): `S`, `Y` (required), `H` (default 0); eqs. (23)–(32).
//! - `kinematic_hardening`: elastoplastic + Prager back-stress modulus `H_kin` (tension) or
//!   `HI_kin` (others); optional Armstrong–Frederick recovery `b_kin` (default 0, unit m, or 1 in
//!   tension).
//! - `stiffness_degradation`: elastoplastic + `D_inf` (-) (asymptotic stiffness loss, < 1) and
//!   `alpha_D` (accumulated plastic curvature (1/m), or strain (-) in tension, at 63 % of D_inf).
//! - `viscoelasticity`: elastoplastic + Maxwell branch `S_v1` (e.g. `EI_v1`), `tau_v1` (s); optional
//!   branches 2 and 3 (`S_v2`, `tau_v2`, `S_v3`, `tau_v3`; stiffness default 0 = absent).
//! - `friction_hysteresis`: elastoplastic + Iwan elements of total stiffness `S_f` (e.g. `EI_f`)
//!   saturating at the friction strength `M_f` (`F_f` in tension), `n_f` slip levels (default 10;
//!   real: a fraction adds a last, partial level) sampling a power-law density of slip strains
//!   with exponent `chi_f` (default 0: uniform).
//! - `BASE+EXT+…`: extensions stacked, each at most once: `viscoelasticity` and
//!   `friction_hysteresis` (parallel branches) on `linear`, `piecewise_linear` or `elastoplastic`;
//!   `kinematic_hardening` and `stiffness_degradation` (hardening rules of the one return
//!   mapping) on `elastoplastic` only. The extension names alone mean `elastoplastic+…`
//!   (`kinematic_hardening+viscoelasticity`); the canonical name lists the extensions in the
//!   order above, whatever the order given, and the parameters follow in that order.
//!
//! Every law is complete in all six components: stiffnesses a test does not load default to the
//! chapter's cable (Table 1: EA = 7.96·10⁴ N, GJ = 2.02·10⁻³ N m², EI = 1.37·10⁻³ N m²) and
//! GA = 0.3·EA (ν = 0.5, κ = 0.9); they can be overridden by name (`EA`, `GJ`, `EI`, `GA`) and are
//! marked `fitted: false` (the test is insensitive to them).

use crate::channel::Channel;
use crate::elastoplastic::{Degradation, Elastoplastic};
use crate::error::LawError;
use crate::friction::IwanElements;
use crate::law::Law;
use crate::linear::{LinearElastic, SectionStiffness, GA_PER_EA};
use crate::parallel::Parallel;
use crate::piecewise::PiecewiseLinear;
use crate::viscoelastic::{MaxwellBranch, MaxwellBranches};
use cablab_core::{Effect, TestKind};
use serde::Serialize;
use std::collections::BTreeMap;

/// The law names [`build`] accepts alone (besides the aliases and `BASE+EXT` compositions).
pub const LAW_NAMES: [&str; 7] = [
    "linear",
    "piecewise_linear",
    "elastoplastic",
    "kinematic_hardening",
    "stiffness_degradation",
    "viscoelasticity",
    "friction_hysteresis",
];

/// One parameter of a law, as data for the CLI's help and the calibration's bounds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParamSpec {
    /// Name as passed in `--param NAME=VALUE` and in the parameter map.
    pub name: String,
    /// SI unit (`N`, `N m`, `N m^2`, `1/m`, `s`, `1`).
    pub unit: String,
    /// Value used when the parameter is not given; `None` means required.
    pub default: Option<f64>,
    /// Smallest admissible value (inclusive).
    pub lower: f64,
    /// Largest admissible value (inclusive).
    pub upper: f64,
    /// What the parameter is.
    pub doc: String,
    /// Whether calibration should fit it by default: false for stiffnesses of components the
    /// test does not load, structural choices (number of elements), optional refinements
    /// (Armstrong–Frederick recovery, extra Maxwell branches) that stay at their default unless
    /// asked for.
    pub fitted: bool,
}

/// The 6-vector component a test of `kind` loads: tension → 2 (Γ₃), torsion → 5 (K₃),
/// pure_bending and three_point → 3 (K₁). `Unknown` maps to 3 (bending, the chapter's focus);
/// [`build`] rejects it.
pub fn loaded_component(kind: TestKind) -> usize {
    match kind {
        TestKind::Tension => 2,
        TestKind::Torsion => 5,
        TestKind::ThreePoint | TestKind::PureBending | TestKind::Unknown => 3,
    }
}

/// The law that adds a sectional effect of the diagnosis vocabulary to the default baseline:
/// `plasticity` → `elastoplastic`, `piecewise_elasticity` → `piecewise_linear`, the four
/// extensions → their own names, `none` → `elastoplastic` (the baseline itself). `None` for the
/// effects that are not sectional laws (`machine_compliance`, `sensor_drift`,
/// `support_friction`: they belong to the test set-up, not to the section) and for the verdict
/// `unexplained`.
pub fn law_for_effect(effect: Effect) -> Option<&'static str> {
    match effect {
        Effect::None | Effect::Plasticity => Some("elastoplastic"),
        Effect::PiecewiseElasticity => Some("piecewise_linear"),
        Effect::KinematicHardening => Some("kinematic_hardening"),
        Effect::StiffnessDegradation => Some("stiffness_degradation"),
        Effect::Viscoelasticity => Some("viscoelasticity"),
        Effect::FrictionHysteresis => Some("friction_hysteresis"),
        Effect::MachineCompliance
        | Effect::SensorDrift
        | Effect::SupportFriction
        | Effect::Unexplained => None,
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Base {
    Linear,
    Piecewise,
    Elastoplastic,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Ext {
    Kinematic,
    Degradation,
    Viscoelastic,
    Friction,
}

/// Canonical name, base and extensions (in canonical order) of a law name.
fn parse(law: &str) -> Result<(String, Base, Vec<Ext>), LawError> {
    let unknown = || {
        LawError::UnknownLaw {
        given: law.to_string(),
        known: format!(
            "{} (aliases plasticity, piecewise_elasticity; compositions BASE+EXT+…: viscoelasticity and friction_hysteresis on linear, piecewise_linear or elastoplastic, kinematic_hardening and stiffness_degradation on elastoplastic, each extension once)",
            LAW_NAMES.join(", ")
        ),
    }
    };
    let norm = law.trim().to_ascii_lowercase().replace('-', "_");
    let base_of = |s: &str| match s {
        "linear" | "linear_elastic" => Some(Base::Linear),
        "piecewise_linear" | "piecewise_elasticity" => Some(Base::Piecewise),
        "elastoplastic" | "plasticity" => Some(Base::Elastoplastic),
        _ => None,
    };
    let ext_of = |s: &str| match s {
        "kinematic_hardening" => Some(Ext::Kinematic),
        "stiffness_degradation" => Some(Ext::Degradation),
        "viscoelasticity" => Some(Ext::Viscoelastic),
        "friction_hysteresis" => Some(Ext::Friction),
        _ => None,
    };
    let mut tokens = norm.split('+').map(str::trim);
    let first = tokens.next().unwrap_or("");
    let (base, mut exts) = match (base_of(first), ext_of(first)) {
        (Some(b), _) => (b, Vec::new()),
        (None, Some(e)) => (Base::Elastoplastic, vec![e]),
        (None, None) => return Err(unknown()),
    };
    for t in tokens {
        let e = ext_of(t).ok_or_else(unknown)?;
        if exts.contains(&e) {
            return Err(unknown());
        }
        exts.push(e);
    }
    if base != Base::Elastoplastic
        && exts
            .iter()
            .any(|e| matches!(e, Ext::Kinematic | Ext::Degradation))
    {
        return Err(unknown());
    }
    exts.sort();
    Ok((canonical_name(base, &exts), base, exts))
}

fn base_name(b: Base) -> &'static str {
    match b {
        Base::Linear => "linear",
        Base::Piecewise => "piecewise_linear",
        Base::Elastoplastic => "elastoplastic",
    }
}

fn ext_name(e: Ext) -> &'static str {
    match e {
        Ext::Kinematic => "kinematic_hardening",
        Ext::Degradation => "stiffness_degradation",
        Ext::Viscoelastic => "viscoelasticity",
        Ext::Friction => "friction_hysteresis",
    }
}

/// `elastoplastic` with extensions is named by its extensions alone (`kinematic_hardening`,
/// `kinematic_hardening+viscoelasticity`); other bases lead (`linear+friction_hysteresis`).
fn canonical_name(base: Base, exts: &[Ext]) -> String {
    let mut parts: Vec<&str> = Vec::new();
    if base != Base::Elastoplastic || exts.is_empty() {
        parts.push(base_name(base));
    }
    parts.extend(exts.iter().map(|&e| ext_name(e)));
    parts.join("+")
}

/// Names and units of a channel's quantities.
pub(crate) struct Names {
    pub(crate) stiff: &'static str,
    stiff_unit: &'static str,
    pub(crate) strength: &'static str,
    strength_unit: &'static str,
    pub(crate) hard: &'static str,
    pub(crate) strain: &'static str,
    strain_unit: &'static str,
    stiff_max: f64,
    strength_max: f64,
}

pub(crate) fn names(ch: Channel) -> Names {
    match ch {
        Channel::Axial => Names {
            stiff: "EA",
            stiff_unit: "N",
            strength: "F",
            strength_unit: "N",
            hard: "H",
            strain: "Gamma",
            strain_unit: "1",
            stiff_max: 1e12,
            strength_max: 1e9,
        },
        Channel::Twist => Names {
            stiff: "GJ",
            stiff_unit: "N m^2",
            strength: "M",
            strength_unit: "N m",
            hard: "HI",
            strain: "K",
            strain_unit: "1/m",
            stiff_max: 1e6,
            strength_max: 1e6,
        },
        Channel::Bending => Names {
            stiff: "EI",
            stiff_unit: "N m^2",
            strength: "M",
            strength_unit: "N m",
            hard: "HI",
            strain: "K",
            strain_unit: "1/m",
            stiff_max: 1e6,
            strength_max: 1e6,
        },
    }
}

/// Smallest admissible stiffness (a zero stiffness would make the section singular).
const STIFF_MIN: f64 = 1e-12;

fn spec(
    name: String,
    unit: &str,
    default: Option<f64>,
    lower: f64,
    upper: f64,
    doc: String,
    fitted: bool,
) -> ParamSpec {
    ParamSpec {
        name,
        unit: unit.to_string(),
        default,
        lower,
        upper,
        doc,
        fitted,
    }
}

fn specs_for(kind: TestKind, base: Base, exts: &[Ext]) -> Result<Vec<ParamSpec>, String> {
    let ch = Channel::of_kind(kind)
        .ok_or_else(|| "the kind decides which component the law loads".to_string())?;
    let n = names(ch);
    let mut v = Vec::new();
    match base {
        Base::Linear => v.push(spec(
            n.stiff.into(),
            n.stiff_unit,
            None,
            STIFF_MIN,
            n.stiff_max,
            format!("elastic stiffness ({})", n.stiff),
            true,
        )),
        Base::Piecewise => {
            v.push(spec(
                format!("{}1", n.stiff),
                n.stiff_unit,
                None,
                STIFF_MIN,
                n.stiff_max,
                "stiffness below the threshold (eq. 19)".into(),
                true,
            ));
            v.push(spec(
                format!("{}2", n.stiff),
                n.stiff_unit,
                None,
                0.0,
                n.stiff_max,
                "stiffness above the threshold (eq. 19)".into(),
                true,
            ));
            v.push(spec(
                format!("{}_t", n.strain),
                n.strain_unit,
                None,
                0.0,
                1e6,
                "threshold strain magnitude (eq. 19)".into(),
                true,
            ));
        }
        Base::Elastoplastic => {
            v.push(spec(
                n.stiff.into(),
                n.stiff_unit,
                None,
                STIFF_MIN,
                n.stiff_max,
                format!("elastic stiffness ({})", n.stiff),
                true,
            ));
            v.push(spec(
                format!("{}_y", n.strength),
                n.strength_unit,
                None,
                0.0,
                n.strength_max,
                "initial yield strength (eq. 32)".into(),
                true,
            ));
            v.push(spec(
                n.hard.into(),
                n.stiff_unit,
                Some(0.0),
                0.0,
                n.stiff_max,
                "linear isotropic hardening modulus (eq. 32)".into(),
                true,
            ));
        }
    }
    for &ext in exts {
        match ext {
            Ext::Kinematic => {
                v.push(spec(
                    format!("{}_kin", n.hard),
                    n.stiff_unit,
                    None,
                    0.0,
                    n.stiff_max,
                    "Prager kinematic hardening modulus c of the back stress".into(),
                    true,
                ));
                let inv = if n.strain_unit == "1" { "1" } else { "m" };
                v.push(spec("b_kin".into(), inv, Some(0.0), 0.0, 1e9, "Armstrong-Frederick recovery b (back stress saturates at c/b); 0 = linear Prager rule".into(), false));
            }
            Ext::Degradation => {
                v.push(spec("D_inf".into(), "1", None, 0.0, 0.99, "asymptotic loss of elastic stiffness, k = k0 (1 - D_inf (1 - exp(-alpha/alpha_D)))".into(), true));
                v.push(spec(
                    "alpha_D".into(),
                    n.strain_unit,
                    None,
                    1e-12,
                    1e6,
                    "accumulated plastic deformation at which 63 % of D_inf is reached".into(),
                    true,
                ));
            }
            Ext::Viscoelastic => {
                for (i, tau) in [(1, None), (2, Some(10.0)), (3, Some(100.0))] {
                    let first = i == 1;
                    v.push(spec(
                        format!("{}_v{i}", n.stiff),
                        n.stiff_unit,
                        if first { None } else { Some(0.0) },
                        0.0,
                        n.stiff_max,
                        format!(
                            "spring stiffness of Maxwell branch {i}{}",
                            if first { "" } else { " (0: no branch)" }
                        ),
                        first,
                    ));
                    v.push(spec(
                        format!("tau_v{i}"),
                        "s",
                        tau,
                        1e-9,
                        1e15,
                        format!("relaxation time of Maxwell branch {i}"),
                        first,
                    ));
                }
            }
            Ext::Friction => {
                v.push(spec(
                    format!("{}_f", n.stiff),
                    n.stiff_unit,
                    None,
                    STIFF_MIN,
                    n.stiff_max,
                    "total stiffness of the Jenkins (spring + slider) elements".into(),
                    true,
                ));
                v.push(spec(
                    format!("{}_f", n.strength),
                    n.strength_unit,
                    None,
                    0.0,
                    n.strength_max,
                    "friction strength reached when every element slips".into(),
                    true,
                ));
                v.push(spec(
                    "n_f".into(),
                    "1",
                    Some(10.0),
                    1.0,
                    200.0,
                    "number of slip levels (Jenkins elements of equal stiffness; a fraction adds a last level of that share)".into(),
                    true,
                ));
                v.push(spec(
                    "chi_f".into(),
                    "1",
                    Some(0.0),
                    -0.95,
                    50.0,
                    "exponent of the Iwan density of slip strains, ρ ∝ ε*^χ (0: uniform, parabolic backbone; < 0: more early slip; > 0: slip concentrated near saturation)".into(),
                    true,
                ));
            }
        }
    }
    let d = SectionStiffness::CHAPTER_CABLE;
    for (name, unit, value, max, comp) in [
        ("EA", "N", d.ea_n, 1e12, Channel::Axial),
        ("GJ", "N m^2", d.gj_nm2, 1e6, Channel::Twist),
        ("EI", "N m^2", d.ei_nm2, 1e6, Channel::Bending),
    ] {
        if comp != ch {
            v.push(spec(
                name.into(),
                unit,
                Some(value),
                STIFF_MIN,
                max,
                format!("{name} of the unloaded component (default: the chapter's cable, Table 1)"),
                false,
            ));
        }
    }
    v.push(spec(
        "GA".into(),
        "N",
        Some(d.ga_n),
        STIFF_MIN,
        1e12,
        "transverse shear stiffness (default 0.3 EA: nu = 0.5, kappa = 0.9)".into(),
        false,
    ));
    Ok(v)
}

/// The canonical name of a law name or composition (`elastoplastic+viscoelasticity+kinematic_hardening`
/// → `kinematic_hardening+viscoelasticity`), or why it names no law.
pub fn canonical_law_name(law: &str) -> Result<String, LawError> {
    parse(law).map(|(name, ..)| name)
}

/// The parameters of `law` for tests of `kind`, in order (loaded parameters first), or an error
/// naming an unknown law or an unsupported kind.
pub fn try_param_specs(kind: TestKind, law: &str) -> Result<Vec<ParamSpec>, LawError> {
    let (name, base, exts) = parse(law)?;
    specs_for(kind, base, &exts).map_err(|why| LawError::UnsupportedKind {
        law: name,
        kind: kind.to_string(),
        why,
    })
}

/// The parameters of `law` for tests of `kind` (empty for an unknown law or kind; use
/// [`try_param_specs`] for the reason).
pub fn param_specs(kind: TestKind, law: &str) -> Vec<ParamSpec> {
    try_param_specs(kind, law).unwrap_or_default()
}

/// The scale [`example_params`] takes for `kind`: the chapter cable's stiffness in the loaded
/// component ((EA) = 7.96·10⁴ N, (GJ) = 2.02·10⁻³ N m², (EI) = 1.37·10⁻³ N m²) and a
/// strength of the same order as its tests reach (54 N, 0.02 N m, 0.01 N m); for benchmarks
/// and tests. Three-point bending loads the bending component.
pub fn example_scale(kind: TestKind) -> (f64, f64) {
    match kind {
        TestKind::Tension => (7.96e4, 54.0),
        TestKind::Torsion => (2.02e-3, 0.02),
        _ => (1.37e-3, 0.01),
    }
}

/// Plausible values for every required parameter of `law` for tests of `kind`, scaled to a
/// loaded `stiffness` and `strength` (yield strain strength/stiffness): for examples, benchmarks
/// and tests that need "some" law of each name. Optional parameters keep their defaults.
pub fn example_params(
    kind: TestKind,
    law: &str,
    stiffness: f64,
    strength: f64,
) -> Result<BTreeMap<String, f64>, LawError> {
    let (k, y) = (stiffness, strength);
    let ey = y / k;
    let mut params = BTreeMap::new();
    for sp in try_param_specs(kind, law)?
        .into_iter()
        .filter(|s| s.default.is_none())
    {
        let n = sp.name.as_str();
        let v = match n {
            "D_inf" => 0.3,
            "alpha_D" => 2.0 * ey,
            "tau_v1" => 0.5,
            _ if n.ends_with("_y") => y,
            _ if n.ends_with("_kin") => 0.3 * k,
            _ if n.ends_with("_v1") => 0.4 * k,
            _ if n.ends_with("_t") => ey,
            _ if n.ends_with('1') => k,
            _ if n.ends_with('2') => 0.2 * k,
            _ if n.starts_with("F_") || n.starts_with("M_") => 0.3 * y,
            _ if n.ends_with("_f") => 0.3 * k,
            _ => k,
        };
        params.insert(sp.name, v);
    }
    Ok(params)
}

/// Build `law` for tests of `kind` from SI parameter values (`params` by [`ParamSpec::name`]).
/// Unknown laws and parameter names, missing required values and values that are not finite or
/// outside their bounds are errors that name the culprit.
pub fn build(
    kind: TestKind,
    law: &str,
    params: &BTreeMap<String, f64>,
) -> Result<Box<dyn Law>, LawError> {
    let (name, base, exts) = parse(law)?;
    let specs = try_param_specs(kind, law)?;
    for given in params.keys() {
        if !specs.iter().any(|s| &s.name == given) {
            return Err(LawError::UnknownParam {
                law: name.clone(),
                kind: kind.to_string(),
                given: given.clone(),
                known: specs
                    .iter()
                    .map(|s| s.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
    }
    let mut values = BTreeMap::new();
    for s in &specs {
        let v = match (params.get(&s.name), s.default) {
            (Some(&v), _) => v,
            (None, Some(d)) => d,
            (None, None) => {
                return Err(LawError::MissingParam {
                    law: name.clone(),
                    name: s.name.clone(),
                    doc: s.doc.clone(),
                    unit: s.unit.clone(),
                })
            }
        };
        let invalid = |why: String| LawError::InvalidParam {
            law: name.clone(),
            name: s.name.clone(),
            value: v,
            why,
        };
        if !v.is_finite() {
            return Err(invalid("not a finite number".into()));
        }
        if v < s.lower || v > s.upper {
            return Err(invalid(format!(
                "must lie in [{:e}, {:e}] {}",
                s.lower, s.upper, s.unit
            )));
        }
        values.insert(s.name.as_str(), v);
    }
    let get = |k: &str| values.get(k).copied().unwrap_or(0.0);
    let ch = Channel::of_kind(kind).ok_or_else(|| LawError::UnsupportedKind {
        law: name.clone(),
        kind: kind.to_string(),
        why: "the kind decides which component the law loads".into(),
    })?;
    let n = names(ch);
    let mut elastic = SectionStiffness::CHAPTER_CABLE;
    if let Some(&v) = values.get("EA") {
        elastic.ea_n = v;
    }
    if let Some(&v) = values.get("GJ") {
        elastic.gj_nm2 = v;
    }
    if let Some(&v) = values.get("EI") {
        elastic.ei_nm2 = v;
    }
    // GA follows EA unless given.
    elastic.ga_n = params
        .get("GA")
        .copied()
        .unwrap_or(GA_PER_EA * elastic.ea_n);

    let base_law: Box<dyn Law> = match base {
        Base::Linear => Box::new(LinearElastic::new(elastic)),
        Base::Piecewise => Box::new(PiecewiseLinear {
            elastic,
            channel: ch,
            k1: get(&format!("{}1", n.stiff)),
            k2: get(&format!("{}2", n.stiff)),
            threshold: get(&format!("{}_t", n.strain)),
        }),
        Base::Elastoplastic => {
            let mut ep = Elastoplastic::isotropic(
                elastic,
                ch,
                get(&format!("{}_y", n.strength)),
                get(n.hard),
            );
            if exts
                .iter()
                .any(|e| matches!(e, Ext::Kinematic | Ext::Degradation))
            {
                ep.label = canonical_name(
                    base,
                    &exts
                        .iter()
                        .copied()
                        .filter(|e| matches!(e, Ext::Kinematic | Ext::Degradation))
                        .collect::<Vec<_>>(),
                );
            }
            for &e in &exts {
                match e {
                    Ext::Kinematic => {
                        ep.plastic[0].kin_hardening = get(&format!("{}_kin", n.hard));
                        ep.plastic[0].kin_recovery = get("b_kin");
                    }
                    Ext::Degradation => {
                        ep.plastic[0].degradation = Some(Degradation {
                            d_inf: get("D_inf"),
                            alpha_d: get("alpha_D"),
                        });
                    }
                    _ => {}
                }
            }
            Box::new(ep)
        }
    };
    // Parallel branches (Maxwell, Iwan) wrap the section law one at a time; each composite is
    // named by the extensions it holds so far.
    let mut law = base_law;
    let mut held: Vec<Ext> = exts
        .iter()
        .copied()
        .filter(|e| matches!(e, Ext::Kinematic | Ext::Degradation))
        .collect();
    for &e in &exts {
        let branch: Box<dyn Law> = match e {
            Ext::Viscoelastic => {
                let branches = (1..=3)
                    .map(|i| MaxwellBranch {
                        stiffness: get(&format!("{}_v{i}", n.stiff)),
                        tau_s: get(&format!("tau_v{i}")),
                    })
                    .enumerate()
                    .filter(|(i, b)| *i == 0 || b.stiffness > 0.0)
                    .map(|(_, b)| b)
                    .collect();
                Box::new(MaxwellBranches {
                    channel: ch,
                    branches,
                })
            }
            Ext::Friction => Box::new(IwanElements::slip_levels(
                ch,
                get(&format!("{}_f", n.stiff)),
                get(&format!("{}_f", n.strength)),
                get("n_f"),
                get("chi_f"),
            )),
            Ext::Kinematic | Ext::Degradation => continue,
        };
        held.push(e);
        law = Box::new(Parallel::new(canonical_name(base, &held), law, branch));
    }
    debug_assert_eq!(law.name(), name);
    Ok(law)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::driver::drive_uniform;

    fn p(kv: &[(&str, f64)]) -> BTreeMap<String, f64> {
        kv.iter().map(|(k, v)| (k.to_string(), *v)).collect()
    }

    #[test]
    fn contract_parameter_names() {
        let names = |k, l| {
            param_specs(k, l)
                .into_iter()
                .filter(|s| s.fitted)
                .map(|s| s.name)
                .collect::<Vec<_>>()
        };
        let want: [(TestKind, &str, &[&str]); 12] = [
            (TestKind::Tension, "linear", &["EA"][..]),
            (TestKind::Torsion, "linear", &["GJ"][..]),
            (TestKind::PureBending, "linear", &["EI"][..]),
            (
                TestKind::ThreePoint,
                "piecewise_linear",
                &["EI1", "EI2", "K_t"][..],
            ),
            (
                TestKind::PureBending,
                "elastoplastic",
                &["EI", "M_y", "HI"][..],
            ),
            (TestKind::Tension, "elastoplastic", &["EA", "F_y", "H"][..]),
            (TestKind::Torsion, "elastoplastic", &["GJ", "M_y", "HI"][..]),
            (
                TestKind::PureBending,
                "kinematic_hardening",
                &["EI", "M_y", "HI", "HI_kin"][..],
            ),
            (
                TestKind::Tension,
                "stiffness_degradation",
                &["EA", "F_y", "H", "D_inf", "alpha_D"][..],
            ),
            (
                TestKind::PureBending,
                "viscoelasticity",
                &["EI", "M_y", "HI", "EI_v1", "tau_v1"][..],
            ),
            (
                TestKind::Tension,
                "friction_hysteresis",
                &["EA", "F_y", "H", "EA_f", "F_f", "n_f", "chi_f"][..],
            ),
            (
                TestKind::Torsion,
                "linear+friction_hysteresis",
                &["GJ", "GJ_f", "M_f", "n_f", "chi_f"][..],
            ),
        ];
        for (kind, law, fitted) in want {
            assert_eq!(names(kind, law), fitted, "{kind} {law}");
        }
        for k in TestKind::ALL {
            for l in LAW_NAMES {
                for s in param_specs(k, l) {
                    assert!(s.lower <= s.upper, "{k} {l} {}", s.name);
                    if let Some(d) = s.default {
                        assert!(
                            d >= s.lower && d <= s.upper,
                            "{k} {l} {} default {d}",
                            s.name
                        );
                    }
                }
            }
        }
        assert!(param_specs(TestKind::Unknown, "linear").is_empty());
        assert!(param_specs(TestKind::Tension, "nonsense").is_empty());
    }

    #[test]
    fn effects_map_to_buildable_laws() {
        for e in Effect::ALL {
            if let Some(l) = law_for_effect(e) {
                assert!(
                    !param_specs(TestKind::PureBending, l).is_empty(),
                    "{e} -> {l}"
                );
                let (canonical, ..) = parse(l).unwrap();
                assert_eq!(canonical, l);
            }
        }
        assert_eq!(law_for_effect(Effect::Plasticity), Some("elastoplastic"));
        assert_eq!(law_for_effect(Effect::SupportFriction), None);
    }

    #[test]
    fn extensions_stack_and_their_branches_add() {
        // Names are canonical whatever the order given; parameters concatenate.
        let names = |l| {
            param_specs(TestKind::PureBending, l)
                .into_iter()
                .filter(|s| s.fitted)
                .map(|s| s.name)
                .collect::<Vec<_>>()
        };
        assert_eq!(
            names("viscoelasticity+kinematic_hardening"),
            ["EI", "M_y", "HI", "HI_kin", "EI_v1", "tau_v1"]
        );
        assert_eq!(
            names("linear+friction_hysteresis+viscoelasticity"),
            ["EI", "EI_v1", "tau_v1", "EI_f", "M_f", "n_f", "chi_f"]
        );
        let (canonical, ..) =
            parse("elastoplastic+friction_hysteresis+stiffness_degradation").unwrap();
        assert_eq!(canonical, "stiffness_degradation+friction_hysteresis");
        // Each extension once; hardening rules only on a yielding base.
        assert!(parse("viscoelasticity+viscoelasticity").is_err());
        assert!(parse("linear+kinematic_hardening").is_err());
        assert!(parse("linear+nonsense").is_err());

        // Parallel branches: the stacked law's moment is the sum of its parts', sample by sample,
        // over a cyclic history with a hold (the Maxwell branch relaxes, the Iwan elements slip).
        let strain: Vec<f64> = (0..400)
            .map(|i| {
                let t = i as f64 * 0.05;
                if (8.0..10.0).contains(&t) {
                    2.0
                } else {
                    2.0 * (t * 0.8).sin() + 1.0 * (t * 0.31).sin()
                }
            })
            .collect();
        let time: Vec<f64> = (0..400).map(|i| i as f64 * 0.05).collect();
        let base = p(&[("EI", 1.0), ("M_y", 1.5), ("HI", 0.2)]);
        let visco = [("EI_v1", 0.4), ("tau_v1", 1.5)];
        let fric = [("EI_f", 0.3), ("M_f", 0.1)];
        let run = |law: &str, extra: &[(&str, f64)]| {
            let mut params = base.clone();
            params.extend(extra.iter().map(|(k, v)| (k.to_string(), *v)));
            let law = build(TestKind::PureBending, law, &params).unwrap();
            drive_uniform(law.as_ref(), 3, &strain, &time)
        };
        let ep = run("elastoplastic", &[]);
        let v = run("viscoelasticity", &visco);
        let f = run("friction_hysteresis", &fric);
        let both: Vec<(&str, f64)> = visco.iter().chain(&fric).copied().collect();
        let vf = run("friction_hysteresis+viscoelasticity", &both);
        let mut hyst = 0.0f64;
        for i in 0..strain.len() {
            let sum = v[i] + f[i] - ep[i];
            assert!((vf[i] - sum).abs() < 1e-12, "{i}: {} vs {sum}", vf[i]);
            hyst = hyst.max((f[i] - ep[i]).abs());
        }
        assert!(hyst > 0.05, "the friction branch carries load: {hyst}");
        // Hardening rules combine in one return mapping: with no degradation the stack is the
        // kinematic law, and degradation changes it once plastic flow accumulates.
        let kin = run("kinematic_hardening", &[("HI_kin", 0.3)]);
        let kd0 = run(
            "kinematic_hardening+stiffness_degradation",
            &[("HI_kin", 0.3), ("D_inf", 0.0), ("alpha_D", 1.0)],
        );
        assert_eq!(kin, kd0);
        let kd = run(
            "kinematic_hardening+stiffness_degradation",
            &[("HI_kin", 0.3), ("D_inf", 0.3), ("alpha_D", 0.5)],
        );
        assert!(kin.iter().zip(&kd).any(|(a, b)| (a - b).abs() > 1e-2));
    }

    #[test]
    fn loaded_components() {
        assert_eq!(loaded_component(TestKind::Tension), 2);
        assert_eq!(loaded_component(TestKind::Torsion), 5);
        assert_eq!(loaded_component(TestKind::PureBending), 3);
        assert_eq!(loaded_component(TestKind::ThreePoint), 3);
    }

    #[test]
    fn errors_name_the_culprit() {
        let e = build(TestKind::Tension, "elastoplastik", &p(&[])).unwrap_err();
        assert!(
            matches!(&e, LawError::UnknownLaw { given, .. } if given == "elastoplastik"),
            "{e}"
        );
        let e = build(
            TestKind::Tension,
            "elastoplastic",
            &p(&[("EA", 1e5), ("F_y", 50.0), ("M_y", 1.0)]),
        )
        .unwrap_err();
        assert!(
            matches!(&e, LawError::UnknownParam { given, .. } if given == "M_y"),
            "{e}"
        );
        assert!(e.to_string().contains("F_y"), "{e}");
        let e = build(TestKind::Tension, "elastoplastic", &p(&[("EA", 1e5)])).unwrap_err();
        assert!(
            matches!(&e, LawError::MissingParam { name, .. } if name == "F_y"),
            "{e}"
        );
        let e = build(
            TestKind::PureBending,
            "elastoplastic",
            &p(&[("EI", -1.0), ("M_y", 1.0)]),
        )
        .unwrap_err();
        assert!(
            matches!(&e, LawError::InvalidParam { name, value, .. } if name == "EI" && *value == -1.0),
            "{e}"
        );
        let e = build(TestKind::PureBending, "linear", &p(&[("EI", f64::NAN)])).unwrap_err();
        assert!(
            matches!(&e, LawError::InvalidParam { name, .. } if name == "EI"),
            "{e}"
        );
        let e = build(
            TestKind::PureBending,
            "stiffness_degradation",
            &p(&[("EI", 1.0), ("M_y", 1.0), ("D_inf", 1.0), ("alpha_D", 1.0)]),
        )
        .unwrap_err();
        assert!(
            matches!(&e, LawError::InvalidParam { name, .. } if name == "D_inf"),
            "{e}"
        );
        let e = build(TestKind::Unknown, "linear", &p(&[("EI", 1.0)])).unwrap_err();
        assert!(matches!(&e, LawError::UnsupportedKind { .. }), "{e}");
        let e = build(TestKind::PureBending, "linear+kinematic_hardening", &p(&[])).unwrap_err();
        assert!(matches!(&e, LawError::UnknownLaw { .. }), "{e}");
        let e = build(
            TestKind::PureBending,
            "friction_hysteresis",
            &p(&[
                ("EI", 1.0),
                ("M_y", 1.0),
                ("EI_f", 1.0),
                ("M_f", 1.0),
                ("n_f", 0.5),
            ]),
        )
        .unwrap_err();
        assert!(
            matches!(&e, LawError::InvalidParam { name, .. } if name == "n_f"),
            "{e}"
        );
    }

    /// Built laws reproduce their defining numbers (SPEC cycle through the registry; defaults).
    #[test]
    fn built_laws_behave() {
        let law = build(
            TestKind::PureBending,
            "elastoplastic",
            &p(&[("EI", 1.0), ("M_y", 1.0), ("HI", 0.25)]),
        )
        .unwrap();
        assert_eq!(law.name(), "elastoplastic");
        let m = drive_uniform(law.as_ref(), 3, &[0.0, 3.0, -3.0], &[0.0, 1.0, 2.0]);
        assert!((m[1] - 1.4).abs() < 1e-12 && (m[2] + 2.04).abs() < 1e-12);
        let t = law.elastic_tangent();
        assert_eq!(t[(2, 2)], 7.96e4);
        assert_eq!(t[(0, 0)], 0.3 * 7.96e4);
        assert_eq!(t[(4, 4)], 1.0);

        let law = build(TestKind::Tension, "linear", &p(&[("EA", 1e5)])).unwrap();
        let t = law.elastic_tangent();
        assert_eq!(
            (t[(2, 2)], t[(0, 0)], t[(3, 3)], t[(5, 5)]),
            (1e5, 0.3 * 1e5, 1.37e-3, 2.02e-3)
        );

        let law = build(
            TestKind::Torsion,
            "piecewise_elasticity",
            &p(&[("GJ1", 2.0), ("GJ2", 0.5), ("K_t", 0.1)]),
        )
        .unwrap();
        assert_eq!(law.name(), "piecewise_linear");
        let m = drive_uniform(law.as_ref(), 5, &[0.3], &[0.0]);
        assert!((m[0] - (0.2 + 0.5 * 0.2)).abs() < 1e-12);

        for (l, extra) in [
            ("kinematic_hardening", vec![("HI_kin", 0.5)]),
            (
                "stiffness_degradation",
                vec![("D_inf", 0.3), ("alpha_D", 1.0)],
            ),
            (
                "viscoelasticity",
                vec![("EI_v1", 0.5), ("tau_v1", 1.0), ("EI_v2", 0.1)],
            ),
            ("friction_hysteresis", vec![("EI_f", 0.5), ("M_f", 0.1)]),
        ] {
            let mut params = p(&[("EI", 1.0), ("M_y", 1.0), ("HI", 0.25)]);
            params.extend(extra.iter().map(|(k, v)| (k.to_string(), *v)));
            let law = build(TestKind::ThreePoint, l, &params).unwrap();
            assert_eq!(law.name(), l);
            let m = drive_uniform(law.as_ref(), 3, &[0.0, 3.0, -3.0], &[0.0, 1.0, 2.0]);
            // Every extension changes the baseline's response.
            assert!(
                (m[1] - 1.4).abs() > 1e-3 || (m[2] + 2.04).abs() > 1e-3,
                "{l}: {m:?}"
            );
        }
        let law = build(
            TestKind::PureBending,
            "viscoelasticity",
            &p(&[
                ("EI", 1.0),
                ("M_y", 1.0),
                ("EI_v1", 0.5),
                ("tau_v1", 1.0),
                ("EI_v2", 0.1),
            ]),
        )
        .unwrap();
        assert_eq!(
            law.n_state(),
            5 + 2 * 3,
            "branch 3 (stiffness 0) is dropped"
        );
        let law = build(
            TestKind::PureBending,
            "linear+viscoelasticity",
            &p(&[("EI", 1.0), ("EI_v1", 0.5), ("tau_v1", 2.0)]),
        )
        .unwrap();
        assert_eq!(law.name(), "linear+viscoelasticity");
        // Step to K = 1 at t = 0 then hold: M = 1 + 0.5 e^(−t/2).
        let m = drive_uniform(law.as_ref(), 3, &[1.0, 1.0], &[0.0, 2.0]);
        assert!((m[0] - 1.5).abs() < 1e-12 && (m[1] - (1.0 + 0.5 * (-1.0f64).exp())).abs() < 1e-12);
    }

    /// Every law for every kind: consistent tangent against finite differences after a cyclic,
    /// timed history (elastic, plastic, reversed states), other components loaded too.
    #[test]
    fn every_built_law_has_a_consistent_tangent() {
        use crate::testutil::assert_tangent_fd;
        use crate::Strain6;
        // (kind, loaded stiffness k, strength y; yield strain y/k)
        let kinds = [
            (TestKind::Tension, 1e5, 50.0),
            (TestKind::Torsion, 2e-3, 0.02),
            (TestKind::PureBending, 1.37e-3, 0.01),
        ];
        let mut laws: Vec<String> = LAW_NAMES.iter().map(|s| s.to_string()).collect();
        laws.push("linear+viscoelasticity".into());
        laws.push("piecewise_linear+friction_hysteresis".into());
        for (kind, k, y) in kinds {
            let ey = y / k;
            let comp = loaded_component(kind);
            for law in &laws {
                let mut params = example_params(kind, law, k, y).unwrap();
                if law == "kinematic_hardening" {
                    params.insert("b_kin".into(), 0.5 / ey);
                }
                let built =
                    build(kind, law, &params).unwrap_or_else(|e| panic!("{kind} {law}: {e}"));
                let mut old = vec![0.0; built.n_state()];
                built.init_state(&mut old);
                let mut new = old.clone();
                let mut eps = Strain6::zeros();
                for e in [1.0, 3.1, 2.0, -0.5, -2.9, 1.7] {
                    eps[comp] = e * ey;
                    built.update(&eps, 0.2, &old, &mut new);
                    old.copy_from_slice(&new);
                }
                for (e, other) in [(2.3, 0.0), (0.9, 0.4), (-3.7, 1.3), (1.37, -0.8)] {
                    let mut x = Strain6::new(1e-4, -2e-4, 1e-3, 0.5, 0.2, 0.3);
                    x[comp] = e * ey;
                    if kind == TestKind::PureBending {
                        x[4] = other * ey;
                    }
                    assert_tangent_fd(built.as_ref(), &x, 0.1, &old, 1e-6);
                }
            }
        }
    }
}
