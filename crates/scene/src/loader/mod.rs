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
mod emitters;
mod error;
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

/// Reads a Wavefront OBJ file as Mitsuba's `obj` shape with the identity transform
/// (`flip_tex_coords`: v → 1 − v, Mitsuba's default for OBJ). Normals missing from the file
/// are recomputed; degenerate triangles are dropped.
pub fn load_obj(path: &Path, flip_tex_coords: bool) -> Result<Mesh, LoadError> {
    let data = std::fs::read(path)
        .map_err(|e| LoadError::in_file(path, format!("cannot read mesh file: {e}")))?;
    let raw = obj::parse_obj(&String::from_utf8_lossy(&data), flip_tex_coords, false)
        .map_err(|e| LoadError::at_line(path, e.line, e.message))?;
    let (m, _) = mesh::finalize(raw, &DMat4::IDENTITY, false, false)
        .map_err(|e| LoadError::in_file(path, e))?;
    Ok(m)
}

/// Reads a PLY file (ASCII or binary) as Mitsuba's `ply` shape with the identity transform.
/// Normals missing from the file are recomputed; degenerate triangles are dropped.
pub fn load_ply(path: &Path, flip_tex_coords: bool) -> Result<Mesh, LoadError> {
    let data = std::fs::read(path)
        .map_err(|e| LoadError::in_file(path, format!("cannot read mesh file: {e}")))?;
    let raw =
        ply::parse_ply(&data, flip_tex_coords, false).map_err(|e| LoadError::in_file(path, e))?;
    let (m, _) = mesh::finalize(raw, &DMat4::IDENTITY, false, false)
        .map_err(|e| LoadError::in_file(path, e))?;
    Ok(m)
}
