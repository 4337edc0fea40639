//! Emitters: what radiates, how a direction towards it is sampled for next-event estimation
//! and with what density a BSDF-sampled ray that reaches it would have been sampled. One file
//! per kind, as Mitsuba 3's `src/emitters/`; *which* emitter next-event estimation picks is
//! the business of [`crate::lights`].
//!
//! Conventions (Mitsuba's `Emitter` interface, `include/mitsuba/render/emitter.h`):
//!
//! * [`Emitter::sample_direction`] returns the unit direction from a reference point towards
//!   the light, its solid-angle density and the radiance arriving along it if nothing is in
//!   between. Delta lights (point, spot, directional) have density 1 by convention and return
//!   intensity / d² or irradiance in place of radiance, so the estimator is f · L / pdf for
//!   every kind.
//! * [`Emitter::pdf_direction`] is the density with which `sample_direction` produces the
//!   direction of a ray that BSDF sampling found; 0 for delta lights, which only next-event
//!   estimation reaches.
//! * Area lights are sampled one *light primitive* at a time: one triangle (`face`) of an
//!   emitting mesh, or the whole analytic shape (`face` 0). The choice of the triangle is part
//!   of light selection, so a mesh light of many triangles is many lights to the light BVH.

mod area;
mod constant;
mod directional;
mod envmap;
mod point;
mod spot;

pub use area::AreaLight;
pub use constant::ConstantLight;
pub use directional::DirectionalLight;
pub use envmap::Envmap;
pub use point::PointLight;
pub use spot::SpotLight;

use crate::description::EmitterDesc;
use crate::shape::{Shape, SurfaceInteraction};
use glam::{Vec2, Vec3};
use radia_math::lanes::{f32x16, Vec3s};
use radia_math::real::Real;
use radia_math::Spectrum;

/// Every kind of light radia knows: a closed set dispatched by `match`.
#[derive(Clone, Debug)]
pub enum Emitter {
    /// Mitsuba's `area`, attached to a shape.
    Area(AreaLight),
    /// `point`: a delta light radiating `intensity` in every direction.
    Point(PointLight),
    /// `spot`: a point light restricted to a cone.
    Spot(SpotLight),
    /// `directional`: parallel light from infinity.
    Directional(DirectionalLight),
    /// `constant`: uniform radiance from every direction at infinity.
    Constant(ConstantLight),
    /// `envmap`: a latitude-longitude image at infinity.
    Envmap(Envmap),
}

/// A direction sampled towards an emitter from a reference point.
#[derive(Clone, Copy, Debug)]
pub struct EmitterSample {
    /// Unit direction from the reference point towards the emitter (world space).
    pub d: Vec3,
    /// Distance to the sampled point (infinite for lights at infinity).
    pub dist: f32,
    /// Point on the emitter (finite emitters only).
    pub p: Vec3,
    /// Geometric normal at `p` on an area light; zero for point lights and lights at
    /// infinity.
    pub n: Vec3,
    /// Per-axis bound on the rounding error of `p` (zero where `p` is exact: point lights).
    pub p_error: Vec3,
    /// Solid-angle density of `d` (1 for delta lights). From [`Emitter::sample_direction`] it
    /// excludes the choice of the light; from `Scene::sample_emitter_direction` it includes it.
    pub pdf: f32,
    /// Radiance arriving along −d if unoccluded (intensity / d² or irradiance for delta lights).
    pub radiance: Spectrum,
    /// True for delta lights (reachable only by next-event estimation).
    pub is_delta: bool,
}

/// [`EmitterSample`]s of a packet's lanes, by component (stale where not `valid`).
#[derive(Clone, Copy, Debug)]
pub struct EmitterSampleLanes {
    /// Lanes with a sample (the one-lane `Option` is `Some`).
    pub valid: u32,
    /// Lanes whose sample is of a delta light.
    pub delta: u32,
    pub d: Vec3s,
    pub dist: f32x16,
    pub p: Vec3s,
    pub n: Vec3s,
    pub p_error: Vec3s,
    pub pdf: f32x16,
    pub radiance: Vec3s,
}

impl Default for EmitterSampleLanes {
    fn default() -> Self {
        Self::new()
    }
}

