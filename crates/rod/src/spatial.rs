//! The static 3D geometrically exact (Simo–Reissner, shear-deformable Cosserat) rod with an
//! analytic consistent tangent: positions and unit quaternions per node, multiplicative
//! rotation-vector updates, load or displacement control with step cutting.
//!
//! Kinematics (chapter eqs. (8)–(10)): two-node elements with one (midpoint) integration point.
//! With Ψ = log(R_aᵀ R_b) the relative rotation vector of the end frames, the element strains are
//! K = Ψ/l₀ and Γ = R_mᵀ (x_b − x_a)/l₀ − e₃ with the midpoint frame R_m = R_a exp(Ψ/2)
//! (Crisfield–Jelenić: interpolating the *relative* rotation makes the strains objective and
//! path independent; one-point integration avoids shear locking). A stress-free reference
//! configuration may be curved: its strains are subtracted. Rotations are never linearised:
//! a Newton correction (Δx, Δθ) updates R ← exp(Δθ) R with the spatial spin Δθ, so any total
//! angle (a full circle, several turns of twist) is exact. The relative rotation of one element
//! must stay below [`MAX_ELEMENT_ROTATION_RAD`] (log is unique below π); a step that exceeds it
//! is rejected with a reason ("refine the mesh").
//!
//! Linearisation: with δΨ = J_l(Ψ)⁻¹ R_aᵀ (δθ_b − δθ_a) (J_l the left Jacobian of SO(3)) and the
//! midpoint spin δθ_m = δθ_a + P (δθ_b − δθ_a), P = ½ R_a J_l(Ψ/2) J_l(Ψ)⁻¹ R_aᵀ, the strain
//! matrix is
//! `δΓ = R_mᵀ (δx_b − δx_a)/l₀ + R_mᵀ d̂ δθ_m`, `δK = J_l(Ψ)⁻¹ R_aᵀ (δθ_b − δθ_a)/l₀`
//! (d = (x_b − x_a)/l₀). Internal forces are l₀ Bᵀσ (σ = [F, M] from the law, material frame);
//! the tangent is l₀ Bᵀ C B (C the law's consistent tangent) plus the geometric stiffness
//! ∂(l₀ Bᵀσ)/∂q at fixed σ, written out analytically (derivatives of the SO(3) Jacobians as
//! series near Ψ = 0). Unit tests check B and the geometric part against central differences.
//! Cost: one element evaluation is a few dozen 3×3 products; no finite differences anywhere.
//!
//! Loads and constraints:
//! - fixed degrees of freedom per node on the *increments* (x, y, z, θx, θy, θz spatial spins):
//!   clamped = all six, pinned = the three positions;
//! - displacement control: a prescribed position (fixed components only) and a prescribed
//!   orientation (all three spins fixed), reached along the straight line / the rotation geodesic
//!   from the last converged configuration (so one step must turn a node by less than π);
//! - dead (spatially fixed) nodal forces and moments. A dead moment is the spatial vector
//!   conjugate to the spatial spin: it has no potential in 3D (not conservative; the tangent is
//!   not symmetric even at equilibrium), which the non-symmetric block solve does not mind; its
//!   equilibria are well defined. For a moment about a fixed axis (plane bending, pure torsion) it
//!   coincides with the conservative "axial"/semi-tangential moment of Argyris;
//! - follower nodal moments, given in the node's director frame (they turn with the node), with
//!   their load stiffness in the tangent.
//!
//! Solver: Newton on the block-tridiagonal (6×6 blocks) system, solved in O(n) per iteration by
//! the crate's block Thomas solver (nalgebra LU per block); plain Newton for the first
//! iterations, then a Crisfield line search (secant on Δ·R, with residual backtracking). A control
//! step that fails is cut in half (at most [`SolverOptions::max_bisections`] cuts per step; the
//! sub-step doubles again after two easy sub-steps), and the law's internal variables are
//! committed only after each converged sub-step. Failures return [`RodError::NotConverged`]
//! with the reason (singular tangent = mechanism, non-finite residual, element rotation too large
//! for the mesh, no convergence), the residual and the iterations spent.
//!
//! Pure physics: numbers in, numbers out. Does not: contact, distributed loads, dynamics,
//! arc-length control (limit points under load control are not passed).

use crate::blocktri::{constrain, solve_block_tridiagonal, subtract_column};
use crate::newton::NewtonSystem;
use crate::planar::{SolverOptions, SMALL_CORRECTION};
use crate::RodError;
use cablab_laws::Law;
use nalgebra::{Matrix3, Matrix6, SMatrix, SVector, UnitQuaternion, Vector3, Vector6};

type V12 = SVector<f64, 12>;
type M12 = SMatrix<f64, 12, 12>;
type M3x12 = SMatrix<f64, 3, 12>;
type B6x12 = SMatrix<f64, 6, 12>;

/// Largest relative rotation of the two end frames of one element (rad). The rotation-vector
/// logarithm is unique below π; beyond this the mesh is too coarse for the deformation.
pub const MAX_ELEMENT_ROTATION_RAD: f64 = 2.5;
/// Below this angle the SO(3) Jacobian coefficients are evaluated by their Taylor series.
const SERIES_BELOW_RAD: f64 = 0.05;

