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
//! * [`Bsdf::pdf`] is the solid-angle density with which [`Bsdf::sample`] returns `wo`,
//!   counting only the non-delta lobes; [`Bsdf::eval`] is likewise zero on delta lobes.
//! * [`Bsdf::sample`] returns `weight = eval / pdf` and the solid-angle `pdf` of `wo` for a
//!   smooth (diffuse or glossy) lobe. For a **delta** lobe (flagged in `lobe`) `weight` is
//!   the lobe's full contribution divided by the probability of choosing it, and `pdf` is
//!   that discrete probability, as Mitsuba's `bs.pdf` (1 when the model has a single lobe).
//!   The integrator must not use the pdf of a delta sample for MIS.
//! * Radiance transport only (Mitsuba's `TransportMode::Radiance`): a refracted sample's
//!   weight carries the 1/η² solid-angle compression of radiance (η the relative IOR along
//!   the sampled direction, returned as [`BsdfSample::eta`]); the integrator's Russian
//!   roulette multiplies η² back in, as Mitsuba's `path.cpp`.
//!
//! # Models
//! | Mitsuba plugin | type | file |
//! | --- | --- | --- |
//! | `diffuse` | [`Diffuse`] (Lambert) | `diffuse.rs` |
//! | `phong` (radia) | [`Phong`], normalized Phong | `phong.rs` |
//! | `blinnphong` (radia) | [`BlinnPhong`], normalized Blinn-Phong | `blinn_phong.rs` |
//! | `conductor` | [`Conductor`] | `conductor.rs` |
//! | `roughconductor` | [`RoughConductor`] | `rough_conductor.rs` |
//! | `cooktorrance` (radia) | [`CookTorrance`], Schlick Fresnel, glTF metal/rough | `cook_torrance.rs` |
//! | `dielectric` | [`Dielectric`] | `dielectric.rs` |
//! | `thindielectric` | [`ThinDielectric`] | `thin_dielectric.rs` |
//! | `roughdielectric` | [`RoughDielectric`] | `rough_dielectric.rs` |
//! | `plastic` | [`Plastic`] | `plastic.rs` |
//! | `roughplastic` | [`RoughPlastic`] | `rough_plastic.rs` |
//! | `principled` | [`Principled`] (Disney, Blender's Principled BSDF) | `principled.rs` |
//! | `principledthin` | [`PrincipledThin`] (a sheet: both sides alike, no bending) | `principled_thin.rs` |
//! | `blendbsdf` | [`Blend`] | `blend.rs` |
//! | `twosided` | [`TwoSided`] | `twosided.rs` |
//! | `normalmap` | [`NormalMap`] | `normal_map.rs` |
//! | `bumpmap` | [`BumpMap`] | `bump_map.rs` |
//! | `mask` | [`Mask`] (opacity, cut-outs) | `mask.rs` |
//! | `null` | [`Null`] (invisible) | `null.rs` |
//!
//! Shared pieces: [`microfacet`] (Beckmann and GGX distributions, Smith masking, visible
//! normal sampling), [`fresnel`] (dielectric, conductor and Schlick Fresnel, reflect and
//! refract), [`ior`] (Mitsuba's named indices of refraction and conductor presets),
//! `perturbed.rs` (the shading-frame change `normalmap` and `bumpmap` share), [`Texture`]
//! (`texture/`: constants, bitmaps, checkerboards), `principled_helpers.rs` (what
//! `principled` and `principledthin` share, Mitsuba's `principledhelpers.h`).
//!
//! # One path or sixteen
//! Every model is written once over [`radia_math::real::Real`] (`eval_pdf_r`, `sample_r`);
//! those that nest others (`twosided`, `blendbsdf`, `normalmap`, `bumpmap`, `mask`) have
//! lanes where their nested models do ([`Bsdf::has_r`]), querying them through `nested.rs`.
//! Their one-path `eval`, `pdf`, `eval_pdf` and `sample` are the `f32` instantiation; over
//! `f32x16` each lane gets the same bits (`lanes_test.rs`, `lanes_test_principled.rs`). The
//! packet loop runs all of them in lanes, null samples ([`BsdfSampleR::null`]) included.

