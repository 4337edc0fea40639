//! The typed scene description: what a loader (Mitsuba XML, glTF) produces and
//! [`crate::Scene::build`] consumes. Plain data in world space; no strings left to compare.

use glam::{Affine3A, DVec3, Mat3A, Vec2, Vec3, Vec4};
use radia_bsdf::{Bsdf, Texture};
use radia_math::Spectrum;
use radia_sampling::SamplerKind;

pub use crate::aov::{parse_aovs, AovDesc, AovKind, AovOutput};

/// Mitsuba's `path` integrator parameters (`src/integrators/path.cpp`).
#[derive(Clone, Debug, PartialEq)]
pub struct IntegratorDesc {
    /// Longest path in segments; −1 = unbounded (Mitsuba's default).
    pub max_depth: i32,
    /// Depth from which Russian roulette starts (Mitsuba's default 5).
    pub rr_depth: i32,
    /// Camera rays see through area emitters and escaped primary rays give 0.
    pub hide_emitters: bool,
    /// Mitsuba's `aov` integrator around the one above: the outputs written beside the image.
    pub aov: Option<AovDesc>,
    /// radia's `classic` integrator instead of the path tracer (`max_depth` then bounds the
    /// Whitted recursion).
    pub classic: Option<ClassicDesc>,
    /// radia's `npr` integrator instead of the path tracer.
    pub npr: Option<NprDesc>,
}

/// How the `npr` integrator fills surfaces.
#[derive(Clone, Debug, PartialEq)]
pub enum NprStyle {
    /// Lambert's cos θ quantised to `levels` bands, shown as kd·k/(levels − 1), or, with a
    /// `ramp` (then `levels` = its length), as the ramp's k-th colour.
    Toon {
        levels: u32,
        ramp: Option<Vec<Spectrum>>,
    },
    /// Gooch et al. 1998: k_cool = (0, 0, b) + α·kd, k_warm = (y, y, 0) + β·kd, blended by
    /// (1 + l·n)/2.
    Gooch {
        b: f32,
        y: f32,
        alpha: f32,
        beta: f32,
    },
}

/// radia's `npr` integrator (see `radia_render::npr`).
#[derive(Clone, Debug, PartialEq)]
pub struct NprDesc {
    pub style: NprStyle,
    /// Line width in pixels (0: no lines).
    pub line_width: f32,
    pub line_color: Spectrum,
    /// Neighbouring normals further apart than this (degrees) make a crease line.
    pub crease_angle: f32,
    /// A neighbour farther off the tangent plane than this fraction of the distance makes
    /// a silhouette line.
    pub depth_threshold: f32,
}

/// How the `classic` integrator shades a triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClassicShading {
    /// One evaluation per triangle: at its centroid with its face normal.
    Flat,
    /// Lighting evaluated at the three vertices (vertex normals) and interpolated.
    Gouraud,
    /// Normals interpolated, lighting evaluated at every hit.
    Phong,
}

/// radia's `classic` integrator: textbook local illumination (see `radia_render::classic`).
#[derive(Clone, Debug, PartialEq)]
pub struct ClassicDesc {
    /// Ambient radiance, multiplied by the material's diffuse reflectance.
    pub ambient: Spectrum,
    /// (a, b, c) of the attenuation 1/(a + b·d + c·d²) of point and spot lights; (0, 0, 1)
    /// is the inverse-square law.
    pub attenuation: [f32; 3],
    pub shading: ClassicShading,
    /// Shadow rays (hard shadows) on or off.
    pub shadows: bool,
}

impl Default for IntegratorDesc {
    fn default() -> Self {
        Self {
            max_depth: -1,
            rr_depth: 5,
            hide_emitters: false,
            aov: None,
            classic: None,
            npr: None,
        }
    }
}

/// Reconstruction filter of the film (`src/rfilters/*.cpp`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FilterDesc {
    /// Every sample lands in its own pixel with weight 1 (radius 0.5).
    Box,
    /// Mitsuba's default: Gaussian of `stddev` pixels truncated at `radius` = 4·stddev and shifted
    /// to reach zero there.
    Gaussian { stddev: f32 },
}

#[derive(Clone, Debug, PartialEq)]
pub struct FilmDesc {
    pub width: u32,
    pub height: u32,
    pub filter: FilterDesc,
}

