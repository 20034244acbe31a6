//! Piecewise linear elastic law, chapter eq. (19) (Bowden cables): in the loaded channel the
//! stiffness is k₁ below the threshold |ε| < ε_t and k₂ above it, M = M_t + k₂(|ε| − ε_t) with
//! M_t = k₁ ε_t, sign-symmetric and reversible (loading = unloading).
//!
//! In bending the law acts on the curvature vector (K₁, K₂): |M| = m(|K|), M ∥ K, so the
//! response is isotropic in the bending plane. Other components are linear elastic. No history.

use crate::channel::{eye, norm1, Channel};
use crate::law::{ComponentStep, Law, LawResponse, SensStep, Strain6, Tangent6};
use crate::linear::SectionStiffness;
use nalgebra::{Matrix2, Vector2};

/// Piecewise linear elastic law (eq. (19)) in one channel, linear elastic elsewhere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PiecewiseLinear {
    /// Stiffnesses of the other components (the channel's own entry is ignored).
    pub elastic: SectionStiffness,
    /// The channel with the slope change.
    pub channel: Channel,
    /// Stiffness below the threshold, (EI)_B,1 in bending (N m²; N for axial).
    pub k1: f64,
    /// Stiffness above the threshold, (EI)_B,2 in bending.
    pub k2: f64,
    /// Threshold strain magnitude, K_B,t in bending (1/m; dimensionless for axial).
    pub threshold: f64,
}

impl PiecewiseLinear {
    /// Magnitude of the response at strain magnitude `r` ≥ 0, eq. (19).
    #[inline]
    pub fn magnitude(&self, r: f64) -> f64 {
        if r < self.threshold {
            self.k1 * r
        } else {
            self.k1 * self.threshold + self.k2 * (r - self.threshold)
        }
    }

    fn channel_response(&self, e: &Vector2<f64>) -> (Vector2<f64>, Matrix2<f64>) {
        let r = e.norm();
        let id = eye(self.channel);
        if r < self.threshold || r == 0.0 {
            return (self.k1 * e, self.k1 * id);
        }
        let n = e / r;
        let m = self.magnitude(r);
        let nn = n * n.transpose();
        (m * n, self.k2 * nn + (m / r) * (id - nn))
    }
}

impl Law for PiecewiseLinear {
    fn off_channel_linear(&self, component: usize) -> bool {
        self.channel.position(component).is_some()
    }

    fn name(&self) -> &str {
        "piecewise_linear"
    }

    fn n_state(&self) -> usize {
        0
    }

    fn update(&self, eps: &Strain6, _dt: f64, _old: &[f64], _new: &mut [f64]) -> LawResponse {
        let mut tangent = self.elastic.tangent_without([self.channel]);
        let mut stress = tangent.diagonal().component_mul(eps);
        let (s, c) = self.channel_response(&self.channel.get(eps));
        self.channel.add_to(&s, &mut stress);
        self.channel.add_block(&c, &mut tangent);
        LawResponse { stress, tangent }
    }

    fn elastic_tangent(&self) -> Tangent6 {
        let mut t = self.elastic.tangent_without([self.channel]);
        self.channel
            .add_block(&(self.k1 * eye(self.channel)), &mut t);
        t
    }
    /// On the channel's axis the response vector is parallel to the strain, so the scalar form
    /// of `channel_response` (same operations, |ε| as the norm of (ε, 0)) gives the same entry.
    fn update_component(&self, step: ComponentStep, _old: &[f64], _new: &mut [f64]) -> (f64, f64) {
        let ComponentStep {
            component, strain, ..
        } = step;
        if component > 5 {
            return (f64::NAN, f64::NAN);
        }
        if self.channel.position(component).is_none() {
            let k = self.elastic.diagonal()[component];
            return (k * strain, k);
        }
        let r = norm1(strain);
        if r < self.threshold || r == 0.0 {
            return (self.k1 * strain, self.k1);
        }
        let n = strain / r;
        let m = self.magnitude(r);
        let nn = n * n;
        (m * n, self.k2 * nn + (m / r) * (1.0 - nn))
    }

    /// k₁, k₂ and the threshold strain of the loaded channel (`EI1`, `EI2`, `K_t`).
    fn sens_params(&self, component: usize) -> Option<Vec<String>> {
        self.channel.position(component)?;
        let n = crate::registry::names(self.channel);
        Some(vec![
            format!("{}1", n.stiff),
            format!("{}2", n.stiff),
            format!("{}_t", n.strain),
        ])
    }

    fn sens_count(&self, component: usize) -> Option<usize> {
        self.channel.position(component).map(|_| 3)
    }

