//! Shape plugins (`src/shapes/*.cpp`): `obj`, `ply`, `rectangle`, `cube`, `sphere`, `disk`,
//! each with `to_world`, `flip_normals`, at most one nested BSDF and one `area` emitter.

use super::bsdfs::{build_bsdf, default_bsdf};
use super::build::Builder;
use super::displacement::{self, MeshModifier};
use super::emitters::area_emitter;
use super::props::Props;
use super::xml::Kind;
use super::LoadError;
use crate::mesh::{self, MeshStats, RawMesh};
use crate::{obj, ply};
use glam::{DMat3, DMat4, DVec3, Mat3A};
use radia_scene::{Geometry, ShapeDesc};
use std::path::{Path, PathBuf};

/// A shape and the `sampling_weight` of its area emitter (1 if it has none).
pub(crate) fn build_shape(b: &mut Builder<'_>, idx: usize) -> Result<(ShapeDesc, f32), LoadError> {
    let mut p = Props::new(b.doc, idx);
    let origin = format!("{}:{}", b.doc.file_of(p.node).display(), p.node.pos.line);
    match p.node.plugin.as_str() {
        "instance" => return Ok((build_instance(b, p, origin)?, 1.0)),
        "shapegroup" => {
            return Err(p.err(
                "a shapegroup is not a shape of its own: declare it at the top of the scene and place it with <shape type=\"instance\">",
            ))
        }
        _ => {}
    }

    // Children: one BSDF, one emitter (Mitsuba's Shape constructor).
    let mut bsdf = None;
    let mut emission = None;
    let mut sampling_weight = 1.0;
    for (i, n, kind) in p.objects() {
        match kind {
            Kind::Bsdf => {
                if bsdf.is_some() {
                    return Err(p.err_at(
                        p.prop_pos(i),
                        "only a single BSDF child object can be specified per shape",
                    ));
                }
                p.take(i);
                bsdf = Some(build_bsdf(b, n, 0)?);
            }
            Kind::Emitter => {
                if emission.is_some() {
                    return Err(p.err_at(
                        p.prop_pos(i),
                        "only a single emitter child object can be specified per shape",
                    ));
                }
                p.take(i);
                let (radiance, weight) = area_emitter(b, n)?;
                emission = Some(radiance);
                sampling_weight = weight;
            }
            _ => {} // reported by `finish`
        }
    }

    let to_world = b.to_world(&mut p)?;
    let flip_normals = p.boolean("flip_normals", false)?;
    let plugin = p.node.plugin.as_str();
    // radia's subdivision and displacement (`displacement.rs`), on every mesh shape.
    let modifier = match plugin {
        "obj" | "ply" | "rectangle" | "cube" => displacement::read_modifier(b, &mut p)?,
        _ => None,
    };
    let geometry = match plugin {
        "obj" | "ply" => {
            let face_normals = p.boolean("face_normals", false)?;
            let flip_tex_coords = p.boolean("flip_tex_coords", plugin == "obj")?;
            let filename = match p.string_opt("filename")? {
                Some(f) => f,
                None => return Err(p.err(format!("<shape type=\"{plugin}\">: the \"filename\" parameter is required"))),
            };
            let path = resolve_path(&b.doc.dir, filename);
            let (file, line, col) = (b.doc.file_of(p.node), p.node.pos.line, p.node.pos.col);
            let data = crate::read_regular_file(&path).map_err(|e| {
                let what = if e.kind() == std::io::ErrorKind::NotFound { "not found".to_string() } else { e.to_string() };
                LoadError::at(
                    file,
                    p.node.pos,
                    format!("mesh file \"{}\" (filename=\"{filename}\"): {what}", path.display()),
                )
            })?;
            let here = format!("(mesh of the shape at {}:{line}:{col})", file.display());
            let raw = if plugin == "obj" {
                let text = String::from_utf8_lossy(&data);
                obj::parse_obj(&text, flip_tex_coords, face_normals)
                    .map_err(|e| LoadError::at_line(&path, e.line, format!("{} {here}", e.message)))?
            } else {
                ply::parse_ply(&data, flip_tex_coords, face_normals)
                    .map_err(|e| LoadError::in_file(&path, format!("{e} {here}")))?
            };
            // Mitsuba builds an empty mesh; a file without faces is almost surely not the
            // mesh meant (or not a mesh at all: an OBJ reader skips unknown lines).
            if raw.indices.is_empty() {
                return Err(LoadError::in_file(&path, format!("the file has no faces {here}")));
            }
            let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into());
            let raw = modified(&p, raw, modifier.as_ref(), &name)?;
            mesh_geometry(b, &p, raw, &to_world, face_normals, flip_normals, &name)?
        }
        "rectangle" => {
            // Flat: no vertex normals whatever face_normals says, unless displaced.
            let face_normals = p.boolean("face_normals", false)?;
            let flat = face_normals || modifier.as_ref().is_none_or(|m| m.displacement.is_none());
            let raw = modified(&p, mesh::rectangle(), modifier.as_ref(), "rectangle")?;
            mesh_geometry(b, &p, raw, &to_world, flat, flip_normals, "rectangle")?
        }
        "cube" => {
            let face_normals = p.boolean("face_normals", false)?;
            let raw = modified(&p, mesh::cube(), modifier.as_ref(), "cube")?;
            mesh_geometry(b, &p, raw, &to_world, face_normals, flip_normals, "cube")?
        }
        "sphere" => {
            let center = p.point("center", DVec3::ZERO)?;
            let radius = p.float("radius", 1.0)?;
            let m = to_world * DMat4::from_translation(center) * DMat4::from_scale(DVec3::splat(radius));
            let linear = DMat3::from_mat4(m);
            let world_center = m.transform_point3(DVec3::ZERO);
            let world_radius = (linear * DVec3::X).length();
            if !(world_radius > 0.0) || !world_radius.is_finite() || !world_center.is_finite() {
                return Err(p.err(format!("sphere: invalid radius {radius} or transform (world radius {world_radius})")));
            }
            let (c0, c1, c2) = (linear.x_axis.length(), linear.y_axis.length(), linear.z_axis.length());
            let uniform = (c0 - c1).abs() <= 1e-6 * c0 && (c0 - c2).abs() <= 1e-6 * c0;
            let orthogonal = linear.x_axis.dot(linear.y_axis).abs() <= 1e-6 * c0 * c1
                && linear.x_axis.dot(linear.z_axis).abs() <= 1e-6 * c0 * c2
                && linear.y_axis.dot(linear.z_axis).abs() <= 1e-6 * c1 * c2;
            if !uniform || !orthogonal {
                b.warnings.push(format!(
                    "{}:{}:{}: sphere: to_world should not contain non-uniform scaling or shearing; using radius {world_radius}",
                    b.doc.file_of(p.node).display(),
                    p.node.pos.line,
                    p.node.pos.col
                ));
            }
            // A mirroring transform (or a negative radius) turns the sphere inside out, as in
            // Mitsuba (sign of the polar decomposition's stretch).
            let flip = flip_normals ^ (linear.determinant() < 0.0);
            // The whole linear part orients the parametrisation (Mitsuba's `to_object`).
            Geometry::Sphere {
                center: world_center.as_vec3(),
                radius: world_radius as f32,
                to_world: Mat3A::from(linear.as_mat3()),
                flip_normals: flip,
            }
        }
        "disk" => {
            let det = DMat3::from_mat4(to_world).determinant();
            if !(det.abs() > 0.0) {
                return Err(p.err("disk: the to_world transform is singular"));
            }
            Geometry::Disk { to_world: glam::Affine3A::from_mat4(to_world.as_mat4()), flip_normals }
        }
        other => {
            return Err(p.err(format!(
                "unsupported shape plugin type \"{other}\" (radia supports: obj, ply, rectangle, cube, sphere, disk, shapegroup, instance)"
            )))
        }
    };
    p.finish()?;

    let is_emitter = emission.is_some();
    let shape = ShapeDesc {
        geometry,
        bsdf: bsdf.unwrap_or_else(|| default_bsdf(is_emitter)),
        emission,
        origin,
    };
    Ok((shape, sampling_weight))
}

