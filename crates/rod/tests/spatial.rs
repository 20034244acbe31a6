//! Verification of the 3D geometrically exact rod (`cablab_rod::spatial`) against the analytical
//! solutions of SPEC.md: the cantilever table (in an arbitrarily rotated frame), pure bending to a
//! full circle (dead and follower moment), the bent-and-twisted helix under an end moment (EI ≠ GJ
//! and EI = GJ), objectivity, clamped torsion (linear to two full turns, elastoplastic along a
//! cycle against the uniform sectional evaluation), the pinned elastica under displacement control,
//! a curved stress-free reference, mesh convergence, step cutting and the failure paths. It is also
//! the reference for the rest of the crate: the planar rod is checked to be its exact in-plane
//! reduction, and the drivers' uniform-state shortcuts for tension and torsion to equal it along
//! elastoplastic cycles. Measured values are printed to the (captured) test output: run with
//! `--nocapture` to see them.

use cablab_core::TestKind;
use cablab_laws::{build, drive_uniform, loaded_component, Law, LinearElastic, SectionStiffness};
use cablab_rod::scenarios::cantilever_tip_load;
use cablab_rod::spatial::{rotation_vector, Controls, SpatialRod, StepStats};
use cablab_rod::{simulate_path, RodError, TestSetup};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// EI = 1, GJ = 0.7, EA = GA = 10⁷: the inextensible, unshearable limit for L = 1, loads ≤ 10.
fn stiff_law() -> LinearElastic {
    LinearElastic::new(SectionStiffness {
        ga_n: 1e7,
        ea_n: 1e7,
        ei_nm2: 1.0,
        gj_nm2: 0.7,
    })
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The SPEC cantilever table: α = PL²/EI → w/L, u/L, tip rotation.
const CANTILEVER: [(f64, f64, f64, f64); 4] = [
    (1.0, 0.30172, 0.05643, 0.46135),
    (2.0, 0.49346, 0.16064, 0.78175),
    (5.0, 0.71379, 0.38763, 1.21537),
    (10.0, 0.81061, 0.55500, 1.43029),
];

struct Cantilever {
    w: f64,
    u: f64,
    phi: f64,
    off_plane: f64,
    tip: Vector3<f64>,
    tip_rot: UnitQuaternion<f64>,
    stats: StepStats,
}

/// Clamped at `origin`, axis `frame`·e₃, L = 1, dead tip load α along `frame`·(cos 0.7, sin 0.7, 0)
/// (an arbitrary direction across the axis, not a principal one), `steps` load steps.
fn cantilever(
    law: &dyn Law,
    alpha: f64,
    elements: usize,
    steps: usize,
    frame: UnitQuaternion<f64>,
    origin: Vector3<f64>,
) -> Cantilever {
    let mut rod = SpatialRod::straight_along(law, 1.0, elements, origin, frame).unwrap();
    rod.clamp(0);
    let tip = rod.nodes() - 1;
    let dir = frame * Vector3::new(0.7f64.cos(), 0.7f64.sin(), 0.0);
    let axis = frame * Vector3::z();
    let mut c = Controls::new(rod.nodes());
    c.force[tip] = dir * alpha;
    let stats = rod.ramp(&c, steps).unwrap();
    let d = rod.x[tip] - (origin + axis);
    Cantilever {
        w: d.dot(&dir),
        u: -d.dot(&axis),
        phi: (frame.inverse() * rod.rot[tip]).angle(),
        off_plane: d.dot(&axis.cross(&dir)),
        tip: rod.x[tip],
        tip_rot: rod.rot[tip],
        stats,
    }
}

/// SPEC cantilever table in 3D at 64 elements, the whole problem rotated by a generic rotation
/// and shifted: every entry within 1e-3 relative, and the rotated solution is the rotated
/// unrotated solution (to 1e-10).
#[test]
fn cantilever_table_in_a_rotated_frame() {
    let law = stiff_law();
    let g = UnitQuaternion::from_scaled_axis(Vector3::new(0.4, -1.1, 0.8));
    let shift = Vector3::new(0.3, -0.2, 1.5);
    for (alpha, w, u, phi) in CANTILEVER {
        let steps = (2.0 * alpha).ceil() as usize;
        let base = cantilever(
            &law,
            alpha,
            64,
            steps,
            UnitQuaternion::identity(),
            Vector3::zeros(),
        );
        let rot = cantilever(&law, alpha, 64, steps, g, shift);
        for c in [&base, &rot] {
            assert!(rel(c.w, w) < 1e-3, "alpha {alpha}: w/L {} vs {w}", c.w);
            assert!(rel(c.u, u) < 1e-3, "alpha {alpha}: u/L {} vs {u}", c.u);
            assert!(
                rel(c.phi, phi) < 1e-3,
                "alpha {alpha}: rotation {} vs {phi}",
                c.phi
            );
            assert!(
                c.off_plane.abs() < 1e-10,
                "alpha {alpha}: leaves the plane by {}",
                c.off_plane
            );
        }
        eprintln!(
            "alpha {alpha}: w/L {:.6} u/L {:.6} phi {:.6} (rel. errors {:.1e} {:.1e} {:.1e}), {} Newton iterations",
            rot.w,
            rot.u,
            rot.phi,
            rel(rot.w, w),
            rel(rot.u, u),
            rel(rot.phi, phi),
            rot.stats.newton_iterations
        );
        assert!((rot.tip - (g * base.tip + shift)).norm() < 1e-10);
        assert!(rot.tip_rot.angle_to(&(g * base.tip_rot)) < 1e-10);
    }
}

/// Pure bending by a dead end moment M about a fixed axis: uniform curvature M/EI and the free
/// end at z/L = sin(m)/m, y/L = −(1 − cos m)/m for m = ML/EI up to a full circle (m = 2π, where
/// the tip frame is back to the identity and its quaternion has flipped sign).
#[test]
fn pure_bending_to_a_full_circle() {
    let law = stiff_law();
    for m in [PI / 2.0, PI, 1.5 * PI, 2.0 * PI] {
        let mut rod = SpatialRod::straight(&law, 1.0, 64).unwrap();
        rod.clamp(0);
        let tip = rod.nodes() - 1;
        let mut c = Controls::new(rod.nodes());
        c.moment[tip] = Vector3::new(m, 0.0, 0.0);
        rod.ramp(&c, 16).unwrap();
        let exact = Vector3::new(0.0, -(1.0 - m.cos()) / m, m.sin() / m);
        let err = (rod.x[tip] - exact).norm();
        assert!(
            err < 1e-3,
            "m = {m}: tip {} vs {exact} (error {err:e})",
            rod.x[tip]
        );
        let total: f64 = rod.strains().iter().map(|s| s[3] / 64.0).sum();
        assert!(
            (total - m).abs() < 1e-9,
            "m = {m}: total bending angle {total}"
        );
        for s in rod.strains() {
            assert!((s[3] - m).abs() < 1e-7 * m, "curvature {} vs {m}", s[3]);
            assert!(s[4].abs() < 1e-9 && s[5].abs() < 1e-9, "spurious K {s}");
        }
        let r_exact = UnitQuaternion::from_scaled_axis(Vector3::new(m, 0.0, 0.0));
        assert!(rod.rot[tip].angle_to(&r_exact) < 1e-7);
    }
}

/// The same full circle under a follower end moment (it turns with the tip): about a fixed
/// axis it is the same load, so the same circle.
#[test]
fn pure_bending_by_a_follower_moment() {
    let law = stiff_law();
    let m = 2.0 * PI;
    let mut rod = SpatialRod::straight(&law, 1.0, 48).unwrap();
    rod.clamp(0);
    let tip = rod.nodes() - 1;
    let mut c = Controls::new(rod.nodes());
    c.follower_moment[tip] = Vector3::new(m, 0.0, 0.0);
    rod.ramp(&c, 16).unwrap();
    assert!(
        rod.x[tip].norm() < 1e-9,
        "the circle closes: tip {}",
        rod.x[tip]
    );
    for s in rod.strains() {
        assert!((s[3] - m).abs() < 1e-7 * m);
    }
}

/// Closed form of the clamped rod (R(0) = I, along e₃) under a dead end moment M with
/// C_M = diag(EI, EI, GJ), no force: the internal moment is M everywhere, so (Kirchhoff's
/// analogy: the torque-free symmetric top) R(s) = exp(s M̂·|M|/EI) exp(s c e₃) with
/// c = (1/GJ − 1/EI) M·e₃ — a regular precession: the tangent turns about M at the rate |M|/EI,
/// the centreline is a helix about M, and the material curvature K(s) = C_M⁻¹ R(s)ᵀ M has a
/// constant twist K₃ = M·e₃/GJ and a constant bending magnitude |K⊥| = |M × e₃|/EI (its
/// direction precesses in the material frame unless EI = GJ).
struct Helix {
    axis: Vector3<f64>,
    omega: f64,
    cos_b: f64,
    sin_b: f64,
    u: Vector3<f64>,
    c: f64,
}

impl Helix {
    fn new(m: Vector3<f64>, ei: f64, gj: f64) -> Self {
        let axis = m.normalize();
        let cos_b = axis.z;
        let sin_b = (1.0 - cos_b * cos_b).sqrt();
        Helix {
            axis,
            omega: m.norm() / ei,
            cos_b,
            sin_b,
            u: (Vector3::z() - axis * cos_b) / sin_b,
            c: (1.0 / gj - 1.0 / ei) * m.z,
        }
    }
    fn position(&self, s: f64) -> Vector3<f64> {
        let ws = self.omega * s;
        self.axis * (s * self.cos_b)
            + (self.u * ws.sin() + self.axis.cross(&self.u) * (1.0 - ws.cos()))
                * (self.sin_b / self.omega)
    }
    fn rotation(&self, s: f64) -> UnitQuaternion<f64> {
        UnitQuaternion::from_scaled_axis(self.axis * (self.omega * s))
            * UnitQuaternion::from_scaled_axis(Vector3::z() * (self.c * s))
    }
    fn radius(&self) -> f64 {
        self.sin_b / self.omega
    }
    /// A point on the helix axis.
    fn centre(&self) -> Vector3<f64> {
        self.axis.cross(&self.u) * self.radius()
    }
}

/// Solve the helix problem: L = 1, EI = 1, GJ = 0.7, M = (0.8, 0, 1.2) at the tip, 64 elements.
fn solve_helix(law: &dyn Law) -> (SpatialRod<'_>, Vector3<f64>) {
    let m = Vector3::new(0.8, 0.0, 1.2);
    let mut rod = SpatialRod::straight(law, 1.0, 64).unwrap();
    rod.clamp(0);
    let tip = rod.nodes() - 1;
    let mut c = Controls::new(rod.nodes());
    c.moment[tip] = m;
    rod.ramp(&c, 8).unwrap();
    (rod, m)
}

/// Torsion–bending coupling with EI ≠ GJ: constant twist M₃/GJ, constant bending magnitude,
/// K = C_M⁻¹ R_mᵀ M element by element, nodes on a helix of the analytic radius sin β EI/|M|
/// advancing s cos β along the axis M̂ (pitch 2π cos β EI/|M|), tip position and frame exact.
#[test]
fn end_moment_with_ei_ne_gj_gives_the_precessing_helix() {
    let law = stiff_law();
    let (ei, gj) = (1.0, 0.7);
    let (rod, m) = solve_helix(&law);
    let h = Helix::new(m, ei, gj);
    let k3 = m.z / gj;
    let k_perp = m.cross(&Vector3::z()).norm() / ei;
    let le = 1.0 / 64.0;
    let cm_inv = Matrix3::from_diagonal(&Vector3::new(1.0 / ei, 1.0 / ei, 1.0 / gj));
    let mut k1_seen = (f64::INFINITY, f64::NEG_INFINITY);
    for (e, s) in rod.strains().iter().enumerate() {
        assert!(rel(s[5], k3) < 1e-4, "element {e}: twist {} vs {k3}", s[5]);
        let kp = (s[3] * s[3] + s[4] * s[4]).sqrt();
        assert!(rel(kp, k_perp) < 1e-4, "element {e}: |K⊥| {kp} vs {k_perp}");
        // Pointwise K = C_M⁻¹ R(s)ᵀ M at the element's midpoint frame.
        let mid = rod.rot[e].nlerp(&rod.rot[e + 1], 0.5);
        let k_an = cm_inv * (mid.inverse() * m);
        let k = Vector3::new(s[3], s[4], s[5]);
        assert!(
            (k - k_an).norm() < 1e-3 * k_an.norm(),
            "element {e}: K {k} vs {k_an}"
        );
        k1_seen = (k1_seen.0.min(s[3]), k1_seen.1.max(s[3]));
    }
    // EI ≠ GJ: the bending direction precesses in the material frame (K is not constant).
    // It turns by −c s: K₁ = |K⊥| cos(c s) from the first to the last element midpoint.
    let range = k_perp * ((h.c * le / 2.0).cos() - (h.c * (1.0 - le / 2.0)).cos());
    assert!(range > 0.05);
    assert!(
        ((k1_seen.1 - k1_seen.0) - range).abs() < 1e-3,
        "K₁ range {k1_seen:?} vs {range}"
    );
    let (rho, pitch) = (h.radius(), 2.0 * PI * h.cos_b / h.omega);
    // Independent check of the closed form: a helix of curvature κ = |M⊥|/EI and torsion
    // τ = M₃/EI has radius κ/(κ² + τ²) and pitch 2π τ/(κ² + τ²).
    let (kappa, tau) = (0.8 / ei, 1.2 / ei);
    assert!((rho - kappa / (kappa * kappa + tau * tau)).abs() < 1e-12);
    assert!((pitch - 2.0 * PI * tau / (kappa * kappa + tau * tau)).abs() < 1e-12);
    for (i, x) in rod.x.iter().enumerate() {
        let s = i as f64 * le;
        let r = x - h.centre();
        let along = r.dot(&h.axis);
        let dist = (r - h.axis * along).norm();
        assert!(
            (dist - rho).abs() < 1e-4,
            "node {i}: distance from axis {dist} vs radius {rho}"
        );
        assert!(
            (along - s * pitch * h.omega / (2.0 * PI)).abs() < 1e-4,
            "node {i}: advance {along}"
        );
        assert!(
            (x - h.position(s)).norm() < 2e-4,
            "node {i}: {x} vs {}",
            h.position(s)
        );
    }
    let tip = rod.nodes() - 1;
    eprintln!(
        "helix: tip position error {:.2e}, tip frame error {:.2e} rad, K₁ range {k1_seen:?}",
        (rod.x[tip] - h.position(1.0)).norm(),
        rod.rot[tip].angle_to(&h.rotation(1.0))
    );
    assert!(rod.rot[tip].angle_to(&h.rotation(1.0)) < 1e-4);
}

/// The special case EI = GJ: a dead end moment m = (1, 0, 1.5) N m,
/// EI = GJ = 1, no precession (c = 0): R(s) = exp(s m), the material curvature-twist K = m is the
/// same in every element, and the tip lies on the closed-form helix.
#[test]
fn end_moment_with_ei_eq_gj_gives_uniform_curvature() {
    let law = LinearElastic::new(SectionStiffness {
        ga_n: 1e7,
        ea_n: 1e7,
        ei_nm2: 1.0,
        gj_nm2: 1.0,
    });
    let m = Vector3::new(1.0, 0.0, 1.5);
    let mut rod = SpatialRod::straight(&law, 1.0, 80).unwrap();
    rod.clamp(0);
    let tip = rod.nodes() - 1;
    let mut c = Controls::new(rod.nodes());
    c.moment[tip] = m;
    rod.ramp(&c, 8).unwrap();
    let h = Helix::new(m, 1.0, 1.0);
    assert_eq!(h.c, 0.0);
    for s in rod.strains() {
        let k = Vector3::new(s[3], s[4], s[5]);
        assert!((k - m).norm() < 1e-9, "K {k} vs {m}");
    }
    let exact = h.position(1.0);
    let err = (rod.x[tip] - exact).norm();
    eprintln!("helix EI = GJ: tip position error {err:.2e}");
    assert!(err < 1e-3 * exact.norm(), "tip {} vs {exact}", rod.x[tip]);
    assert!(rod.rot[tip].angle_to(&UnitQuaternion::from_scaled_axis(m)) < 1e-7);
}

/// Objectivity: a rigid rotation (and shift) of a converged 3D equilibrium (end force and end
/// moment, extensible and shearable rod so that the residual has no round-off floor from a huge
/// EA), loads turned with it, leaves the strains unchanged, keeps the residual at zero and turns
/// the reactions.
#[test]
fn rigid_rotation_of_an_equilibrium_is_an_equilibrium() {
    let law = LinearElastic::new(SectionStiffness {
        ga_n: 60.0,
        ea_n: 100.0,
        ei_nm2: 1.0,
        gj_nm2: 0.7,
    });
    let mut rod = SpatialRod::straight(&law, 1.0, 32).unwrap();
    rod.clamp(0);
    let tip = rod.nodes() - 1;
    let mut c = Controls::new(rod.nodes());
    c.moment[tip] = Vector3::new(0.8, 0.0, 1.2);
    c.force[tip] = Vector3::new(1.0, -0.5, 0.3);
    rod.ramp(&c, 8).unwrap();
    rod.evaluate().unwrap();
    let strains = rod.strains().to_vec();
    let reaction = rod.residual(0);
    let scale = reaction.norm();
    assert!(
        rod.free_residual_norm() < 1e-9 * scale,
        "residual {}",
        rod.free_residual_norm()
    );
    // Global balance: the support moment is −(M + (x_tip − x_0) × F).
    let m_support = Vector3::new(reaction[3], reaction[4], reaction[5]);
    let arm = rod.x[tip] - rod.x[0];
    assert!((m_support + c.moment[tip] + arm.cross(&c.force[tip])).norm() < 1e-9 * scale);
    let g = UnitQuaternion::from_scaled_axis(Vector3::new(-2.0, 0.7, 1.9));
    rod.transform_rigidly(&g, &Vector3::new(5.0, -3.0, 2.0));
    rod.evaluate().unwrap();
    for (a, b) in strains.iter().zip(rod.strains()) {
        assert!((a - b).amax() < 1e-12, "{a} vs {b}");
    }
    assert!(
        rod.free_residual_norm() < 1e-9 * scale,
        "residual {}",
        rod.free_residual_norm()
    );
    let r = rod.residual(0);
    let f_rot = g * Vector3::new(reaction[0], reaction[1], reaction[2]);
    let m_rot = g * Vector3::new(reaction[3], reaction[4], reaction[5]);
    assert!((Vector3::new(r[0], r[1], r[2]) - f_rot).norm() < 1e-9 * scale);
    assert!((Vector3::new(r[3], r[4], r[5]) - m_rot).norm() < 1e-9 * scale);
    // The reaction balances the loads: support force = −F, support moment = −(M + r_tip × F).
    let f = Vector3::new(r[0], r[1], r[2]);
    assert!((f + g * c.force[tip]).norm() < 1e-9 * scale);
}

/// Clamped–clamped torsion under displacement control, twisted to two full turns (4π) in steps
/// of π/8: the torque is GJ θ/L at every step (linear law, no singularity at θ = π, 2π, ...),
/// the reaction at the other end is opposite, the centreline does not move. Then a prescribed
/// end displacement stretches the twisted rod: axial force EA δ/L.
#[test]
fn clamped_torsion_through_several_turns() {
    let gj = 2.02e-3;
    let ea = 7.96e4;
    let law = LinearElastic::new(SectionStiffness {
        ga_n: 0.3 * ea,
        ea_n: ea,
        ei_nm2: 1.37e-3,
        gj_nm2: gj,
    });
    let l = 0.033;
    let mut rod = SpatialRod::straight(&law, l, 16).unwrap();
    rod.clamp(0);
    let tip = rod.nodes() - 1;
    rod.clamp(tip);
    let mut c = Controls::new(rod.nodes());
    for k in 1..=32 {
        let theta = k as f64 * PI / 8.0;
        c.rotation[tip] = Some(UnitQuaternion::from_scaled_axis(Vector3::z() * theta));
        rod.apply(&c, 0.0, k).unwrap();
        let torque = rod.residual(tip)[5];
        assert!(
            rel(torque, gj * theta / l) < 1e-9,
            "theta {theta}: torque {torque}"
        );
        assert!(rel(-rod.residual(0)[5], gj * theta / l) < 1e-9);
        for s in rod.strains() {
            assert!(rel(s[5], theta / l) < 1e-9);
        }
        assert!(rod.x.iter().all(|x| x.x.abs() < 1e-12 && x.y.abs() < 1e-12));
    }
    let delta = 1e-4;
    c.position[tip] = Some(Vector3::new(0.0, 0.0, l + delta));
    rod.apply(&c, 0.0, 33).unwrap();
    assert!(
        rel(rod.residual(tip)[2], ea * delta / l) < 1e-6,
        "force {}",
        rod.residual(tip)[2]
    );
    assert!(rel(rod.residual(tip)[5], gj * 4.0 * PI / l) < 1e-9);
}

/// Elastoplastic torsion through the 3D rod (clamped ends, end twist cycled 0 → 2π → −2π → π in
/// steps of π/12, as in the chapter's torsion test) equals the uniform sectional evaluation
/// `drive_uniform` at K₃ = θ/L: internal variables are carried per integration point and
/// committed step by step.
#[test]
fn elastoplastic_torsion_cycle_matches_uniform_evaluation() {
    let params: BTreeMap<String, f64> = [("GJ", 2.02e-3), ("M_y", 0.1), ("HI", 2e-4)]
        .iter()
        .map(|(k, v)| (k.to_string(), *v))
        .collect();
    let law = build(TestKind::Torsion, "elastoplastic", &params).unwrap();
    let l = 0.033;
    let d = PI / 12.0;
    let mut theta = vec![0.0];
    for (target, sign) in [(2.0 * PI, 1.0), (-2.0 * PI, -1.0), (PI, 1.0)] {
        while (target - theta.last().unwrap()) * sign > 1e-12 {
            theta.push(theta.last().unwrap() + sign * d);
        }
    }
    let theta = &theta[1..];
    let k3: Vec<f64> = theta.iter().map(|t| t / l).collect();
    let time: Vec<f64> = (0..theta.len()).map(|i| i as f64).collect();
    let expected = drive_uniform(law.as_ref(), 5, &k3, &time);
    let mut rod = SpatialRod::straight(law.as_ref(), l, 8).unwrap();
    rod.clamp(0);
    let tip = rod.nodes() - 1;
    rod.clamp(tip);
    let mut c = Controls::new(rod.nodes());
    let m_max = expected.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let mut plastic = 0;
    for (k, (&t, &m)) in theta.iter().zip(&expected).enumerate() {
        c.rotation[tip] = Some(UnitQuaternion::from_scaled_axis(Vector3::z() * t));
        rod.apply(&c, 1.0, k).unwrap();
        let torque = rod.residual(tip)[5];
        assert!(
            (torque - m).abs() < 1e-8 * m_max,
            "step {k}, theta {t}: rod {torque} vs uniform {m}"
        );
        if (m - 2.02e-3 * t / l).abs() > 1e-3 * m_max {
            plastic += 1;
        }
    }
    assert!(
        plastic > 10,
        "the cycle must be plastic ({plastic} plastic steps)"
    );
    assert!(rod.element_state(0).iter().any(|&s| s != 0.0));
}

/// The drivers' uniform-state shortcut is exact: tension and torsion through the 3D rod (clamped
/// ends, elastoplastic with hardening, control cycled 0 → c_max → −c_max/2 in steps of c_max/10)
/// give, step by step, the end reaction that `simulate_path` (the driver as run) and
/// `drive_uniform` (the sectional law at Γ₃ = Δl/L or K₃ = θ/L) compute without a rod.
#[test]
fn uniform_shortcuts_match_the_spatial_rod() {
    let law_for = |kind: TestKind, params: &[(&str, f64)]| {
        let map: BTreeMap<String, f64> = params.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        build(kind, "elastoplastic", &map).unwrap()
    };
    let cases = [
        (
            TestKind::Torsion,
            law_for(
                TestKind::Torsion,
                &[("GJ", 2.02e-3), ("M_y", 0.1), ("HI", 2e-4)],
            ),
            0.033,
            4.0,
        ),
        (
            TestKind::Tension,
            law_for(
                TestKind::Tension,
                &[("EA", 7.96e4), ("F_y", 54.0), ("H", 5e3)],
            ),
            0.032,
            8e-5,
        ),
    ];
    for (kind, law, l, c_max) in cases {
        let direct = simulate_path(
            &TestSetup::new(kind, l),
            law.as_ref(),
            &[c_max, -0.5 * c_max],
            Some(c_max / 10.0),
        )
        .unwrap();
        // Γ₃ or K₃; the rod lies along e₃, so it is also the spatial component of the reaction.
        let component = loaded_component(kind);
        let strain: Vec<f64> = direct.control.iter().map(|c| c / l).collect();
        let uniform = drive_uniform(law.as_ref(), component, &strain, &direct.time_s);
        let scale = direct.response.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let elastic = law.elastic_tangent()[(component, component)];
        let mut rod = SpatialRod::straight(law.as_ref(), l, 8).unwrap();
        rod.clamp(0);
        let tip = rod.nodes() - 1;
        rod.clamp(tip);
        let mut c = Controls::new(rod.nodes());
        let mut plastic = 0;
        for (k, (&ctrl, &d)) in direct.control.iter().zip(&direct.response).enumerate() {
            if kind == TestKind::Torsion {
                c.rotation[tip] = Some(UnitQuaternion::from_scaled_axis(Vector3::z() * ctrl));
            } else {
                c.position[tip] = Some(Vector3::new(0.0, 0.0, l + ctrl));
            }
            rod.apply(&c, 1.0, k).unwrap();
            let r = rod.residual(tip)[component];
            assert!(
                (r - d).abs() < 1e-8 * scale,
                "{kind}: rod {r} vs driver {d} at control {ctrl}"
            );
            assert!(
                (uniform[k] - d).abs() <= 1e-12 * scale,
                "{kind}: drive_uniform {} vs driver {d} at control {ctrl}",
                uniform[k]
            );
            if (d - elastic * ctrl / l).abs() > 1e-3 * scale {
                plastic += 1;
            }
        }
        assert!(
            plastic > 5,
            "{kind}: the cycle must be plastic ({plastic} plastic steps)"
        );
    }
}

/// The planar rod is the exact in-plane reduction of the 3D rod: the α = 10 cantilever at 32
/// elements through `scenarios::cantilever_tip_load` (planar) and through `SpatialRod` (load
/// across e₃ along e₁) gives the same tip deflection, shortening and rotation to solver
/// tolerance, not merely to discretisation error.
#[test]
fn planar_reduction_matches_the_spatial_rod() {
    let law = stiff_law();
    let planar = cantilever_tip_load(&law, 1.0, 32, 10.0, 10).unwrap();
    let mut rod = SpatialRod::straight(&law, 1.0, 32).unwrap();
    rod.clamp(0);
    let tip = rod.nodes() - 1;
    let mut c = Controls::new(rod.nodes());
    c.force[tip] = Vector3::new(10.0, 0.0, 0.0);
    rod.ramp(&c, 10).unwrap();
    let (w, u, phi) = (rod.x[tip].x, 1.0 - rod.x[tip].z, rod.rot[tip].angle());
    eprintln!(
        "planar vs spatial, alpha 10, 32 elements: w/L {:.3e}, u/L {:.3e}, rotation {:.3e} rel. difference",
        rel(w, planar.deflection_m),
        rel(u, planar.shortening_m),
        rel(phi, planar.rotation_rad)
    );
    assert!(
        rel(w, planar.deflection_m) < 1e-10,
        "w/L {w} vs {}",
        planar.deflection_m
    );
    assert!(
        rel(u, planar.shortening_m) < 1e-10,
        "u/L {u} vs {}",
        planar.shortening_m
    );
    assert!(
        rel(phi, planar.rotation_rad) < 1e-10,
        "rotation {phi} vs {}",
        planar.rotation_rad
    );
    // Far from the converged value at this mesh (the agreement above is not the table's).
    assert!(rel(w, 0.81061) > 1e-5);
}

/// Mesh convergence at α = 2: tip deflection with 4, 8, 16, 32, 64 elements converges at the
/// observed order 2 (midpoint-integrated two-node element) to the table value.
#[test]
fn cantilever_mesh_convergence_is_second_order() {
    let law = stiff_law();
    let w: Vec<f64> = [4, 8, 16, 32, 64]
        .iter()
        .map(|&n| {
            cantilever(
                &law,
                2.0,
                n,
                4,
                UnitQuaternion::identity(),
                Vector3::zeros(),
            )
            .w
        })
        .collect();
    eprintln!("tip deflection at 4..64 elements: {w:?}");
    for i in 0..w.len() - 2 {
        let order = ((w[i] - w[i + 1]) / (w[i + 1] - w[i + 2])).abs().log2();
        assert!(
            (order - 2.0).abs() < 0.1,
            "observed order {order} at {} elements ({w:?})",
            4 << i
        );
    }
    // Richardson extrapolation of the two finest meshes matches the table to its 5 digits.
    let extrapolated = w[4] + (w[4] - w[3]) / 3.0;
    assert!(
        (extrapolated - 0.49346).abs() < 1e-5,
        "extrapolated {extrapolated}"
    );
    assert!((w[4] - 0.49346).abs() < 1e-4, "64 elements: {}", w[4]);
}

/// A stress-free curved reference (nodes on an arc of curvature κ₀ = 2, 24 elements) is
/// unstressed as built, and a dead end moment −EI K₀ (K₀ its discrete reference curvature)
/// straightens it exactly.
#[test]
fn curved_reference_is_stress_free_and_straightens_under_its_moment() {
    let law = stiff_law();
    let kappa0 = 2.0;
    let n = 24;
    let ds = 1.0 / n as f64;
    let x: Vec<Vector3<f64>> = (0..=n)
        .map(|i| {
            let a = kappa0 * i as f64 * ds;
            Vector3::new(0.0, -(1.0 - a.cos()) / kappa0, a.sin() / kappa0)
        })
        .collect();
    let rot: Vec<UnitQuaternion<f64>> = (0..=n)
        .map(|i| UnitQuaternion::from_scaled_axis(Vector3::x() * (kappa0 * i as f64 * ds)))
        .collect();
    let mut rod = SpatialRod::from_reference(&law, x, rot).unwrap();
    rod.clamp(0);
    rod.evaluate().unwrap();
    assert!(rod.strains().iter().all(|s| s.amax() < 1e-12));
    assert!(rod.free_residual_norm() < 1e-9);
    let chord_sum: f64 = rod.reference_lengths().iter().sum();
    // Element lengths are the chords; the discrete reference curvature is the relative rotation
    // of the end frames over the chord, κ₀ ds / chord.
    let chord = 2.0 * (0.5 * kappa0 * ds).sin() / kappa0;
    assert!((chord_sum - n as f64 * chord).abs() < 1e-14);
    let mut c = Controls::new(rod.nodes());
    c.moment[n] = Vector3::new(-kappa0 * ds / chord, 0.0, 0.0);
    let stats = rod.ramp(&c, 4).unwrap();
    assert!(stats.newton_iterations > 0);
    assert!(
        (rod.x[n] - Vector3::new(0.0, 0.0, chord_sum)).norm() < 1e-9,
        "tip {}",
        rod.x[n]
    );
    assert!(rod.rot.iter().all(|q| q.angle() < 1e-9));
}

/// Step cutting rescues a step Newton cannot take at once: the α = 10 cantilever in a single
/// load step from the straight rod converges after bisections, to the table values.
#[test]
fn step_cutting_rescues_a_large_load_step() {
    let law = stiff_law();
    let mut rod = SpatialRod::straight(&law, 1.0, 64).unwrap();
    rod.clamp(0);
    let mut c = Controls::new(rod.nodes());
    c.force[64] = Vector3::new(10.0, 0.0, 0.0);
    let stats = rod.apply(&c, 0.0, 0).unwrap();
    assert!(stats.bisections > 0 && stats.substeps > 1, "{stats:?}");
    assert!(rel(rod.x[64].x, 0.81061) < 1e-3, "w/L {}", rod.x[64].x);
    assert!(
        rel(1.0 - rod.x[64].z, 0.55500) < 1e-3,
        "u/L {}",
        1.0 - rod.x[64].z
    );
    assert_eq!(rod.controls(), &c);
}

/// Pinned–pinned Euler elastica under displacement control (SPEC.md): ends pinned (positions
/// fixed, rotations free; the twist of one end held), the end is pushed to chord/L = 0.45695
/// from a bowed start; the axial reaction is then P/P_cr = 1.39320 (P_cr = π²EI/L²) and
/// the end slopes are 90°.
#[test]
fn pinned_elastica_at_ninety_degree_end_slope() {
    let law = stiff_law();
    let n = 64;
    let mut rod = SpatialRod::straight(&law, 1.0, n).unwrap();
    rod.fixed[0] = [true, true, true, false, false, true];
    rod.fixed[n] = [true, true, true, false, false, false];
    // Start from a bowed, unstretched shape (the straight compressed rod is an equilibrium too):
    // slope φ(s) = 0.3 cos(πs), frames turned about e_y, chords of the reference length.
    let le = 1.0 / n as f64;
    let phi = |s: f64| 0.3 * (PI * s).cos();
    for i in 0..=n {
        rod.rot[i] = UnitQuaternion::from_scaled_axis(Vector3::y() * phi(i as f64 * le));
        if i > 0 {
            let pm = phi((i as f64 - 0.5) * le);
            rod.x[i] = rod.x[i - 1] + Vector3::new(pm.sin(), 0.0, pm.cos()) * le;
        }
    }
    let mut c = Controls::new(rod.nodes());
    c.position[n] = Some(Vector3::new(0.0, 0.0, 0.45695));
    rod.ramp(&c, 20).unwrap();
    let p = -rod.residual(n)[2];
    let p_cr = PI * PI;
    eprintln!(
        "elastica: P/P_cr {:.6}, end slopes {:.6} {:.6}",
        p / p_cr,
        rod.rot[0].angle(),
        rod.rot[n].angle()
    );
    assert!(rel(p / p_cr, 1.39320) < 1e-3, "P/P_cr {}", p / p_cr);
    for i in [0, n] {
        let slope = rod.rot[i].angle();
        assert!(rel(slope, PI / 2.0) < 1e-3, "end slope {slope}");
    }
    assert!(rod.x.iter().all(|x| x.y.abs() < 1e-9), "stays in its plane");
}

/// Failures are errors with reasons, never panics: a free rod under a force is a mechanism,
/// a mesh too coarse for a full circle is reported, mismatched controls are rejected.
#[test]
fn failures_are_reported_with_reasons() {
    let law = stiff_law();
    let mut rod = SpatialRod::straight(&law, 1.0, 4).unwrap();
    let mut c = Controls::new(rod.nodes());
    c.force[4] = Vector3::new(1.0, 0.0, 0.0);
    match rod.apply(&c, 0.0, 7) {
        Err(RodError::NotConverged {
            step: 7, reason, ..
        }) => {
            assert!(reason.contains("singular tangent"), "{reason}")
        }
        other => panic!("expected a singular tangent, got {other:?}"),
    }
    let mut rod = SpatialRod::straight(&law, 1.0, 2).unwrap();
    rod.clamp(0);
    let mut c = Controls::new(rod.nodes());
    c.moment[2] = Vector3::new(2.0 * PI, 0.0, 0.0);
    rod.options.max_bisections = 3;
    match rod.ramp(&c, 1) {
        Err(RodError::NotConverged { reason, .. }) => {
            assert!(reason.contains("refine the mesh"), "{reason}");
            assert!(reason.contains("3 step cuts"), "{reason}");
        }
        other => panic!("expected a refine-the-mesh failure, got {other:?}"),
    }
    // The rod stays at its last converged state (unloaded here): strains are finite and small.
    assert!(rod.x.iter().all(|x| x.iter().all(|v| v.is_finite())));
    assert!(matches!(
        rod.apply(&Controls::new(5), 0.0, 0),
        Err(RodError::InvalidInput(_))
    ));
    let mut c = Controls::new(rod.nodes());
    c.rotation[1] = Some(UnitQuaternion::identity());
    assert!(matches!(
        rod.apply(&c, 0.0, 0),
        Err(RodError::InvalidInput(_))
    ));
    assert!(SpatialRod::straight(&law, -1.0, 4).is_err());
    assert!(SpatialRod::straight(&law, 1.0, 0).is_err());
}

/// Rotation vectors: exact near the identity and at large angles (used for tip rotations).
#[test]
fn rotation_vector_inverts_the_exponential() {
    for w in [
        Vector3::new(1e-9, -2e-9, 3e-9),
        Vector3::new(0.3, -1.2, 2.0),
        Vector3::new(0.0, 3.0, 0.0),
    ] {
        let back = rotation_vector(&UnitQuaternion::from_scaled_axis(w));
        assert!(
            (back - w).norm() <= 1e-14 * w.norm().max(1.0),
            "{w} -> {back}"
        );
    }
}

/// Timing of the α = 10 cantilever (32, 64 and 128 elements, 20 load steps): run with
/// `cargo test -p cablab-rod --test spatial -- --ignored --nocapture spatial_timing`.
#[test]
#[ignore = "timing report, no assertion on time"]
fn spatial_timing() {
    let law = stiff_law();
    for (elements, steps) in [(32, 20), (64, 20), (128, 20)] {
        // Best of five (the machine is shared).
        let mut best = f64::INFINITY;
        let mut last = None;
        for _ in 0..5 {
            let t0 = std::time::Instant::now();
            let c = cantilever(
                &law,
                10.0,
                elements,
                steps,
                UnitQuaternion::identity(),
                Vector3::zeros(),
            );
            best = best.min(t0.elapsed().as_secs_f64());
            last = Some(c);
        }
        let c = last.unwrap();
        println!(
            "spatial_timing: alpha 10, {elements} elements, {steps} load steps, {} Newton iterations ({} sub-steps, {} cuts), best of 5 {:.2} ms, w/L {:.5}",
            c.stats.newton_iterations,
            c.stats.substeps,
            c.stats.bisections,
            best * 1e3,
            c.w
        );
    }
}
