//! Light selection for next-event estimation: which light to sample from a shading point.
//!
//! The unit of choice is the *light primitive* ([`LightPrim`]): one triangle of an emitting
//! mesh, or one whole emitter of any other kind. Three strategies ([`LightSamplerKind`]):
//!
//! * **uniform**: Mitsuba's (`src/render/scene.cpp`): every emitter equally likely, then a
//!   triangle of a mesh by area, so its images and noise can be compared with Mitsuba's.
//! * **power**: in proportion to each primitive's power (an alias table), as pbrt-v4's
//!   `PowerLightSampler`.
//! * **bvh** (the default): a light BVH after pbrt-v4's `BVHLightSampler` (Conty Estevez and
//!   Kulla 2018, `src/pbrt/lightsamplers.{h,cpp}`): the choice follows an estimate of each
//!   light's contribution at the shading point from its power, distance and orientation.
//!
//! A scene with a single light primitive builds no structure at all. Whatever the strategy,
//! the probability of a choice ([`Lights::pmf`]) is a function of the shading point and its
//! normal only, so next-event estimation and the MIS weight of an emitter hit by BSDF
//! sampling use the same number.

mod bvh;
#[cfg(test)]
mod tests;

pub use bvh::{BvhLight, LightBounds, LightBvh};

use crate::emitter::{Emitter, EmitterSample, EmitterSampleLanes};
use crate::shape::{
    uniform_sphere_directions, LightSpheres, LightTriangleTable, LightTriangles, Shape, ShapeKind,
    SurfaceInteraction,
};
use crate::Scene;
use glam::{Vec2, Vec3};
use radia_bsdf::Texture;
pub(crate) use radia_math::lanes::lanes_of;
use radia_math::lanes::{f32x16, mask, Vec3s};
use radia_math::real::{Real, Vector2};
use radia_sampling::{warp, DiscreteDistribution};

/// Queries of [`Scene::sample_emitter_directions`].
pub const LIGHT_LANES: usize = 16;

/// How next-event estimation chooses a light.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSamplerKind {
    /// Uniformly over emitters, then by area over a mesh's triangles (Mitsuba's choice).
    Uniform,
    /// In proportion to power. Like `Bvh`, leaves a constant environment to BSDF sampling
    /// (see [`Lights::build`]).
    Power,
    /// By a light BVH that accounts for distance and orientation (radia's default).
    #[default]
    Bvh,
}

impl std::str::FromStr for LightSamplerKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "uniform" => Ok(Self::Uniform),
            "power" => Ok(Self::Power),
            "bvh" => Ok(Self::Bvh),
            _ => Err(format!(
                "unknown light sampler \"{s}\" (expected uniform, power or bvh)"
            )),
        }
    }
}

impl std::fmt::Display for LightSamplerKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Uniform => "uniform",
            Self::Power => "power",
            Self::Bvh => "bvh",
        })
    }
}

/// Where a light is chosen from: the shading point and its shading normal (zero when there
/// is no surface, e.g. in a medium).
#[derive(Clone, Copy, Debug)]
pub struct LightContext {
    pub p: Vec3,
    pub n: Vec3,
}

/// One light to choose: triangle `face` of emitter `emitter` (0 for emitters that are not
/// meshes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightPrim {
    pub emitter: u32,
    pub face: u32,
}

/// The light primitives of a scene and the structure that chooses among them.
#[derive(Clone, Debug)]
pub struct Lights {
    prims: Vec<LightPrim>,
    /// Index of the first light primitive of each emitter; its faces follow.
    first_prim: Vec<u32>,
    selector: Selector,
    /// Emitters (delta lights) sampled at every vertex, outside the selector.
    split: Vec<u32>,
    /// The flat triangles among the primitives, for light sampling in lanes.
    triangles: LightTriangleTable,
    /// How each emitter's primitives are sampled in lanes, by emitter (the same for every
    /// face of a mesh: an emitting mesh has a light triangle for each).
    lane_lights: Vec<LaneLight>,
}

