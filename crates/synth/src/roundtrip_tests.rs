//! Round trips: every layout written by [`crate::generate_with_truth`] parses back (with a small
//! test-only reader) to the measured channels within the written precision, carries the specimen
//! metadata, and is byte-identical under the same seed.

use std::collections::BTreeMap;

use cablab_core::{Specimen, TestKind};

use crate::spec::*;
use crate::truth::Truth;
use crate::{generate_with_truth, SynthOutput};

/// Bilinear elastoplastic spring in the control (test-only truth, not the registry law):
/// stiffness k, yield at r_y, hardening slope h.
struct Bilinear {
    k: f64,
    r_y: f64,
    h: f64,
}
impl Truth for Bilinear {
    fn respond(&self, control: &[f64], _t: &[f64]) -> Result<Vec<f64>, crate::SynthError> {
        let (mut cp, mut alpha) = (0.0f64, 0.0f64);
        let kp = self.k * self.h / (self.k - self.h); // plastic modulus in control terms
        Ok(control
            .iter()
            .map(|&c| {
                let trial = self.k * (c - cp);
                let f = trial.abs() - (self.r_y + kp * alpha);
                if f > 0.0 {
                    let dg = f / (self.k + kp);
                    cp += dg * trial.signum();
                    alpha += dg;
                }
                self.k * (c - cp)
            })
            .collect())
    }
}

fn spec(kind: TestKind, layout: Layout) -> SynthSpec {
    let protocol = match kind {
        TestKind::Tension => Protocol {
            steps: vec![Step::ResponseCycles {
                lower: 2.0,
                upper: 100.0,
                rate: 2e-5,
                count: 3,
                dwell_s: 0.5,
                max_control: 2e-3,
            }],
        },
        TestKind::Torsion | TestKind::PureBending => Protocol {
            steps: vec![Step::Cycles {
                lower: 0.0,
                upper: 1.4,
                rate: 0.1,
                count: 2,
                dwell_s: 0.0,
            }],
        },
        _ => Protocol {
            steps: vec![
                Step::Ramp {
                    to: 2e-3,
                    rate: 1e-4,
                },
                Step::Hold { duration_s: 1.0 },
                Step::Ramp {
                    to: 0.0,
                    rate: 1e-4,
                },
            ],
        },
    };
    SynthSpec {
        kind,
        specimen: Specimen {
            label: Some("cable-2.8-Ä1".into()),
            diameter_m: Some(2.8e-3),
            free_length_m: Some(if kind == TestKind::ThreePoint {
                0.056
            } else {
                0.032
            }),
        },
        law: "test-bilinear".into(),
        params: BTreeMap::new(),
        extension: None,
        rig: Rig::default(),
        protocol,
        artefacts: Artefacts {
            noise_rel: 1e-3,
            control_noise_rel: 1e-4,
            response_offset: 0.01,
            drift_per_s: 1e-4,
            slack: 5e-6,
            ..Artefacts::default()
        },
        layout,
        seed: 42,
        sample_rate_hz: 20.0,
        file_stem: None,
        specimen_number: Some(2),
    }
}

fn truth_for(kind: TestKind) -> Bilinear {
    match kind {
        TestKind::Tension => Bilinear {
            k: 7.96e4 / 0.032,
            r_y: 54.0,
            h: 0.2 * 7.96e4 / 0.032,
        },
        TestKind::Torsion | TestKind::PureBending => Bilinear {
            k: 0.05,
            r_y: 0.03,
            h: 0.005,
        },
        _ => Bilinear {
            k: 500.0,
            r_y: 0.6,
            h: 100.0,
        },
    }
}

/// Test-only reader: decodes, finds the header row by the written channel names, skips the units
/// row, and parses every data row (quotes stripped, decimal comma honoured).
fn read_back(out: &SynthOutput, layout: Layout) -> (String, Vec<Vec<f64>>) {
    let text = match layout {
        Layout::BluehillCsv => String::from_utf8(out.bytes.clone()).expect("Bluehill is UTF-8"),
        _ => {
            assert!(
                std::str::from_utf8(&out.bytes).is_err(),
                "Latin-1 file must not be valid UTF-8 here"
            );
            encoding_rs::WINDOWS_1252.decode(&out.bytes).0.into_owned()
        }
    };
    let sep = if layout == Layout::BluehillCsv {
        ','
    } else {
        '\t'
    };
    let comma = layout != Layout::BluehillCsv;
    let lines: Vec<&str> = text.lines().collect();
    let first_name = &out.channels[0].name;
    let h = lines
        .iter()
        .position(|l| l.split(sep).any(|c| c.trim_matches('"') == first_name))
        .expect("header row");
    let mut cols = vec![Vec::new(); out.channels.len()];
    for l in &lines[h + 2..] {
        if l.trim().is_empty() {
            continue;
        }
        let mut cells: Vec<&str> = l.split(sep).collect();
        if layout == Layout::BluehillCsv {
            assert_eq!(cells[0], "\"\"");
            cells.remove(0);
        }
        for (j, c) in cells.iter().enumerate() {
            let s = c.trim_matches('"');
            let s = if comma {
                s.replace(',', ".")
            } else {
                s.to_string()
            };
            cols[j].push(s.parse::<f64>().unwrap_or_else(|_| panic!("number '{s}'")));
        }
    }
    (text, cols)
}

