//! Scene file formats: each reader turns a file into radia's typed [`SceneDescription`],
//! which [`radia_scene::Scene::build`] then makes renderable (BVH, light sampler, ...), the
//! same way for every format. Dependencies run one way: the CLI uses this crate, this crate
//! uses the scene and BSDF crates, and those know no file format.
//!
//! | format | extension | reader |
//! | --- | --- | --- |
//! | glTF 2.0 (JSON with external or embedded buffers, or binary GLB) | `.gltf`, `.glb` | [`gltf::load_gltf`] (module [`gltf`]) |
//! | Mitsuba 3 XML | anything else | [`mitsuba::load_mitsuba_xml`] (module [`mitsuba`]) |
//! | PLY (ASCII and binary), Wavefront OBJ | `.ply`, `.obj` (named by a scene) | [`load_ply`], [`load_obj`] |
//! | images: OpenEXR, Radiance HDR, PNG, JPEG | named by a scene | [`decode_rgb_image`] (module `image`) |
//!
//! Every reader reports a problem as a [`LoadError`] naming the file and, where there is
//! one, the line and column. `mesh` turns what a mesh reader found into a
//! [`radia_scene::Mesh`] the same way for every format (normals, degenerate triangles).
//!
//! The PLY and OBJ readers are this crate's own rather than `ply-rs-bw` or `tobj`: they read
//! what Mitsuba's `ply.cpp` and `obj.cpp` read, with its semantics (ASCII and both binary
//! byte orders, any vertex property layout with `u`/`v`, `s`/`t` or `texture_u`/`texture_v`,
//! `face_normals`, `flip_tex_coords`, one vertex per distinct OBJ `v/vt/vn` triple), and a
//! little more (polygons fan-triangulated, negative OBJ indices), every problem an error
//! naming the file and line (`ply.rs`, `obj.rs`).
//! Measured on a 4,004,450-triangle mesh (2 cores, loaded machine, median of 5, 2026-12-02):
//! binary PLY (116 MB) 0.68 s here, read and finished into a mesh, against 2.45 s for
//! `ply-rs-bw` 1.0 parsing into typed vertex and face records; OBJ (442 MB, `v/vt/vn`) 7.5 s
//! here against 7.9 s for `tobj` 4.0 (`single_index`, parse only).

mod error;
pub mod fuzzing;
pub mod gltf;
mod image;
mod mesh;
pub mod mitsuba;
mod obj;
mod ply;

pub use error::{LoadError, TextPos};
pub use gltf::{load_gltf, load_gltf_with_warnings, GltfOptions};
pub use image::decode_rgb_image;
pub use mitsuba::{load_mitsuba_xml, load_mitsuba_xml_str, load_mitsuba_xml_with_warnings};

use glam::DMat4;
use radia_scene::{Mesh, SceneDescription};
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
        SceneFormat::MitsubaXml => load_mitsuba_xml(path, &options.defines),
    }
}

/// Reads a Wavefront OBJ file as Mitsuba's `obj` shape with the identity transform
/// (`flip_tex_coords`: v → 1 − v, Mitsuba's default for OBJ). Normals missing from the file
/// are recomputed; degenerate triangles are dropped.
pub fn load_obj(path: &Path, flip_tex_coords: bool) -> Result<Mesh, LoadError> {
    let data = read_regular_file(path)
        .map_err(|e| LoadError::in_file(path, format!("cannot read mesh file: {e}")))?;
    obj_from_bytes(path, &data, flip_tex_coords)
}

/// [`load_obj`] of the file's bytes (`path` names it in errors).
pub fn obj_from_bytes(path: &Path, data: &[u8], flip_tex_coords: bool) -> Result<Mesh, LoadError> {
    let raw = obj::parse_obj(&String::from_utf8_lossy(data), flip_tex_coords, false)
        .map_err(|e| LoadError::at_line(path, e.line, e.message))?;
    let (m, _) = mesh::finalize(raw, &DMat4::IDENTITY, false, false)
        .map_err(|e| LoadError::in_file(path, e))?;
    Ok(m)
}

/// Reads a PLY file (ASCII or binary) as Mitsuba's `ply` shape with the identity transform.
/// Normals missing from the file are recomputed; degenerate triangles are dropped.
pub fn load_ply(path: &Path, flip_tex_coords: bool) -> Result<Mesh, LoadError> {
    let data = read_regular_file(path)
        .map_err(|e| LoadError::in_file(path, format!("cannot read mesh file: {e}")))?;
    ply_from_bytes(path, &data, flip_tex_coords)
}

/// [`load_ply`] of the file's bytes (`path` names it in errors).
pub fn ply_from_bytes(path: &Path, data: &[u8], flip_tex_coords: bool) -> Result<Mesh, LoadError> {
    let raw =
        ply::parse_ply(data, flip_tex_coords, false).map_err(|e| LoadError::in_file(path, e))?;
    let (m, _) = mesh::finalize(raw, &DMat4::IDENTITY, false, false)
        .map_err(|e| LoadError::in_file(path, e))?;
    Ok(m)
}

/// `std::fs::read` of a regular file only: a device (`/dev/zero`, a FIFO) named as a mesh
/// or image would otherwise be read until memory runs out, or block forever.
pub(crate) fn read_regular_file(path: &Path) -> std::io::Result<Vec<u8>> {
    if NO_DISK.with(std::cell::Cell::get) {
        return Err(std::io::Error::other("file access is disabled (fuzzing)"));
    }
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        let what = if meta.is_dir() {
            "a directory"
        } else {
            "not a regular file"
        };
        return Err(std::io::Error::other(format!(
            "{} is {what}",
            path.display()
        )));
    }
    std::fs::read(path)
}

thread_local! {
    /// Set while [`without_disk`] runs: every file read of the loaders fails.
    static NO_DISK: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs `f` with the loaders' file reads disabled on this thread (fuzzing: a scene names
/// meshes and images, and must not reach the real disk).
pub(crate) fn without_disk<R>(f: impl FnOnce() -> R) -> R {
    struct Reset;
    impl Drop for Reset {
        fn drop(&mut self) {
            NO_DISK.with(|d| d.set(false));
        }
    }
    NO_DISK.with(|d| d.set(true));
    let _reset = Reset;
    f()
}
