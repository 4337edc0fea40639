//! Stanford PLY reader (ASCII, binary little and big endian) with the conventions of
//! Mitsuba's `ply` plugin (`src/shapes/ply.cpp`, `ply.h`): vertex `x y z`, optional `nx ny nz`,
//! texture coordinates `u v`, `texture_u texture_v` or `s t`; faces from the list
//! `vertex_indices` or `vertex_index`. Mitsuba accepts only triangles; polygons are
//! fan-triangulated here (a quad becomes two triangles). Other elements and properties are
//! skipped.

use crate::mesh::RawMesh;
use glam::{Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F16,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "long" => Scalar::I64,
            "ulong" => Scalar::U64,
            "half" | "float16" => Scalar::F16,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn is_float(self) -> bool {
        matches!(self, Scalar::F16 | Scalar::F32 | Scalar::F64)
    }

    /// Bytes in a binary file.
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 | Scalar::F16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::I64 | Scalar::U64 | Scalar::F64 => 8,
        }
    }
}

/// The binary value of type `t` at the start of `b` (which holds at least `t.size()` bytes),
/// as f64 like [`Body::read`]. For the fixed-layout fast paths of [`parse_ply`].
#[inline(always)]
fn scalar_at(b: &[u8], t: Scalar, big: bool) -> f64 {
    macro_rules! get {
        ($ty:ty, $n:literal) => {{
            let mut a = [0u8; $n];
            a.copy_from_slice(&b[..$n]);
            if big {
                <$ty>::from_be_bytes(a)
            } else {
                <$ty>::from_le_bytes(a)
            }
        }};
    }
    match t {
        Scalar::I8 => b[0] as i8 as f64,
        Scalar::U8 => b[0] as f64,
        Scalar::I16 => get!(i16, 2) as f64,
        Scalar::U16 => get!(u16, 2) as f64,
        Scalar::I32 => get!(i32, 4) as f64,
        Scalar::U32 => get!(u32, 4) as f64,
        Scalar::I64 => get!(i64, 8) as f64,
        Scalar::U64 => get!(u64, 8) as f64,
        Scalar::F16 => half_to_f32(get!(u16, 2)) as f64,
        Scalar::F32 => get!(f32, 4) as f64,
        Scalar::F64 => get!(f64, 8),
    }
}

#[derive(Clone, Debug)]
enum PropType {
    Scalar(Scalar),
    /// count type, item type
    List(Scalar, Scalar),
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    ty: PropType,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    Little,
    Big,
}