/// How [`Scene::sample_emitter_directions`] samples an emitter's light primitives, decided
/// once from the emitter and its shape (rather than for every lane of every packet).
#[derive(Clone, Copy, Debug)]
enum LaneLight {
    /// A constant environment of this radiance.
    Uniform(Vec3),
    /// An environment map.
    Envmap,
    /// A flat triangle of this constant radiance ([`LightTriangleTable`]).
    Triangle(Vec3),
    /// A sphere of this constant radiance: centre, radius, `flip_normals`.
    Sphere(Vec3, (Vec3, f32, bool)),
    /// A point light (`spot`: a spot light, whose falloff is then found lane by lane) at
    /// this position, of this intensity.
    Point(Vec3, Vec3, bool),
    /// A directional light: the direction towards it, its irradiance.
    Directional(Vec3, Vec3),
    /// Any other: sampled one lane at a time.
    Scalar,
}

impl LaneLight {
    fn of(emitter: &Emitter, shapes: &[Shape]) -> Self {
        match emitter {
            Emitter::Constant(light) => Self::Uniform(light.radiance),
            Emitter::Envmap(_) => Self::Envmap,
            Emitter::Area(light) => {
                let Texture::Constant(c) = light.radiance else {
                    return Self::Scalar;
                };
                let shape = &shapes[light.shape as usize];
                if shape.lane_light_triangle(0).is_some() {
                    Self::Triangle(c)
                } else if let Some(sphere) = shape.light_sphere() {
                    Self::Sphere(c, sphere)
                } else {
                    Self::Scalar
                }
            }
            Emitter::Point(light) => Self::Point(light.position, light.intensity, false),
            Emitter::Spot(light) => Self::Point(light.position, light.intensity, true),
            Emitter::Directional(light) => Self::Directional(-light.direction, light.irradiance),
        }
    }
}

#[derive(Clone, Debug)]
enum Selector {
    /// Nothing emits.
    Empty,
    /// One light primitive: chosen with probability 1.
    Single,
    /// Fixed probabilities (uniform or power).
    Table(DiscreteDistribution),
    Bvh(LightBvh),
}

