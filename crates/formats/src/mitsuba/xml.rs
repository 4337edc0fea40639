//! First stage of the loader: the XML text becomes a list of plugin nodes with typed
//! properties, following Mitsuba 3.9.1's parser (`src/core/parser.cpp`): `$name`
//! substitution (longest names first, `\$` escapes), `<default>`, attribute checks, value
//! syntax, `<transform>` composition, ids, `<ref>` and `<alias>`. Nothing here knows what a
//! plugin does with its properties; that is the builder's job (`build.rs`).

use super::transform;
use crate::error::{LoadError, TextPos};
use glam::{DMat4, DVec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Object element kinds radia can build. Mitsuba also has `medium`, `phase` and `volume`;
/// those are rejected while parsing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    Scene,
    Integrator,
    Sensor,
    Film,
    Sampler,
    RFilter,
    Shape,
    Bsdf,
    Emitter,
    Texture,
}

impl Kind {
    /// The XML tag of this kind.
    pub fn tag(self) -> &'static str {
        match self {
            Kind::Scene => "scene",
            Kind::Integrator => "integrator",
            Kind::Sensor => "sensor",
            Kind::Film => "film",
            Kind::Sampler => "sampler",
            Kind::RFilter => "rfilter",
            Kind::Shape => "shape",
            Kind::Bsdf => "bsdf",
            Kind::Emitter => "emitter",
            Kind::Texture => "texture",
        }
    }
}

/// A property value, in the precision Mitsuba parses (double).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Value {
    Float(f64),
    Integer(i64),
    Boolean(bool),
    String(String),
    Rgb(DVec3),
    /// A uniform `<spectrum value="v"/>` (one value at every wavelength). What it means in
    /// Mitsuba's RGB variants depends on who reads it ([`super::props::Props::color`]).
    UniformSpectrum(f64),
    /// `<point>` or `<vector>` (one type in Mitsuba 3).
    Vector(DVec3),
    Transform(DMat4),
    /// An unresolved `<ref id="..."/>`; replaced by `Object` before building.
    Ref(String),
    /// A nested or referenced object: an index into [`Doc::nodes`].
    Object(usize),
}

impl Value {
    /// The name of the value's type, as the XML tag that makes it.
    pub fn type_name(&self) -> &'static str {
        match self {
            Value::Float(_) => "float",
            Value::Integer(_) => "integer",
            Value::Boolean(_) => "boolean",
            Value::String(_) => "string",
            Value::Rgb(_) => "rgb",
            Value::UniformSpectrum(_) => "spectrum",
            Value::Vector(_) => "point/vector",
            Value::Transform(_) => "transform",
            Value::Ref(_) | Value::Object(_) => "object",
        }
    }
}

/// One named property of a node, with where it was declared.
#[derive(Clone, Debug)]
pub(crate) struct Prop {
    pub name: String,
    pub value: Value,
    pub pos: TextPos,
}

/// One plugin instance (`<bsdf type="diffuse">` ...).
#[derive(Clone, Debug)]
pub(crate) struct Node {
    pub kind: Kind,
    /// The `type` attribute ("scene" for the root).
    pub plugin: String,
    pub id: Option<String>,
    /// Index into [`Doc::files`] of the file the node is declared in.
    pub file: u32,
    pub pos: TextPos,
    /// Properties in document order; nested objects get the names `_arg_0`, `_arg_1`, ...
    /// unless they have a `name` attribute.
    pub props: Vec<Prop>,
}

impl Node {
    /// `<bsdf type="diffuse" id="white">`: how messages name the node.
    pub fn describe(&self) -> String {
        match (&self.id, self.kind) {
            (_, Kind::Scene) => "<scene>".to_string(),
            (Some(id), k) => format!("<{} type=\"{}\" id=\"{id}\">", k.tag(), self.plugin),
            (None, k) => format!("<{} type=\"{}\">", k.tag(), self.plugin),
        }
    }
}

/// The parsed scene file: `nodes[0]` is the `<scene>`.
#[derive(Clone, Debug)]
pub(crate) struct Doc {
    pub file: PathBuf,
    /// Directory of the scene file: relative mesh paths start here, also in included files
    /// (Mitsuba's parser.cpp adds the including file's directory to the file resolver only
    /// while it finds and parses an `<include>`; plugins resolve their files later, with the
    /// scene's resolver).
    pub dir: PathBuf,
    /// `files[0]` is `file`; then every file read through `<include>`.
    pub files: Vec<PathBuf>,
    pub nodes: Vec<Node>,
}

impl Doc {
    /// The file node `n` was declared in (for messages).
    pub fn file_of(&self, n: &Node) -> &Path {
        &self.files[n.file as usize]
    }
}

/// Mitsuba's `ParserConfig::max_include_depth` (`include/mitsuba/core/parser.h`).
const MAX_INCLUDE_DEPTH: usize = 15;

/// Deeper element nesting than this is refused (the parsers recurse).
const MAX_DEPTH: usize = 100;

