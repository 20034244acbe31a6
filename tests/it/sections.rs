//! Flat (rectangular) sections b × h (issue 12): the moduli from A = b h, I = b h³/12 and
//! Saint-Venant's J_t, given as flags, as `[[specimen]]` keys or by the file's own metadata,
//! checked on generated linear logs whose modulus is known.

use crate::common::cablab;
use crate::real_exports::{json, notes, stiffness, temp_file, within};
use serde_json::Value;

/// Beam of the MTS three-point layout in EXPECTED.md: PLA, b = 11.86 mm, h = 2.937 mm, span
/// 40.28 mm, E = 2.05 GPa: I = b h³/12 = 25.04 mm⁴, F = 48 E I w / L³ (eq. (3)), linear with a
/// small deterministic ripple.
const B: f64 = 11.86e-3;
const H: f64 = 2.937e-3;
const SPAN: f64 = 40.28e-3;
const E_PLA: f64 = 2.05e9;

fn beam_log(header: &str) -> String {
    let i = B * H.powi(3) / 12.0;
    let k = 48.0 * E_PLA * i / SPAN.powi(3);
    let mut s = String::from(header);
    s += "Time (s),Deflection (mm),Force (N)\n";
    for n in 0..=300 {
        let w = 0.3e-3 * n as f64 / 300.0; // w/L ≤ 0.75 %: eq. (3) holds
        let f = k * w + 0.005 * ((n * 7919 % 13) as f64 - 6.0);
        s += &format!("{},{},{f}\n", 0.05 * n as f64, w * 1e3);
    }
    s
}

/// Three-point bending of a flat beam: E = (EI)/(b h³/12) with the flags, within 0.5 %; the
/// note names I and the bending axis. A diameter and a flat section together are refused
/// (exit 2), and so is a width without a thickness.
#[test]
fn a_flat_beam_in_three_point_bending_gets_e_from_b_h_cubed_over_12() {
    let (_d, p) = temp_file("beam.csv", &beam_log(""));
    let base = [
        "analyze",
        &p,
        "--kind",
        "three-point",
        "--length-mm",
        "40.28",
    ];
    let mut args = base.to_vec();
    args.extend(["--width-mm", "11.86", "--thickness-mm", "2.937"]);
    let a = json(&args);
    let i = B * H.powi(3) / 12.0;
    let ei = stiffness(&a);
    assert!(within(ei, E_PLA * i, 0.005), "EI {ei:e}");
    let e = a["modulus_pa"].as_f64().unwrap();
    assert!(within(e, E_PLA, 0.005), "E {e:e}");
    assert!((e - ei / i).abs() <= 1e-9 * e, "E = EI/I exactly");
    let w = notes(&a);
    assert!(
        w.iter()
            .any(|w| w.contains("flat section 11.8600 × 2.9370 mm")
                && w.contains("I = b h³/12 = 25.0")
                && w.contains("bending about the width")),
        "{w:?}"
    );
    for bad in [
        &[
            "--width-mm",
            "11.86",
            "--thickness-mm",
            "2.937",
            "--diameter-mm",
            "3",
        ][..],
        &["--width-mm", "11.86"][..],
    ] {
        let out = cablab().args(base).args(bad).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{bad:?}");
    }
}

/// Torsion of a 10 × 2 mm aluminium strip, E = 70 GPa, ν = 0.3 (G = 26.9 GPa): (GJ) = G J_t
/// with Saint-Venant's J_t = 0.2913 b h³ = 23.3 mm⁴ (b/h = 5; Timoshenko & Goodier § 109:
/// k₁ = 0.291). The modulus 2(1+ν)(GJ)/J_t is E within 0.5 % from the flags and from the
/// file's own `Specimen thickness`/`Specimen width`; the polar moment b h (b² + h²)/12 = 173 mm⁴
/// would give E 7.4× too low.
#[test]
fn a_flat_strip_in_torsion_uses_saint_venants_torsion_constant() {
    let (b, h, l0, e, nu) = (10e-3, 2e-3, 0.1, 70e9, 0.3);
    let j_t = 0.2913 * b * h * h * h;
    let gj = e / (2.0 * (1.0 + nu)) * j_t;
    let body = |meta: &str| {
        let mut s = String::from(meta);
        s += "Time (s),Angle (deg),Torque (N·m)\n";
        for n in 0..=200 {
            let theta = 0.2 * n as f64 / 200.0; // rad
            let t = gj * theta / l0 + 1e-4 * ((n * 7919 % 11) as f64 - 5.0);
            s += &format!("{},{},{t}\n", n as f64, theta.to_degrees());
        }
        s
    };
    let (_d, p) = temp_file("strip.csv", &body(""));
    let base = [
        "analyze",
        "--kind",
        "torsion",
        "--length-mm",
        "100",
        "--nu",
        "0.3",
    ];
    let flags = ["--width-mm", "10", "--thickness-mm", "2"];
    let a = json(&[&base[..], &[p.as_str()], &flags[..]].concat());
    let got = a["modulus_pa"].as_f64().unwrap();
    assert!(within(got, e, 0.005), "E {got:e}");
    let polar = b * h * (b * b + h * h) / 12.0;
    assert!(got / (2.0 * (1.0 + nu) * gj / polar) > 7.0);
    assert!(
        notes(&a)
            .iter()
            .any(|w| w.contains("Saint-Venant's torsion constant of the rectangle J_t = 23.3")),
        "{:?}",
        notes(&a)
    );
    // The same section stated in the file: no flag needed, and the note says where it came from.
    let (_d2, p2) = temp_file(
        "strip_meta.csv",
        &body("Specimen thickness: 2 mm\nSpecimen width: 10 mm\n"),
    );
    let m = json(&[&base[..], &[p2.as_str()]].concat());
    let got = m["modulus_pa"].as_f64().unwrap();
    assert!(within(got, e, 0.005), "E from metadata {got:e}");
    assert!(
        notes(&m)
            .iter()
            .any(|w| w.contains("flat section 10.0000 × 2.0000 mm (width × thickness, from the metadata's thickness and width)")),
        "{:?}",
        notes(&m)
    );
}