impl Default for FilmDesc {
    fn default() -> Self {
        // hdrfilm defaults (src/films/hdrfilm.cpp)
        Self {
            width: 768,
            height: 576,
            filter: FilterDesc::Gaussian { stddev: 0.5 },
        }
    }
}

/// `perspective` sensor (`src/sensors/perspective.cpp`), with `fov` already converted to the
/// horizontal axis.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraDesc {
    /// Camera to world; the camera looks along local +z, local +y is up, local +x is
    /// image left (Mitsuba's convention: image x runs towards −x).
    pub to_world: Affine3A,
    /// Full horizontal field of view in degrees.
    pub fov_x_degrees: f32,
    pub near_clip: f32,
    pub far_clip: f32,
    /// The principal point's offset from the film centre, in units of the film's width and
    /// height (`principal_point_offset_x/y`, Mitsuba's `src/sensors/perspective.cpp`): the
    /// pixel at film position p sees what the centred camera sees at p + offset.
    pub principal_point_offset: Vec2,
}

/// The sensor's sampler (`src/samplers/*.cpp`). `sample_count` is as the scene gives it; the
/// renderer rounds it as the sampler requires.
#[derive(Clone, Debug, PartialEq)]
pub struct SamplerDesc {
    pub kind: SamplerKind,
    pub sample_count: u32,
    pub seed: u64,
}

impl Default for SamplerDesc {
    /// A scene that names no sampler: Mitsuba's default count (4 spp) with radia's default
    /// sampler ([`SamplerKind::DEFAULT`], Owen-scrambled Sobol; Mitsuba's would be
    /// `independent`: same expected image, more noise).
    fn default() -> Self {
        Self {
            kind: SamplerKind::DEFAULT,
            sample_count: 4,
            seed: 0,
        }
    }
}

/// A triangle mesh in world space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (unit length), or `None` for flat shading.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates.
    pub uvs: Option<Vec<Vec2>>,
    /// Per-vertex tangents of a normal-mapped glTF primitive (glTF's `TANGENT`, §3.7.2.1):
    /// xyz the unit tangent, w = ±1 the sign of the bitangent, cross(normal, xyz)·w. When
    /// present they, not ∂p/∂u, orient the shading frame (see [`crate::shape`]); `None`
    /// for every other mesh, which keeps the ∂p/∂u frame of Mitsuba.
    pub tangents: Option<Vec<Vec4>>,
    /// Counter-clockwise triangles: the geometric normal is (p1 − p0) × (p2 − p0).
    pub indices: Vec<[u32; 3]>,
    /// Mitsuba's `flip_normals`: the geometric and shading normals are negated.
    pub flip_normals: bool,
}

/// The geometry of one shape.
#[derive(Clone, Debug, PartialEq)]
pub enum Geometry {
    Mesh(Mesh),
    /// Analytic sphere (`src/shapes/sphere.cpp`), outward normals unless flipped.
    Sphere {
        center: Vec3,
        radius: f32,
        /// The linear part of the shape's `to_world` (radius included): where the unit
        /// sphere's axes go. It orients the uv parametrisation and ∂p/∂u, ∂p/∂v, as Mitsuba
        /// maps hit points back by the inverse (`to_object`); the surface itself is the
        /// sphere of `center` and `radius` whatever the matrix (a non-uniform scale does not
        /// make an ellipsoid, as in Mitsuba). `Mat3A::from_diagonal(Vec3::splat(radius))`
        /// for an unrotated sphere ([`Geometry::sphere`]).
        to_world: Mat3A,
        flip_normals: bool,
    },
    /// Analytic unit disk in the xy-plane, normal +z, mapped by `to_world` (`src/shapes/disk.cpp`).
    Disk {
        to_world: Affine3A,
        flip_normals: bool,
    },
    /// Mitsuba's `instance` (`src/shapes/instance.cpp`): shape group `group` of
    /// [`SceneDescription::shape_groups`] placed by `to_world`. Its shapes keep their own
    /// materials; the instance's `bsdf` and `emission` are unused (an instance has neither).
    Instance {
        group: u32,
        to_world: Affine3A,
    },
}

impl Geometry {
    /// An unrotated sphere: its uv poles on the z axis, u = 0 towards +x.
    pub fn sphere(center: Vec3, radius: f32, flip_normals: bool) -> Self {
        Geometry::Sphere {
            center,
            radius,
            to_world: Mat3A::from_diagonal(Vec3::splat(radius)),
            flip_normals,
        }
    }
}

