//! The typed scene: camera, shapes and their BVH, emitters, light selection. It knows no
//! file format: the readers in `radia-formats` (Mitsuba XML, glTF, PLY, OBJ, images) build
//! its [`SceneDescription`], and [`Scene::build`] makes that renderable.

pub mod accel;
mod aov;
pub mod camera;
pub mod description;
pub mod emitter;
mod fingerprint;
pub mod lights;
pub mod memory;
mod shadow_lanes;
pub mod shape;
mod spherical;

pub use accel::{Accel, Hit, PacketHits, RayPacket, PACKET_LANES};
pub use camera::{look_at, Camera};
pub use description::*;
pub use emitter::{Emitter, EmitterSample, EmitterSampleLanes};
pub use lights::{LightContext, LightSamplerKind, Lights};
pub use shadow_lanes::ShadowLanes;
use shape::{DiskHits, MeshHits, ShapeKind, SphereHits};
pub use shape::{Shape, SurfaceInteraction, SurfaceLanes};

use glam::Vec3;
use radia_bsdf::{Bsdf, ShadingPoint};
use radia_math::lanes::lanes_of;
use radia_math::Ray;

/// Mitsuba's relative ray epsilon (`include/mitsuba/core/constants.h`: 1500 · 2⁻²⁴). Ray
/// origins are not offset by it (see [`offset_origin`]); it survives as the relative amount
/// by which shadow rays stop short of their target, [`SHADOW_EPSILON`], as in Mitsuba.
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
    /// Where render space's origin lies in the scene file's world coordinates
    /// ([`SceneDescription::world_origin`]).
    pub world_origin: glam::DVec3,
    /// Each emitter's `sampling_weight`, by emitter index.
    pub sampling_weights: Vec<f32>,
    /// Some surface lets light through (a `mask` or `null` BSDF): shadow rays that hit
    /// something must then look at what they hit ([`Scene::transmittance`]).
    has_null_surfaces: bool,
    /// [`Bsdf::reads_surface_frame`] of each BSDF, by index ([`Scene::shading_point`]).
    reads_surface_frame: Vec<bool>,
    accel: Accel,
}