/// Header: format, elements, byte offset of the body.
fn parse_header(data: &[u8]) -> Result<(Format, Vec<Element>, usize), String> {
    let mut pos = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut first = true;
    loop {
        let Some(nl) = data[pos..].iter().position(|&b| b == b'\n') else {
            return Err("invalid PLY header: missing \"end_header\"".into());
        };
        let line = std::str::from_utf8(&data[pos..pos + nl])
            .map_err(|_| "invalid PLY header: not ASCII text".to_string())?
            .trim_end_matches('\r');
        pos += nl + 1;
        let toks: Vec<&str> = line.split_ascii_whitespace().collect();
        if first {
            if toks != ["ply"] {
                return Err("not a PLY file (the first line must be \"ply\")".into());
            }
            first = false;
            continue;
        }
        let Some(&kw) = toks.first() else { continue };
        match kw {
            "comment" | "obj_info" => {}
            "format" => {
                if format.is_some() {
                    return Err("invalid PLY header: duplicate \"format\" line".into());
                }
                let f = match toks.get(1) {
                    Some(&"ascii") => Format::Ascii,
                    Some(&"binary_little_endian") => Format::Little,
                    Some(&"binary_big_endian") => Format::Big,
                    _ => {
                        return Err(format!(
                            "invalid PLY header: unknown format line \"{line}\""
                        ))
                    }
                };
                if toks.get(2) != Some(&"1.0") || toks.len() != 3 {
                    return Err(format!("invalid PLY header: unsupported format line \"{line}\" (expected version 1.0)"));
                }
                format = Some(f);
            }
            "element" => {
                if toks.len() != 3 {
                    return Err(format!(
                        "invalid PLY header: malformed element line \"{line}\""
                    ));
                }
                let count = toks[2]
                    .parse::<usize>()
                    .map_err(|_| format!("invalid PLY header: bad element count in \"{line}\""))?;
                elements.push(Element {
                    name: toks[1].to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            "property" => {
                let Some(el) = elements.last_mut() else {
                    return Err("invalid PLY header: \"property\" before \"element\"".into());
                };
                let bad_type =
                    |t: &str| format!("invalid PLY header: unknown type \"{t}\" in \"{line}\"");
                let prop = if toks.get(1) == Some(&"list") {
                    if toks.len() != 5 {
                        return Err(format!(
                            "invalid PLY header: malformed property line \"{line}\""
                        ));
                    }
                    let ct = Scalar::parse(toks[2]).ok_or_else(|| bad_type(toks[2]))?;
                    let it = Scalar::parse(toks[3]).ok_or_else(|| bad_type(toks[3]))?;
                    if ct.is_float() {
                        return Err(format!(
                            "invalid PLY header: list count type must be an integer in \"{line}\""
                        ));
                    }
                    Property {
                        name: toks[4].to_string(),
                        ty: PropType::List(ct, it),
                    }
                } else {
                    if toks.len() != 3 {
                        return Err(format!(
                            "invalid PLY header: malformed property line \"{line}\""
                        ));
                    }
                    let t = Scalar::parse(toks[1]).ok_or_else(|| bad_type(toks[1]))?;
                    Property {
                        name: toks[2].to_string(),
                        ty: PropType::Scalar(t),
                    }
                };
                el.props.push(prop);
            }
            "end_header" => {
                if toks.len() != 1 {
                    return Err("invalid PLY header: excess tokens after \"end_header\"".into());
                }
                let format =
                    format.ok_or_else(|| "invalid PLY header: no \"format\" line".to_string())?;
                return Ok((format, elements, pos));
            }
            other => return Err(format!("invalid PLY header: unknown keyword \"{other}\"")),
        }
    }
}

/// Sequential reader of the body's numbers.
struct Body<'a> {
    data: &'a [u8],
    pos: usize,
    format: Format,
}

impl Body<'_> {
    fn next_token(&mut self) -> Option<&str> {
        while self.pos < self.data.len() && self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < self.data.len() && !self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if start == self.pos {
            return None;
        }
        std::str::from_utf8(&self.data[start..self.pos]).ok()
    }

    fn bytes<const N: usize>(&mut self) -> Option<[u8; N]> {
        let end = self.pos.checked_add(N)?;
        let mut b: [u8; N] = self.data.get(self.pos..end)?.try_into().ok()?;
        self.pos = end;
        if self.format == Format::Little {
            if cfg!(target_endian = "big") {
                b.reverse();
            }
        } else if cfg!(target_endian = "little") {
            b.reverse();
        }
        Some(b)
    }

    /// One value as f64 (exact for every integer a mesh can index).
    fn read(&mut self, t: Scalar) -> Option<f64> {
        if self.format == Format::Ascii {
            let tok = self.next_token()?;
            return if t.is_float() {
                tok.parse::<f64>().ok()
            } else {
                let v = tok.parse::<i64>().ok()?;
                let ok = match t {
                    Scalar::I8 => i8::try_from(v).is_ok(),
                    Scalar::U8 => u8::try_from(v).is_ok(),
                    Scalar::I16 => i16::try_from(v).is_ok(),
                    Scalar::U16 => u16::try_from(v).is_ok(),
                    Scalar::I32 => i32::try_from(v).is_ok(),
                    Scalar::U32 => u32::try_from(v).is_ok(),
                    Scalar::U64 => v >= 0,
                    _ => true,
                };
                ok.then_some(v as f64)
            };
        }
        // The byte arrays are in native order after `bytes`.
        Some(match t {
            Scalar::I8 => i8::from_ne_bytes(self.bytes()?) as f64,
            Scalar::U8 => u8::from_ne_bytes(self.bytes()?) as f64,
            Scalar::I16 => i16::from_ne_bytes(self.bytes()?) as f64,
            Scalar::U16 => u16::from_ne_bytes(self.bytes()?) as f64,
            Scalar::I32 => i32::from_ne_bytes(self.bytes()?) as f64,
            Scalar::U32 => u32::from_ne_bytes(self.bytes()?) as f64,
            Scalar::I64 => i64::from_ne_bytes(self.bytes()?) as f64,
            Scalar::U64 => u64::from_ne_bytes(self.bytes()?) as f64,
            Scalar::F16 => half_to_f32(u16::from_ne_bytes(self.bytes()?)) as f64,
            Scalar::F32 => f32::from_ne_bytes(self.bytes()?) as f64,
            Scalar::F64 => f64::from_ne_bytes(self.bytes()?),
        })
    }
}

/// IEEE 754 binary16 to f32.
fn half_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = ((h >> 10) & 0x1f) as i32;
    let mant = (h & 0x3ff) as f32;
    sign * match exp {
        0 => mant * 2f32.powi(-24),
        31 => {
            if mant == 0.0 {
                f32::INFINITY
            } else {
                f32::NAN
            }
        }
        e => (1.0 + mant / 1024.0) * 2f32.powi(e - 15),
    }
}

