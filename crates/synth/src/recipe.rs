//! Campaign recipes: a TOML list of test series, each expanded into one [`SynthSpec`] per
//! specimen with specimen-to-specimen scatter of the law parameters drawn under the recipe seed,
//! and written to a folder. This is the only module of the crate that touches files
//! ([`run_recipe`]); [`expand_recipe`] is pure.
//!
//! Scatter: for a series of `count` specimens and a relative standard deviation `s` of parameter
//! `p`, specimen k gets `p · (1 + s · (z_k − z̄))` with z_k standard normal draws; centring on the
//! series mean makes the series mean equal the nominal value (the chapter's tables report means).

use std::collections::BTreeMap;
use std::path::Path;

use cablab_core::{Specimen, TestKind};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use crate::error::SynthError;
use crate::spec::{Artefacts, Extension, Layout, Protocol, Rig, SynthSpec};

/// A campaign recipe.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Recipe {
    /// Master seed: every scatter draw and every noise seed derives from it.
    pub seed: u64,
    /// The test series.
    #[serde(rename = "series")]
    pub series: Vec<RecipeEntry>,
}

/// One test series: `count` specimens of one type in one kind of test.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecipeEntry {
    /// Series name; files are named `<name>_<k>.<ext>` (k from 1).
    pub name: String,
    /// Sub-folder of the output folder the series is written to (e.g. the specimen type
    /// `cable`); one plain name, no path separators. `None`: the output folder itself.
    #[serde(default)]
    pub folder: Option<String>,
    /// Number of specimens (≥ 1).
    pub count: u32,
    /// Label prefix; specimen labels are `<label>-<k>`.
    pub label: String,
    /// Kind of test.
    pub kind: TestKind,
    /// Diameter, m.
    pub diameter_m: f64,
    /// Free length or support span, m.
    pub free_length_m: f64,
    /// Baseline law (registry name).
    pub law: String,
    /// Nominal baseline parameters, SI.
    pub params: BTreeMap<String, f64>,
    /// Relative standard deviation of each scattered parameter (e.g. `{ EA = 0.015 }`).
    #[serde(default)]
    pub scatter: BTreeMap<String, f64>,
    /// Optional extension law.
    #[serde(default)]
    pub extension: Option<Extension>,
    /// Rig options of the rod model.
    #[serde(default)]
    pub rig: Rig,
    /// Machine program.
    pub protocol: Protocol,
    /// Rig artefacts.
    #[serde(default)]
    pub artefacts: Artefacts,
    /// Layouts, used in turn over the specimens (specimen k gets `layouts[(k-1) % len]`).
    pub layouts: Vec<Layout>,
    /// Logger sampling rate, Hz.
    pub sample_rate_hz: f64,
}

/// SplitMix64: derives independent seeds from the master seed.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Parses a recipe from TOML text.
pub fn parse_recipe(text: &str) -> Result<Recipe, SynthError> {
    toml::from_str(text).map_err(|e| SynthError::Recipe(e.to_string()))
}

/// Expands a recipe into one spec per specimen, in series order. Pure and deterministic.
pub fn expand_recipe(recipe: &Recipe) -> Result<Vec<SynthSpec>, SynthError> {
    let mut out = Vec::new();
    for (ei, e) in recipe.series.iter().enumerate() {
        let field = |f: &str| format!("series[{ei}] ({}).{f}", e.name);
        if let Some(f) = &e.folder {
            if f.is_empty()
                || !f
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
            {
                return Err(SynthError::Recipe(format!(
                    "{}: '{f}' must be one plain folder name (letters, digits, - and _)",
                    field("folder")
                )));
            }
        }
        if e.count == 0 {
            return Err(SynthError::Recipe(format!(
                "{}: must be >= 1",
                field("count")
            )));
        }
        if e.layouts.is_empty() {
            return Err(SynthError::Recipe(format!(
                "{}: list at least one layout",
                field("layouts")
            )));
        }
        for (p, s) in &e.scatter {
            if !e.params.contains_key(p) {
                return Err(SynthError::Recipe(format!(
                    "{}: '{p}' is not among the params",
                    field("scatter")
                )));
            }
            if !(s.is_finite() && *s >= 0.0 && *s < 0.3) {
                return Err(SynthError::Recipe(format!(
                    "{}: {p} = {s} must be in [0, 0.3)",
                    field("scatter")
                )));
            }
        }
        let series_seed = mix(recipe.seed ^ mix(ei as u64 + 1));
        let mut rng = ChaCha8Rng::seed_from_u64(series_seed);
        // One centred draw per scattered parameter (BTreeMap order: deterministic).
        let n = e.count as usize;
        let mut factors: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
        for (p, s) in &e.scatter {
            let z: Vec<f64> = (0..n)
                .map(|_| rng.sample::<f64, _>(StandardNormal))
                .collect();
            let mean = if n > 1 {
                z.iter().sum::<f64>() / n as f64
            } else {
                0.0
            };
            factors.insert(
                p.as_str(),
                z.iter().map(|zk| 1.0 + s * (zk - mean)).collect(),
            );
        }
        for k in 0..n {
            let mut params = e.params.clone();
            for (p, f) in &factors {
                if let Some(v) = params.get_mut(*p) {
                    *v *= f[k];
                }
            }
            let spec = SynthSpec {
                kind: e.kind,
                specimen: Specimen {
                    label: Some(format!("{}-{}", e.label, k + 1)),
                    diameter_m: Some(e.diameter_m),
                    free_length_m: Some(e.free_length_m),
                },
                law: e.law.clone(),
                params,
                extension: e.extension.clone(),
                rig: e.rig.clone(),
                protocol: e.protocol.clone(),
                artefacts: e.artefacts.clone(),
                layout: e.layouts[k % e.layouts.len()],
                seed: mix(series_seed ^ mix(k as u64 + 1)),
                sample_rate_hz: e.sample_rate_hz,
                file_stem: Some(match &e.folder {
                    Some(f) => format!("{f}/{}_{}", e.name, k + 1),
                    None => format!("{}_{}", e.name, k + 1),
                }),
                specimen_number: Some(k as u32 + 1),
            };
            spec.validate()
                .map_err(|err| SynthError::Recipe(format!("{}: {err}", field("spec"))))?;
            out.push(spec);
        }
    }
    Ok(out)
}