use glam::{Vec2, Vec3};
use radia_math::real::{Mask as _, Real, Vector2, Vector3};
use radia_math::Spectrum;

mod aov;
mod blend;
mod blinn_phong;
mod bump_map;
mod conductor;
mod cook_torrance;
mod dielectric;
mod diffuse;
pub mod fresnel;
pub mod ior;
mod mask;
pub mod microfacet;
mod nested;
mod normal_map;
mod null;
mod perturbed;
mod phong;
mod plastic;
mod principled;
mod principled_helpers;
mod principled_thin;
mod rough_conductor;
mod rough_dielectric;
mod rough_plastic;
mod texture;
mod thin_dielectric;
mod twosided;

#[cfg(test)]
mod lanes_test;
#[cfg(test)]
mod lanes_test_principled;
#[cfg(test)]
mod testing;

pub use blend::Blend;
pub use blinn_phong::BlinnPhong;
pub use bump_map::BumpMap;
pub use conductor::Conductor;
pub use cook_torrance::{CookTorrance, CookTorranceFresnel};
pub use dielectric::Dielectric;
pub use diffuse::Diffuse;
pub use mask::Mask;
pub use microfacet::{MicrofacetDistribution, MicrofacetType};
pub use normal_map::NormalMap;
pub use null::Null;
pub use perturbed::PerturbOptions;
pub use phong::Phong;
pub use plastic::Plastic;
pub use principled::{Principled, PrincipledIor};
pub use principled_thin::PrincipledThin;
pub use rough_conductor::RoughConductor;
pub use rough_dielectric::RoughDielectric;
pub use rough_plastic::RoughPlastic;
pub use texture::{
    decode_8bit, srgb_to_linear, Bitmap, BitmapError, Checkerboard, FilterType, Texture,
    UvTransform, WrapMode,
};
pub use thin_dielectric::ThinDielectric;
pub use twosided::TwoSided;

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
    /// Straight through, unchanged (wo = −wi): the transparent part of `mask` and `null`.
    /// As Mitsuba's `BSDFFlags::Null` (`include/mitsuba/render/bsdf.h`) it counts as a
    /// delta lobe and as transmission.
    pub const NULL: Self = Self(1 << 6);

    pub const DIFFUSE: Self = Self(Self::DIFFUSE_REFLECTION.0 | Self::DIFFUSE_TRANSMISSION.0);
    pub const GLOSSY: Self = Self(Self::GLOSSY_REFLECTION.0 | Self::GLOSSY_TRANSMISSION.0);
    pub const DELTA: Self =
        Self(Self::DELTA_REFLECTION.0 | Self::DELTA_TRANSMISSION.0 | Self::NULL.0);
    pub const SMOOTH: Self = Self(Self::DIFFUSE.0 | Self::GLOSSY.0);
    pub const REFLECTION: Self =
        Self(Self::DIFFUSE_REFLECTION.0 | Self::GLOSSY_REFLECTION.0 | Self::DELTA_REFLECTION.0);
    pub const TRANSMISSION: Self = Self(
        Self::DIFFUSE_TRANSMISSION.0
            | Self::GLOSSY_TRANSMISSION.0
            | Self::DELTA_TRANSMISSION.0
            | Self::NULL.0,
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
    /// True for a null sample (the path goes on unchanged) or a model with a null lobe.
    #[inline]
    pub const fn is_null(self) -> bool {
        self.intersects(Self::NULL)
    }
}

impl std::ops::BitOr for LobeFlags {
    type Output = Self;
    fn bitor(self, rhs: Self) -> Self {
        Self(self.0 | rhs.0)
    }
}

/// Where on the surface a BSDF is queried: what textures and the normal/bump-map adapters
/// need. Vectors are in the **local shading frame**, like the BSDF's directions.
#[derive(Clone, Copy, Debug, Default)]
pub struct ShadingPoint {
    /// Surface texture coordinates (Mitsuba's `si.uv`).
    pub uv: Vec2,
    /// ∂p/∂u and ∂p/∂v of the surface parametrisation (Mitsuba's `si.dp_du`, `si.dp_dv`).
    pub dp_du: Vec3,
    pub dp_dv: Vec3,
    /// The geometric normal (Mitsuba's `si.n`); +z when it agrees with the shading normal.
    pub n: Vec3,
}