impl Lights {
    /// Light primitives of `emitters` and the `kind` of structure to choose among them.
    /// `sampling_weights` (by emitter; missing entries are 1) scale each emitter's share:
    /// see [`weight_of`]. `scene_sphere` (centre, radius) bounds the geometry: lights at infinity send their
    /// power through it.
    pub fn build(
        kind: LightSamplerKind,
        emitters: &[Emitter],
        sampling_weights: &[f32],
        shapes: &[Shape],
        scene_sphere: (Vec3, f32),
    ) -> Self {
        let mut prims = Vec::new();
        let mut first_prim = Vec::with_capacity(emitters.len());
        for (e, emitter) in emitters.iter().enumerate() {
            first_prim.push(prims.len() as u32);
            for face in 0..emitter.primitive_count(shapes) {
                prims.push(LightPrim {
                    emitter: e as u32,
                    face,
                });
            }
        }
        // A constant environment is left to BSDF sampling under radia's own strategies (as
        // pbrt-v4's path integrator leaves it: `UniformInfiniteLight::SampleLi` gives no
        // sample when `allowIncompletePDF`, src/pbrt/lights.cpp): the BSDF's own samples
        // follow the BSDF times a constant, where a uniform direction over the sphere misses
        // it (half of them below the surface), and the light samples it would take go to the
        // other lights. Its density for next-event estimation is then 0, so BSDF samples that
        // escape take it at full weight: the estimate stays unbiased. Mitsuba's uniform
        // choice (`--light-sampler uniform`) samples it as Mitsuba does.
        let to_bsdf = |p: &LightPrim| {
            kind != LightSamplerKind::Uniform
                && matches!(emitters[p.emitter as usize], Emitter::Constant(_))
        };
        let split = split_lights(kind, emitters, sampling_weights);
        let excluded = |p: &LightPrim| to_bsdf(p) || split.contains(&p.emitter);
        let weight = |p: &LightPrim| {
            if excluded(p) {
                0.0
            } else {
                weight_of(sampling_weights, p.emitter)
            }
        };
        let power =
            |p: &LightPrim| emitters[p.emitter as usize].power(shapes, p.face, scene_sphere.1);
        // At most two bounded light primitives (a rectangle's two triangles, beside any
        // lights at infinity) are chosen from a table as Mitsuba chooses them (1/N per
        // emitter, in proportion to area within a mesh): weighing two such halves by
        // importance changes nothing measurable (the Cornell box: the same relMSE at 1.2× the
        // time), and against an environment the tree's share is no better than an equal one
        // (relMSE at equal spp, sobol, 64²: face-normals 6.2e-5 by the table against 7.0e-5
        // by the tree, rough-conductors 1.50e-4 against 1.45e-4), while its walk and its
        // density for every escaped ray cost a sixth of the render (twosided.xml). An
        // emitting mesh of more triangles gets the tree, which skips the triangles that face
        // away and favours the near ones (a 120-triangle sphere mesh lighting a floor and a
        // glossy wall: 2.8× less relMSE at 1.45× the time than by area).
        let bounded = prims
            .iter()
            .filter(|p| !emitters[p.emitter as usize].is_infinite() && !excluded(p))
            .count();
        let structure = if bounded <= 2 {
            LightSamplerKind::Uniform
        } else {
            kind
        };
        let selector = match (prims.len(), structure) {
            (0, _) => Selector::Empty,
            (1, _) if excluded(&prims[0]) => Selector::Empty,
            (1, _) => Selector::Single,
            (_, LightSamplerKind::Uniform) => {
                // Mitsuba: 1 / (number of emitters), or with sampling weights the emitter's
                // weight over their sum (the table normalises), then area within a mesh.
                let share = 1.0 / emitters.len() as f32;
                let weights: Vec<f32> = prims
                    .iter()
                    .map(|p| match &emitters[p.emitter as usize] {
                        Emitter::Area(a) => {
                            let shape = &shapes[a.shape as usize];
                            if shape.area > 0.0 {
                                weight(p) * share * shape.part_area(p.face) / shape.area
                            } else {
                                0.0
                            }
                        }
                        _ => weight(p) * share,
                    })
                    .collect();
                DiscreteDistribution::new(&weights).map_or(Selector::Empty, Selector::Table)
            }
            (_, LightSamplerKind::Power) => {
                let weights: Vec<f32> = prims.iter().map(|p| weight(p) * power(p)).collect();
                DiscreteDistribution::new(&weights).map_or(Selector::Empty, Selector::Table)
            }
            (_, LightSamplerKind::Bvh) => {
                let lights: Vec<BvhLight> = prims
                    .iter()
                    .map(|p| {
                        let e = &emitters[p.emitter as usize];
                        let phi = weight(p) * power(p);
                        if !(phi > 0.0) {
                            BvhLight::Off
                        } else if e.is_infinite() {
                            BvhLight::Infinite(weight(p))
                        } else {
                            bvh::light_bounds(e, shapes, p.face, phi)
                                .map_or(BvhLight::Off, BvhLight::Bounded)
                        }
                    })
                    .collect();
                // The tree's share against the lights at infinity: the mean weight of the
                // emitters in it that can be chosen (1 when no weight is set).
                let bounded: Vec<f32> = (0..emitters.len() as u32)
                    .filter(|&e| !emitters[e as usize].is_infinite() && !split.contains(&e))
                    .map(|e| weight_of(sampling_weights, e))
                    .filter(|&w| w > 0.0)
                    .collect();
                let bounded_weight = if bounded.is_empty() {
                    1.0
                } else {
                    bounded.iter().sum::<f32>() / bounded.len() as f32
                };
                LightBvh::build(&lights, bounded_weight).map_or(Selector::Empty, Selector::Bvh)
            }
        };
        let triangles =
            LightTriangleTable::new(prims.iter().map(|p| match &emitters[p.emitter as usize] {
                Emitter::Area(a) => shapes[a.shape as usize].lane_light_triangle(p.face),
                _ => None,
            }));
        let lane_lights = emitters.iter().map(|e| LaneLight::of(e, shapes)).collect();
        Self {
            prims,
            first_prim,
            selector,
            split,
            triangles,
            lane_lights,
        }
    }

    /// The delta lights sampled at every vertex, besides the light chosen among the others
    /// (see [`split_lights`]).
    pub fn split(&self) -> &[u32] {
        &self.split
    }

    /// Number of light primitives.
    pub fn len(&self) -> usize {
        self.prims.len()
    }