/// Rotation vector (axis × angle, angle in [0, π]) of a unit quaternion, accurate near the
/// identity: 2 atan2(|v|, w) v/|v|.
pub fn rotation_vector(q: &UnitQuaternion<f64>) -> Vector3<f64> {
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

/// Coefficients of J_l(φ) = I + b φ̂ + c φ̂² at θ = |φ|: (b, b′/θ, c, c′/θ),
/// b = (1 − cos θ)/θ², c = (θ − sin θ)/θ³.
fn jl_coefs(t: f64) -> (f64, f64, f64, f64) {
    if t < SERIES_BELOW_RAD {
        let t2 = t * t;
        let t4 = t2 * t2;
        let t6 = t4 * t2;
        (
            0.5 - t2 / 24.0 + t4 / 720.0 - t6 / 40320.0,
            -1.0 / 12.0 + t2 / 180.0 - t4 / 6720.0,
            1.0 / 6.0 - t2 / 120.0 + t4 / 5040.0 - t6 / 362880.0,
            -1.0 / 60.0 + t2 / 1260.0 - t4 / 60480.0,
        )
    } else {
        let s = t.sin();
        let one_minus_cos = 2.0 * (0.5 * t).sin().powi(2);
        let t2 = t * t;
        let t3 = t2 * t;
        let t4 = t2 * t2;
        let b = one_minus_cos / t2;
        let db = (t * s - 2.0 * one_minus_cos) / t4;
        let cc = (t - s) / t3;
        let dc = (one_minus_cos / t3 - 3.0 * (t - s) / t4) / t;
        (b, db, cc, dc)
    }
}

/// Coefficient of J_l(φ)⁻¹ = I − ½ φ̂ + c φ̂² at θ = |φ|: (c, c′/θ),
/// c = 1/θ² − cot(θ/2)/(2θ).
fn jl_inv_coefs(t: f64) -> (f64, f64) {
    if t < SERIES_BELOW_RAD {
        let t2 = t * t;
        let t4 = t2 * t2;
        let t6 = t4 * t2;
        (
            1.0 / 12.0 + t2 / 720.0 + t4 / 30240.0 + t6 / 1209600.0,
            1.0 / 360.0 + t2 / 7560.0 + t4 / 201600.0,
        )
    } else {
        let h = 0.5 * t;
        let cot = h.cos() / h.sin();
        let csc2 = 1.0 / h.sin().powi(2);
        let t2 = t * t;
        let c = 1.0 / t2 - cot / (2.0 * t);
        let dc = (-2.0 / (t2 * t) + cot / (2.0 * t2) + csc2 / (4.0 * t)) / t;
        (c, dc)
    }
}

/// The matrix I + b ψ̂ + c ψ̂².
fn series_matrix(psi: &Vector3<f64>, b: f64, c: f64) -> Matrix3<f64> {
    let h = psi.cross_matrix();
    Matrix3::identity() + h * b + h * h * c
}

/// ∂/∂ψ [(I + b(θ) ψ̂ + c(θ) ψ̂²) u] at fixed u, given b, b′/θ, c, c′/θ.
fn series_derivative(
    psi: &Vector3<f64>,
    u: &Vector3<f64>,
    (b, db, c, dc): (f64, f64, f64, f64),
) -> Matrix3<f64> {
    let pu = psi.cross(u);
    let ppu = psi.cross(&pu);
    pu * psi.transpose() * db - u.cross_matrix() * b
        + ppu * psi.transpose() * dc
        + (Matrix3::identity() * psi.dot(u) + psi * u.transpose() - u * psi.transpose() * 2.0) * c
}

/// Kinematics of one element: raw strains, strain matrix B = ∂ε/∂(δx_a, δθ_a, δx_b, δθ_b) and
/// the intermediate quantities the geometric stiffness needs.
#[derive(Debug, Clone)]
struct Kinematics {
    strain: Vector6<f64>,
    b: B6x12,
    ra: Matrix3<f64>,
    rm: Matrix3<f64>,
    d: Vector3<f64>,
    psi: Vector3<f64>,
    /// J_l(Ψ)⁻¹.
    t: Matrix3<f64>,
    /// P = ½ R_a J_l(Ψ/2) J_l(Ψ)⁻¹ R_aᵀ.
    p: Matrix3<f64>,
}

/// Element kinematics between the frames (x_a, q_a) and (x_b, q_b) of reference length `l0`.
fn kinematics(
    xa: &Vector3<f64>,
    qa: &UnitQuaternion<f64>,
    xb: &Vector3<f64>,
    qb: &UnitQuaternion<f64>,
    l0: f64,
) -> Kinematics {
    let ra = qa.to_rotation_matrix().into_inner();
    let psi = rotation_vector(&(qa.inverse() * qb));
    let th = psi.norm();
    let rm = (qa * UnitQuaternion::from_scaled_axis(psi * 0.5))
        .to_rotation_matrix()
        .into_inner();
    let d = (xb - xa) / l0;
    let gam = rm.transpose() * d - Vector3::z();
    let (c2, _) = jl_inv_coefs(th);
    let t = series_matrix(&psi, -0.5, c2);
    let (bh, _, ch, _) = jl_coefs(0.5 * th);
    let jl_half = series_matrix(&(psi * 0.5), bh, ch);
    let p = ra * jl_half * t * ra.transpose() * 0.5;
    let inv = 1.0 / l0;
    let i3 = Matrix3::identity();
    let rmt = rm.transpose();
    let rmt_d = rmt * d.cross_matrix();
    let t_rat = t * ra.transpose() * inv;
    let mut b = B6x12::zeros();
    b.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-rmt * inv));
    b.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(rmt_d * (i3 - p)));
    b.fixed_view_mut::<3, 3>(0, 6).copy_from(&(rmt * inv));
    b.fixed_view_mut::<3, 3>(0, 9).copy_from(&(rmt_d * p));
    b.fixed_view_mut::<3, 3>(3, 3).copy_from(&(-t_rat));
    b.fixed_view_mut::<3, 3>(3, 9).copy_from(&t_rat);
    Kinematics {
        strain: Vector6::new(gam.x, gam.y, gam.z, psi.x * inv, psi.y * inv, psi.z * inv),
        b,
        ra,
        rm,
        d,
        psi,
        t,
        p,
    }
}

