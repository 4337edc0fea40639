//! radia's `classic` integrator: the textbook local illumination model with Whitted-style
//! mirror reflection and refraction, for previews and teaching.
//!
//! ```xml
//! <integrator type="classic">
//!     <rgb name="ambient" value="0.05"/>
//!     <string name="attenuation" value="1, 0, 0.5"/>   <!-- 1/(a + b d + c d²) -->
//!     <string name="shading" value="gouraud"/>          <!-- flat | gouraud | phong -->
//!     <boolean name="shadows" value="true"/>
//!     <integer name="max_depth" value="5"/>             <!-- Whitted recursion -->
//! </integrator>
//! ```
//!
//! At a surface, L = Le + ambient·kd + Σ_lights f(wi, wl)·cos θl · E_l · V, where f is the
//! scene's own BSDF (`diffuse` gives the Lambert term kd/π; radia's `phong` and `blinnphong`
//! add their specular lobes, so one scene file renders with the path tracer and with this
//! model), kd its diffuse reflectance (the AOV albedo), E_l what the light delivers (a
//! point or spot light's intensity times the attenuation, by default the inverse-square
//! law; a directional light's irradiance) and V a hard shadow ray. With the radiometric
//! conventions of the path tracer, the ambient 0, a point light and a diffuse scene give
//! exactly the path tracer's direct illumination (`max_depth` = 2).
//!
//! * Area lights are lit by one point sampled on them per sample (the same estimator as
//!   the path tracer's light sampling, without MIS): soft shadows that converge with the
//!   sample count, where a "centre" would put a point light inside the lamp's geometry.
//!   Environment emitters only show as the background (light them with `ambient`).
//! * Surfaces whose BSDF has only delta lobes (`conductor`, `dielectric`,
//!   `thindielectric`) are traced Whitted-style: every delta lobe is followed, weighted by
//!   its probability and weight (Fresnel for a dielectric), to `max_depth` segments.
//! * A `mask` is shaded with its opacity-weighted nested BSDF, plus what lies behind it
//!   times its transparency; shadow rays pass through cut-outs (`Scene::transmittance`).
//! * `shading` on triangle meshes: `phong` evaluates at every hit with the interpolated
//!   normal; `gouraud` evaluates at the triangle's three vertices (their normals, the view
//!   from each vertex) and interpolates the colours barycentrically; `flat` evaluates once
//!   at the centroid with the face normal. Analytic shapes (sphere, disk) have no vertices
//!   and are always shaded per hit.

use crate::integrator::Integrator;
use crate::path::PathStats;
use glam::{Vec2, Vec3};
use radia_bsdf::ShadingPoint;
use radia_math::{Frame, Ray, Spectrum};
use radia_sampling::{SampleStream, Sampler};
use radia_scene::shape::ShapeKind;
use radia_scene::{ClassicDesc, ClassicShading, Emitter, Scene, SurfaceInteraction};

pub struct ClassicIntegrator<'a> {
    desc: &'a ClassicDesc,
    /// Longest path in segments (camera ray included).
    max_depth: u32,
}

/// First sample dimension of the area-light choices (one 3-value block per light and bounce).
const DIMS: u32 = 2;

impl Integrator for ClassicIntegrator<'_> {
    fn li<S: Sampler>(
        &self,
        scene: &Scene,
        ray: Ray,
        _pos: Vec2,
        sampler: &mut SampleStream<'_, S>,
        stats: &mut PathStats,
    ) -> Spectrum {
        self.trace(scene, ray, 0, sampler, stats)
    }
}

impl<'a> ClassicIntegrator<'a> {
    pub fn new(scene: &Scene, desc: &'a ClassicDesc) -> Self {
        Self {
            desc,
            max_depth: scene.integrator.max_depth.max(1) as u32,
        }
    }

    fn trace<S: Sampler>(
        &self,
        scene: &Scene,
        ray: Ray,
        depth: u32,
        sampler: &mut SampleStream<'_, S>,
        stats: &mut PathStats,
    ) -> Spectrum {
        stats.rays += 1;
        let Some(si) = scene.intersect(&ray) else {
            return match scene.environment {
                Some(env) => scene.emitters[env as usize].eval_environment(ray.d),
                None => Spectrum::ZERO,
            };
        };
        let mut result = scene
            .surface_emitter(&si)
            .map_or(Spectrum::ZERO, |(_, e)| e.eval_surface(&si));
        let bsdf = scene.bsdf(&si);
        if !bsdf.flags().has_smooth() {
            // ---- Whitted: follow every delta lobe ----
            if depth + 1 < self.max_depth {
                let sp = si.shading_point();
                for u1 in [0.0, 1.0 - f32::EPSILON] {
                    let Some(bs) = bsdf.sample(&sp, si.wi, u1, Vec2::ZERO) else {
                        continue;
                    };
                    if (u1 > 0.0 && bs.pdf >= 1.0) || bs.weight == Spectrum::ZERO {
                        continue; // a single lobe: already followed
                    }
                    let d = si.frame.to_world(bs.wo);
                    let li = self.trace(scene, si.spawn_ray(d), depth + 1, sampler, stats);
                    result += bs.weight * bs.pdf.min(1.0) * li;
                }
            }
            return result;
        }
        result += self.shade(scene, &si, ray.o, depth, sampler, stats);
        // ---- A `mask`'s transparent part: what lies behind, seen straight through ----
        let through = bsdf.null_transmission(&si.shading_point());
        if through > 0.0 && depth + 1 < self.max_depth {
            let behind = self.trace(scene, si.spawn_ray(ray.d), depth + 1, sampler, stats);
            result += behind * through;
        }
        result
    }

