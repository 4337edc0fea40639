//! glTF 2.0 scenes (<https://registry.khronos.org/glTF/specs/2.0/glTF-2.0.html>), read with
//! the `gltf` crate and mapped onto radia's scene description.
//!
//! ```text
//! radia render model.glb --spp 64 --resolution 640x480 --camera 1
//! ```
//!
//! # What is read, and how
//! - **Files**: `.gltf` (JSON) with external buffers (paths relative to the file,
//!   percent-decoded) or `data:` URIs (base64), and binary `.glb` with its `BIN` chunk
//!   (`data.rs`). Every problem (unreadable or short buffer, truncated GLB, a bad accessor,
//!   an index out of range, invalid JSON) is an error naming the glTF file, the object
//!   (`mesh 0 primitive 1: accessor 3 ...`) and what is wrong.
//! - **Extensions**: `KHR_lights_punctual` and `KHR_materials_emissive_strength` are read.
//!   Any other extension in `extensionsRequired` is an error naming it; one that is only in
//!   `extensionsUsed` gives a single warning listing them (the asset renders without it).
//! - **Nodes** (`nodes.rs`): the default scene (`scene`, else the first of `scenes`, else
//!   every root node when the file has no scene), every node of it, with each node's
//!   world transform = parent's · local (`matrix`, or T·R·S). Skins, morph targets and
//!   animations are ignored with a warning (the rest pose is rendered).
//! - **Meshes** (`mesh.rs`): triangle primitives (`TRIANGLES`, and `TRIANGLE_STRIP`/`FAN`
//!   unrolled as the specification's §3.7.2.1 defines), indexed or not; positions,
//!   normals (transformed by the inverse transpose), the uv set the material's textures
//!   name (`texCoord`, default `TEXCOORD_0`), and for normal-mapped primitives tangents
//!   (`TANGENT`, else MikkTSpace's: `tangents.rs`). Without normals the
//!   primitive is flat-shaded, as the specification requires. A node whose world
//!   transform has a negative determinant has its winding reversed (§3.7.2.1), so front
//!   faces stay counter-clockwise. Point and line primitives have no area: they are
//!   skipped with a warning. Zero-area triangles are dropped (with a warning).
//! - **Textures** (`textures.rs`): base colour, metallic-roughness, normal and emissive
//!   textures from embedded, data-URI or external PNG/JPEG images, with the samplers'
//!   wrap modes and magnification filter.
//! - **Materials** (`material.rs`): the metallic-roughness model onto radia's
//!   `cooktorrance` (see there for the mapping, `doubleSided`, alpha modes, emission).
//! - **Lights** (`lights.rs`): `KHR_lights_punctual` in glTF's photometric units, see
//!   [`lights`](self::lights) for the conversion (1 cd → 1 W/sr: none).
//! - **Camera** (`camera.rs`): the first perspective camera that a node of the scene
//!   instances (or the one `--camera N` names), else a default camera framing the scene's
//!   bounds; see [`camera`](self::camera).
//!
//! # Defaults that are radia's choice
//! - **Film**: `--resolution` if given; else 768 pixels wide (Mitsuba's default film
//!   width) and 768 / aspect high, the aspect being the camera's `aspectRatio`, else 4:3
//!   (768 × 576, Mitsuba's default film). Gaussian filter and 4 spp with radia's default
//!   sampler, as an XML scene that names none (`--spp` sets the count).
//! - **Environment**: a file with no punctual light and no emissive material gets a
//!   constant environment of radiance 1 (a white sky: a diffuse white surface facing it
//!   renders at 1), so that something is visible, as glTF viewers light such files with a
//!   default environment. [`GltfOptions::environment`] (`--environment R` on the command
//!   line) sets that radiance for any file, lights or not; 0 turns it off.
//! - **Integrator**: Mitsuba's `path` with its defaults (unbounded depth, roulette from
//!   depth 5).

mod camera;
mod data;
pub mod lights;
pub mod material;
mod mesh;
mod nodes;
mod tangents;
mod textures;

use crate::LoadError;
use data::GltfFile;
use glam::DMat4;
use radia_math::Spectrum;
use radia_scene::{
    EmitterDesc, FilmDesc, Geometry, IntegratorDesc, SamplerDesc, SceneDescription, ShapeDesc,
};
use std::path::Path;

/// The extensions radia reads.
pub const SUPPORTED_EXTENSIONS: &[&str] =
    &["KHR_lights_punctual", "KHR_materials_emissive_strength"];

/// What the caller (the command line) may choose for a glTF file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GltfOptions {
    /// The index (in the file's `cameras`) of the camera to render from; default: the first
    /// perspective camera a node of the scene instances.
    pub camera: Option<usize>,
    /// Film size; default 768 wide and as high as the camera's aspect ratio says.
    pub resolution: Option<(u32, u32)>,
    /// Radiance of a constant environment added to the scene; default: 1 if the file has no
    /// light and no emissive material, else none. `Some(0)` adds none.
    pub environment: Option<f32>,
}

/// Mitsuba's default film width, which the film keeps when only an aspect ratio is known.
pub const DEFAULT_FILM_WIDTH: u32 = 768;

/// The radiance of the environment added to a file without lights.
pub const DEFAULT_ENVIRONMENT_RADIANCE: f32 = 1.0;