impl ShadingPoint {
    /// A point at `uv` on a flat surface whose parametrisation follows the shading frame
    /// (∂p/∂u = s, ∂p/∂v = t, geometric normal = shading normal): for tests and tools.
    pub const fn at_uv(uv: Vec2) -> Self {
        Self {
            uv,
            dp_du: Vec3::X,
            dp_dv: Vec3::Y,
            n: Vec3::Z,
        }
    }
}

/// [`ShadingPoint`] over a [`Real`]: one point, or one per lane of a packet of paths.
#[derive(Clone, Copy, Debug)]
pub struct ShadingPointR<R> {
    pub uv: Vector2<R>,
    pub dp_du: Vector3<R>,
    pub dp_dv: Vector3<R>,
    pub n: Vector3<R>,
}

impl<R: Real> ShadingPointR<R> {
    /// Lane `k` as a one-path [`ShadingPoint`].
    #[inline(always)]
    pub fn lane(&self, k: usize) -> ShadingPoint {
        ShadingPoint {
            uv: self.uv.lane(k),
            dp_du: self.dp_du.lane(k),
            dp_dv: self.dp_dv.lane(k),
            n: self.n.lane(k),
        }
    }
}

impl From<&ShadingPoint> for ShadingPointR<f32> {
    #[inline(always)]
    fn from(sp: &ShadingPoint) -> Self {
        Self {
            uv: sp.uv.into(),
            dp_du: sp.dp_du.into(),
            dp_dv: sp.dp_dv.into(),
            n: sp.n.into(),
        }
    }
}

/// [`BsdfSample`] over a [`Real`]: what the path loop needs of the sampled lobe, as masks.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSampleR<R: Real> {
    pub wo: Vector3<R>,
    pub weight: Vector3<R>,
    pub pdf: R,
    pub eta: R,
    /// Lanes with a sample (the one-path `Option` is `Some`); the other fields are
    /// meaningless elsewhere.
    pub valid: R::Mask,
    /// Lanes whose sample came from a delta lobe.
    pub delta: R::Mask,
    /// Lanes whose sample is a null lobe's ([`LobeFlags::NULL`]: straight on, wo = −wi,
    /// weight 1), delta as well: the path goes on from where it last scattered.
    pub null: R::Mask,
}

impl<R: Real> BsdfSampleR<R> {
    /// No sample in any lane.
    #[inline(always)]
    pub fn none() -> Self {
        Self {
            wo: Vector3::zero(),
            weight: Vector3::zero(),
            pdf: R::zero(),
            eta: R::one(),
            valid: R::Mask::splat(false),
            delta: R::Mask::splat(false),
            null: R::Mask::splat(false),
        }
    }
}

/// Lane by lane, the sample of `if_true` or of `if_false` (masks included).
impl<R: Real> radia_math::real::Select<R> for BsdfSampleR<R> {
    #[inline(always)]
    fn select(m: R::Mask, if_true: Self, if_false: Self) -> Self {
        Self {
            wo: Vector3::select(m, if_true.wo, if_false.wo),
            weight: Vector3::select(m, if_true.weight, if_false.weight),
            pdf: R::select(m, if_true.pdf, if_false.pdf),
            eta: R::select(m, if_true.eta, if_false.eta),
            valid: (m & if_true.valid) | (!m & if_false.valid),
            delta: (m & if_true.delta) | (!m & if_false.delta),
            null: (m & if_true.null) | (!m & if_false.null),
        }
    }
}

impl BsdfSampleR<f32> {
    /// The one-path record: `Some` where the sample is valid, from the lobe the model says
    /// it chose.
    #[inline(always)]
    pub(crate) fn one_path(self, lobe: LobeFlags) -> Option<BsdfSample> {
        self.valid.then(|| BsdfSample {
            wo: self.wo.into(),
            weight: self.weight.into(),
            pdf: self.pdf,
            eta: self.eta,
            lobe,
        })
    }
}

