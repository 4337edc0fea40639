//! Mesh primitives to radia's world-space [`Mesh`] (specification §3.7.2).

use super::data::{check_accessor, AccessorSpec, GltfFile};
use super::nodes::MeshInstance;
use super::tangents::{self, Vertices};
use glam::{DMat3, Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use radia_scene::Mesh;

/// What the primitives had that radia skips, reported once per file.
#[derive(Default)]
pub(crate) struct Warnings {
    /// Point and line primitives skipped.
    non_triangles: usize,
    /// Zero-area triangles dropped.
    degenerate: usize,
    /// Normal-mapped primitives without uvs, or whose MikkTSpace tangents failed: their
    /// normal maps use the ∂p/∂u frame.
    no_tangents: usize,
}

impl Warnings {
    pub fn report(&self, warn: &mut dyn FnMut(String)) {
        if self.non_triangles > 0 {
            warn(format!(
                "{} point or line primitive(s) skipped: radia renders triangles only",
                self.non_triangles
            ));
        }
        if self.degenerate > 0 {
            warn(format!("{} zero-area triangle(s) dropped", self.degenerate));
        }
        if self.no_tangents > 0 {
            warn(format!(
                "{} normal-mapped primitive(s) without TANGENT got no MikkTSpace tangents (no texture coordinates, or degenerate ones): their normal maps follow the uv derivatives",
                self.no_tangents
            ));
        }
    }
}

const FLOAT: &[(DataType, bool)] = &[(DataType::F32, false)];

/// The world-space mesh of one primitive of `inst`, with the uv set `TEXCOORD_<tex_coord>`
/// (if the primitive has it) and, if `normal_mapped`, tangents ([`tangents`]), or `None`
/// for a primitive radia skips (points, lines, no triangle left).
pub(crate) fn build_primitive(
    file: &GltfFile,
    inst: &MeshInstance<'_>,
    prim: &gltf::Primitive<'_>,
    tex_coord: u32,
    normal_mapped: bool,
    warnings: &mut Warnings,
) -> Result<Option<Mesh>, String> {
    let at = format!("mesh {} primitive {}", inst.mesh.index(), prim.index());
    let fail = |e: String| format!("{at}: {e}");
    let mode = prim.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        warnings.non_triangles += 1;
        return Ok(None);
    }
    let reader = prim.reader(|b| file.buffer(b));

    let pos_acc = prim
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| fail("has no POSITION attribute".into()))?;
    check_accessor(
        file,
        &pos_acc,
        &AccessorSpec {
            what: "POSITION",
            dimensions: &[Dimensions::Vec3],
            types: FLOAT,
        },
    )
    .map_err(fail)?;
    let mut positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or_else(|| fail("cannot read POSITION".into()))?
        .map(Vec3::from_array)
        .collect();
    let n = positions.len();

    let mut normals = match prim.get(&gltf::Semantic::Normals) {
        Some(acc) => {
            check_accessor(
                file,
                &acc,
                &AccessorSpec {
                    what: "NORMAL",
                    dimensions: &[Dimensions::Vec3],
                    types: FLOAT,
                },
            )
            .map_err(fail)?;
            let v: Vec<Vec3> = reader
                .read_normals()
                .ok_or_else(|| fail("cannot read NORMAL".into()))?
                .map(Vec3::from_array)
                .collect();
            same_count(&v, n, "NORMAL").map_err(fail)?;
            Some(v)
        }
        None => None,
    };

    let uv_name = format!("TEXCOORD_{tex_coord}");
    let mut uvs = match prim.get(&gltf::Semantic::TexCoords(tex_coord)) {
        Some(acc) => {
            check_accessor(
                file,
                &acc,
                &AccessorSpec {
                    what: &uv_name,
                    dimensions: &[Dimensions::Vec2],
                    types: &[
                        (DataType::F32, false),
                        (DataType::U8, true),
                        (DataType::U16, true),
                    ],
                },
            )
            .map_err(fail)?;
            let v: Vec<Vec2> = reader
                .read_tex_coords(tex_coord)
                .ok_or_else(|| fail(format!("cannot read {uv_name}")))?
                .into_f32()
                .map(Vec2::from_array)
                .collect();
            same_count(&v, n, &uv_name).map_err(fail)?;
            Some(v)
        }
        None => None,
    };

    // The vertex sequence: the indices, or 0..n.
    let sequence: Vec<u32> = match prim.indices() {
        Some(acc) => {
            check_accessor(
                file,
                &acc,
                &AccessorSpec {
                    what: "indices",
                    dimensions: &[Dimensions::Scalar],
                    types: &[
                        (DataType::U8, false),
                        (DataType::U16, false),
                        (DataType::U32, false),
                    ],
                },
            )
            .map_err(fail)?;
            let v: Vec<u32> = reader
                .read_indices()
                .ok_or_else(|| fail("cannot read the indices".into()))?
                .into_u32()
                .collect();
            if let Some((k, &i)) = v.iter().enumerate().find(|(_, &i)| i as usize >= n) {
                return Err(fail(format!(
                    "index {i} (element {k} of indices accessor {}) is out of range: POSITION has {n} vertices",
                    acc.index()
                )));
            }
            v
        }
        None => (0..n as u32).collect(),
    };
    let mut triangles = assemble(mode, &sequence);
    if triangles.is_empty() {
        return Ok(None);
    }

    // Tangents in object space, for normal-mapped primitives only.
    let tangents = match (normal_mapped, prim.get(&gltf::Semantic::Tangents)) {
        (false, _) => None,
        (true, Some(acc)) => {
            check_accessor(
                file,
                &acc,
                &AccessorSpec {
                    what: "TANGENT",
                    dimensions: &[Dimensions::Vec4],
                    types: FLOAT,
                },
            )
            .map_err(fail)?;
            let v: Vec<Vec4> = reader
                .read_tangents()
                .ok_or_else(|| fail("cannot read TANGENT".into()))?
                .map(Vec4::from_array)
                .collect();
            same_count(&v, n, "TANGENT").map_err(fail)?;
            Some(v)
        }
        (true, None) => {
            let corners = uvs.as_deref().and_then(|uv| {
                tangents::mikktspace_corners(&positions, normals.as_deref(), uv, &triangles)
            });
            match corners {
                Some(c) => Some(tangents::per_vertex(
                    &c,
                    &mut triangles,
                    Vertices {
                        positions: &mut positions,
                        normals: normals.as_mut(),
                        uvs: uvs.as_mut(),
                    },
                )),
                None => {
                    warnings.no_tangents += 1;
                    None
                }
            }
        }
    };

    // To world space. A mirroring transform turns counter-clockwise faces clockwise: the
    // specification makes the determinant's sign decide the winding, so reverse it.
    let m = inst.to_world;
    let linear = DMat3::from_mat4(m);
    let det = linear.determinant();
    if !(det.abs() > 0.0) {
        return Err(fail(format!(
            "the world transform of node {} is singular",
            inst.node
        )));
    }
    let normal_matrix = linear.inverse().transpose();
    let positions: Vec<Vec3> = positions
        .iter()
        .map(|p| m.transform_point3(p.as_dvec3()).as_vec3())
        .collect();
    if let Some(k) = positions.iter().position(|p| !p.is_finite()) {
        return Err(fail(format!("vertex {k} has a non-finite position")));
    }
    let normals = normals
        .map(|ns| {
            ns.iter()
                .enumerate()
                .map(|(k, nv)| {
                    let w = (normal_matrix * nv.as_dvec3()).normalize().as_vec3();
                    if w.is_finite() {
                        Ok(w)
                    } else {
                        Err(fail(format!("vertex {k} has a zero or non-finite NORMAL")))
                    }
                })
                .collect::<Result<Vec<_>, _>>()
        })
        .transpose()?;

    // Tangents are directions on the surface: they transform by the linear part (the
    // Khronos sample viewer's `u_ModelMatrix * a_tangent`). The bitangent, cross(n, t)·w,
    // must follow the mapped texture v direction; a mirroring transform reverses the cross
    // product of the mapped normal and tangent, so w changes sign with the determinant.
    let det_sign = if det < 0.0 { -1.0 } else { 1.0 };
    let tangents = tangents
        .map(|ts| {
            ts.iter()
                .enumerate()
                .map(|(k, t)| {
                    if !t.is_finite() {
                        return Err(fail(format!("vertex {k} has a non-finite TANGENT")));
                    }
                    let xyz = (linear * t.truncate().as_dvec3())
                        .normalize_or_zero()
                        .as_vec3();
                    let w = if t.w < 0.0 { -det_sign } else { det_sign };
                    Ok(xyz.extend(w))
                })
                .collect::<Result<Vec<_>, _>>()
        })
        .transpose()?;

    let mut indices = Vec::with_capacity(triangles.len());
    for t in triangles {
        let t = if det < 0.0 { [t[0], t[2], t[1]] } else { t };
        let [a, b, c] = t.map(|i| positions[i as usize]);
        if (b - a).cross(c - a).length_squared() > 0.0 {
            indices.push(t);
        } else {
            warnings.degenerate += 1;
        }
    }
    if indices.is_empty() {
        return Ok(None);
    }
    Ok(Some(Mesh {
        positions,
        normals,
        uvs,
        tangents,
        indices,
        flip_normals: false,
    }))
}

