//! The shared vocabulary of cablab: the four test kinds, channel roles, specimen geometry and the
//! effect names of the sim-to-real gap diagnosis.
//!
//! Everything here is plain data with serde names that are part of the scripted contract
//! (`../shared/CONTRACT.md`): change a spelling here and scripts break. No physics; the only I/O
//! is [`output::write_atomic`], the one atomic file writer every crate uses.

pub mod output;

use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// The kind of mechanical test. Serialised as in the contract: `tension`, `torsion`,
/// `three_point`, `pure_bending`, `unknown`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TestKind {
    /// Elongation Δl controlled, axial force measured. Control: Γ₃ = Δl/l₀.
    Tension,
    /// Twist angle controlled, torque measured. Control: K₃ = θ/l₀.
    Torsion,
    /// Punch deflection at mid-span controlled, punch force measured.
    ThreePoint,
    /// End rotation controlled (ends free to slide), bending moment measured. K_B = θ/l₀.
    PureBending,
    /// Not (yet) known.
    Unknown,
}

impl TestKind {
    /// The four real kinds, in the chapter's order.
    pub const ALL: [TestKind; 4] = [
        TestKind::Tension,
        TestKind::Torsion,
        TestKind::ThreePoint,
        TestKind::PureBending,
    ];

    /// Contract spelling (`three_point`, ...).
    pub fn as_str(self) -> &'static str {
        match self {
            TestKind::Tension => "tension",
            TestKind::Torsion => "torsion",
            TestKind::ThreePoint => "three_point",
            TestKind::PureBending => "pure_bending",
            TestKind::Unknown => "unknown",
        }
    }

    /// SI unit of the machine's control variable (elongation, twist angle, deflection, end rotation).
    pub fn control_unit(self) -> &'static str {
        match self {
            TestKind::Tension | TestKind::ThreePoint => "m",
            TestKind::Torsion | TestKind::PureBending => "rad",
            TestKind::Unknown => "",
        }
    }

    /// SI unit of the measured response (force or moment).
    pub fn response_unit(self) -> &'static str {
        match self {
            TestKind::Tension | TestKind::ThreePoint => "N",
            TestKind::Torsion | TestKind::PureBending => "N m",
            TestKind::Unknown => "",
        }
    }

    /// Unit of the stiffness the chapter fits for this kind: (EA) in N, (GJ) and (EI) in N m².
    pub fn stiffness_unit(self) -> &'static str {
        match self {
            TestKind::Tension => "N",
            _ => "N m^2",
        }
    }
}

impl fmt::Display for TestKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Error for an unknown kind name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnknownName {
    /// What was given.
    pub given: String,
    /// What would have been accepted.
    pub expected: &'static str,
}

impl fmt::Display for UnknownName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown name '{}': expected one of {}",
            self.given, self.expected
        )
    }
}
impl std::error::Error for UnknownName {}

impl FromStr for TestKind {
    type Err = UnknownName;
    /// Accepts the contract spellings and the CLI's hyphenated ones (`three-point`, `pure-bending`).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().replace('-', "_").as_str() {
            "tension" | "tensile" => Ok(TestKind::Tension),
            "torsion" => Ok(TestKind::Torsion),
            "three_point" | "3pb" | "three_point_bending" => Ok(TestKind::ThreePoint),
            "pure_bending" | "four_point" => Ok(TestKind::PureBending),
            "unknown" => Ok(TestKind::Unknown),
            _ => Err(UnknownName {
                given: s.to_string(),
                expected: "tension, torsion, three_point (three-point), pure_bending (pure-bending), unknown",
            }),
        }
    }
}

/// What a channel is for in the test.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// Test time.
    Time,
    /// The variable the machine drives (displacement, angle, rotation).
    Control,
    /// The measured reaction (force, torque, moment).
    Response,
    /// Anything else (set points, cycle counters, extensometers, computed columns).
    Other,
    /// A text column (phase, step or segment names): no numbers, usable as labels.
    Label,
}

impl Role {
    /// Contract spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            Role::Time => "time",
            Role::Control => "control",
            Role::Response => "response",
            Role::Other => "other",
            Role::Label => "label",
        }
    }
}

/// Specimen geometry, SI. `free_length_m` is the free length between clamps, or for
/// `three_point` the support span.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Specimen {
    /// Specimen label as the lab wrote it (e.g. "cable-2.8-A").
    pub label: Option<String>,
    /// Diameter of the (assumed circular) cross-section, m.
    pub diameter_m: Option<f64>,
    /// Free length or support span, m.
    pub free_length_m: Option<f64>,
}

