//! The planar geometrically exact (Reissner / Simo–Reissner) rod: finite elements, contact and a
//! Newton solver with line search.
//!
//! Why planar: every test the chapter runs on the rod (three-point and pure bending, the
//! cantilever, the elastica) loads a straight rod in one plane. For such loading the 3D
//! Cosserat rod (chapter eqs. (8)–(14)) reduces *exactly* to a planar one: the centreline stays in
//! the x–y plane and the director frame is a rotation by one angle θ about e_z, so rotations are
//! handled exactly by a scalar (no linearised rotations anywhere). Unknowns per node: x, y, θ.
//! The tangent is block tridiagonal (3×3 blocks), solved in O(n) — this is what makes a
//! 100-element, 1,000-step elastoplastic three-point run take milliseconds.
//!
//! Frame convention: a₃ = (cos θ, sin θ, 0) is the section normal, a₁ = e_z (the bending axis),
//! a₂ = a₃ × a₁ = (sin θ, −cos θ, 0). Strains (chapter eq. (10)) at an element's midpoint:
//! Γ₂ = ⟨a₂, r′⟩ (shear), Γ₃ = ⟨a₃, r′⟩ − 1 (axial), K₁ = θ′ (bending about a₁ = e_z, the
//! component `cablab_laws::loaded_component` names for bending); the other three components of
//! the law's 6-vector are zero. Internally the shear is carried as γ = −Γ₂ = ⟨(−sin θ, cos θ), r′⟩. Elements are two-node, linear in (x, y, θ), with one-point
//! (midpoint) integration: the classical locking-free Reissner element, second-order accurate.
//! Internal variables of the law live per element (one integration point each), committed only
//! when a step converges.
//!
//! Contact (three-point bending): a support is a rigid cylinder (or point) that holds the rod
//! bilaterally in the normal direction with a penalty, lets it slide (the contact point moves from
//! element to element) and optionally resists sliding with regularised Coulomb friction (a stick
//! spring with a return mapping, so it is rate independent); the punch is unilateral (it can only
//! push), so contact opens on unloading.
//!
//! Does not: 3D loading (torsion coupled with bending), dynamics, distributed loads.

use crate::blocktri::{
    constrain, solve_block_tridiagonal, solve_block_tridiagonal_many, subtract_column,
};
use crate::newton::NewtonSystem;
use crate::RodError;
use cablab_laws::Law;
use nalgebra::{Matrix2, Matrix3, SMatrix, SVector, Vector2, Vector3, Vector6};

type Vec6 = SVector<f64, 6>;
/// A Newton correction below this (relative to the rod length; radians for rotations) counts as
/// converged: with EA ≫ EI/L² the residual has a round-off floor (ε·EA·L/l₀ per element) above a
/// purely relative residual test, while the configuration is already exact to ~10⁻⁹.
pub(crate) const SMALL_CORRECTION: f64 = 1e-9;
/// Friction branch switches per solve before the supports' branches are left to the state at
/// every evaluation (the active-set loop of [`PlanarRod::solve`]).
const MAX_FRICTION_SWITCHES: usize = 6;
/// Switches of the part of the rod a support is held on ([`SupportHold`]) per solve before the
/// supports are left to the element search at every evaluation (as before holds existed).
const MAX_HOLD_SWITCHES: usize = 8;
/// How far (in ξ, fractions of the element) a converged contact may lie beyond an end of the
/// element it is held on and still count as on it: the converged configuration is exact to
/// ~[`SMALL_CORRECTION`] × the rod length, ~10⁻⁷ of an element, and the forces of the element and
/// of the node agree there to that order.
const HOLD_TOLERANCE: f64 = 1e-6;
/// Law 6-vector index of the planar (shear γ, axial Γ₃, bending K₁) components, and their sign.
const LAW_INDEX: [usize; 3] = [1, 2, 3];
const LAW_SIGN: [f64; 3] = [-1.0, 1.0, 1.0];
type Mat6 = SMatrix<f64, 6, 6>;

/// Newton controls shared by all rod solves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverOptions {
    /// Maximum Newton iterations per load step before the step is cut.
    pub max_iterations: usize,
    /// Relative residual tolerance (residual over the force scale of the problem).
    pub tolerance: f64,
    /// How often a failing step may be halved before the solve gives up.
    pub max_bisections: usize,
    /// Whether a driven test (pure bending, three-point) starts each step's Newton iteration from
    /// the extrapolation of its last two committed steps (fewer iterations, same equilibrium to
    /// the tolerance) rather than from the committed configuration; never with support friction.
    pub predictor: bool,
}

impl Default for SolverOptions {
    fn default() -> Self {
        SolverOptions {
            max_iterations: 30,
            tolerance: 1e-9,
            max_bisections: 12,
            predictor: true,
        }
    }
}

/// A rigid support (cylinder of effective radius `radius_eff_m` around `centre`, or a point when
/// the radius is 0) under the rod: bilateral normal penalty, free sliding, optional Coulomb friction.
#[derive(Debug, Clone, PartialEq)]
pub struct Support {
    /// Centre of the support cylinder (m).
    pub centre: Vector2<f64>,
    /// Support radius plus rod radius (the centreline keeps this distance), m.
    pub radius_eff_m: f64,
    /// Normal penalty stiffness, N/m.
    pub k_normal: f64,
    /// Tangential (stick) penalty stiffness of the friction regularisation, N/m.
    pub k_tangent: f64,
    /// Coulomb friction coefficient μ (0 = frictionless).
    pub mu: f64,
    /// Committed contact: reference arc length of the rod material point at the contact, m.
    pub contact_s_m: f64,
    /// Committed contact: where that material point was (centreline), m.
    pub contact_point: Vector2<f64>,
    /// Committed tangential (friction) force on the rod, N (along the rod tangent).
    pub tangential_force_n: f64,
    trial: (f64, Vector2<f64>, f64),
    hint: usize,
    /// The part of the rod the contact is held on during a solve (None: searched at every
    /// evaluation; see [`SupportHold`]).
    held: Option<SupportHold>,
    /// The friction branch the residual is held on during a solve (None: decided from the state
    /// at every evaluation), the branch the state calls for at the last evaluation, and the one
    /// of the last committed step (see [`PlanarRod::solve`]).
    frozen: Option<FrictionBranch>,
    decided: FrictionBranch,
    committed_branch: FrictionBranch,
    /// Normal force the support exerts on the rod at the last evaluation, N.
    pub normal_force_n: f64,
    /// Tangential (friction) force on the rod at the last evaluation, N.
    pub friction_force_n: f64,
    /// Whether the support lay beyond the rod's free end at the last evaluation.
    pub off_end: bool,
    /// What the contact's tangent needs from the last evaluation (None: no contact force).
    tangent: Option<SupportTangent>,
}

/// The part of a support's evaluation its tangent needs ([`PlanarRod::build_tangent`]): the
/// element in contact, the anchor (the material point in contact at the last converged step: its
/// element and ξ) and the friction branch of the residual.
#[derive(Debug, Clone, Copy, PartialEq)]
struct SupportTangent {
    e: usize,
    at: ContactAt,
    e_anchor: usize,
    xi_anchor: f64,
    branch: FrictionBranch,
}

impl Support {
    /// A support at `centre` touching the rod at reference arc length `contact_s_m`, where the
    /// centreline sits at `contact_point`.
    pub fn new(
        centre: Vector2<f64>,
        radius_eff_m: f64,
        k_normal: f64,
        mu: f64,
        contact_s_m: f64,
        contact_point: Vector2<f64>,
    ) -> Self {
        Support {
            centre,
            radius_eff_m,
            k_normal,
            k_tangent: k_normal,
            mu,
            contact_s_m,
            contact_point,
            tangential_force_n: 0.0,
            trial: (contact_s_m, contact_point, 0.0),
            hint: 0,
            held: None,
            frozen: None,
            decided: FrictionBranch::Free,
            committed_branch: FrictionBranch::Stick,
            normal_force_n: 0.0,
            friction_force_n: 0.0,
            off_end: false,
            tangent: None,
        }
    }
}

/// A rigid punch at x = 0 pushing the rod in −y: unilateral node contact with a penalty.
/// `tip_y_m` is the lowest point of the effective surface (punch radius plus rod radius); with
/// `radius_eff_m = 0` it acts on node 0 only (a point punch at mid-span).
#[derive(Debug, Clone, PartialEq)]
pub struct Punch {
    /// Lowest point of the effective punch surface, m.
    pub tip_y_m: f64,
    /// Punch radius plus rod radius, m (0 = point punch on node 0).
    pub radius_eff_m: f64,
    /// Penalty stiffness, N/m.
    pub k: f64,
    /// Sum of the vertical forces the punch exerts on the modelled rod at the last evaluation (N, ≥ 0, pushing down).
    pub force_n: f64,
    /// Nodes in contact (active set) during the current solve.
    pub active: Vec<bool>,
    /// Nodes in contact at the last committed step.
    pub active_committed: Vec<bool>,
}

impl Punch {
    /// A punch whose effective surface has its lowest point at `tip_y_m`, not yet in contact.
    pub fn new(tip_y_m: f64, radius_eff_m: f64, k: f64) -> Self {
        Punch {
            tip_y_m,
            radius_eff_m,
            k,
            force_n: 0.0,
            active: Vec::new(),
            active_committed: Vec::new(),
        }
    }

    /// Whether any node touches the punch at the last evaluation.
    pub fn in_contact(&self) -> bool {
        self.active.iter().any(|&a| a)
    }
}

