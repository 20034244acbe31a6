//! Temporary: in-memory blind cases diagnosed with and without the zero-offset removal.
use cablab_core::TestKind;
use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let pat = &args[1];
    let (cases, _) = cablab_diagnose::blind::standard_matrix(
        &[TestKind::Tension, TestKind::Torsion, TestKind::PureBending],
        &[0.003, 0.01],
        &[1, 2, 3],
    );
    for c in cases.iter().filter(|c| c.name.contains(pat.as_str())) {
        let mut z = c.tests.clone();
        let mut off = vec![];
        for t in z.iter_mut() {
            off.push(cablab_measure::zero_offsets(&mut t.control, &mut t.response));
        }
        for (label, tests) in [("raw", &c.tests), ("zeroed", &z)] {
            let d = diagnose(Context::project(), tests, &DiagnoseOptions::default()).unwrap();
            let e = &d.effects[0];
            println!(
                "{} {label}: verdict {} g0 {:.3} best {} {:.3} offsets {:?}",
                c.name,
                d.verdict.effect,
                d.baseline.gap_heldout_rel / d.verdict.noise_rel,
                e.effect,
                e.gap_after_noise,
                off
            );
        }
    }
}
