//! A protocol-diverse family of generated tests (issue 12 item 7), independent of the demo
//! recipe: the demo varies specimens and laws over one protocol per kind; this family varies
//! what the demo does not.
//!
//! Each case, drawn from a seed (ChaCha8), is a [`SynthSpec`] for the real virtual lab (laws
//! from the registry, the real export layouts) plus its truth:
//! * kind: tension, torsion, pure bending (40 % / 30 % / 20 %) or three-point (10 %, linear law:
//!   the rod solver's large deflections make elastoplastic three-point truth a model question;
//!   a solid section, EA = E A and GA = 0.3 EA, and the truth is the apparent EI of
//!   48 EI w / l³ with the shear compliance, [`three_point_apparent_ei`]);
//! * law: `linear` or `elastoplastic` with E of 20–200 GPa, a yield strain 0.2–0.6 % and a
//!   hardening of 2–30 % of the elastic stiffness, on diameters of 1–8 mm and lengths of
//!   50–300 mm (span ≥ 16 d for three-point);
//! * amplitude schedule: constant, step-up (first cycle elastic: 0.5, 0.9, 2, 3 × the yield
//!   control) or step-down; one-sided (back to zero control) or two-sided (torsion and pure
//!   bending);
//! * dwells of 0–30 s at the turning points (or none), the rate changed by 0.1–10× from step to
//!   step, sampling 1 Hz – 2 kHz with 30–600 samples on the first ramp;
//! * response noise 0.05–1 % of the load cell's full scale, white or (30 %) AR(1) with
//!   φ = 0.3–0.95 at the logger's rate, ADC quantisation (none, 12 or 16 bit), a toe (slack)
//!   region in 30 % of the cases, a decimated export (every 2nd–8th row, ≥ 20 rows left on
//!   the first ramp) in 20 %.
//!
//! [`break_case`] adds monotonic tension tests to fracture (or stopped before it) under white
//! or AR(1) noise, as curves (the break detection's truth).
//!
//! A share ([`RATE_DEPENDENT_SHARE`]) of the tension, torsion and bending cases is
//! rate-dependent instead: `linear+viscoelasticity` (a Maxwell branch of 0.2–1 × the elastic
//! stiffness, relaxation time 0.2–2 × the first ramp's duration), with dwells of 1–3
//! relaxation times in two thirds of them, the rate changes above in all.
//!
//! Does not make drifting specimens.

use crate::spec::{Artefacts, Extension, Layout, Protocol, Step, SynthSpec};
use cablab_core::{Specimen, TestKind};
use cablab_laws::linear::GA_PER_EA;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

/// Share of the family's cases (not three-point) with a rate-dependent law: `linear` with a
/// viscoelastic Maxwell branch (`linear+viscoelasticity`).
pub const RATE_DEPENDENT_SHARE: f64 = 0.15;

/// Amplitude schedule of a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Schedule {
    /// The same amplitude every cycle.
    Constant,
    /// Growing amplitudes (the first cycle elastic for an elastoplastic law).
    StepUp,
    /// Falling amplitudes.
    StepDown,
}

/// What a generated case should measure as.
#[derive(Debug, Clone, PartialEq)]
pub struct FamilyTruth {
    /// Elastic stiffness (EA N, GJ or EI N m²); NaN for a rate-dependent law (its apparent
    /// stiffness depends on the rate).
    pub stiffness: f64,
    /// Relative accuracy of `stiffness` as the virtual lab reproduces it: 0 where the rod's
    /// answer is exact (uniform tension, torsion, pure bending); 10⁻³ for three-point, the
    /// rod solver's verified agreement with 48 EI w / l³ (`cablab-rod` verification). A CI
    /// narrower than this cannot be checked against the truth more finely.
    pub stiffness_tol: f64,
    /// Yield response (F_y N or M_y N m) when the law yields within the test.
    pub yield_response: Option<f64>,
    /// Expected behaviour class (`linear_elastic`, `elastoplastic` or `rate_dependent`).
    pub class: &'static str,
    /// The schedule drawn.
    pub schedule: Schedule,
    /// Whether cycles go to both signs.
    pub two_sided: bool,
    /// Response noise, fraction of full scale.
    pub noise_rel: f64,
    /// AR(1) coefficient of the noise at the logger's rate (0: white).
    pub noise_ar1: f64,
    /// Export decimation (every k-th row; 0 or 1: none).
    pub decimate: usize,
    /// Dwell at every turning point, s (0: none).
    pub dwell_s: f64,
    /// Machine control (m or rad) over which the first loading is elastic: from the end of the
    /// slack to the first ramp's end or, for an elastoplastic law, the yield control, whichever
    /// comes first (an oracle window for the stiffness).
    pub elastic_machine: [f64; 2],
}

