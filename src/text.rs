//! Plain-text renderings for people at a terminal (the JSON forms are the contract; these are
//! not and may change).

use cablab_measure::Analysis;
use std::fmt::Write;

/// A short, readable summary of one characterised test; `nu`: the Poisson ratio the torsion
/// modulus was taken with.
pub fn analysis_text(file: &str, an: &Analysis, nu: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{file}: {} test, behaviour {}{}",
        an.kind,
        an.behaviour_class,
        match an.behaviour.as_str() {
            d if d == an.behaviour_class => String::new(),
            "broken" => " (broken)".to_string(),
            d => format!(" ({})", d.replace('_', " ")),
        }
    );
    match &an.stiffness {
        Some(st) => {
            let _ = writeln!(
                s,
                "  stiffness   {:.5e} {}  (95% CI {:.5e} .. {:.5e}; fit window {:.4e} .. {:.4e} {}{})",
                st.value,
                st.unit,
                st.ci95[0],
                st.ci95[1],
                st.window[0],
                st.window[1],
                // A strain's unit is "1": the window is named by its variable instead.
                if st.window_unit == "1" {
                    "(strain)"
                } else {
                    st.window_unit
                },
                if st.window_automatic { ", automatic" } else { "" }
            );
        }
        None => {
            let _ = writeln!(
                s,
                "  stiffness   -  ({})",
                an.why_by_key.get("stiffness").map_or("", |w| w)
            );
        }
    }
    match an.modulus_pa {
        // Torsion gives the shear modulus G = (GJ)/J; the modulus is the chapter's E_tor, the
        // Young's modulus it implies for an isotropic section, which is not what a torsion
        // user reads first: both are shown.
        Some(e) if an.kind == cablab_core::TestKind::Torsion => {
            let _ = writeln!(
                s,
                "  modulus     {:.1} MPa  (E_tor = 2 (1 + ν) G with ν = {nu}, --nu; the shear modulus G = {:.1} MPa)",
                e * 1e-6,
                e * 1e-6 / (2.0 * (1.0 + nu))
            );
        }
        Some(e) => {
            let _ = writeln!(s, "  modulus     {:.1} MPa", e * 1e-6);
        }
        None => {
            let _ = writeln!(
                s,
                "  modulus     -  ({})",
                an.why_by_key.get("modulus_pa").map_or("", |w| w)
            );
        }
    }
    // Units beside every number: the sectional control's (strain, 1/m, or m for a three-point
    // deflection), the response's and the stiffness'.
    let cu = match an.kind {
        cablab_core::TestKind::Tension => " (strain)",
        cablab_core::TestKind::ThreePoint => " m",
        cablab_core::TestKind::Torsion | cablab_core::TestKind::PureBending => " 1/m",
        cablab_core::TestKind::Unknown => "",
    };
    let ru = an.kind.response_unit();
    let su = an
        .stiffness
        .as_ref()
        .map_or(an.kind.stiffness_unit().to_string(), |st| {
            st.unit.to_string()
        });
    match &an.yield_point {
        Some(y) => {
            let _ = writeln!(
                s,
                "  yield       control {:.5e}{cu}, response {:.5e} {ru}",
                y.control, y.response
            );
        }
        None => {
            let _ = writeln!(
                s,
                "  yield       -  ({})",
                an.why_by_key.get("yield").map_or("", |w| w)
            );
        }
    }
    if let Some(p) = &an.piecewise {
        let _ = writeln!(
            s,
            "  threshold   control {:.5e}{cu}, response {:.5e} {ru}",
            p.threshold_control, p.threshold_response
        );
    }
    for c in &an.cycles {
        let f = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.4e}"));
        // A negative loop area is never a dissipated energy: said next to the number.
        let sign_note = match (c.loop_area, c.loop_area_resolved) {
            (Some(a), Some(false)) if a < 0.0 => " (negative, within resolution: 0)",
            (Some(a), _) if a < 0.0 => " (negative: not a dissipated energy, see warning)",
            _ => "",
        };
        let _ = writeln!(
            s,
            "  cycle {:>2}    loop area {} J{sign_note}, residual {}{}, unloading stiffness {}{}",
            c.index,
            f(c.loop_area),
            f(c.residual),
            match (c.residual.is_some(), c.residual_extrapolated) {
                (true, true) => format!("{cu} (extrapolated to zero load along the unloading)"),
                (true, false) => cu.to_string(),
                _ => String::new(),
            },
            f(c.unloading_stiffness),
            if c.unloading_stiffness.is_some() {
                format!(" {su}")
            } else {
                String::new()
            }
        );
    }
    for w in &an.warnings {
        let _ = writeln!(s, "  warning: {w}");
    }
    for n in &an.notes {
        let _ = writeln!(s, "  note: {n}");
    }
    s
}
