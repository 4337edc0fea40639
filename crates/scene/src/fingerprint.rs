//! A fingerprint of a scene description: what must agree between the pieces of a render split
//! across processes or machines (`radia merge` refuses pieces whose fingerprints differ).
//!
//! It hashes the content the renderer sees (integrator, camera, film, sampler, every shape's
//! geometry, material and emission, every emitter), not the XML text: two machines that keep
//! the scene under different paths, or a scene whose `<default>`s are overridden to the same
//! values, agree. Where a shape was declared (`origin`, a "file:line" for messages) is left out
//! for the same reason. Bulk data (mesh vertices, envmap pixels) is hashed as its bits; the
//! rest through its `Debug` form, which lists every field.

use crate::description::{EmitterDesc, Geometry, Mesh, SceneDescription};
use glam::{Vec2, Vec3};
use std::fmt::Write as _;
use xxhash_rust::xxh3::Xxh3;

impl SceneDescription {
    /// A 64-bit hash (xxh3, the same on every platform and release) of everything that
    /// determines the rendered image.
    pub fn fingerprint(&self) -> u64 {
        let mut h = Hasher(Xxh3::new());
        let _ = write!(
            h,
            "{:?}|{:?}|{:?}|{:?}|",
            self.integrator, self.camera, self.film, self.sampler
        );
        let hash_shape = |h: &mut Hasher, shape: &crate::ShapeDesc| {
            match &shape.geometry {
                Geometry::Mesh(mesh) => hash_mesh(h, mesh),
                other => {
                    let _ = write!(h, "{other:?}");
                }
            }
            let _ = write!(h, "|{:?}|{:?}|", shape.bsdf, shape.emission);
        };
        for shape in &self.shapes {
            hash_shape(&mut h, shape);
        }
        // Absent without shape groups, so such scenes keep their fingerprints.
        for (g, group) in self.shape_groups.iter().enumerate() {
            let _ = write!(h, "group {g}|");
            for shape in group {
                hash_shape(&mut h, shape);
            }
        }
        for emitter in &self.emitters {
            match emitter {
                EmitterDesc::Envmap {
                    image,
                    scale,
                    to_world,
                    mis_compensation,
                } => {
                    let _ = write!(
                        h,
                        "envmap {}x{} {scale:?} {to_world:?} {mis_compensation}",
                        image.width, image.height
                    );
                    h.vec3s(&image.pixels);
                }
                other => {
                    let _ = write!(h, "{other:?}");
                }
            }
            h.0.update(b"|");
        }
        // Positions above are camera-relative; two scenes that differ by a translation of
        // everything differ only here (and in their `position` AOV).
        let _ = write!(h, "{:?}", self.world_origin);
        // Absent when every weight is 1, so such scenes keep their fingerprints.
        if self.sampling_weights != Default::default() {
            let _ = write!(h, "weights {:?}|", self.sampling_weights);
        }
        h.0.digest()
    }
}

fn hash_mesh(h: &mut Hasher, mesh: &Mesh) {
    let _ = write!(
        h,
        "mesh {} {} {:?} {:?} {}",
        mesh.positions.len(),
        mesh.indices.len(),
        mesh.normals.as_ref().map(Vec::len),
        mesh.uvs.as_ref().map(Vec::len),
        mesh.flip_normals
    );
    h.vec3s(&mesh.positions);
    if let Some(n) = &mesh.normals {
        h.vec3s(n);
    }
    if let Some(uv) = &mesh.uvs {
        for v in uv.iter().flat_map(Vec2::to_array) {
            h.0.update(&v.to_le_bytes());
        }
    }
    for i in mesh.indices.iter().flatten() {
        h.0.update(&i.to_le_bytes());
    }
}

/// Feeds `write!` output straight into the hash (no string is built).
struct Hasher(Xxh3);

impl Hasher {
    fn vec3s(&mut self, values: &[Vec3]) {
        for v in values {
            for c in v.to_array() {
                self.0.update(&c.to_le_bytes());
            }
        }
    }
}

impl std::fmt::Write for Hasher {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.0.update(s.as_bytes());
        Ok(())
    }
}
