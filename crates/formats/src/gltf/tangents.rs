//! Per-vertex tangents of normal-mapped primitives (specification §3.7.2.1): the `TANGENT`
//! attribute if the primitive has one, else MikkTSpace's, "calculated with the specified
//! vertex positions, normals, and texture coordinates associated with the normal texture"
//! (the `mikktspace` crate, a port of Mikkelsen's reference code that Blender and the
//! Khronos tools use).
//!
//! MikkTSpace gives one tangent per triangle corner. Corners that share a vertex usually get
//! the same one; where they do not (a vertex where charts of different orientation meet), the
//! vertex is split so that every corner keeps its own, as the algorithm intends.

use glam::{Vec2, Vec3, Vec4};
use std::collections::HashMap;

/// The geometry MikkTSpace reads: indexed triangles, normals per vertex or, without
/// them, the face normal (glTF's flat shading, §3.7.2.1).
struct Input<'a> {
    positions: &'a [Vec3],
    normals: Option<&'a [Vec3]>,
    uvs: &'a [Vec2],
    triangles: &'a [[u32; 3]],
    /// Output: one tangent per corner, xyz and the bitangent sign in w.
    corners: Vec<Vec4>,
}

impl mikktspace::Geometry for Input<'_> {
    fn num_faces(&self) -> usize {
        self.triangles.len()
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.positions[self.triangles[face][vert] as usize].to_array()
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        match self.normals {
            Some(ns) => ns[self.triangles[face][vert] as usize].to_array(),
            None => {
                let [a, b, c] = self.triangles[face].map(|i| self.positions[i as usize]);
                (b - a).cross(c - a).normalize_or_zero().to_array()
            }
        }
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        self.uvs[self.triangles[face][vert] as usize].to_array()
    }
    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        self.corners[face * 3 + vert] = Vec4::from_array(tangent);
    }
}

/// MikkTSpace tangents of the corners of `triangles` (3 per triangle, in order), or `None`
/// if the algorithm gives up (it then says the geometry is unsuitable).
pub(crate) fn mikktspace_corners(
    positions: &[Vec3],
    normals: Option<&[Vec3]>,
    uvs: &[Vec2],
    triangles: &[[u32; 3]],
) -> Option<Vec<Vec4>> {
    let mut input = Input {
        positions,
        normals,
        uvs,
        triangles,
        corners: vec![Vec4::ZERO; triangles.len() * 3],
    };
    mikktspace::generate_tangents(&mut input).then_some(input.corners)
}

/// The vertex arrays of a primitive, which [`per_vertex`] may extend.
pub(crate) struct Vertices<'a> {
    pub positions: &'a mut Vec<Vec3>,
    pub normals: Option<&'a mut Vec<Vec3>>,
    pub uvs: Option<&'a mut Vec<Vec2>>,
}