/// The byte offset of the first start tag nested deeper than `max` levels, if any. Comments,
/// CDATA sections, processing instructions and declarations are skipped and quoted attribute
/// values may contain '>' or '/', so valid XML is counted exactly; on malformed input the
/// count may be off, which only matters for the parse error that follows anyway.
fn nesting_exceeds(text: &str, max: usize) -> Option<usize> {
    let b = text.as_bytes();
    let skip_past = |from: usize, end: &str| {
        text[from..]
            .find(end)
            .map_or(b.len(), |k| from + k + end.len())
    };
    let mut depth = 0usize;
    let mut i = 0;
    while let Some(k) = text[i..].find('<') {
        let p = i + k;
        let rest = &text[p..];
        if rest.starts_with("<!--") {
            i = skip_past(p + 4, "-->");
        } else if rest.starts_with("<![CDATA[") {
            i = skip_past(p + 9, "]]>");
        } else if rest.starts_with("<?") {
            i = skip_past(p + 2, "?>");
        } else if rest.starts_with("<!") {
            i = skip_past(p + 2, ">");
        } else if rest.starts_with("</") {
            depth = depth.saturating_sub(1);
            i = skip_past(p + 2, ">");
        } else {
            // A start tag: find its '>' outside quotes; "/>" closes it at once.
            let mut j = p + 1;
            let mut quote = None;
            let mut last = 0u8;
            while j < b.len() {
                let c = b[j];
                match quote {
                    Some(q) if c == q => quote = None,
                    Some(_) => {}
                    None if c == b'"' || c == b'\'' => quote = Some(c),
                    None if c == b'>' => break,
                    None if !c.is_ascii_whitespace() => last = c,
                    None => {}
                }
                j += 1;
            }
            if last != b'/' {
                depth += 1;
                if depth > max {
                    return Some(p);
                }
            }
            i = (j + 1).min(b.len());
        }
        if i >= b.len() {
            break;
        }
    }
    None
}

/// Reads and parses `path`; `defines` act as Mitsuba's `-D name=value`.
pub(crate) fn parse_file(path: &Path, defines: &[(String, String)]) -> Result<Doc, LoadError> {
    let bytes = crate::read_regular_file(path)
        .map_err(|e| LoadError::in_file(path, format!("cannot read scene file: {e}")))?;
    let text = match String::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => {
            let valid = e.utf8_error().valid_up_to();
            let prefix = &e.as_bytes()[..valid];
            let line = prefix.iter().filter(|&&b| b == b'\n').count() + 1;
            let col = valid
                - prefix
                    .iter()
                    .rposition(|&b| b == b'\n')
                    .map_or(0, |p| p + 1)
                + 1;
            return Err(LoadError::at(
                path,
                TextPos {
                    line: line as u32,
                    col: col as u32,
                },
                "the scene file is not valid UTF-8",
            ));
        }
    };
    parse_str(path, &text, defines)
}

/// Parses scene text as if it had been read from `path`.
pub(crate) fn parse_str(
    path: &Path,
    text: &str,
    defines: &[(String, String)],
) -> Result<Doc, LoadError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let xml = parse_xml(path, text)?;
    let mut params: Vec<Param> = Vec::new();
    for (name, value) in defines {
        if name.is_empty() || name.contains('$') {
            return Err(LoadError::in_file(
                path,
                format!("invalid parameter name \"{name}\" passed in defines"),
            ));
        }
        let key = format!("${name}");
        params.retain(|p| p.key != key);
        params.push(Param {
            key,
            value: value.clone(),
            used: false,
        });
    }
    // Longest keys first so that `$spp` never eats the start of `$spp_x` (stable sort).
    params.sort_by(|a, b| b.key.len().cmp(&a.key.len()));

    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut parser = Parser {
        file: path,
        file_index: 0,
        xml: &xml,
        params,
        nodes: Vec::new(),
        ids: HashMap::new(),
        upgrade_v1: false,
        files: vec![path.to_path_buf()],
        chain: Vec::new(),
        dir: dir.clone(),
        at_included_root: false,
    };

    let root = xml.root_element();
    let root_pos = parser.pos_of(root);
    if root.tag_name().name() != "scene" {
        return Err(parser.err(
            root_pos,
            format!(
                "the root element must be <scene>, found <{}>",
                root.tag_name().name()
            ),
        ));
    }
    parser.read_version(root)?;

    let mut counter = 0;
    parser.element(root, None, &mut counter, 0)?;

    let unused: Vec<String> = parser
        .params
        .iter()
        .filter(|p| !p.used)
        .map(|p| format!("{}={}", p.key, p.value))
        .collect();
    if !unused.is_empty() {
        // Mitsuba 3.9.1 treats an unused parameter as an error by default.
        return Err(LoadError::in_file(
            path,
            format!("unused parameters: {}", unused.join(", ")),
        ));
    }

    let Parser {
        nodes, ids, files, ..
    } = parser;
    let mut doc = Doc {
        file: path.to_path_buf(),
        dir,
        files,
        nodes,
    };
    resolve_refs(&mut doc, &ids)?;
    check_cycles(&doc)?;
    Ok(doc)
}

/// The XML tree of `text` (read from `path`), refusing absurd nesting first.
fn parse_xml<'x>(path: &Path, text: &'x str) -> Result<roxmltree::Document<'x>, LoadError> {
    // roxmltree recurses once per nesting level: refuse absurd nesting before it overflows
    // the stack.
    if let Some(offset) = nesting_exceeds(text, MAX_DEPTH) {
        let line = text[..offset].matches('\n').count() + 1;
        let col = text[..offset]
            .rsplit('\n')
            .next()
            .map_or(0, |l| l.chars().count())
            + 1;
        return Err(LoadError::at(
            path,
            TextPos {
                line: line as u32,
                col: col as u32,
            },
            format!("elements are nested more than {MAX_DEPTH} levels deep"),
        ));
    }
    roxmltree::Document::parse(text).map_err(|e| {
        let p = e.pos();
        let mut msg = e.to_string();
        // roxmltree appends " at ROW:COL"; the position is already in front.
        if let Some(i) = msg.rfind(" at ") {
            if msg[i + 4..].chars().all(|c| c.is_ascii_digit() || c == ':') {
                msg.truncate(i);
            }
        }
        LoadError::at(
            path,
            TextPos {
                line: p.row,
                col: p.col,
            },
            format!("malformed XML: {msg}"),
        )
    })
}