/// The planar rod model: mesh, configuration, boundary conditions, loads, contacts, law state.
#[derive(Debug)]
pub struct PlanarRod<'a> {
    law: &'a dyn Law,
    /// Element reference lengths, m.
    pub l0: Vec<f64>,
    /// Reference arc length of each node, m.
    pub s_ref: Vec<f64>,
    /// Current nodal configuration (x m, y m, θ rad).
    pub q: Vec<Vector3<f64>>,
    /// Prescribed values per node and degree of freedom (None = free).
    pub prescribed: Vec<[Option<f64>; 3]>,
    /// Dead nodal loads (Fx N, Fy N, M N m).
    pub f_ext: Vec<Vector3<f64>>,
    /// Supports under the rod.
    pub supports: Vec<Support>,
    /// Punch at mid-span, if any.
    pub punch: Option<Punch>,
    /// Newton controls.
    pub options: SolverOptions,
    n_state: usize,
    state: Vec<f64>,
    trial: Vec<f64>,
    axial_fallback: Option<f64>,
    shear_fallback: Option<f64>,
    force_scale: f64,
    length_scale: f64,
    /// Element strains (shear γ, axial Γ₃, bending curvature K₁ 1/m) at the last evaluation.
    pub strain: Vec<Vector3<f64>>,
    /// Element stress resultants (shear force N, axial force N, bending moment M₁ N m) at the last evaluation.
    pub stress: Vec<Vector3<f64>>,
    res: Vec<Vector3<f64>>,
    diag: Vec<Matrix3<f64>>,
    upper: Vec<Matrix3<f64>>,
    lower: Vec<Matrix3<f64>>,
    work: Vec<Matrix3<f64>>,
    /// The Newton correction, and the configuration it starts from.
    rhs: Vec<Vector3<f64>>,
    q0: Vec<Vector3<f64>>,
    /// Per element, what its tangent needs from the last evaluation: the kinematics and the
    /// section's tangent (the stress is in `stress`).
    element_eval: Vec<(Kinematics, Matrix3<f64>)>,
    /// Whether `diag`, `upper` and `lower` hold the tangent of the last evaluation.
    tangent_built: bool,
    /// Forward sensitivities of the equilibrium path, when asked for ([`PlanarRod::enable_sens`]).
    sens: Option<PlanarSens>,
    /// The section's shear–axial block (signs of the rod's strains) when the law's shear and
    /// axial channels are plain linear ones ([`Law::off_channel_linear`] of bending, no
    /// coupling in the elastic tangent): the sections then step the bending curvature alone
    /// ([`Law::update_component`]) and take shear and axial force from this block.
    off_channel: Option<Matrix2<f64>>,
}

/// Forward (tangent-linear) sensitivities of a rod's equilibrium path to the parameters of its
/// law and to the penalties that scale with them ([`PlanarRod::enable_sens`]).
///
/// At a converged step R(q, s_old; p) = 0, so K ∂q/∂p = −∂R/∂p|_q, where ∂R/∂p|_q holds the law's
/// ∂σ/∂p at fixed strain (through the committed state's own derivative, [`Law::update_component_sens`]
/// with ∂ε/∂p = 0), the contact penalties' ∂k/∂p and the supports' forces' derivatives in their
/// committed contact state and μ (central differences of the force law on the residual's branch,
/// as the tangent takes its position derivatives); K is the converged step's own tangent. The
/// law is then stepped again with ∂ε/∂p = B ∂q/∂p for the new state's derivative (the law is linear
/// in both). Holds for the bending component only: the law's shear and axial channels must be
/// linear, uncoupled from bending and free of the parameters, which each step checks (the
/// section's tangent, and the component update against the full one, state included).
#[derive(Debug)]
struct PlanarSens {
    ncol: usize,
    /// ∂k/∂p of the punch penalty and of the supports' normal penalty, per column.
    d_k_punch: Vec<f64>,
    d_k_support: Vec<f64>,
    /// ∂μ/∂p of the supports' friction coefficient per column.
    d_mu: Vec<f64>,
    /// ∂/∂p of each support's committed contact state (arc length, contact point x and y,
    /// tangential force), committed and trial, `4 · ncol` per support, row-major.
    d_support: Vec<f64>,
    d_support_trial: Vec<f64>,
    /// ∂(state)/∂p per element, committed and trial (`n_state · ncol` per element, row-major).
    d_state: Vec<f64>,
    d_trial: Vec<f64>,
    /// ∂q/∂p per column (nodes each), and ∂(response)/∂p of the last step per column.
    dq: Vec<Vec<Vector3<f64>>>,
    d_punch_force: Vec<f64>,
    scratch: Vec<f64>,
    de: Vec<f64>,
    ds: Vec<f64>,
}

/// Kinematics of one element: strains (γ, Γ₃, K), B = ∂ε/∂q (3×6) and the midpoint directors.
#[derive(Debug, Clone, Copy)]
struct Kinematics {
    strain: Vector3<f64>,
    b: SMatrix<f64, 3, 6>,
    a1: Vector2<f64>,
    a3: Vector2<f64>,
    inv: f64,
}

fn kinematics(qa: &Vector3<f64>, qb: &Vector3<f64>, l0: f64) -> Kinematics {
    let tm = 0.5 * (qa[2] + qb[2]);
    let (s, c) = tm.sin_cos();
    let a1 = Vector2::new(-s, c);
    let a3 = Vector2::new(c, s);
    let rp = Vector2::new(qb[0] - qa[0], qb[1] - qa[1]) / l0;
    let g1 = a1.dot(&rp);
    let g3 = a3.dot(&rp) - 1.0;
    let k = (qb[2] - qa[2]) / l0;
    let inv = 1.0 / l0;
    let mut b = SMatrix::<f64, 3, 6>::zeros();
    // Γ₁ row
    b[(0, 0)] = -a1.x * inv;
    b[(0, 1)] = -a1.y * inv;
    b[(0, 3)] = a1.x * inv;
    b[(0, 4)] = a1.y * inv;
    b[(0, 2)] = -0.5 * (1.0 + g3);
    b[(0, 5)] = -0.5 * (1.0 + g3);
    // Γ₃ row
    b[(1, 0)] = -a3.x * inv;
    b[(1, 1)] = -a3.y * inv;
    b[(1, 3)] = a3.x * inv;
    b[(1, 4)] = a3.y * inv;
    b[(1, 2)] = 0.5 * g1;
    b[(1, 5)] = 0.5 * g1;
    // bending K row
    b[(2, 2)] = -inv;
    b[(2, 5)] = inv;
    Kinematics {
        strain: Vector3::new(g1, g3, k),
        b,
        a1,
        a3,
        inv,
    }
}

/// Geometric stiffness σ₁ ∂²γ/∂q² + σ₃ ∂²Γ₃/∂q² (its few non-zeros written directly, which keeps
/// the element cheap). ∂a₁/∂θ = −a₃, ∂a₃/∂θ = a₁, ∂θm/∂θa = ∂θm/∂θb = 1/2.
fn geometric_stiffness(kin: &Kinematics, sig_shear: f64, sig_axial: f64) -> Mat6 {
    let mut g = Mat6::zeros();
    let (g1, g3) = (kin.strain[0], kin.strain[1]);
    for ang in [2usize, 5] {
        for d in 0..2 {
            // ∂²γ/∂r_a∂θ = +½ a₃/l0, ∂²Γ₃/∂r_a∂θ = −½ a₁/l0 (opposite sign for r_b).
            let v = 0.5 * kin.inv * (sig_shear * kin.a3[d] - sig_axial * kin.a1[d]);
            g[(d, ang)] = v;
            g[(ang, d)] = v;
            g[(3 + d, ang)] = -v;
            g[(ang, 3 + d)] = -v;
        }
    }
    let tt = -0.25 * (sig_shear * g1 + sig_axial * (1.0 + g3));
    for i in [2usize, 5] {
        for j in [2usize, 5] {
            g[(i, j)] = tt;
        }
    }
    g
}

/// Which branch of the regularised Coulomb law a support's friction force is on.
#[derive(Debug, Clone, Copy, PartialEq)]
enum FrictionBranch {
    /// No friction: μ = 0, or the support does not press on the rod (N ≤ 0, limit μN⁺ = 0).
    Free,
    /// The stick spring: T = T_old − k_t·slip, inside the limit.
    Stick,
    /// Sliding: T = ±μN (the sign of the trial force).
    Slip(f64),
}

/// Forces of a support on one element and the trial contact state.
#[derive(Debug, Clone, Copy)]
struct SupportEval {
    /// Force on element end a, N.
    fa: Vector2<f64>,
    /// Force on element end b, N.
    fb: Vector2<f64>,
    /// Normal force on the rod (positive pushes it off the support), N.
    normal: f64,
    /// Tangential friction force on the rod along the rod tangent, N.
    friction: f64,
    /// Reference arc length of the current contact point, m.
    s_c: f64,
    /// Current contact point on the centreline, m.
    p_c: Vector2<f64>,
    /// The friction branch the force is on.
    branch: FrictionBranch,
}

/// Where on the segment a–b a support's force acts ([`support_forces`]).
#[derive(Debug, Clone, Copy, PartialEq)]
enum ContactAt {
    /// The segment where the support projects onto it (0 ≤ ξ < 1), else no force: the element
    /// search.
    Within,
    /// The segment where the support projects onto it, past its ends the node's contact: the
    /// contact of a support searched at every evaluation.
    Auto,
    /// The segment's own line and normal, extended beyond its ends (the force split by the same
    /// linear rule in ξ): a support held on the element.
    Segment,
    /// The node at end b (true) or a (false), along the line from the support's centre to it: a
    /// support held on the node.
    Node(bool),
}

/// The part of the rod a support's contact is held on during a Newton solve
/// ([`PlanarRod::solve`]).
///
/// Why: a node-to-segment contact that picks its element anew at every iterate (the element it
/// projects onto, the node's contact in the kink's wedge between two elements) has a force law
/// whose pieces meet continuously but with different derivatives, and near a node the pieces
/// are ~10⁻¹⁰ m apart (the penalty's penetration × the kink's angle) while a Newton iterate
/// moves the contact by ~10⁻⁵ m: the iterates jumped from piece to piece and cycled with period
/// four (a linear rod with EI = 2 N m² on a 40.28 mm span, whose shear strain of 0.044 kinks
/// the centreline at the node in contact, did not converge at w = 2.38 mm, residual stuck at
/// 10⁻²). Held on one piece, a solve's force law is smooth and Newton converges in a few
/// iterations; the converged contact is then checked against the geometry and, where it lies
/// on another part of the rod, held there and solved again (an active set, as for the friction
/// branches and the punch).
///
/// Which equilibrium: the segments' first. Held on element e the contact acts along e's own
/// normal, extended beyond its ends; it is right when the support projects onto e (within
/// [`HOLD_TOLERANCE`]), else the neighbour on that side is held. When the neighbour's
/// equilibrium lies back on e's side (each segment's lies beyond the node they share: the
/// support sits in the kink's wedge, where neither projects), the node is held, along the line
/// from the support's centre to it (the node's contact of [`support_forces`], continuous with
/// both elements at the wedge's edges); it is right while the support stays in that wedge. So
/// the node holds the rod only where no segment can (a kink's wedge catches the rod like a notch
/// until the axial force across it exceeds ≈ N × the kink's angle), and where the support
/// projects onto two overlapping elements the one it was on stays. (Where a held solve fails,
/// or the holds do not settle, the search at every evaluation takes over for the rest of the
/// solve, as before holds existed.)
#[derive(Debug, Clone, Copy, PartialEq)]
enum SupportHold {
    /// Element e's segment, extended.
    Segment(usize),
    /// Node j (between elements j − 1 and j).
    Node(usize),
}

