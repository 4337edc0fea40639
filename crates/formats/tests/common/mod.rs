//! Writes small glTF files for the tests: a JSON document built with `serde_json` plus one
//! binary buffer, saved as `.gltf` with an external `.bin`, as `.gltf` with a base64 data
//! URI, or as `.glb`.
#![allow(dead_code)]

use base64::Engine;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

pub struct GltfBuilder {
    pub json: Value,
    pub bin: Vec<u8>,
}

#[derive(Clone, Copy, Debug)]
pub enum Container {
    /// `name.gltf` with `name.bin` beside it.
    External,
    /// `name.gltf` with the buffer in a base64 data URI.
    DataUri,
    /// `name.glb`.
    Glb,
}

pub const ALL_CONTAINERS: [Container; 3] =
    [Container::External, Container::DataUri, Container::Glb];

/// A fresh directory for one test's files (under the target's temporary folder, kept after
/// the run so that they can be validated with the Khronos validator).
pub fn test_dir(name: &str) -> PathBuf {
    let base = option_env!("CARGO_TARGET_TMPDIR")
        .map(PathBuf::from)
        .unwrap_or_else(std::env::temp_dir);
    let dir = base.join("gltf-tests").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

impl Default for GltfBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl GltfBuilder {
    pub fn new() -> Self {
        Self {
            json: json!({ "asset": { "version": "2.0", "generator": "radia tests" } }),
            bin: Vec::new(),
        }
    }

    /// Appends `v` to the top-level array `key`; returns its index.
    pub fn push(&mut self, key: &str, v: Value) -> usize {
        let root = self.json.as_object_mut().unwrap();
        let arr = root.entry(key).or_insert_with(|| json!([]));
        let arr = arr.as_array_mut().unwrap();
        arr.push(v);
        arr.len() - 1
    }

    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        let mut v = json!({ "buffer": 0, "byteOffset": offset, "byteLength": bytes.len() });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.push("bufferViews", v)
    }

    /// A float accessor of `ty` ("VEC3", ...); POSITION accessors carry min/max as the
    /// specification requires.
    pub fn floats(&mut self, data: &[f32], ty: &str) -> usize {
        let n = match ty {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            _ => panic!("type {ty}"),
        };
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(34962));
        let mut min = vec![f32::INFINITY; n];
        let mut max = vec![f32::NEG_INFINITY; n];
        for c in data.chunks(n) {
            for k in 0..n {
                min[k] = min[k].min(c[k]);
                max[k] = max[k].max(c[k]);
            }
        }
        self.push(
            "accessors",
            json!({ "bufferView": view, "componentType": 5126, "count": data.len() / n,
                    "type": ty, "min": min, "max": max }),
        )
    }

    /// An UNSIGNED_SHORT index accessor.
    pub fn indices(&mut self, data: &[u16]) -> usize {
        let mut bytes: Vec<u8> = data.iter().flat_map(|i| i.to_le_bytes()).collect();
        while bytes.len() % 4 != 0 {
            bytes.push(0);
        }
        let view = self.view(&bytes, Some(34963));
        self.push(
            "accessors",
            json!({ "bufferView": view, "componentType": 5123, "count": data.len(), "type": "SCALAR" }),
        )
    }

    /// A mesh of one triangle primitive; returns the mesh index.
    pub fn mesh(
        &mut self,
        positions: &[[f32; 3]],
        normals: Option<&[[f32; 3]]>,
        indices: Option<&[u16]>,
        material: Option<usize>,
    ) -> usize {
        let p = self.floats(&positions.concat(), "VEC3");
        let mut attributes = json!({ "POSITION": p });
        if let Some(ns) = normals {
            attributes["NORMAL"] = json!(self.floats(&ns.concat(), "VEC3"));
        }
        let mut prim = json!({ "attributes": attributes });
        if let Some(ix) = indices {
            prim["indices"] = json!(self.indices(ix));
        }
        if let Some(m) = material {
            prim["material"] = json!(m);
        }
        self.push("meshes", json!({ "primitives": [prim] }))
    }

    /// A node list of a single default scene.
    pub fn scene(&mut self, roots: &[usize]) {
        self.push("scenes", json!({ "nodes": roots }));
        self.json["scene"] = json!(0);
    }

    pub fn use_extension(&mut self, name: &str, required: bool) {
        self.push("extensionsUsed", json!(name));
        if required {
            self.push("extensionsRequired", json!(name));
        }
    }

    /// Writes the file in `dir` as `name` with the container's extension.
    pub fn write(&self, dir: &Path, name: &str, container: Container) -> PathBuf {
        let mut json = self.json.clone();
        match container {
            Container::External => {
                std::fs::write(dir.join(format!("{name}.bin")), &self.bin).unwrap();
                json["buffers"] =
                    json!([{ "uri": format!("{name}.bin"), "byteLength": self.bin.len() }]);
                let path = dir.join(format!("{name}.gltf"));
                std::fs::write(&path, serde_json::to_vec_pretty(&json).unwrap()).unwrap();
                path
            }
            Container::DataUri => {
                let b64 = base64::engine::general_purpose::STANDARD.encode(&self.bin);
                json["buffers"] = json!([{
                    "uri": format!("data:application/octet-stream;base64,{b64}"),
                    "byteLength": self.bin.len()
                }]);
                let path = dir.join(format!("{name}.gltf"));
                std::fs::write(&path, serde_json::to_vec_pretty(&json).unwrap()).unwrap();
                path
            }
            Container::Glb => {
                json["buffers"] = json!([{ "byteLength": self.bin.len() }]);
                let path = dir.join(format!("{name}.glb"));
                std::fs::write(&path, glb(&json, &self.bin)).unwrap();
                path
            }
        }
    }
}