/// The result of [`Bsdf::sample`].
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Sampled direction (local frame), pointing away from the surface.
    pub wo: Vec3,
    /// eval(wi, wo) / pdf, the factor the path throughput is multiplied by (for a delta
    /// lobe: its contribution over the probability of choosing it).
    pub weight: Spectrum,
    /// Solid-angle density of `wo` for smooth lobes; for a delta lobe the discrete
    /// probability of having chosen it.
    pub pdf: f32,
    /// Relative index of refraction along the sampled direction: η_transmitted/η_incident
    /// for a refraction (Mitsuba's `eta_it`), 1 for reflection.
    pub eta: f32,
    /// The lobe the sample came from.
    pub lobe: LobeFlags,
}

/// Every scattering model radia knows: a closed set dispatched by `match`.
#[derive(Clone, Debug)]
pub enum Bsdf {
    Diffuse(Diffuse),
    Phong(Phong),
    BlinnPhong(BlinnPhong),
    Conductor(Conductor),
    RoughConductor(RoughConductor),
    CookTorrance(CookTorrance),
    Dielectric(Dielectric),
    ThinDielectric(ThinDielectric),
    RoughDielectric(RoughDielectric),
    Plastic(Plastic),
    RoughPlastic(RoughPlastic),
    Principled(Principled),
    PrincipledThin(PrincipledThin),
    Blend(Blend),
    TwoSided(TwoSided),
    NormalMap(NormalMap),
    BumpMap(BumpMap),
    Mask(Mask),
    Null(Null),
}

/// Expands to a `match` that calls `$method` on whichever model `$self` holds.
macro_rules! dispatch {
    ($self:expr, $m:ident => $call:expr) => {
        match $self {
            Bsdf::Diffuse($m) => $call,
            Bsdf::Phong($m) => $call,
            Bsdf::BlinnPhong($m) => $call,
            Bsdf::Conductor($m) => $call,
            Bsdf::RoughConductor($m) => $call,
            Bsdf::CookTorrance($m) => $call,
            Bsdf::Dielectric($m) => $call,
            Bsdf::ThinDielectric($m) => $call,
            Bsdf::RoughDielectric($m) => $call,
            Bsdf::Plastic($m) => $call,
            Bsdf::RoughPlastic($m) => $call,
            Bsdf::Principled($m) => $call,
            Bsdf::PrincipledThin($m) => $call,
            Bsdf::Blend($m) => $call,
            Bsdf::TwoSided($m) => $call,
            Bsdf::NormalMap($m) => $call,
            Bsdf::BumpMap($m) => $call,
            Bsdf::Mask($m) => $call,
            Bsdf::Null($m) => $call,
        }
    };
}

impl Bsdf {
    /// The lobes this model has.
    #[inline]
    pub fn flags(&self) -> LobeFlags {
        dispatch!(self, m => m.flags())
    }

    /// Whether [`Bsdf::sample`] reads its `u1`, the choice among lobes or blended
    /// components. The path integrator draws that value only for models that do: under the
    /// stratified samplers each value costs a permutation, and a diffuse or metal surface
    /// has nothing to choose. `testing::check_consistency` checks that a model that says
    /// `false` samples the same whatever `u1`.
    #[inline(always)]
    pub fn samples_lobe(&self) -> bool {
        match self {
            Bsdf::Diffuse(_) | Bsdf::Conductor(_) | Bsdf::RoughConductor(_) | Bsdf::Null(_) => {
                false
            }
            Bsdf::TwoSided(_) | Bsdf::NormalMap(_) | Bsdf::BumpMap(_) => self.nested_samples_lobe(),
            _ => true,
        }
    }

    /// Whether the model reads more of its [`ShadingPoint`] than `uv`: the parametrisation's
    /// tangents and the geometric normal, which only normal and bump maps (anywhere in the
    /// tree) use. Scenes decide this once per BSDF, so that a surface without them is not
    /// given tangents it never reads.
    pub fn reads_surface_frame(&self) -> bool {
        match self {
            Bsdf::NormalMap(_) | Bsdf::BumpMap(_) => true,
            Bsdf::Blend(m) => m.bsdfs.iter().any(Bsdf::reads_surface_frame),
            Bsdf::TwoSided(m) => m.sides.iter().any(Bsdf::reads_surface_frame),
            Bsdf::Mask(m) => m.nested.reads_surface_frame(),
            _ => false,
        }
    }

