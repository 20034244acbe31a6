//! Integration tests of cablab-report: the SVGs are well-formed XML and carry the expected
//! series, strings from inputs are escaped, output is deterministic, and the HTML report shows
//! in headless Chromium (skipped with a visible message where no browser is installed).

mod browser;
mod fixtures;
mod html;
mod svg;
mod words;