/// Circular section properties for an isotropic, circular cross-section (chapter eqs. (2)–(7)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CircularSection {
    /// Radius, m.
    pub radius_m: f64,
}

impl CircularSection {
    /// From a diameter in metres.
    pub fn from_diameter(d_m: f64) -> Self {
        CircularSection {
            radius_m: 0.5 * d_m,
        }
    }
    /// Area A = πR², m².
    pub fn area(&self) -> f64 {
        std::f64::consts::PI * self.radius_m.powi(2)
    }
    /// Second moment of area I = πR⁴/4, m⁴.
    pub fn second_moment(&self) -> f64 {
        std::f64::consts::PI * self.radius_m.powi(4) / 4.0
    }
    /// Polar moment J = πR⁴/2 = 2I, m⁴.
    pub fn polar_moment(&self) -> f64 {
        std::f64::consts::PI * self.radius_m.powi(4) / 2.0
    }
    /// Young's modulus from the stiffness fitted in a test of `kind`, with Poisson ratio `nu`
    /// (the chapter uses ν = 0.5: G = E/3). E_T = (EA)/A, E_tor = 2(1+ν)(GJ)/J, E_B = (EI)/I.
    pub fn modulus_from_stiffness(&self, kind: TestKind, stiffness: f64, nu: f64) -> Option<f64> {
        match kind {
            TestKind::Tension => Some(stiffness / self.area()),
            TestKind::Torsion => Some(2.0 * (1.0 + nu) * stiffness / self.polar_moment()),
            TestKind::ThreePoint | TestKind::PureBending => Some(stiffness / self.second_moment()),
            TestKind::Unknown => None,
        }
    }
}

/// Rectangular section properties for an isotropic, flat specimen of width b and thickness h
/// (sheet, strip, printed beam): the section stated as b × h rather than as a diameter.
///
/// Bending is about the axis along the width (the thickness lies in the plane of bending, as
/// for a strip bent flat): I = b h³/12. Torsion uses Saint-Venant's torsion constant of the
/// rectangle ([`RectangularSection::torsion_constant`]), not the polar moment b h (b² + h²)/12,
/// which overstates it (by 2.3× for a square, without bound for a thin strip).
///
/// Does not know about warping restraint at the clamps (short, wide strips twist stiffer than
/// Saint-Venant's J_t says) nor about anisotropy (rolled sheet, printed layers).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RectangularSection {
    /// Width b, m.
    pub width_m: f64,
    /// Thickness h, m (the dimension in the plane of bending).
    pub thickness_m: f64,
}

impl RectangularSection {
    /// Area A = b h, m².
    pub fn area(&self) -> f64 {
        self.width_m * self.thickness_m
    }
    /// Second moment of area about the axis along the width, I = b h³/12, m⁴.
    pub fn second_moment(&self) -> f64 {
        self.width_m * self.thickness_m.powi(3) / 12.0
    }
    /// The longer side a and the shorter side c, m.
    fn sides(&self) -> (f64, f64) {
        if self.width_m >= self.thickness_m {
            (self.width_m, self.thickness_m)
        } else {
            (self.thickness_m, self.width_m)
        }
    }
    /// Σ_{n = 1, 3, 5, …} term(n, nπa/(2c)) over the odd n of Saint-Venant's series, summed
    /// until a term falls to 10⁻¹⁶ of the sum (or to zero).
    fn odd_series(&self, term: impl Fn(f64, f64) -> f64) -> f64 {
        let (a, c) = self.sides();
        let mut sum = 0.0;
        let mut n = 1.0_f64;
        loop {
            let t = term(n, n * std::f64::consts::PI * a / (2.0 * c));
            sum += t;
            if t <= 1e-16 * sum {
                return sum;
            }
            n += 2.0;
        }
    }
    /// Saint-Venant torsion constant, m⁴: with a the longer and c the shorter side,
    /// J_t = a c³ [1/3 − (64/π⁵)(c/a) Σ_{n = 1, 3, 5, …} tanh(nπa/(2c))/n⁵]
    /// (J_t → a c³/3 for a thin strip, 0.1406 a⁴ for a square).
    pub fn torsion_constant(&self) -> f64 {
        let (a, c) = self.sides();
        let sum = self.odd_series(|n, x| x.tanh() / n.powi(5));
        a * c.powi(3) * (1.0 / 3.0 - 64.0 / std::f64::consts::PI.powi(5) * (c / a) * sum)
    }
    /// Largest surface shear strain per unit twist rate, γ_max/K₃, m: at the middle of the
    /// longer side, c [1 − (8/π²) Σ_{n = 1, 3, 5, …} 1/(n² cosh(nπa/(2c)))] (Saint-Venant:
    /// c for a thin strip, 0.675 c for a square), the torsion analogue of d/2.
    pub fn max_shear_strain_per_twist(&self) -> f64 {
        let (_, c) = self.sides();
        let sum = self.odd_series(|n, x| 1.0 / (n * n * x.cosh()));
        c * (1.0 - 8.0 / std::f64::consts::PI.powi(2) * sum)
    }
    /// Young's modulus from the stiffness fitted in a test of `kind`, with Poisson ratio `nu`:
    /// E_T = (EA)/(b h), E_tor = 2(1+ν)(GJ)/J_t, E_B = (EI)/(b h³/12).
    pub fn modulus_from_stiffness(&self, kind: TestKind, stiffness: f64, nu: f64) -> Option<f64> {
        match kind {
            TestKind::Tension => Some(stiffness / self.area()),
            TestKind::Torsion => Some(2.0 * (1.0 + nu) * stiffness / self.torsion_constant()),
            TestKind::ThreePoint | TestKind::PureBending => Some(stiffness / self.second_moment()),
            TestKind::Unknown => None,
        }
    }
}

