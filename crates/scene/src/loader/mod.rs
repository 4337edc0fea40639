//! Mitsuba 3 XML scene loader, and the PLY and OBJ mesh readers it uses.
//!
//! [`load_mitsuba_xml`] follows Mitsuba 3.9.1's parser (`src/core/parser.cpp`) and plugins
//! for the subset radia renders; anything outside it (an unknown element, plugin type or
//! parameter, a value of the wrong type) is an error naming the file, line and column, never
//! silently ignored. Two stages:
//!
//! 1. `xml.rs`: the text becomes plugin nodes with typed properties (`$name` substitution,
//!    `<default>`, values, `<transform>`, ids and references).
//! 2. `build.rs`, `shapes.rs`, `bsdfs.rs`, `emitters.rs`, `textures.rs`: each plugin reads its parameters,
//!    with Mitsuba's names, defaults and checks, into the [`SceneDescription`]. Parameters a
//!    plugin does not read are reported.

mod bsdfs;
mod build;
mod displacement;
mod emitters;
mod error;
pub mod fuzzing;
mod image;
mod mesh;
mod obj;
mod ply;
mod props;
mod shapes;
mod textures;
mod transform;
mod xml;

#[cfg(test)]
mod tests;

pub use self::image::decode_rgb_image;
pub use error::{LoadError, TextPos};

use crate::{Mesh, SceneDescription};
use glam::DMat4;
use std::path::Path;

/// Loads a Mitsuba 3 XML scene. `defines` are Mitsuba's `-D name=value`: they override the
/// file's `<default>`s, and as in Mitsuba one that no attribute uses is an error.
///
/// Warnings (dropped degenerate triangles, several sensors, ...) are printed to stderr; use
/// [`load_mitsuba_xml_with_warnings`] to receive them instead.
pub fn load_mitsuba_xml(
    path: &Path,
    defines: &[(String, String)],
) -> Result<SceneDescription, LoadError> {
    let (scene, warnings) = load_mitsuba_xml_with_warnings(path, defines)?;
    for w in warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

/// [`load_mitsuba_xml`], returning the warnings ("file:line:col: message") instead of
/// printing them.
pub fn load_mitsuba_xml_with_warnings(
    path: &Path,
    defines: &[(String, String)],
) -> Result<(SceneDescription, Vec<String>), LoadError> {
    let doc = xml::parse_file(path, defines)?;
    build::build_scene(&doc)
}

/// [`load_mitsuba_xml_with_warnings`] of scene text, as if read from `path`: meshes and
/// images are looked up relative to its folder (the fuzzing entry point, with a folder that
/// holds nothing).
pub fn load_mitsuba_xml_str(
    path: &Path,
    text: &str,
    defines: &[(String, String)],
) -> Result<(SceneDescription, Vec<String>), LoadError> {
    let doc = xml::parse_str(path, text, defines)?;
    build::build_scene(&doc)
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