impl SupportHold {
    /// The element the force acts through and how, on a rod of `ne` elements.
    fn contact(self, ne: usize) -> (usize, ContactAt) {
        match self {
            SupportHold::Segment(e) => (e.min(ne - 1), ContactAt::Segment),
            SupportHold::Node(0) => (0, ContactAt::Node(false)),
            SupportHold::Node(j) => ((j - 1).min(ne - 1), ContactAt::Node(true)),
        }
    }
}

/// The forces a support exerts on the segment a–b: a normal penalty on the signed gap, plus
/// (μ > 0) regularised Coulomb friction. Friction is incremental and rate independent: the slip
/// of a step is the tangential displacement of the material point that was in contact at the last
/// converged step (`anchor`, its current position) from where it was then; the tangential force
/// follows an elastic predictor T = T_old − k_t·slip and a return to |T| ≤ μN. Rolling over a
/// round support (the contact point moves through the material without sliding) therefore costs
/// no friction. Forces are split to the end points by the contact parameter ξ. `at`: which part
/// of the segment acts ([`ContactAt`]); None when the support does not project onto the segment
/// and `at` is [`ContactAt::Within`].
///
/// `branch`: None decides the friction branch from the state (the residual); Some keeps the
/// given one with its formula extended smoothly beyond its range (stick without the limit, slip
/// as ±μN without N⁺), which the tangent's finite differences use: the derivative of the branch
/// the residual is on, not a difference quotient across a kink of the law (at N ≈ 0 a step of
/// the difference quotient opens or closes the contact and a secant of μN⁺ of the order
/// μ k_n/2 enters the tangent, which stalled Newton where the punch lets go of the rod).
#[allow(clippy::too_many_arguments)]
fn support_forces(
    sup: &Support,
    pa: Vector2<f64>,
    pb: Vector2<f64>,
    s_a: f64,
    l0: f64,
    at: ContactAt,
    anchor: Vector2<f64>,
    branch: Option<FrictionBranch>,
) -> Option<SupportEval> {
    let d = pb - pa;
    let len = d.norm();
    if len <= 0.0 || !len.is_finite() {
        return None;
    }
    let t_seg = d / len;
    let n_seg = Vector2::new(-t_seg.y, t_seg.x);
    let xi = t_seg.dot(&(sup.centre - pa)) / len;
    if at == ContactAt::Within && !(0.0..1.0).contains(&xi) {
        return None;
    }
    // Past an end of the segment (the support in the wedge between two elements' normals, on
    // the convex side of a kink): the contact is the node's, along the line from the support's
    // centre to it, which turns from one element's normal to the next across the wedge, so the
    // force is continuous where the contact passes a node. (The element's own normal there, as
    // before, made the force jump by the kink's angle and Newton cycle between the two elements:
    // a linear rod on point supports did not converge where a node crossed a support.)
    let at_node = match at {
        ContactAt::Node(b) => Some(b),
        ContactAt::Auto if !(0.0..=1.0).contains(&xi) => Some(xi >= 0.0),
        _ => None,
    };
    let (t, n, gap) = if let Some(b) = at_node {
        let node = if b { pb } else { pa };
        let r = node - sup.centre;
        let dist = r.norm();
        if dist > 0.0 && dist.is_finite() {
            // Oriented as the element's normal (the rod's side of the support).
            let side = if n_seg.dot(&r) < 0.0 { -1.0 } else { 1.0 };
            let n = side * r / dist;
            (Vector2::new(n.y, -n.x), n, side * dist - sup.radius_eff_m)
        } else {
            (t_seg, n_seg, -sup.radius_eff_m)
        }
    } else {
        (
            t_seg,
            n_seg,
            n_seg.dot(&(pa - sup.centre)) - sup.radius_eff_m,
        )
    };
    // The split of the force between the ends: at the node all on it; on a held segment by the
    // linear rule extended beyond its ends (smooth along a Newton solve; the converged contact
    // lies on the segment).
    let xi_force = match (at_node, at) {
        (Some(b), _) => {
            if b {
                1.0
            } else {
                0.0
            }
        }
        (None, ContactAt::Segment) => xi,
        _ => xi.clamp(0.0, 1.0),
    };
    let xi = xi.clamp(0.0, 1.0);
    let normal = -sup.k_normal * gap;
    let mut fa = (1.0 - xi_force) * normal * n;
    let mut fb = xi_force * normal * n;
    let mut friction = 0.0;
    let mut decided = FrictionBranch::Free;
    if sup.mu > 0.0 {
        let slip = t.dot(&(anchor - sup.contact_point));
        let trial = sup.tangential_force_n - sup.k_tangent * slip;
        let limit = sup.mu * normal.max(0.0);
        decided = branch.unwrap_or(if limit <= 0.0 {
            FrictionBranch::Free
        } else if trial.abs() > limit {
            FrictionBranch::Slip(trial.signum())
        } else {
            FrictionBranch::Stick
        });
        friction = match decided {
            FrictionBranch::Free => 0.0,
            FrictionBranch::Stick => trial,
            FrictionBranch::Slip(sign) => sign * sup.mu * normal,
        };
        fa += (1.0 - xi_force) * friction * t;
        fb += xi_force * friction * t;
    }
    Some(SupportEval {
        fa,
        fb,
        normal,
        friction,
        s_c: s_a + xi * l0,
        p_c: pa + xi * d,
        branch: decided,
    })
}

/// Where the anchor (the material point in contact at the last converged step, at `xi_anchor`
/// of element `e_anchor`) is when the element in contact, `e`, has its ends at `pa` and `pb`.
fn anchor_of(
    e: usize,
    e_anchor: usize,
    xi_anchor: f64,
    pa: Vector2<f64>,
    pb: Vector2<f64>,
    q: &[Vector3<f64>],
) -> Vector2<f64> {
    if e_anchor == e {
        pa + (pb - pa) * xi_anchor
    } else {
        q[e_anchor].xy() + (q[e_anchor + 1].xy() - q[e_anchor].xy()) * xi_anchor
    }
}

