//! The 3D geometrically exact (Cosserat / Simo–Reissner) rod: positions and unit quaternions per
//! node, static equilibrium by Newton's method. The reference implementation of chapter eqs.
//! (8)–(14) in space, used to verify the planar reduction and the uniform-state shortcuts.
//!
//! Discretisation: two-node elements with one integration point. With Ψ = log(R_aᵀ R_b) the
//! relative rotation vector of the end frames (rotation vectors, never linearised angles), the
//! element strains (chapter eq. (10)) are K = Ψ/l₀ and Γ = R_mᵀ (x_b − x_a)/l₀ − e₃ with the
//! midpoint frame R_m = R_a exp(Ψ/2): objective (invariant under rigid rotation) and free of
//! shear locking. Configuration updates are multiplicative, R ← exp(Δφ) R with the spatial spin
//! Δφ, so rotations of any size are exact. Internal forces are l₀ Bᵀσ with B = ∂ε/∂(δx, δφ)
//! evaluated by central differences of the exact strain map (12 directions per element); the
//! tangent is l₀ (Bᵀ C B + ∂(Bᵀσ)/∂q) with the law's consistent tangent C and the geometric part
//! by differences of Bᵀσ. The system is block tridiagonal (6×6 blocks).
//!
//! Does not: contact, distributed loads, follower loads (loads are dead, spatially fixed). It is
//! 3–10× slower per element than [`crate::planar`], which is why the three-point driver uses the
//! planar rod (exact for in-plane loading).

use crate::blocktri::solve_block_tridiagonal;
use crate::planar::{SolverOptions, SMALL_CORRECTION};
use crate::RodError;
use cablab_laws::Law;
use nalgebra::{Matrix6, SMatrix, SVector, UnitQuaternion, Vector3, Vector6};

type V12 = SVector<f64, 12>;
type M12 = SMatrix<f64, 12, 12>;
type B = SMatrix<f64, 6, 12>;

/// Rotation vector of a unit quaternion (angle in [0, π]), accurate for tiny angles:
/// 2 atan2(|v|, w) v/|v| (nalgebra's acos-based `scaled_axis` loses digits near the identity,
/// which would spoil the difference quotients below).
fn log_quat(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    let (mut w, mut v) = (q.scalar(), q.vector().into_owned());
    if w < 0.0 {
        w = -w;
        v = -v;
    }
    let s = v.norm();
    if s < 1e-300 {
        return v * 2.0;
    }
    v * (2.0 * s.atan2(w) / s)
}

/// Sectional strains [Γ₁, Γ₂, Γ₃, K₁, K₂, K₃] of the element between frames a and b.
fn element_strain(
    xa: &Vector3<f64>,
    qa: &UnitQuaternion<f64>,
    xb: &Vector3<f64>,
    qb: &UnitQuaternion<f64>,
    l0: f64,
) -> Vector6<f64> {
    let psi = log_quat(&(qa.inverse() * qb));
    let qm = qa * UnitQuaternion::from_scaled_axis(psi * 0.5);
    let g = qm.inverse_transform_vector(&(xb - xa)) / l0 - Vector3::z();
    Vector6::new(g.x, g.y, g.z, psi.x / l0, psi.y / l0, psi.z / l0)
}

/// Perturb the element's 12 parameters (δx_a, δφ_a, δx_b, δφ_b) in direction `j` by `h`.
fn perturbed(
    x: [Vector3<f64>; 2],
    q: [UnitQuaternion<f64>; 2],
    j: usize,
    h: f64,
) -> ([Vector3<f64>; 2], [UnitQuaternion<f64>; 2]) {
    let (mut x, mut q) = (x, q);
    let node = j / 6;
    let k = j % 6;
    if k < 3 {
        x[node][k] += h;
    } else {
        let mut w = Vector3::zeros();
        w[k - 3] = h;
        q[node] = UnitQuaternion::from_scaled_axis(w) * q[node];
    }
    (x, q)
}

/// B = ∂ε/∂(δx_a, δφ_a, δx_b, δφ_b) by central differences of the exact strain map.
fn strain_jacobian(x: [Vector3<f64>; 2], q: [UnitQuaternion<f64>; 2], l0: f64) -> B {
    let mut b = B::zeros();
    for j in 0..12 {
        let h = if j % 6 < 3 { 1e-5 * l0 } else { 1e-5 };
        let (xp, qp) = perturbed(x, q, j, h);
        let (xm, qm) = perturbed(x, q, j, -h);
        let d = (element_strain(&xp[0], &qp[0], &xp[1], &qp[1], l0)
            - element_strain(&xm[0], &qm[0], &xm[1], &qm[1], l0))
            / (2.0 * h);
        b.set_column(j, &d);
    }
    b
}

