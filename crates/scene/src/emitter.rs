//! Emitters: what radiates, how it is sampled for next-event estimation and what density a
//! BSDF-sampled ray that reaches it had under that sampling.

use crate::shape::{Shape, SurfaceInteraction};
use glam::{Vec2, Vec3};
use radia_math::Spectrum;
use radia_sampling::warp;

#[derive(Clone, Debug)]
pub enum Emitter {
    /// Mitsuba's `area`: one-sided, emits `radiance` on the side the shading normal faces.
    Area { shape: u32, radiance: Spectrum },
    /// Mitsuba's `constant`: `radiance` from every direction at infinity.
    Constant { radiance: Spectrum },
}

/// A direction sampled towards an emitter from a reference point.
#[derive(Clone, Copy, Debug)]
pub struct EmitterSample {
    /// Unit direction from the reference point towards the emitter (world space).
    pub d: Vec3,
    /// Distance to the sampled point (infinite for environments).
    pub dist: f32,
    /// Point on the emitter (finite emitters only).
    pub p: Vec3,
    /// Solid-angle density of `d`, not including the choice of the emitter.
    pub pdf: f32,
    /// Radiance arriving along −d if unoccluded.
    pub radiance: Spectrum,
    /// True for delta lights (reachable only by next-event estimation).
    pub is_delta: bool,
}

impl Emitter {
    pub fn is_environment(&self) -> bool {
        matches!(self, Emitter::Constant { .. })
    }

    /// Samples a direction from `ref_p` towards the emitter. `None` when the sample carries
    /// no light (back face of a one-sided emitter, degenerate geometry).
    pub fn sample_direction(
        &self,
        shapes: &[Shape],
        ref_p: Vec3,
        u: Vec2,
    ) -> Option<EmitterSample> {
        match self {
            Emitter::Area { shape, radiance } => {
                let ds = shapes[*shape as usize].sample_direction(ref_p, u)?;
                // One-sided: the emitting side is the one the normal points to.
                if ds.n.dot(ds.d) >= 0.0 {
                    return None;
                }
                Some(EmitterSample {
                    d: ds.d,
                    dist: ds.dist,
                    p: ds.p,
                    pdf: ds.pdf,
                    radiance: *radiance,
                    is_delta: false,
                })
            }
            Emitter::Constant { radiance } => {
                let d = warp::square_to_uniform_sphere(u);
                Some(EmitterSample {
                    d,
                    dist: f32::INFINITY,
                    p: Vec3::ZERO,
                    pdf: warp::uniform_sphere_pdf(),
                    radiance: *radiance,
                    is_delta: false,
                })
            }
        }
    }

    /// Radiance leaving the emitting surface at `si` towards `-ray.d` (area emitters).
    #[inline]
    pub fn eval_surface(&self, si: &SurfaceInteraction) -> Spectrum {
        match self {
            Emitter::Area { radiance, .. } => {
                if si.wi.z > 0.0 {
                    *radiance
                } else {
                    Spectrum::ZERO
                }
            }
            Emitter::Constant { .. } => Spectrum::ZERO,
        }
    }

    /// Radiance arriving along a ray that escaped the scene in direction `d`.
    #[inline]
    pub fn eval_environment(&self, _d: Vec3) -> Spectrum {
        match self {
            Emitter::Constant { radiance } => *radiance,
            Emitter::Area { .. } => Spectrum::ZERO,
        }
    }

    /// Solid-angle pdf of [`Emitter::sample_direction`] from `ref_p` for a hit at `si`
    /// (area emitters) or an escaped direction `d` (environments).
    #[inline]
    pub fn pdf_direction(
        &self,
        shapes: &[Shape],
        ref_p: Vec3,
        si: Option<&SurfaceInteraction>,
        _d: Vec3,
    ) -> f32 {
        match self {
            Emitter::Area { shape, .. } => match si {
                Some(si) => shapes[*shape as usize].pdf_direction(ref_p, si.p, si.n),
                None => 0.0,
            },
            Emitter::Constant { .. } => warp::uniform_sphere_pdf(),
        }
    }
}