/// Loads a glTF 2.0 file (`.gltf` or `.glb`), printing warnings to stderr.
pub fn load_gltf(path: &Path, options: &GltfOptions) -> Result<SceneDescription, LoadError> {
    let (scene, warnings) = load_gltf_with_warnings(path, options)?;
    for w in warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

/// [`load_gltf`], returning the warnings ("file: message") instead of printing them.
pub fn load_gltf_with_warnings(
    path: &Path,
    options: &GltfOptions,
) -> Result<(SceneDescription, Vec<String>), LoadError> {
    let file = GltfFile::open(path)?;
    let err = |msg: String| LoadError::in_file(path, msg);
    let mut warnings = Vec::new();
    let mut warn = |msg: String| warnings.push(format!("{}: {msg}", path.display()));
    let instances = nodes::flatten(&file.doc, &mut warn).map_err(err)?;
    let shapes = read_shapes(&file, path, &instances, &mut warn)?;
    let mut emitters: Vec<EmitterDesc> = instances
        .lights
        .iter()
        .filter_map(|l| lights::build_light(l, &mut warn))
        .collect();
    let lit = !emitters.is_empty() || shapes.iter().any(|s| s.emission.is_some());
    let environment = match options.environment {
        Some(r) => r,
        None if lit => 0.0,
        None => DEFAULT_ENVIRONMENT_RADIANCE,
    };
    if !(environment >= 0.0 && environment.is_finite()) {
        return Err(err(format!(
            "the environment radiance must be a finite value >= 0, got {environment}"
        )));
    }
    if environment > 0.0 {
        emitters.push(EmitterDesc::Constant {
            radiance: Spectrum::splat(environment),
        });
    }

    let (camera, film) =
        camera::build_camera(&file.doc, &instances, &shapes, options, &mut warn).map_err(err)?;

    let desc = SceneDescription {
        integrator: IntegratorDesc::default(),
        camera,
        film,
        sampler: SamplerDesc::default(),
        shapes,
        shape_groups: Vec::new(),
        // glTF positions are f32 in the file: rendered where they are.
        world_origin: glam::DVec3::ZERO,
        emitters,
        sampling_weights: Default::default(),
    };
    Ok((desc, warnings))
}

/// The surfaces of a glTF file as a Mitsuba XML scene's `<shape type="gltf">` uses them
/// (radia's extension): every mesh primitive of the default scene with its material
/// (emissive ones glow), each node's transform followed by `to_world`. The file's cameras
/// and lights are not part of a shape: the XML scene frames and lights it, and a warning
/// says what was left out.
pub(crate) fn load_gltf_shapes(
    path: &Path,
    to_world: DMat4,
    warn: &mut dyn FnMut(String),
) -> Result<Vec<ShapeDesc>, LoadError> {
    let file = GltfFile::open(path)?;
    let mut warn = |msg: String| warn(format!("{}: {msg}", path.display()));
    let mut instances =
        nodes::flatten(&file.doc, &mut warn).map_err(|e| LoadError::in_file(path, e))?;
    for inst in &mut instances.meshes {
        inst.to_world = to_world * inst.to_world;
    }
    let (lights, cameras) = (instances.lights.len(), instances.cameras.len());
    if lights + cameras > 0 {
        warn(format!(
            "<shape type=\"gltf\"> takes the file's surfaces only: its {lights} light(s) and \
             {cameras} camera(s) are not used"
        ));
    }
    read_shapes(&file, path, &instances, &mut warn)
}

/// The shapes of the mesh instances, each primitive with its material.
fn read_shapes(
    file: &GltfFile,
    path: &Path,
    instances: &nodes::Instances<'_>,
    warn: &mut dyn FnMut(String),
) -> Result<Vec<ShapeDesc>, LoadError> {
    let err = |msg: String| LoadError::in_file(path, msg);
    let unsupported = data::unsupported_used(&file.doc);
    if !unsupported.is_empty() {
        warn(format!(
            "the file uses extension(s) radia does not support, which are ignored: {}",
            unsupported.join(", ")
        ));
    }
    let mut shapes = Vec::new();
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut images = textures::Images::new(file, &dir);
    let mut materials = material::Materials::new();
    let mut mesh_warnings = mesh::Warnings::default();
    for inst in &instances.meshes {
        for prim in inst.mesh.primitives() {
            let mat = materials
                .get(prim.material(), &mut images, &mut *warn)
                .map_err(err)?;
            if mat.cut_out {
                continue;
            }
            let tex_coord = mat.tex_coord.unwrap_or(0);
            let Some(shape) = mesh::build_primitive(
                file,
                inst,
                &prim,
                tex_coord,
                mat.normal_mapped,
                &mut mesh_warnings,
            )
            .map_err(err)?
            else {
                continue;
            };
            shapes.push(ShapeDesc {
                geometry: Geometry::Mesh(shape),
                bsdf: mat.bsdf.clone(),
                emission: mat.emission.clone(),
                origin: format!(
                    "{}: mesh {} primitive {}",
                    path.display(),
                    inst.mesh.index(),
                    prim.index()
                ),
            });
        }
    }
    mesh_warnings.report(&mut *warn);
    Ok(shapes)
}

/// The film: `resolution`, else [`DEFAULT_FILM_WIDTH`] wide with the given aspect.
fn film(resolution: Option<(u32, u32)>, aspect: Option<f32>) -> FilmDesc {
    let (width, height) = resolution.unwrap_or_else(|| {
        let aspect = aspect.unwrap_or(4.0 / 3.0);
        let h = (DEFAULT_FILM_WIDTH as f32 / aspect).round().max(1.0) as u32;
        (DEFAULT_FILM_WIDTH, h)
    });
    FilmDesc {
        width,
        height,
        ..FilmDesc::default()
    }
}
