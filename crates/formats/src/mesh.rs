//! From a mesh in object space (as read from a file or generated) to the world-space
//! [`Mesh`] of the description, as Mitsuba's mesh plugins do it: positions by `to_world`,
//! normals by its inverse transpose (renormalized), missing normals recomputed with
//! Mitsuba's angle-weighted scheme (`Mesh::recompute_vertex_normals`, `src/render/mesh.cpp`).

use glam::{DMat3, DMat4, Vec2, Vec3};
use radia_scene::Mesh;
use rayon::prelude::*;
use std::f32::consts::PI;

/// A triangle mesh in object space.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct RawMesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex normals from the file; a zero vector marks a vertex without one.
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<[u32; 3]>,
}

/// What [`finalize`] had to repair.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct MeshStats {
    /// Zero-area triangles removed.
    pub degenerate: usize,
    /// Referenced vertices whose recomputed normal was zero (set to (1, 0, 0) as Mitsuba).
    pub invalid_normals: usize,
}

/// Transforms `raw` to world space. With `face_normals` the result has no vertex normals;
/// otherwise file normals are transformed and vertices without one get the recomputed
/// angle-weighted normal. Indices must already be in range. Errors are messages for the caller
/// to place.
pub(crate) fn finalize(
    raw: RawMesh,
    to_world: &DMat4,
    face_normals: bool,
    flip_normals: bool,
) -> Result<(Mesh, MeshStats), String> {
    let linear = DMat3::from_mat4(*to_world);
    let det = linear.determinant();
    if !(det.abs() > 0.0) || !to_world.is_finite() {
        return Err("the shape's to_world transform is singular".to_string());
    }
    let normal_matrix = linear.inverse().transpose();

    // In parallel over vertices and triangles; the results (order and values) are those of a
    // sequential loop.
    let positions: Vec<Vec3> = raw
        .positions
        .par_iter()
        .map(|p| to_world.transform_point3(p.as_dvec3()).as_vec3())
        .collect();
    if positions.par_iter().any(|w| !w.is_finite()) {
        return Err("the mesh contains invalid (non-finite) vertex positions".to_string());
    }

    let mut stats = MeshStats::default();
    let indices: Vec<[u32; 3]> = raw
        .indices
        .par_iter()
        .copied()
        .filter(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            (b - a).cross(c - a).length_squared() > 0.0
        })
        .collect();
    stats.degenerate = raw.indices.len() - indices.len();

    let normals = if face_normals {
        None
    } else {
        let mut file_normals = raw.normals;
        let mut missing = file_normals.is_none();
        if let Some(ns) = &mut file_normals {
            // (zero normals: missing; transformed ones: non-finite)
            let (zero, bad) = ns
                .par_iter_mut()
                .map(|n| {
                    if *n == Vec3::ZERO {
                        return (true, false);
                    }
                    *n = (normal_matrix * n.as_dvec3()).normalize().as_vec3();
                    (false, !n.is_finite())
                })
                .reduce(|| (false, false), |a, b| (a.0 | b.0, a.1 | b.1));
            if bad {
                return Err("the mesh contains invalid (non-finite) vertex normals".to_string());
            }
            missing |= zero;
        }
        if missing {
            let (computed, invalid) = recompute_vertex_normals(&positions, &indices);
            stats.invalid_normals = invalid;
            match &mut file_normals {
                Some(ns) => {
                    for (n, c) in ns.iter_mut().zip(computed) {
                        if *n == Vec3::ZERO {
                            *n = c;
                        }
                    }
                }
                None => file_normals = Some(computed),
            }
        }
        file_normals
    };

    Ok((
        Mesh {
            positions,
            normals,
            uvs: raw.uvs,
            tangents: None,
            indices,
            flip_normals,
        },
        stats,
    ))
}

/// The angle between two unit vectors, accurate also for nearly (anti)parallel ones
/// (Dr.Jit's `unit_angle`).
fn unit_angle(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * ((a + b).length() * 0.5).min(1.0).asin()
    } else {
        2.0 * ((b - a).length() * 0.5).min(1.0).asin()
    }
}