/// "X.Y.Z" with three numeric parts (Mitsuba's `util::Version`); returns X.
fn parse_version(s: &str) -> Option<u32> {
    let parts: Vec<&str> = s.split([' ', '.']).filter(|t| !t.is_empty()).collect();
    if parts.len() != 3 {
        return None;
    }
    let nums: Option<Vec<u32>> = parts.iter().map(|p| p.parse::<u32>().ok()).collect();
    nums.map(|n| n[0])
}

/// One `$name` substitution: from `defines` (Mitsuba's -D) or a `<default>`.
struct Param {
    /// "$name"
    key: String,
    value: String,
    used: bool,
}

/// Replaces every `$name` in `value` (longest names first, `\$` left alone), then reports the
/// first unresolved `$name` as `Err(name)`, then turns `\$` into `$`.
fn substitute(value: &str, params: &mut [Param]) -> Result<String, String> {
    let mut v = value.to_string();
    for p in params.iter_mut() {
        let mut pos = 0;
        while let Some(off) = v[pos..].find(&p.key) {
            let at = pos + off;
            if at > 0 && v.as_bytes()[at - 1] == b'\\' {
                pos = at + p.key.len();
            } else {
                v.replace_range(at..at + p.key.len(), &p.value);
                p.used = true;
                pos = at + p.value.len();
            }
        }
    }
    let bytes = v.as_bytes();
    for (i, &c) in bytes.iter().enumerate() {
        if c == b'$' && !(i > 0 && bytes[i - 1] == b'\\') {
            let name: String = v[i + 1..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            return Err(name);
        }
    }
    Ok(v.replace("\\$", "$"))
}

/// Splits a list of numbers at commas and whitespace (Mitsuba's `tokenize` with ", "; XML
/// attribute normalization has already turned tabs and newlines into spaces).
pub(crate) fn tokenize(s: &str) -> Vec<&str> {
    s.split(|c: char| c == ',' || c.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
        .collect()
}

/// Mitsuba's `string::stof`: optional spaces/tabs around, an optional leading '+', then a
/// decimal float (also "inf", "nan").
pub(crate) fn parse_float(s: &str) -> Option<f64> {
    // Rust's float syntax matches fast_float's here: one optional sign, decimal digits with an
    // optional point and exponent, or inf/infinity/nan in any case.
    s.trim_matches(|c| c == ' ' || c == '\t')
        .parse::<f64>()
        .ok()
}

/// Mitsuba's `<integer>` syntax: optional whitespace, optional '-', decimal digits, optional
/// trailing whitespace, within the range of a 64-bit integer.
fn parse_integer(s: &str) -> Option<i64> {
    let t = s.trim_matches(|c: char| c.is_ascii_whitespace());
    let digits = t.strip_prefix('-').unwrap_or(t);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    t.parse::<i64>().ok()
}

/// Mitsuba's `upgrade_from_v1` renaming: "fovAxis" → "fov_axis", "sampleCount" → "sample_count".
fn camel_to_underscore(s: &str) -> String {
    let chars: Vec<char> = s.chars().collect();
    let mut out = String::with_capacity(s.len() + 4);
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if i > 0 && chars[i - 1].is_ascii_lowercase() && c.is_ascii_uppercase() {
            out.push('_');
            out.push(c.to_ascii_lowercase());
            while i + 1 < chars.len() && chars[i + 1].is_ascii_uppercase() {
                i += 1;
                out.push(chars[i].to_ascii_lowercase());
            }
        } else {
            out.push(c);
        }
        i += 1;
    }
    out
}

/// An attribute after `$` substitution.
struct Attr<'x> {
    name: &'x str,
    value: String,
    pos: TextPos,
}