    /// True when next-event estimation has nothing to sample.
    pub fn is_empty(&self) -> bool {
        matches!(self.selector, Selector::Empty) && self.split.is_empty()
    }

    /// Whether next-event estimation chooses a light (besides the split ones): false when
    /// there is none to choose.
    pub fn chooses(&self) -> bool {
        !matches!(self.selector, Selector::Empty)
    }

    /// Whether [`Lights::sample`] reads its `u`: not with one light primitive or none.
    #[inline]
    pub fn choice_uses_sample(&self) -> bool {
        !matches!(self.selector, Selector::Empty | Selector::Single)
    }

    pub fn prim(&self, index: usize) -> LightPrim {
        self.prims[index]
    }

    /// The light primitive of triangle `face` of `emitter` (`face` 0 for other kinds).
    #[inline]
    pub fn prim_index(&self, emitter: u32, face: u32) -> usize {
        (self.first_prim[emitter as usize] + face) as usize
    }

    /// Chooses a light primitive from `ctx` with `u` in [0, 1): its index and probability.
    #[inline]
    pub fn sample(&self, ctx: &LightContext, u: f32) -> Option<(usize, f32)> {
        match &self.selector {
            Selector::Empty => None,
            Selector::Single => Some((0, 1.0)),
            Selector::Table(t) => {
                let s = t.sample(u);
                Some((s.index, s.pmf))
            }
            Selector::Bvh(b) => b.sample(ctx.p, ctx.n, u),
        }
    }

    /// [`Lights::sample`] for the lanes `active` of the points `p`, normals `n` and values
    /// `u`, into `out` (the other lanes untouched).
    #[inline]
    pub fn sample_lanes(
        &self,
        active: u32,
        p: Vec3s,
        n: Vec3s,
        u: f32x16,
        out: &mut [Option<(usize, f32)>; LIGHT_LANES],
    ) {
        match &self.selector {
            Selector::Empty => lanes_of(active).for_each(|k| out[k] = None),
            Selector::Single => lanes_of(active).for_each(|k| out[k] = Some((0, 1.0))),
            Selector::Table(t) => {
                let u = u.to_array();
                for k in lanes_of(active) {
                    let s = t.sample(u[k]);
                    out[k] = Some((s.index, s.pmf));
                }
            }
            Selector::Bvh(b) => b.sample_lanes(active, p, n, u, out),
        }
    }

    /// Probability that [`Lights::sample`] chooses light primitive `index` from `ctx`.
    #[inline]
    pub fn pmf(&self, ctx: &LightContext, index: usize) -> f32 {
        match &self.selector {
            Selector::Empty => 0.0,
            Selector::Single => 1.0,
            Selector::Table(t) => t.pmf(index),
            Selector::Bvh(b) => b.pmf(ctx.p, ctx.n, index),
        }
    }

    /// [`Lights::pmf`] of light primitive `index` where it is the same from every point
    /// (every light of the uniform and power choices, the lights at infinity of the BVH's);
    /// `None` where it depends on the point.
    #[inline]
    pub fn pmf_anywhere(&self, index: usize) -> Option<f32> {
        match &self.selector {
            Selector::Empty => Some(0.0),
            Selector::Single => Some(1.0),
            Selector::Table(t) => Some(t.pmf(index)),
            Selector::Bvh(b) => b.pmf_anywhere(index),
        }
    }
}

/// The `sampling_weight` of emitter `e` (1 when `weights` has no entry for it).
///
/// Mitsuba (`src/render/scene.cpp`, `update_emitter_sampling_distribution`) chooses emitter
/// e with probability w_e / Σw, so a weight says "this many times as many samples as a
/// weight-1 emitter". radia's strategies keep that meaning by multiplying each emitter's
/// share by w_e before normalising: uniform, w_e (Mitsuba's exactly); power, w_e · power;
/// the light BVH, w_e · power as the power in its importance, and for lights at infinity
/// w_e against the mean weight of the bounded emitters (see [`LightBvh::build`]). Every
/// choice's probability is computed from the same weighted numbers it is sampled with, so
/// the estimate stays unbiased for any weights ≥ 0; a weight-0 emitter is only reached by
/// BSDF sampling.
pub fn weight_of(weights: &[f32], e: u32) -> f32 {
    weights.get(e as usize).copied().unwrap_or(1.0)
}