/// A GLB container (specification §4.4): header, JSON chunk padded with spaces, BIN chunk
/// padded with zeros.
pub fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while b.len() % 4 != 0 {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + if b.is_empty() { 0 } else { 8 + b.len() };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    if !b.is_empty() {
        out.extend_from_slice(&(b.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&b);
    }
    out
}

/// A unit quad in the xy-plane facing +z: 4 vertices, 2 counter-clockwise triangles.
pub const QUAD: [[f32; 3]; 4] = [[-1., -1., 0.], [1., -1., 0.], [1., 1., 0.], [-1., 1., 0.]];
pub const QUAD_INDICES: [u16; 6] = [0, 1, 2, 0, 2, 3];

/// A cube [−1, 1]³ with outward counter-clockwise faces (flat: no normals).
pub fn cube() -> (Vec<[f32; 3]>, Vec<u16>) {
    let (x, y, z) = (glam::Vec3::X, glam::Vec3::Y, glam::Vec3::Z);
    // (n, u, v) with u × v = n.
    let faces = [
        (x, y, z),
        (-x, z, y),
        (y, z, x),
        (-y, x, z),
        (z, x, y),
        (-z, y, x),
    ];
    let mut p = Vec::new();
    let mut ix = Vec::new();
    for (n, u, v) in faces {
        let base = p.len() as u16;
        for c in [n - u - v, n + u - v, n + u + v, n - u + v] {
            p.push(c.to_array());
        }
        ix.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    (p, ix)
}

/// The node matrix (column-major) of a glTF camera or light at `eye` looking at `target`:
/// local −z towards the target, +y as close to `up` as it can be, +x to the right.
pub fn looking_at(eye: glam::Vec3, target: glam::Vec3, up: glam::Vec3) -> [f32; 16] {
    let back = (eye - target).normalize();
    let right = up.cross(back).normalize();
    let up = back.cross(right);
    glam::Mat4::from_cols(
        right.extend(0.0),
        up.extend(0.0),
        back.extend(0.0),
        eye.extend(1.0),
    )
    .to_cols_array()
}

impl GltfBuilder {
    /// An image embedded in the buffer (a buffer view without target) with its MIME type;
    /// returns the image index.
    pub fn image(&mut self, bytes: &[u8], mime_type: &str) -> usize {
        let view = self.view(bytes, None);
        self.push(
            "images",
            json!({ "bufferView": view, "mimeType": mime_type }),
        )
    }

    /// A texture of `image` with a new sampler (`magFilter`, `wrapS`, `wrapT` as glTF's GL
    /// enums); returns the texture index.
    pub fn texture(&mut self, image: usize, mag_filter: u32, wrap_s: u32, wrap_t: u32) -> usize {
        let sampler = self.push(
            "samplers",
            json!({ "magFilter": mag_filter, "wrapS": wrap_s, "wrapT": wrap_t }),
        );
        self.push("textures", json!({ "source": image, "sampler": sampler }))
    }

    /// A mesh of one indexed triangle primitive with normals and TEXCOORD_0.
    pub fn mesh_with_uv(
        &mut self,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        uvs: &[[f32; 2]],
        indices: &[u16],
        material: usize,
    ) -> usize {
        let p = self.floats(&positions.concat(), "VEC3");
        let n = self.floats(&normals.concat(), "VEC3");
        let t = self.floats(&uvs.concat(), "VEC2");
        let i = self.indices(indices);
        self.push(
            "meshes",
            json!({ "primitives": [{ "attributes": { "POSITION": p, "NORMAL": n, "TEXCOORD_0": t },
                                      "indices": i, "material": material }] }),
        )
    }
}

/// glTF sampler enums (§5.26).
pub const NEAREST: u32 = 9728;
pub const LINEAR: u32 = 9729;
pub const REPEAT: u32 = 10497;
pub const MIRRORED_REPEAT: u32 = 33648;
pub const CLAMP_TO_EDGE: u32 = 33071;

/// An 8-bit PNG (RGB, or RGBA with `channels` 4) of `width × height` texels, row 0 at the top.
pub fn png(width: u32, height: u32, channels: u8, data: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let color = if channels == 4 {
        image::ExtendedColorType::Rgba8
    } else if channels == 1 {
        image::ExtendedColorType::L8
    } else {
        image::ExtendedColorType::Rgb8
    };
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut out),
        data,
        width,
        height,
        color,
    )
    .unwrap();
    out
}

