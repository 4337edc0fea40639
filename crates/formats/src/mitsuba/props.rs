//! Typed access to one node's properties, remembering which ones a plugin read: like
//! Mitsuba's `Properties` with its "unreferenced property" check, every property the plugin
//! did not ask for is an error in [`Props::finish`].

use super::xml::{Doc, Kind, Node, Value};
use crate::error::{LoadError, TextPos};
use glam::{DMat4, DVec3};

/// Mitsuba's `xyz_to_srgb` applied to XYZ = (1, 1, 1): the rows of its matrix summed.
const EQUAL_ENERGY_SRGB: DVec3 = DVec3::new(
    3.240479 - 1.537150 - 0.498535,
    -0.969256 + 1.875991 + 0.041556,
    0.055648 - 0.204043 + 1.057311,
);

pub(crate) struct Props<'a> {
    pub doc: &'a Doc,
    pub node: &'a Node,
    used: Vec<bool>,
}

impl<'a> Props<'a> {
    pub fn new(doc: &'a Doc, idx: usize) -> Self {
        let node = &doc.nodes[idx];
        Self {
            doc,
            node,
            used: vec![false; node.props.len()],
        }
    }

    /// An error at the node's element.
    pub fn err(&self, msg: impl Into<String>) -> LoadError {
        LoadError::at(self.doc.file_of(self.node), self.node.pos, msg)
    }

    pub fn err_at(&self, pos: TextPos, msg: impl Into<String>) -> LoadError {
        LoadError::at(self.doc.file_of(self.node), pos, msg)
    }

    fn find(&self, name: &str) -> Option<usize> {
        self.node
            .props
            .iter()
            .position(|p| p.name == name && !matches!(p.value, Value::Object(_)))
    }

    /// Where the property `name` was declared, else the node's position.
    pub fn pos_of(&self, name: &str) -> TextPos {
        self.find(name)
            .map_or(self.node.pos, |i| self.node.props[i].pos)
    }

    /// For plugins with alternative parameter sets (e.g. a conductor's `material` or `eta`/`k`).
    #[allow(dead_code)]
    pub fn has(&self, name: &str) -> bool {
        self.find(name).is_some()
    }

    fn wrong_type(&self, i: usize, expected: &str) -> LoadError {
        let p = &self.node.props[i];
        self.err_at(
            p.pos,
            format!(
                "parameter \"{}\" of {} has the wrong type: expected {expected}, found <{}>",
                p.name,
                self.node.describe(),
                p.value.type_name()
            ),
        )
    }

    fn get(&mut self, name: &str) -> Option<(usize, &'a Value)> {
        let i = self.find(name)?;
        self.used[i] = true;
        Some((i, &self.node.props[i].value))
    }

    /// A `<float>` (an `<integer>` is converted, as Mitsuba does).
    pub fn float_opt(&mut self, name: &str) -> Result<Option<f64>, LoadError> {
        match self.get(name) {
            None => Ok(None),
            Some((_, Value::Float(x))) => Ok(Some(*x)),
            Some((_, Value::Integer(k))) => Ok(Some(*k as f64)),
            Some((i, _)) => Err(self.wrong_type(i, "<float>")),
        }
    }

    pub fn float(&mut self, name: &str, default: f64) -> Result<f64, LoadError> {
        Ok(self.float_opt(name)?.unwrap_or(default))
    }

    /// An `<integer>` within [min, max] (Mitsuba's range check of `get<int>`/`get<uint32_t>`).
    pub fn int(&mut self, name: &str, default: i64, min: i64, max: i64) -> Result<i64, LoadError> {
        match self.get(name) {
            None => Ok(default),
            Some((i, Value::Integer(k))) => {
                if *k < min || *k > max {
                    Err(self.err_at(
                        self.node.props[i].pos,
                        format!("parameter \"{name}\": value {k} is out of bounds, must be in the range [{min}, {max}]"),
                    ))
                } else {
                    Ok(*k)
                }
            }
            Some((i, _)) => Err(self.wrong_type(i, "<integer>")),
        }
    }

    pub fn boolean(&mut self, name: &str, default: bool) -> Result<bool, LoadError> {
        match self.get(name) {
            None => Ok(default),
            Some((_, Value::Boolean(b))) => Ok(*b),
            Some((i, _)) => Err(self.wrong_type(i, "<boolean>")),
        }
    }