/// One case of the family: the virtual lab's spec and the truth.
#[derive(Debug, Clone)]
pub struct FamilyCase {
    /// Generate with [`crate::generate`].
    pub spec: SynthSpec,
    /// What the characterisation should find.
    pub truth: FamilyTruth,
}

/// The bending stiffness the chapter's three-point formula F = 48 EI w / l³ measures on a
/// shear-flexible (Timoshenko) rod of span `l`: the mid-span compliance is l³/(48 EI) + l/(4 GA),
/// so EI_app = EI / (1 + 12 EI / (GA l²)) (2.5 (d/l)² below EI for a solid round section with
/// GA = 0.3 EA: 1 % at l = 16 d). The measurement does not correct for shear (a cable's GA
/// is not known from a three-point test), so this is what it must find.
pub fn three_point_apparent_ei(ei: f64, ga: f64, span: f64) -> f64 {
    ei / (1.0 + 12.0 * ei / (ga * span * span))
}

fn log_uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    (rng.random_range(lo.ln()..hi.ln())).exp()
}

/// `clean` plus stationary AR(1) noise of marginal σ `sd` and coefficient `phi` (0: white), one
/// standard normal draw per sample from `rng`.
fn with_ar1_noise(rng: &mut ChaCha8Rng, clean: &[f64], sd: f64, phi: f64) -> Vec<f64> {
    use rand_distr::{Distribution, StandardNormal};
    let mut p = 0.0f64;
    clean
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let e: f64 = StandardNormal.sample(rng);
            p = if i == 0 {
                e
            } else {
                phi * p + (1.0 - phi * phi).sqrt() * e
            };
            c + sd * p
        })
        .collect()
}

