//! Wavefront OBJ reader with the semantics of Mitsuba's `obj` plugin (`src/shapes/obj.cpp`):
//! `v`, `vt`, `vn` and `f` lines (other statements are ignored); face corners `v`, `v/vt`,
//! `v//vn` or `v/vt/vn`, plus negative (relative) indices, which Mitsuba lacks; polygons
//! are fan-triangulated; one output vertex per distinct (v, vt, vn) triple, numbered in order
//! of first use.

use crate::mesh::RawMesh;
use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// A problem in an OBJ file: message and 1-based line.
#[derive(Debug)]
pub(crate) struct ObjError {
    pub line: u32,
    pub message: String,
}

/// Parses OBJ text. `flip_tex_coords` maps v to 1 − v; with `skip_normals` (`face_normals`)
/// `vn` lines are not read.
pub(crate) fn parse_obj(
    text: &str,
    flip_tex_coords: bool,
    skip_normals: bool,
) -> Result<RawMesh, ObjError> {
    let mut v: Vec<Vec3> = Vec::new();
    let mut vt: Vec<Vec2> = Vec::new();
    let mut vn: Vec<Vec3> = Vec::new();
    // (v, vt, vn), 1-based, 0 = absent -> output vertex.
    let mut map: HashMap<[u32; 3], u32> = HashMap::new();
    let mut keys: Vec<[u32; 3]> = Vec::new();
    let mut indices: Vec<[u32; 3]> = Vec::new();
    let mut any_vt = false;
    let mut any_vn = false;

    for (lineno, raw_line) in text.split('\n').enumerate() {
        let line_no = (lineno + 1) as u32;
        let err = |message: String| ObjError {
            line: line_no,
            message,
        };
        let line = raw_line
            .trim_end_matches('\r')
            .trim_start_matches([' ', '\t']);
        let mut toks = line.split_ascii_whitespace();
        let Some(kw) = toks.next() else { continue };
        let floats = |toks: std::str::SplitAsciiWhitespace,
                      n: usize,
                      what: &str|
         -> Result<Vec<f32>, ObjError> {
            let vals: Vec<f32> = toks.take(n).map_while(|t| t.parse::<f32>().ok()).collect();
            if vals.len() < n {
                return Err(ObjError {
                    line: line_no,
                    message: format!(
                        "could not parse {what} line \"{}\" (expected {n} numbers)",
                        raw_line.trim_end()
                    ),
                });
            }
            Ok(vals)
        };
        match kw {
            "v" => {
                let p = floats(toks, 3, "vertex")?;
                let p = Vec3::new(p[0], p[1], p[2]);
                if !p.is_finite() {
                    return Err(err(
                        "the mesh contains invalid (non-finite) vertex position data".into(),
                    ));
                }
                v.push(p);
            }
            "vt" => {
                let t = floats(toks, 2, "texture coordinate")?;
                let y = if flip_tex_coords { 1.0 - t[1] } else { t[1] };
                vt.push(Vec2::new(t[0], y));
            }
            "vn" => {
                if !skip_normals {
                    let n = floats(toks, 3, "normal")?;
                    let n = Vec3::new(n[0], n[1], n[2]);
                    if !n.is_finite() {
                        return Err(err(
                            "the mesh contains invalid (non-finite) vertex normal data".into(),
                        ));
                    }
                    vn.push(n);
                }
            }
            "f" => {
                let mut corners: Vec<u32> = Vec::new();
                for tok in toks {
                    let key =
                        face_corner(tok, v.len(), vt.len(), vn.len(), skip_normals).map_err(err)?;
                    any_vt |= key[1] != 0;
                    any_vn |= key[2] != 0;
                    let next = keys.len() as u32;
                    let id = *map.entry(key).or_insert_with(|| {
                        keys.push(key);
                        next
                    });
                    corners.push(id);
                }
                if corners.len() < 3 {
                    return Err(err(format!(
                        "face with fewer than 3 vertices: \"{}\"",
                        raw_line.trim_end()
                    )));
                }
                for k in 1..corners.len() - 1 {
                    indices.push([corners[0], corners[k], corners[k + 1]]);
                }
            }
            _ => {}
        }
    }

    let positions = keys.iter().map(|k| v[(k[0] - 1) as usize]).collect();
    let uvs = any_vt.then(|| {
        keys.iter()
            .map(|k| {
                if k[1] == 0 {
                    Vec2::ZERO
                } else {
                    vt[(k[1] - 1) as usize]
                }
            })
            .collect()
    });
    // Corners without a normal keep a zero vector: they get a recomputed one later.
    let normals = (any_vn && !skip_normals).then(|| {
        keys.iter()
            .map(|k| {
                if k[2] == 0 {
                    Vec3::ZERO
                } else {
                    vn[(k[2] - 1) as usize]
                }
            })
            .collect()
    });
    Ok(RawMesh {
        positions,
        normals,
        uvs,
        indices,
    })
}

/// Resolves one 1-based or negative (relative) OBJ index against `count` elements so far.
fn resolve(s: &str, count: usize, what: &str) -> Result<u32, String> {
    let i: i64 = s
        .parse()
        .map_err(|_| format!("could not parse {what} index \"{s}\""))?;
    let abs = if i < 0 { count as i64 + 1 + i } else { i };
    if i == 0 || abs < 1 || abs > count as i64 {
        return Err(format!(
            "reference to invalid {what} {i} ({count} defined so far)"
        ));
    }
    Ok(abs as u32)
}

/// One face corner: "v", "v/vt", "v//vn" or "v/vt/vn".
fn face_corner(
    tok: &str,
    nv: usize,
    nvt: usize,
    nvn: usize,
    skip_normals: bool,
) -> Result<[u32; 3], String> {
    let parts: Vec<&str> = tok.split('/').collect();
    if parts.len() > 3 || parts[0].is_empty() {
        return Err(format!("could not parse face corner \"{tok}\""));
    }
    let mut key = [resolve(parts[0], nv, "vertex")?, 0, 0];
    if let Some(t) = parts.get(1).filter(|t| !t.is_empty()) {
        key[1] = resolve(t, nvt, "texture coordinate")?;
    }
    if let Some(n) = parts.get(2).filter(|n| !n.is_empty()) {
        // With face_normals the normals are not read, but the index still tells vertices
        // apart, as in Mitsuba; it is only range-checked when normals are read.
        key[2] = if skip_normals {
            n.parse::<i64>()
                .map_err(|_| format!("could not parse normal index \"{n}\""))?
                .unsigned_abs() as u32
        } else {
            resolve(n, nvn, "normal")?
        };
    }
    Ok(key)
}
