//! The BSDF interface and radia's scattering models, one file per model.
//!
//! # Convention (the same as Mitsuba 3's `BSDF::eval`)
//! All directions are unit vectors in the **local shading frame** (normal = +z); models never
//! see world space: [`radia_math::Frame`] is the one place where frames change.
//!
//! * `wi` points **back along the path**, towards the previous vertex (the camera for the
//!   first bounce). This is Mitsuba's `si.wi`; pbrt-v4 calls it `wo`.
//! * `wo` is the new direction, towards the light. Mitsuba's `wo`; pbrt-v4's `wi`.
//! * [`Bsdf::eval`] returns f(wi, wo) · |cos θ_wo|, **including** the foreshortening cosine,
//!   as Mitsuba does (pbrt-v4's `f` excludes it).
//! * [`Bsdf::sample`] returns `weight = eval / pdf` and the solid-angle `pdf` of `wo`
//!   (for delta lobes the pdf is 1 by convention and `eval`/`pdf` are 0).
//! * Radiance transport only: refraction scales the weight by 1/η² as Mitsuba's
//!   `TransportMode::Radiance`.

use glam::{Vec2, Vec3};
use radia_math::Spectrum;

mod diffuse;
mod texture;
mod twosided;

pub use diffuse::Diffuse;
pub use twosided::TwoSided;
pub use texture::Texture;

/// Lobe flags: which kind of scattering a model has, or which lobe a sample came from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct LobeFlags(u16);

impl LobeFlags {
    pub const NONE: Self = Self(0);
    pub const DIFFUSE_REFLECTION: Self = Self(1 << 0);
    pub const DIFFUSE_TRANSMISSION: Self = Self(1 << 1);
    pub const GLOSSY_REFLECTION: Self = Self(1 << 2);
    pub const GLOSSY_TRANSMISSION: Self = Self(1 << 3);
    pub const DELTA_REFLECTION: Self = Self(1 << 4);
    pub const DELTA_TRANSMISSION: Self = Self(1 << 5);

    pub const DIFFUSE: Self = Self(Self::DIFFUSE_REFLECTION.0 | Self::DIFFUSE_TRANSMISSION.0);
    pub const GLOSSY: Self = Self(Self::GLOSSY_REFLECTION.0 | Self::GLOSSY_TRANSMISSION.0);
    pub const DELTA: Self = Self(Self::DELTA_REFLECTION.0 | Self::DELTA_TRANSMISSION.0);
    pub const SMOOTH: Self = Self(Self::DIFFUSE.0 | Self::GLOSSY.0);
    pub const REFLECTION: Self =
        Self(Self::DIFFUSE_REFLECTION.0 | Self::GLOSSY_REFLECTION.0 | Self::DELTA_REFLECTION.0);
    pub const TRANSMISSION: Self = Self(
        Self::DIFFUSE_TRANSMISSION.0 | Self::GLOSSY_TRANSMISSION.0 | Self::DELTA_TRANSMISSION.0,
    );

    #[inline]
    pub const fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }
    #[inline]
    pub const fn intersects(self, other: Self) -> bool {
        self.0 & other.0 != 0
    }
    /// True when some lobe is not a Dirac delta: light sampling (NEE) can help.
    #[inline]
    pub const fn has_smooth(self) -> bool {
        self.intersects(Self::SMOOTH)
    }
    #[inline]
    pub const fn is_delta(self) -> bool {
        self.intersects(Self::DELTA)
    }
}

impl std::ops::BitOr for LobeFlags {
    type Output = Self;
    fn bitor(self, rhs: Self) -> Self {
        Self(self.0 | rhs.0)
    }
}

/// Where on the surface a BSDF is queried: what textures need.
#[derive(Clone, Copy, Debug, Default)]
pub struct ShadingPoint {
    pub uv: Vec2,
}

/// The result of [`Bsdf::sample`].
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Sampled direction (local frame), pointing away from the surface.
    pub wo: Vec3,
    /// eval(wi, wo) / pdf, the factor the path throughput is multiplied by.
    pub weight: Spectrum,
    /// Solid-angle density of `wo` (1 for delta lobes by convention).
    pub pdf: f32,
    /// Relative index of refraction along the sampled direction (1 for reflection).
    pub eta: f32,
    /// The lobe the sample came from.
    pub lobe: LobeFlags,
}

/// Every scattering model radia knows: a closed set dispatched by `match`.
#[derive(Clone, Debug)]
pub enum Bsdf {
    Diffuse(Diffuse),
    TwoSided(TwoSided),
}

impl Bsdf {
    /// The lobes this model has.
    #[inline]
    pub fn flags(&self) -> LobeFlags {
        match self {
            Bsdf::Diffuse(_) => LobeFlags::DIFFUSE_REFLECTION,
            Bsdf::TwoSided(m) => m.flags(),
        }
    }

    /// f(wi, wo) · |cos θ_wo| (see the crate docs for the convention).
    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        match self {
            Bsdf::Diffuse(m) => m.eval(sp, wi, wo),
            Bsdf::TwoSided(m) => m.eval(sp, wi, wo),
        }
    }

    /// Solid-angle pdf with which [`Bsdf::sample`] returns `wo` given `wi`.
    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        match self {
            Bsdf::Diffuse(m) => m.pdf(sp, wi, wo),
            Bsdf::TwoSided(m) => m.pdf(sp, wi, wo),
        }
    }

    /// Samples `wo` given `wi` from a lobe-selection value `u1` and a 2D value `u2`.
    /// `None` when no valid direction exists (e.g. `wi` below the surface of a one-sided model).
    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        match self {
            Bsdf::Diffuse(m) => m.sample(sp, wi, u1, u2),
            Bsdf::TwoSided(m) => m.sample(sp, wi, u1, u2),
        }
    }

    /// eval and pdf together (one call in the NEE hot path).
    #[inline]
    pub fn eval_pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> (Spectrum, f32) {
        (self.eval(sp, wi, wo), self.pdf(sp, wi, wo))
    }
}