/// The most delta lights that next-event estimation samples all of at every vertex.
pub const SPLIT_DELTA_LIGHTS_MAX: usize = 8;

/// The delta lights (point, spot, directional) that next-event estimation samples at every
/// vertex under radia's own strategies (`bvh`, `power`), each with its own shadow ray, rather
/// than choosing one light among all: light splitting. A delta light's sample takes no random
/// value and its estimate has no noise of its own but its visibility, so choosing among them
/// is where their noise comes from: a vertex lit by one of three lights gets that light's
/// estimate three times a third of the time (scenes/delta-lights.xml, 64², 1024 spp, sobol:
/// the relMSE between seeds 1.74e-4 chosen, 4.2e-5 split, at 1.25× the time). The other
/// lights are chosen among themselves as before. All of a scene's delta lights when they are
/// at most [`SPLIT_DELTA_LIGHTS_MAX`] (each costs a shadow ray at every vertex), else none: on
/// the same scene with its three lights replaced by eight point lights, splitting them cut the
/// relMSE 6.6× at 2.4× the time against Mitsuba's uniform choice (4 lights: 4.8× at 1.5×),
/// and with nine the tree's choice gained only 1.2× over the uniform one; never
/// under Mitsuba's `uniform` choice (its estimator, exactly), nor a light whose sampling
/// weight is 0 (which next-event estimation never samples, as in Mitsuba).
fn split_lights(
    kind: LightSamplerKind,
    emitters: &[Emitter],
    sampling_weights: &[f32],
) -> Vec<u32> {
    if kind == LightSamplerKind::Uniform {
        return Vec::new();
    }
    let delta: Vec<u32> = (0..emitters.len() as u32)
        .filter(|&e| emitters[e as usize].is_delta() && weight_of(sampling_weights, e) > 0.0)
        .collect();
    if delta.len() <= SPLIT_DELTA_LIGHTS_MAX {
        delta
    } else {
        Vec::new()
    }
}

/// Centre and radius of the sphere around every shape (Mitsuba's scene bounding sphere, what
/// lights at infinity shine through); the unit sphere when there are no shapes.
pub fn scene_sphere(shapes: &[Shape]) -> (Vec3, f32) {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    // A shape group's own shapes are not in the scene: its instances are (Mitsuba's scene
    // bounding box, `src/render/scene.cpp`).
    for s in shapes.iter().filter(|s| s.group.is_none()) {
        let (a, b) = match &s.kind {
            ShapeKind::Mesh(m) => m
                .positions
                .iter()
                .fold((lo, hi), |(a, b), &p| (a.min(p), b.max(p))),
            ShapeKind::Sphere { center, radius, .. } => (*center - *radius, *center + *radius),
            ShapeKind::Disk { to_world, .. } => {
                let c = to_world.transform_point3(Vec3::ZERO);
                let r = to_world.transform_vector3(Vec3::X).length()
                    + to_world.transform_vector3(Vec3::Y).length();
                (c - r, c + r)
            }
            ShapeKind::Instance(instance) => (instance.bounds[0], instance.bounds[1]),
        };
        lo = lo.min(a);
        hi = hi.max(b);
    }
    if !(lo.cmple(hi).all()) {
        return (Vec3::ZERO, 1.0);
    }
    ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-4))
}

impl Scene {
    /// Rebuilds the light selection with another strategy.
    pub fn set_light_sampler(&mut self, kind: LightSamplerKind) {
        self.lights = Lights::build(
            kind,
            &self.emitters,
            &self.sampling_weights,
            &self.shapes,
            scene_sphere(&self.shapes),
        );
    }

    /// Next-event estimation: chooses a light from `ctx` with `u_sel`, then a direction
    /// towards it with `u`. The returned pdf includes the probability of the choice (as
    /// Mitsuba's `Scene::sample_emitter_direction`). Visibility is not tested.
    #[inline]
    pub fn sample_emitter_direction(
        &self,
        ctx: &LightContext,
        u_sel: f32,
        u: Vec2,
    ) -> Option<EmitterSample> {
        let (index, pmf) = self.lights.sample(ctx, u_sel)?;
        self.sample_light_prim(self.lights.prim(index), pmf, ctx.p, u)
    }