    pub fn string_opt(&mut self, name: &str) -> Result<Option<&'a str>, LoadError> {
        match self.get(name) {
            None => Ok(None),
            Some((_, Value::String(s))) => Ok(Some(s.as_str())),
            Some((i, _)) => Err(self.wrong_type(i, "<string>")),
        }
    }

    /// A `<point>` or `<vector>`.
    pub fn point(&mut self, name: &str, default: DVec3) -> Result<DVec3, LoadError> {
        match self.get(name) {
            None => Ok(default),
            Some((_, Value::Vector(v))) => Ok(*v),
            Some((i, _)) => Err(self.wrong_type(i, "<point>")),
        }
    }

    pub fn transform(&mut self, name: &str) -> Result<DMat4, LoadError> {
        match self.get(name) {
            None => Ok(DMat4::IDENTITY),
            Some((_, Value::Transform(m))) => Ok(*m),
            Some((i, _)) => Err(self.wrong_type(i, "<transform>")),
        }
    }

    /// A constant texture given as `<float>`/`<integer>` (grey), `<rgb>` or a uniform
    /// `<spectrum>`, as Mitsuba's `get_texture`. With `bounded` (reflectances), RGB
    /// components must lie in [0, 1] as in Mitsuba's `srgb` spectrum; a float or uniform
    /// spectrum is not range-checked (Mitsuba's `uniform`).
    pub fn color(&mut self, name: &str, default: f64, bounded: bool) -> Result<DVec3, LoadError> {
        self.color_of(name, default, bounded, false)
    }

    /// [`Props::color`] of an emitter's radiance, intensity or irradiance (Mitsuba's
    /// `get_emissive_texture`). The same, except that a uniform spectrum of value v is the
    /// colour v · M (1, 1, 1), M Mitsuba's XYZ-to-sRGB matrix (`xyz_to_srgb`,
    /// `include/mitsuba/core/spectrum.h`): equal energy at every wavelength is not white
    /// in sRGB, whose white is D65, and Mitsuba's RGB variants give it that colour so that
    /// they match its spectral ones (`Properties::get_texture_impl`,
    /// `src/core/properties.cpp`).
    pub fn emitted_color(&mut self, name: &str, default: f64) -> Result<DVec3, LoadError> {
        self.color_of(name, default, false, true)
    }

    fn color_of(
        &mut self,
        name: &str,
        default: f64,
        bounded: bool,
        emitted: bool,
    ) -> Result<DVec3, LoadError> {
        let (i, c) = match self.get(name) {
            None => return Ok(DVec3::splat(default)),
            Some((i, Value::Float(x))) => (i, DVec3::splat(*x)),
            Some((i, Value::UniformSpectrum(x))) if emitted => (i, *x * EQUAL_ENERGY_SRGB),
            Some((i, Value::UniformSpectrum(x))) => (i, DVec3::splat(*x)),
            Some((i, Value::Integer(k))) => (i, DVec3::splat(*k as f64)),
            Some((i, Value::Rgb(c))) => {
                if bounded && (c.min_element() < 0.0 || c.max_element() > 1.0) {
                    return Err(self.err_at(
                        self.node.props[i].pos,
                        format!(
                            "invalid RGB reflectance value ({}, {}, {}) for \"{name}\", must be in the range [0, 1]",
                            c.x, c.y, c.z
                        ),
                    ));
                }
                (i, *c)
            }
            Some((i, Value::Object(_))) | Some((i, _)) => {
                return Err(self.wrong_type(i, "<rgb>, <float> or <texture>"))
            }
        };
        if !c.is_finite() {
            return Err(self.err_at(
                self.node.props[i].pos,
                format!("parameter \"{name}\" must be finite"),
            ));
        }
        // Negative radiance, intensity or index of refraction has no physical meaning
        // (Mitsuba's unbounded spectra accept it; radia refuses it as a typo).
        if c.min_element() < 0.0 {
            return Err(self.err_at(
                self.node.props[i].pos,
                format!(
                    "parameter \"{name}\" must not be negative, got ({}, {}, {})",
                    c.x, c.y, c.z
                ),
            ));
        }
        Ok(c)
    }

    /// The nested or referenced objects not yet taken: (property index, node index, kind).
    pub fn objects(&self) -> Vec<(usize, usize, Kind)> {
        self.node
            .props
            .iter()
            .enumerate()
            .filter(|(i, _)| !self.used[*i])
            .filter_map(|(i, p)| match p.value {
                Value::Object(n) => Some((i, n, self.doc.nodes[n].kind)),
                _ => None,
            })
            .collect()
    }

    /// The not yet consumed object property called `name` (a nested `<texture name=...>` or
    /// a `<ref name=... id=...>`): (property index, node index).
    pub fn object_named(&self, name: &str) -> Option<(usize, usize)> {
        self.node
            .props
            .iter()
            .enumerate()
            .find(|(i, p)| !self.used[*i] && p.name == name && matches!(p.value, Value::Object(_)))
            .map(|(i, p)| match p.value {
                Value::Object(n) => (i, n),
                _ => unreachable!("filtered on Object"),
            })
    }

    /// True when `name` is given, as a value or as an object.
    pub fn has_any(&self, name: &str) -> bool {
        self.node.props.iter().any(|p| p.name == name)
    }

    /// Marks the object property `i` as consumed.
    pub fn take(&mut self, i: usize) {
        self.used[i] = true;
    }

    pub fn prop_pos(&self, i: usize) -> TextPos {
        self.node.props[i].pos
    }

    /// Every property must have been read: a misspelt or unsupported parameter, or a nested
    /// object the plugin does not take, is an error at its declaration.
    pub fn finish(self) -> Result<(), LoadError> {
        if let Some(i) = self.used.iter().position(|u| !u) {
            let p = &self.node.props[i];
            let others: Vec<&str> = self
                .used
                .iter()
                .enumerate()
                .skip(i + 1)
                .filter(|(_, u)| !**u)
                .map(|(k, _)| self.node.props[k].name.as_str())
                .collect();
            let also = if others.is_empty() {
                String::new()
            } else {
                format!(" (also unused: {})", others.join(", "))
            };
            let msg = match p.value {
                Value::Object(n) => format!(
                    "unexpected nested {} in {}{also}",
                    self.doc.nodes[n].describe(),
                    self.node.describe()
                ),
                _ => format!(
                    "unexpected parameter \"{}\" (<{}>) in {}: misspelt, or not supported by radia{also}",
                    p.name,
                    p.value.type_name(),
                    self.node.describe()
                ),
            };
            return Err(self.err_at(p.pos, msg));
        }
        Ok(())
    }
}