/// The `[[specimen]]` keys `width_mm`/`thickness_mm` through a whole campaign: the summary's
/// modulus is the analytical E of the beam, and result.json and the report state the section.
#[test]
fn a_pipeline_with_a_flat_specimen_type_reports_the_beams_modulus() {
    let d = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(d.path().join("raw_data")).unwrap();
    std::fs::create_dir_all(d.path().join("pipelines")).unwrap();
    std::fs::write(d.path().join("raw_data/beam_1.csv"), beam_log("")).unwrap();
    std::fs::write(
        d.path().join("pipelines/flat.toml"),
        r#"[campaign]
name = "flat"
[[specimen]]
label = "PLA beam"
width_mm = 11.86
thickness_mm = 2.937
[[input]]
glob = "raw_data/beam_*.csv"
specimen = "PLA beam"
kind = "three_point"
length_mm = 40.28
[diagnosis]
enabled = false
"#,
    )
    .unwrap();
    let o = assert_cmd::Command::cargo_bin("cablab")
        .unwrap()
        .current_dir(d.path())
        .env("CI", "1")
        .args(["run", "pipelines/flat.toml"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: Value =
        serde_json::from_slice(&std::fs::read(d.path().join("reports/flat/summary.json")).unwrap())
            .unwrap();
    let t = &s["tests"][0];
    let e = t["modulus_pa"].as_f64().unwrap();
    assert!(within(e, E_PLA, 0.005), "E {e:e}");
    assert!(t.get("needs").is_none(), "{t}");
    // One test: its folder under tests/ (named by the id's slug) holds result.json.
    let dir = std::fs::read_dir(d.path().join("reports/flat/tests"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let r: Value =
        serde_json::from_slice(&std::fs::read(dir.join("result.json")).unwrap()).unwrap();
    let f = &r["geometry"]["flat_section"];
    assert!(within(f["width_m"].as_f64().unwrap(), B, 1e-12), "{f}");
    assert!(within(f["thickness_m"].as_f64().unwrap(), H, 1e-12), "{f}");
    // The report's test page gives the section the moduli use, not "diameter: not stated (the
    // moduli need it)" beside a modulus.
    let html = std::fs::read_to_string(d.path().join("reports/flat/index.html")).unwrap();
    assert!(
        html.contains("section</dt><dd>11.86 × 2.937 mm (width × thickness)"),
        "{}",
        &html[html.find("<dl").unwrap_or(0)..][..2000.min(html.len())]
    );
    assert!(!html.contains("the moduli need it"));
}

/// A torsional extensometer's surface shear strain on a thin strip (50 × 1 mm): Saint-Venant's
/// largest shear strain is γ = c θ / l₀ with c the thickness (the series term is 10⁻³⁴ here),
/// so the flat section turns γ into the twist θ = γ l₀ / c and (GJ) = T l₀ / θ.
#[test]
fn a_shear_strain_on_a_thin_strip_becomes_the_twist() {
    let (gj, l0, c) = (0.5, 0.08, 1e-3);
    let mut s = String::from("Time (s),Shear Strain (deg),Torque (N·m)\n");
    for n in 0..=200 {
        let theta = 0.5 * n as f64 / 200.0; // rad
        let t = gj * theta / l0 + 1e-4 * ((n * 7919 % 11) as f64 - 5.0);
        s += &format!("{},{},{t}\n", n as f64, (c * theta / l0).to_degrees());
    }
    let (_d, p) = temp_file("thin.csv", &s);
    let a = json(&[
        "analyze",
        &p,
        "--kind",
        "torsion",
        "--length-mm",
        "80",
        "--width-mm",
        "50",
        "--thickness-mm",
        "1",
    ]);
    assert!(within(stiffness(&a), gj, 0.005), "{:e}", stiffness(&a));
    assert!(
        notes(&a)
            .iter()
            .any(|w| w.contains("largest surface shear strain of the flat section")),
        "{:?}",
        notes(&a)
    );
}