impl Scene {
    pub fn build(desc: SceneDescription) -> Self {
        let mut shapes = Vec::with_capacity(desc.shapes.len());
        let mut bsdfs = Vec::with_capacity(desc.shapes.len());
        let mut emitters = Vec::new();
        let mut sampling_weights = Vec::new();
        for (i, s) in desc.shapes.into_iter().enumerate() {
            let emitter = s.emission.map(|radiance| {
                sampling_weights.push(desc.sampling_weights.shape(i));
                emitters.push(Emitter::Area(emitter::AreaLight {
                    shape: i as u32,
                    radiance,
                }));
                (emitters.len() - 1) as u32
            });
            bsdfs.push(s.bsdf);
            shapes.push(Shape::new(s.geometry, i as u32, emitter));
        }
        // The shape groups' shapes after the scene's own (so that a shape's index among the
        // scene's shapes is its place in the file, as `shape_index` counts), each with its
        // own material; their bounds, in the group's space, bound the instances.
        let mut group_bounds = Vec::with_capacity(desc.shape_groups.len());
        for (g, group) in desc.shape_groups.into_iter().enumerate() {
            let mut bounds = [Vec3::INFINITY, Vec3::NEG_INFINITY];
            for s in group {
                let mut shape = Shape::new(s.geometry, bsdfs.len() as u32, None);
                shape.group = Some(g as u32);
                let [lo, hi] = accel::shape_bounds(&shape);
                bounds = [bounds[0].min(lo), bounds[1].max(hi)];
                bsdfs.push(s.bsdf);
                shapes.push(shape);
            }
            group_bounds.push(bounds);
        }
        for shape in &mut shapes {
            if let shape::ShapeKind::Instance(instance) = &mut shape.kind {
                instance.bounds = instance.world_bounds(group_bounds[instance.group as usize]);
            }
        }
        let mut environment = None;
        for (j, e) in desc.emitters.iter().enumerate() {
            sampling_weights.push(desc.sampling_weights.emitter(j));
            let e = Emitter::from_desc(e);
            if e.is_environment() {
                environment = Some(emitters.len() as u32);
            }
            emitters.push(e);
        }
        let lights = Lights::build(
            LightSamplerKind::default(),
            &emitters,
            &sampling_weights,
            &shapes,
            lights::scene_sphere(&shapes),
        );
        let accel = Accel::build(&shapes);
        let has_null_surfaces = bsdfs.iter().any(|b| b.flags().is_null());
        let reads_surface_frame = bsdfs.iter().map(Bsdf::reads_surface_frame).collect();
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
            world_origin: desc.world_origin,
            sampling_weights,
            has_null_surfaces,
            reads_surface_frame,
            accel,
        }
    }

    pub fn primitive_count(&self) -> usize {
        self.accel.len()
    }

    /// The closest surface along `ray`.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceInteraction> {
        let hit = self.accel.intersect(&self.shapes, ray)?;
        Some(self.interaction(&hit, ray))
    }

    /// Per active lane of `rays` the closest surface (None where the ray escapes or the lane
    /// is inactive): what [`Scene::intersect`] gives for that lane's ray (when two surfaces
    /// are hit at exactly the same distance, possibly the other one;
    /// [`Accel::intersect_packet`]). [`Scene::intersect_packet_lanes`], one lane at a time.
    pub fn intersect_packet(
        &self,
        rays: &RayPacket,
        out: &mut [Option<SurfaceInteraction>; PACKET_LANES],
    ) {
        let mut lanes = SurfaceLanes::new();
        self.intersect_packet_lanes(rays, &mut lanes);
        for (k, si) in out.iter_mut().enumerate() {
            *si = lanes.get(k);
        }
    }

    /// [`Scene::intersect_packet`] into lanes: `out.hit` is the lanes with a hit, and each of
    /// their fields holds what [`Scene::intersect`] gives for that lane's ray.
    pub fn intersect_packet_lanes(&self, rays: &RayPacket, out: &mut SurfaceLanes) {
        let hits = self.accel.intersect_packet(&self.shapes, rays);
        out.hit = 0;
        // Hits on mesh triangles, spheres and disks are gathered and their interactions
        // computed together (`shape::MeshHits`, `SphereHits`, `DiskHits`); hits on instances,
        // and the lanes those hand back, one by one. The lanes are sorted by kind first, so
        // that only the gatherings of kinds hit are made (zeroing all three, kilobytes, for
        // every packet was 1.5-3% of the render time of scenes of triangles only).
        let (mut mesh_lanes, mut sphere_lanes, mut disk_lanes) = (0u32, 0u32, 0u32);
        let mut owners = [[0u32; 2]; PACKET_LANES];
        let mut one_by_one = 0u32;
        for lane in lanes_of(hits.hit) {
            owners[lane] = self.accel.owner(hits.prim[lane] as usize);
            let lanes = match &self.shapes[owners[lane][0] as usize].kind {
                ShapeKind::Mesh(mesh) if MeshHits::takes(mesh) => &mut mesh_lanes,
                ShapeKind::Sphere { .. } => &mut sphere_lanes,
                ShapeKind::Disk { .. } => &mut disk_lanes,
                _ => &mut one_by_one,
            };
            *lanes |= 1 << lane;
        }
        let kind_of = |lane: usize| &self.shapes[owners[lane][0] as usize].kind;
        if mesh_lanes != 0 {
            let mut meshes = MeshHits::new();
            for lane in lanes_of(mesh_lanes) {
                let ShapeKind::Mesh(mesh) = kind_of(lane) else {
                    unreachable!("a lane of a mesh")
                };
                let [shape, face] = owners[lane];
                meshes.push(lane, mesh, shape, face, hits.prim[lane]);
            }
            one_by_one |= meshes.interactions(&self.accel, &hits, rays, out);
        }
        if sphere_lanes != 0 {
            let mut spheres = SphereHits::new();
            for lane in lanes_of(sphere_lanes) {
                spheres.push(lane, owners[lane][0], kind_of(lane));
            }
            one_by_one |= spheres.interactions(&hits, rays, out);
        }
        if disk_lanes != 0 {
            let mut disks = DiskHits::new();
            for lane in lanes_of(disk_lanes) {
                disks.push(lane, owners[lane][0], kind_of(lane));
            }
            one_by_one |= disks.interactions(&hits, rays, out);
        }
        for lane in lanes_of(one_by_one) {
            let hit = hits.hit(lane).expect("a lane with a hit");
            let si = self.interaction(&hit, &rays.ray(lane));
            out.set(lane, Some(&si));
        }
    }

    /// The surface interaction of `hit`, found for `ray`.
    #[inline(always)]
    fn interaction(&self, hit: &Hit, ray: &Ray) -> SurfaceInteraction {
        let prim = self.accel.primitive(&self.shapes, hit.prim as usize);
        if let accel::Primitive::Instance { shape } = prim {
            return self.instance_interaction(shape, hit, ray);
        }
        self.shapes[prim.shape() as usize].interaction(hit, &prim, ray.o, ray.d)
    }

    /// The interaction at `hit` on instance `instance`: found in its group's space, with the
    /// very ray its traversal traced there, and moved back to world space.
    #[inline(never)]
    fn instance_interaction(&self, instance: u32, hit: &Hit, ray: &Ray) -> SurfaceInteraction {
        let ShapeKind::Instance(inst) = &self.shapes[instance as usize].kind else {
            unreachable!("an instance primitive belongs to an instance");
        };
        let local = inst.local_ray(ray, ray.t_max);
        let group = self.accel.group(inst.group);
        let prim = group.primitive(&self.shapes, hit.inner as usize);
        let inner = Hit {
            t: hit.t,
            prim: hit.inner,
            bary: hit.bary,
            inner: 0,
        };
        let si = self.shapes[prim.shape() as usize].interaction(&inner, &prim, local.o, local.d);
        inst.to_world(&si, ray.d, instance)
    }

    /// True when something blocks `ray` before `ray.t_max`.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.accel.occluded(&self.shapes, ray)
    }

    /// Bit i set when the ray of lane i of `rays` is blocked before its t_max
    /// ([`Scene::occluded`] per lane; inactive lanes clear).
    #[inline]
    pub fn occluded_packet(&self, rays: &RayPacket) -> u32 {
        self.accel.occluded_packet(&self.shapes, rays)
    }

    /// The fraction of light that arrives along the shadow ray `ray`: 1 when nothing blocks
    /// it, 0 when an opaque surface does, and the product of the null transmissions
    /// ([`Bsdf::null_transmission`]) of the `mask`/`null` surfaces it crosses otherwise, 0
    /// when it would cross more than `max_crossings` of them (each crossing is a bounce
    /// against `max_depth`, as for the BSDF-sampled path through them).
    ///
    /// Mitsuba 3.9.1 blocks its shadow rays at every surface instead (`ray_test` has no
    /// alpha test: see `crates/bsdf/src/mask.rs`), so that point lights cast black shadows
    /// through holes. The cost in a scene without such surfaces is one test of a flag per
    /// blocked shadow ray.
    #[inline]
    pub fn transmittance(&self, ray: &Ray, max_crossings: u32) -> f32 {
        if !self.occluded(ray) {
            return 1.0;
        }
        self.transmittance_of_blocked(ray, max_crossings)
    }

    /// [`Scene::transmittance`] of a shadow ray known to be blocked ([`Scene::occluded`]).
    #[inline]
    pub fn transmittance_of_blocked(&self, ray: &Ray, max_crossings: u32) -> f32 {
        if !self.has_null_surfaces {
            return 0.0;
        }
        self.transmittance_through_nulls(ray, max_crossings)
    }

    /// [`Scene::transmittance`] of a blocked ray in a scene with null surfaces: the hits
    /// along it one by one, from the origin to `ray.t_max`.
    #[inline(never)]
    fn transmittance_through_nulls(&self, ray: &Ray, max_crossings: u32) -> f32 {
        let mut t = 1.0f32;
        let mut r = *ray;
        let mut crossings = 0u32;
        while let Some(si) = self.intersect(&r) {
            let tr = self.bsdf(&si).null_transmission(&self.shading_point(&si));
            crossings += 1;
            if tr.is_nan() || tr <= 0.0 || crossings > max_crossings {
                return 0.0;
            }
            t *= tr;
            // On from the hit, to the same end point (infinity stays infinity).
            let next = si.spawn_ray(r.d);
            let travelled = (next.o - r.o).dot(r.d);
            r = Ray::new(next.o, r.d, r.t_max - travelled);
            if r.t_max.is_nan() || r.t_max <= 0.0 {
                break;
            }
        }
        t
    }

    pub fn accel(&self) -> &Accel {
        &self.accel
    }

    #[inline]
    pub fn bsdf(&self, si: &SurfaceInteraction) -> &Bsdf {
        &self.bsdfs[self.shapes[si.shape as usize].bsdf as usize]
    }

    /// What the BSDF at `si` sees of the point ([`SurfaceInteraction::shading_point`]): only
    /// uv, with placeholder tangents and normal, for a BSDF that reads nothing else
    /// ([`Bsdf::reads_surface_frame`]); moving three vectors into the shading frame at every
    /// hit was measurable in texture-free scenes.
    #[inline]
    pub fn shading_point(&self, si: &SurfaceInteraction) -> ShadingPoint {
        if self.reads_surface_frame[self.shapes[si.shape as usize].bsdf as usize] {
            si.shading_point()
        } else {
            ShadingPoint::at_uv(si.uv)
        }
    }

    /// [`Bsdf::reads_surface_frame`] of BSDF `bsdf` (by index).
    #[inline(always)]
    pub fn bsdf_reads_surface_frame(&self, bsdf: u32) -> bool {
        self.reads_surface_frame[bsdf as usize]
    }

    /// The environment when it is an image (`envmap`): the packet loop looks up its lanes'
    /// escaped rays in it together ([`emitter::Envmap::eval_pdfs`]).
    #[inline]
    pub fn environment_map(&self) -> Option<&emitter::Envmap> {
        match &self.emitters[self.environment? as usize] {
            Emitter::Envmap(map) => Some(map),
            _ => None,
        }
    }

    /// The area emitter of the surface at `si`, if it glows.
    #[inline]
    pub fn surface_emitter(&self, si: &SurfaceInteraction) -> Option<(u32, &Emitter)> {
        self.shapes[si.shape as usize]
            .emitter
            .map(|e| (e, &self.emitters[e as usize]))
    }
}