fn attr<'a>(attrs: &'a [Attr<'_>], name: &str) -> Option<&'a str> {
    attrs
        .iter()
        .find(|a| a.name == name)
        .map(|a| a.value.as_str())
}

struct Parser<'a, 'x> {
    file: &'a Path,
    /// Index of `file` in `files`.
    file_index: u32,
    xml: &'a roxmltree::Document<'x>,
    params: Vec<Param>,
    nodes: Vec<Node>,
    ids: HashMap<String, (usize, TextPos)>,
    upgrade_v1: bool,
    /// Every file read so far (the scene, then included files).
    files: Vec<PathBuf>,
    /// The `<include>`s being processed, outermost first: the canonical path of each file
    /// being included, and how messages show where it was included from.
    chain: Vec<(PathBuf, String)>,
    /// Directory of the scene file.
    dir: PathBuf,
    /// Set while the root element of an included file (not a `<scene>`) is read.
    at_included_root: bool,
}

impl<'a, 'x> Parser<'a, 'x> {
    /// The root's `version` attribute (required, as in Mitsuba's `parse_file_impl`); files
    /// older than 2.0.0 use camelCase parameter names (Mitsuba's `upgrade_from_v1`).
    fn read_version(&mut self, root: roxmltree::Node) -> Result<(), LoadError> {
        let root_pos = self.pos_of(root);
        let tag = root.tag_name().name();
        let version = root.attribute("version").ok_or_else(|| {
            self.err(
                root_pos,
                format!("missing required attribute \"version\" in the root element <{tag}>"),
            )
        })?;
        let major = parse_version(version).ok_or_else(|| {
            self.err(
                root_pos,
                format!("invalid version number \"{version}\" (expected e.g. \"3.0.0\")"),
            )
        })?;
        self.upgrade_v1 = major < 2;
        Ok(())
    }

    /// `<include filename="..."/>` (Mitsuba's parser.cpp, `TagType::Include`): the file is
    /// found relative to the including file's directory (then the scene's), parsed with the
    /// same parameters, and merged: the children of a `<scene>` root join `parent`; any other
    /// root (one object, e.g. a `<bsdf>`) becomes a child of `parent`, named by the
    /// include's `name` attribute if it has one. Mitsuba stops at 15 nested includes; radia
    /// also names the chain of files when one includes itself.
    fn include(
        &mut self,
        filename: &str,
        name: &str,
        parent: usize,
        arg_counter: &mut usize,
        epos: TextPos,
        depth: usize,
    ) -> Result<(), LoadError> {
        let here = format!("{}:{}", self.file.display(), epos.line);
        let including_dir = self
            .file
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let candidates = [including_dir.join(filename), self.dir.join(filename)];
        let Some(path) = candidates.iter().find(|p| p.is_file()).cloned() else {
            return Err(self.err(
                epos,
                format!(
                    "included file \"{filename}\" not found (looked for \"{}\")",
                    candidates[0].display()
                ),
            ));
        };
        let canonical = path.canonicalize().unwrap_or_else(|_| path.clone());
        // The files being read: the scene file, then each include of the chain.
        let top = &self.files[0];
        let top = top.canonicalize().unwrap_or_else(|_| top.clone());
        if canonical == top || self.chain.iter().any(|(c, _)| *c == canonical) {
            let mut files: Vec<String> = self.chain.iter().map(|(_, from)| from.clone()).collect();
            files.push(here);
            files.push(path.display().to_string());
            return Err(self.err(
                epos,
                format!("recursive <include>: {}", files.join(" includes ")),
            ));
        }
        if self.chain.len() + 1 >= MAX_INCLUDE_DEPTH {
            return Err(self.err(
                epos,
                format!("exceeded the maximum include depth of {MAX_INCLUDE_DEPTH}"),
            ));
        }
        let bytes = crate::read_regular_file(&path).map_err(|e| {
            self.err(
                epos,
                format!("cannot read included file \"{}\": {e}", path.display()),
            )
        })?;
        let text = String::from_utf8(bytes).map_err(|_| {
            self.err(
                epos,
                format!("included file \"{}\" is not valid UTF-8", path.display()),
            )
        })?;
        let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
        let xml = parse_xml(&path, text)?;

        let file_index = self.files.len() as u32;
        self.files.push(path.clone());
        self.chain.push((canonical, here.clone()));
        let mut sub = Parser {
            file: &path,
            file_index,
            xml: &xml,
            params: std::mem::take(&mut self.params),
            nodes: std::mem::take(&mut self.nodes),
            ids: std::mem::take(&mut self.ids),
            upgrade_v1: false,
            files: std::mem::take(&mut self.files),
            chain: std::mem::take(&mut self.chain),
            dir: self.dir.clone(),
            at_included_root: false,
        };
        let result = sub.included_root(xml.root_element(), name, parent, arg_counter, depth);
        self.params = sub.params;
        self.nodes = sub.nodes;
        self.ids = sub.ids;
        self.files = sub.files;
        self.chain = sub.chain;
        self.chain.pop();
        // Mitsuba: "while processing <include>: ..."; here each level of a nested include
        // appends where it was included from.
        result.map_err(|mut e| {
            if !e.message.starts_with("recursive <include>") {
                e.message = format!("{} (included from {here})", e.message);
            }
            e
        })
    }

    /// Merges the root of an included file into `parent` (see [`Parser::include`]).
    fn included_root(
        &mut self,
        root: roxmltree::Node<'_, 'x>,
        name: &str,
        parent: usize,
        arg_counter: &mut usize,
        depth: usize,
    ) -> Result<(), LoadError> {
        self.read_version(root)?;
        if root.tag_name().name() == "scene" {
            for child in root.children().filter(|c| c.is_element()) {
                self.element(child, Some(parent), arg_counter, depth + 1)?;
            }
            return Ok(());
        }
        let before = self.nodes[parent].props.len();
        self.at_included_root = true;
        self.element(root, Some(parent), arg_counter, depth + 1)?;
        self.at_included_root = false;
        if !name.is_empty() && self.nodes[parent].props.len() == before + 1 {
            let prop = self.nodes[parent].props.pop().expect("just added");
            self.add_prop(parent, name, prop.value, prop.pos)?;
        }
        Ok(())
    }

    fn pos_at(&self, offset: usize) -> TextPos {
        let p = self.xml.text_pos_at(offset);
        TextPos {
            line: p.row,
            col: p.col,
        }
    }

    fn pos_of(&self, n: roxmltree::Node) -> TextPos {
        self.pos_at(n.range().start)
    }

    fn err(&self, pos: TextPos, msg: impl Into<String>) -> LoadError {
        LoadError::at(self.file, pos, msg)
    }

    /// The element's attributes with `$name` substituted.
    fn attributes<'n>(
        &mut self,
        elem: roxmltree::Node<'n, 'x>,
    ) -> Result<Vec<Attr<'n>>, LoadError> {
        let tag = elem.tag_name().name();
        let epos = self.pos_of(elem);
        let mut out = Vec::new();
        for a in elem.attributes() {
            let raw = a.value();
            let value = if raw.contains('$') {
                match substitute(raw, &mut self.params) {
                    Ok(v) => v,
                    Err(name) => {
                        return Err(self.err(
                            epos,
                            format!(
                                "undefined parameter \"${name}\" in attribute {}=\"{raw}\" of <{tag}> \
                                 (declare it with <default name=\"{name}\" value=\"...\"/> or pass it as a define)",
                                a.name()
                            ),
                        ))
                    }
                }
            } else {
                raw.to_string()
            };
            let pos = self.pos_at(a.range().start);
            out.push(Attr {
                name: a.name(),
                value,
                pos,
            });
        }
        Ok(out)
    }

    /// Mitsuba's `check_attributes`: only the listed attributes may appear; those starting
    /// with '!' must.
    fn check_attributes(
        &self,
        tag: &str,
        epos: TextPos,
        attrs: &[Attr],
        spec: &[&str],
    ) -> Result<(), LoadError> {
        for a in attrs {
            if !spec.iter().any(|s| s.trim_start_matches('!') == a.name) {
                let allowed: Vec<&str> = spec.iter().map(|s| s.trim_start_matches('!')).collect();
                return Err(self.err(
                    a.pos,
                    format!(
                        "unexpected attribute \"{}\" in element <{tag}> (allowed: {})",
                        a.name,
                        allowed.join(", ")
                    ),
                ));
            }
        }
        for s in spec {
            if let Some(req) = s.strip_prefix('!') {
                if attr(attrs, req).is_none() {
                    return Err(self.err(
                        epos,
                        format!("missing required attribute \"{req}\" in element <{tag}>"),
                    ));
                }
            }
        }
        Ok(())
    }

    fn float_attr(&self, pos: TextPos, tag: &str, name: &str, v: &str) -> Result<f64, LoadError> {
        parse_float(v).ok_or_else(|| {
            self.err(pos, format!("could not parse floating point value \"{v}\" in attribute \"{name}\" of <{tag}>"))
        })
    }

    /// Adds a property to node `parent`, refusing a second property of the same name.
    fn add_prop(
        &mut self,
        parent: usize,
        name: &str,
        value: Value,
        pos: TextPos,
    ) -> Result<(), LoadError> {
        let mut name = if self.upgrade_v1 {
            camel_to_underscore(name)
        } else {
            name.to_string()
        };
        if self.upgrade_v1
            && name == "diffuse_reflectance"
            && self.nodes[parent].plugin == "diffuse"
        {
            name = "reflectance".to_string();
        }
        if let Some(prev) = self.nodes[parent].props.iter().find(|p| p.name == name) {
            return Err(self.err(
                pos,
                format!(
                    "parameter \"{name}\" of {} is specified more than once (first at line {}, col {})",
                    self.nodes[parent].describe(),
                    prev.pos.line,
                    prev.pos.col
                ),
            ));
        }
        self.nodes[parent].props.push(Prop { name, value, pos });
        Ok(())
    }

    fn element(
        &mut self,
        elem: roxmltree::Node<'_, 'x>,
        parent: Option<usize>,
        arg_counter: &mut usize,
        depth: usize,
    ) -> Result<(), LoadError> {
        let epos = self.pos_of(elem);
        if depth > MAX_DEPTH {
            return Err(self.err(
                epos,
                format!("elements are nested more than {MAX_DEPTH} levels deep"),
            ));
        }
        let attrs = self.attributes(elem)?;
        let tag = elem.tag_name().name();

        let kind = match tag {
            "scene" => Some(Kind::Scene),
            "integrator" => Some(Kind::Integrator),
            "sensor" => Some(Kind::Sensor),
            "film" => Some(Kind::Film),
            "sampler" => Some(Kind::Sampler),
            "rfilter" => Some(Kind::RFilter),
            "shape" => Some(Kind::Shape),
            "bsdf" => Some(Kind::Bsdf),
            "emitter" => Some(Kind::Emitter),
            "texture" => Some(Kind::Texture),
            _ => None,
        };
        if let Some(kind) = kind {
            return self.object(elem, kind, parent, attrs, arg_counter, epos, depth);
        }

        // Everything else is a property or a directive and needs a parent object.
        let parent_idx = match parent {
            Some(p) => p,
            None => {
                return Err(self.err(
                    epos,
                    format!("the root element must be <scene>, found <{tag}>"),
                ))
            }
        };
        if tag != "transform" {
            if let Some(child) = elem.children().find(|c| c.is_element()) {
                return Err(self.err(
                    self.pos_of(child),
                    format!(
                        "<{}> element cannot occur as a child of <{tag}>",
                        child.tag_name().name()
                    ),
                ));
            }
        }
        let name = attr(&attrs, "name").unwrap_or("").to_string();

        match tag {
            "float" => {
                self.check_attributes(tag, epos, &attrs, &["!name", "!value"])?;
                let v = attr(&attrs, "value").unwrap_or("");
                let x = parse_float(v).ok_or_else(|| {
                    self.err(epos, format!("could not parse floating point value \"{v}\" of <float name=\"{name}\">"))
                })?;
                self.add_prop(parent_idx, &name, Value::Float(x), epos)
            }
            "integer" => {
                self.check_attributes(tag, epos, &attrs, &["!name", "!value"])?;
                let v = attr(&attrs, "value").unwrap_or("");
                let x = parse_integer(v).ok_or_else(|| {
                    self.err(
                        epos,
                        format!(
                            "could not parse integer value \"{v}\" of <integer name=\"{name}\">"
                        ),
                    )
                })?;
                self.add_prop(parent_idx, &name, Value::Integer(x), epos)
            }
            "boolean" => {
                self.check_attributes(tag, epos, &attrs, &["!name", "!value"])?;
                let v = attr(&attrs, "value").unwrap_or("");
                let b = if v.eq_ignore_ascii_case("true") {
                    true
                } else if v.eq_ignore_ascii_case("false") {
                    false
                } else {
                    return Err(self.err(
                        epos,
                        format!("could not parse boolean value \"{v}\" of <boolean name=\"{name}\"> -- must be \"true\" or \"false\""),
                    ));
                };
                self.add_prop(parent_idx, &name, Value::Boolean(b), epos)
            }
            "string" => {
                self.check_attributes(tag, epos, &attrs, &["!name", "!value"])?;
                let v = attr(&attrs, "value").unwrap_or("").to_string();
                self.add_prop(parent_idx, &name, Value::String(v), epos)
            }
            "rgb" => {
                self.check_attributes(tag, epos, &attrs, &["!name", "!value"])?;
                let v = attr(&attrs, "value").unwrap_or("");
                let toks = tokenize(v);
                let nums: Option<Vec<f64>> = toks.iter().map(|t| parse_float(t)).collect();
                let c = match (toks.len(), nums) {
                    (1, Some(n)) => DVec3::splat(n[0]),
                    (3, Some(n)) => DVec3::new(n[0], n[1], n[2]),
                    (1 | 3, None) => {
                        return Err(self.err(
                            epos,
                            format!("could not parse RGB value \"{v}\" of <rgb name=\"{name}\">"),
                        ))
                    }
                    (k, _) => {
                        return Err(self.err(
                            epos,
                            format!(
                            "<rgb name=\"{name}\"> requires one or three values (got {k}: \"{v}\")"
                        ),
                        ))
                    }
                };
                self.add_prop(parent_idx, &name, Value::Rgb(c), epos)
            }
            "point" | "vector" => {
                self.check_attributes(tag, epos, &attrs, &["!name", "value", "x", "y", "z"])?;
                let v = self.xyz(tag, epos, &attrs, None)?;
                self.add_prop(parent_idx, &name, Value::Vector(v), epos)
            }
            "transform" => {
                self.check_attributes(tag, epos, &attrs, &["!name"])?;
                let m = self.transform(elem)?;
                self.add_prop(parent_idx, &name, Value::Transform(m), epos)
            }
            "ref" => {
                self.check_attributes(tag, epos, &attrs, &["!id", "name"])?;
                let id = attr(&attrs, "id").unwrap_or("").to_string();
                let pname = if name.is_empty() {
                    let n = format!("_arg_{arg_counter}");
                    *arg_counter += 1;
                    n
                } else {
                    name
                };
                self.add_prop(parent_idx, &pname, Value::Ref(id), epos)
            }
            "default" => {
                self.check_attributes(tag, epos, &attrs, &["!name", "!value"])?;
                if name.is_empty() {
                    return Err(self.err(epos, "<default>: the name must not be empty"));
                }
                let key = format!("${name}");
                if !self.params.iter().any(|p| p.key == key) {
                    let value = attr(&attrs, "value").unwrap_or("").to_string();
                    let at = self
                        .params
                        .iter()
                        .position(|p| key.len() > p.key.len())
                        .unwrap_or(self.params.len());
                    self.params.insert(
                        at,
                        Param {
                            key,
                            value,
                            used: true,
                        },
                    );
                }
                Ok(())
            }
            "alias" => {
                self.check_attributes(tag, epos, &attrs, &["!id", "!as"])?;
                let src = attr(&attrs, "id").unwrap_or("");
                let dst = attr(&attrs, "as").unwrap_or("");
                if self.ids.contains_key(dst) {
                    return Err(self.err(
                        epos,
                        format!("alias destination id \"{dst}\" already exists"),
                    ));
                }
                let target = match self.ids.get(src) {
                    Some(&(t, _)) => t,
                    None => {
                        return Err(self.err(epos, format!("alias source id \"{src}\" not found")))
                    }
                };
                self.ids.insert(dst.to_string(), (target, epos));
                Ok(())
            }
            "translate" | "rotate" | "scale" | "lookat" | "matrix" => Err(self.err(
                epos,
                format!("transform operation <{tag}> can only appear inside a <transform> element"),
            )),
            "medium" | "phase" | "volume" => {
                Err(self.err(epos, format!("<{tag}> objects are not supported by radia")))
            }
            // Mitsuba's parser (`src/core/parser.cpp`, `Properties::Spectrum` in
            // `src/core/properties.cpp`): `value` is one number (a uniform spectrum) or
            // wavelength:value pairs, or `filename` names a spectrum file; a `type` makes it
            // a spectrum plugin. radia renders in RGB and takes the uniform one.
            "spectrum" => {
                if let Some(t) = attr(&attrs, "type") {
                    return Err(self.err(
                        epos,
                        format!(
                            "spectrum plugin type \"{t}\" is not supported by radia (use <rgb>)"
                        ),
                    ));
                }
                self.check_attributes(tag, epos, &attrs, &["!name", "value", "filename"])?;
                let v = match (attr(&attrs, "value"), attr(&attrs, "filename")) {
                    (Some(v), None) => v,
                    (None, Some(f)) => {
                        return Err(self.err(
                            epos,
                            format!("<spectrum name=\"{name}\" filename=\"{f}\">: spectra from files are not supported by radia (use <rgb>)"),
                        ))
                    }
                    _ => {
                        return Err(self.err(
                            epos,
                            "<spectrum> element requires either \"value\" or \"filename\" attribute (but not both)",
                        ))
                    }
                };
                let toks = tokenize(v);
                if toks.len() == 1 && !v.contains(':') {
                    let x = parse_float(toks[0]).ok_or_else(|| {
                        self.err(epos, format!("could not parse uniform spectrum value \"{v}\" of <spectrum name=\"{name}\">"))
                    })?;
                    self.add_prop(parent_idx, &name, Value::UniformSpectrum(x), epos)
                } else {
                    Err(self.err(
                        epos,
                        format!("<spectrum name=\"{name}\" value=\"{v}\">: wavelength:value spectra are not supported by radia, which renders in RGB (use <rgb>, or one value for a uniform spectrum)"),
                    ))
                }
            }
            "include" => {
                self.check_attributes(tag, epos, &attrs, &["!filename", "name"])?;
                let filename = attr(&attrs, "filename").unwrap_or("");
                self.include(filename, &name, parent_idx, arg_counter, epos, depth)
            }
            "path" => Err(self.err(epos, format!("<{tag}> is not supported by radia"))),
            _ => Err(self.err(epos, format!("unsupported XML element <{tag}>"))),
        }
    }

    /// x/y/z attributes, or `value` with one (replicated) or three numbers. With `default`,
    /// missing components take it; without, all three are required.
    fn xyz(
        &self,
        tag: &str,
        epos: TextPos,
        attrs: &[Attr],
        default: Option<f64>,
    ) -> Result<DVec3, LoadError> {
        let has_xyz = ["x", "y", "z"].iter().any(|n| attr(attrs, n).is_some());
        if let Some(v) = attr(attrs, "value") {
            if has_xyz {
                return Err(self.err(
                    epos,
                    format!("<{tag}>: cannot mix the \"value\" and \"x\"/\"y\"/\"z\" attributes"),
                ));
            }
            let toks = tokenize(v);
            let nums: Vec<f64> = toks
                .iter()
                .map(|t| self.float_attr(epos, tag, "value", t))
                .collect::<Result<_, _>>()?;
            return match nums.len() {
                1 => Ok(DVec3::splat(nums[0])),
                3 => Ok(DVec3::new(nums[0], nums[1], nums[2])),
                k => Err(self.err(
                    epos,
                    format!("<{tag}>: the \"value\" attribute must have exactly 1 or 3 elements (got {k}: \"{v}\")"),
                )),
            };
        }
        let mut out = [0.0; 3];
        for (i, n) in ["x", "y", "z"].iter().enumerate() {
            out[i] = match (attr(attrs, n), default) {
                (Some(v), _) => self.float_attr(epos, tag, n, v)?,
                (None, Some(d)) => d,
                (None, None) => {
                    return Err(self.err(
                        epos,
                        format!("missing required attribute \"{n}\" in element <{tag}>"),
                    ))
                }
            };
        }
        Ok(DVec3::from_array(out))
    }

    /// Three numbers in one attribute (lookat's origin/target/up).
    fn vec3_attr(&self, epos: TextPos, tag: &str, name: &str, v: &str) -> Result<DVec3, LoadError> {
        let toks = tokenize(v);
        if toks.len() != 3 {
            return Err(self.err(
                epos,
                format!(
                    "attribute \"{name}\" of <{tag}> must have 3 values, got {}: \"{v}\"",
                    toks.len()
                ),
            ));
        }
        let mut out = [0.0; 3];
        for (i, t) in toks.iter().enumerate() {
            out[i] = self.float_attr(epos, tag, name, t)?;
        }
        Ok(DVec3::from_array(out))
    }

    /// The operations of a `<transform>` in document order: M = T_last ⋯ T_first.
    fn transform(&mut self, elem: roxmltree::Node<'_, 'x>) -> Result<DMat4, LoadError> {
        let mut m = DMat4::IDENTITY;
        for child in elem.children().filter(|c| c.is_element()) {
            let attrs = self.attributes(child)?;
            let tag = child.tag_name().name();
            let epos = self.pos_of(child);
            if let Some(gc) = child.children().find(|c| c.is_element()) {
                return Err(self.err(
                    self.pos_of(gc),
                    format!(
                        "<{}> element cannot occur as a child of <{tag}>",
                        gc.tag_name().name()
                    ),
                ));
            }
            let op = match tag {
                "translate" => {
                    self.check_attributes(tag, epos, &attrs, &["value", "x", "y", "z"])?;
                    transform::translate(self.xyz(tag, epos, &attrs, Some(0.0))?)
                }
                "scale" => {
                    self.check_attributes(tag, epos, &attrs, &["value", "x", "y", "z"])?;
                    transform::scale(self.xyz(tag, epos, &attrs, Some(1.0))?)
                }
                "rotate" => {
                    self.check_attributes(tag, epos, &attrs, &["!angle", "value", "x", "y", "z"])?;
                    let axis = self.xyz(tag, epos, &attrs, Some(0.0))?;
                    if axis == DVec3::ZERO {
                        return Err(self.err(epos, "<rotate>: the rotation axis cannot be zero"));
                    }
                    let a = attr(&attrs, "angle").unwrap_or("");
                    let angle = parse_float(a).ok_or_else(|| {
                        self.err(
                            epos,
                            format!("<rotate>: could not parse angle value \"{a}\""),
                        )
                    })?;
                    transform::rotate(axis, angle)
                }
                "lookat" => {
                    self.check_attributes(tag, epos, &attrs, &["!origin", "!target", "up"])?;
                    let origin =
                        self.vec3_attr(epos, tag, "origin", attr(&attrs, "origin").unwrap_or(""))?;
                    let target =
                        self.vec3_attr(epos, tag, "target", attr(&attrs, "target").unwrap_or(""))?;
                    let up = match attr(&attrs, "up") {
                        Some(u) if !u.is_empty() => self.vec3_attr(epos, tag, "up", u)?,
                        _ => DVec3::ZERO,
                    };
                    transform::look_at(origin, target, up).ok_or_else(|| {
                        self.err(
                            epos,
                            "invalid <lookat> transformation (target equals origin, or up is parallel to the view direction)",
                        )
                    })?
                }
                "matrix" => {
                    self.check_attributes(tag, epos, &attrs, &["!value"])?;
                    let v = attr(&attrs, "value").unwrap_or("");
                    let toks = tokenize(v);
                    let n = match toks.len() {
                        16 => 4,
                        9 => 3,
                        k => {
                            return Err(self
                                .err(epos, format!("<matrix> must have 9 or 16 values, got {k}")))
                        }
                    };
                    let mut rows = [
                        [0.0, 0.0, 0.0, 0.0],
                        [0.0, 0.0, 0.0, 0.0],
                        [0.0, 0.0, 0.0, 0.0],
                        [0.0, 0.0, 0.0, 1.0],
                    ];
                    rows[0][0] = 1.0;
                    rows[1][1] = 1.0;
                    rows[2][2] = 1.0;
                    for i in 0..n {
                        for j in 0..n {
                            let t = toks[i * n + j];
                            rows[i][j] = parse_float(t).ok_or_else(|| {
                                self.err(
                                    epos,
                                    format!("<matrix>: could not parse matrix value \"{t}\""),
                                )
                            })?;
                        }
                    }
                    let mm = transform::from_rows(rows);
                    if !transform::is_affine(&mm) {
                        return Err(self.err(
                            epos,
                            "<matrix>: the last row must be \"0 0 0 1\" (projective transforms are not supported)",
                        ));
                    }
                    mm
                }
                _ => {
                    return Err(self.err(
                        epos,
                        format!("unexpected <{tag}> element inside <transform>"),
                    ))
                }
            };
            m = op * m;
        }
        if !m.is_finite() {
            return Err(self.err(self.pos_of(elem), "the transform is not finite"));
        }
        Ok(m)
    }

    #[allow(clippy::too_many_arguments)]
    fn object(
        &mut self,
        elem: roxmltree::Node<'_, 'x>,
        kind: Kind,
        parent: Option<usize>,
        attrs: Vec<Attr>,
        arg_counter: &mut usize,
        epos: TextPos,
        depth: usize,
    ) -> Result<(), LoadError> {
        let tag = kind.tag();
        let plugin = match (parent, kind) {
            (None, Kind::Scene) => {
                self.check_attributes(tag, epos, &attrs, &["!version", "type", "id", "name"])?;
                if let Some(t) = attr(&attrs, "type") {
                    if t != "scene" {
                        return Err(self.err(epos, format!("unsupported scene type \"{t}\"")));
                    }
                }
                "scene".to_string()
            }
            (None, _) => {
                return Err(self.err(
                    epos,
                    format!("the root element must be <scene>, found <{tag}>"),
                ))
            }
            (Some(_), Kind::Scene) => {
                return Err(self.err(epos, "nested <scene> elements are not supported"))
            }
            (Some(_), _) => {
                // The root of an included file carries the file's `version` (parser.cpp's
                // `is_root`).
                let spec: &[&str] = if std::mem::take(&mut self.at_included_root) {
                    &["!version", "!type", "id", "name"]
                } else {
                    &["!type", "id", "name"]
                };
                self.check_attributes(tag, epos, &attrs, spec)?;
                attr(&attrs, "type").unwrap_or("").to_string()
            }
        };
        let id = attr(&attrs, "id")
            .filter(|s| !s.is_empty())
            .map(str::to_string);
        let idx = self.nodes.len();
        if let Some(id) = &id {
            if let Some(&(_, prev)) = self.ids.get(id) {
                return Err(self.err(
                    epos,
                    format!(
                        "duplicate id \"{id}\" (previously declared at line {}, col {})",
                        prev.line, prev.col
                    ),
                ));
            }
            self.ids.insert(id.clone(), (idx, epos));
        }
        let node = Node {
            kind,
            plugin,
            id,
            file: self.file_index,
            pos: epos,
            props: Vec::new(),
        };
        let name = match attr(&attrs, "name") {
            Some(n) if !n.is_empty() => n.to_string(),
            _ => {
                let n = format!("_arg_{arg_counter}");
                *arg_counter += 1;
                n
            }
        };
        self.nodes.push(node);
        if let Some(p) = parent {
            self.add_prop(p, &name, Value::Object(idx), epos)?;
        }
        let mut counter = 0;
        for child in elem.children().filter(|c| c.is_element()) {
            self.element(child, Some(idx), &mut counter, depth + 1)?;
        }
        Ok(())
    }
}

