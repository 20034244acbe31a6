//! Speed of the rod solver: the cyclic elastoplastic three-point simulation (the calibration's
//! inner loop), its cost per step against the element count, and the static cantilever of
//! SPEC.md's reference table (to compare with rod codes that reach statics by damped dynamics).
//!
//! Run: `cargo bench -p cablab-rod`. Does not assert anything; the tests check the physics.

use cablab_core::TestKind;
use cablab_laws::{build, Law, LinearElastic, SectionStiffness};
use cablab_rod::scenarios::cantilever_tip_load;
use cablab_rod::spatial::{Controls, SpatialRod};
use cablab_rod::{simulate_history, TestSetup};
use nalgebra::Vector3;
use std::collections::BTreeMap;

fn main() {
    divan::main();
}

/// The chapter's cable in three-point bending (span 56 mm), elastoplastic with isotropic hardening.
fn cable_law() -> Box<dyn Law> {
    let p: BTreeMap<String, f64> = [("EI", 1.37e-3), ("M_y", 4e-3), ("HI", 1e-4)]
        .iter()
        .map(|(k, v)| (k.to_string(), *v))
        .collect();
    build(TestKind::ThreePoint, "elastoplastic", &p).expect("law")
}

/// Two triangular cycles 0 → 6 mm → 0 in `steps` samples (the chapter's plastic protocol).
fn history(steps: usize) -> (Vec<f64>, Vec<f64>) {
    let w_max = 0.006;
    let c = (1..=steps)
        .map(|i| {
            let phase = (i as f64 / steps as f64 * 4.0) % 2.0;
            w_max * if phase <= 1.0 { phase } else { 2.0 - phase }
        })
        .collect();
    let t = (1..=steps).map(|i| i as f64 * 0.1).collect();
    (c, t)
}

/// 1,000 load steps of the cyclic elastoplastic three-point test, at 25/50/100/200 elements
/// (half model). The brief's target: under 100 ms at 100 elements.
#[divan::bench(args = [25, 50, 100, 200], sample_count = 10)]
fn three_point_cyclic_1000_steps(bencher: divan::Bencher, elements: usize) {
    let law = cable_law();
    let (c, t) = history(1000);
    let mut setup = TestSetup::new(TestKind::ThreePoint, 0.056);
    setup.elements = elements;
    bencher.bench(|| {
        simulate_history(&setup, law.as_ref(), divan::black_box(&c), &t).expect("converges")
    });
}

/// Static cantilever, α = PL²/EI = 10 (the hardest row of the table), 100 elements, 10 Newton
/// load steps.
#[divan::bench(sample_count = 20)]
fn cantilever_alpha10_100_elements(bencher: divan::Bencher) {
    let mut s = SectionStiffness::CHAPTER_CABLE;
    s.ei_nm2 = 1.0;
    s.ea_n = 1e7;
    s.ga_n = 1e7;
    let law = LinearElastic::new(s);
    bencher.bench(|| {
        cantilever_tip_load(&law, 1.0, 100, divan::black_box(10.0), 10).expect("converges")
    });
}

/// The same cantilever (α = 10, 100 elements, 10 load steps) through the 3D rod (quaternions,
/// 6×6 blocks, analytic consistent tangent).
#[divan::bench(sample_count = 10)]
fn cantilever_alpha10_100_elements_3d(bencher: divan::Bencher) {
    let mut s = SectionStiffness::CHAPTER_CABLE;
    s.ei_nm2 = 1.0;
    s.gj_nm2 = 1.0;
    s.ea_n = 1e7;
    s.ga_n = 1e7;
    let law = LinearElastic::new(s);
    bencher.bench(|| {
        let mut rod = SpatialRod::straight(&law, 1.0, 100).expect("rod");
        rod.clamp(0);
        let tip = rod.nodes() - 1;
        let mut c = Controls::new(rod.nodes());
        c.force[tip] = Vector3::new(-divan::black_box(10.0), 0.0, 0.0);
        rod.ramp(&c, 10).expect("converges");
        rod.x[tip]
    });
}
