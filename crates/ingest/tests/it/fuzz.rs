//! Property test: random bytes and mutations of real fixture bytes, through `read_bytes` with
//! every `--format` and with detection, never panic (errors are fine). Bounded: a fixed number of
//! cases per property, small inputs.

use cablab_ingest::{read_bytes, Format, ReadOptions};
use proptest::prelude::*;
use std::path::PathBuf;

fn fixtures() -> Vec<Vec<u8>> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/data");
    let mut v = Vec::new();
    for name in [
        "bam__mts793_cube_compression.dat",
        "mtscyclic__mts793_cyclic_type1_es.dat",
        "bam__testsuite_emodul_cyclic_compression.csv",
        "cthbiax__testsuite_axial_torsion_daq.xml",
        "materialdigital__instron8852_tension_46NT71.csv",
        "catman_ascii_sample.txt",
        "tensileanalyzer__uiuc_tension_steel1045_1.csv",
        "sdata__nist_numisheet2020_tct_dp980.csv",
        "mechtesting__tension_steel1045_extensometer.csv",
        "mechtesting__tension_steel1045_machine.csv",
        "hilhorst__testxpert_tension_mdb1pct_en.TRA",
        "hilhorst__testxpert_tension_allong1_fr.TRA",
    ] {
        let b = std::fs::read(dir.join(name)).expect("fixture");
        // Keep inputs small so that each case is fast: the head holds every layout feature.
        v.push(b[..b.len().min(6000)].to_vec());
    }
    // A UTF-16 NEXYGEN-like head.
    let t = "Time (s)\tLoad (N)\tMachine Extension (mm)\r\n0.0000\t\t\r\n0.7238\t0.0011054\t0.0077767\r\n";
    v.push(t.encode_utf16().flat_map(|u| u.to_le_bytes()).collect());
    v
}

fn all_options() -> Vec<ReadOptions> {
    let mut v = vec![ReadOptions::default()];
    for f in Format::ALL {
        v.push(ReadOptions {
            format: Some(f),
            ..Default::default()
        });
    }
    v.push(ReadOptions {
        block: Some(2),
        time: Some("Time".into()),
        ..Default::default()
    });
    v
}

#[derive(Debug, Clone)]
enum Edit {
    Flip(usize, u8),
    Insert(usize, Vec<u8>),
    Delete(usize, usize),
    Truncate(usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Edit::Flip(p, b)),
        (
            any::<usize>(),
            prop::collection::vec(
                prop_oneof![
                    Just(b'\t'),
                    Just(b';'),
                    Just(b','),
                    Just(b'"'),
                    Just(b'\n'),
                    Just(b'\r'),
                    Just(b'0'),
                    Just(b'-'),
                    Just(b'E'),
                    Just(0xFCu8),
                    Just(0u8),
                    any::<u8>()
                ],
                1..8
            )
        )
            .prop_map(|(p, b)| Edit::Insert(p, b)),
        (any::<usize>(), 1usize..200).prop_map(|(p, n)| Edit::Delete(p, n)),
        any::<usize>().prop_map(Edit::Truncate),
    ]
}

fn apply(mut b: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for e in edits {
        let n = b.len().max(1);
        match e {
            Edit::Flip(p, x) => {
                if !b.is_empty() {
                    let i = p % b.len();
                    b[i] = *x;
                }
            }
            Edit::Insert(p, s) => {
                let i = p % n;
                let i = i.min(b.len());
                b.splice(i..i, s.iter().copied());
            }
            Edit::Delete(p, k) => {
                if !b.is_empty() {
                    let i = p % b.len();
                    let j = (i + k).min(b.len());
                    b.drain(i..j);
                }
            }
            Edit::Truncate(p) => b.truncate(p % n),
        }
    }
    b
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 160, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..1500)) {
        for o in all_options() {
            let _ = read_bytes(&bytes, "random", &o);
        }
    }

    #[test]
    fn random_text_never_panics(s in "[0-9a-zA-Z ,;\t\"\\.\\-eE()\\[\\]\r\n]{0,600}") {
        for o in all_options() {
            let _ = read_bytes(s.as_bytes(), "text", &o);
        }
    }

    #[test]
    fn mutated_fixtures_never_panic(which in 0usize..13, edits in prop::collection::vec(edit(), 1..6)) {
        let fx = fixtures();
        let bytes = apply(fx[which % fx.len()].clone(), &edits);
        for o in all_options() {
            let (_, heap) = crate::mem::peak(|| {
                if let Ok(r) = read_bytes(&bytes, "mutated", &o) {
                    let _ = r.inspect();
                }
            });
            // Bounded memory: a small multiple of the input (plus polars' fixed overhead).
            prop_assert!(heap <= 64 * bytes.len() + (8 << 20), "{heap} bytes for {}", bytes.len());
        }
    }
}
