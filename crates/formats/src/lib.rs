//! Scene file formats: each reader turns a file into radia's typed [`SceneDescription`],
//! which [`radia_scene::Scene::build`] then makes renderable (BVH, light sampler, ...), the
//! same way for every format. Dependencies run one way: the CLI uses this crate, this crate
//! uses the scene and BSDF crates, and those know no file format.
//!
//! | format | extension | reader |
//! | --- | --- | --- |
//! | glTF 2.0 (JSON with external or embedded buffers, or binary GLB) | `.gltf`, `.glb` | [`gltf::load_gltf`] (module [`gltf`]) |
//! | Mitsuba 3 XML | anything else | [`radia_scene::load_mitsuba_xml`] |
//!
//! The Mitsuba XML, PLY and OBJ readers still live in `radia_scene::loader` and will move
//! into this crate (issue #10's layout item), so that `crates/scene` knows no file format;
//! [`load_scene`] already hides where they are.

pub mod fuzzing;
pub mod gltf;

pub use gltf::{load_gltf, load_gltf_with_warnings, GltfOptions};
pub use radia_scene::LoadError;

use radia_scene::SceneDescription;
use std::path::Path;

/// The file formats radia reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneFormat {
    /// glTF 2.0, `.gltf` (JSON) or `.glb` (binary).
    Gltf,
    /// Mitsuba 3 XML.
    MitsubaXml,
}

impl SceneFormat {
    /// The format a file name says: `.gltf`/`.glb` (any case) is glTF, everything else is
    /// read as Mitsuba XML (which reports a non-XML file as such).
    pub fn of_path(path: &Path) -> Self {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("gltf") | Some("glb") => SceneFormat::Gltf,
            _ => SceneFormat::MitsubaXml,
        }
    }
}

/// What the command line can say about how a scene is read.
#[derive(Clone, Debug, Default)]
pub struct SceneOptions {
    /// Mitsuba's `-D name=value` (XML only: glTF files have no parameters).
    pub defines: Vec<(String, String)>,
    /// glTF: which camera, the film size, the default environment.
    pub gltf: GltfOptions,
}

/// Reads the scene at `path` in the format its extension names ([`SceneFormat::of_path`]),
/// printing warnings to stderr.
pub fn load_scene(path: &Path, options: &SceneOptions) -> Result<SceneDescription, LoadError> {
    match SceneFormat::of_path(path) {
        SceneFormat::Gltf => {
            if let Some((name, _)) = options.defines.first() {
                return Err(LoadError::in_file(
                    path,
                    format!("-D {name}=...: glTF files have no parameters to define (-D applies to Mitsuba XML scenes)"),
                ));
            }
            load_gltf(path, &options.gltf)
        }
        SceneFormat::MitsubaXml => radia_scene::load_mitsuba_xml(path, &options.defines),
    }
}