    /// The local illumination at `si` under the chosen shading.
    fn shade<S: Sampler>(
        &self,
        scene: &Scene,
        si: &SurfaceInteraction,
        eye: Vec3,
        depth: u32,
        sampler: &mut SampleStream<'_, S>,
        stats: &mut PathStats,
    ) -> Spectrum {
        // An instanced mesh's vertices are in its group's space: shaded per pixel.
        let ShapeKind::Mesh(mesh) = &scene.shapes[si.shape as usize].kind else {
            return self.local(scene, si, depth, sampler, stats);
        };
        if si.instance.is_some() {
            return self.local(scene, si, depth, sampler, stats);
        }
        if self.desc.shading == ClassicShading::Phong {
            return self.local(scene, si, depth, sampler, stats);
        }
        let idx = mesh.indices[si.face as usize].map(|i| i as usize);
        let p = idx.map(|i| mesh.positions[i]);
        let uv = mesh.uvs.as_ref().map(|uvs| idx.map(|i| uvs[i]));
        // The vertex si sees `eye` from `at` with shading normal `n`.
        let at = |at: Vec3, n: Vec3, uv: Option<Vec2>| {
            let mut v = *si;
            v.p = at;
            v.frame = Frame::from_normal_tangent(n, si.dp_du);
            v.wi = v.frame.to_local((eye - at).normalize());
            if let Some(uv) = uv {
                v.uv = uv;
            }
            v
        };
        match self.desc.shading {
            ClassicShading::Flat => {
                let c = (p[0] + p[1] + p[2]) / 3.0;
                let uvc = uv.map(|t| (t[0] + t[1] + t[2]) / 3.0);
                self.local(scene, &at(c, si.n, uvc), depth, sampler, stats)
            }
            _ => {
                let b = barycentric(si.p, p);
                let mut sum = Spectrum::ZERO;
                for k in 0..3 {
                    let n = mesh.normals.as_ref().map_or(si.n, |ns| {
                        let n = ns[idx[k]];
                        if mesh.flip_normals {
                            -n
                        } else {
                            n
                        }
                    });
                    let v = at(p[k], n, uv.map(|t| t[k]));
                    sum += self.local(scene, &v, depth, sampler, stats) * b[k];
                }
                sum
            }
        }
    }

    /// ambient·kd + Σ_lights f·cos·E·V at `si`.
    fn local<S: Sampler>(
        &self,
        scene: &Scene,
        si: &SurfaceInteraction,
        depth: u32,
        sampler: &mut SampleStream<'_, S>,
        stats: &mut PathStats,
    ) -> Spectrum {
        let bsdf = scene.bsdf(si);
        let sp: ShadingPoint = si.shading_point();
        let mut result = self.desc.ambient * bsdf.diffuse_reflectance(&sp, si.wi);
        let [a, b, c] = self.desc.attenuation;
        let inverse_square = self.desc.attenuation == [0.0, 0.0, 1.0];
        for (i, emitter) in scene.emitters.iter().enumerate() {
            if emitter.is_environment() {
                continue;
            }
            sampler.seek(DIMS + (depth * scene.emitters.len() as u32 + i as u32) * 3);
            let u = sampler.next_2d();
            let count = emitter.primitive_count(&scene.shapes);
            let face = ((sampler.next_1d() * count as f32) as u32).min(count - 1);
            let Some(es) = emitter.sample_direction(&scene.shapes, si.p, face, u) else {
                continue;
            };
            let wo = si.frame.to_local(es.d);
            let f = bsdf.eval(&sp, si.wi, wo);
            let pdf_positive = es.pdf > 0.0; // false for NaN too
            if f == Spectrum::ZERO || !pdf_positive {
                continue;
            }
            let mut e = es.radiance / es.pdf * count as f32;
            let point_like = matches!(emitter, Emitter::Point(_) | Emitter::Spot(_));
            if point_like && !inverse_square {
                let d = es.dist;
                e *= d * d / (a + b * d + c * d * d);
            }
            if self.desc.shadows {
                let shadow = si.shadow_ray(&es);
                stats.rays += 1;
                // Through cut-outs (`mask`, `null`), as the path tracer's shadow rays.
                let transmittance = scene.transmittance(&shadow, u32::MAX);
                if transmittance == 0.0 {
                    continue;
                }
                e *= transmittance;
            }
            result += f * e;
        }
        result
    }
}

/// Barycentric coordinates of `p` in triangle `t` (clamped to it).
fn barycentric(p: Vec3, t: [Vec3; 3]) -> [f32; 3] {
    let (e1, e2, d) = (t[1] - t[0], t[2] - t[0], p - t[0]);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let det = d11 * d22 - d12 * d12;
    let degenerate = det.is_nan() || det == 0.0;
    if degenerate {
        return [1.0 / 3.0; 3];
    }
    let b1 = ((d22 * d1 - d12 * d2) / det).clamp(0.0, 1.0);
    let b2 = ((d11 * d2 - d12 * d1) / det).clamp(0.0, 1.0 - b1);
    [1.0 - b1 - b2, b1, b2]
}
