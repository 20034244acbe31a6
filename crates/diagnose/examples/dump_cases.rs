//! Temporary: write the virtual-lab files of blind cases whose name contains a pattern.
use cablab_core::TestKind;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let pat = &args[1];
    let out = &args[2];
    let (cases, _) = cablab_diagnose::blind::standard_matrix(
        &[TestKind::Tension, TestKind::Torsion, TestKind::PureBending],
        &[0.003, 0.01],
        &[1, 2, 3],
    );
    for c in cases.iter().filter(|c| c.name.contains(pat.as_str())) {
        for (name, bytes) in &c.files {
            let p = format!("{out}/{}_{}", c.name.replace(['/', '%'], "_"), name.replace('/', "_"));
            std::fs::write(&p, bytes).unwrap();
            println!("{p}");
        }
    }
}