/// Mitsuba's `shapegroup` (`src/render/shapegroup.cpp`): its shapes, in the group's own
/// space, as shape group number .. of the scene (built once per node, however many instances
/// refer to it). Refused as Mitsuba refuses them: anything but a shape inside, a nested
/// group or instance, a shape with an emitter.
pub(crate) fn build_shape_group(b: &mut Builder<'_>, idx: usize) -> Result<u32, LoadError> {
    if let Some(&g) = b.group_cache.get(&idx) {
        return Ok(g);
    }
    let mut p = Props::new(b.doc, idx);
    if p.has_any("to_world") {
        // Mitsuba's Shape constructor reads it, and the group never uses it.
        p.transform("to_world")?;
        b.warnings.push(format!(
            "{}:{}:{}: shapegroup: \"to_world\" is ignored (as by Mitsuba); place the group with an instance's to_world",
            b.doc.file_of(p.node).display(),
            p.node.pos.line,
            p.node.pos.col
        ));
    }
    let mut members = Vec::new();
    let was_in_group = std::mem::replace(&mut b.in_group, true);
    for (i, n, kind) in p.objects() {
        p.take(i);
        let child = &b.doc.nodes[n];
        let here = p.prop_pos(i);
        let refused = match (kind, child.plugin.as_str()) {
            (Kind::Shape, "shapegroup") => Some("nested shape groups are not permitted (Mitsuba: \"Nested ShapeGroup is not permitted\")".to_string()),
            (Kind::Shape, "instance") => Some("an instance inside a shapegroup: nested instancing is not permitted (as in Mitsuba)".to_string()),
            (Kind::Shape, _) => None,
            (_, _) => Some(format!(
                "a shapegroup holds only shapes, not {} (Mitsuba: \"Tried to add an unsupported object\")",
                b.doc.nodes[n].describe()
            )),
        };
        if let Some(message) = refused {
            b.in_group = was_in_group;
            return Err(p.err_at(here, message));
        }
        // A `<shape type="gltf">` adds all the file's surfaces to the group.
        let built = if b.doc.nodes[n].plugin == "gltf" {
            build_gltf_shapes(b, n)
        } else {
            build_shape(b, n).map(|(shape, _)| vec![shape])
        };
        let shapes = match built {
            Ok(s) => s,
            Err(e) => {
                b.in_group = was_in_group;
                return Err(e);
            }
        };
        if shapes.iter().any(|s| s.emission.is_some()) {
            b.in_group = was_in_group;
            let child = &b.doc.nodes[n];
            return Err(LoadError::at(
                b.doc.file_of(child),
                child.pos,
                "a shape with an area emitter inside a shapegroup (for a glTF file: an emissive material): instancing of emitters is not supported (as in Mitsuba)",
            ));
        }
        members.extend(shapes);
    }
    b.in_group = was_in_group;
    p.finish()?;
    let g = b.shape_groups.len() as u32;
    b.shape_groups.push(members);
    b.group_cache.insert(idx, g);
    Ok(g)
}