/// The case of `seed` (see the module doc for the distributions).
pub fn family_case(seed: u64) -> FamilyCase {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5EED_FA41_1700_0012);
    // Rate-dependent cases come from a stream of their own, so the other cases' draws are
    // those of the family without them.
    let mut visco_rng = ChaCha8Rng::seed_from_u64(seed ^ 0x0DA5_4B07_1200_0004);
    let rate_dependent = visco_rng.random_bool(RATE_DEPENDENT_SHARE);
    let u: f64 = rng.random();
    let kind = if u < 0.4 {
        TestKind::Tension
    } else if u < 0.7 {
        TestKind::Torsion
    } else if u < 0.9 {
        TestKind::PureBending
    } else {
        TestKind::ThreePoint
    };
    let d = rng.random_range(1e-3..8e-3);
    let l0 = if kind == TestKind::ThreePoint {
        rng.random_range(16.0..30.0) * d
    } else {
        rng.random_range(0.05..0.3)
    };
    let e = log_uniform(&mut rng, 20e9, 200e9);
    let g = e / 3.0;
    let area = std::f64::consts::PI * d * d / 4.0;
    let i2 = std::f64::consts::PI * d.powi(4) / 64.0;
    let ey = rng.random_range(0.002..0.006);
    let h = rng.random_range(0.02..0.3);
    let elastoplastic = kind != TestKind::ThreePoint && rng.random_bool(0.6);
    let rate_dependent = rate_dependent && kind != TestKind::ThreePoint;
    let elastoplastic = elastoplastic && !rate_dependent;
    // Stiffness, yield response and the control at yield (machine units).
    let (stiff_name, yname, hname, stiffness, y, cy) = match kind {
        TestKind::Tension => ("EA", "F_y", "H", e * area, e * area * ey, ey * l0),
        TestKind::Torsion => {
            let j = 2.0 * i2;
            let k = 2.0 * ey / d; // twist per length at the surface shear strain 2 εy
            ("GJ", "M_y", "HI", g * j, g * j * k, k * l0)
        }
        TestKind::PureBending => {
            let k = 2.0 * ey / d;
            ("EI", "M_y", "HI", e * i2, e * i2 * k, k * l0)
        }
        // Three-point: elastic up to w/l0 ≈ 0.03 (small deflection). The truth is the apparent
        // EI of the chapter's formula on a shear-flexible rod (see `three_point_apparent_ei`).
        _ => (
            "EI",
            "M_y",
            "HI",
            three_point_apparent_ei(e * i2, GA_PER_EA * e * area, l0),
            f64::NAN,
            0.03 * l0,
        ),
    };
    let schedule = match rng.random_range(0..3) {
        0 => Schedule::Constant,
        1 => Schedule::StepUp,
        _ => Schedule::StepDown,
    };
    let amps: Vec<f64> = match schedule {
        Schedule::Constant => {
            let a = if elastoplastic {
                rng.random_range(2.0..3.0)
            } else {
                1.0
            };
            vec![a; 3]
        }
        Schedule::StepUp => vec![0.5, 0.9, 2.0, 3.0],
        Schedule::StepDown => vec![3.0, 2.0, 1.0],
    };
    let linear_scale = if elastoplastic { 1.0 } else { 1.0 / 3.0 };
    let amps: Vec<f64> = amps.iter().map(|a| a * cy * linear_scale).collect();
    let two_sided =
        matches!(kind, TestKind::Torsion | TestKind::PureBending) && rng.random_bool(0.5);
    let fs = log_uniform(&mut rng, 1.0, 2000.0);
    let n1 = log_uniform(&mut rng, 30.0, 600.0);
    let base_rate = amps[0] * fs / n1;
    let dwell = if rng.random_bool(0.3) {
        0.0
    } else {
        rng.random_range(0.0..30.0)
    };
    // A Maxwell branch of 0.2–1 × the elastic stiffness relaxing in 0.2–2 × the first ramp's
    // duration; in two thirds of these cases the dwells last 1–3 relaxation times.
    let ramp_s = amps[0] / base_rate;
    let visco = rate_dependent.then(|| {
        let tau = ramp_s * visco_rng.random_range(0.2..2.0);
        let k_v = visco_rng.random_range(0.2..1.0);
        let dwell = if visco_rng.random_bool(2.0 / 3.0) {
            tau * visco_rng.random_range(1.0..3.0)
        } else {
            0.0
        };
        (tau, k_v, dwell)
    });
    let dwell = visco.map_or(dwell, |v| v.2);
    let mut steps = Vec::new();
    let mut rate = base_rate;
    for (k, &a) in amps.iter().enumerate() {
        if k > 0 {
            rate = (base_rate * log_uniform(&mut rng, 0.1, 10.0)).min(base_rate * 10.0);
        }
        steps.push(Step::Ramp { to: a, rate });
        if dwell > 0.0 {
            steps.push(Step::Hold { duration_s: dwell });
        }
        let lower = if two_sided { -a } else { 0.0 };
        steps.push(Step::Ramp { to: lower, rate });
        if dwell > 0.0 {
            steps.push(Step::Hold { duration_s: dwell });
        }
        if two_sided {
            steps.push(Step::Ramp { to: 0.0, rate });
        }
    }
    let noise_rel = log_uniform(&mut rng, 5e-4, 1e-2);
    let artefacts = Artefacts {
        noise_rel,
        adc_bits: [0, 12, 16][rng.random_range(0..3)],
        slack: if rng.random_bool(0.3) {
            rng.random_range(0.05..0.3) * amps[0]
        } else {
            0.0
        },
        ..Artefacts::default()
    };
    let layout =
        [Layout::TestXpert, Layout::BluehillCsv, Layout::Mts793Dat][rng.random_range(0..3)];
    // Drawn last, so the cases' other parameters do not depend on them.
    let artefacts = Artefacts {
        noise_ar1: if rng.random_bool(0.3) {
            rng.random_range(0.3..0.95)
        } else {
            0.0
        },
        // A decimated export in a fifth of the cases, keeping ≥ 20 rows on the first ramp.
        decimate: if rng.random_bool(0.2) {
            rng.random_range(2..=8).min((n1 / 20.0) as usize)
        } else {
            0
        },
        ..artefacts
    };
    let mut params = BTreeMap::new();
    if kind == TestKind::ThreePoint {
        // The rod's section must be one section: without EA the registry's shear stiffness
        // would be the chapter cable's (0.3 · 7.96·10⁴ N), up to 20 % of a stiff rod's
        // three-point compliance (the round-1 "three-point bias").
        params.insert("EI".to_string(), e * i2);
        params.insert("EA".to_string(), e * area);
    } else {
        params.insert(stiff_name.to_string(), stiffness);
    }
    if elastoplastic {
        params.insert(yname.to_string(), y);
        params.insert(hname.to_string(), h * stiffness);
    }
    let extension = visco.map(|(tau, k_v, _)| Extension {
        name: "viscoelasticity".into(),
        params: BTreeMap::from([
            (format!("{stiff_name}_v1"), k_v * stiffness),
            ("tau_v1".to_string(), tau),
        ]),
    });
    let spec = SynthSpec {
        kind,
        specimen: Specimen {
            label: Some(format!("family-{seed}")),
            diameter_m: Some(d),
            free_length_m: Some(l0),
        },
        law: if elastoplastic {
            "elastoplastic"
        } else {
            "linear"
        }
        .into(),
        params,
        extension,
        rig: Default::default(),
        protocol: Protocol { steps },
        artefacts,
        layout,
        seed,
        sample_rate_hz: fs,
        file_stem: Some(format!("family_{seed}")),
        specimen_number: None,
    };
    let (noise_ar1, decimate) = (spec.artefacts.noise_ar1, spec.artefacts.decimate);
    let slack = spec.artefacts.slack;
    let elastic_top = if elastoplastic {
        amps[0].min(cy)
    } else {
        amps[0]
    };
    FamilyCase {
        spec,
        truth: FamilyTruth {
            stiffness: if rate_dependent { f64::NAN } else { stiffness },
            stiffness_tol: if kind == TestKind::ThreePoint {
                1e-3
            } else {
                0.0
            },
            yield_response: elastoplastic.then_some(y),
            class: if rate_dependent {
                "rate_dependent"
            } else if elastoplastic {
                "elastoplastic"
            } else {
                "linear_elastic"
            },
            schedule,
            two_sided,
            noise_rel,
            noise_ar1,
            decimate,
            elastic_machine: [slack, slack + elastic_top],
            dwell_s: dwell,
        },
    }
}