/// The 3D rod model: mesh, configuration (positions, unit quaternions), constraints, dead loads.
#[derive(Debug)]
pub struct Rod3d<'a> {
    law: &'a dyn Law,
    /// Element reference lengths, m.
    pub l0: Vec<f64>,
    /// Node positions, m.
    pub x: Vec<Vector3<f64>>,
    /// Node director frames R = [a₁ a₂ a₃] as unit quaternions.
    pub rot: Vec<UnitQuaternion<f64>>,
    eps0: Vec<Vector6<f64>>,
    /// Fixed degrees of freedom per node (x, y, z, φx, φy, φz): their increments are zero (set the
    /// value directly in `x`/`rot` to prescribe it).
    pub fixed: Vec<[bool; 6]>,
    /// Dead nodal forces, N.
    pub force: Vec<Vector3<f64>>,
    /// Dead nodal moments (spatial), N m.
    pub moment: Vec<Vector3<f64>>,
    /// Newton controls.
    pub options: SolverOptions,
    n_state: usize,
    state: Vec<f64>,
    trial: Vec<f64>,
    /// Element strains [Γ, K] at the last evaluation.
    pub strain: Vec<Vector6<f64>>,
    /// Element stress resultants [F, M] (material frame) at the last evaluation.
    pub stress: Vec<Vector6<f64>>,
    res: Vec<Vector6<f64>>,
    diag: Vec<Matrix6<f64>>,
    upper: Vec<Matrix6<f64>>,
    lower: Vec<Matrix6<f64>>,
    work: Vec<Matrix6<f64>>,
    force_scale: f64,
    length_scale: f64,
}

impl<'a> Rod3d<'a> {
    /// A straight, unstressed rod along +z (directors = global axes) from the origin,
    /// `elements` equal elements over `length_m`.
    pub fn straight(law: &'a dyn Law, length_m: f64, elements: usize) -> Result<Self, RodError> {
        if !(length_m.is_finite() && length_m > 0.0) {
            return Err(RodError::InvalidSetup(format!(
                "rod length must be positive and finite, got {length_m} m"
            )));
        }
        if elements == 0 {
            return Err(RodError::InvalidSetup(
                "the rod needs at least one element".into(),
            ));
        }
        let c = law.elastic_tangent();
        let ei = c[(3, 3)].max(c[(4, 4)]);
        if !(ei.is_finite() && (0..6).all(|i| c[(i, i)] > 0.0)) {
            return Err(RodError::InvalidSetup(format!(
                "law '{}' must have a positive elastic stiffness in all six components for the 3D rod",
                law.name()
            )));
        }
        let le = length_m / elements as f64;
        let n_state = law.n_state();
        let mut state = vec![0.0; n_state * elements];
        for e in 0..elements {
            law.init_state(&mut state[e * n_state..(e + 1) * n_state]);
        }
        let nodes = elements + 1;
        Ok(Rod3d {
            law,
            l0: vec![le; elements],
            x: (0..nodes)
                .map(|i| Vector3::new(0.0, 0.0, i as f64 * le))
                .collect(),
            rot: vec![UnitQuaternion::identity(); nodes],
            eps0: vec![Vector6::zeros(); elements],
            fixed: vec![[false; 6]; nodes],
            force: vec![Vector3::zeros(); nodes],
            moment: vec![Vector3::zeros(); nodes],
            options: SolverOptions::default(),
            n_state,
            trial: state.clone(),
            state,
            strain: vec![Vector6::zeros(); elements],
            stress: vec![Vector6::zeros(); elements],
            res: vec![Vector6::zeros(); nodes],
            diag: vec![Matrix6::zeros(); nodes],
            upper: vec![Matrix6::zeros(); elements],
            lower: vec![Matrix6::zeros(); elements],
            work: Vec::with_capacity(nodes),
            force_scale: ei / (length_m * length_m),
            length_scale: length_m,
        })
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.x.len()
    }

    /// Residual at node `i` (internal − external force, moment) at the last evaluation: at fixed
    /// degrees of freedom, the reaction the support exerts on the rod (spatial components).
    pub fn residual(&self, i: usize) -> Vector6<f64> {
        self.res[i]
    }