    /// Next-event estimation's sample of split light `i` (the emitter `lights.split()[i]`,
    /// sampled at every vertex besides the chosen light: see `split_lights`) from `p`; its
    /// density is 1 (no choice, a delta light).
    #[inline]
    pub fn sample_split_light(&self, i: usize, p: Vec3) -> Option<EmitterSample> {
        let e = self.lights.split[i];
        self.emitters[e as usize].sample_direction(&self.shapes, p, 0, Vec2::ZERO)
    }

    /// [`Scene::sample_split_light`] for the lanes `active` of sixteen points `p` at once:
    /// lane k of `out` becomes, bit for bit, what it returns for lane k's point (other lanes
    /// are left as they are).
    pub fn sample_split_lights(
        &self,
        i: usize,
        active: u32,
        p: Vec3s,
        out: &mut EmitterSampleLanes,
    ) {
        let e = self.lights.split[i];
        out.valid &= !active;
        let (lanes, at, radiance) = match self.lights.lane_lights[e as usize] {
            LaneLight::Point(position, intensity, spot) => {
                let spots = if spot { active } else { 0 };
                ((active, spots, 0), position, intensity)
            }
            LaneLight::Directional(towards, irradiance) => ((0, 0, active), towards, irradiance),
            _ => unreachable!("split lights are delta lights"),
        };
        let (at, radiance) = (Vec3s::splat(at), Vec3s::splat(radiance));
        self.delta_light_samples(lanes, |_| e, p, at, radiance, f32x16::ONE, out);
    }

    /// The light sample of light primitive `prim`, chosen with probability `pmf`, from `p`.
    #[inline(always)]
    fn sample_light_prim(
        &self,
        prim: LightPrim,
        pmf: f32,
        p: Vec3,
        u: Vec2,
    ) -> Option<EmitterSample> {
        let mut es =
            self.emitters[prim.emitter as usize].sample_direction(&self.shapes, p, prim.face, u)?;
        es.pdf *= pmf;
        Some(es)
    }