impl<'a> PlanarRod<'a> {
    /// A straight rod along +x from the origin, `elements` elements of equal length over
    /// `length_m`, unloaded, unconstrained. `bending_stiffness_nm2` sets the force scale of the
    /// convergence test and the inextensibility fallback.
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
        let ei = c[(3, 3)];
        if !(ei.is_finite() && ei > 0.0) {
            return Err(RodError::InvalidSetup(format!(
                "law '{}' has no positive bending stiffness in its elastic tangent (C[K1,K1] = {ei})",
                law.name()
            )));
        }
        let le = length_m / elements as f64;
        // Axial and shear stiffness: the law's, or (if it gives none, e.g. a bending-only law)
        // an inextensible/unshearable penalty 10⁶ EI / le² that leaves bending unaffected.
        let fallback = 1e6 * ei / (le * le);
        let axial_fallback = if c[(2, 2)] > 0.0 {
            None
        } else {
            Some(fallback)
        };
        let shear_fallback = if c[(1, 1)] > 0.0 {
            None
        } else {
            Some(fallback)
        };
        let coupled = (0..6).any(|i| {
            (0..6).any(|j| i != j && c[(i, j)] != 0.0 && (i == 3 || j == 3) && (i < 3 || j < 3))
        });
        let off_channel = (law.off_channel_linear(3)
            && !coupled
            && axial_fallback.is_none()
            && shear_fallback.is_none())
        .then(|| {
            Matrix2::from_fn(|i, j| LAW_SIGN[i] * LAW_SIGN[j] * c[(LAW_INDEX[i], LAW_INDEX[j])])
        });
        let n_state = law.n_state();
        let mut state = vec![0.0; n_state * elements];
        for e in 0..elements {
            law.init_state(&mut state[e * n_state..(e + 1) * n_state]);
        }
        let nodes = elements + 1;
        Ok(PlanarRod {
            law,
            l0: vec![le; elements],
            s_ref: (0..nodes).map(|i| i as f64 * le).collect(),
            q: (0..nodes)
                .map(|i| Vector3::new(i as f64 * le, 0.0, 0.0))
                .collect(),
            prescribed: vec![[None; 3]; nodes],
            f_ext: vec![Vector3::zeros(); nodes],
            supports: Vec::new(),
            punch: None,
            options: SolverOptions::default(),
            n_state,
            trial: state.clone(),
            state,
            axial_fallback,
            shear_fallback,
            force_scale: ei / (length_m * length_m),
            length_scale: length_m,
            strain: vec![Vector3::zeros(); elements],
            stress: vec![Vector3::zeros(); elements],
            res: vec![Vector3::zeros(); nodes],
            diag: vec![Matrix3::zeros(); nodes],
            upper: vec![Matrix3::zeros(); elements],
            lower: vec![Matrix3::zeros(); elements],
            work: Vec::with_capacity(nodes),
            rhs: vec![Vector3::zeros(); nodes],
            q0: Vec::with_capacity(nodes),
            element_eval: Vec::with_capacity(elements),
            tangent_built: false,
            sens: None,
            off_channel,
        })
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.q.len()
    }

    /// Committed internal state of element `e`.
    pub fn element_state(&self, e: usize) -> &[f64] {
        &self.state[e * self.n_state..(e + 1) * self.n_state]
    }

    /// Residual (internal + contact − external forces) at node `i` from the last evaluation:
    /// at a prescribed degree of freedom this is the reaction the constraint exerts on the rod.
    pub fn residual(&self, i: usize) -> Vector3<f64> {
        self.res[i]
    }

    /// Evaluate the residual at the current `q`, writing trial law states, and keep what the
    /// block-tridiagonal tangent there needs; [`PlanarRod::build_tangent`] builds it when a
    /// Newton correction asks for it. About 40 % of the evaluations are never followed by a
    /// correction (the last one of every converged solve, rejected line-search trials), and
    /// the tangent is most of an evaluation's cost after the law. `dt` goes to rate-dependent
    /// laws.
    fn assemble(&mut self, dt: f64) {
        let ne = self.l0.len();
        for r in self.res.iter_mut() {
            *r = Vector3::zeros();
        }
        self.tangent_built = false;
        self.element_eval.clear();
        let ns = self.n_state;
        for e in 0..ne {
            let l0 = self.l0[e];
            let kin = kinematics(&self.q[e], &self.q[e + 1], l0);
            // Law components: Γ₂ = −γ (index 1), Γ₃ (2), K₁ (3).
            let eps = Vector6::new(0.0, -kin.strain[0], kin.strain[1], kin.strain[2], 0.0, 0.0);
            let (old, new) = (
                &self.state[e * ns..(e + 1) * ns],
                &mut self.trial[e * ns..(e + 1) * ns],
            );
            let (mut sig, mut cm);
            if let Some(block) = self.off_channel {
                let step = cablab_laws::ComponentStep {
                    component: 3,
                    strain: kin.strain[2],
                    dt,
                };
                let (m, k) = self.law.update_component(step, old, new);
                let f = block * kin.strain.xy();
                sig = Vector3::new(f.x, f.y, m);
                cm = Matrix3::zeros();
                cm.fixed_view_mut::<2, 2>(0, 0).copy_from(&block);
                cm[(2, 2)] = k;
            } else {
                let resp = self.law.update(&eps, dt, old, new);
                sig = Vector3::new(-resp.stress[1], resp.stress[2], resp.stress[3]);
                cm = Matrix3::from_fn(|i, j| {
                    LAW_SIGN[i] * LAW_SIGN[j] * resp.tangent[(LAW_INDEX[i], LAW_INDEX[j])]
                });
            }
            if let Some(ga) = self.shear_fallback {
                sig[0] = ga * kin.strain[0];
                for j in 0..3 {
                    cm[(0, j)] = 0.0;
                    cm[(j, 0)] = 0.0;
                }
                cm[(0, 0)] = ga;
            }
            if let Some(ea) = self.axial_fallback {
                sig[1] = ea * kin.strain[1];
                for j in 0..3 {
                    cm[(1, j)] = 0.0;
                    cm[(j, 1)] = 0.0;
                }
                cm[(1, 1)] = ea;
            }
            self.strain[e] = kin.strain;
            self.stress[e] = sig;
            let f: Vec6 = kin.b.transpose() * sig * l0;
            for d in 0..3 {
                self.res[e][d] += f[d];
                self.res[e + 1][d] += f[3 + d];
            }
            self.element_eval.push((kin, cm));
        }
        for (r, f) in self.res.iter_mut().zip(&self.f_ext) {
            *r -= f;
        }
        self.assemble_punch();
        self.assemble_supports();
    }

    /// The block-tridiagonal tangent at the configuration of the last [`PlanarRod::assemble`],
    /// from what it kept: the elements, then the punch, then the supports, by the operations
    /// and in the order the evaluation once built it alongside the residual (the same bits).
    fn build_tangent(&mut self) {
        if self.tangent_built {
            return;
        }
        self.tangent_built = true;
        self.diag.iter_mut().for_each(|m| *m = Matrix3::zeros());
        self.upper.iter_mut().for_each(|m| *m = Matrix3::zeros());
        self.lower.iter_mut().for_each(|m| *m = Matrix3::zeros());
        for (e, (kin, cm)) in self.element_eval.iter().enumerate() {
            let (l0, sig) = (self.l0[e], self.stress[e]);
            let k: Mat6 =
                (kin.b.transpose() * cm * kin.b + geometric_stiffness(kin, sig[0], sig[1])) * l0;
            self.diag[e] += k.fixed_view::<3, 3>(0, 0);
            self.diag[e + 1] += k.fixed_view::<3, 3>(3, 3);
            self.upper[e] += k.fixed_view::<3, 3>(0, 3);
            self.lower[e] += k.fixed_view::<3, 3>(3, 0);
        }
        self.punch_tangent();
        self.support_tangents();
    }

    /// Signed gap of node `i` to the punch (negative = penetration) and the outward normal, or
    /// None when the node cannot touch the punch.
    fn punch_gap(p: &Punch, i: usize, r: Vector2<f64>) -> Option<(f64, Vector2<f64>, f64)> {
        if p.radius_eff_m <= 0.0 {
            return (i == 0).then(|| (p.tip_y_m - r.y, Vector2::new(0.0, -1.0), f64::INFINITY));
        }
        if r.x.abs() > p.radius_eff_m {
            return None;
        }
        let c = Vector2::new(0.0, p.tip_y_m + p.radius_eff_m);
        let d = r - c;
        let dist = d.norm();
        (dist > 0.0).then(|| (dist - p.radius_eff_m, d / dist, dist))
    }

    fn assemble_punch(&mut self) {
        let Some(p) = self.punch.as_mut() else { return };
        p.force_n = 0.0;
        if p.active.len() != self.q.len() {
            p.active.resize(self.q.len(), false);
            p.active_committed.resize(self.q.len(), false);
        }
        for i in 0..self.q.len() {
            if !p.active[i] {
                continue;
            }
            let Some((gap, n, _)) = Self::punch_gap(p, i, self.q[i].xy()) else {
                continue;
            };
            // Active nodes are held bilaterally (energy ½ k g²): residual k g n, tangent
            // k (n nᵀ + g (I − n nᵀ)/dist) (`punch_tangent`); the active set decides
            // unilaterality.
            let rv = p.k * gap * n;
            self.res[i][0] += rv.x;
            self.res[i][1] += rv.y;
            p.force_n += rv.y;
        }
    }

    /// The punch's part of the tangent at the configuration of the last evaluation (the nodes
    /// [`PlanarRod::assemble_punch`] held).
    fn punch_tangent(&mut self) {
        let Some(p) = self.punch.as_ref() else { return };
        for i in 0..self.q.len() {
            if !p.active[i] {
                continue;
            }
            let Some((gap, n, dist)) = Self::punch_gap(p, i, self.q[i].xy()) else {
                continue;
            };
            let nn = n * n.transpose();
            let kk = (nn + (Matrix2::identity() - nn) * (gap / dist)) * p.k;
            for a in 0..2 {
                for b in 0..2 {
                    self.diag[i][(a, b)] += kk[(a, b)];
                }
            }
        }
    }

    /// Update the punch's active set at a converged configuration: release nodes the punch
    /// would pull (positive gap while active), engage nodes it penetrates. Returns whether it changed.
    fn update_punch_active_set(&mut self) -> bool {
        let Some(p) = self.punch.as_mut() else {
            return false;
        };
        let tol = 1e-12 * self.length_scale;
        let mut changed = false;
        for i in 0..self.q.len() {
            let Some((gap, _, _)) = Self::punch_gap(p, i, self.q[i].xy()) else {
                if p.active[i] {
                    p.active[i] = false;
                    changed = true;
                }
                continue;
            };
            if p.active[i] && gap > 0.0 {
                p.active[i] = false;
                changed = true;
            } else if !p.active[i] && gap < -tol {
                p.active[i] = true;
                changed = true;
            }
        }
        changed
    }

    /// The element support `si` projects onto at the current configuration, searching outward
    /// from element `hint` (None: onto none, in a kink's wedge or past an end of the rod).
    fn find_support_element(&self, si: usize, hint: usize) -> Option<usize> {
        let ne = self.l0.len();
        let hint = hint.min(ne - 1);
        for off in 0..ne {
            for e in [hint + off, hint.wrapping_sub(off)] {
                if e < ne {
                    let pa = self.q[e].xy();
                    let pb = self.q[e + 1].xy();
                    if support_forces(
                        &self.supports[si],
                        pa,
                        pb,
                        self.s_ref[e],
                        self.l0[e],
                        ContactAt::Within,
                        pa,
                        Some(FrictionBranch::Free),
                    )
                    .is_some()
                    {
                        return Some(e);
                    }
                }
            }
        }
        None
    }

    /// Where support `si`'s centre projects onto the line of element `e`, as its ξ (0 at node
    /// `e`, 1 at node `e + 1`, outside [0, 1] beyond its ends).
    fn support_xi(&self, si: usize, e: usize) -> f64 {
        let (pa, pb) = (self.q[e].xy(), self.q[e + 1].xy());
        let d = pb - pa;
        d.dot(&(self.supports[si].centre - pa)) / d.norm_squared()
    }

    /// Hold each support on the element it projects onto at the configuration a solve starts
    /// from (the committed or predicted one), or on its last element where it projects onto
    /// none (a kink's wedge: the segments are tried before the node, see [`SupportHold`]).
    fn hold_supports(&mut self) {
        let ne = self.l0.len();
        for si in 0..self.supports.len() {
            let hint = self.supports[si].hint.min(ne - 1);
            let e = self.find_support_element(si, hint).unwrap_or(hint);
            self.supports[si].held = Some(SupportHold::Segment(e));
        }
    }

    /// Leave every support's element to the search at every evaluation.
    fn release_supports(&mut self) {
        self.supports.iter_mut().for_each(|s| s.held = None);
    }

    /// At a converged configuration: move each support whose contact does not lie on the part
    /// of the rod it is held on to the part it lies on ([`SupportHold`]; `visited`: per support,
    /// the holds this solve has left). Returns whether any moved.
    fn update_support_holds(&mut self, visited: &mut [Vec<SupportHold>]) -> bool {
        let ne = self.l0.len();
        let tol = HOLD_TOLERANCE;
        let mut changed = false;
        for (si, left) in visited.iter_mut().enumerate() {
            let Some(hold) = self.supports[si].held else {
                continue;
            };
            let next = match hold {
                SupportHold::Segment(e) => {
                    let xi = self.support_xi(si, e);
                    // Past an end: the neighbour there, or, when its equilibrium lay back on
                    // this side, the node they share. Past the rod's ends: `off_end` reports it.
                    let (nb, node) = if xi > 1.0 + tol && e + 1 < ne {
                        (e + 1, e + 1)
                    } else if xi < -tol && e > 0 {
                        (e - 1, e)
                    } else {
                        continue;
                    };
                    if left.contains(&SupportHold::Segment(nb)) {
                        SupportHold::Node(node)
                    } else {
                        SupportHold::Segment(nb)
                    }
                }
                SupportHold::Node(j) => {
                    // Right while the support stays in the node's wedge, past the end of the
                    // element before it and before the start of the one after it.
                    if j < ne && self.support_xi(si, j) > tol {
                        SupportHold::Segment(j)
                    } else if j > 0 && self.support_xi(si, j - 1) < 1.0 - tol {
                        SupportHold::Segment(j - 1)
                    } else {
                        continue;
                    }
                }
            };
            left.push(hold);
            self.supports[si].held = Some(next);
            changed = true;
        }
        changed
    }

    fn assemble_supports(&mut self) {
        let ne = self.l0.len();
        for si in 0..self.supports.len() {
            self.supports[si].tangent = None;
            // Find the element the support projects onto, searching outward from the last one.
            let hint = self.supports[si].hint.min(ne - 1);
            let found = self.find_support_element(si, hint);
            // Held (within a solve, see `SupportHold`): that element or node. Else the element
            // found; in a kink gap between two elements the nearest one, clamped (the node's
            // contact). Past the rod's free end: flagged, the solve reports it.
            let (e, at) = self.supports[si]
                .held
                .map_or((found.unwrap_or(hint), ContactAt::Auto), |h| h.contact(ne));
            let last = ne - 1;
            let beyond_end = found.is_none() && {
                let (pa, pb) = (self.q[last].xy(), self.q[last + 1].xy());
                (pb - pa).dot(&(self.supports[si].centre - pb)) > 0.0
            };
            self.supports[si].off_end = beyond_end;
            let sup = &self.supports[si];
            let (pa, pb) = (self.q[e].xy(), self.q[e + 1].xy());
            let (s_a, l0) = (self.s_ref[e], self.l0[e]);
            // The material point in contact at the last converged step: its element and ξ. (When it
            // lies in another element than the contact, the tangent omits that dependence: a
            // slightly inexact Newton matrix, never a wrong residual.)
            let e_anchor = self
                .s_ref
                .partition_point(|&s| s <= sup.contact_s_m)
                .saturating_sub(1)
                .min(ne - 1);
            let xi_anchor =
                ((sup.contact_s_m - self.s_ref[e_anchor]) / self.l0[e_anchor]).clamp(0.0, 1.0);
            let anchor = anchor_of(e, e_anchor, xi_anchor, pa, pb, &self.q);
            let Some(ev) = support_forces(sup, pa, pb, s_a, l0, at, anchor, sup.frozen) else {
                continue;
            };
            // The branch the state calls for (the same as `ev.branch` when nothing is frozen).
            let decided = match sup.frozen {
                None => ev.branch,
                Some(_) => support_forces(sup, pa, pb, s_a, l0, at, anchor, None)
                    .map_or(ev.branch, |d| d.branch),
            };
            for d in 0..2 {
                self.res[e][d] -= ev.fa[d];
                self.res[e + 1][d] -= ev.fb[d];
            }
            let sup = &mut self.supports[si];
            sup.hint = e;
            sup.normal_force_n = ev.normal;
            sup.friction_force_n = ev.friction;
            sup.trial = (ev.s_c, ev.p_c, ev.friction);
            sup.decided = decided;
            sup.tangent = Some(SupportTangent {
                e,
                at,
                e_anchor,
                xi_anchor,
                branch: ev.branch,
            });
        }
    }

    /// The supports' part of the tangent at the configuration of the last evaluation: central
    /// differences of the contact forces w.r.t. (xa, ya, xb, yb) of the element in contact, on
    /// the friction branch of the residual (see `support_forces`). None of the fields the
    /// evaluation wrote after the residual enter the forces.
    fn support_tangents(&mut self) {
        for si in 0..self.supports.len() {
            let sup = &self.supports[si];
            let Some(SupportTangent {
                e,
                at,
                e_anchor,
                xi_anchor,
                branch,
            }) = sup.tangent
            else {
                continue;
            };
            let (pa, pb) = (self.q[e].xy(), self.q[e + 1].xy());
            let (s_a, l0) = (self.s_ref[e], self.l0[e]);
            let h = 1e-7 * l0;
            let mut jac = SMatrix::<f64, 4, 4>::zeros();
            for j in 0..4 {
                let mut p_plus = [pa, pb];
                let mut p_minus = [pa, pb];
                p_plus[j / 2][j % 2] += h;
                p_minus[j / 2][j % 2] -= h;
                let fp = support_forces(
                    sup,
                    p_plus[0],
                    p_plus[1],
                    s_a,
                    l0,
                    at,
                    anchor_of(e, e_anchor, xi_anchor, p_plus[0], p_plus[1], &self.q),
                    Some(branch),
                );
                let fm = support_forces(
                    sup,
                    p_minus[0],
                    p_minus[1],
                    s_a,
                    l0,
                    at,
                    anchor_of(e, e_anchor, xi_anchor, p_minus[0], p_minus[1], &self.q),
                    Some(branch),
                );
                if let (Some(fp), Some(fm)) = (fp, fm) {
                    for d in 0..2 {
                        jac[(d, j)] = (fp.fa[d] - fm.fa[d]) / (2.0 * h);
                        jac[(2 + d, j)] = (fp.fb[d] - fm.fb[d]) / (2.0 * h);
                    }
                }
            }
            // Residual = −forces, so its tangent is −jac.
            for a in 0..2 {
                for b in 0..2 {
                    self.diag[e][(a, b)] -= jac[(a, b)];
                    self.diag[e + 1][(a, b)] -= jac[(2 + a, 2 + b)];
                    self.upper[e][(a, b)] -= jac[(a, 2 + b)];
                    self.lower[e][(a, b)] -= jac[(2 + a, b)];
                }
            }
        }
    }

    /// Hold each rough support's friction on one branch for the coming Newton solve: the one it
    /// ended the last committed step on (stick at the start).
    fn freeze_friction(&mut self) {
        for s in &mut self.supports {
            s.frozen = (s.mu > 0.0).then_some(s.committed_branch);
        }
    }

    /// At a converged configuration: move each support whose state calls for another friction
    /// branch than the frozen one to that branch; from sliding one way to sliding the other, to
    /// stick first (the equilibrium of a slip branch lets the rod slide freely, so the state
    /// it leaves calls for the opposite slip whenever the truth is stick: during a dwell, where
    /// a relaxing section lowers the normal force below what held the rod, the branches
    /// alternated ± and never settled). Returns whether any moved.
    fn update_friction_branches(&mut self) -> bool {
        let mut changed = false;
        for s in &mut self.supports {
            if let Some(f) = s.frozen {
                if f != s.decided {
                    s.frozen = Some(match (f, s.decided) {
                        (FrictionBranch::Slip(a), FrictionBranch::Slip(b)) if a != b => {
                            FrictionBranch::Stick
                        }
                        (_, d) => d,
                    });
                    changed = true;
                }
            }
        }
        changed
    }

    /// Scaled norm of the residual over the free degrees of freedom (moments divided by the rod length).
    fn free_residual_norm(&self) -> f64 {
        let mut sum = 0.0;
        for (i, r) in self.res.iter().enumerate() {
            for d in 0..3 {
                if self.prescribed[i][d].is_none() {
                    let v = if d == 2 {
                        r[d] / self.length_scale
                    } else {
                        r[d]
                    };
                    sum += v * v;
                }
            }
        }
        sum.sqrt()
    }

    fn reference_force(&self) -> f64 {
        let mut f = self.force_scale;
        for (i, r) in self.res.iter().enumerate() {
            f = f
                .max(self.f_ext[i].xy().norm())
                .max(self.f_ext[i][2].abs() / self.length_scale);
            for d in 0..3 {
                if self.prescribed[i][d].is_some() {
                    let v = if d == 2 {
                        r[d] / self.length_scale
                    } else {
                        r[d]
                    };
                    f = f.max(v.abs());
                }
            }
        }
        if let Some(p) = &self.punch {
            f = f.max(p.force_n);
        }
        for s in &self.supports {
            f = f.max(s.normal_force_n.abs());
        }
        f
    }

    /// Solve the current load step by Newton's method with a backtracking line search. Prescribed
    /// values are applied as increments in the first iteration. On success the trial state is
    /// ready to [`commit`](Self::commit); on failure the configuration is left where Newton stopped
    /// (the caller restores it). `step` only labels errors.
    ///
    /// Contact is an active set around Newton. Punch: see below. Support friction: each rough
    /// support's force is held on one branch of the Coulomb law (stick, slip ±, or free when the
    /// support does not press) during a Newton solve, starting from the branch of the last
    /// committed step; at the converged configuration a support whose state calls for another
    /// branch moves to it and the step is solved again (at most [`MAX_FRICTION_SWITCHES`] times,
    /// then the state decides at every evaluation). Each Newton solve then sees a smooth
    /// residual: deciding the branch at every iterate let the iterates flip between stick, slip
    /// and a lifted contact (where the normal force of a trial configuration changes sign) and
    /// stall; the equilibrium is the same, as the branch is checked on it.
    ///
    /// Support contacts: the same for the part of the rod each support acts on. It is held on
    /// one element (or node) during a Newton solve, starting from the element the support
    /// projects onto at the start; at the converged configuration a support whose contact lies
    /// elsewhere is held there and the step is solved again from that configuration (at most
    /// [`MAX_HOLD_SWITCHES`] times, then the element is searched at every evaluation, as it was
    /// before holds; see [`SupportHold`] for why and which equilibrium). A Newton solve that
    /// fails while held is tried once more from the step's start with the search at every
    /// evaluation.
    pub fn solve(&mut self, dt: f64, step: usize) -> Result<usize, RodError> {
        // Punch contact by an active set around Newton: start from the last committed contact
        // status (so unloading does not first throw the rod off the punch), converge, then release
        // pulled nodes / engage penetrated ones and re-solve until the set is stable.
        if let Some(p) = self.punch.as_mut() {
            p.active.clone_from(&p.active_committed);
        }
        self.freeze_friction();
        self.hold_supports();
        let solved = self.solve_active_sets(dt, step);
        self.release_supports();
        solved
    }

    /// The active-set loop of [`PlanarRod::solve`] around Newton, from the punch's set, the
    /// friction branches and the supports' holds `solve` set up.
    fn solve_active_sets(&mut self, dt: f64, step: usize) -> Result<usize, RodError> {
        let start = self.q.clone();
        let mut total = 0;
        let mut switches = 0;
        let mut hold_switches = 0;
        let mut visited = vec![Vec::new(); self.supports.len()];
        for _ in 0..(4 * self.nodes()).max(20) {
            let mut solved = self.solve_newton(dt, step);
            if solved.is_err() && self.supports.iter().any(|s| s.held.is_some()) {
                // No equilibrium where the supports are held: the solve without holds, from the
                // step's start.
                self.release_supports();
                self.q.clone_from(&start);
                solved = self.solve_newton(dt, step);
            }
            let solved = match solved {
                // A frozen branch the step cannot reach an equilibrium on (a stick spring held
                // where the support slides far): once more with the branch decided by the state.
                Err(_) if self.supports.iter().any(|s| s.frozen.is_some()) => {
                    self.supports.iter_mut().for_each(|s| s.frozen = None);
                    self.q.clone_from(&start);
                    self.solve_newton(dt, step)
                }
                other => other,
            };
            total += solved?;
            if let Some(si) = self.supports.iter().position(|s| s.off_end) {
                return Err(RodError::NotConverged {
                    step,
                    iterations: total,
                    residual: f64::NAN,
                    reason: format!(
                        "the rod slid off support {si}: the deflection pulls more rod over the support than the model has beyond it (its overhang; by default it grows with the history's largest deflection)"
                    ),
                });
            }
            // The supports' holds first (the contact's place on the rod; solved again from
            // here, a node's wedge away at most), then friction branches (at most a few
            // switches, then the state decides at every evaluation), then the punch's active set.
            if self.update_support_holds(&mut visited) {
                hold_switches += 1;
                if hold_switches >= MAX_HOLD_SWITCHES {
                    self.release_supports();
                }
                continue;
            }
            // A new branch is solved from the step's start: the equilibrium of the branch it
            // leaves can lie far off (a stick spring holding 100 × μN), and Newton from there
            // found unphysical equilibria (the rod wrapped round a support) on coarse rods.
            if switches < MAX_FRICTION_SWITCHES && self.update_friction_branches() {
                switches += 1;
                if switches == MAX_FRICTION_SWITCHES {
                    self.supports.iter_mut().for_each(|s| s.frozen = None);
                }
                self.q.clone_from(&start);
                continue;
            }
            if !self.update_punch_active_set() {
                return Ok(total);
            }
        }
        Err(RodError::NotConverged {
            step,
            iterations: total,
            residual: f64::NAN,
            reason: "punch contact active set does not settle (contact chatter)".into(),
        })
    }

    fn solve_newton(&mut self, dt: f64, step: usize) -> Result<usize, RodError> {
        let options = self.options;
        crate::newton::solve(self, &options, dt, step)
    }

    /// Accept the converged step: trial law states and friction stick points become committed.
    pub fn commit(&mut self) {
        self.state.copy_from_slice(&self.trial);
        if let Some(s) = self.sens.as_mut() {
            std::mem::swap(&mut s.d_state, &mut s.d_trial);
            std::mem::swap(&mut s.d_support, &mut s.d_support_trial);
        }
        if let Some(p) = self.punch.as_mut() {
            p.active_committed.clone_from(&p.active);
        }
        for s in &mut self.supports {
            (s.contact_s_m, s.contact_point, s.tangential_force_n) = s.trial;
            s.committed_branch = s.decided;
        }
    }
}

