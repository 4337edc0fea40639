//! The Mitsuba 3 XML scene reader (its PLY and OBJ meshes are read by [`crate::ply`] and
//! [`crate::obj`], its images by [`crate::image`]).
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
mod props;
mod shapes;
mod textures;
mod transform;
mod xml;

#[cfg(test)]
mod tests;

pub use crate::error::{LoadError, TextPos};

use radia_scene::SceneDescription;
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
