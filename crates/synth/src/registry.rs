//! Builds the truth model of a spec from the law registry of `cablab-laws` (baseline law plus an
//! optional extension, composed the registry's way) and, for three-point bending, the rod solver
//! of `cablab-rod`. The only place this crate names sibling APIs beyond the `Law` trait.

use std::collections::BTreeMap;

use cablab_core::TestKind;
use cablab_laws::Law;
use cablab_rod::{simulate_history, TestSetup};

use crate::error::SynthError;
use crate::spec::SynthSpec;
use crate::truth::{SectionalTruth, Truth};

/// The registry name and parameter map of the spec's law: the baseline alone, or the extension
/// layered on it (`elastoplastic` + `kinematic_hardening` → `kinematic_hardening`;
/// `linear` + `viscoelasticity` → `linear+viscoelasticity`), with both parameter maps merged.
pub fn registry_law(spec: &SynthSpec) -> Result<(String, BTreeMap<String, f64>), SynthError> {
    let mut params = spec.params.clone();
    let Some(ext) = &spec.extension else {
        return Ok((spec.law.clone(), params));
    };
    for (k, v) in &ext.params {
        if params.insert(k.clone(), *v).is_some() {
            return Err(SynthError::InvalidSpec {
                field: format!("extension.params.{k}"),
                why: "also given in params".into(),
            });
        }
    }
    let base = spec.law.trim().to_ascii_lowercase();
    let name = if base == "elastoplastic" || base == "plasticity" {
        ext.name.clone()
    } else {
        format!("{}+{}", spec.law.trim(), ext.name.trim())
    };
    Ok((name, params))
}

/// The law of the spec, from the registry.
pub fn build_law(spec: &SynthSpec) -> Result<Box<dyn Law>, SynthError> {
    let (name, params) = registry_law(spec)?;
    cablab_laws::build(spec.kind, &name, &params).map_err(|e| SynthError::Truth(e.to_string()))
}

/// Three-point bending through the rod solver: a replay of the control history with the rig's
/// support friction and roller radii.
#[derive(Debug)]
pub struct RodTruth {
    law: Box<dyn Law>,
    setup: TestSetup,
}

impl Truth for RodTruth {
    fn respond(&self, control: &[f64], time_s: &[f64]) -> Result<Vec<f64>, SynthError> {
        simulate_history(&self.setup, self.law.as_ref(), control, time_s)
            .map(|c| c.response)
            .map_err(|e| SynthError::Truth(e.to_string()))
    }
}

/// The truth model of `spec`.
pub fn build_truth(spec: &SynthSpec) -> Result<Box<dyn Truth>, SynthError> {
    let law = build_law(spec)?;
    let l0 = spec.specimen.free_length_m.unwrap_or(0.0);
    match spec.kind {
        TestKind::ThreePoint => {
            let mut setup = TestSetup::new(TestKind::ThreePoint, l0);
            setup.support_friction = spec.rig.support_friction;
            if let Some(r) = spec.rig.roller_radius_m {
                setup.set_contact_radii(r, r, spec.specimen.diameter_m);
            }
            Ok(Box::new(RodTruth { law, setup }))
        }
        kind => Ok(Box::new(SectionalTruth::new(kind, law, l0)?)),
    }
}
