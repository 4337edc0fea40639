//! Displacement mapping, a radia extension: a mesh modifier applied at load time, in object
//! space, before `to_world` (as Blender's Displace modifier works in the object's space: a
//! `displacement_scale` of 0.1 moves a vertex 0.1 units of the mesh file, whatever the
//! shape's transform).
//!
//! ```xml
//! <shape type="obj">
//!     <string name="filename" value="plane.obj"/>
//!     <texture type="bitmap" name="displacement">
//!         <string name="filename" value="height.png"/>
//!         <boolean name="raw" value="true"/>
//!     </texture>
//!     <float name="displacement_scale" value="0.1"/>   <!-- default 1 -->
//!     <float name="displacement_shift" value="0"/>     <!-- default 0 -->
//!     <integer name="subdivisions" value="4"/>         <!-- default 0 -->
//! </shape>
//! ```
//!
//! 1. **Subdivision**: each level splits every triangle into four at its edge midpoints
//!    (position, normal, uv interpolated); a midpoint is shared by the triangles on both
//!    sides of its edge (keyed by the edge's vertex pair), so a mesh that was watertight stays
//!    watertight. `subdivisions` works without a displacement too.
//! 2. **Displacement**: every vertex moves along its normal (the file's, else Mitsuba's
//!    angle-weighted vertex normal, interpolated and renormalised at midpoints) by
//!    `displacement_scale × h(uv) + displacement_shift`, where h is the texture's scalar
//!    value at the vertex's uv: the value of a grey texture, else the luminance (Rec. 709, as
//!    Mitsuba's `eval_1` of a bitmap) of its colour (`flip_normals` does not change the
//!    direction: it only flips the finished surface). A constant (`<float name="displacement"
//!    value="0.05"/>`) inflates the mesh and needs no uvs; a texture on a mesh without uvs
//!    is an error.
//! 3. **Normals** are then recomputed as for a mesh file without normals (Mitsuba's
//!    angle-weighted scheme, `mesh::recompute_vertex_normals`), so a displaced mesh shades
//!    exactly as the same surface modelled directly and stored without normals; `face_normals`
//!    keeps it flat-shaded.
//!
//! Vertices that a mesh duplicates along a seam (the `cube`'s per-face vertices, uv seams)
//! are displaced separately: where their normals or heights differ, the surface opens.

use super::build::Builder;
use super::props::Props;
use super::textures::{is_texture, texture_param};
use super::LoadError;
use crate::mesh::{recompute_vertex_normals, RawMesh};
use glam::{Vec2, Vec3};
use radia_bsdf::{ShadingPoint, Texture};
use radia_math::luminance;
use std::collections::HashMap;

/// Triangles a subdivided mesh may have (64 Mi: about 3 GiB of mesh and BVH); more is
/// refused before anything is allocated.
pub(crate) const MAX_TRIANGLES: u64 = 1 << 26;

/// The largest `subdivisions` value accepted by the parser (4^16 times one triangle is
/// already over [`MAX_TRIANGLES`]); the triangle budget is what limits a real mesh.
const MAX_LEVELS: i64 = 16;

/// What to do to a mesh shape's geometry after reading it.
#[derive(Clone, Debug)]
pub(crate) struct MeshModifier {
    pub subdivisions: u32,
    pub displacement: Option<Displacement>,
}

#[derive(Clone, Debug)]
pub(crate) struct Displacement {
    pub height: Texture,
    pub scale: f32,
    pub shift: f32,
}

impl Displacement {
    /// The offset along the normal at `uv`.
    fn offset(&self, uv: Vec2) -> f32 {
        let c = self.height.eval(&ShadingPoint::at_uv(uv));
        let h = if c.x == c.y && c.y == c.z {
            c.x
        } else {
            luminance(c)
        };
        self.scale * h + self.shift
    }
}

/// Reads `displacement`, `displacement_scale`, `displacement_shift` and `subdivisions` of a
/// mesh shape; `None` when none is given (the mesh is left as read).
pub(crate) fn read_modifier(
    b: &mut Builder<'_>,
    p: &mut Props<'_>,
) -> Result<Option<MeshModifier>, LoadError> {
    let subdivisions = p.int("subdivisions", 0, 0, MAX_LEVELS)? as u32;
    let scale_pos = p.pos_of("displacement_scale");
    let shift_pos = p.pos_of("displacement_shift");
    let stray = if p.has_any("displacement_scale") {
        Some(scale_pos)
    } else if p.has_any("displacement_shift") {
        Some(shift_pos)
    } else {
        None
    };
    let scale = p.float("displacement_scale", 1.0)?;
    let shift = p.float("displacement_shift", 0.0)?;
    for (name, x, pos) in [
        ("displacement_scale", scale, scale_pos),
        ("displacement_shift", shift, shift_pos),
    ] {
        if !(x as f32).is_finite() {
            return Err(p.err_at(
                pos,
                format!("parameter \"{name}\": {x:e} is not a finite number"),
            ));
        }
    }
    let displacement = if is_texture(p, "displacement") || p.has_any("displacement") {
        let height = texture_param(b, p, "displacement", 0.0, false)?;
        Some(Displacement {
            height,
            scale: scale as f32,
            shift: shift as f32,
        })
    } else if let Some(pos) = stray {
        return Err(p.err_at(
            pos,
            "\"displacement_scale\"/\"displacement_shift\" given without a \"displacement\" texture or value",
        ));
    } else {
        None
    };
    if subdivisions == 0 && displacement.is_none() {
        return Ok(None);
    }
    Ok(Some(MeshModifier {
        subdivisions,
        displacement,
    }))
}

