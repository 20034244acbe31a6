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
}