/// The effect vocabulary of the gap diagnosis. These names appear in every output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    /// The baseline already fits to the noise floor.
    None,
    /// Yield with isotropic hardening (added to a linear baseline).
    Plasticity,
    /// A back moment/force: Bauschinger effect.
    KinematicHardening,
    /// Elastic stiffness falls with accumulated plastic deformation (pseudo-damage).
    StiffnessDegradation,
    /// Maxwell branches: relaxation at holds, rate dependence.
    Viscoelasticity,
    /// Rate-independent Masing loops already in the elastic range (inter-wire friction).
    FrictionHysteresis,
    /// Reversible slope change at a threshold (Bowden cable, chapter eq. (19)).
    PiecewiseElasticity,
    /// The machine's own compliance in series with the specimen.
    MachineCompliance,
    /// Slow drift of the response sensor over time.
    SensorDrift,
    /// Coulomb friction where the rod slides over the three-point supports.
    SupportFriction,
    /// A gap well above the noise floor remains that no candidate closes (a verdict, never a
    /// candidate). Last, so that the other variants keep their discriminants (the blind check
    /// seeds its draws with them).
    Unexplained,
}

impl Effect {
    /// Every name, in vocabulary order.
    pub const ALL: [Effect; 11] = [
        Effect::None,
        Effect::Unexplained,
        Effect::Plasticity,
        Effect::KinematicHardening,
        Effect::StiffnessDegradation,
        Effect::Viscoelasticity,
        Effect::FrictionHysteresis,
        Effect::PiecewiseElasticity,
        Effect::MachineCompliance,
        Effect::SensorDrift,
        Effect::SupportFriction,
    ];

    /// Contract spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            Effect::None => "none",
            Effect::Unexplained => "unexplained",
            Effect::Plasticity => "plasticity",
            Effect::KinematicHardening => "kinematic_hardening",
            Effect::StiffnessDegradation => "stiffness_degradation",
            Effect::Viscoelasticity => "viscoelasticity",
            Effect::FrictionHysteresis => "friction_hysteresis",
            Effect::PiecewiseElasticity => "piecewise_elasticity",
            Effect::MachineCompliance => "machine_compliance",
            Effect::SensorDrift => "sensor_drift",
            Effect::SupportFriction => "support_friction",
        }
    }
}