/// Moves `p`, known up to the per-axis absolute error `p_error`, along the geometric normal
/// `n` to the side `d` points to, just far enough that the true surface is certainly behind
/// it, then one float further (pbrt-v4's `OffsetRayOrigin`, `src/pbrt/interaction.h`).
///
/// Mitsuba offsets by (1 + max|p|) · 1500 · 2⁻²⁴ instead (`Interaction::offset_p`). That
/// absolute 1 is half of a scene scaled by 10⁻⁴, and the 1500 ulps of |p| are metres in a
/// scene translated by 10⁵; an offset from the error bound of the point itself is as small
/// as it can safely be at every scale and position.
#[inline]
pub fn offset_origin(p: Vec3, p_error: Vec3, n: Vec3, d: Vec3) -> Vec3 {
    let dist = n.abs().dot(p_error);
    let offset = if n.dot(d) >= 0.0 { n * dist } else { -n * dist };
    let po = p + offset;
    // Round away from p, so that the rounding of the addition cannot undo the offset.
    Vec3::new(
        step_away(po.x, offset.x),
        step_away(po.y, offset.y),
        step_away(po.z, offset.z),
    )
}

/// The next float after `x` in the direction of `o`'s sign (`x` itself when `o` is zero or
/// `x` is not finite): `f32::next_up` or `next_down`, in integer arithmetic without
/// branches, as this runs for every ray leaving a surface.
#[inline(always)]
fn step_away(x: f32, o: f32) -> f32 {
    const SIGN: u32 = 0x8000_0000;
    let ob = o.to_bits();
    // From ±0, step as if from a zero of o's sign: to the smallest subnormal of that sign.
    let bits = if x == 0.0 { ob & SIGN } else { x.to_bits() };
    // +1 (away from zero) when x and o have the same sign, −1 (towards it) otherwise.
    let step = (((bits ^ ob) as i32) >> 31) | 1;
    let stepped = f32::from_bits(bits.wrapping_add(step as u32));
    if o == 0.0 || !x.is_finite() {
        x
    } else {
        stepped
    }
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
        Ray::new(
            offset_origin(self.p, self.p_error, self.n, d),
            d,
            f32::INFINITY,
        )
    }

    /// A shadow ray towards the exactly known point `target` (a point light's position),
    /// stopping just short of it.
    #[inline]
    pub fn spawn_ray_to(&self, target: Vec3) -> Ray {
        let o = offset_origin(self.p, self.p_error, self.n, target - self.p);
        shadow_ray(o, target)
    }

    /// The shadow ray of the emitter sample `es` taken from this point ([`ShadowEnds::ray`]).
    /// Always inlined: called, it returned the ray through memory in pieces that the caller
    /// read back whole, a store-forwarding stall (5% of the packet loop on the Cornell box).
    #[inline(always)]
    pub fn shadow_ray(&self, es: &EmitterSample) -> Ray {
        self.shadow_ends(es).ray()
    }

    /// What [`Self::shadow_ray`] joins, for the ray to be made later
    /// ([`ShadowEnds::ray`], or sixteen at once by [`ShadowLanes`]).
    #[inline(always)]
    pub fn shadow_ends(&self, es: &EmitterSample) -> ShadowEnds {
        let at_infinity = !es.dist.is_finite();
        ShadowEnds {
            p: self.p,
            p_error: self.p_error,
            n: self.n,
            target: if at_infinity { es.d } else { es.p },
            target_n: es.n,
            target_error: es.p_error,
            at_infinity,
        }
    }
}