/// A monotonic tension test to fracture (or not), as a logger records it: the truth of issue
/// 12 item 5's break detection under correlated noise.
#[derive(Debug, Clone)]
pub struct BreakCase {
    /// Time, s.
    pub time_s: Vec<f64>,
    /// Elongation, m (rises throughout).
    pub control: Vec<f64>,
    /// Force, N, with the noise.
    pub response: Vec<f64>,
    /// Free length, m.
    pub free_length_m: f64,
    /// First sample of the fallen response (None: the specimen does not break).
    pub break_sample: Option<usize>,
    /// Largest noise-free force, N.
    pub max_response: f64,
    /// ∫ F dΔl of the noise-free curve up to the break sample, J (None without a break).
    pub work_to_break: Option<f64>,
    /// AR(1) coefficient of the noise (0: white).
    pub noise_ar1: f64,
}

/// The monotonic case of `seed`: a bilinear elastoplastic rise (E A of 2·10³–2·10⁵ N, yield
/// at 0.2–0.6 % strain, hardening 1–20 %) to 2–10 × the yield strain on 200–3000 rows, with
/// response noise of 0.05–1 % of the maximum, white or AR(1) (φ = 0.3–0.95, in 60 % of the
/// cases). Two thirds of the cases break: the force falls within 1–3 rows to 0–20 % of its
/// value and the crosshead runs on for 5–30 % more rows; the others end at their maximum
/// (a test stopped before fracture) or soften gradually to no less than 70 % of it (necking
/// without fracture).
///
/// Does not make cyclic, compressive or three-point tests.
pub fn break_case(seed: u64) -> BreakCase {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xB4EA_C0DE_0012_0005);
    let l0 = rng.random_range(0.05..0.3);
    let ea = log_uniform(&mut rng, 2e3, 2e5);
    let ey = rng.random_range(0.002..0.006);
    let h = rng.random_range(0.01..0.2);
    let e_end = ey * rng.random_range(2.0..10.0);
    let n_rise = log_uniform(&mut rng, 200.0, 3000.0) as usize;
    let breaks = rng.random_bool(2.0 / 3.0);
    let soften = !breaks && rng.random_bool(0.5);
    let tail = if breaks || soften {
        (n_rise as f64 * rng.random_range(0.05..0.3)) as usize + 5
    } else {
        0
    };
    let drop_rows = rng.random_range(1..=3usize);
    let residual = rng.random_range(0.0..0.2);
    let soft_to = rng.random_range(0.7..0.95);
    let noise_rel = log_uniform(&mut rng, 5e-4, 1e-2);
    let phi = if rng.random_bool(0.6) {
        rng.random_range(0.3..0.95)
    } else {
        0.0
    };
    let law = |e: f64| -> f64 {
        if e <= ey {
            ea * e
        } else {
            ea * ey + h * ea * (e - ey)
        }
    };
    let de = e_end / n_rise as f64;
    let mut strain = Vec::with_capacity(n_rise + tail + 1);
    let mut clean = Vec::with_capacity(n_rise + tail + 1);
    for i in 0..=n_rise {
        let e = de * i as f64;
        strain.push(e);
        clean.push(law(e));
    }
    let top = clean[n_rise];
    for i in 1..=tail {
        let e = e_end + de * i as f64;
        strain.push(e);
        clean.push(if breaks {
            let t = (i as f64 / drop_rows as f64).min(1.0);
            top * (1.0 - t * (1.0 - residual))
        } else {
            top * (1.0 - (1.0 - soft_to) * i as f64 / tail as f64)
        });
    }
    // The first row at or below the drop level of the analysis (half the maximum).
    let break_sample = breaks.then(|| {
        (n_rise + 1..clean.len())
            .find(|&i| clean[i] < 0.5 * top)
            .unwrap_or(clean.len() - 1)
    });
    let work_to_break = break_sample.map(|j| {
        (0..j)
            .map(|i| 0.5 * (clean[i] + clean[i + 1]) * (strain[i + 1] - strain[i]) * l0)
            .sum()
    });
    let response = with_ar1_noise(&mut rng, &clean, noise_rel * top, phi);
    let rate_hz = 10.0;
    BreakCase {
        time_s: (0..clean.len()).map(|i| i as f64 / rate_hz).collect(),
        control: strain.iter().map(|e| e * l0).collect(),
        response,
        free_length_m: l0,
        break_sample,
        max_response: top,
        work_to_break,
        noise_ar1: phi,
    }
}