/// Geometric stiffness ∂(l₀ Bᵀσ)/∂(δx_a, δθ_a, δx_b, δθ_b) at fixed σ = [F, M].
///
/// With n = R_m F, w = n × d and z = R_a J_r(Ψ)⁻¹ (½ l₀ J_r(Ψ/2) R_aᵀ w + M) the element forces
/// are (−n, l₀ w − z, n, z); each of n, w, z is differentiated by the chain rule.
fn geometric_stiffness(k: &Kinematics, sig: &Vector6<f64>, l0: f64) -> M12 {
    let f = Vector3::new(sig[0], sig[1], sig[2]);
    let m = Vector3::new(sig[3], sig[4], sig[5]);
    let i3 = Matrix3::identity();
    let n = k.rm * f;
    let w = n.cross(&k.d);
    let mut dd = M3x12::zeros();
    dd.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-i3 / l0));
    dd.fixed_view_mut::<3, 3>(0, 6).copy_from(&(i3 / l0));
    let mut dthm = M3x12::zeros();
    dthm.fixed_view_mut::<3, 3>(0, 3).copy_from(&(i3 - k.p));
    dthm.fixed_view_mut::<3, 3>(0, 9).copy_from(&k.p);
    let mut dtha = M3x12::zeros();
    dtha.fixed_view_mut::<3, 3>(0, 3).copy_from(&i3);
    let mut dphi = M3x12::zeros();
    dphi.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-i3));
    dphi.fixed_view_mut::<3, 3>(0, 9).copy_from(&i3);
    let dpsi = k.t * k.ra.transpose() * dphi;
    let nx = n.cross_matrix();
    let dn = -nx * dthm;
    let dw = k.d.cross_matrix() * nx * dthm + nx * dd;
    let rat = k.ra.transpose();
    let v = rat * w;
    let dv = rat * w.cross_matrix() * dtha + rat * dw;
    // g = J_r(Ψ/2) v = (I − b φ̂ + c φ̂²) v with φ = Ψ/2.
    let half = k.psi * 0.5;
    let th = k.psi.norm();
    let (bh, dbh, ch, dch) = jl_coefs(0.5 * th);
    let jr_half = series_matrix(&half, -bh, ch);
    let g = jr_half * v;
    let dg = series_derivative(&half, &v, (-bh, -dbh, ch, dch)) * 0.5;
    let u = g * (0.5 * l0) + m;
    let du = (dg * dpsi + jr_half * dv) * (0.5 * l0);
    // y = J_r(Ψ)⁻¹ u = (I + ½ Ψ̂ + c Ψ̂²) u.
    let (c2, dc2) = jl_inv_coefs(th);
    let jr_inv = series_matrix(&k.psi, 0.5, c2);
    let y = jr_inv * u;
    let dy = series_derivative(&k.psi, &u, (0.5, 0.0, c2, dc2)) * dpsi + jr_inv * du;
    let z = k.ra * y;
    let dz = -z.cross_matrix() * dtha + k.ra * dy;
    let mut out = M12::zeros();
    out.fixed_view_mut::<3, 12>(0, 0).copy_from(&(-dn));
    out.fixed_view_mut::<3, 12>(3, 0).copy_from(&(dw * l0 - dz));
    out.fixed_view_mut::<3, 12>(6, 0).copy_from(&dn);
    out.fixed_view_mut::<3, 12>(9, 0).copy_from(&dz);
    out
}

/// Loads and prescribed values of one state of the control history (one entry per node).
#[derive(Debug, Clone, PartialEq)]
pub struct Controls {
    /// Dead nodal forces (spatial components), N.
    pub force: Vec<Vector3<f64>>,
    /// Dead nodal moments (spatially fixed vectors, conjugate to the spatial spins), N m.
    pub moment: Vec<Vector3<f64>>,
    /// Follower nodal moments, components in the node's director frame, N m.
    pub follower_moment: Vec<Vector3<f64>>,
    /// Prescribed node positions, m: only the components whose increments are fixed are used;
    /// `None` holds the current position.
    pub position: Vec<Option<Vector3<f64>>>,
    /// Prescribed node orientations (all three spins of the node must be fixed); `None` holds
    /// the current orientation.
    pub rotation: Vec<Option<UnitQuaternion<f64>>>,
}

impl Controls {
    /// No loads, nothing prescribed, for a rod of `nodes` nodes.
    pub fn new(nodes: usize) -> Self {
        Controls {
            force: vec![Vector3::zeros(); nodes],
            moment: vec![Vector3::zeros(); nodes],
            follower_moment: vec![Vector3::zeros(); nodes],
            position: vec![None; nodes],
            rotation: vec![None; nodes],
        }
    }

    /// Loads at fraction `lam` between `self` (λ = 0) and `target` (λ = 1); prescribed values
    /// from the configuration (`x0`, `q0`) at λ = 0 along straight lines / rotation geodesics.
    fn interpolate(
        &self,
        target: &Controls,
        x0: &[Vector3<f64>],
        q0: &[UnitQuaternion<f64>],
        lam: f64,
    ) -> Controls {
        let lin = |a: &[Vector3<f64>], b: &[Vector3<f64>]| -> Vec<Vector3<f64>> {
            a.iter().zip(b).map(|(a, b)| a + (b - a) * lam).collect()
        };
        Controls {
            force: lin(&self.force, &target.force),
            moment: lin(&self.moment, &target.moment),
            follower_moment: lin(&self.follower_moment, &target.follower_moment),
            position: target
                .position
                .iter()
                .zip(x0)
                .map(|(p, x)| p.map(|p| x + (p - x) * lam))
                .collect(),
            rotation: target
                .rotation
                .iter()
                .zip(q0)
                .map(|(r, q)| {
                    r.map(|r| {
                        UnitQuaternion::from_scaled_axis(rotation_vector(&(r * q.inverse())) * lam)
                            * q
                    })
                })
                .collect(),
        }
    }
}

/// What one control step cost.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StepStats {
    /// Newton iterations over all converged sub-steps (failed attempts not counted).
    pub newton_iterations: usize,
    /// Converged sub-steps (1 when the step was not cut).
    pub substeps: usize,
    /// Times the step was cut in half.
    pub bisections: usize,
}

