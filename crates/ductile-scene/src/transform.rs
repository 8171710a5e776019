//! Local transforms of scene nodes.

use glam::{Affine3A, Quat, Vec3};
use serde::{Deserialize, Serialize};

/// A node's placement relative to its parent: `M = T · R · S`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Transform {
    /// Translation.
    pub translation: Vec3,
    /// Rotation (unit quaternion `(x, y, z, w)`).
    pub rotation: Quat,
    /// Scale per axis.
    pub scale: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Self = Self {
        translation: Vec3::ZERO,
        rotation: Quat::IDENTITY,
        scale: Vec3::ONE,
    };

    /// A pure translation.
    #[must_use]
    pub fn from_translation(translation: Vec3) -> Self {
        Self {
            translation,
            ..Self::IDENTITY
        }
    }

    /// The affine map `T · R · S`.
    #[must_use]
    pub fn affine(&self) -> Affine3A {
        Affine3A::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }

    /// True when every component is finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.translation.is_finite() && self.rotation.is_finite() && self.scale.is_finite()
    }

    /// Why a finite transform cannot be inverted or carried, if it cannot: a zero scale
    /// component or a zero rotation quaternion (which glam would otherwise treat as a
    /// rotation by NaN, and a renormalising reader as the identity); or a translation or
    /// scale beyond ±10⁹, or a scale below 10⁻⁹ in magnitude, whose products with the tools'
    /// parameters leave the range Ductile computes in
    /// ([`ductile_core::error::MAX_MAGNITUDE`]). Tools are carried into mesh space through
    /// the inverse of the mesh's world transform, so all are refused everywhere, on the node
    /// that holds them rather than as derived values of the tools beneath it.
    #[must_use]
    pub fn degeneracy(&self) -> Option<&'static str> {
        use ductile_core::error::MAX_MAGNITUDE;
        if self.scale.x == 0.0 || self.scale.y == 0.0 || self.scale.z == 0.0 {
            Some("a scale component is zero")
        } else if self.rotation.length_squared() == 0.0 {
            Some("the rotation quaternion is zero")
        } else if self.translation.abs().max_element() > MAX_MAGNITUDE {
            Some("a translation component lies beyond ±1e9")
        } else if self.scale.abs().max_element() > MAX_MAGNITUDE {
            Some("a scale component lies beyond ±1e9")
        } else if self.scale.abs().min_element() < 1.0 / MAX_MAGNITUDE {
            Some("a scale component is smaller than 1e-9 in magnitude")
        } else {
            None
        }
    }
}