    /// No history: σ = k₁ ε below the threshold, n (k₁ ε_t + k₂ (|ε| − ε_t)) above it, so
    /// ∂σ/∂(k₁, k₂, ε_t) = (ε, 0, 0) or n (ε_t, |ε| − ε_t, k₁ − k₂), plus the tangent times ∂ε.
    fn update_component_sens(
        &self,
        step: ComponentStep,
        old: &[f64],
        new: &mut [f64],
        sens: SensStep<'_>,
    ) -> Option<(f64, f64)> {
        self.channel.position(step.component)?;
        let (s, k) = self.update_component(step, old, new);
        let e = step.strain;
        let r = norm1(e);
        let own = if r < self.threshold || r == 0.0 {
            [e, 0.0, 0.0]
        } else {
            let n = e / r;
            [
                n * self.threshold,
                n * (r - self.threshold),
                n * (self.k1 - self.k2),
            ]
        };
        for (j, (ds, de)) in sens.ds.iter_mut().zip(sens.de).enumerate() {
            *ds += k * de;
            if let Some(v) = j.checked_sub(sens.first).and_then(|l| own.get(l)) {
                *ds += v;
            }
        }
        Some((s, k))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::driver::drive_uniform;
    use crate::testutil::{assert_tangent_fd, path};

    /// Chapter Table 2 (Bowden cable): (EI)_B,1 = 1.40, (EI)_B,2 = 0.19 N m², K_B,t = 0.18 1/m.
    fn bowden() -> PiecewiseLinear {
        PiecewiseLinear {
            elastic: SectionStiffness::CHAPTER_CABLE,
            channel: Channel::Bending,
            k1: 1.40,
            k2: 0.19,
            threshold: 0.18,
        }
    }

    fn eq19(k: f64) -> f64 {
        let (ei1, ei2, kt) = (1.40, 0.19, 0.18);
        if k.abs() < kt {
            ei1 * k
        } else {
            k.signum() * (ei1 * kt + ei2 * (k.abs() - kt))
        }
    }

    #[test]
    fn bowden_table2_values_eq19() {
        let law = bowden();
        let m = |k: f64| {
            law.update(&Strain6::new(0., 0., 0., k, 0., 0.), 0.0, &[], &mut [])
                .stress[3]
        };
        assert!((m(0.1) - 0.14).abs() < 1e-12);
        assert!((m(0.18) - 0.252).abs() < 1e-12);
        assert!((m(0.5) - 0.3128).abs() < 1e-12);
        assert!((m(-0.5) + 0.3128).abs() < 1e-12);
        // Biaxial: |M| = m(|K|), M parallel to K.
        let r = law.update(&Strain6::new(0., 0., 0., 0.3, 0.4, 0.), 0.0, &[], &mut []);
        assert!((r.stress[3] - 0.3128 * 0.6).abs() < 1e-12);
        assert!((r.stress[4] - 0.3128 * 0.8).abs() < 1e-12);
    }

    #[test]
    fn loading_equals_unloading() {
        let law = bowden();
        // 0 → 1 → −1 → 0 (1/m)
        let k = path(0.0, &[(1.0, 100), (-1.0, 200), (0.0, 100)]);
        let n = k.len();
        let time: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let m = drive_uniform(&law, 3, &k, &time);
        for (ki, mi) in k.iter().zip(&m) {
            assert!((mi - eq19(*ki)).abs() < 1e-12, "K = {ki}: M = {mi}");
        }
    }

    #[test]
    fn tangent_matches_finite_difference() {
        let law = bowden();
        for e in [
            Strain6::new(1e-4, 0., 1e-4, 0.05, -0.03, 0.2),
            Strain6::new(0., 0., 0., 0.3, 0.4, 0.),
            Strain6::new(0., 0., 0., -0.7, 0.1, 0.),
        ] {
            assert_tangent_fd(&law, &e, 0.0, &[], 1e-6);
        }
        let tension = PiecewiseLinear {
            channel: Channel::Axial,
            k1: 1e5,
            k2: 2e4,
            threshold: 1e-3,
            ..bowden()
        };
        assert_tangent_fd(
            &tension,
            &Strain6::new(0., 0., 3e-3, 0.1, 0., 0.),
            0.0,
            &[],
            1e-6,
        );
        let r = tension.update(&Strain6::new(0., 0., -3e-3, 0., 0., 0.), 0.0, &[], &mut []);
        assert!((r.stress[2] + (100.0 + 2e4 * 2e-3)).abs() < 1e-9);
        assert!((r.tangent[(2, 2)] - 2e4).abs() < 1e-9);
    }
}