    fn assemble(&mut self, dt: f64, tangent: bool) {
        let ns = self.n_state;
        self.res.iter_mut().for_each(|r| *r = Vector6::zeros());
        if tangent {
            self.diag.iter_mut().for_each(|m| *m = Matrix6::zeros());
            self.upper.iter_mut().for_each(|m| *m = Matrix6::zeros());
            self.lower.iter_mut().for_each(|m| *m = Matrix6::zeros());
        }
        for e in 0..self.l0.len() {
            let l0 = self.l0[e];
            let x = [self.x[e], self.x[e + 1]];
            let q = [self.rot[e], self.rot[e + 1]];
            let eps = element_strain(&x[0], &q[0], &x[1], &q[1], l0) - self.eps0[e];
            let b = strain_jacobian(x, q, l0);
            let resp = self.law.update(
                &eps,
                dt,
                &self.state[e * ns..(e + 1) * ns],
                &mut self.trial[e * ns..(e + 1) * ns],
            );
            let sig = resp.stress;
            self.strain[e] = eps;
            self.stress[e] = sig;
            let f: V12 = b.transpose() * sig * l0;
            for d in 0..6 {
                self.res[e][d] += f[d];
                self.res[e + 1][d] += f[6 + d];
            }
            if tangent {
                let mut k: M12 = b.transpose() * resp.tangent * b * l0;
                // Geometric part: ∂(Bᵀσ)/∂q at fixed σ, central differences of B.
                for j in 0..12 {
                    let h = if j % 6 < 3 { 1e-6 * l0 } else { 1e-6 };
                    let (xp, qp) = perturbed(x, q, j, h);
                    let (xm, qm) = perturbed(x, q, j, -h);
                    let col = (strain_jacobian(xp, qp, l0).transpose() * sig
                        - strain_jacobian(xm, qm, l0).transpose() * sig)
                        * (l0 / (2.0 * h));
                    for i in 0..12 {
                        k[(i, j)] += col[i];
                    }
                }
                self.diag[e] += k.fixed_view::<6, 6>(0, 0);
                self.diag[e + 1] += k.fixed_view::<6, 6>(6, 6);
                self.upper[e] += k.fixed_view::<6, 6>(0, 6);
                self.lower[e] += k.fixed_view::<6, 6>(6, 0);
            }
        }
        for i in 0..self.nodes() {
            for d in 0..3 {
                self.res[i][d] -= self.force[i][d];
                self.res[i][3 + d] -= self.moment[i][d];
            }
        }
    }

    fn free_residual_norm(&self) -> f64 {
        let mut s = 0.0;
        for (i, r) in self.res.iter().enumerate() {
            for d in 0..6 {
                if !self.fixed[i][d] {
                    let v = if d >= 3 {
                        r[d] / self.length_scale
                    } else {
                        r[d]
                    };
                    s += v * v;
                }
            }
        }
        s.sqrt()
    }

    fn reference_force(&self) -> f64 {
        let mut f = self.force_scale;
        for (i, r) in self.res.iter().enumerate() {
            f = f
                .max(self.force[i].norm())
                .max(self.moment[i].norm() / self.length_scale);
            for d in 0..6 {
                if self.fixed[i][d] {
                    let v = if d >= 3 {
                        r[d] / self.length_scale
                    } else {
                        r[d]
                    };
                    f = f.max(v.abs());
                }
            }
        }
        f
    }

    fn apply(
        &mut self,
        x0: &[Vector3<f64>],
        q0: &[UnitQuaternion<f64>],
        dq: &[Vector6<f64>],
        alpha: f64,
    ) {
        for i in 0..x0.len() {
            let d = dq[i] * alpha;
            self.x[i] = x0[i] + Vector3::new(d[0], d[1], d[2]);
            self.rot[i] = UnitQuaternion::from_scaled_axis(Vector3::new(d[3], d[4], d[5])) * q0[i];
        }
    }