/// One written file of a recipe run, with the truth parameters behind it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WrittenFile {
    /// File name inside the output folder.
    pub file: String,
    /// Specimen label.
    pub label: String,
    /// Kind of test.
    pub kind: TestKind,
    /// Layout.
    pub layout: Layout,
    /// Noise seed (written as a string: TOML integers are signed 64-bit, seeds use all 64 bits).
    #[serde(with = "seed_text")]
    pub seed: u64,
    /// Baseline law.
    pub law: String,
    /// Baseline parameters of this specimen after scatter, SI.
    pub params: BTreeMap<String, f64>,
    /// Extension, if any.
    pub extension: Option<Extension>,
    /// Data rows written.
    pub rows: usize,
    /// Bytes written.
    pub bytes: usize,
}

/// Seeds as decimal strings in TOML (whose integers stop at i64::MAX); integers are accepted back.
mod seed_text {
    use serde::{de, Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &u64, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&v.to_string())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Seed {
            Text(String),
            Int(u64),
        }
        match Seed::deserialize(d)? {
            Seed::Text(t) => t.parse().map_err(de::Error::custom),
            Seed::Int(i) => Ok(i),
        }
    }
}

/// Runs a recipe: generates every file and writes it into `out_dir` (created if missing), plus
/// `TRUTH.toml` listing each file with the truth parameters behind it. Each file is written to a
/// temporary name and renamed, so a failure never leaves a half-written file.
pub fn run_recipe(recipe_toml: &str, out_dir: &Path) -> Result<Vec<WrittenFile>, SynthError> {
    let recipe = parse_recipe(recipe_toml)?;
    let specs = expand_recipe(&recipe)?;
    // Generate everything first: nothing is written unless the whole campaign succeeds.
    let mut outputs = Vec::with_capacity(specs.len());
    for s in &specs {
        let o = crate::generate(s).map_err(|e| {
            SynthError::Recipe(format!("{}: {e}", s.file_stem.clone().unwrap_or_default()))
        })?;
        outputs.push(o);
    }
    std::fs::create_dir_all(out_dir).map_err(|e| io(out_dir, e))?;
    let mut written = Vec::new();
    for (s, o) in specs.iter().zip(&outputs) {
        let path = out_dir.join(&o.file_name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| io(parent, e))?;
        }
        write_atomic(&path, &o.bytes)?;
        written.push(WrittenFile {
            file: o.file_name.clone(),
            label: s.specimen.label.clone().unwrap_or_default(),
            kind: s.kind,
            layout: s.layout,
            seed: s.seed,
            law: s.law.clone(),
            params: s.params.clone(),
            extension: s.extension.clone(),
            rows: o.measured.time_s.len(),
            bytes: o.bytes.len(),
        });
    }
    #[derive(Serialize)]
    struct TruthFile<'a> {
        note: &'a str,
        file: &'a [WrittenFile],
    }
    let truth = TruthFile {
        note: "Synthetic campaign written by cablab-synth from a recipe (see pipelines/); \
               params are the truth behind each file (SI).",
        file: &written,
    };
    let text = toml::to_string(&truth).map_err(|e| SynthError::Recipe(e.to_string()))?;
    write_atomic(&out_dir.join("TRUTH.toml"), text.as_bytes())?;
    Ok(written)
}

fn io(p: &Path, source: std::io::Error) -> SynthError {
    SynthError::Io {
        path: p.display().to_string(),
        source,
    }
}

