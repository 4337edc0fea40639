//! The typed scene: camera, shapes and their BVH, emitters; and the loaders that build it
//! (Mitsuba 3 XML, PLY and OBJ meshes).

pub mod accel;
pub mod camera;
pub mod description;
pub mod emitter;
mod fingerprint;
pub mod lights;
pub mod loader;
pub mod memory;
pub mod shape;
mod spherical;

pub use accel::Accel;
pub use camera::{look_at, Camera};
pub use description::*;
pub use emitter::{Emitter, EmitterSample};
pub use lights::{LightContext, LightSamplerKind, Lights};
pub use loader::{load_mitsuba_xml, LoadError};
pub use shape::{Shape, SurfaceInteraction};

use glam::Vec3;
use radia_bsdf::{Bsdf, ShadingPoint};
use radia_math::Ray;

/// Ray offsets as Mitsuba's `Interaction::offset_p` (`include/mitsuba/render/interaction.h`):
/// the origin moves along the geometric normal by (1 + max|p|) · 1500 · 2⁻²⁴, and shadow rays
/// stop short by a ten times larger relative epsilon.
pub const RAY_EPSILON: f32 = 1500.0 * f32::EPSILON / 2.0;
pub const SHADOW_EPSILON: f32 = RAY_EPSILON * 10.0;

/// A scene ready to render.
pub struct Scene {
    pub camera: Camera,
    pub film: FilmDesc,
    pub sampler: SamplerDesc,
    pub integrator: IntegratorDesc,
    pub shapes: Vec<Shape>,
    pub bsdfs: Vec<Bsdf>,
    pub emitters: Vec<Emitter>,
    /// The emitter seen by rays that leave the scene, if any.
    pub environment: Option<u32>,
    /// Light selection for next-event estimation (radia's default strategy unless
    /// [`Scene::set_light_sampler`] chose another).
    pub lights: Lights,
    accel: Accel,
}

impl Scene {
    pub fn build(desc: SceneDescription) -> Self {
        let mut shapes = Vec::with_capacity(desc.shapes.len());
        let mut bsdfs = Vec::with_capacity(desc.shapes.len());
        let mut emitters = Vec::new();
        for (i, s) in desc.shapes.into_iter().enumerate() {
            let emitter = s.emission.map(|radiance| {
                emitters.push(Emitter::Area(emitter::AreaLight {
                    shape: i as u32,
                    radiance,
                }));
                (emitters.len() - 1) as u32
            });
            bsdfs.push(s.bsdf);
            shapes.push(Shape::new(s.geometry, i as u32, emitter));
        }
        let mut environment = None;
        for e in &desc.emitters {
            let e = Emitter::from_desc(e);
            if e.is_environment() {
                environment = Some(emitters.len() as u32);
            }
            emitters.push(e);
        }
        let lights = Lights::build(
            LightSamplerKind::default(),
            &emitters,
            &shapes,
            lights::scene_sphere(&shapes),
        );
        let accel = Accel::build(&shapes);
        Self {
            camera: Camera::new(&desc.camera, desc.film.width, desc.film.height),
            film: desc.film,
            sampler: desc.sampler,
            integrator: desc.integrator,
            shapes,
            bsdfs,
            emitters,
            environment,
            lights,
            accel,
        }
    }

    pub fn primitive_count(&self) -> usize {
        self.accel.primitives.len()
    }

    /// The closest surface along `ray`.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceInteraction> {
        let hit = self.accel.intersect(&self.shapes, ray)?;
        let prim = &self.accel.primitives[hit.prim as usize];
        Some(self.shapes[prim.shape() as usize].interaction(&hit, prim, ray.o, ray.d))
    }

    /// True when something blocks `ray` before `ray.t_max`.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.accel.occluded(&self.shapes, ray)
    }

    pub fn accel(&self) -> &Accel {
        &self.accel
    }

    #[inline]
    pub fn bsdf(&self, si: &SurfaceInteraction) -> &Bsdf {
        &self.bsdfs[self.shapes[si.shape as usize].bsdf as usize]
    }

    /// The area emitter of the surface at `si`, if it glows.
    #[inline]
    pub fn surface_emitter(&self, si: &SurfaceInteraction) -> Option<(u32, &Emitter)> {
        self.shapes[si.shape as usize]
            .emitter
            .map(|e| (e, &self.emitters[e as usize]))
    }
}

/// Offsets `p` along the geometric normal `n` towards the side `d` points to.
#[inline]
pub fn offset_origin(p: Vec3, n: Vec3, d: Vec3) -> Vec3 {
    let mag = (1.0 + p.abs().max_element()) * RAY_EPSILON;
    let mag = if n.dot(d) >= 0.0 { mag } else { -mag };
    p + n * mag
}

impl SurfaceInteraction {
    /// What the BSDF and its textures see of this point: uv, and the parametrisation's
    /// tangents and the geometric normal in the local shading frame.
    #[inline]
    pub fn shading_point(&self) -> ShadingPoint {
        ShadingPoint {
            uv: self.uv,
            dp_du: self.frame.to_local(self.dp_du),
            dp_dv: self.frame.to_local(self.dp_dv),
            n: self.frame.to_local(self.n),
        }
    }

    /// A ray leaving the surface in the world-space direction `d`.
    #[inline]
    pub fn spawn_ray(&self, d: Vec3) -> Ray {
        Ray::new(offset_origin(self.p, self.n, d), d, f32::INFINITY)
    }

    /// A shadow ray towards `target`, stopping just short of it.
    #[inline]
    pub fn spawn_ray_to(&self, target: Vec3) -> Ray {
        let o = offset_origin(self.p, self.n, target - self.p);
        let delta = target - o;
        let dist = delta.length();
        Ray::new(o, delta / dist, dist * (1.0 - SHADOW_EPSILON))
    }

    /// A shadow ray in direction `d` towards something at infinity.
    #[inline]
    pub fn spawn_ray_towards_infinity(&self, d: Vec3) -> Ray {
        self.spawn_ray(d)
    }
}
