//! Helpers shared by the integration tests.

use std::path::PathBuf;

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