/// Vertex normals as the average of the adjacent face normals weighted by the face's angle
/// at the vertex (Thürmer and Wüthrich 1998), skipping zero-area faces. A vertex that gets no
/// contribution receives (1, 0, 0), as in Mitsuba; their number is returned (only vertices used
/// by some triangle are counted).
pub(crate) fn recompute_vertex_normals(
    positions: &[Vec3],
    indices: &[[u32; 3]],
) -> (Vec<Vec3>, usize) {
    let mut acc = vec![Vec3::ZERO; positions.len()];
    let mut used = vec![false; positions.len()];
    for t in indices {
        let v = t.map(|i| positions[i as usize]);
        for &i in t {
            used[i as usize] = true;
        }
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        let len2 = n.length_squared();
        if !(len2 > 0.0) {
            continue;
        }
        let n = n / len2.sqrt();
        for j in 0..3 {
            let e1 = (v[(j + 1) % 3] - v[j]).normalize();
            let e2 = (v[(j + 2) % 3] - v[j]).normalize();
            let angle = unit_angle(e1, e2);
            if angle.is_finite() {
                acc[t[j] as usize] += n * angle;
            }
        }
    }
    let mut invalid = 0;
    let normals = acc
        .into_iter()
        .zip(used)
        .map(|(n, u)| {
            let len = n.length();
            if len > 0.0 && len.is_finite() {
                n / len
            } else {
                if u {
                    invalid += 1;
                }
                Vec3::X
            }
        })
        .collect();
    (normals, invalid)
}

/// Mitsuba's `cube` (`src/shapes/cube.cpp`): [-1, 1]³ as 24 vertices (4 per face, so normals
/// and uvs are per face) and 12 triangles.
pub(crate) fn cube() -> RawMesh {
    #[rustfmt::skip]
    const P: [[f32; 3]; 24] = [
        [ 1., -1., -1.], [ 1., -1.,  1.], [-1., -1.,  1.], [-1., -1., -1.],
        [ 1.,  1., -1.], [-1.,  1., -1.], [-1.,  1.,  1.], [ 1.,  1.,  1.],
        [ 1., -1., -1.], [ 1.,  1., -1.], [ 1.,  1.,  1.], [ 1., -1.,  1.],
        [ 1., -1.,  1.], [ 1.,  1.,  1.], [-1.,  1.,  1.], [-1., -1.,  1.],
        [-1., -1.,  1.], [-1.,  1.,  1.], [-1.,  1., -1.], [-1., -1., -1.],
        [ 1.,  1., -1.], [ 1., -1., -1.], [-1., -1., -1.], [-1.,  1., -1.],
    ];
    // One normal per face of four vertices: -y, +y, +x, +z, -x, -z.
    const N: [[f32; 3]; 6] = [
        [0., -1., 0.],
        [0., 1., 0.],
        [1., 0., 0.],
        [0., 0., 1.],
        [-1., 0., 0.],
        [0., 0., -1.],
    ];
    const UV: [[f32; 2]; 4] = [[0., 1.], [1., 1.], [1., 0.], [0., 0.]];
    let positions = P.iter().map(|p| Vec3::from_array(*p)).collect();
    let normals = (0..24).map(|i| Vec3::from_array(N[i / 4])).collect();
    let uvs = (0..24).map(|i| Vec2::from_array(UV[i % 4])).collect();
    let indices = (0..6u32)
        .flat_map(|f| [[4 * f, 4 * f + 1, 4 * f + 2], [4 * f + 3, 4 * f, 4 * f + 2]])
        .collect();
    RawMesh {
        positions,
        normals: Some(normals),
        uvs: Some(uvs),
        indices,
    }
}

/// Mitsuba's `rectangle` (`src/shapes/rectangle.cpp`): [-1, 1]² at z = 0, normal +z,
/// uv = ((x + 1)/2, (y + 1)/2), two triangles; flat, so no vertex normals.
pub(crate) fn rectangle() -> RawMesh {
    let mut positions = Vec::with_capacity(4);
    let mut uvs = Vec::with_capacity(4);
    for i in 0..4u32 {
        let (x, y) = ((i & 1) as f32, ((i & 2) >> 1) as f32);
        positions.push(Vec3::new(2.0 * x - 1.0, 2.0 * y - 1.0, 0.0));
        uvs.push(Vec2::new(x, y));
    }
    RawMesh {
        positions,
        normals: None,
        uvs: Some(uvs),
        indices: vec![[1, 2, 0], [1, 3, 2]],
    }
}