/// The two ends of a shadow ray before either is moved off its surface: the point it leaves
/// (its position, error bound and geometric normal) and the emitter sample's point with its
/// own, or for a light at infinity the direction towards it.
#[derive(Clone, Copy, Debug)]
pub struct ShadowEnds {
    pub p: Vec3,
    pub p_error: Vec3,
    pub n: Vec3,
    /// The point aimed at, or the direction when `at_infinity`.
    pub target: Vec3,
    pub target_n: Vec3,
    pub target_error: Vec3,
    pub at_infinity: bool,
}

impl ShadowEnds {
    /// The shadow ray: to a point on a surface, both ends offset off their surfaces
    /// (pbrt-v4's `SpawnRayTo` between two interactions), so that neither the surface left
    /// nor the one aimed at can occlude it; towards a light at infinity, from the offset
    /// origin along the direction.
    #[inline(always)]
    pub fn ray(&self) -> Ray {
        if self.at_infinity {
            Ray::new(
                offset_origin(self.p, self.p_error, self.n, self.target),
                self.target,
                f32::INFINITY,
            )
        } else {
            let o = offset_origin(self.p, self.p_error, self.n, self.target - self.p);
            let t = offset_origin(
                self.target,
                self.target_error,
                self.target_n,
                o - self.target,
            );
            shadow_ray(o, t)
        }
    }
}

/// The ray from `o` to `target`, stopping the relative [`SHADOW_EPSILON`] short of it as
/// Mitsuba's `Interaction::spawn_ray_to` does.
#[inline]
fn shadow_ray(o: Vec3, target: Vec3) -> Ray {
    let delta = target - o;
    let dist = delta.length();
    Ray::new(o, delta / dist, dist * (1.0 - SHADOW_EPSILON))
}

#[cfg(test)]
mod tests {
    use super::step_away;

    #[test]
    fn step_away_is_next_up_or_next_down() {
        let xs = [
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::from_bits(1),
            -f32::from_bits(1),
            f32::MAX,
            f32::MIN,
            1e5,
            -3.7e-20,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        for &x in &xs {
            for o in [1e-3f32, -1e-3, 0.0, -0.0] {
                let want = if o > 0.0 && x.is_finite() {
                    x.next_up()
                } else if o < 0.0 && x.is_finite() {
                    x.next_down()
                } else {
                    x
                };
                assert_eq!(
                    step_away(x, o).to_bits(),
                    want.to_bits(),
                    "x {x:e}, o {o:e}"
                );
            }
        }
    }
}
