//! Debug probe (temporary): machine-compliance forward model on a three-point case.
use cablab_core::{Effect, TestKind};
use cablab_diagnose::blind::generate_case_at;
use cablab_diagnose::calibrate::Forward;
use cablab_diagnose::model::ModelForward;
use cablab_diagnose::registry::{Registry, Rod};
use cablab_diagnose::ModelSpec;
use cablab_synth::Layout;
fn main() {
    let case = generate_case_at(
        TestKind::ThreePoint,
        Effect::None,
        0.003,
        1,
        Layout::TestXpert,
        10.0,
    )
    .unwrap();
    let reg = Registry;
    let rod = Rod::default();
    let m = ModelSpec::law("elastoplastic").with(Effect::MachineCompliance);
    let fwd = ModelForward::new(&case.tests, &m, &reg, Some(&rod)).unwrap();
    for s in fwd.specs() {
        println!("{:?}", s);
    }
    let mut out = vec![0.0; case.tests[0].control.len()];
    for frac in [0.0, 0.1, 0.2, 0.5, 0.9] {
        let p: Vec<f64> = fwd
            .specs()
            .iter()
            .map(|s| {
                if s.name == "compliance" {
                    s.at_fraction(frac)
                } else {
                    s.initial
                }
            })
            .collect();
        println!("C frac {frac}: {:?}", fwd.simulate(&p, 0, &mut out));
    }
}