/// Per-vertex tangents from per-corner ones: a vertex whose corners all have the same
/// tangent keeps its index; one whose corners differ is duplicated (all attributes) for each
/// further tangent, and `triangles` are renumbered accordingly.
pub(crate) fn per_vertex(
    corners: &[Vec4],
    triangles: &mut [[u32; 3]],
    v: Vertices<'_>,
) -> Vec<Vec4> {
    let n = v.positions.len();
    let mut tangents: Vec<Option<Vec4>> = vec![None; n];
    let mut copies: HashMap<(u32, [u32; 4]), u32> = HashMap::new();
    let mut extra: Vec<(u32, Vec4)> = Vec::new();
    for (k, corner) in triangles.iter_mut().flatten().enumerate() {
        let t = corners[k];
        let i = *corner as usize;
        match tangents[i] {
            None => tangents[i] = Some(t),
            Some(have) if have.to_array().map(f32::to_bits) == t.to_array().map(f32::to_bits) => {}
            Some(_) => {
                let key = (*corner, t.to_array().map(f32::to_bits));
                let next = (n + extra.len()) as u32;
                let copy = *copies.entry(key).or_insert_with(|| {
                    extra.push((key.0, t));
                    next
                });
                *corner = copy;
            }
        }
    }
    let mut out: Vec<Vec4> = tangents
        .into_iter()
        .map(|t| t.unwrap_or(Vec4::ZERO))
        .collect();
    let Vertices {
        positions,
        mut normals,
        mut uvs,
    } = v;
    for (from, t) in extra {
        let from = from as usize;
        positions.push(positions[from]);
        if let Some(ns) = normals.as_deref_mut() {
            ns.push(ns[from]);
        }
        if let Some(uv) = uvs.as_deref_mut() {
            uv.push(uv[from]);
        }
        out.push(t);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit quad in the xy-plane, normal +z, two counter-clockwise triangles, with uv
    /// u = x or, `mirrored`, u = 1 − x (v = y either way).
    fn quad(mirrored: bool) -> (Vec<Vec3>, Vec<Vec3>, Vec<Vec2>, Vec<[u32; 3]>) {
        let p = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let uv = p
            .iter()
            .map(|q| Vec2::new(if mirrored { 1.0 - q.x } else { q.x }, q.y))
            .collect();
        (p, vec![Vec3::Z; 4], uv, vec![[0, 1, 2], [0, 2, 3]])
    }

    /// The quad's MikkTSpace tangents per vertex, with its positions, uv and triangles.
    fn quad_tangents(mirrored: bool) -> (Vec<Vec3>, Vec<Vec2>, Vec<[u32; 3]>, Vec<Vec4>) {
        let (p, n, uv, mut tris) = quad(mirrored);
        let corners = mikktspace_corners(&p, Some(&n), &uv, &tris).unwrap();
        let t = per_vertex(
            &corners,
            &mut tris,
            Vertices {
                positions: &mut p.clone(),
                normals: None,
                uvs: None,
            },
        );
        (p, uv, tris, t)
    }

    /// ∂p/∂u of the quad's triangles (radia's `shape.rs` formula, here on the plane).
    fn dp_du(p: &[Vec3], uv: &[Vec2], t: [u32; 3]) -> Vec3 {
        let [a, b, c] = t.map(|i| p[i as usize]);
        let [ta, tb, tc] = t.map(|i| uv[i as usize]);
        let (dp0, dp1, duv0, duv1) = (b - a, c - a, tb - ta, tc - ta);
        let det = duv0.x * duv1.y - duv0.y * duv1.x;
        (dp0 * duv1.y - dp1 * duv0.y) / det
    }

    #[test]
    fn plain_quad_tangent_is_dp_du_with_sign_plus_one() {
        let (p, uv, tris, t) = quad_tangents(false);
        assert_eq!(t.len(), 4, "no vertex split on a quad with one chart");
        for tri in &tris {
            let d = dp_du(&p, &uv, *tri).normalize();
            for &i in tri {
                let ti = t[i as usize];
                assert!((ti.truncate() - d).length() < 1e-5, "{ti} vs {d}");
                assert_eq!(ti.w, 1.0);
            }
        }
    }

    #[test]
    fn mirrored_quad_has_sign_minus_one() {
        let (p, uv, tris, t) = quad_tangents(true);
        for tri in &tris {
            // u grows towards −x: ∂p/∂u = (−1, 0, 0), and the bitangent cross(n, t)·w must
            // then be +y (the direction v grows in), so w = −1.
            let d = dp_du(&p, &uv, *tri).normalize();
            assert!((d - Vec3::NEG_X).length() < 1e-6);
            for &i in tri {
                let ti = t[i as usize];
                assert!((ti.truncate() - d).length() < 1e-5, "{ti} vs {d}");
                assert_eq!(ti.w, -1.0);
                assert!((Vec3::Z.cross(ti.truncate()) * ti.w - Vec3::Y).length() < 1e-5);
            }
        }
    }

    /// A vertex whose corners get different tangents is split, with its attributes.
    #[test]
    fn differing_corners_split_the_vertex() {
        let mut positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE];
        let mut uvs = vec![Vec2::ZERO; 4];
        let mut tris = vec![[0, 1, 2], [2, 1, 3]];
        let a = Vec4::new(1.0, 0.0, 0.0, 1.0);
        let b = Vec4::new(1.0, 0.0, 0.0, -1.0);
        let t = per_vertex(
            &[a, a, a, b, b, b],
            &mut tris,
            Vertices {
                positions: &mut positions,
                normals: None,
                uvs: Some(&mut uvs),
            },
        );
        assert_eq!(tris, vec![[0, 1, 2], [4, 5, 3]]);
        assert_eq!(t, vec![a, a, a, b, b, b]);
        assert_eq!(positions[4], Vec3::Y);
        assert_eq!(positions[5], Vec3::X);
        assert_eq!(uvs.len(), 6);
    }
}