fn check_round_trip(kind: TestKind, layout: Layout) {
    let s = spec(kind, layout);
    let out = generate_with_truth(&s, &truth_for(kind)).unwrap();
    let (text, cols) = read_back(&out, layout);
    let n = out.measured.time_s.len();
    assert!(n > 50, "{n} rows");
    for (ch, col) in out.channels.iter().zip(&cols) {
        assert_eq!(col.len(), n, "{}", ch.name);
        let want: &[f64] = match ch.role.as_str() {
            "time" => &out.measured.time_s,
            "control" => &out.measured.control_si,
            "response" => &out.measured.response_si,
            _ => &out.measured.cycle,
        };
        let tol = ch.precision_si() * (1.0 + 1e-9) + 1e-15;
        for (i, (&v, &w)) in col.iter().zip(want).enumerate() {
            let got = v * ch.si_per_unit;
            assert!(
                (got - w).abs() <= tol,
                "{kind} {layout:?} {} row {i}: {got} vs {w} (tol {tol})",
                ch.name
            );
        }
    }
    // Metadata: label, diameter and length, kind note.
    assert!(text.contains("cable-2.8-Ä1"), "label missing");
    let note = format!("kind={}", kind.as_str());
    assert!(text.contains(&note));
    match layout {
        Layout::TestXpert => {
            assert!(text.contains("\"Durchmesser\"\t2,8\t\"mm\""));
            let l = if kind == TestKind::ThreePoint {
                "56"
            } else {
                "32"
            };
            assert!(text.contains(&format!("\"Versuchslänge\"\t{l}\t\"mm\"")));
        }
        Layout::BluehillCsv => {
            assert!(text.contains("\"Diameter\",\"2.8\",\"mm\""));
            assert!(text.starts_with("\"Specimen label\""));
            assert!(
                text.contains("\n2,Time,"),
                "specimen number as first header cell"
            );
            assert!(text.ends_with("\n\n"));
        }
        Layout::Mts793Dat => {
            assert!(text.starts_with("MTS793|MPT|DEU|"));
            assert!(text.contains("Durchmesser :\t2,8\n"));
            assert!(text.contains("Probenbezeichnung :  \tcable-2.8-Ä1\n"));
        }
    }
    // Determinism under the seed.
    let again = generate_with_truth(&s, &truth_for(kind)).unwrap();
    assert_eq!(out.bytes, again.bytes);
    let mut s2 = s.clone();
    s2.seed = 43;
    assert_ne!(
        generate_with_truth(&s2, &truth_for(kind)).unwrap().bytes,
        out.bytes
    );
}

#[test]
fn round_trip_every_layout_and_kind() {
    for layout in [Layout::TestXpert, Layout::BluehillCsv, Layout::Mts793Dat] {
        for kind in TestKind::ALL {
            check_round_trip(kind, layout);
        }
    }
}

/// Load-limited tension: the noise-free truth turns at the force limits (event detection), the
/// slack travel precedes loading, and the measured record differs from the truth only by the
/// artefacts.
#[test]
fn tension_load_cycles_turn_at_the_limits_in_the_truth() {
    let s = spec(TestKind::Tension, Layout::TestXpert);
    let out = generate_with_truth(&s, &truth_for(TestKind::Tension)).unwrap();
    let r = &out.truth.response_si;
    let max = r.iter().cloned().fold(f64::MIN, f64::max);
    // The exact turning point lies between samples; the logged peak is within one sample's rise.
    let step = 7.96e4 / 0.032 * 2e-5 / 20.0;
    assert!(
        max <= 100.0 * (1.0 + 1e-6) && max > 100.0 - step,
        "peak {max}"
    );
    // Plastic: after the first load to 100 N the elongation at the 2 N preload is residual.
    let i_peak = r.iter().position(|&x| x == max).unwrap();
    let i_val = (i_peak..r.len())
        .min_by(|&a, &b| r[a].total_cmp(&r[b]))
        .unwrap();
    let c_res = out.truth.control_specimen_si[i_val];
    // Bilinear: unloading elastic from 100 N to ≈2 N, plastic strain (100−54)/k·(1−h/k)... > 0.
    assert!(c_res > 1e-5, "residual {c_res}");
    // Slack: first rows read zero force within noise while the machine moves.
    assert_eq!(out.truth.response_si[0], 0.0);
    assert!(out.truth.control_machine_si[1] > 0.0 && out.truth.control_specimen_si[1] == 0.0);
}