/// How a [`CyclicBreakCase`] ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CyclicEnd {
    /// At the end of its last unloading (no break).
    Unloaded,
    /// Stopped at the peak of its last loading (no break).
    AtPeak,
    /// The specimen breaks on its last loading: the force is gone within 1–3 rows while the
    /// crosshead runs on.
    Breaks,
    /// The force falls gradually, to 70–95 % of the last loading's peak, while the crosshead
    /// runs on (damage, a wire slipping in its grip; no fracture).
    Softens,
}

/// A cyclic tension test (a fatigue block or a cable's load cycles) whose last cycle may end in
/// a fracture: the truth of the break detection on records whose largest cycle is not their
/// last.
#[derive(Debug, Clone)]
pub struct CyclicBreakCase {
    /// Time, s.
    pub time_s: Vec<f64>,
    /// Elongation, m.
    pub control: Vec<f64>,
    /// Force, N, with the noise.
    pub response: Vec<f64>,
    /// Free length, m.
    pub free_length_m: f64,
    /// How it ends.
    pub end: CyclicEnd,
    /// First sample below half the last loading's noise-free peak (the analysis' drop level),
    /// for [`CyclicEnd::Breaks`].
    pub break_sample: Option<usize>,
    /// The sample of the last loading's noise-free peak ([`CyclicEnd::Breaks`] and
    /// [`CyclicEnd::Softens`]: the last sample before the fall).
    pub last_peak: Option<usize>,
    /// Sine cycles (else triangles).
    pub sine: bool,
    /// Samples per cycle.
    pub per_cycle: usize,
    /// AR(1) coefficient of the noise (0: white).
    pub noise_ar1: f64,
}