/// Mitsuba's `instance` (`src/shapes/instance.cpp`): exactly one shape group (nested or
/// referenced) placed by `to_world`.
fn build_instance(
    b: &mut Builder<'_>,
    mut p: Props<'_>,
    origin: String,
) -> Result<ShapeDesc, LoadError> {
    if b.in_group {
        return Err(p.err(
            "an instance inside a shapegroup: nested instancing is not permitted (as in Mitsuba)",
        ));
    }
    let mut group = None;
    for (i, n, kind) in p.objects() {
        let target = &b.doc.nodes[n];
        if kind != Kind::Shape || target.plugin != "shapegroup" {
            return Err(p.err_at(
                p.prop_pos(i),
                format!(
                    "only a shapegroup can be specified in an instance, found {}",
                    target.describe()
                ),
            ));
        }
        if group.is_some() {
            return Err(p.err_at(
                p.prop_pos(i),
                "only a single shapegroup can be specified per instance",
            ));
        }
        p.take(i);
        group = Some(build_shape_group(b, n)?);
    }
    let Some(group) = group else {
        return Err(
            p.err("instance: a reference to a shapegroup must be specified (<ref id=\"...\"/>)")
        );
    };
    let to_world = b.to_world(&mut p)?;
    let det = DMat3::from_mat4(to_world).determinant();
    if det == 0.0 || !det.is_finite() {
        return Err(p.err("instance: the to_world transform is singular or not finite"));
    }
    p.finish()?;
    Ok(ShapeDesc {
        geometry: Geometry::Instance {
            group,
            to_world: glam::Affine3A::from_mat4(to_world.as_mat4()),
        },
        bsdf: default_bsdf(false),
        emission: None,
        origin,
    })
}

