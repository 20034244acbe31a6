//! Renders the demo report in headless Chromium (when installed) and checks what it shows.

use crate::fixtures::demo_doc;
use cablab_report::render_html;
use std::path::PathBuf;
use std::process::Command;

/// The first Chromium-like browser found: `/usr/bin/chromium`, else on PATH.
fn find_browser() -> Option<PathBuf> {
    let fixed = PathBuf::from("/usr/bin/chromium");
    if fixed.is_file() {
        return Some(fixed);
    }
    let path = std::env::var_os("PATH")?;
    for dir in std::env::split_paths(&path) {
        for name in [
            "chromium",
            "chromium-browser",
            "google-chrome",
            "google-chrome-stable",
        ] {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

fn chromium(
    browser: &PathBuf,
    profile: &std::path::Path,
    extra: &[&str],
    url: &str,
) -> std::process::Output {
    Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-dev-shm-usage",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(url)
        .output()
        .expect("run the browser")
}

#[test]
fn report_shows_in_headless_chromium() {
    let Some(browser) = find_browser() else {
        println!(
            "SKIPPED: no chromium (install it, e.g. `apt-get install chromium`, to run this test)"
        );
        eprintln!("SKIPPED: no chromium");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("report.html");
    std::fs::write(&page, render_html(&demo_doc(true))).unwrap();
    let url = format!("file://{}", page.display());
    let profile = dir.path().join("profile");

    let out = chromium(&browser, &profile, &["--dump-dom"], &url);
    assert!(
        out.status.success(),
        "chromium failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let dom = String::from_utf8_lossy(&out.stdout);
    // The title, the table, every section and every SVG made it into the live DOM …
    assert!(
        dom.contains(
            "<h1 id=\"top\">Demo campaign &lt;script&gt;alert(1)&lt;/script&gt; &amp; co</h1>"
        ),
        "{dom}"
    );
    assert!(dom.contains("<td class=\"num\">12900</td>"));
    assert_eq!(dom.matches("<svg ").count(), 7);
    assert_eq!(dom.matches("<section ").count(), 4);
    assert!(dom.contains("elongation Δl [µm]"));
    // … and the hostile strings stayed text: no script element was created.
    assert!(!dom.contains("<script"));

    let shot = dir.path().join("shot.png");
    let out = chromium(
        &browser,
        &profile,
        &[
            "--window-size=820,2400",
            &format!("--screenshot={}", shot.display()),
        ],
        &url,
    );
    assert!(
        out.status.success(),
        "screenshot failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let png = std::fs::read(&shot).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    // A page with text, tables and plots compresses far worse than a blank one (~10 kB).
    assert!(
        png.len() > 60_000,
        "screenshot suspiciously small: {} bytes",
        png.len()
    );
}