fn same_count<T>(v: &[T], n: usize, what: &str) -> Result<(), String> {
    if v.len() != n {
        return Err(format!(
            "{what} has {} elements but POSITION has {n} (all attributes of a primitive must have the same count)",
            v.len()
        ));
    }
    Ok(())
}

/// Triangles from a vertex sequence (§3.7.2.1): lists in threes (a trailing incomplete
/// triangle is ignored); strips as {v_i, v_(i+1+i%2), v_(i+2−i%2)}; fans as
/// {v_(i+1), v_(i+2), v_0}.
pub(crate) fn assemble(mode: Mode, v: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::Triangles => v.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
        Mode::TriangleStrip => (0..v.len().saturating_sub(2))
            .map(|i| [v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]])
            .collect(),
        Mode::TriangleFan => (0..v.len().saturating_sub(2))
            .map(|i| [v[i + 1], v[i + 2], v[0]])
            .collect(),
        _ => Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_keep_the_winding() {
        // A quad 0-1-2-3 (counter-clockwise: 0,1,2 and 1,3,2 in a strip).
        assert_eq!(
            assemble(Mode::TriangleStrip, &[0, 1, 2, 3]),
            vec![[0, 1, 2], [1, 3, 2]]
        );
        assert_eq!(
            assemble(Mode::TriangleFan, &[0, 1, 2, 3]),
            vec![[1, 2, 0], [2, 3, 0]]
        );
        assert_eq!(assemble(Mode::Triangles, &[0, 1, 2, 3, 4]), vec![[0, 1, 2]]);
        assert!(assemble(Mode::TriangleStrip, &[0, 1]).is_empty());
    }
}