/// `raw` subdivided and displaced as the shape asks (unchanged without a modifier).
fn modified(
    p: &Props<'_>,
    raw: RawMesh,
    modifier: Option<&MeshModifier>,
    name: &str,
) -> Result<RawMesh, LoadError> {
    match modifier {
        None => Ok(raw),
        Some(m) => displacement::apply(raw, m).map_err(|e| p.err(format!("\"{name}\": {e}"))),
    }
}

/// World-space mesh geometry; repairs are reported as warnings.
fn mesh_geometry(
    b: &mut Builder<'_>,
    p: &Props<'_>,
    raw: RawMesh,
    to_world: &DMat4,
    face_normals: bool,
    flip_normals: bool,
    name: &str,
) -> Result<Geometry, LoadError> {
    let (m, stats) = mesh::finalize(raw, to_world, face_normals, flip_normals)
        .map_err(|e| p.err(format!("\"{name}\": {e}")))?;
    let where_ = format!(
        "{}:{}:{}",
        b.doc.file_of(p.node).display(),
        p.node.pos.line,
        p.node.pos.col
    );
    let MeshStats {
        degenerate,
        invalid_normals,
    } = stats;
    if degenerate > 0 {
        b.warnings.push(format!(
            "{where_}: \"{name}\": dropped {degenerate} degenerate (zero-area) triangle(s)"
        ));
    }
    if invalid_normals > 0 {
        b.warnings.push(format!(
            "{where_}: \"{name}\": computed vertex normals ({invalid_normals} invalid vertices)"
        ));
    }
    if m.indices.is_empty() {
        b.warnings
            .push(format!("{where_}: \"{name}\": the mesh has no triangles"));
    }
    Ok(Geometry::Mesh(m))
}

/// A mesh filename relative to the scene file's directory (then to the working directory, as
/// Mitsuba's file resolver falls back to it).
pub(crate) fn resolve_path(dir: &Path, filename: &str) -> PathBuf {
    let f = Path::new(filename);
    if f.is_absolute() {
        return f.to_path_buf();
    }
    let in_dir = dir.join(f);
    if !in_dir.exists() && f.exists() {
        return f.to_path_buf();
    }
    in_dir
}

/// radia's `<shape type="gltf">` (an extension): the surfaces of a glTF 2.0 file
/// (`filename`, `.gltf` or `.glb`) with the file's own materials, each placed by its node
/// transforms and then by `to_world`, so that a glTF asset can be framed and lit by a Mitsuba
/// scene ([`crate::gltf`] reads it; the file's cameras and lights are left out, with a
/// warning). One glTF primitive becomes one shape.
pub(crate) fn build_gltf_shapes(
    b: &mut Builder<'_>,
    idx: usize,
) -> Result<Vec<ShapeDesc>, LoadError> {
    let mut p = Props::new(b.doc, idx);
    let (file, pos) = (b.doc.file_of(p.node), p.node.pos);
    for (i, _, kind) in p.objects() {
        if matches!(kind, Kind::Bsdf | Kind::Emitter) {
            return Err(p.err_at(
                p.prop_pos(i),
                "<shape type=\"gltf\"> takes its materials and emission from the glTF file: \
                 a nested <bsdf> or <emitter> is not supported",
            ));
        }
    }
    let to_world = b.to_world(&mut p)?;
    let Some(filename) = p.string_opt("filename")? else {
        return Err(p.err("<shape type=\"gltf\">: the \"filename\" parameter is required"));
    };
    let path = resolve_path(&b.doc.dir, filename);
    p.finish()?;
    let mut warnings = Vec::new();
    let shapes = crate::gltf::load_gltf_shapes(&path, to_world, &mut |w| warnings.push(w))
        .map_err(|e| LoadError::at(file, pos, format!("<shape type=\"gltf\">: {e}")))?;
    let where_ = format!("{}:{}:{}", file.display(), pos.line, pos.col);
    for w in warnings {
        b.warnings.push(format!("{where_}: {w}"));
    }
    if shapes.is_empty() {
        b.warnings.push(format!(
            "{where_}: <shape type=\"gltf\">: \"{filename}\" has no triangles to render"
        ));
    }
    Ok(shapes)
}
