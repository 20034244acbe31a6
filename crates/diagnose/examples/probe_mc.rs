//! Debug probe (temporary): machine-compliance fixed point on a three-point case.
use cablab_core::{Effect, TestKind};
use cablab_diagnose::blind::generate_case_at;
use cablab_diagnose::model::RodSimulator;
use cablab_diagnose::registry::Rod;
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
    let t = &case.tests[0];
    let mut p = std::collections::BTreeMap::new();
    p.insert("EI".to_string(), 1.37e-3);
    p.insert("M_y".to_string(), 0.008);
    p.insert("HI".to_string(), 5e-5);
    let law = cablab_laws::build(TestKind::ThreePoint, "elastoplastic", &p).unwrap();
    let rod = Rod::default();
    let c = 5e-4;
    let k = 374.0;
    let relax = 1.0 / (1.0 + c * k);
    let mut w = t.control.clone();
    let mut out = vec![0.0; w.len()];
    for it in 0..10 {
        rod.simulate(t, law.as_ref(), &w, 0.0, &mut out).unwrap();
        let mut worst = (0.0f64, 0);
        for i in 0..w.len() {
            let g = t.control[i] - c * out[i] - w[i];
            if g.abs() > worst.0 {
                worst = (g.abs(), i);
            }
            w[i] += relax * g;
        }
        println!(
            "it {it}: max change {:.3e} at {} (u {:.4e}, F {:.4e})",
            worst.0, worst.1, t.control[worst.1], out[worst.1]
        );
    }
}