    /// Solve the current load step by Newton's method (plain Newton, then residual backtracking
    /// if it has not converged after a few iterations). On success call [`commit`](Self::commit).
    #[allow(clippy::needless_range_loop)] // several arrays indexed by node
    pub fn solve(&mut self, dt: f64, step: usize) -> Result<usize, RodError> {
        let n = self.nodes();
        let fail = |iterations: usize, residual: f64, reason: String| RodError::NotConverged {
            step,
            iterations,
            residual,
            reason,
        };
        self.assemble(dt, true);
        let mut rhs = vec![Vector6::zeros(); n];
        for it in 0..self.options.max_iterations {
            let r0 = self.free_residual_norm();
            let f_ref = self.reference_force();
            if !r0.is_finite() {
                return Err(fail(
                    it,
                    r0,
                    "residual is not finite (law returned NaN/inf)".into(),
                ));
            }
            if r0 <= self.options.tolerance * f_ref {
                return Ok(it);
            }
            for i in 0..n {
                rhs[i] = -self.res[i];
                for d in 0..6 {
                    if self.fixed[i][d] {
                        self.diag[i].row_mut(d).fill(0.0);
                        self.diag[i].column_mut(d).fill(0.0);
                        self.diag[i][(d, d)] = 1.0;
                        if i + 1 < n {
                            self.upper[i].row_mut(d).fill(0.0);
                            self.lower[i].column_mut(d).fill(0.0);
                        }
                        if i > 0 {
                            self.lower[i - 1].row_mut(d).fill(0.0);
                            self.upper[i - 1].column_mut(d).fill(0.0);
                        }
                        rhs[i][d] = 0.0;
                    }
                }
            }
            if let Err(block) = solve_block_tridiagonal(
                &self.diag,
                &self.upper,
                &self.lower,
                &mut rhs,
                &mut self.work,
            ) {
                return Err(fail(
                    it,
                    r0 / f_ref,
                    format!("singular tangent at node {block} (mechanism: add constraints)"),
                ));
            }
            let small = rhs.iter().all(|d| {
                d.fixed_rows::<3>(0).amax() <= SMALL_CORRECTION * self.length_scale
                    && d.fixed_rows::<3>(3).amax() <= SMALL_CORRECTION
            });
            let (x0, q0) = (self.x.clone(), self.rot.clone());
            let mut alpha = 1.0;
            self.apply(&x0, &q0, &rhs, alpha);
            self.assemble(dt, true);
            if it >= 8 {
                for _ in 0..8 {
                    let r1 = self.free_residual_norm();
                    if r1.is_finite() && r1 < r0 {
                        break;
                    }
                    alpha *= 0.5;
                    self.apply(&x0, &q0, &rhs, alpha);
                    self.assemble(dt, true);
                }
            }
            if small && self.free_residual_norm().is_finite() {
                return Ok(it + 1);
            }
        }
        let r = self.free_residual_norm();
        let f_ref = self.reference_force();
        if r <= self.options.tolerance * f_ref {
            return Ok(self.options.max_iterations);
        }
        Err(fail(
            self.options.max_iterations,
            r / f_ref,
            format!(
                "no convergence in {} Newton iterations",
                self.options.max_iterations
            ),
        ))
    }