/// Replaces every `Value::Ref` by the object it names.
fn resolve_refs(doc: &mut Doc, ids: &HashMap<String, (usize, TextPos)>) -> Result<(), LoadError> {
    for node in &mut doc.nodes {
        let file = &doc.files[node.file as usize];
        for prop in &mut node.props {
            if let Value::Ref(id) = &prop.value {
                match ids.get(id) {
                    Some(&(target, _)) => prop.value = Value::Object(target),
                    None => {
                        return Err(LoadError::at(
                            file,
                            prop.pos,
                            format!(
                            "unresolved reference to \"{id}\": no object with id=\"{id}\" exists"
                        ),
                        ))
                    }
                }
            }
        }
    }
    Ok(())
}

/// Objects must form a tree-like DAG: a reference back to an enclosing object is an error.
fn check_cycles(doc: &Doc) -> Result<(), LoadError> {
    // 0 = unvisited, 1 = on the current path, 2 = finished.
    let mut state = vec![0u8; doc.nodes.len()];
    for start in 0..doc.nodes.len() {
        if state[start] != 0 {
            continue;
        }
        // Explicit stack of (node, index of the next property to visit).
        let mut stack: Vec<(usize, usize)> = vec![(start, 0)];
        state[start] = 1;
        while let Some(top) = stack.last_mut() {
            let (n, i) = *top;
            let props = &doc.nodes[n].props;
            if i >= props.len() {
                state[n] = 2;
                stack.pop();
                continue;
            }
            top.1 += 1;
            let prop = &props[i];
            if let Value::Object(child) = prop.value {
                match state[child] {
                    0 => {
                        state[child] = 1;
                        stack.push((child, 0));
                    }
                    1 => {
                        let name = |k: usize| {
                            doc.nodes[k]
                                .id
                                .clone()
                                .unwrap_or_else(|| doc.nodes[k].describe())
                        };
                        return Err(LoadError::at(
                            doc.file_of(&doc.nodes[n]),
                            prop.pos,
                            format!(
                                "circular reference: {} refers (directly or through nested objects) to its enclosing {}",
                                name(n),
                                name(child)
                            ),
                        ));
                    }
                    _ => {}
                }
            }
        }
    }
    Ok(())
}
