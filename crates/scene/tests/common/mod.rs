//! Geometry shared by the BVH tests (each test file is its own crate): a tessellated sphere,
//! a soup of random triangles, random points and directions.

#![allow(dead_code)] // each test binary uses its own part

use glam::{Vec2, Vec3};
use radia_scene::Mesh;
use rand::Rng;
use rand_pcg::Pcg64;

/// A closed sphere of `rings` × `segments` quads (two triangles each), sharing its vertices.
pub fn uv_sphere(center: Vec3, radius: f32, rings: u32, segments: u32) -> Mesh {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
            positions.push(
                center
                    + radius
                        * Vec3::new(
                            theta.sin() * phi.cos(),
                            theta.sin() * phi.sin(),
                            theta.cos(),
                        ),
            );
        }
    }
    for r in 0..rings {
        for s in 0..segments {
            let a = r * segments + s;
            let b = r * segments + (s + 1) % segments;
            let c = a + segments;
            let d = b + segments;
            indices.push([a, c, b]);
            indices.push([b, c, d]);
        }
    }
    Mesh {
        positions,
        indices,
        ..Default::default()
    }
}

/// `n` small triangles: corners within `size` of centres uniform in [−half, half]³.
pub fn soup(rng: &mut Pcg64, n: usize, half: f32, size: f32) -> Mesh {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for i in 0..n {
        let c = random_in_cube(rng, half);
        for _ in 0..3 {
            positions.push(c + random_in_cube(rng, size));
        }
        let k = 3 * i as u32;
        indices.push([k, k + 1, k + 2]);
    }
    Mesh {
        positions,
        indices,
        ..Default::default()
    }
}

/// A uniformly random point in the cube [−half, half]³.
pub fn random_in_cube(rng: &mut Pcg64, half: f32) -> Vec3 {
    Vec3::new(
        rng.random_range(-half..half),
        rng.random_range(-half..half),
        rng.random_range(-half..half),
    )
}

/// A uniformly random unit vector.
pub fn random_dir(rng: &mut Pcg64) -> Vec3 {
    radia_sampling::warp::square_to_uniform_sphere(Vec2::new(rng.random(), rng.random()))
}
