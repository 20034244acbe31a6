//! The words and tables the report writes for a reader, on the fixtures the demo document uses.

use crate::fixtures::*;
use cablab_report::*;

#[test]
fn effect_case_gives_where_which_how_far_and_separation() {
    let w = diagnosis_words(&kinematic_hardening_verdict());
    let paras: Vec<&str> = w.split("\n\n").collect();
    assert_eq!(paras.len(), 3, "{w}");
    assert_eq!(
        paras[0],
        "Where: the largest share of the squared residual, 41\u{a0}%, lies in cycle 3 unloading."
    );
    assert!(paras[1].starts_with("Which: kinematic hardening (the yield limit moves"));
    assert!(paras[1].contains("from 6.2\u{a0}% to 1.1\u{a0}%"));
    assert!(
        paras[1].ends_with("down to the noise floor (0.9\u{a0}%)."),
        "{}",
        paras[1]
    );
    assert!(paras[2].starts_with("Equally good on the held-out data: stiffness degradation."));
    assert!(
        paras[2].ends_with("To separate them: cycles with reversed loading and growing amplitude."),
        "{}",
        paras[2]
    );
}

#[test]
fn parameter_table_reproduces_table_2() {
    let t = parameter_table("Table 2", &bowden_table2()).to_table();
    let values: Vec<(&str, &str)> = t
        .rows
        .iter()
        .map(|r| (r[2].as_str(), r[3].as_str()))
        .collect();
    assert_eq!(
        values,
        [
            ("1.40", "N m\u{b2}"),
            ("0.190", "N m\u{b2}"),
            ("0.180", "1/m")
        ]
    );
}
