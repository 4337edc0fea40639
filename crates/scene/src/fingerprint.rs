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

#[cfg(test)]
mod tests {
    use crate::description::*;
    use crate::loader::load_mitsuba_xml_with_warnings;

    fn load(xml: &str, name: &str) -> SceneDescription {
        let dir = std::env::temp_dir().join(format!("radia-fingerprint-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, xml).unwrap();
        load_mitsuba_xml_with_warnings(&path, &[]).unwrap().0
    }

    const SCENE: &str = r#"<scene version="3.0.0">
        <default name="r" value="1"/>
        <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>
        <integer name="height" value="8"/></film></sensor>
        <shape type="sphere"><float name="radius" value="$r"/></shape>
        <emitter type="constant"/>
    </scene>"#;

    #[test]
    fn same_content_under_another_path_agrees() {
        let a = load(SCENE, "a.xml");
        let b = load(&format!("\n\n{SCENE}"), "b.xml");
        assert_eq!(a.fingerprint(), b.fingerprint());
    }

    #[test]
    fn any_change_of_content_disagrees() {
        let a = load(SCENE, "c.xml");
        let b = load(
            &SCENE.replace(r#"value="1"/>"#, r#"value="1.01"/>"#),
            "d.xml",
        );
        assert_ne!(a.fingerprint(), b.fingerprint());
        let mut c = a.clone();
        c.film.width = 9;
        assert_ne!(a.fingerprint(), c.fingerprint());
        let mut d = a.clone();
        d.integrator.max_depth = 3;
        assert_ne!(a.fingerprint(), d.fingerprint());
    }
}
