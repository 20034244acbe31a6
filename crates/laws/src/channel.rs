//! Deformation channels of the section: axial (Γ₃ → F₃), twist (K₃ → M₃) and bending
//! ((K₁, K₂) → (M₁, M₂), a vector in the bending plane).
//!
//! Inelastic laws act on one channel at a time; a scalar channel is handled as a 2-vector whose
//! second entry stays zero, so the same radial-return code serves bending (circle in the moment
//! plane, eq. (32)) and the tension/torsion analogues (eq. (30)). No physics lives here, only
//! the mapping between 6-vectors and channel 2-vectors.

use crate::law::{Strain6, Stress6, Tangent6};
use cablab_core::TestKind;
use nalgebra::{Matrix2, Vector2};

/// One deformation channel of the section.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Channel {
    /// Axial strain Γ₃ and axial force F₃ (component 2).
    Axial,
    /// Twist K₃ and torque M₃ (component 5).
    Twist,
    /// Bending curvatures (K₁, K₂) and moments (M₁, M₂) (components 3 and 4).
    Bending,
}

impl Channel {
    /// The channel a test of `kind` loads; `None` for [`TestKind::Unknown`].
    pub fn of_kind(kind: TestKind) -> Option<Channel> {
        match kind {
            TestKind::Tension => Some(Channel::Axial),
            TestKind::Torsion => Some(Channel::Twist),
            TestKind::ThreePoint | TestKind::PureBending => Some(Channel::Bending),
            TestKind::Unknown => None,
        }
    }

    /// Indices into the 6-vectors.
    pub fn components(self) -> &'static [usize] {
        match self {
            Channel::Axial => &[2],
            Channel::Twist => &[5],
            Channel::Bending => &[3, 4],
        }
    }

    /// Position of the 6-vector `component` within the channel (0 or 1), `None` if the channel
    /// does not contain it.
    #[inline]
    pub fn position(self, component: usize) -> Option<usize> {
        match (self, component) {
            (Channel::Axial, 2) | (Channel::Twist, 5) | (Channel::Bending, 3) => Some(0),
            (Channel::Bending, 4) => Some(1),
            _ => None,
        }
    }

    /// Number of components (1 or 2).
    pub fn dim(self) -> usize {
        self.components().len()
    }

    /// The channel's part of a 6-vector as a 2-vector (second entry 0 for scalar channels).
    #[inline]
    pub fn get(self, v: &Strain6) -> Vector2<f64> {
        match self {
            Channel::Axial => Vector2::new(v[2], 0.0),
            Channel::Twist => Vector2::new(v[5], 0.0),
            Channel::Bending => Vector2::new(v[3], v[4]),
        }
    }

    /// Add a channel 2-vector into a 6-vector.
    #[inline]
    pub fn add_to(self, s: &Vector2<f64>, out: &mut Stress6) {
        for (i, &c) in self.components().iter().enumerate() {
            out[c] += s[i];
        }
    }

    /// Add a channel 2×2 block into a 6×6 tangent (only the `dim × dim` part is used).
    #[inline]
    pub fn add_block(self, m: &Matrix2<f64>, out: &mut Tangent6) {
        let comps = self.components();
        for (i, &ci) in comps.iter().enumerate() {
            for (j, &cj) in comps.iter().enumerate() {
                out[(ci, cj)] += m[(i, j)];
            }
        }
    }

    /// Read `dim` entries of `state` starting at `at` as a 2-vector.
    #[inline]
    pub(crate) fn read(self, state: &[f64], at: usize) -> Vector2<f64> {
        if self.dim() == 2 {
            Vector2::new(state[at], state[at + 1])
        } else {
            Vector2::new(state[at], 0.0)
        }
    }

    /// Write the first `dim` entries of `v` into `state` starting at `at`.
    #[inline]
    pub(crate) fn write(self, v: &Vector2<f64>, state: &mut [f64], at: usize) {
        state[at] = v[0];
        if self.dim() == 2 {
            state[at + 1] = v[1];
        }
    }
}

/// The magnitude of a scalar channel value, computed as the 2-vector norm of `(v, 0)` is
/// (√(v² + 0)), so that the scalar fast paths reproduce the vector code bit for bit (`|v|` would
/// differ where v² under- or overflows).
#[inline]
pub(crate) fn norm1(v: f64) -> f64 {
    (v * v).sqrt()
}

/// Identity restricted to the channel's dimension (the 2×2 identity for bending, diag(1, 0) for a
/// scalar channel), so that blocks never leak into the unused second entry.
#[inline]
pub(crate) fn eye(ch: Channel) -> Matrix2<f64> {
    if ch.dim() == 2 {
        Matrix2::identity()
    } else {
        Matrix2::new(1.0, 0.0, 0.0, 0.0)
    }
}