/// Subdivides and displaces `raw` (object space). Errors are messages for the caller to place.
pub(crate) fn apply(raw: RawMesh, m: &MeshModifier) -> Result<RawMesh, String> {
    let triangles = raw.indices.len() as u64;
    let after = triangles
        .checked_mul(1u64 << (2 * m.subdivisions))
        .filter(|&t| t <= MAX_TRIANGLES);
    if after.is_none() {
        return Err(format!(
            "{} subdivision level(s) of {triangles} triangles would make {} triangles, more than the limit of {MAX_TRIANGLES}",
            m.subdivisions,
            triangles as f64 * 4f64.powi(m.subdivisions as i32),
        ));
    }
    if let Some(d) = &m.displacement {
        if raw.uvs.is_none() && !d.height.is_constant() {
            return Err(
                "a displacement texture needs texture coordinates, and the mesh has none"
                    .to_string(),
            );
        }
    }
    // Without normals and without a displacement, subdivision leaves the normals to be
    // recomputed later (as for the unsubdivided mesh); otherwise each vertex needs one.
    let had_normals = raw.normals.is_some();
    let mut mesh = raw;
    if had_normals || m.displacement.is_some() {
        fill_normals(&mut mesh);
    }
    for _ in 0..m.subdivisions {
        mesh = subdivide(&mesh);
    }
    if let Some(d) = &m.displacement {
        let normals = mesh.normals.take().expect("filled above");
        for (i, (p, n)) in mesh.positions.iter_mut().zip(&normals).enumerate() {
            let uv = mesh.uvs.as_ref().map_or(Vec2::ZERO, |uvs| uvs[i]);
            *p += *n * d.offset(uv);
        }
        // `finalize` recomputes the normals of the displaced surface (none are set).
    }
    Ok(mesh)
}

/// Gives every vertex a unit normal: the file's where it has one, else the angle-weighted
/// vertex normal of the object-space mesh.
fn fill_normals(mesh: &mut RawMesh) {
    let (computed, _) = recompute_vertex_normals(&mesh.positions, &mesh.indices);
    match &mut mesh.normals {
        Some(ns) => {
            for (n, c) in ns.iter_mut().zip(computed) {
                *n = if *n == Vec3::ZERO {
                    c
                } else {
                    n.normalize_or(c)
                };
            }
        }
        None => mesh.normals = Some(computed),
    }
}