    /// Accept the converged step: trial law states become committed.
    pub fn commit(&mut self) {
        self.state.copy_from_slice(&self.trial);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_laws::Linear;
    use cablab_core::TestKind;
    use std::collections::BTreeMap;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    /// Strains are objective: a rigid rotation of the whole element leaves them unchanged.
    #[test]
    fn strains_are_objective() {
        let xa = Vector3::new(0.1, 0.2, 0.0);
        let xb = Vector3::new(0.15, 0.25, 0.3);
        let qa = UnitQuaternion::from_scaled_axis(Vector3::new(0.2, -0.4, 0.1));
        let qb = UnitQuaternion::from_scaled_axis(Vector3::new(0.5, 0.3, -0.7));
        let e1 = element_strain(&xa, &qa, &xb, &qb, 0.3);
        let g = UnitQuaternion::from_scaled_axis(Vector3::new(1.0, -2.0, 0.5));
        let e2 = element_strain(&(g * xa), &(g * qa), &(g * xb), &(g * qb), 0.3);
        assert!((e1 - e2).amax() < 1e-12, "{e1} vs {e2}");
    }

    /// The rotation-vector log is exact near the identity and inverts exp.
    #[test]
    fn log_inverts_exp() {
        for w in [
            Vector3::new(1e-9, -2e-9, 3e-9),
            Vector3::new(0.3, -1.2, 2.0),
            Vector3::new(0.0, 3.0, 0.0),
        ] {
            let back = log_quat(&UnitQuaternion::from_scaled_axis(w));
            assert!(
                (back - w).norm() <= 1e-14 * w.norm().max(1.0) + 1e-24,
                "{w} -> {back}"
            );
        }
    }

    /// SPEC cantilever table through the 3D rod (64 elements, rod along z, load along −x).
    #[test]
    fn cantilever_table_3d() {
        let law = Linear::new(1e7, 1e7, 1.0);
        for (alpha, w, u, phi) in [
            (2.0, 0.49346, 0.16064, 0.78175),
            (10.0, 0.81061, 0.55500, 1.43029),
        ] {
            let mut rod = Rod3d::straight(&law, 1.0, 64).unwrap();
            rod.fixed[0] = [true; 6];
            let tip = rod.nodes() - 1;
            for k in 1..=10 {
                rod.force[tip] = Vector3::new(-alpha * k as f64 / 10.0, 0.0, 0.0);
                rod.solve(0.0, k).unwrap();
                rod.commit();
            }
            let t = rod.x[tip];
            let rot = rod.rot[tip].angle();
            assert!(rel(-t.x, w) < 1e-3, "alpha {alpha}: w {}", -t.x);
            assert!(rel(1.0 - t.z, u) < 1e-3, "alpha {alpha}: u {}", 1.0 - t.z);
            assert!(rel(rot, phi) < 1e-3, "alpha {alpha}: rotation {rot}");
            assert!(t.y.abs() < 1e-9, "stays in plane");
        }
    }

    /// A truly 3D case: a dead end moment m = (1, 0, 1.5) N m on a clamped rod with EI = GJ = 1
    /// bends and twists it into a helix, R(s) = exp(s m̂), r(L) = ∫ R(s) e₃ ds (closed form).
    #[test]
    fn end_wrench_gives_exact_helix() {
        let law = Linear::new(1e7, 1e7, 1.0);
        let length = 1.0;
        let mut rod = Rod3d::straight(&law, length, 80).unwrap();
        rod.fixed[0] = [true; 6];
        let tip = rod.nodes() - 1;
        let m = Vector3::new(1.0, 0.0, 1.5);
        for k in 1..=8 {
            rod.moment[tip] = m * (k as f64 / 8.0);
            rod.solve(0.0, k).unwrap();
            rod.commit();
        }
        let kappa = m.norm();
        let n = m / kappa;
        let e3 = Vector3::z();
        let kl = kappa * length;
        let exact = n * n.dot(&e3) * length
            + (e3 - n * n.dot(&e3)) * (kl.sin() / kappa)
            + n.cross(&e3) * ((1.0 - kl.cos()) / kappa);
        let err = (rod.x[tip] - exact).norm();
        assert!(err < 1e-3 * exact.norm(), "tip {} vs {exact}", rod.x[tip]);
        let r_exact = UnitQuaternion::from_scaled_axis(m * length);
        assert!(rod.rot[tip].angle_to(&r_exact) < 1e-3);
        // Uniform curvature-twist K = m (material) in every element.
        for s in &rod.strain {
            assert!(
                (s.fixed_rows::<3>(3) - m).norm() < 1e-3,
                "K {}",
                s.fixed_rows::<3>(3)
            );
        }
    }

    fn build(kind: TestKind, params: &[(&str, f64)]) -> Box<dyn Law> {
        let map: BTreeMap<String, f64> = params.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        cablab_laws::build(kind, "elastoplastic", &map).unwrap()
    }

    /// Torsion and tension through the 3D rod (clamped ends, elastoplastic cycle) equal the direct
    /// sectional evaluation the drivers use: the uniform-state shortcut is exact.
    #[test]
    fn uniform_shortcuts_match_3d_rod() {
        use crate::drivers::{simulate_path, TestSetup};
        let cases = [
            (
                TestKind::Torsion,
                build(
                    TestKind::Torsion,
                    &[("GJ", 2.02e-3), ("M_y", 0.1), ("HI", 2e-4)],
                ),
                0.033,
                4.0,
            ),
            (
                TestKind::Tension,
                build(
                    TestKind::Tension,
                    &[("EA", 7.96e4), ("F_y", 54.0), ("H", 5e3)],
                ),
                0.032,
                8e-5,
            ),
        ];
        for (kind, law, l, c_max) in cases {
            let path = [c_max, -c_max * 0.5];
            let direct = simulate_path(
                &TestSetup::new(kind, l),
                law.as_ref(),
                &path,
                Some(c_max / 10.0),
            )
            .unwrap();
            let mut rod = Rod3d::straight(law.as_ref(), l, 8).unwrap();
            rod.fixed[0] = [true; 6];
            let tip = rod.nodes() - 1;
            rod.fixed[tip] = [true; 6];
            for (k, &c) in direct.control.iter().enumerate() {
                if kind == TestKind::Torsion {
                    rod.rot[tip] = UnitQuaternion::from_scaled_axis(Vector3::z() * c);
                } else {
                    rod.x[tip] = Vector3::new(0.0, 0.0, l + c);
                }
                rod.solve(1.0, k).unwrap();
                rod.commit();
                let reaction = rod.residual(tip);
                let r = if kind == TestKind::Torsion {
                    reaction[5]
                } else {
                    reaction[2]
                };
                let d = direct.response[k];
                assert!(
                    (r - d).abs() <= 1e-6 * d.abs().max(1e-3),
                    "{kind}: rod {r} vs sectional {d} at {c}"
                );
            }
        }
    }
}