/// A UV sphere of radius 1 with `rings` × `segments` quads: positions, normals, uv and
/// counter-clockwise (outward) triangles.
#[allow(clippy::type_complexity)]
pub fn uv_sphere(
    rings: u16,
    segments: u16,
) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<[f32; 2]>, Vec<u16>) {
    let (mut p, mut uv, mut ix) = (Vec::new(), Vec::new(), Vec::new());
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
            p.push([
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            ]);
            uv.push([s as f32 / segments as f32, r as f32 / rings as f32]);
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b) = (r * row + s, (r + 1) * row + s);
            if r > 0 {
                ix.extend([a, b, a + 1]);
            }
            if r + 1 < rings {
                ix.extend([a + 1, b, b + 1]);
            }
        }
    }
    let n = p.clone();
    (p, n, uv, ix)
}

/// A Wavefront OBJ of a mesh (positions, normals, uv as given: read it with
/// `flip_tex_coords` false to keep glTF's uv).
pub fn obj(
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    uvs: &[[f32; 2]],
    indices: &[u16],
) -> String {
    let mut s = String::new();
    for v in positions {
        s += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    for v in uvs {
        s += &format!("vt {} {}\n", v[0], v[1]);
    }
    for v in normals {
        s += &format!("vn {} {} {}\n", v[0], v[1], v[2]);
    }
    for t in indices.chunks(3) {
        s += "f";
        for i in t {
            s += &format!(" {0}/{0}/{0}", i + 1);
        }
        s += "\n";
    }
    s
}