/// The registry truth: the chapter's cable in tension (EA = 7.96·10⁴ N, F_y = 54 N, H = 2·10⁴ N,
/// l₀ = 32 mm). Below yield the noise-free truth is F = EA Δl/l₀ (eq. (1)); the 100 N cycles
/// leave a residual elongation at the preload equal to the plastic strain × l₀.
#[test]
fn registry_elastoplastic_tension_truth() {
    let mut s = spec(TestKind::Tension, Layout::Mts793Dat);
    s.law = "elastoplastic".into();
    s.params = [("EA", 7.96e4), ("F_y", 54.0), ("H", 2.0e4)]
        .iter()
        .map(|(k, v)| (k.to_string(), *v))
        .collect();
    s.artefacts = Artefacts {
        slack: 0.0,
        ..Artefacts::default()
    };
    let out = crate::generate(&s).unwrap();
    let (c, r) = (&out.truth.control_specimen_si, &out.truth.response_si);
    for i in 0..c.len() {
        if r[i] > 0.0 && r[i] < 50.0 && i < 20 {
            assert!(
                (r[i] - 7.96e4 * c[i] / 0.032).abs() < 1e-9 * 7.96e4,
                "row {i}"
            );
        }
    }
    // Peak 100 N on the hardening line: ε = 54/EA + (100−54)(1/E_t) with E_t = EA·H/(EA+H).
    let et = 7.96e4 * 2.0e4 / (7.96e4 + 2.0e4);
    let eps_pl = (100.0 - 54.0) * (1.0 / et - 1.0 / 7.96e4);
    let i_last = r.len() - 1;
    // Last row: unloaded to the 2 N preload → elongation = (ε_pl + 2/EA) l₀.
    assert!((r[i_last] - 2.0).abs() < 1e-6, "final force {}", r[i_last]);
    let want = (eps_pl + 2.0 / 7.96e4) * 0.032;
    assert!(
        (c[i_last] / want - 1.0).abs() < 1e-6,
        "residual {} vs {want}",
        c[i_last]
    );
}

/// Three-point bending through the rod: the elastic force at small deflection follows
/// F = 48 EI w / l₀³ (eq. (3)) to within the rod's geometric nonlinearity (< 0.5 % at w/l₀ = 0.01).
#[test]
fn registry_three_point_truth_matches_eq3_at_small_deflection() {
    let mut s = spec(TestKind::ThreePoint, Layout::BluehillCsv);
    s.law = "linear".into();
    s.params = [("EI".to_string(), 1.37e-3)].into_iter().collect();
    s.protocol = Protocol {
        steps: vec![Step::Ramp {
            to: 0.56e-3,
            rate: 1e-4,
        }],
    };
    s.sample_rate_hz = 5.0;
    let out = crate::generate(&s).unwrap();
    let (c, r) = (&out.truth.control_specimen_si, &out.truth.response_si);
    let i = c.len() - 1;
    let f_eq3 = 48.0 * 1.37e-3 * c[i] / 0.056f64.powi(3);
    assert!(
        (r[i] / f_eq3 - 1.0).abs() < 5e-3,
        "rod {} vs eq. (3) {f_eq3}",
        r[i]
    );
}

fn plain(
    kind: TestKind,
    law: &str,
    params: &[(&str, f64)],
    steps: Vec<Step>,
    l0: f64,
) -> SynthSpec {
    let mut s = spec(kind, Layout::BluehillCsv);
    s.law = law.into();
    s.params = params.iter().map(|(k, v)| (k.to_string(), *v)).collect();
    s.specimen.free_length_m = Some(l0);
    s.protocol = Protocol { steps };
    s.artefacts = Artefacts {
        noise_rel: 0.0,
        adc_bits: 0,
        control_quantum: Some(0.0),
        ..Artefacts::default()
    };
    s.sample_rate_hz = 10.0;
    s
}

