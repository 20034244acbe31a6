//! Helpers shared by the integration tests.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The project root (where Cargo.toml is).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `../shared/real_logs` when present (it is beside the repository on lab machines and in CI).
pub fn real_logs() -> Option<PathBuf> {
    let p = root().join("../shared/real_logs");
    p.is_dir().then_some(p)
}

/// A `cablab` command running in the project root.
pub fn cablab() -> assert_cmd::Command {
    let mut c = assert_cmd::Command::cargo_bin("cablab").expect("the cablab binary is built");
    c.current_dir(root());
    c
}

/// Copy the folder `from` (recursively) to `to`.
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let p = e.path();
        if p.is_dir() {
            copy_dir(&p, &to.join(e.file_name()));
        } else {
            std::fs::copy(&p, to.join(e.file_name())).unwrap();
        }
    }
}

/// Every file below `dir` (relative path → bytes).
pub fn tree(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.insert(
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    out
}

/// A Shimadzu Trapezium export of three specimens side by side, written as the real one is
/// (raballito/tensile_test_analyzer's flexure example, GPL, so a twin): a row naming each
/// specimen on every third cell (`Brut 1`, `Recuit`, `Etiré test 250°C`), `Temps,Force,
/// Course_Traverse` repeated, their units repeated, then rows of three cells per specimen
/// (`lens` rows each, empty cells below a shorter one's end); specimen j's force is `ks[j]` N/mm
/// times the punch travel, which rises 0.4 µm a row.
pub fn trapezium_twin(ks: [f64; 3], lens: [usize; 3]) -> String {
    let mut s = String::from("Brut 1,,,Recuit,,,Etiré test 250°C,,\n");
    s += &["Temps,Force,Course_Traverse"; 3].join(",");
    s += "\n";
    s += &["sec,N,mm"; 3].join(",");
    s += "\n";
    for i in 0..lens.iter().copied().max().unwrap_or(0) {
        let cells: Vec<String> = (0..3)
            .map(|j| {
                if i < lens[j] {
                    let w = 4e-4 * i as f64; // mm
                    format!("{:.2},{:.5},{w:.5}", 0.01 * i as f64, ks[j] * w)
                } else {
                    ",,".to_string()
                }
            })
            .collect();
        s += &cells.join(",");
        s += "\n";
    }
    s
}