impl PlanarRod<'_> {
    /// Carry forward sensitivities from here on (the rod unloaded and virgin: the state's
    /// derivatives start at 0) over `d_k_punch.len()` columns: the law's
    /// ([`Law::sens_params`] of the bending component, in that order) and any that act only
    /// through the penalties (the machine compliance folded into the punch) or the supports'
    /// friction coefficient. `d_k_punch` and `d_k_support` are ∂k/∂p of the punch's and the
    /// supports' penalties (normal and stick alike) per column, `d_mu` ∂μ/∂p. `false` (nothing
    /// enabled) where the rod cannot: a law without bending sensitivities or without its own
    /// shear and axial stiffness.
    pub fn enable_sens(&mut self, d_k_punch: &[f64], d_k_support: &[f64], d_mu: &[f64]) -> bool {
        let ncol = d_k_punch.len();
        let Some(n_law) = self.law.sens_count(3) else {
            return false;
        };
        if n_law > ncol
            || d_k_support.len() != ncol
            || d_mu.len() != ncol
            || self.axial_fallback.is_some()
            || self.shear_fallback.is_some()
        {
            return false;
        }
        let n_sup = self.supports.len();
        let (ne, nodes) = (self.l0.len(), self.nodes());
        self.sens = Some(PlanarSens {
            ncol,
            d_k_punch: d_k_punch.to_vec(),
            d_k_support: d_k_support.to_vec(),
            d_mu: d_mu.to_vec(),
            d_support: vec![0.0; 4 * ncol * n_sup],
            d_support_trial: vec![0.0; 4 * ncol * n_sup],
            d_state: vec![0.0; ne * self.n_state * ncol],
            d_trial: vec![0.0; ne * self.n_state * ncol],
            dq: vec![vec![Vector3::zeros(); nodes]; ncol],
            d_punch_force: vec![0.0; ncol],
            scratch: vec![0.0; self.n_state],
            de: vec![0.0; ncol],
            ds: vec![0.0; ncol],
        });
        true
    }

    /// ∂(punch force)/∂p per column at the last step [`PlanarRod::sens_step`] took, if
    /// sensitivities are on.
    pub fn punch_force_sens(&self) -> Option<&[f64]> {
        self.sens.as_ref().map(|s| s.d_punch_force.as_slice())
    }

    /// Propagate the sensitivities over the step just solved (before [`PlanarRod::commit`]), of
    /// duration `dt`; `false` when this step cannot be differentiated, and they are dropped
    /// ([`PlanarRod::punch_force_sens`] gives `None` from then on).
    pub fn sens_step(&mut self, dt: f64) -> bool {
        let Some(mut sens) = self.sens.take() else {
            return false;
        };
        let ok = self.propagate_sens(&mut sens, dt).is_some();
        if ok {
            self.sens = Some(sens);
        }
        ok
    }

    /// Element `e`'s section at bending strain `k` over `dt` with sensitivities: ∂σ/∂p into
    /// `sens.ds` given ∂ε/∂p in `sens.de`, the new state's derivatives into `sens.d_trial`, the
    /// new state into `sens.scratch`; the stress, or None where the law cannot differentiate.
    fn section_sens(&self, sens: &mut PlanarSens, e: usize, k: f64, dt: f64) -> Option<f64> {
        let (ns, ncol) = (self.n_state, sens.ncol);
        sens.ds.iter_mut().for_each(|v| *v = 0.0);
        let block = e * ns * ncol..(e + 1) * ns * ncol;
        let step = cablab_laws::ComponentStep {
            component: 3,
            strain: k,
            dt,
        };
        let (sigma, _) = self.law.update_component_sens(
            step,
            &self.state[e * ns..(e + 1) * ns],
            &mut sens.scratch,
            cablab_laws::SensStep {
                first: 0,
                d_old: &sens.d_state[block.clone()],
                d_new: &mut sens.d_trial[block],
                de: &sens.de,
                ds: &mut sens.ds,
            },
        )?;
        Some(sigma)
    }

    /// The derivatives of support `sup`'s forces on its element's ends (rows 0–3: fa, fb) and
    /// of its new contact state (rows 4–7: arc length, contact point, tangential force) with
    /// respect to the element's end positions (columns 0–3: pa, pb), the anchor element's end
    /// positions (4–7; zero when the anchor lies in the element in contact, where it moves with
    /// pa and pb), the committed contact state, the normal and stick penalties and μ (8–14),
    /// by central differences on the residual's friction branch.
    fn support_rates(&self, sup: &Support, st: &SupportTangent) -> Option<SMatrix<f64, 8, 15>> {
        let e = st.e;
        let (s_a, l0) = (self.s_ref[e], self.l0[e]);
        let (ea, la, sa) = (st.e_anchor, self.l0[st.e_anchor], self.s_ref[st.e_anchor]);
        let x0 = [
            self.q[e][0],
            self.q[e][1],
            self.q[e + 1][0],
            self.q[e + 1][1],
            self.q[ea][0],
            self.q[ea][1],
            self.q[ea + 1][0],
            self.q[ea + 1][1],
            sup.contact_s_m,
            sup.contact_point.x,
            sup.contact_point.y,
            sup.tangential_force_n,
            sup.k_normal,
            sup.k_tangent,
            sup.mu,
        ];
        let eval = |x: &[f64; 15]| -> Option<[f64; 8]> {
            let mut s = sup.clone();
            (s.contact_s_m, s.contact_point) = (x[8], Vector2::new(x[9], x[10]));
            (s.tangential_force_n, s.k_normal, s.k_tangent, s.mu) = (x[11], x[12], x[13], x[14]);
            let (pa, pb) = (Vector2::new(x[0], x[1]), Vector2::new(x[2], x[3]));
            let xi = ((x[8] - sa) / la).clamp(0.0, 1.0);
            let anchor = if ea == e {
                pa + (pb - pa) * xi
            } else {
                let (aa, ab) = (Vector2::new(x[4], x[5]), Vector2::new(x[6], x[7]));
                aa + (ab - aa) * xi
            };
            let ev = support_forces(&s, pa, pb, s_a, l0, st.at, anchor, Some(st.branch))?;
            Some([
                ev.fa.x,
                ev.fa.y,
                ev.fb.x,
                ev.fb.y,
                ev.s_c,
                ev.p_c.x,
                ev.p_c.y,
                ev.friction,
            ])
        };
        let force = sup.normal_force_n.abs().max(sup.tangential_force_n.abs());
        let force = force.max(1e-9 * sup.k_normal * l0);
        let mut jac = SMatrix::<f64, 8, 15>::zeros();
        for k in 0..15 {
            if (4..8).contains(&k) && ea == e {
                continue;
            }
            let h = match k {
                0..=10 => 1e-7 * l0,
                11 => 1e-7 * force,
                12 | 13 => 1e-6 * x0[k].abs().max(f64::MIN_POSITIVE),
                _ => 1e-6 * x0[k].abs().max(1e-6),
            };
            let (mut up, mut down) = (x0, x0);
            up[k] += h;
            down[k] -= h;
            let (fu, fd) = (eval(&up)?, eval(&down)?);
            for r in 0..8 {
                jac[(r, k)] = (fu[r] - fd[r]) / (2.0 * h);
            }
        }
        Some(jac)
    }

    fn propagate_sens(&mut self, sens: &mut PlanarSens, dt: f64) -> Option<()> {
        let (ne, ns, ncol, nodes) = (self.l0.len(), self.n_state, sens.ncol, self.nodes());
        // The converged step's tangent, constrained as a correction constrains it.
        self.build_tangent();
        for i in 0..nodes {
            for d in 0..3 {
                if self.prescribed[i][d].is_some() {
                    constrain(&mut self.diag, &mut self.upper, &mut self.lower, (i, d));
                }
            }
        }
        self.tangent_built = false;
        for col in sens.dq.iter_mut() {
            col.iter_mut().for_each(|v| *v = Vector3::zeros());
        }
        // −∂R/∂p at fixed q: the sections' ∂σ/∂p at fixed strain, then the penalties'.
        let tol = 1e-9;
        for e in 0..ne {
            let (kin, cm) = &self.element_eval[e];
            // Bending must stand alone in the section's tangent.
            if cm[(2, 0)] != 0.0 || cm[(2, 1)] != 0.0 || cm[(0, 2)] != 0.0 || cm[(1, 2)] != 0.0 {
                return None;
            }
            sens.de.iter_mut().for_each(|v| *v = 0.0);
            let sigma = self.section_sens(sens, e, kin.strain[2], dt)?;
            // The component update is the full one (no state or stress off the bending axis).
            let m = self.stress[e][2];
            if (sigma - m).abs() > tol * (m.abs() + self.force_scale * self.length_scale) {
                return None;
            }
            let trial = &self.trial[e * ns..(e + 1) * ns];
            if trial
                .iter()
                .zip(&sens.scratch)
                .any(|(a, b)| (a - b).abs() > tol * (a.abs() + b.abs()) + 1e-300)
            {
                return None;
            }
            let l0 = self.l0[e];
            for j in 0..ncol {
                let f = kin.b.row(2).transpose() * (sens.ds[j] * l0);
                for d in 0..3 {
                    sens.dq[j][e][d] -= f[d];
                    sens.dq[j][e + 1][d] -= f[3 + d];
                }
            }
        }
        if let Some(p) = self.punch.as_ref() {
            for i in 0..nodes {
                if !p.active.get(i).copied().unwrap_or(false) {
                    continue;
                }
                let Some((gap, n, _)) = Self::punch_gap(p, i, self.q[i].xy()) else {
                    continue;
                };
                for j in 0..ncol {
                    let f = n * (gap * sens.d_k_punch[j]);
                    sens.dq[j][i][0] -= f.x;
                    sens.dq[j][i][1] -= f.y;
                }
            }
        }
        // The supports: their forces' and new contact state's derivatives in the element's ends,
        // the committed contact state, the penalties and μ (central differences of the force
        // law on the residual's branch, as the tangent takes them).
        let mut local = Vec::with_capacity(self.supports.len());
        for (si, sup) in self.supports.iter().enumerate() {
            let Some(st) = sup.tangent else {
                local.push(None);
                continue;
            };
            let j = self.support_rates(sup, &st)?;
            let (e, ea) = (st.e, st.e_anchor);
            // A sticking support whose anchor lies in another element than the contact couples
            // nodes the block-tridiagonal tangent does not hold (the Newton tangent omits them
            // too): not differentiated. (Measured: where the contact crosses a node the
            // support slides, and the anchor does not enter the forces.)
            if ea != e && (0..4).any(|r| (4..8).any(|k| j[(r, k)] != 0.0)) {
                return None;
            }
            for c in 0..ncol {
                let dx = support_input_rates(sens, si, c);
                for r in 0..4 {
                    let v: f64 = (0..7).map(|k| j[(r, 8 + k)] * dx[k]).sum();
                    sens.dq[c][e + r / 2][r % 2] += v;
                }
            }
            local.push(Some((e, ea, j)));
        }
        for col in sens.dq.iter_mut() {
            for (c, p) in col.iter_mut().zip(&self.prescribed).take(nodes) {
                for (cd, pd) in c.iter_mut().zip(p) {
                    if pd.is_some() {
                        *cd = 0.0;
                    }
                }
            }
        }
        solve_block_tridiagonal_many(
            &self.diag,
            &self.upper,
            &self.lower,
            &mut sens.dq,
            &mut self.work,
        )
        .ok()?;
        for (si, entry) in local.iter().enumerate() {
            let at = si * 4 * ncol;
            match entry {
                Some((e, ea, j)) => {
                    for c in 0..ncol {
                        let dx = support_input_rates(sens, si, c);
                        let dqc = &sens.dq[c];
                        let dpos = [
                            dqc[*e].x,
                            dqc[*e].y,
                            dqc[e + 1].x,
                            dqc[e + 1].y,
                            dqc[*ea].x,
                            dqc[*ea].y,
                            dqc[ea + 1].x,
                            dqc[ea + 1].y,
                        ];
                        for r in 0..4 {
                            let v: f64 = (0..8).map(|k| j[(4 + r, k)] * dpos[k]).sum::<f64>()
                                + (0..7).map(|k| j[(4 + r, 8 + k)] * dx[k]).sum::<f64>();
                            sens.d_support_trial[at + r * ncol + c] = v;
                        }
                    }
                }
                None => {
                    let (old, new) = (&sens.d_support, &mut sens.d_support_trial);
                    new[at..at + 4 * ncol].copy_from_slice(&old[at..at + 4 * ncol]);
                }
            }
        }
        // The sections' new state derivatives, with ∂ε/∂p = B ∂q/∂p.
        for e in 0..ne {
            let kin = &self.element_eval[e].0;
            for j in 0..ncol {
                let (a, b) = (sens.dq[j][e], sens.dq[j][e + 1]);
                let dqe = Vec6::new(a[0], a[1], a[2], b[0], b[1], b[2]);
                sens.de[j] = kin.b.row(2).dot(&dqe.transpose());
            }
            self.section_sens(sens, e, kin.strain[2], dt)?;
        }
        // The punch force: Σ k g n_y over the held nodes.
        sens.d_punch_force.iter_mut().for_each(|v| *v = 0.0);
        if let Some(p) = self.punch.as_ref() {
            for i in 0..nodes {
                if !p.active.get(i).copied().unwrap_or(false) {
                    continue;
                }
                let Some((gap, n, dist)) = Self::punch_gap(p, i, self.q[i].xy()) else {
                    continue;
                };
                let nn = n * n.transpose();
                let m = nn + (Matrix2::identity() - nn) * (gap / dist);
                for j in 0..ncol {
                    let dr = sens.dq[j][i].xy();
                    sens.d_punch_force[j] += (n * (gap * sens.d_k_punch[j]) + m * dr * p.k).y;
                }
            }
        }
        let finite = sens.d_punch_force.iter().all(|v| v.is_finite())
            && sens
                .dq
                .iter()
                .flatten()
                .all(|v| v.iter().all(|x| x.is_finite()));
        finite.then_some(())
    }
}