impl std::ops::AddAssign for StepStats {
    fn add_assign(&mut self, o: StepStats) {
        self.newton_iterations += o.newton_iterations;
        self.substeps += o.substeps;
        self.bisections += o.bisections;
    }
}

/// The 3D rod: mesh, configuration, constraints, applied controls and law state per element.
#[derive(Debug)]
pub struct SpatialRod<'a> {
    law: &'a dyn Law,
    /// Element reference lengths, m.
    l0: Vec<f64>,
    /// Node positions, m.
    pub x: Vec<Vector3<f64>>,
    /// Node director frames R = [a₁ a₂ a₃] as unit quaternions.
    pub rot: Vec<UnitQuaternion<f64>>,
    /// Fixed increments per node (x, y, z, θx, θy, θz; spatial axes): clamped = all six.
    pub fixed: Vec<[bool; 6]>,
    /// Newton controls.
    pub options: SolverOptions,
    controls: Controls,
    current: Controls,
    eps0: Vec<Vector6<f64>>,
    n_state: usize,
    state: Vec<f64>,
    trial: Vec<f64>,
    strain: Vec<Vector6<f64>>,
    stress: Vec<Vector6<f64>>,
    res: Vec<Vector6<f64>>,
    diag: Vec<Matrix6<f64>>,
    upper: Vec<Matrix6<f64>>,
    lower: Vec<Matrix6<f64>>,
    work: Vec<Matrix6<f64>>,
    force_scale: f64,
    length_scale: f64,
    newton: NewtonBuffers,
}

impl<'a> SpatialRod<'a> {
    /// A rod whose stress-free reference configuration is given by node positions and director
    /// frames (straight or curved; the reference strains are subtracted from the law's input).
    /// Element lengths are the chords between nodes, so the discrete reference curvature is the
    /// relative rotation of the end frames over the chord (for nodes on an arc of curvature κ₀,
    /// slightly more than κ₀: κ₀ Δs / chord).
    pub fn from_reference(
        law: &'a dyn Law,
        x: Vec<Vector3<f64>>,
        rot: Vec<UnitQuaternion<f64>>,
    ) -> Result<Self, RodError> {
        if x.len() < 2 || x.len() != rot.len() {
            return Err(RodError::InvalidSetup(format!(
                "the rod needs at least two nodes with one frame each (got {} positions, {} frames)",
                x.len(),
                rot.len()
            )));
        }
        let c = law.elastic_tangent();
        if !(0..6).all(|i| c[(i, i)].is_finite() && c[(i, i)] > 0.0) {
            return Err(RodError::InvalidSetup(format!(
                "law '{}' must have a positive elastic stiffness in all six components for the 3D rod (diagonal {:?})",
                law.name(),
                c.diagonal().as_slice()
            )));
        }
        let mut l0 = Vec::with_capacity(x.len() - 1);
        let mut eps0 = Vec::with_capacity(x.len() - 1);
        for e in 0..x.len() - 1 {
            let le = (x[e + 1] - x[e]).norm();
            if !(le.is_finite() && le > 0.0) {
                return Err(RodError::InvalidSetup(format!(
                    "element {e} has length {le} m (nodes must be distinct and finite)"
                )));
            }
            let k = kinematics(&x[e], &rot[e], &x[e + 1], &rot[e + 1], le);
            if k.psi.norm() > MAX_ELEMENT_ROTATION_RAD {
                return Err(RodError::InvalidSetup(format!(
                    "element {e}: its end frames differ by {:.3} rad (> {MAX_ELEMENT_ROTATION_RAD}); refine the reference mesh",
                    k.psi.norm()
                )));
            }
            l0.push(le);
            eps0.push(k.strain);
        }
        let length: f64 = l0.iter().sum();
        let ei = c[(3, 3)].max(c[(4, 4)]);
        let elements = l0.len();
        let n_state = law.n_state();
        let mut state = vec![0.0; n_state * elements];
        for e in 0..elements {
            law.init_state(&mut state[e * n_state..(e + 1) * n_state]);
        }
        let nodes = x.len();
        Ok(SpatialRod {
            law,
            l0,
            x,
            rot,
            fixed: vec![[false; 6]; nodes],
            options: SolverOptions::default(),
            controls: Controls::new(nodes),
            current: Controls::new(nodes),
            eps0,
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
            force_scale: ei / (length * length),
            length_scale: length,
            newton: NewtonBuffers::default(),
        })
    }

    /// A straight, unstressed rod from `origin` along `frame`·e₃ with directors `frame`,
    /// `elements` equal elements over `length_m`.
    pub fn straight_along(
        law: &'a dyn Law,
        length_m: f64,
        elements: usize,
        origin: Vector3<f64>,
        frame: UnitQuaternion<f64>,
    ) -> Result<Self, RodError> {
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
        let le = length_m / elements as f64;
        let axis = frame * Vector3::z();
        let x = (0..=elements)
            .map(|i| origin + axis * (i as f64 * le))
            .collect();
        SpatialRod::from_reference(law, x, vec![frame; elements + 1])
    }

    /// A straight, unstressed rod along +z from the origin (directors = global axes).
    pub fn straight(law: &'a dyn Law, length_m: f64, elements: usize) -> Result<Self, RodError> {
        SpatialRod::straight_along(
            law,
            length_m,
            elements,
            Vector3::zeros(),
            UnitQuaternion::identity(),
        )
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.x.len()
    }

    /// Number of elements (= integration points).
    pub fn elements(&self) -> usize {
        self.l0.len()
    }

    /// Element reference lengths, m.
    pub fn reference_lengths(&self) -> &[f64] {
        &self.l0
    }

    /// Clamp node `i` (all six increments fixed); out-of-range indices are ignored.
    pub fn clamp(&mut self, i: usize) {
        if let Some(f) = self.fixed.get_mut(i) {
            *f = [true; 6];
        }
    }

    /// The controls of the last converged state.
    pub fn controls(&self) -> &Controls {
        &self.controls
    }