    /// [`Bsdf::samples_lobe`] of an adapter: its nested models' (kept out of line, as the
    /// recursion would stop `samples_lobe` from inlining).
    #[inline(never)]
    fn nested_samples_lobe(&self) -> bool {
        match self {
            Bsdf::TwoSided(m) => m.sides.iter().any(Bsdf::samples_lobe),
            Bsdf::NormalMap(m) => m.nested.samples_lobe(),
            Bsdf::BumpMap(m) => m.nested.samples_lobe(),
            _ => self.samples_lobe(),
        }
    }

    /// f(wi, wo) · |cos θ_wo| (see the crate docs for the convention).
    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        dispatch!(self, m => m.eval(sp, wi, wo))
    }

    /// Solid-angle pdf with which [`Bsdf::sample`] returns `wo` given `wi` (smooth lobes only).
    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        dispatch!(self, m => m.pdf(sp, wi, wo))
    }

    /// Samples `wo` given `wi` from a lobe-selection value `u1` and a 2D value `u2`.
    /// `None` when no valid direction exists (e.g. `wi` below the surface of a one-sided model).
    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        dispatch!(self, m => m.sample(sp, wi, u1, u2))
    }

    /// The fraction of light that passes straight through the surface at `sp` (Mitsuba's
    /// `eval_null_transmission`): 1 − opacity for a `mask`, 1 for `null`, the weighted sum
    /// for a blend, 0 for every other model. It equals the probability that
    /// [`Bsdf::sample`] returns a [`LobeFlags::NULL`] sample (each of weight 1), which is
    /// what lets shadow rays cross such surfaces consistently with BSDF sampling.
    /// (`twosided` nests no transmissive model and the loader refuses a null lobe under
    /// `normalmap`/`bumpmap`, so neither needs a case.)
    #[inline]
    pub fn null_transmission(&self, sp: &ShadingPoint) -> f32 {
        match self {
            Bsdf::Null(_) => 1.0,
            Bsdf::Mask(m) => m.null_transmission(sp),
            Bsdf::Blend(m) if m.flags().is_null() => {
                let w = m.weight_at(sp);
                m.bsdfs[0].null_transmission(sp) * (1.0 - w) + m.bsdfs[1].null_transmission(sp) * w
            }
            _ => 0.0,
        }
    }

    /// eval and pdf together (one call in the NEE hot path).
    #[inline]
    pub fn eval_pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> (Spectrum, f32) {
        match self {
            Bsdf::Diffuse(m) => m.eval_pdf(sp, wi, wo),
            // Models whose value and density share costly steps compute them together.
            Bsdf::Principled(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::RoughConductor(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::Conductor(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::Dielectric(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::ThinDielectric(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::RoughDielectric(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::Plastic(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::RoughPlastic(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::TwoSided(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::Phong(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::BlinnPhong(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::CookTorrance(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::PrincipledThin(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::Blend(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::NormalMap(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::BumpMap(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::Mask(m) => m.eval_pdf(sp, wi, wo),
            Bsdf::Null(m) => m.eval_pdf(sp, wi, wo),
        }
    }
}

/// The models written over [`Real`] as well, which the packet loop runs over sixteen paths at
/// once (`radia_render::wavefront`); for one path they give what [`Bsdf::eval_pdf`] and
/// [`Bsdf::sample`] give, bit for bit (the one-path functions call them).
impl Bsdf {
    /// Whether [`Bsdf::eval_pdf_r`] and [`Bsdf::sample_r`] have this model (`None` from
    /// them otherwise: the packet loop runs those paths one at a time). A model that nests
    /// others has them if its nested models do.
    #[inline]
    pub fn has_r(&self) -> bool {
        if let Bsdf::TwoSided(m) = self {
            return m.has_r();
        }
        matches!(
            self,
            Bsdf::Diffuse(_)
                | Bsdf::Conductor(_)
                | Bsdf::RoughConductor(_)
                | Bsdf::Dielectric(_)
                | Bsdf::ThinDielectric(_)
                | Bsdf::RoughDielectric(_)
                | Bsdf::Plastic(_)
                | Bsdf::RoughPlastic(_)
                | Bsdf::Phong(_)
                | Bsdf::BlinnPhong(_)
                | Bsdf::CookTorrance(_)
                | Bsdf::Principled(_)
                | Bsdf::PrincipledThin(_)
        ) || self.nested_has_r()
    }

    /// [`Bsdf::has_r`] of the models that nest others (out of line: it recurses).
    #[inline(never)]
    fn nested_has_r(&self) -> bool {
        match self {
            Bsdf::Blend(m) => m.bsdfs.iter().all(Bsdf::has_r),
            Bsdf::NormalMap(m) => m.nested.has_r(),
            Bsdf::BumpMap(m) => m.nested.has_r(),
            Bsdf::Mask(m) => m.nested.has_r(),
            Bsdf::Null(_) => true,
            _ => false,
        }
    }

    /// [`Bsdf::eval_pdf`] over any [`Real`] (lanes for which the model says 0 give 0).
    #[inline(always)]
    pub fn eval_pdf_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> Option<(Vector3<R>, R)> {
        match self {
            Bsdf::Diffuse(m) => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::Conductor(m) => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::RoughConductor(m) => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::Dielectric(m) => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::ThinDielectric(m) => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::RoughDielectric(m) => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::Plastic(m) => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::RoughPlastic(m) => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::Phong(m) => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::BlinnPhong(m) => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::CookTorrance(m) => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::TwoSided(m) => m.eval_pdf_r(sp, wi, wo),
            Bsdf::Principled(m) => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::PrincipledThin(m) => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::Blend(m) if self.has_r() => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::NormalMap(m) if self.has_r() => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::BumpMap(m) if self.has_r() => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::Mask(m) if self.has_r() => Some(m.eval_pdf_r(sp, wi, wo)),
            Bsdf::Null(m) => Some(m.eval_pdf_r(sp, wi, wo)),
            _ => None,
        }
    }

    /// [`Bsdf::sample`] over any [`Real`].
    #[inline(always)]
    pub fn sample_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> Option<BsdfSampleR<R>> {
        match self {
            Bsdf::Diffuse(m) => Some(m.sample_r(sp, wi, u2)),
            Bsdf::Conductor(m) => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::RoughConductor(m) => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::Dielectric(m) => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::ThinDielectric(m) => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::RoughDielectric(m) => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::Plastic(m) => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::RoughPlastic(m) => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::Phong(m) => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::BlinnPhong(m) => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::CookTorrance(m) => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::TwoSided(m) => m.sample_r(sp, wi, u1, u2),
            Bsdf::Principled(m) => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::PrincipledThin(m) => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::Blend(m) if self.has_r() => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::NormalMap(m) if self.has_r() => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::BumpMap(m) if self.has_r() => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::Mask(m) if self.has_r() => Some(m.sample_r(sp, wi, u1, u2)),
            Bsdf::Null(m) => Some(m.sample_r(sp, wi, u1, u2)),
            _ => None,
        }
    }
}

/// The sample record of a model that mixes a cosine-sampled diffuse lobe with one glossy
/// lobe (Phong, Blinn-Phong, Cook-Torrance) over any [`Real`]: `wo` came from the glossy
/// lobe in the lanes of `glossy`; `pdf` is the whole mixture's density of `wo` and `value`
/// its `eval`. Valid where `valid` and the density is positive and finite.
#[inline(always)]
pub(crate) fn mixture_sample_r<R: Real>(
    wo: Vector3<R>,
    pdf: R,
    valid: R::Mask,
    value: impl FnOnce() -> Vector3<R>,
) -> BsdfSampleR<R> {
    let valid = valid & pdf.greater(R::zero()) & pdf.is_finite();
    if !valid.any() {
        return BsdfSampleR::none();
    }
    BsdfSampleR {
        wo,
        weight: value().div(pdf),
        pdf,
        eta: R::one(),
        valid,
        delta: R::Mask::splat(false),
        null: R::Mask::splat(false),
    }
}

/// The lobe flags of a [`mixture_sample_r`] for one path.
#[inline(always)]
pub(crate) fn mixture_lobe(glossy: bool) -> LobeFlags {
    if glossy {
        LobeFlags::GLOSSY_REFLECTION
    } else {
        LobeFlags::DIFFUSE_REFLECTION
    }
}

/// Mean of the three channels: Mitsuba's `Texture::mean()` of an RGB constant, used for lobe
/// sampling weights.
#[inline]
pub(crate) fn mean(c: Spectrum) -> f32 {
    (c.x + c.y + c.z) * (1.0 / 3.0)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::microfacet::Shadowing;
    use crate::testing::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg32;

    /// log-uniform in [lo, hi].
    pub(crate) fn log_uniform(rng: &mut Pcg32, lo: f32, hi: f32) -> f32 {
        (lo.ln() + rng.random::<f32>() * (hi.ln() - lo.ln())).exp()
    }

    pub(crate) fn random_color(rng: &mut Pcg32) -> Spectrum {
        match rng.random_range(0..4) {
            0 => Spectrum::ZERO,
            1 => Spectrum::ONE,
            _ => Spectrum::new(rng.random(), rng.random(), rng.random()),
        }
    }

    /// Any model, with parameters spanning their extremes: α in [10⁻⁴, 1] (and anisotropic),
    /// IOR in [1.0001, 4] on either side, exponents up to 10⁵, blends and two-sided nests.
    pub(crate) fn random_bsdf(rng: &mut Pcg32, depth: u32) -> Bsdf {
        let kind = if rng.random() {
            MicrofacetType::Beckmann
        } else {
            MicrofacetType::Ggx
        };
        let alpha = log_uniform(rng, 1e-4, 1.0);
        let alpha_v = if rng.random_range(0..3) == 0 {
            log_uniform(rng, 1e-4, 1.0)
        } else {
            alpha
        };
        let dist = MicrofacetDistribution::new(kind, alpha, alpha_v, rng.random_range(0..4) != 0);
        let ior = 1.0001 + rng.random::<f32>() * 2.9999;
        let (int_ior, ext_ior) = if rng.random() { (ior, 1.0) } else { (1.0, ior) };
        let shadowing = if rng.random() {
            Shadowing::Separable
        } else {
            Shadowing::HeightCorrelated
        };
        let exponent = log_uniform(rng, 1e-3, 1e5);
        let presets = crate::ior::CONDUCTOR_PRESETS;
        let preset = presets[rng.random_range(0..presets.len())];
        let n = if depth > 0 { 17 } else { 12 };
        match rng.random_range(0..n) {
            0 => Bsdf::Diffuse(Diffuse::new(random_color(rng))),
            1 => Bsdf::Phong(Phong::new(
                random_color(rng) * 0.5,
                random_color(rng) * 0.5,
                exponent,
            )),
            2 => Bsdf::BlinnPhong(BlinnPhong::new(
                random_color(rng) * 0.5,
                random_color(rng) * 0.5,
                exponent,
            )),
            3 => Bsdf::Conductor(Conductor::new(
                preset.eta.into(),
                preset.k.into(),
                random_color(rng),
            )),
            4 => Bsdf::RoughConductor(
                RoughConductor::new(dist, preset.eta.into(), preset.k.into(), random_color(rng))
                    .with_shadowing(shadowing),
            ),
            5 => Bsdf::CookTorrance(CookTorrance::new(
                dist,
                shadowing,
                if rng.random() {
                    CookTorranceFresnel::Schlick {
                        f0: random_color(rng).into(),
                    }
                } else {
                    CookTorranceFresnel::MetallicRoughness {
                        base_color: random_color(rng).into(),
                        metallic: rng.random::<f32>().into(),
                    }
                },
            )),
            6 => Bsdf::Dielectric(Dielectric::new(int_ior, ext_ior)),
            7 => Bsdf::ThinDielectric(ThinDielectric::new(int_ior, ext_ior)),
            8 => Bsdf::RoughDielectric(RoughDielectric::new(dist, int_ior, ext_ior)),
            9 => Bsdf::Plastic(Plastic::new(
                int_ior,
                ext_ior,
                random_color(rng),
                Spectrum::ONE,
                rng.random(),
            )),
            10 => Bsdf::RoughPlastic(RoughPlastic::new(
                kind,
                alpha,
                rng.random(),
                int_ior,
                ext_ior,
                random_color(rng),
                Spectrum::ONE,
                rng.random(),
            )),
            11 => Bsdf::Null(Null),
            15 => Bsdf::Mask(Mask::new(
                if rng.random() {
                    Texture::from(rng.random::<f32>() * 1.2 - 0.1)
                } else {
                    Checkerboard::new(0.0, 1.0, UvTransform::IDENTITY).into()
                },
                random_bsdf(rng, depth - 1),
            )),
            16 => Bsdf::Blend(Blend::new(
                rng.random(),
                random_bsdf(rng, depth - 1),
                random_bsdf(rng, depth - 1),
            )),
            12 => {
                let front = random_reflective(rng, depth - 1);
                let back = random_reflective(rng, depth - 1);
                Bsdf::TwoSided(TwoSided::new(front, back))
            }
            13 => Bsdf::NormalMap(NormalMap::new(
                // Any colour, including mid-grey (a zero normal) and pure axes.
                random_color(rng).into(),
                random_bsdf(rng, depth - 1),
                PerturbOptions {
                    flip_invalid_normals: rng.random(),
                    use_shadowing_function: rng.random(),
                },
            )),
            _ => {
                let data: Vec<f32> = (0..4).map(|_| rng.random()).collect();
                let height = Bitmap::new(
                    2,
                    2,
                    1,
                    data,
                    FilterType::Bilinear,
                    WrapMode::Repeat,
                    UvTransform::IDENTITY,
                )
                .expect("valid bitmap");
                Bsdf::BumpMap(BumpMap::new(
                    height.into(),
                    log_uniform(rng, 1e-3, 1e3),
                    random_bsdf(rng, depth - 1),
                    PerturbOptions::default(),
                ))
            }
        }
    }

    fn random_reflective(rng: &mut Pcg32, depth: u32) -> Bsdf {
        loop {
            let b = random_bsdf(rng, depth);
            if !b.flags().intersects(LobeFlags::TRANSMISSION) {
                return b;
            }
        }
    }

    /// Directions including the hard cases: grazing (|cos θ| down to 10⁻⁷), exactly in the
    /// tangent plane, along the normal, below the surface, and mirror/refraction-aligned
    /// pairs (half vectors that vanish).
    pub(crate) fn random_direction(rng: &mut Pcg32) -> Vec3 {
        let phi = rng.random::<f32>() * 6.2831855;
        let z = match rng.random_range(0..8) {
            0 => 0.0,
            1 => log_uniform(rng, 1e-7, 1e-2),
            2 => -log_uniform(rng, 1e-7, 1e-2),
            3 => 1.0,
            4 => -1.0,
            _ => rng.random_range(-1.0..1.0),
        };
        dir(z, phi)
    }

    pub(crate) fn random_u(rng: &mut Pcg32) -> f32 {
        match rng.random_range(0..10) {
            0 => 0.0,
            1 => 1.0 - f32::EPSILON / 2.0,
            _ => rng.random(),
        }
    }

    /// No NaN or infinity from eval, pdf or sample over 10⁶ random calls with extreme
    /// parameters and directions; pdf and eval are never negative, samples are unit vectors.
    #[test]
    fn no_nan_or_inf() {
        let mut rng = Pcg32::seed_from_u64(0x5eed);
        let mut calls = 0usize;
        while calls < 1_000_000 {
            let b = random_bsdf(&mut rng, 2);
            for _ in 0..5000 {
                let wi = random_direction(&mut rng);
                let wo = match rng.random_range(0..4) {
                    0 => -wi,
                    1 => Vec3::new(-wi.x, -wi.y, wi.z),
                    2 => wi,
                    _ => random_direction(&mut rng),
                };
                let u = Vec2::new(random_u(&mut rng), random_u(&mut rng));
                check_finite("fuzz", &b, wi, wo, random_u(&mut rng), u);
                calls += 3;
            }
        }
    }
}