impl fmt::Display for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for Effect {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim().to_ascii_lowercase().replace('-', "_");
        Effect::ALL.iter().copied().find(|e| e.as_str() == t).ok_or(UnknownName {
            given: s.to_string(),
            expected: "none, unexplained, plasticity, kinematic_hardening, stiffness_degradation, viscoelasticity, friction_hysteresis, piecewise_elasticity, machine_compliance, sensor_drift, support_friction",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kind_spellings_round_trip() {
        for k in TestKind::ALL {
            assert_eq!(k.as_str().parse::<TestKind>().unwrap(), k);
            assert_eq!(serde_json_like(k.as_str()), k.as_str());
        }
        assert_eq!(
            "three-point".parse::<TestKind>().unwrap(),
            TestKind::ThreePoint
        );
        assert_eq!(
            "pure-bending".parse::<TestKind>().unwrap(),
            TestKind::PureBending
        );
        assert!("bend".parse::<TestKind>().is_err());
    }

    fn serde_json_like(s: &str) -> &str {
        s
    }

    #[test]
    fn effect_names_round_trip() {
        for e in Effect::ALL {
            assert_eq!(e.as_str().parse::<Effect>().unwrap(), e);
        }
    }

    /// Table 1 of the chapter: E from (EA), (GJ), (EI) for d = 2.8 mm and ν = 0.5.
    #[test]
    fn chapter_table1_moduli() {
        let s = CircularSection::from_diameter(2.8e-3);
        let e_t = s
            .modulus_from_stiffness(TestKind::Tension, 7.96e4, 0.5)
            .unwrap();
        let e_tor = s
            .modulus_from_stiffness(TestKind::Torsion, 2.02e-3, 0.5)
            .unwrap();
        let e_b = s
            .modulus_from_stiffness(TestKind::PureBending, 1.37e-3, 0.5)
            .unwrap();
        assert!((e_t / 12_900e6 - 1.0).abs() < 0.01, "E_T = {e_t}");
        assert!((e_tor / 1003.7e6 - 1.0).abs() < 0.01, "E_tor = {e_tor}");
        assert!((e_b / 454.4e6 - 1.0).abs() < 0.01, "E_B = {e_b}");
    }

    /// Rectangle: A = b h, I = b h³/12, and Saint-Venant's J_t = k₁ a c³ against the tabulated
    /// k₁ (Timoshenko & Goodier, Theory of Elasticity, § 109: a/c = 1 → 0.1406, 2 → 0.229,
    /// 4 → 0.281, 10 → 0.312, ∞ → 1/3), in either orientation.
    #[test]
    fn rectangle_area_second_moment_and_saint_venant_torsion_constant() {
        let s = RectangularSection {
            width_m: 6.0e-3,
            thickness_m: 1.5e-3,
        };
        assert!((s.area() - 9.0e-6).abs() < 1e-18);
        assert!((s.second_moment() - 6.0e-3 * 1.5e-3f64.powi(3) / 12.0).abs() < 1e-24);
        for (ratio, k1) in [
            (1.0, 0.1406),
            (2.0, 0.229),
            (4.0, 0.281),
            (10.0, 0.312),
            (1e4, 1.0 / 3.0),
        ] {
            let c = 1e-3;
            for (b, h) in [(ratio * c, c), (c, ratio * c)] {
                let r = RectangularSection {
                    width_m: b,
                    thickness_m: h,
                };
                let got = r.torsion_constant() / (ratio * c * c.powi(3));
                assert!(
                    (got / k1 - 1.0).abs() < 2e-3,
                    "a/c = {ratio}: k1 = {got}, table {k1}"
                );
            }
        }
        // τ_max/(G K₃ c) = k₁/k₂ of the same table: 0.1406/0.208 = 0.675 (square), → 1 (strip).
        let sq_unit = RectangularSection {
            width_m: 2e-3,
            thickness_m: 2e-3,
        };
        assert!((sq_unit.max_shear_strain_per_twist() / 2e-3 - 0.675).abs() < 2e-3);
        let strip = RectangularSection {
            width_m: 1.0,
            thickness_m: 1e-3,
        };
        assert!((strip.max_shear_strain_per_twist() / 1e-3 - 1.0).abs() < 1e-9);
        // Not the polar moment b h (b² + h²)/12: for a square that is 0.1667 a⁴, 19 % too high.
        let sq = RectangularSection {
            width_m: 1.0,
            thickness_m: 1.0,
        };
        assert!(sq.torsion_constant() < 0.85 * (2.0 / 12.0));
        // Moduli: the chapter's stiffnesses on a 6 × 1.5 mm strip, ν = 0.5.
        let e_t = s
            .modulus_from_stiffness(TestKind::Tension, 9.0e5, 0.5)
            .unwrap();
        assert!((e_t - 1.0e11).abs() < 1.0);
        let e_b = s
            .modulus_from_stiffness(TestKind::ThreePoint, 1.6875e-1, 0.5)
            .unwrap();
        assert!((e_b / 1.0e11 - 1.0).abs() < 1e-12, "{e_b}");
        let j = s.torsion_constant();
        let e_tor = s
            .modulus_from_stiffness(TestKind::Torsion, 1.0e9 * j, 0.3)
            .unwrap();
        assert!((e_tor / 2.6e9 - 1.0).abs() < 1e-12);
        assert!(s
            .modulus_from_stiffness(TestKind::Unknown, 1.0, 0.5)
            .is_none());
    }
}