/// The one atomic writer ([`cablab_core::output::write_atomic`]): temporary in the same folder,
/// fsync, rename; nothing left behind on failure.
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), SynthError> {
    cablab_core::output::write_atomic(path, bytes).map_err(|e| io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    const DEMO: &str = include_str!("../../../pipelines/demo_recipe.toml");

    /// The demo recipe parses, every series has ≥ 3 specimens, the three layouts all occur for
    /// every kind, and the centred scatter keeps each series' mean at the nominal value.
    #[test]
    fn demo_recipe_expands_with_centred_scatter() {
        let r = parse_recipe(DEMO).unwrap();
        let specs = expand_recipe(&r).unwrap();
        assert!(specs.len() >= 30);
        for e in &r.series {
            assert!(e.count >= 3, "{}", e.name);
            let stem = match &e.folder {
                Some(f) => format!("{f}/{}_", e.name),
                None => format!("{}_", e.name),
            };
            let mine: Vec<&SynthSpec> = specs
                .iter()
                .filter(|s| s.file_stem.as_deref().unwrap().starts_with(&stem))
                .collect();
            assert_eq!(mine.len(), e.count as usize);
            for (p, sd) in &e.scatter {
                let v: Vec<f64> = mine.iter().map(|s| s.params[p] / e.params[p]).collect();
                let mean = v.iter().sum::<f64>() / v.len() as f64;
                assert!((mean - 1.0).abs() < 1e-12, "{} {p} mean {mean}", e.name);
                assert!(
                    v.iter().any(|x| (x - 1.0).abs() > 1e-4),
                    "{} {p} has no scatter",
                    e.name
                );
                assert!(
                    v.iter().all(|x| (x - 1.0).abs() < 4.0 * sd),
                    "{} {p}",
                    e.name
                );
            }
        }
        for kind in TestKind::ALL {
            let layouts: std::collections::BTreeSet<_> = specs
                .iter()
                .filter(|s| s.kind == kind)
                .map(|s| s.layout.extension())
                .collect();
            assert_eq!(layouts.len(), 3, "{kind}");
        }
        // Deterministic: same recipe, same specs; another seed, other scatter.
        assert_eq!(expand_recipe(&r).unwrap(), specs);
        let mut r2 = r.clone();
        r2.seed += 1;
        assert_ne!(expand_recipe(&r2).unwrap()[0].params, specs[0].params);
    }

    #[test]
    fn recipe_errors_name_the_series_and_field() {
        let mut r = parse_recipe(DEMO).unwrap();
        r.series[1].scatter.insert("nope".into(), 0.01);
        let e = expand_recipe(&r).unwrap_err().to_string();
        assert!(
            e.contains("series[1] (tension_100N).scatter") && e.contains("nope"),
            "{e}"
        );
        let bad = DEMO.replace(
            "count = 5, dwell_s = 1.0, max_control = 1.0e-3",
            "count = 5, dwel = 1.0, max_control = 1.0e-3",
        );
        let e = parse_recipe(&bad).unwrap_err().to_string();
        assert!(e.contains("dwel"), "{e}");
    }

    /// A one-series recipe runs end to end into a temporary folder with TRUTH.toml and no leftovers.
    #[test]
    fn run_recipe_writes_files_and_truth() {
        let text = r#"
seed = 1
[[series]]
name = "t"
label = "x"
count = 2
kind = "tension"
diameter_m = 2.8e-3
free_length_m = 0.032
law = "linear"
params = { EA = 7.96e4 }
scatter = { EA = 0.01 }
layouts = ["mts793_dat", "bluehill_csv"]
sample_rate_hz = 10.0
protocol = { steps = [ { step = "cycles", lower = 0.0, upper = 1.0e-5, rate = 1.0e-6, count = 1 } ] }
"#;
        let dir = tempfile::tempdir().unwrap();
        let files = run_recipe(text, dir.path()).unwrap();
        assert_eq!(files.len(), 2);
        let names = || {
            let mut v: Vec<String> = std::fs::read_dir(dir.path())
                .unwrap()
                .map(|e| e.unwrap().file_name().into_string().unwrap())
                .collect();
            v.sort();
            v
        };
        assert_eq!(names(), vec!["TRUTH.toml", "t_1.dat", "t_2.csv"]);
        let first = std::fs::read(dir.path().join("t_1.dat")).unwrap();
        let again = run_recipe(text, dir.path()).unwrap();
        assert_eq!(again, files);
        assert_eq!(std::fs::read(dir.path().join("t_1.dat")).unwrap(), first);
        // 1 cycle of 2 × 10 s at 10 Hz: 201 rows.
        assert_eq!(files[0].rows, 201);
        // A file that cannot be written (its name is taken by a folder): an error naming it, the
        // files already there unchanged, no temporary left beside them.
        std::fs::remove_file(dir.path().join("t_2.csv")).unwrap();
        std::fs::create_dir_all(dir.path().join("t_2.csv/taken")).unwrap();
        let e = run_recipe(text, dir.path()).unwrap_err().to_string();
        assert!(e.contains("t_2.csv"), "{e}");
        assert_eq!(names(), vec!["TRUTH.toml", "t_1.dat", "t_2.csv"]);
        assert_eq!(std::fs::read(dir.path().join("t_1.dat")).unwrap(), first);
    }
}