    /// [`Scene::sample_emitter_direction`] for the lanes `active` of sixteen queries at
    /// once, from the points `p` with shading normals `n`, choice values `u_sel` and
    /// position values `u`: lane k of `out` becomes, bit for bit, what it returns for lane
    /// k's values (other lanes are left as they are). The light is chosen lane by lane; area
    /// lights of constant radiance on flat triangles that are small seen from their lane and
    /// on spheres seen from outside, constant environments, environment maps and point, spot
    /// and directional lights are then sampled in lanes ([`crate::shape::LightTriangles`],
    /// [`crate::shape::LightSpheres`], [`crate::emitter::Envmap::sample_directions`], a
    /// spot's falloff lane by lane), every other light one lane at a time.
    pub fn sample_emitter_directions(
        &self,
        active: u32,
        p: Vec3s,
        n: Vec3s,
        u_sel: f32x16,
        u: Vector2<f32x16>,
        out: &mut EmitterSampleLanes,
    ) {
        let mut triangles = LightTriangles::new();
        let mut spheres = LightSpheres::new();
        let mut chosen = [(
            LightPrim {
                emitter: 0,
                face: 0,
            },
            0.0,
        ); LIGHT_LANES];
        let mut pmf = f32x16::ONE;
        let mut radiance = Vec3s::splat(Vec3::ZERO);
        // Lanes that chose a constant environment.
        let mut uniform = 0u32;
        // Lanes that chose the environment map (`envmap`, an emitter index).
        let (mut mapped, mut envmap) = (0u32, None);
        // Lanes that chose a point or spot light (`spots`), at `light_p`, or a directional
        // light, towards `light_p`.
        let (mut points, mut spots, mut directional) = (0u32, 0u32, 0u32);
        let mut light_p = Vec3s::splat(Vec3::ZERO);
        // Lanes whose light is sampled one lane at a time (in one place at the end, so that
        // the scalar sample is inlined once).
        let mut scalar = 0u32;
        out.valid &= !active;
        let mut choices = [None; LIGHT_LANES];
        self.lights.sample_lanes(active, p, n, u_sel, &mut choices);
        for k in lanes_of(active) {
            let Some((index, prim_pmf)) = choices[k] else {
                continue;
            };
            let prim = self.lights.prim(index);
            chosen[k] = (prim, prim_pmf);
            pmf.set_lane(k, prim_pmf);
            match self.lights.lane_lights[prim.emitter as usize] {
                LaneLight::Uniform(r) => {
                    uniform |= 1 << k;
                    radiance.set_lane(k, r);
                    continue;
                }
                // (A scene has one environment: another map would go to the scalar code.)
                LaneLight::Envmap if *envmap.get_or_insert(prim.emitter) == prim.emitter => {
                    mapped |= 1 << k;
                    continue;
                }
                LaneLight::Triangle(r) => {
                    triangles.push(k, index as u32);
                    radiance.set_lane(k, r);
                    continue;
                }
                LaneLight::Sphere(r, sphere) => {
                    spheres.push(k, sphere);
                    radiance.set_lane(k, r);
                    continue;
                }
                LaneLight::Point(position, intensity, spot) => {
                    points |= 1 << k;
                    spots |= u32::from(spot) << k;
                    light_p.set_lane(k, position);
                    radiance.set_lane(k, intensity);
                    continue;
                }
                LaneLight::Directional(towards, irradiance) => {
                    directional |= 1 << k;
                    light_p.set_lane(k, towards);
                    radiance.set_lane(k, irradiance);
                    continue;
                }
                _ => {}
            }
            scalar |= 1 << k;
        }
        let zero = Vec3s::splat(Vec3::ZERO);
        if uniform != 0 {
            let m = mask(uniform);
            out.valid |= uniform;
            out.delta &= !uniform;
            out.d = Vec3s::select(m, uniform_sphere_directions(u), out.d);
            out.dist = m.select(f32x16::splat(f32::INFINITY), out.dist);
            out.p = Vec3s::select(m, zero, out.p);
            out.n = Vec3s::select(m, zero, out.n);
            out.p_error = Vec3s::select(m, zero, out.p_error);
            out.pdf = m.select(f32x16::splat(warp::uniform_sphere_pdf()) * pmf, out.pdf);
            out.radiance = Vec3s::select(m, radiance, out.radiance);
        }
        if points | directional != 0 {
            let lanes = (points, spots, directional);
            let emitter = |k: usize| chosen[k].0.emitter;
            self.delta_light_samples(lanes, emitter, p, light_p, radiance, pmf, out);
        }
        if let Some(Emitter::Envmap(map)) = envmap.map(|e| &self.emitters[e as usize]) {
            map.sample_directions(mapped, u, pmf, out);
        }
        for (lanes, samples) in [
            (
                triangles.lanes(),
                (triangles.lanes() != 0).then(|| triangles.sample(&self.lights.triangles, p, u)),
            ),
            (
                spheres.lanes(),
                (spheres.lanes() != 0).then(|| spheres.sample(p, u)),
            ),
        ] {
            let Some(s) = samples else { continue };
            scalar |= lanes & !s.done;
            let valid = lanes & s.done & s.valid;
            if valid == 0 {
                continue;
            }
            let m = mask(valid);
            out.valid |= valid;
            out.delta &= !valid;
            out.d = Vec3s::select(m, s.d, out.d);
            out.dist = m.select(s.dist, out.dist);
            out.p = Vec3s::select(m, s.p, out.p);
            out.n = Vec3s::select(m, s.n, out.n);
            out.p_error = Vec3s::select(m, s.p_error, out.p_error);
            out.pdf = m.select(s.pdf * pmf, out.pdf);
            out.radiance = Vec3s::select(m, radiance, out.radiance);
        }
        for k in lanes_of(scalar) {
            let (prim, prim_pmf) = chosen[k];
            let es = self.sample_light_prim(prim, prim_pmf, p.lane(k), u.lane(k));
            out.set(k, es.as_ref());
        }
    }