impl EmitterSampleLanes {
    pub fn new() -> Self {
        let zero = Vec3s::splat(Vec3::ZERO);
        Self {
            valid: 0,
            delta: 0,
            d: zero,
            dist: f32x16::ZERO,
            p: zero,
            n: zero,
            p_error: zero,
            pdf: f32x16::ONE,
            radiance: zero,
        }
    }

    /// Lane `k`'s sample.
    #[inline(always)]
    pub fn get(&self, k: usize) -> Option<EmitterSample> {
        (self.valid & (1 << k) != 0).then(|| EmitterSample {
            d: self.d.lane(k),
            dist: self.dist.lane(k),
            p: self.p.lane(k),
            n: self.n.lane(k),
            p_error: self.p_error.lane(k),
            pdf: self.pdf.lane(k),
            radiance: self.radiance.lane(k),
            is_delta: self.delta & (1 << k) != 0,
        })
    }

    /// Makes lane `k`'s sample `es`.
    #[inline(always)]
    pub fn set(&mut self, k: usize, es: Option<&EmitterSample>) {
        let bit = 1 << k;
        let Some(es) = es else {
            self.valid &= !bit;
            return;
        };
        self.valid |= bit;
        self.delta = (self.delta & !bit) | (u32::from(es.is_delta) << k);
        self.d.set_lane(k, es.d);
        self.dist.set_lane(k, es.dist);
        self.p.set_lane(k, es.p);
        self.n.set_lane(k, es.n);
        self.p_error.set_lane(k, es.p_error);
        self.pdf.set_lane(k, es.pdf);
        self.radiance.set_lane(k, es.radiance);
    }
}

impl Emitter {
    /// The emitter an [`EmitterDesc`] describes.
    pub fn from_desc(desc: &EmitterDesc) -> Self {
        match desc {
            EmitterDesc::Constant { radiance } => Emitter::Constant(ConstantLight {
                radiance: *radiance,
            }),
            EmitterDesc::Envmap {
                image,
                scale,
                to_world,
                mis_compensation,
            } => Emitter::Envmap(Envmap::new(image, *scale, *to_world, *mis_compensation)),
            EmitterDesc::Point {
                position,
                intensity,
            } => Emitter::Point(PointLight {
                position: *position,
                intensity: *intensity,
            }),
            EmitterDesc::Spot {
                to_world,
                intensity,
                cutoff_angle,
                beam_width,
                falloff_exponent,
            } => Emitter::Spot(SpotLight::new(
                *to_world,
                *intensity,
                *cutoff_angle,
                *beam_width,
                *falloff_exponent,
            )),
            EmitterDesc::SmoothSpot {
                to_world,
                intensity,
                inner_cone_angle,
                outer_cone_angle,
            } => Emitter::Spot(SpotLight::smooth(
                *to_world,
                *intensity,
                *inner_cone_angle,
                *outer_cone_angle,
            )),
            EmitterDesc::Directional {
                direction,
                irradiance,
            } => Emitter::Directional(DirectionalLight {
                direction: direction.normalize(),
                irradiance: *irradiance,
            }),
        }
    }

    /// Seen by rays that leave the scene (`constant`, `envmap`): Mitsuba's `is_environment`,
    /// of which a scene may have one.
    pub fn is_environment(&self) -> bool {
        matches!(self, Emitter::Constant(_) | Emitter::Envmap(_))
    }

    /// Lights at infinity (environments and directional lights): they have no position, so
    /// the light BVH keeps them apart.
    pub fn is_infinite(&self) -> bool {
        matches!(
            self,
            Emitter::Constant(_) | Emitter::Envmap(_) | Emitter::Directional(_)
        )
    }