/// Extensions compose the registry's way, and parameters may not be given twice.
#[test]
fn extension_names_compose_like_the_registry() {
    let mut s = plain(
        TestKind::PureBending,
        "elastoplastic",
        &[("EI", 1.0)],
        vec![Step::Hold { duration_s: 1.0 }],
        0.05,
    );
    s.extension = Some(Extension {
        name: "kinematic_hardening".into(),
        params: [("HI_kin".to_string(), 0.1)].into(),
    });
    assert_eq!(
        crate::registry::registry_law(&s).unwrap().0,
        "kinematic_hardening"
    );
    s.law = "linear".into();
    s.extension = Some(Extension {
        name: "viscoelasticity".into(),
        params: [("EI".to_string(), 2.0)].into(),
    });
    assert!(crate::registry::registry_law(&s).is_err());
    s.extension = Some(Extension {
        name: "viscoelasticity".into(),
        params: BTreeMap::new(),
    });
    assert_eq!(
        crate::registry::registry_law(&s).unwrap().0,
        "linear+viscoelasticity"
    );
}

/// `linear` + `viscoelasticity` in pure bending: at a hold after a fast ramp the moment relaxes
/// from (EI + EI_v1) K towards EI K with time constant tau_v1 (Maxwell branch).
#[test]
fn viscoelastic_extension_relaxes_at_a_hold() {
    let (ei, eiv, tau, l0) = (1.37e-3, 0.5e-3, 2.0, 0.05);
    let mut s = plain(
        TestKind::PureBending,
        "linear",
        &[("EI", ei)],
        vec![
            Step::Ramp { to: 0.5, rate: 5.0 },
            Step::Hold { duration_s: 30.0 },
        ],
        l0,
    );
    s.extension = Some(Extension {
        name: "viscoelasticity".into(),
        params: [("EI_v1".to_string(), eiv), ("tau_v1".to_string(), tau)].into(),
    });
    let o = crate::generate(&s).unwrap();
    let (t, r) = (&o.truth.time_s, &o.truth.response_si);
    let k = 0.5 / l0;
    let i_hold = t.iter().position(|&x| x >= 0.1 - 1e-12).unwrap();
    assert!(
        r[i_hold] > ei * k * 1.2,
        "no overstress at the hold start: {}",
        r[i_hold]
    );
    let end = *r.last().unwrap();
    assert!(
        (end / (ei * k) - 1.0).abs() < 1e-3,
        "relaxed to {end}, elastic {}",
        ei * k
    );
    // Monotone relaxation during the hold.
    assert!(r[i_hold..].windows(2).all(|w| w[1] <= w[0] + 1e-15));
}

/// `support_friction` (three-point): Coulomb friction at the supports stiffens loading and softens
/// unloading, opening a loop in a linear elastic rod that has none without friction.
#[test]
fn support_friction_opens_a_loop_in_three_point_bending() {
    let steps = vec![Step::Cycles {
        lower: 0.0,
        upper: 4e-3,
        rate: 1e-3,
        count: 1,
        dwell_s: 0.0,
    }];
    let s0 = plain(
        TestKind::ThreePoint,
        "linear",
        &[("EI", 1.37e-3)],
        steps.clone(),
        0.056,
    );
    let mut s1 = s0.clone();
    s1.rig.support_friction = 0.3;
    let (o0, o1) = (crate::generate(&s0).unwrap(), crate::generate(&s1).unwrap());
    let (c, r0, r1) = (
        &o0.truth.control_specimen_si,
        &o0.truth.response_si,
        &o1.truth.response_si,
    );
    let up = c.iter().position(|&x| (x - 2e-3).abs() < 1e-9).unwrap();
    let down = c.iter().rposition(|&x| (x - 2e-3).abs() < 1e-9).unwrap();
    assert!(
        (r0[up] - r0[down]).abs() < 1e-6 * r0[up],
        "frictionless loop {} {}",
        r0[up],
        r0[down]
    );
    assert!(
        r1[up] > r0[up] * 1.01,
        "friction loading {} vs {}",
        r1[up],
        r0[up]
    );
    assert!(
        r1[down] < r0[down] * 0.99,
        "friction unloading {} vs {}",
        r1[down],
        r0[down]
    );
}

/// A spec survives TOML (the form `cablab synth` and recipes use), layouts and steps by name.
#[test]
fn spec_round_trips_through_toml() {
    let mut s = spec(TestKind::Tension, Layout::Mts793Dat);
    s.extension = Some(Extension {
        name: "viscoelasticity".into(),
        params: [("EA_v1".to_string(), 1e4)].into(),
    });
    s.rig.support_friction = 0.1;
    let text = toml::to_string(&s).unwrap();
    assert!(
        text.contains("layout = \"mts793_dat\"") && text.contains("step = \"response_cycles\""),
        "{text}"
    );
    let back: SynthSpec = toml::from_str(&text).unwrap();
    assert_eq!(back, s);
    assert!(toml::from_str::<SynthSpec>(&text.replace("sample_rate_hz", "sample_rate")).is_err());
}