/// A shape with its material and, if it glows, its `area` emitter.
#[derive(Clone, Debug)]
pub struct ShapeDesc {
    pub geometry: Geometry,
    pub bsdf: Bsdf,
    /// Radiance of the one-sided `area` emitter attached to the shape (a constant or a
    /// texture over the shape's uv).
    pub emission: Option<Texture>,
    /// Where the shape was declared (for messages): "file:line".
    pub origin: String,
}

/// Emitters that are not attached to a shape (`src/emitters/*.cpp`; see
/// [`crate::emitter`] for each one's semantics).
#[derive(Clone, Debug, PartialEq)]
pub enum EmitterDesc {
    /// `constant`: the same radiance from every direction, visible as the background.
    Constant { radiance: Spectrum },
    /// `envmap`: a latitude-longitude image at infinity, times `scale`; `to_world` is a
    /// rotation.
    Envmap {
        image: RgbImage,
        scale: f32,
        to_world: Affine3A,
        mis_compensation: bool,
    },
    /// `point`: `intensity` (W/sr) from `position`.
    Point { position: Vec3, intensity: Spectrum },
    /// `spot`: from the origin of `to_world` along its +z; angles in degrees. A
    /// `falloff_exponent` (radia extension) replaces Mitsuba's linear falloff by cos^e.
    Spot {
        to_world: Affine3A,
        intensity: Spectrum,
        cutoff_angle: f32,
        beam_width: f32,
        falloff_exponent: Option<f32>,
    },
    /// glTF's spot (`KHR_lights_punctual`): from the origin of `to_world` along its +z,
    /// `intensity` · clamp((cos θ − cos outer) / max(0.001, cos inner − cos outer), 0, 1)²;
    /// angles in degrees.
    SmoothSpot {
        to_world: Affine3A,
        intensity: Spectrum,
        inner_cone_angle: f32,
        outer_cone_angle: f32,
    },
    /// `directional`: `irradiance` (W/m²) arriving along the unit `direction` of travel.
    Directional {
        direction: Vec3,
        irradiance: Spectrum,
    },
}

impl EmitterDesc {
    /// Seen by rays that leave the scene (`constant`, `envmap`): a scene has at most one.
    pub fn is_environment(&self) -> bool {
        matches!(
            self,
            EmitterDesc::Constant { .. } | EmitterDesc::Envmap { .. }
        )
    }
}

/// A linear RGB image, row-major with row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Spectrum>,
}

/// Everything needed to render one image.
#[derive(Clone, Debug)]
pub struct SceneDescription {
    pub integrator: IntegratorDesc,
    pub camera: CameraDesc,
    pub film: FilmDesc,
    pub sampler: SamplerDesc,
    /// The scene's shapes in file order (Mitsuba's `Scene::shapes()`: instances included,
    /// shape groups not), the order `shape_index` counts.
    pub shapes: Vec<ShapeDesc>,
    /// Mitsuba's `shapegroup`s (`src/shapes/shapegroup.cpp`): shapes in the group's own
    /// space, rendered only through the [`Geometry::Instance`]s that place them. Never an
    /// emitter, an instance or another group (refused by the loader, as by Mitsuba).
    pub shape_groups: Vec<Vec<ShapeDesc>>,
    pub emitters: Vec<EmitterDesc>,
    /// Where render space's origin lies in the file's world coordinates. The loaders place
    /// the camera at the origin (positions are f32, whose spacing grows with distance from
    /// it); outputs in world coordinates, such as the `position` AOV, add this back.
    pub world_origin: DVec3,
    /// Each emitter's `sampling_weight`.
    pub sampling_weights: SamplingWeights,
}

/// Mitsuba's per-emitter `sampling_weight` (`src/render/emitter.cpp`, default 1): how much
/// next-event estimation favours the emitter relative to the others (see
/// [`crate::lights`] for how each light-selection strategy applies it). A missing entry
/// is 1, so `SamplingWeights::default()` leaves every emitter at 1.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SamplingWeights {
    /// By shape index: the weight of that shape's `area` emitter.
    pub shapes: Vec<f32>,
    /// By index into [`SceneDescription::emitters`].
    pub emitters: Vec<f32>,
}

impl SamplingWeights {
    pub fn shape(&self, index: usize) -> f32 {
        self.shapes.get(index).copied().unwrap_or(1.0)
    }

    pub fn emitter(&self, index: usize) -> f32 {
        self.emitters.get(index).copied().unwrap_or(1.0)
    }
}
