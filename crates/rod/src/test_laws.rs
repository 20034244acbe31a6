//! Small private laws for the solver's own tests (so the rod can be verified independently of
//! the laws crate): linear elasticity, chapter eqs. (16)–(17), planar components only.

use cablab_laws::{Law, LawResponse, Strain6, Tangent6};

/// Linear elastic law with C = diag(GA, GA, EA, EI, EI, GJ) (GJ = EI here).
#[derive(Debug, Clone)]
pub(crate) struct Linear {
    c: Tangent6,
}

impl Linear {
    pub(crate) fn new(ea: f64, ga: f64, ei: f64) -> Self {
        Linear {
            c: Tangent6::from_diagonal(&Strain6::new(ga, ga, ea, ei, ei, ei)),
        }
    }
}

impl Law for Linear {
    fn name(&self) -> &str {
        "test_linear"
    }
    fn n_state(&self) -> usize {
        0
    }
    fn update(&self, eps: &Strain6, _dt: f64, _old: &[f64], _new: &mut [f64]) -> LawResponse {
        LawResponse {
            stress: self.c * eps,
            tangent: self.c,
        }
    }
    fn elastic_tangent(&self) -> Tangent6 {
        self.c
    }
}