    /// The samples of the delta lights chosen by [`Scene::sample_emitter_directions`], bit
    /// for bit `PointLight::sample_direction`, `SpotLight::sample_direction` and
    /// `DirectionalLight::sample_direction` (density 1, times the choice's `pmf`): lanes
    /// `points` from the points `p` towards the lights at `light_p` of intensities
    /// `radiance` (`spots` of them spot lights, whose falloff is found lane by lane from
    /// lane k's `emitter(k)`), lanes `directional` towards the directions `light_p` with
    /// irradiances `radiance`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn delta_light_samples(
        &self,
        (points, spots, directional): (u32, u32, u32),
        emitter: impl Fn(usize) -> u32,
        p: Vec3s,
        light_p: Vec3s,
        mut radiance: Vec3s,
        pmf: f32x16,
        out: &mut EmitterSampleLanes,
    ) {
        let delta = light_p - p;
        let dist2 = delta.length_squared();
        let dist = dist2.sqrt();
        let d = delta.div(dist);
        // A point light's radiance; a spot light's is found below.
        radiance = Vec3s::select(mask(points & !spots), radiance.div(dist2), radiance);
        // No sample at the light's own position (or from a NaN point).
        let mut valid = points & dist2.simd_gt(f32x16::ZERO).to_bitmask();
        for k in lanes_of(valid & spots) {
            let Emitter::Spot(spot) = &self.emitters[emitter(k) as usize] else {
                unreachable!("a spot lane chose a spot light");
            };
            let falloff = spot.falloff_towards(d.lane(k));
            if falloff > 0.0 {
                radiance.set_lane(k, spot.intensity * (falloff / dist2.lane(k)));
            } else {
                valid &= !(1 << k);
            }
        }
        valid |= directional;
        let m = mask(valid);
        let at_infinity = mask(directional);
        let zero = Vec3s::splat(Vec3::ZERO);
        out.valid |= valid;
        out.delta |= valid;
        out.d = Vec3s::select(m, Vec3s::select(at_infinity, light_p, d), out.d);
        out.dist = m.select(
            at_infinity.select(f32x16::splat(f32::INFINITY), dist),
            out.dist,
        );
        out.p = Vec3s::select(m, Vec3s::select(at_infinity, zero, light_p), out.p);
        out.n = Vec3s::select(m, zero, out.n);
        out.p_error = Vec3s::select(m, zero, out.p_error);
        out.pdf = m.select(pmf, out.pdf);
        out.radiance = Vec3s::select(m, radiance, out.radiance);
    }

    /// Density with which [`Scene::sample_emitter_direction`] from `ctx` produces the
    /// direction to emitter `emitter` found by BSDF sampling: at the hit `si` (area lights)
    /// or along the escaped direction `d` (environments).
    #[inline]
    pub fn pdf_emitter_direction(
        &self,
        ctx: &LightContext,
        emitter: u32,
        si: Option<&SurfaceInteraction>,
        d: Vec3,
    ) -> f32 {
        let face = si.map_or(0, |s| s.face);
        self.chosen_times(ctx, emitter, face, || {
            self.emitters[emitter as usize].pdf_direction(&self.shapes, ctx.p, si, d)
        })
    }

    /// [`Scene::pdf_emitter_direction`] of the environment `env` along an escaped ray, given
    /// the emitter's own density `pdf_direction` of that direction
    /// ([`crate::Emitter::eval_environment_pdf`]).
    #[inline]
    pub fn pdf_environment(&self, ctx: &LightContext, env: u32, pdf_direction: f32) -> f32 {
        self.chosen_times(ctx, env, 0, || pdf_direction)
    }

    /// The probability with which light selection picks the environment `env`: the same from
    /// every point ([`Lights::pmf_anywhere`]; the light BVH keeps lights at infinity outside
    /// the tree), what [`Scene::pdf_environment`] multiplies the direction's density by (0: it
    /// gives 0).
    #[inline]
    pub fn environment_pmf(&self, env: u32) -> f32 {
        self.lights
            .pmf_anywhere(self.lights.prim_index(env, 0))
            .expect("lights at infinity are chosen apart from any point")
    }

    /// The probability that light selection from `ctx` picks light primitive `face` of
    /// `emitter`, times the emitter's own density (asked for only when that probability is
    /// not 0).
    #[inline(always)]
    fn chosen_times(
        &self,
        ctx: &LightContext,
        emitter: u32,
        face: u32,
        pdf_direction: impl FnOnce() -> f32,
    ) -> f32 {
        let pmf = self.lights.pmf(ctx, self.lights.prim_index(emitter, face));
        if pmf == 0.0 {
            return 0.0;
        }
        pmf * pdf_direction()
    }
}