    /// Point, spot and directional lights: of no extent, so found by light sampling only.
    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Emitter::Point(_) | Emitter::Spot(_) | Emitter::Directional(_)
        )
    }

    /// Number of light primitives: the triangles of an emitting mesh, else 1.
    pub fn primitive_count(&self, shapes: &[Shape]) -> u32 {
        match self {
            Emitter::Area(a) => shapes[a.shape as usize].part_count(),
            _ => 1,
        }
    }

    /// Samples a direction from `ref_p` towards light primitive `face` of the emitter (see
    /// the module docs). `None` when the sample carries no light (back face of a one-sided
    /// emitter, outside a spot's cone, degenerate geometry).
    #[inline]
    pub fn sample_direction(
        &self,
        shapes: &[Shape],
        ref_p: Vec3,
        face: u32,
        u: Vec2,
    ) -> Option<EmitterSample> {
        match self {
            Emitter::Area(e) => e.sample_direction(shapes, ref_p, face, u),
            Emitter::Point(e) => e.sample_direction(ref_p),
            Emitter::Spot(e) => e.sample_direction(ref_p),
            Emitter::Directional(e) => Some(e.sample_direction()),
            Emitter::Constant(e) => Some(e.sample_direction(u)),
            Emitter::Envmap(e) => e.sample_direction(u),
        }
    }

    /// Radiance leaving the emitting surface at `si` towards `si.wi` (area emitters).
    #[inline]
    pub fn eval_surface(&self, si: &SurfaceInteraction) -> Spectrum {
        match self {
            Emitter::Area(e) => e.eval(si),
            _ => Spectrum::ZERO,
        }
    }

    /// Radiance arriving along a ray that escaped the scene in direction `d`.
    #[inline]
    pub fn eval_environment(&self, d: Vec3) -> Spectrum {
        match self {
            Emitter::Constant(e) => e.radiance,
            Emitter::Envmap(e) => e.eval(d),
            _ => Spectrum::ZERO,
        }
    }

    /// [`Emitter::eval_environment_pdf`] where it is the same along every direction (a
    /// constant environment), else `None`.
    #[inline]
    pub fn uniform_environment(&self) -> Option<(Spectrum, f32)> {
        match self {
            Emitter::Constant(e) => Some((e.radiance, ConstantLight::pdf_direction())),
            _ => None,
        }
    }

    /// [`Emitter::eval_environment`] and [`Emitter::pdf_direction`] of an escaped ray's
    /// direction `d` at once (an envmap finds the direction's place in its map once for both).
    #[inline]
    pub fn eval_environment_pdf(&self, d: Vec3) -> (Spectrum, f32) {
        match self {
            Emitter::Constant(e) => (e.radiance, ConstantLight::pdf_direction()),
            Emitter::Envmap(e) => e.eval_pdf(d),
            _ => (Spectrum::ZERO, 0.0),
        }
    }

    /// Solid-angle density with which [`Emitter::sample_direction`] (for the light primitive
    /// that `si` lies on) returns the direction from `ref_p` to the hit `si` (area emitters) or
    /// the escaped direction `d` (environments). 0 for delta lights.
    #[inline]
    pub fn pdf_direction(
        &self,
        shapes: &[Shape],
        ref_p: Vec3,
        si: Option<&SurfaceInteraction>,
        d: Vec3,
    ) -> f32 {
        match self {
            Emitter::Area(e) => si.map_or(0.0, |si| e.pdf_direction(shapes, ref_p, si)),
            Emitter::Constant(_) => ConstantLight::pdf_direction(),
            Emitter::Envmap(e) => e.pdf_direction(d),
            Emitter::Point(_) | Emitter::Spot(_) | Emitter::Directional(_) => 0.0,
        }
    }

    /// Estimated power of light primitive `face` (pbrt-v4's `Light::Phi`, with the maximum
    /// RGB component standing in for the spectrum): what the power light sampler and the
    /// light BVH weight lights by. Lights at infinity send their radiance through the disk of
    /// the scene's bounding sphere of radius `scene_radius`.
    pub fn power(&self, shapes: &[Shape], face: u32, scene_radius: f32) -> f32 {
        let disk = radia_math::PI * scene_radius * scene_radius;
        match self {
            Emitter::Area(e) => e.power(shapes, face),
            Emitter::Point(e) => e.power(),
            Emitter::Spot(e) => e.power(),
            Emitter::Directional(e) => disk * e.irradiance.max_element(),
            Emitter::Constant(e) => disk * ConstantLight::solid_angle() * e.radiance.max_element(),
            Emitter::Envmap(e) => disk * e.radiance_integral(),
        }
    }
}
