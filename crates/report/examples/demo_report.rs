//! Writes the demo report (synthetic data shaped like the chapter's tests) to the path given as
//! the first argument, default `demo_report.html`, to look at in a browser:
//! `cargo run -p cablab-report --example demo_report -- /tmp/demo.html`.

#[path = "../tests/it/fixtures.rs"]
mod fixtures;

fn main() -> std::io::Result<()> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "demo_report.html".into());
    let hostile = std::env::args().any(|a| a == "--hostile");
    std::fs::write(
        &path,
        cablab_report::render_html(&fixtures::demo_doc(hostile)),
    )?;
    eprintln!("wrote {path}");
    Ok(())
}