/// The cyclic case of `seed`: 4–30 one-sided cycles (zero to peak elongation and back, a
/// tension–tension block) of a linear specimen (E A of 2·10³–2·10⁵ N), triangles or sines of
/// 60–600 rows per cycle, the amplitude constant, rising, falling or rising and falling again
/// (a fatigue block: never below 40 % of its largest), response noise of 0.05–1 % of the largest
/// force, white or AR(1) (φ = 0.3–0.95, 40 % of the cases). It ends unloaded, stopped at a peak,
/// broken on its last loading (at 70–100 % of the way up; the force gone to 0–20 % within 1–3
/// rows while the crosshead runs on for 5–40 rows) or softening gradually to 70–95 % of that
/// peak, a quarter each.
pub fn cyclic_break_case(seed: u64) -> CyclicBreakCase {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xC1C1_B4EA_0013_0001);
    let l0 = rng.random_range(0.05..0.3);
    let ea = log_uniform(&mut rng, 2e3, 2e5);
    let cycles = rng.random_range(4..=30usize);
    let per = log_uniform(&mut rng, 60.0, 600.0) as usize;
    let sine = rng.random_bool(0.5);
    let schedule = rng.random_range(0..4u8);
    let end = match rng.random_range(0..4u8) {
        0 => CyclicEnd::Unloaded,
        1 => CyclicEnd::AtPeak,
        2 => CyclicEnd::Breaks,
        _ => CyclicEnd::Softens,
    };
    let strain_top = rng.random_range(0.002..0.01);
    let noise_rel = log_uniform(&mut rng, 5e-4, 1e-2);
    let phi = if rng.random_bool(0.4) {
        rng.random_range(0.3..0.95)
    } else {
        0.0
    };
    let up_to = rng.random_range(0.7..=1.0f64);
    let drop_rows = rng.random_range(1..=3usize);
    let residual = rng.random_range(0.0..0.2);
    let run_on = rng.random_range(5..=40usize);
    let soft_to = rng.random_range(0.7..0.95);
    let amp = |c: usize| -> f64 {
        let x = c as f64 / (cycles - 1) as f64;
        match schedule {
            0 => 1.0,
            1 => 0.4 + 0.6 * x,
            2 => 1.0 - 0.6 * x,
            _ => 0.4 + 0.6 * (std::f64::consts::PI * x).sin(),
        }
    };
    // One cycle's shape at phase p in [0, 1): 0 → 1 → 0.
    let shape = |p: f64| -> f64 {
        if sine {
            0.5 * (1.0 - (std::f64::consts::TAU * p).cos())
        } else if p < 0.5 {
            2.0 * p
        } else {
            2.0 - 2.0 * p
        }
    };
    let mut strain: Vec<f64> = Vec::new();
    for c in 0..cycles - 1 {
        for i in 0..per {
            strain.push(strain_top * amp(c) * shape(i as f64 / per as f64));
        }
    }
    // The last cycle: its loading, then what the end makes of it.
    let last = strain_top * amp(cycles - 1);
    let rise = per / 2;
    let (mut break_sample, mut last_peak) = (None, None);
    let mut clean: Vec<f64>;
    match end {
        CyclicEnd::Unloaded => {
            for i in 0..=per {
                strain.push(last * shape((i % per) as f64 / per as f64));
            }
            clean = strain.iter().map(|e| ea * e).collect();
        }
        CyclicEnd::AtPeak => {
            for i in 0..=rise {
                strain.push(last * shape(i as f64 / per as f64));
            }
            clean = strain.iter().map(|e| ea * e).collect();
        }
        CyclicEnd::Breaks | CyclicEnd::Softens => {
            let stop = ((rise as f64 * up_to) as usize).max(rise / 2);
            for i in 0..=stop {
                strain.push(last * shape(i as f64 / per as f64));
            }
            clean = strain.iter().map(|e| ea * e).collect();
            let k = clean.len() - 1;
            let top = clean[k];
            let step = last / rise as f64;
            let tail = if end == CyclicEnd::Breaks {
                run_on
            } else {
                rise.max(20)
            };
            for i in 1..=tail {
                strain.push(strain[k] + step * i as f64);
                clean.push(if end == CyclicEnd::Breaks {
                    let t = (i as f64 / drop_rows as f64).min(1.0);
                    top * (1.0 - t * (1.0 - residual))
                } else {
                    top * (1.0 - (1.0 - soft_to) * i as f64 / tail as f64)
                });
            }
            last_peak = Some(k);
            if end == CyclicEnd::Breaks {
                break_sample = (k + 1..clean.len()).find(|&i| clean[i] < 0.5 * top);
            }
        }
    }
    let largest = clean.iter().fold(0.0f64, |m, &v| m.max(v));
    let response = with_ar1_noise(&mut rng, &clean, noise_rel * largest, phi);
    let rate_hz = per as f64 / 4.0;
    CyclicBreakCase {
        time_s: (0..clean.len()).map(|i| i as f64 / rate_hz).collect(),
        control: strain.iter().map(|e| e * l0).collect(),
        response,
        free_length_m: l0,
        end,
        break_sample,
        last_peak,
        sine,
        per_cycle: per,
        noise_ar1: phi,
    }
}