/// ∂/∂p along column `c` of support `si`'s committed contact state, penalties and μ (the inputs
/// 8–14 of [`PlanarRod::support_rates`]).
fn support_input_rates(sens: &PlanarSens, si: usize, c: usize) -> [f64; 7] {
    let (ncol, at) = (sens.ncol, si * 4 * sens.ncol);
    let d = |r: usize| sens.d_support[at + r * ncol + c];
    let dk = sens.d_k_support[c];
    [d(0), d(1), d(2), d(3), dk, dk, sens.d_mu[c]]
}

impl NewtonSystem for PlanarRod<'_> {
    fn prescribe(&mut self) -> bool {
        self.prescribed
            .iter()
            .zip(&self.q)
            .any(|(p, q)| (0..3).any(|d| p[d].is_some_and(|v| v != q[d])))
    }

    fn assemble(&mut self, dt: f64) -> Result<(), String> {
        PlanarRod::assemble(self, dt);
        Ok(())
    }

    fn free_residual_norm(&self) -> f64 {
        PlanarRod::free_residual_norm(self)
    }

    fn reference_force(&self) -> f64 {
        PlanarRod::reference_force(self)
    }

    /// Right-hand side: −R on free dofs; the prescribed increment on the constrained ones (moved
    /// to the right-hand side through the tangent's columns, then rows/cols zeroed).
    fn correction(&mut self, pending: bool) -> Result<(), usize> {
        self.build_tangent();
        let n = self.nodes();
        for i in 0..n {
            self.rhs[i] = -self.res[i];
        }
        for i in 0..n {
            for d in 0..3 {
                let Some(v) = self.prescribed[i][d] else {
                    continue;
                };
                let delta = v - self.q[i][d];
                if pending && delta != 0.0 {
                    subtract_column(
                        &self.diag,
                        &self.upper,
                        &self.lower,
                        &mut self.rhs,
                        (i, d),
                        delta,
                    );
                }
            }
        }
        for i in 0..n {
            for d in 0..3 {
                let Some(v) = self.prescribed[i][d] else {
                    continue;
                };
                constrain(&mut self.diag, &mut self.upper, &mut self.lower, (i, d));
                self.rhs[i][d] = v - self.q[i][d];
            }
        }
        // The constraints overwrote rows and columns of the tangent: a later correction at the
        // same evaluation builds it again rather than take the constrained one.
        self.tangent_built = false;
        solve_block_tridiagonal(
            &self.diag,
            &self.upper,
            &self.lower,
            &mut self.rhs,
            &mut self.work,
        )
    }

    fn correction_is_small(&self) -> bool {
        self.rhs.iter().all(|d| {
            d.xy().amax() <= SMALL_CORRECTION * self.length_scale && d[2].abs() <= SMALL_CORRECTION
        })
    }

    fn save(&mut self) {
        self.q0.clone_from(&self.q);
    }

    fn restore(&mut self) {
        self.q.clone_from(&self.q0);
    }

    /// q = q₀ + α Δ, with prescribed values exactly.
    fn move_along(&mut self, alpha: f64) {
        for i in 0..self.q0.len() {
            self.q[i] = self.q0[i] + self.rhs[i] * alpha;
            for d in 0..3 {
                if let Some(v) = self.prescribed[i][d] {
                    self.q[i][d] = v;
                }
            }
        }
    }

    /// Σ over free dofs of Δ·R (the line-search function), at the last evaluation.
    fn directional(&self) -> f64 {
        let mut s = 0.0;
        for (i, (r, d)) in self.res.iter().zip(&self.rhs).enumerate() {
            for k in 0..3 {
                if self.prescribed[i][k].is_none() {
                    s += r[k] * d[k];
                }
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_laws::Linear;

    /// The analytic B matrix and the geometric stiffness agree with central differences.
    #[test]
    fn kinematics_derivatives_match_finite_differences() {
        let qa = Vector3::new(0.1, -0.2, 0.3);
        let qb = Vector3::new(0.35, 0.05, 0.9);
        let l0 = 0.3;
        let k = kinematics(&qa, &qb, l0);
        let h = 1e-6;
        for j in 0..6 {
            let mut ap = qa;
            let mut bp = qb;
            let mut am = qa;
            let mut bm = qb;
            if j < 3 {
                ap[j] += h;
                am[j] -= h;
            } else {
                bp[j - 3] += h;
                bm[j - 3] -= h;
            }
            let kp = kinematics(&ap, &bp, l0);
            let km = kinematics(&am, &bm, l0);
            for r in 0..3 {
                let fd = (kp.strain[r] - km.strain[r]) / (2.0 * h);
                assert!(
                    (fd - k.b[(r, j)]).abs() < 1e-7,
                    "B[{r},{j}] = {} vs fd {fd}",
                    k.b[(r, j)]
                );
            }
            let (h1, h3) = (
                geometric_stiffness(&k, 1.0, 0.0),
                geometric_stiffness(&k, 0.0, 1.0),
            );
            for i in 0..6 {
                let fd1 = (kp.b[(0, i)] - km.b[(0, i)]) / (2.0 * h);
                let fd3 = (kp.b[(1, i)] - km.b[(1, i)]) / (2.0 * h);
                assert!((fd1 - h1[(i, j)]).abs() < 1e-6, "H1[{i},{j}]");
                assert!((fd3 - h3[(i, j)]).abs() < 1e-6, "H3[{i},{j}]");
            }
        }
    }

    /// The tangent built on demand after an evaluation is, bit for bit, the one the
    /// evaluation's own data define: every element's ((Bᵀ C) B + G) l₀ from its law's response at
    /// that configuration, the held punch nodes and the central differences of the support's
    /// contact forces on the residual's friction branch, added in that order. A three-point rod
    /// (elastoplastic, rough support, punch) after a few committed steps, evaluated at a
    /// configuration off equilibrium, and once more at another (so that the evaluation's later
    /// writes to the support are in place).
    #[test]
    fn deferred_tangent_is_the_evaluations_tangent_bit_for_bit() {
        use cablab_laws::{Channel, Elastoplastic, SectionStiffness};
        let law = Elastoplastic::isotropic(
            SectionStiffness::CHAPTER_CABLE,
            Channel::Bending,
            4e-3,
            1e-4,
        );
        let (span, overhang) = (0.056, 0.0084);
        let mut rod = PlanarRod::straight(&law, 0.5 * span + overhang, 12).unwrap();
        rod.prescribed[0] = [Some(0.0), None, Some(0.0)];
        let k = 1e7 * 1.37e-3 / span.powi(3);
        let mut sup = Support::new(
            Vector2::new(0.5 * span, -0.002),
            0.002,
            k,
            0.3,
            0.5 * span,
            Vector2::new(0.5 * span, 0.0),
        );
        sup.k_tangent = k;
        rod.supports.push(sup);
        rod.punch = Some(Punch::new(0.0, 0.0, k));
        for step in 1..=12 {
            rod.punch.as_mut().unwrap().tip_y_m = -0.00025 * step as f64;
            rod.solve(0.1, step).unwrap();
            rod.commit();
        }
        let same = |a: &[Matrix3<f64>], b: &[Matrix3<f64>]| {
            a.len() == b.len()
                && a.iter().zip(b).all(|(x, y)| {
                    x.iter()
                        .zip(y.iter())
                        .all(|(u, v)| u.to_bits() == v.to_bits())
                })
        };
        for shift in [3e-5, -2e-5] {
            for (i, q) in rod.q.iter_mut().enumerate().skip(1) {
                q.y += shift * (i as f64).sqrt();
                q[2] += 0.1 * shift;
            }
            PlanarRod::assemble(&mut rod, 0.1);
            let ne = rod.l0.len();
            let ns = rod.n_state;
            let mut diag = vec![Matrix3::zeros(); ne + 1];
            let mut upper = vec![Matrix3::zeros(); ne];
            let mut lower = vec![Matrix3::zeros(); ne];
            let mut scratch = vec![0.0; ns];
            for e in 0..ne {
                let kin = kinematics(&rod.q[e], &rod.q[e + 1], rod.l0[e]);
                let eps = Vector6::new(0.0, -kin.strain[0], kin.strain[1], kin.strain[2], 0.0, 0.0);
                let resp = law.update(&eps, 0.1, &rod.state[e * ns..(e + 1) * ns], &mut scratch);
                let sig = Vector3::new(-resp.stress[1], resp.stress[2], resp.stress[3]);
                let cm = Matrix3::from_fn(|i, j| {
                    LAW_SIGN[i] * LAW_SIGN[j] * resp.tangent[(LAW_INDEX[i], LAW_INDEX[j])]
                });
                let k: Mat6 = (kin.b.transpose() * cm * kin.b
                    + geometric_stiffness(&kin, sig[0], sig[1]))
                    * rod.l0[e];
                diag[e] += k.fixed_view::<3, 3>(0, 0);
                diag[e + 1] += k.fixed_view::<3, 3>(3, 3);
                upper[e] += k.fixed_view::<3, 3>(0, 3);
                lower[e] += k.fixed_view::<3, 3>(3, 0);
            }
            let p = rod.punch.as_ref().unwrap();
            assert!(p.active[0], "the punch holds node 0");
            let (gap, n, dist) = PlanarRod::punch_gap(p, 0, rod.q[0].xy()).unwrap();
            let nn = n * n.transpose();
            let kk = (nn + (Matrix2::identity() - nn) * (gap / dist)) * p.k;
            for a in 0..2 {
                for b in 0..2 {
                    diag[0][(a, b)] += kk[(a, b)];
                }
            }
            let sup = &rod.supports[0];
            let e = sup.hint;
            let e_anchor = rod
                .s_ref
                .partition_point(|&s| s <= sup.contact_s_m)
                .saturating_sub(1)
                .min(ne - 1);
            let xi = ((sup.contact_s_m - rod.s_ref[e_anchor]) / rod.l0[e_anchor]).clamp(0.0, 1.0);
            let branch = sup.frozen.unwrap_or(sup.decided);
            assert!(sup.held.is_none(), "a solve releases its holds");
            let (pa, pb) = (rod.q[e].xy(), rod.q[e + 1].xy());
            let h = 1e-7 * rod.l0[e];
            for j in 0..4 {
                let mut plus = [pa, pb];
                let mut minus = [pa, pb];
                plus[j / 2][j % 2] += h;
                minus[j / 2][j % 2] -= h;
                let at = |p: [Vector2<f64>; 2]| {
                    support_forces(
                        sup,
                        p[0],
                        p[1],
                        rod.s_ref[e],
                        rod.l0[e],
                        ContactAt::Auto,
                        anchor_of(e, e_anchor, xi, p[0], p[1], &rod.q),
                        Some(branch),
                    )
                    .unwrap()
                };
                let (fp, fm) = (at(plus), at(minus));
                for d in 0..2 {
                    let (col, row) = (j % 2, d);
                    let (da, db) = (
                        (fp.fa[d] - fm.fa[d]) / (2.0 * h),
                        (fp.fb[d] - fm.fb[d]) / (2.0 * h),
                    );
                    if j < 2 {
                        diag[e][(row, col)] -= da;
                        lower[e][(row, col)] -= db;
                    } else {
                        upper[e][(row, col)] -= da;
                        diag[e + 1][(row, col)] -= db;
                    }
                }
            }
            rod.build_tangent();
            assert!(same(&rod.diag, &diag) && same(&rod.upper, &upper) && same(&rod.lower, &lower));
        }
    }

    /// A clamped–free rod under an axial tip force stretches by F L / EA (linear, exact).
    #[test]
    fn axial_tip_force_gives_fl_over_ea() {
        let law = Linear::new(1e3, 1e3, 2.0);
        let mut rod = PlanarRod::straight(&law, 0.5, 4).unwrap();
        rod.prescribed[0] = [Some(0.0); 3];
        rod.f_ext[4] = Vector3::new(10.0, 0.0, 0.0);
        rod.solve(0.0, 0).unwrap();
        let stretch = rod.q[4][0] - 0.5;
        assert!(
            (stretch - 10.0 * 0.5 / 1e3).abs() < 1e-12,
            "stretch {stretch}"
        );
    }
}