/// Parses a PLY file's bytes. `flip_tex_coords` maps v to 1 − v; with `skip_normals`
/// (`face_normals`) normals are not kept.
///
/// Binary files take fast paths where the layout allows (the common case: a vertex element
/// of scalars only, then a face element that is just the index list): vertices are read at
/// fixed offsets of a fixed stride, and faces go straight to triangles without a list per
/// face. The result, errors included, is the same as the general property-by-property
/// reader's (a test compares them).
pub(crate) fn parse_ply(
    data: &[u8],
    flip_tex_coords: bool,
    skip_normals: bool,
) -> Result<RawMesh, String> {
    parse_ply_with(data, flip_tex_coords, skip_normals, true)
}

/// [`parse_ply`]; `fast: false` forces the general reader (for the tests).
pub(crate) fn parse_ply_with(
    data: &[u8],
    flip_tex_coords: bool,
    skip_normals: bool,
    fast: bool,
) -> Result<RawMesh, String> {
    let (format, elements, body_start) = parse_header(data)?;
    let big = format == Format::Big;
    let binary = fast && format != Format::Ascii;
    // The first face error found by the fast face path, reported where the general path
    // checks its polygons.
    let mut face_error: Option<String> = None;
    let mut body = Body {
        data,
        pos: body_start,
        format,
    };
    let mut mesh = RawMesh::default();
    let mut seen_vertex = false;
    let mut seen_face = false;
    let mut polygons: Vec<Vec<f64>> = Vec::new();

    for el in &elements {
        let find = |n: &str| el.props.iter().position(|p| p.name == n);
        let truncated = || format!("unexpected end of data in element \"{}\"", el.name);
        // Guard allocations against absurd counts: every element needs at least one byte.
        let remaining = data.len() - body.pos.min(data.len());
        let capacity = el.count.min(remaining);
        if el.name == "vertex" && !seen_vertex {
            seen_vertex = true;
            let scalar = |n: &str| -> Result<Option<usize>, String> {
                match find(n) {
                    Some(i) if matches!(el.props[i].ty, PropType::Scalar(_)) => Ok(Some(i)),
                    Some(_) => Err(format!("vertex property \"{n}\" must not be a list")),
                    None => Ok(None),
                }
            };
            let (Some(x), Some(y), Some(z)) = (scalar("x")?, scalar("y")?, scalar("z")?) else {
                return Err("the vertex element needs properties x, y and z".into());
            };
            let normal = match (scalar("nx")?, scalar("ny")?, scalar("nz")?) {
                (Some(a), Some(b), Some(c)) if !skip_normals => Some([a, b, c]),
                _ => None,
            };
            let uv = [("u", "v"), ("texture_u", "texture_v"), ("s", "t")]
                .iter()
                .map(|(a, b)| Ok::<_, String>((scalar(a)?, scalar(b)?)))
                .collect::<Result<Vec<_>, _>>()?
                .into_iter()
                .find_map(|p| match p {
                    (Some(a), Some(b)) => Some([a, b]),
                    _ => None,
                });
            mesh.positions.reserve(capacity);
            let mut normals = Vec::with_capacity(if normal.is_some() { capacity } else { 0 });
            let mut uvs = Vec::with_capacity(if uv.is_some() { capacity } else { 0 });
            let mut row = vec![0.0f64; el.props.len()];
            let scalars: Option<Vec<Scalar>> = el
                .props
                .iter()
                .map(|p| match p.ty {
                    PropType::Scalar(t) => Some(t),
                    PropType::List(..) => None,
                })
                .collect();
            if let (true, Some(types)) = (binary, scalars) {
                // Fixed stride: each wanted property at its byte offset.
                let mut offsets = Vec::with_capacity(types.len());
                let mut stride = 0;
                for t in &types {
                    offsets.push(stride);
                    stride += t.size();
                }
                let len = el
                    .count
                    .checked_mul(stride)
                    .filter(|&n| n <= data.len() - body.pos.min(data.len()))
                    .ok_or_else(truncated)?;
                let rows = &data[body.pos..body.pos + len];
                body.pos += len;
                let field = |r: &[u8], k: usize| -> f32 {
                    let b = &r[offsets[k]..];
                    if types[k] == Scalar::F32 {
                        let a = [b[0], b[1], b[2], b[3]];
                        if big {
                            f32::from_be_bytes(a)
                        } else {
                            f32::from_le_bytes(a)
                        }
                    } else {
                        scalar_at(b, types[k], big) as f32
                    }
                };
                mesh.positions.extend(
                    rows.chunks_exact(stride)
                        .map(|r| Vec3::new(field(r, x), field(r, y), field(r, z))),
                );
                if let Some([a, b, c]) = normal {
                    normals.extend(
                        rows.chunks_exact(stride)
                            .map(|r| Vec3::new(field(r, a), field(r, b), field(r, c))),
                    );
                }
                if let Some([a, b]) = uv {
                    uvs.extend(rows.chunks_exact(stride).map(|r| {
                        let v = field(r, b);
                        Vec2::new(field(r, a), if flip_tex_coords { 1.0 - v } else { v })
                    }));
                }
            } else {
                for _ in 0..el.count {
                    for (k, p) in el.props.iter().enumerate() {
                        row[k] = match p.ty {
                            PropType::Scalar(t) => body.read(t).ok_or_else(truncated)?,
                            PropType::List(ct, it) => {
                                let n = body.read(ct).ok_or_else(truncated)?;
                                for _ in 0..n.max(0.0) as u64 {
                                    body.read(it).ok_or_else(truncated)?;
                                }
                                0.0
                            }
                        };
                    }
                    mesh.positions
                        .push(Vec3::new(row[x] as f32, row[y] as f32, row[z] as f32));
                    if let Some([a, b, c]) = normal {
                        normals.push(Vec3::new(row[a] as f32, row[b] as f32, row[c] as f32));
                    }
                    if let Some([a, b]) = uv {
                        let v = row[b] as f32;
                        uvs.push(Vec2::new(
                            row[a] as f32,
                            if flip_tex_coords { 1.0 - v } else { v },
                        ));
                    }
                }
            }
            if normal.is_some() {
                if normals.iter().any(|n| !n.is_finite()) {
                    return Err("the mesh contains invalid (non-finite) vertex normal data".into());
                }
                mesh.normals = Some(normals);
            }
            if uv.is_some() {
                mesh.uvs = Some(uvs);
            }
        } else if el.name == "face" && !seen_face {
            seen_face = true;
            let list = match (find("vertex_indices"), find("vertex_index")) {
                (Some(i), _) | (None, Some(i)) => i,
                _ => {
                    return Err(
                        "the face element needs a vertex_indices (or vertex_index) list".into(),
                    )
                }
            };
            let PropType::List(..) = el.props[list].ty else {
                return Err(format!(
                    "face property \"{}\" must be a list",
                    el.props[list].name
                ));
            };
            let fast_list = match el.props[list].ty {
                PropType::List(ct, it)
                    if binary && seen_vertex && el.props.len() == 1 && !it.is_float() =>
                {
                    Some((ct, it))
                }
                _ => None,
            };
            if let Some((ct, it)) = fast_list {
                // Triangles straight from the bytes; the first invalid face is remembered
                // and reported after the whole body was read, as the general path does.
                let nv = mesh.positions.len();
                let (cs, is) = (ct.size(), it.size());
                mesh.indices.reserve(capacity);
                let mut idx = Vec::new();
                for f in 0..el.count {
                    let c = data.get(body.pos..body.pos + cs).ok_or_else(truncated)?;
                    let n = scalar_at(c, ct, big);
                    if n < 0.0 {
                        return Err("negative list length in the face element".into());
                    }
                    let start = body.pos + cs;
                    let items = (n as usize)
                        .checked_mul(is)
                        .and_then(|len| data.get(start..start.checked_add(len)?))
                        .ok_or_else(truncated)?;
                    body.pos = start + items.len();
                    if face_error.is_some() {
                        continue;
                    }
                    if n < 3.0 {
                        face_error = Some(format!(
                            "face {f} has {} vertices (at least 3 are needed)",
                            n as usize
                        ));
                        continue;
                    }
                    idx.clear();
                    for b in items.chunks_exact(is) {
                        let i = scalar_at(b, it, big);
                        if !(i >= 0.0 && (i as usize) < nv) {
                            face_error = Some(format!(
                                "face {f} refers to vertex {i}, but there are only {nv} vertices"
                            ));
                            break;
                        }
                        idx.push(i as u32);
                    }
                    if face_error.is_none() {
                        for k in 1..idx.len() - 1 {
                            mesh.indices.push([idx[0], idx[k], idx[k + 1]]);
                        }
                    }
                }
                continue;
            }
            polygons.reserve(capacity);
            for _ in 0..el.count {
                for (k, p) in el.props.iter().enumerate() {
                    match p.ty {
                        PropType::Scalar(t) => {
                            body.read(t).ok_or_else(truncated)?;
                        }
                        PropType::List(ct, it) => {
                            let n = body.read(ct).ok_or_else(truncated)?;
                            if n < 0.0 {
                                return Err("negative list length in the face element".into());
                            }
                            let mut items = Vec::with_capacity((n as usize).min(64));
                            for _ in 0..n as u64 {
                                items.push(body.read(it).ok_or_else(truncated)?);
                            }
                            if k == list {
                                polygons.push(items);
                            }
                        }
                    }
                }
            }
        } else if !el.props.is_empty() {
            // Unknown (or repeated) element: read and discard, as Mitsuba skips it.
            for _ in 0..el.count {
                for p in &el.props {
                    match p.ty {
                        PropType::Scalar(t) => {
                            body.read(t).ok_or_else(truncated)?;
                        }
                        PropType::List(ct, it) => {
                            let n = body.read(ct).ok_or_else(truncated)?;
                            for _ in 0..n.max(0.0) as u64 {
                                body.read(it).ok_or_else(truncated)?;
                            }
                        }
                    }
                }
            }
        }
    }
    let trailing = match format {
        Format::Ascii => body.next_token().is_some(),
        _ => body.pos != data.len(),
    };
    if trailing {
        return Err("invalid file -- trailing content after the last element".into());
    }
    if !seen_vertex {
        return Err("the file has no vertex element".into());
    }

    if let Some(e) = face_error {
        return Err(e);
    }
    let nv = mesh.positions.len();
    for (f, poly) in polygons.iter().enumerate() {
        if poly.len() < 3 {
            return Err(format!(
                "face {f} has {} vertices (at least 3 are needed)",
                poly.len()
            ));
        }
        let mut idx = Vec::with_capacity(poly.len());
        for &i in poly {
            if !(i >= 0.0 && (i as usize) < nv) || i.fract() != 0.0 {
                return Err(format!(
                    "face {f} refers to vertex {i}, but there are only {nv} vertices"
                ));
            }
            idx.push(i as u32);
        }
        for k in 1..idx.len() - 1 {
            mesh.indices.push([idx[0], idx[k], idx[k + 1]]);
        }
    }
    if mesh.positions.iter().any(|p| !p.is_finite()) {
        return Err("the mesh contains invalid (non-finite) vertex position data".into());
    }
    Ok(mesh)
}