    /// Element strains [Γ, K] (minus the reference strains) at the last evaluation.
    pub fn strains(&self) -> &[Vector6<f64>] {
        &self.strain
    }

    /// Element stress resultants [F, M] (material frame) at the last evaluation.
    pub fn stresses(&self) -> &[Vector6<f64>] {
        &self.stress
    }

    /// Committed internal law variables of element `e` (empty for an out-of-range index).
    pub fn element_state(&self, e: usize) -> &[f64] {
        let ns = self.n_state;
        self.state.get(e * ns..(e + 1) * ns).unwrap_or(&[])
    }

    /// Residual at node `i` (internal − external force, moment; spatial components) at the last
    /// evaluation. At fixed degrees of freedom it is the reaction the support exerts on the rod.
    pub fn residual(&self, i: usize) -> Vector6<f64> {
        self.res.get(i).copied().unwrap_or_else(Vector6::zeros)
    }

    /// Euclidean norm of the residual over the free degrees of freedom (moments divided by the rod
    /// length, so that all entries are forces), N, at the last evaluation.
    pub fn free_residual_norm(&self) -> f64 {
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

    /// Evaluate strains, stresses and the residual at the current configuration and the controls
    /// of the last converged state (trial law update from the committed state, dt = 0).
    /// Fails only when `x`, `rot` or `fixed` no longer have one entry per node.
    pub fn evaluate(&mut self) -> Result<(), RodError> {
        self.check_controls(&self.controls)?;
        self.current = self.controls.clone();
        let _ = self.assemble(0.0, false);
        Ok(())
    }

    /// Rigid motion of the whole problem: positions x ← g x + shift, frames R ← g R, dead forces,
    /// dead moments and prescribed values turned with it (follower moments are material and stay).
    /// Law states are untouched: strains are objective, so the state stays valid.
    pub fn transform_rigidly(&mut self, g: &UnitQuaternion<f64>, shift: &Vector3<f64>) {
        for x in &mut self.x {
            *x = g * *x + shift;
        }
        for r in &mut self.rot {
            *r = g * *r;
        }
        let c = &mut self.controls;
        c.force.iter_mut().for_each(|f| *f = g * *f);
        c.moment.iter_mut().for_each(|m| *m = g * *m);
        c.position
            .iter_mut()
            .flatten()
            .for_each(|p| *p = g * *p + shift);
        c.rotation.iter_mut().flatten().for_each(|r| *r = g * *r);
    }

    /// Assemble residual (and tangent). Returns the first element whose relative rotation
    /// exceeds [`MAX_ELEMENT_ROTATION_RAD`] as an error.
    fn assemble(&mut self, dt: f64, tangent: bool) -> Result<(), (usize, f64)> {
        let ns = self.n_state;
        self.res.iter_mut().for_each(|r| *r = Vector6::zeros());
        if tangent {
            self.diag.iter_mut().for_each(|m| *m = Matrix6::zeros());
            self.upper.iter_mut().for_each(|m| *m = Matrix6::zeros());
            self.lower.iter_mut().for_each(|m| *m = Matrix6::zeros());
        }
        let mut too_big = None;
        for e in 0..self.l0.len() {
            let l0 = self.l0[e];
            let k = kinematics(
                &self.x[e],
                &self.rot[e],
                &self.x[e + 1],
                &self.rot[e + 1],
                l0,
            );
            let angle = k.psi.norm();
            if angle > MAX_ELEMENT_ROTATION_RAD && too_big.is_none() {
                too_big = Some((e, angle));
            }
            let eps = k.strain - self.eps0[e];
            let resp = self.law.update(
                &eps,
                dt,
                &self.state[e * ns..(e + 1) * ns],
                &mut self.trial[e * ns..(e + 1) * ns],
            );
            let sig = resp.stress;
            self.strain[e] = eps;
            self.stress[e] = sig;
            let f: V12 = k.b.transpose() * sig * l0;
            for d in 0..6 {
                self.res[e][d] += f[d];
                self.res[e + 1][d] += f[6 + d];
            }
            if tangent {
                let km: M12 =
                    k.b.transpose() * resp.tangent * k.b * l0 + geometric_stiffness(&k, &sig, l0);
                self.diag[e] += km.fixed_view::<6, 6>(0, 0);
                self.diag[e + 1] += km.fixed_view::<6, 6>(6, 6);
                self.upper[e] += km.fixed_view::<6, 6>(0, 6);
                self.lower[e] += km.fixed_view::<6, 6>(6, 0);
            }
        }
        for i in 0..self.x.len() {
            let follower = self.rot[i] * self.current.follower_moment[i];
            for d in 0..3 {
                self.res[i][d] -= self.current.force[i][d];
                self.res[i][3 + d] -= self.current.moment[i][d] + follower[d];
            }
            if tangent && follower != Vector3::zeros() {
                let mut blk = self.diag[i].fixed_view_mut::<3, 3>(3, 3);
                blk += follower.cross_matrix();
            }
        }
        match too_big {
            Some(t) => Err(t),
            None => Ok(()),
        }
    }

    fn reference_force(&self) -> f64 {
        let mut f = self.force_scale;
        for (i, r) in self.res.iter().enumerate() {
            f = f
                .max(self.current.force[i].norm())
                .max(self.current.moment[i].norm() / self.length_scale)
                .max(self.current.follower_moment[i].norm() / self.length_scale);
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

    /// Check that a set of controls fits the rod and its constraints.
    fn check_controls(&self, c: &Controls) -> Result<(), RodError> {
        let n = self.l0.len() + 1;
        if self.x.len() != n || self.rot.len() != n || self.fixed.len() != n {
            return Err(RodError::InvalidSetup(format!(
                "positions, frames and fixities need one entry per node ({n} nodes; got {}, {}, {})",
                self.x.len(),
                self.rot.len(),
                self.fixed.len()
            )));
        }
        if c.force.len() != n
            || c.moment.len() != n
            || c.follower_moment.len() != n
            || c.position.len() != n
            || c.rotation.len() != n
        {
            return Err(RodError::InvalidInput(format!(
                "controls must have one entry per node ({n} nodes)"
            )));
        }
        for i in 0..n {
            let finite = |v: &Vector3<f64>| v.iter().all(|x| x.is_finite());
            if !(finite(&c.force[i]) && finite(&c.moment[i]) && finite(&c.follower_moment[i])) {
                return Err(RodError::InvalidInput(format!(
                    "node {i}: loads must be finite"
                )));
            }
            if let Some(p) = c.position[i] {
                if !finite(&p) || !self.fixed[i][..3].iter().any(|&f| f) {
                    return Err(RodError::InvalidInput(format!(
                        "node {i}: a prescribed position must be finite and needs fixed position components"
                    )));
                }
            }
            if let Some(r) = c.rotation[i] {
                if !r.coords.iter().all(|x| x.is_finite()) || !self.fixed[i][3..].iter().all(|&f| f)
                {
                    return Err(RodError::InvalidInput(format!(
                        "node {i}: a prescribed rotation must be finite and needs all three rotations fixed"
                    )));
                }
            }
        }
        Ok(())
    }

    /// Move from the last converged state to `target` (loads linearly, prescribed values along
    /// lines / rotation geodesics) in one step of duration `dt` seconds, cutting it in half when
    /// Newton fails. Law states are committed after each converged sub-step. `step` labels errors.
    /// On failure the rod stays at the last converged sub-step.
    pub fn apply(
        &mut self,
        target: &Controls,
        dt: f64,
        step: usize,
    ) -> Result<StepStats, RodError> {
        self.check_controls(target)?;
        if !dt.is_finite() || dt < 0.0 {
            return Err(RodError::InvalidInput(format!(
                "step duration must be finite and non-negative, got {dt} s"
            )));
        }
        let start = self.controls.clone();
        let (xs, qs) = (self.x.clone(), self.rot.clone());
        let mut stats = StepStats::default();
        let (mut done, mut inc) = (0.0_f64, 1.0_f64);
        let mut streak = 0;
        while done < 1.0 {
            let lam = (done + inc).min(1.0);
            self.current = start.interpolate(target, &xs, &qs, lam);
            let (x0, q0) = (self.x.clone(), self.rot.clone());
            match self.newton(dt * (lam - done), step) {
                Ok(it) => {
                    stats.newton_iterations += it;
                    stats.substeps += 1;
                    self.commit();
                    self.controls = self.current.clone();
                    done = lam;
                    // Two easy sub-steps in a row: try a step twice as long again.
                    streak += 1;
                    if streak >= 2 && inc < 1.0 {
                        inc *= 2.0;
                        streak = 0;
                    }
                }
                Err(err) => {
                    self.x = x0;
                    self.rot = q0;
                    if stats.bisections >= self.options.max_bisections {
                        self.current = self.controls.clone();
                        let _ = self.assemble(0.0, false);
                        return Err(match err {
                            RodError::NotConverged {
                                step,
                                iterations,
                                residual,
                                reason,
                            } => RodError::NotConverged {
                                step,
                                iterations,
                                residual,
                                reason: format!(
                                    "{reason}; after {} step cuts (reached {done:.4} of the step)",
                                    stats.bisections
                                ),
                            },
                            other => other,
                        });
                    }
                    stats.bisections += 1;
                    streak = 0;
                    inc *= 0.5;
                }
            }
        }
        self.controls = target.clone();
        Ok(stats)
    }

    /// Reach `target` from the last converged state in `steps` equal quasi-static steps (dt = 0).
    /// Prescribed rotations are interpolated along the shortest geodesic, so a ramped prescribed
    /// rotation must differ from the start by less than π (use [`apply`](Self::apply) step by step
    /// for several turns).
    pub fn ramp(&mut self, target: &Controls, steps: usize) -> Result<StepStats, RodError> {
        self.check_controls(target)?;
        let steps = steps.max(1);
        let start = self.controls.clone();
        let (xs, qs) = (self.x.clone(), self.rot.clone());
        let mut stats = StepStats::default();
        for k in 1..=steps {
            let c = start.interpolate(target, &xs, &qs, k as f64 / steps as f64);
            stats += self.apply(&c, 0.0, k)?;
        }
        self.controls = target.clone();
        Ok(stats)
    }

    /// Newton's method for the loads and prescribed values in `self.current`
    /// ([`crate::newton::solve`]).
    fn newton(&mut self, dt: f64, step: usize) -> Result<usize, RodError> {
        let options = self.options;
        crate::newton::solve(self, &options, dt, step)
    }

    /// Accept the converged state: trial law states become committed.
    fn commit(&mut self) {
        self.state.copy_from_slice(&self.trial);
    }
}

impl NewtonSystem for SpatialRod<'_> {
    /// Prescribed increments of positions and spins (the rotation vector from the current frame
    /// to the prescribed one).
    fn prescribe(&mut self) -> bool {
        let n = self.nodes();
        self.newton.pres.clear();
        self.newton.pres.resize(n, Vector6::zeros());
        for i in 0..n {
            if let Some(p) = self.current.position[i] {
                for k in 0..3 {
                    if self.fixed[i][k] {
                        self.newton.pres[i][k] = p[k] - self.x[i][k];
                    }
                }
            }
            if let Some(r) = self.current.rotation[i] {
                let w = rotation_vector(&(r * self.rot[i].inverse()));
                self.newton.pres[i].fixed_rows_mut::<3>(3).copy_from(&w);
            }
        }
        self.newton.pres.iter().any(|p| p.iter().any(|&v| v != 0.0))
    }

    fn assemble(&mut self, dt: f64) -> Result<(), String> {
        SpatialRod::assemble(self, dt, true).map_err(|(e, a)| {
            format!(
                "element {e} turned by {a:.3} rad (> {MAX_ELEMENT_ROTATION_RAD} rad) relative to its neighbour: refine the mesh"
            )
        })
    }

    fn free_residual_norm(&self) -> f64 {
        SpatialRod::free_residual_norm(self)
    }

    fn reference_force(&self) -> f64 {
        SpatialRod::reference_force(self)
    }

    #[allow(clippy::needless_range_loop)] // several per-node arrays indexed together
    fn correction(&mut self, pending: bool) -> Result<(), usize> {
        let n = self.nodes();
        let NewtonBuffers { pres, dq, .. } = &mut self.newton;
        dq.clear();
        dq.extend(self.res.iter().map(|r| -r));
        if pending {
            // Move the prescribed increments to the right-hand side through the tangent.
            for i in 0..n {
                for d in 0..6 {
                    let delta = pres[i][d];
                    if !self.fixed[i][d] || delta == 0.0 {
                        continue;
                    }
                    subtract_column(&self.diag, &self.upper, &self.lower, dq, (i, d), delta);
                }
            }
        }
        for i in 0..n {
            for d in 0..6 {
                if self.fixed[i][d] {
                    constrain(&mut self.diag, &mut self.upper, &mut self.lower, (i, d));
                    dq[i][d] = if pending { pres[i][d] } else { 0.0 };
                }
            }
        }
        self.newton.landing = pending;
        solve_block_tridiagonal(
            &self.diag,
            &self.upper,
            &self.lower,
            &mut self.newton.dq,
            &mut self.work,
        )
    }

    fn correction_is_small(&self) -> bool {
        self.newton.dq.iter().all(|d| {
            d.fixed_rows::<3>(0).amax() <= SMALL_CORRECTION * self.length_scale
                && d.fixed_rows::<3>(3).amax() <= SMALL_CORRECTION
        })
    }

    fn save(&mut self) {
        self.newton.x0.clone_from(&self.x);
        self.newton.q0.clone_from(&self.rot);
    }

    fn restore(&mut self) {
        self.x.clone_from(&self.newton.x0);
        self.rot.clone_from(&self.newton.q0);
    }

    /// (x₀, q₀) moved by α Δ (spins applied multiplicatively, spatially); in the step that
    /// applies prescribed increments, landing exactly on the prescribed values.
    fn move_along(&mut self, alpha: f64) {
        let NewtonBuffers { dq, x0, q0, .. } = &self.newton;
        for i in 0..x0.len() {
            let d = dq[i] * alpha;
            self.x[i] = x0[i] + Vector3::new(d[0], d[1], d[2]);
            let mut q = UnitQuaternion::from_scaled_axis(Vector3::new(d[3], d[4], d[5])) * q0[i];
            q.renormalize_fast();
            self.rot[i] = q;
        }
        if self.newton.landing {
            for i in 0..self.x.len() {
                if let Some(p) = self.current.position[i] {
                    for k in 0..3 {
                        if self.fixed[i][k] {
                            self.x[i][k] = p[k];
                        }
                    }
                }
                if let Some(r) = self.current.rotation[i] {
                    self.rot[i] = r;
                }
            }
        }
    }

    /// Σ over free dofs of Δ·R, the line-search function.
    fn directional(&self) -> f64 {
        let mut s = 0.0;
        for (i, (r, d)) in self.res.iter().zip(&self.newton.dq).enumerate() {
            for k in 0..6 {
                if !self.fixed[i][k] {
                    s += r[k] * d[k];
                }
            }
        }
        s
    }
}

/// Newton's work vectors, kept between steps (no allocation per iteration).
#[derive(Debug, Clone, Default)]
struct NewtonBuffers {
    /// Prescribed increments of this step, per node.
    pres: Vec<Vector6<f64>>,
    /// The correction Δ.
    dq: Vec<Vector6<f64>>,
    /// The configuration Δ starts from.
    x0: Vec<Vector3<f64>>,
    q0: Vec<UnitQuaternion<f64>>,
    /// Whether the current correction applies prescribed increments.
    landing: bool,
}

#[cfg(test)]
mod tests {
    use super::*;
    use cablab_laws::{LinearElastic, SectionStiffness};

    fn config() -> (
        Vector3<f64>,
        UnitQuaternion<f64>,
        Vector3<f64>,
        UnitQuaternion<f64>,
    ) {
        (
            Vector3::new(0.1, 0.2, -0.05),
            UnitQuaternion::from_scaled_axis(Vector3::new(0.2, -0.4, 0.1)),
            Vector3::new(0.18, 0.27, 0.25),
            UnitQuaternion::from_scaled_axis(Vector3::new(0.9, 0.3, -0.7)),
        )
    }

    fn perturbed(
        x: [Vector3<f64>; 2],
        q: [UnitQuaternion<f64>; 2],
        j: usize,
        h: f64,
    ) -> ([Vector3<f64>; 2], [UnitQuaternion<f64>; 2]) {
        let (mut x, mut q) = (x, q);
        let (node, k) = (j / 6, j % 6);
        if k < 3 {
            x[node][k] += h;
        } else {
            let mut w = Vector3::zeros();
            w[k - 3] = h;
            q[node] = UnitQuaternion::from_scaled_axis(w) * q[node];
        }
        (x, q)
    }

    /// The Jacobian-series coefficients agree with their closed forms across the switch angle,
    /// and the stated derivative ratios match differences of the coefficients.
    #[test]
    fn series_coefficients_are_continuous_and_differentiate() {
        let below = SERIES_BELOW_RAD * (1.0 - 1e-9);
        let above = SERIES_BELOW_RAD * (1.0 + 1e-9);
        let (a, b) = (jl_coefs(below), jl_coefs(above));
        assert!((a.0 - b.0).abs() < 1e-12 && (a.2 - b.2).abs() < 1e-12);
        assert!((a.1 - b.1).abs() < 1e-9 && (a.3 - b.3).abs() < 1e-9);
        let (a, b) = (jl_inv_coefs(below), jl_inv_coefs(above));
        assert!((a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-9);
        for t in [0.01, 0.3, 1.2, 2.4] {
            let h = 1e-6;
            let (p, m) = (jl_coefs(t + h), jl_coefs(t - h));
            assert!(((p.0 - m.0) / (2.0 * h) / t - jl_coefs(t).1).abs() < 1e-6);
            assert!(((p.2 - m.2) / (2.0 * h) / t - jl_coefs(t).3).abs() < 1e-6);
            let (p, m) = (jl_inv_coefs(t + h), jl_inv_coefs(t - h));
            assert!(((p.0 - m.0) / (2.0 * h) / t - jl_inv_coefs(t).1).abs() < 1e-6);
        }
        // J_l J_l⁻¹ = I.
        let psi = Vector3::new(0.7, -1.1, 0.4);
        let th = psi.norm();
        let (b, _, c, _) = jl_coefs(th);
        let (ci, _) = jl_inv_coefs(th);
        let prod = series_matrix(&psi, b, c) * series_matrix(&psi, -0.5, ci);
        assert!((prod - Matrix3::identity()).amax() < 1e-14);
    }

    /// The analytic B agrees with central differences of the exact strain map.
    #[test]
    fn strain_matrix_matches_finite_differences() {
        let (xa, qa, xb, qb) = config();
        let l0 = 0.3;
        let k = kinematics(&xa, &qa, &xb, &qb, l0);
        for j in 0..12 {
            let h = 1e-6;
            let (xp, qp) = perturbed([xa, xb], [qa, qb], j, h);
            let (xm, qm) = perturbed([xa, xb], [qa, qb], j, -h);
            let fd = (kinematics(&xp[0], &qp[0], &xp[1], &qp[1], l0).strain
                - kinematics(&xm[0], &qm[0], &xm[1], &qm[1], l0).strain)
                / (2.0 * h);
            let err = (fd - k.b.column(j)).amax();
            assert!(err < 1e-8, "column {j}: {err:e}\n{fd}\n{}", k.b.column(j));
        }
    }

    /// The analytic geometric stiffness agrees with central differences of l₀ Bᵀσ at fixed σ,
    /// at a generic configuration and near the identity (series branch).
    #[test]
    fn geometric_stiffness_matches_finite_differences() {
        let sig = Vector6::new(0.7, -1.3, 2.1, 0.4, -0.9, 0.6);
        let (xa, qa, xb, _) = config();
        for qb in [
            config().3,
            qa * UnitQuaternion::from_scaled_axis(Vector3::new(1e-3, -2e-3, 5e-4)),
        ] {
            let l0 = 0.3;
            let k = kinematics(&xa, &qa, &xb, &qb, l0);
            let kg = geometric_stiffness(&k, &sig, l0);
            for j in 0..12 {
                let h = 1e-6;
                let (xp, qp) = perturbed([xa, xb], [qa, qb], j, h);
                let (xm, qm) = perturbed([xa, xb], [qa, qb], j, -h);
                let fp = kinematics(&xp[0], &qp[0], &xp[1], &qp[1], l0).b.transpose() * sig * l0;
                let fm = kinematics(&xm[0], &qm[0], &xm[1], &qm[1], l0).b.transpose() * sig * l0;
                let fd = (fp - fm) / (2.0 * h);
                let err = (fd - kg.column(j)).amax();
                assert!(err < 1e-7, "column {j}: {err:e}\n{fd}\n{}", kg.column(j));
            }
        }
    }

    /// The assembled tangent (material + geometric + follower load stiffness) is the derivative
    /// of the assembled residual: Newton is exactly Newton.
    #[test]
    fn assembled_tangent_is_the_residual_derivative() {
        let law = LinearElastic::new(SectionStiffness {
            ga_n: 50.0,
            ea_n: 80.0,
            ei_nm2: 1.0,
            gj_nm2: 0.7,
        });
        let mut rod = SpatialRod::straight(&law, 1.0, 3).unwrap();
        rod.x[1] += Vector3::new(0.05, -0.02, 0.01);
        rod.x[2] += Vector3::new(-0.03, 0.08, -0.02);
        rod.x[3] += Vector3::new(0.2, 0.1, -0.1);
        rod.rot[1] = UnitQuaternion::from_scaled_axis(Vector3::new(0.3, 0.1, 0.2));
        rod.rot[2] = UnitQuaternion::from_scaled_axis(Vector3::new(-0.2, 0.6, 0.4));
        rod.rot[3] = UnitQuaternion::from_scaled_axis(Vector3::new(0.5, 0.9, -0.3));
        rod.current.follower_moment[3] = Vector3::new(0.3, -0.2, 0.5);
        rod.current.force[3] = Vector3::new(1.0, 0.0, 0.0);
        rod.assemble(0.0, true).unwrap();
        let (diag, upper, lower) = (rod.diag.clone(), rod.upper.clone(), rod.lower.clone());
        let block = |i: usize, j: usize| -> Matrix6<f64> {
            match j as isize - i as isize {
                0 => diag[i],
                1 => upper[i],
                -1 => lower[j],
                _ => Matrix6::zeros(),
            }
        };
        NewtonSystem::save(&mut rod);
        let h = 1e-6;
        for j in 0..rod.nodes() {
            for d in 0..6 {
                let mut dq = vec![Vector6::zeros(); rod.nodes()];
                dq[j][d] = h;
                rod.newton.dq = dq;
                rod.move_along(1.0);
                rod.assemble(0.0, false).unwrap();
                let rp = rod.res.clone();
                rod.move_along(-1.0);
                rod.assemble(0.0, false).unwrap();
                let rm = rod.res.clone();
                for i in 0..rod.nodes() {
                    let fd = (rp[i] - rm[i]) / (2.0 * h);
                    let an = block(i, j).column(d).into_owned();
                    assert!(
                        (fd - an).amax() < 1e-6,
                        "node {i} dof ({j},{d}): {fd} vs {an}"
                    );
                }
            }
        }
    }
}