/// One level of 1:4 midpoint subdivision. Triangle `[a, b, c]` with edge midpoints
/// ab, bc, ca becomes `[a, ab, ca]`, `[ab, b, bc]`, `[ca, bc, c]`, `[ab, bc, ca]` (same
/// winding). Midpoints are appended after the existing vertices, in order of first use.
pub(crate) fn subdivide(mesh: &RawMesh) -> RawMesh {
    let mut out = RawMesh {
        positions: mesh.positions.clone(),
        normals: mesh.normals.clone(),
        uvs: mesh.uvs.clone(),
        indices: Vec::with_capacity(mesh.indices.len() * 4),
    };
    let mut midpoints: HashMap<(u32, u32), u32> =
        HashMap::with_capacity(mesh.indices.len() * 3 / 2 + 1);
    let mut midpoint = |out: &mut RawMesh, i: u32, j: u32, face: [u32; 3]| -> u32 {
        let key = (i.min(j), i.max(j));
        if let Some(&k) = midpoints.get(&key) {
            return k;
        }
        let k = out.positions.len() as u32;
        let (a, b) = (key.0 as usize, key.1 as usize);
        out.positions
            .push((mesh.positions[a] + mesh.positions[b]) * 0.5);
        if let (Some(ns), Some(src)) = (&mut out.normals, &mesh.normals) {
            // Opposite normals (a knife edge) average to zero: take the face's normal.
            let face_normal = || {
                let [p0, p1, p2] = face.map(|v| mesh.positions[v as usize]);
                (p1 - p0).cross(p2 - p0).normalize_or(Vec3::X)
            };
            ns.push(
                (src[a] + src[b])
                    .try_normalize()
                    .unwrap_or_else(face_normal),
            );
        }
        if let (Some(uvs), Some(src)) = (&mut out.uvs, &mesh.uvs) {
            uvs.push((src[a] + src[b]) * 0.5);
        }
        midpoints.insert(key, k);
        k
    };
    for &t in &mesh.indices {
        let [a, b, c] = t;
        let ab = midpoint(&mut out, a, b, t);
        let bc = midpoint(&mut out, b, c, t);
        let ca = midpoint(&mut out, c, a, t);
        out.indices
            .extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use radia_bsdf::{Bitmap, FilterType, UvTransform, WrapMode};

    /// Mitsuba's rectangle ([-1, 1]², uv = (p + 1)/2), two triangles.
    fn plane() -> RawMesh {
        crate::mesh::rectangle()
    }

    /// A closed tetrahedron without uvs.
    fn tetrahedron() -> RawMesh {
        RawMesh {
            positions: vec![
                Vec3::new(1.0, 1.0, 1.0),
                Vec3::new(1.0, -1.0, -1.0),
                Vec3::new(-1.0, 1.0, -1.0),
                Vec3::new(-1.0, -1.0, 1.0),
            ],
            normals: None,
            uvs: None,
            indices: vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]],
        }
    }

    /// How many triangles use each undirected edge.
    fn edge_uses(indices: &[[u32; 3]]) -> HashMap<(u32, u32), usize> {
        let mut uses = HashMap::new();
        for t in indices {
            for k in 0..3 {
                let (i, j) = (t[k], t[(k + 1) % 3]);
                *uses.entry((i.min(j), i.max(j))).or_insert(0) += 1;
            }
        }
        uses
    }

    fn modifier(levels: u32, d: Option<Displacement>) -> MeshModifier {
        MeshModifier {
            subdivisions: levels,
            displacement: d,
        }
    }

    /// A one-channel image texture from rows of values (row 0 at v = 0).
    fn image(rows: &[&[f32]], filter: FilterType, wrap: WrapMode) -> Texture {
        let (w, h) = (rows[0].len(), rows.len());
        let data = rows.iter().flat_map(|r| r.iter().copied()).collect();
        Bitmap::new(w, h, 1, data, filter, wrap, UvTransform::IDENTITY)
            .unwrap()
            .into()
    }

    #[test]
    fn subdivision_is_watertight_and_counts_four_to_the_level() {
        for levels in 0..=4u32 {
            let m = apply(tetrahedron(), &modifier(levels, None)).unwrap();
            assert_eq!(m.indices.len(), 4 * 4usize.pow(levels));
            // Euler: a closed genus-0 mesh has V = E - F + 2 = F/2 + 2 vertices.
            assert_eq!(
                m.positions.len(),
                m.indices.len() / 2 + 2,
                "level {levels}: a vertex is duplicated"
            );
            let uses = edge_uses(&m.indices);
            assert!(
                uses.values().all(|&u| u == 2),
                "level {levels}: an edge is not shared by exactly two triangles"
            );
            // On the plane: interior edges twice, the 4·2^L boundary edges once.
            let m = apply(plane(), &modifier(levels, None)).unwrap();
            assert_eq!(m.indices.len(), 2 * 4usize.pow(levels));
            let n = 1usize << levels;
            assert_eq!(m.positions.len(), (n + 1) * (n + 1));
            let uses = edge_uses(&m.indices);
            assert_eq!(uses.values().filter(|&&u| u == 1).count(), 4 * n);
            assert!(uses.values().all(|&u| u == 1 || u == 2));
            // Every vertex lies on the grid of the plane, with its uv.
            let uvs = m.uvs.as_ref().unwrap();
            for (p, uv) in m.positions.iter().zip(uvs) {
                let g = (p.truncate() + 1.0) * 0.5 * n as f32;
                assert_eq!((g.round(), p.z), (g, 0.0), "{p} off the grid");
                assert_eq!(*uv, (p.truncate() + 1.0) * 0.5);
            }
            // Winding is kept: every triangle still faces +z.
            for t in &m.indices {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                assert!((b - a).cross(c - a).z > 0.0);
            }
        }
    }

    #[test]
    fn plane_vertices_move_by_the_texel_height() {
        // 4×4 texels, nearest: the vertex at grid (i, j) of a 4×4 subdivision (uv = (i, j)/4)
        // reads texel (min(i, 3), min(j, 3)) under clamping.
        let rows: [&[f32]; 4] = [
            &[0.0, 0.1, 0.2, 0.3],
            &[0.4, 0.5, 0.6, 0.7],
            &[0.8, 0.9, 1.0, 0.25],
            &[0.5, 0.125, 0.75, 0.0625],
        ];
        let height = image(&rows, FilterType::Nearest, WrapMode::Clamp);
        let d = Displacement {
            height,
            scale: 0.5,
            shift: 0.25,
        };
        let m = apply(plane(), &modifier(2, Some(d))).unwrap();
        assert!(m.normals.is_none(), "normals are left to be recomputed");
        assert_eq!(m.positions.len(), 25);
        for p in &m.positions {
            let (i, j) = (((p.x + 1.0) * 2.0) as usize, ((p.y + 1.0) * 2.0) as usize);
            let expected = 0.5 * rows[j.min(3)][i.min(3)] + 0.25;
            assert_eq!(p.z, expected, "vertex ({i}, {j})");
        }
    }

    #[test]
    fn a_checkerboard_moves_vertices_to_its_two_heights() {
        // Mitsuba's checkerboard: color0 where (frac(u) > ½) == (frac(v) > ½).
        let checker = radia_bsdf::Checkerboard::new(0.8, 0.2, UvTransform::IDENTITY);
        let d = Displacement {
            height: checker.into(),
            scale: 1.0,
            shift: 0.0,
        };
        let m = apply(plane(), &modifier(3, Some(d))).unwrap();
        for (p, uv) in m.positions.iter().zip(m.uvs.as_ref().unwrap()) {
            let f = *uv - uv.floor();
            let expected = if (f.x > 0.5) == (f.y > 0.5) { 0.8 } else { 0.2 };
            assert_eq!(p.z, expected, "uv {uv}");
        }
    }

    #[test]
    fn a_displaced_ramp_has_the_analytic_normal() {
        // 8 texels in u, bilinear and clamped: h(u) = (8u - ½)/7 between the first and last
        // texel centres, so z = s·h((x + 1)/2) has slope dz/dx = 4s/7 there.
        let ramp: Vec<f32> = (0..8).map(|k| k as f32 / 7.0).collect();
        let height = image(&[&ramp], FilterType::Bilinear, WrapMode::Clamp);
        let s = 0.7;
        let d = Displacement {
            height,
            scale: s,
            shift: 0.0,
        };
        let levels = 4;
        let raw = apply(plane(), &modifier(levels, Some(d))).unwrap();
        let (mesh, stats) =
            crate::mesh::finalize(raw, &glam::DMat4::IDENTITY, false, false).unwrap();
        assert_eq!(stats.invalid_normals, 0);
        let slope = 4.0 * s / 7.0;
        let analytic = Vec3::new(-slope, 0.0, 1.0).normalize();
        let normals = mesh.normals.as_ref().unwrap();
        let cell = 2.0 / (1u32 << levels) as f32;
        let mut checked = 0;
        for (p, n) in mesh.positions.iter().zip(normals) {
            let u = (p.x + 1.0) / 2.0;
            // Vertices whose whole one-ring lies on the linear part.
            if u - cell / 2.0 >= 0.5 / 8.0 && u + cell / 2.0 <= 1.0 - 0.5 / 8.0 {
                assert!(
                    (p.z - s * (8.0 * u - 0.5) / 7.0).abs() < 1e-6,
                    "height at {p}"
                );
                assert!(
                    (*n - analytic).length() < 1e-5,
                    "normal {n} at {p}, expected {analytic}"
                );
                checked += 1;
            }
        }
        assert!(checked >= 12 * 17, "{checked} vertices checked");
    }

    #[test]
    fn a_constant_inflates_a_mesh_without_uvs_along_its_normals() {
        // The tetrahedron's vertex normals point away from the centre: every vertex moves
        // outwards by exactly the offset.
        let d = Displacement {
            height: Texture::from(0.5),
            scale: 0.2,
            shift: 0.0,
        };
        let m = apply(tetrahedron(), &modifier(0, Some(d))).unwrap();
        for p in &m.positions {
            assert!((p.length() - (3f32.sqrt() + 0.1)).abs() < 1e-6, "{p}");
        }
    }

    #[test]
    fn too_many_triangles_and_textures_without_uvs_are_refused() {
        // 2·4^12 triangles would be accepted; 2·4^13 is over the limit, refused at once.
        let e = apply(plane(), &modifier(13, None)).unwrap_err();
        assert!(e.contains("13 subdivision level(s) of 2 triangles would make 134217728 triangles, more than the limit of 67108864"), "{e}");
        let e = apply(plane(), &modifier(16, None)).unwrap_err();
        assert!(e.contains("would make 8589934592 triangles"), "{e}");
        let checker = radia_bsdf::Checkerboard::new(0.8, 0.2, UvTransform::IDENTITY);
        let d = Displacement {
            height: checker.into(),
            scale: 1.0,
            shift: 0.0,
        };
        let e = apply(tetrahedron(), &modifier(0, Some(d))).unwrap_err();
        assert!(e.contains("needs texture coordinates"), "{e}");
    }
}
