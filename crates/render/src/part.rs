//! Pieces of a render split by sample index, and their exact merge.
//!
//! A [`Part`] is the undeveloped film of some sample ranges of a render: per pixel the sums
//! (Σ w·r, Σ w·g, Σ w·b, Σ w) over its samples, with what identifies the render it belongs to
//! (the scene's fingerprint, the seed, the sampler, its sample count, the light sampler). The
//! film of the whole render is the sum of its parts' sums, so merging the parts and developing
//! gives the image of one render of all the samples up to the rounding of the float sums
//! (pieces whose range ends are multiples of [`crate::PASS_SPP`] group their samples exactly
//! as one render does, so only the few additions of the merge itself round differently).
//!
//! Parts are added in ascending order of their first sample index whatever the order they
//! are given or arrive in ([`Merger`]), so a merge gives the same bits every time.
//!
//! # On disk
//! A partial EXR is a float32 OpenEXR with the channels `sum.R`, `sum.G`, `sum.B` and
//! `weight`, and the header attributes `radia.part` (the format version), `radia.scene` (the
//! fingerprint, 16 hex digits), `radia.seed`, `radia.samples` (ranges `A..B` separated by
//! commas, B excluded), `radia.spp`, `radia.sampler` and `radia.lightSampler`.

use crate::film::{develop_pixel, Image};
use crate::renderer::SampleRange;
use std::path::{Path, PathBuf};

/// What identifies the render a part belongs to: parts merge only when all of it agrees.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderIdentity {
    /// [`radia_scene::SceneDescription::fingerprint`] of the scene as rendered (after any
    /// override of the film).
    pub scene: u64,
    pub seed: u64,
    /// The sampler's name (`SamplerKind::name`).
    pub sampler: String,
    /// The sample count the sampler is stratified over (the whole render's spp).
    pub spp: u32,
    /// The light sampler's name (`LightSamplerKind`'s `Display`).
    pub light_sampler: String,
    pub width: u32,
    pub height: u32,
}

/// The accumulated film of some sample ranges of a render.
#[derive(Clone, Debug)]
pub struct Part {
    pub identity: RenderIdentity,
    /// Disjoint, sorted, adjacent ranges coalesced.
    pub samples: Vec<SampleRange>,
    /// (Σ w·r, Σ w·g, Σ w·b, Σ w) per pixel, row-major.
    pub sums: Vec<[f32; 4]>,
}

#[derive(Debug, thiserror::Error)]
pub enum PartError {
    #[error("{path}: {message}")]
    Io { path: PathBuf, message: String },
    #[error("{path}: not a partial render of radia ({message}); make one with `radia render --samples A..B`")]
    NotAPart { path: PathBuf, message: String },
    #[error("cannot merge {b} with {a}: {what} differ ({va} in {a}, {vb} in {b})")]
    Mismatch {
        a: String,
        b: String,
        what: &'static str,
        va: String,
        vb: String,
    },
    #[error("cannot merge {b} with {a}: both render samples {overlap} (parts must not overlap, or those samples would count twice)")]
    Overlap {
        a: String,
        b: String,
        overlap: SampleRange,
    },
    #[error("nothing to merge")]
    Empty,
}

impl Part {
    /// The part of sample range `samples` whose film accumulated `sums`.
    pub fn new(identity: RenderIdentity, samples: SampleRange, sums: Vec<[f32; 4]>) -> Self {
        assert_eq!(
            sums.len(),
            identity.width as usize * identity.height as usize
        );
        Self {
            identity,
            samples: vec![samples],
            sums,
        }
    }

    /// Samples per pixel in this part.
    pub fn sample_count(&self) -> u32 {
        self.samples.iter().map(SampleRange::len).sum()
    }

    /// The ranges of [0, spp) that no part covers.
    pub fn gaps(&self) -> Vec<SampleRange> {
        let mut gaps = Vec::new();
        let mut at = 0;
        for r in &self.samples {
            if r.start > at {
                gaps.push(SampleRange::new(at, r.start));
            }
            at = r.end;
        }
        if at < self.identity.spp {
            gaps.push(SampleRange::new(at, self.identity.spp));
        }
        gaps
    }

    /// The developed image (Σ w·L / Σ w per pixel), as [`crate::Film::develop`].
    pub fn develop(&self) -> Image {
        Image {
            width: self.identity.width,
            height: self.identity.height,
            pixels: self.sums.iter().map(|&p| develop_pixel(p)).collect(),
        }
    }

    /// Adds `other`'s sums to this part's, after checking that both belong to the same render
    /// and share no sample. `a` and `b` name the two parts in the error.
    pub fn add(&mut self, other: &Part, a: &str, b: &str) -> Result<(), PartError> {
        self.check_compatible(other, a, b)?;
        for (d, s) in self.sums.iter_mut().zip(&other.sums) {
            for (d, s) in d.iter_mut().zip(s) {
                *d += s;
            }
        }
        self.samples.extend_from_slice(&other.samples);
        self.samples = coalesce(std::mem::take(&mut self.samples));
        Ok(())
    }

    /// Whether `other` may be added to this part: the same render, no shared sample.
    pub fn check_compatible(&self, other: &Part, a: &str, b: &str) -> Result<(), PartError> {
        let (x, y) = (&self.identity, &other.identity);
        let mismatch = |what, va: String, vb: String| PartError::Mismatch {
            a: a.to_string(),
            b: b.to_string(),
            what,
            va,
            vb,
        };
        if x.scene != y.scene {
            return Err(mismatch(
                "scenes",
                format!("{:016x}", x.scene),
                format!("{:016x}", y.scene),
            ));
        }
        if (x.width, x.height) != (y.width, y.height) {
            return Err(mismatch(
                "resolutions",
                format!("{}x{}", x.width, x.height),
                format!("{}x{}", y.width, y.height),
            ));
        }
        if x.seed != y.seed {
            return Err(mismatch("seeds", x.seed.to_string(), y.seed.to_string()));
        }
        if x.sampler != y.sampler {
            return Err(mismatch("samplers", x.sampler.clone(), y.sampler.clone()));
        }
        if x.spp != y.spp {
            return Err(mismatch(
                "sample counts (spp)",
                x.spp.to_string(),
                y.spp.to_string(),
            ));
        }
        if x.light_sampler != y.light_sampler {
            return Err(mismatch(
                "light samplers",
                x.light_sampler.clone(),
                y.light_sampler.clone(),
            ));
        }
        for r in &self.samples {
            for s in &other.samples {
                let overlap = SampleRange::new(r.start.max(s.start), r.end.min(s.end));
                if !overlap.is_empty() {
                    return Err(PartError::Overlap {
                        a: a.to_string(),
                        b: b.to_string(),
                        overlap,
                    });
                }
            }
        }
        Ok(())
    }
}

fn coalesce(mut ranges: Vec<SampleRange>) -> Vec<SampleRange> {
    ranges.sort_by_key(|r| r.start);
    let mut out: Vec<SampleRange> = Vec::with_capacity(ranges.len());
    for r in ranges {
        match out.last_mut() {
            Some(last) if last.end == r.start => last.end = r.end,
            _ => out.push(r),
        }
    }
    out
}

/// Merges parts as they arrive, adding them in ascending order of their first sample so that
/// the result does not depend on the order of arrival: a part that comes before its turn
/// waits (checked at once, added when the parts before it have been). [`Merger::finish`]
/// adds whatever still waits, in the same order.
#[derive(Default)]
pub struct Merger {
    merged: Option<(Part, String)>,
    /// Parts not yet added, with their names, sorted by first sample.
    waiting: Vec<(Part, String)>,
    /// The first sample index of the next part to add.
    next: u32,
}

impl Merger {
    pub fn new() -> Self {
        Self::default()
    }

    /// Checks `part` against every part seen so far and queues it; adds the parts whose turn
    /// has come. `name` names it in errors (a file name, "range 0..16").
    pub fn push(&mut self, part: Part, name: &str) -> Result<(), PartError> {
        if let Some((m, mname)) = &self.merged {
            m.check_compatible(&part, mname, name)?;
        }
        for (w, wname) in &self.waiting {
            w.check_compatible(&part, wname, name)?;
        }
        let at = self
            .waiting
            .partition_point(|(w, _)| w.samples[0].start < part.samples[0].start);
        self.waiting.insert(at, (part, name.to_string()));
        while self
            .waiting
            .first()
            .is_some_and(|(w, _)| w.samples[0].start == self.next)
        {
            self.add_first()?;
        }
        Ok(())
    }

    fn add_first(&mut self) -> Result<(), PartError> {
        let (part, name) = self.waiting.remove(0);
        self.next = part.samples.last().map_or(self.next, |r| r.end);
        match &mut self.merged {
            None => self.merged = Some((part, name)),
            Some((m, mname)) => {
                m.add(&part, mname, &name)?;
                *mname = format!("{mname} + {name}");
            }
        }
        Ok(())
    }

    /// Samples per pixel received so far (added or waiting).
    pub fn sample_count(&self) -> u32 {
        self.merged
            .iter()
            .map(|(m, _)| m.sample_count())
            .sum::<u32>()
            + self
                .waiting
                .iter()
                .map(|(w, _)| w.sample_count())
                .sum::<u32>()
    }

    /// The merge of every part pushed.
    pub fn finish(mut self) -> Result<Part, PartError> {
        while !self.waiting.is_empty() {
            self.add_first()?;
        }
        self.merged.map(|(m, _)| m).ok_or(PartError::Empty)
    }
}

/// Merges `parts` (named in errors by `names`) in ascending order of their first sample.
pub fn merge(parts: Vec<(Part, String)>) -> Result<Part, PartError> {
    let mut merger = Merger::new();
    for (p, name) in parts {
        merger.push(p, &name)?;
    }
    merger.finish()
}

// ---- EXR I/O -------------------------------------------------------------------------

const FORMAT_VERSION: i32 = 1;
const CHANNELS: [&str; 4] = ["sum.R", "sum.G", "sum.B", "weight"];

/// Writes `part` as a partial EXR (written beside and renamed into place).
pub fn write_part(part: &Part, path: &Path) -> Result<(), PartError> {
    use exr::meta::attribute::AttributeValue;
    use exr::prelude::{
        AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, Text,
        WritableImage,
    };
    let err = |message: String| PartError::Io {
        path: path.to_path_buf(),
        message,
    };
    let id = &part.identity;
    let channel = |c: usize| {
        AnyChannel::new(
            CHANNELS[c],
            FlatSamples::F32(part.sums.iter().map(|p| p[c]).collect()),
        )
    };
    let mut attrs = LayerAttributes::default();
    let text = |s: String| AttributeValue::Text(Text::from(s.as_str()));
    let ranges: Vec<String> = part.samples.iter().map(ToString::to_string).collect();
    for (k, v) in [
        ("radia.part", AttributeValue::I32(FORMAT_VERSION)),
        ("radia.scene", text(format!("{:016x}", id.scene))),
        ("radia.seed", text(id.seed.to_string())),
        ("radia.samples", text(ranges.join(","))),
        ("radia.spp", AttributeValue::I32(id.spp as i32)),
        ("radia.sampler", text(id.sampler.clone())),
        ("radia.lightSampler", text(id.light_sampler.clone())),
    ] {
        attrs.other.insert(Text::from(k), v);
    }
    let layer = Layer::new(
        (id.width as usize, id.height as usize),
        attrs,
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort((0..4).map(channel).collect::<Vec<_>>().into()),
    );
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| err(e.to_string()))?;
    crate::image_io::write_atomically(path, &bytes.into_inner()).map_err(|e| err(e.to_string()))
}

/// Reads a partial EXR written by [`write_part`].
pub fn read_part(path: &Path) -> Result<Part, PartError> {
    use exr::meta::attribute::AttributeValue;
    use exr::prelude::{read, FlatSamples, ReadChannels, ReadLayers, Text};
    let not_part = |message: String| PartError::NotAPart {
        path: path.to_path_buf(),
        message,
    };
    let bytes = std::fs::read(path).map_err(|e| PartError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| not_part(format!("cannot read as OpenEXR: {e}")))?;
    let layer = &image.layer_data;
    let attr = |k: &str| {
        layer
            .attributes
            .other
            .get(&Text::from(k))
            .ok_or_else(|| not_part(format!("no '{k}' attribute in its header")))
    };
    let text = |k: &str| match attr(k)? {
        AttributeValue::Text(t) => Ok(t.to_string()),
        _ => Err(not_part(format!("'{k}' is not text"))),
    };
    let int = |k: &str| match attr(k)? {
        AttributeValue::I32(v) => Ok(*v),
        _ => Err(not_part(format!("'{k}' is not an integer"))),
    };
    let version = int("radia.part")?;
    if version != FORMAT_VERSION {
        return Err(not_part(format!(
            "format version {version}, this radia reads {FORMAT_VERSION}"
        )));
    }
    let scene = u64::from_str_radix(&text("radia.scene")?, 16)
        .map_err(|_| not_part("'radia.scene' is not a hex fingerprint".into()))?;
    let seed = text("radia.seed")?
        .parse::<u64>()
        .map_err(|_| not_part("'radia.seed' is not an integer".into()))?;
    let samples = text("radia.samples")?
        .split(',')
        .map(SampleRange::parse)
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| not_part(format!("'radia.samples': {e}")))?;
    let spp =
        u32::try_from(int("radia.spp")?).map_err(|_| not_part("'radia.spp' is negative".into()))?;
    if samples.iter().any(|r| r.end > spp) {
        return Err(not_part(format!(
            "'radia.samples' goes past the sample count {spp}"
        )));
    }
    let (w, h) = (layer.size.width(), layer.size.height());
    let mut sums = vec![[0.0f32; 4]; w * h];
    for (c, name) in CHANNELS.iter().enumerate() {
        let ch = layer
            .channel_data
            .list
            .iter()
            .find(|ch| ch.name == **name)
            .ok_or_else(|| not_part(format!("no '{name}' channel")))?;
        let FlatSamples::F32(values) = &ch.sample_data else {
            return Err(not_part(format!("channel '{name}' is not float32")));
        };
        for (p, v) in sums.iter_mut().zip(values) {
            p[c] = *v;
        }
    }
    Ok(Part {
        identity: RenderIdentity {
            scene,
            seed,
            sampler: text("radia.sampler")?,
            spp,
            light_sampler: text("radia.lightSampler")?,
            width: w as u32,
            height: h as u32,
        },
        samples: coalesce(samples),
        sums,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn identity() -> RenderIdentity {
        RenderIdentity {
            scene: 0xdead_beef_0123_4567,
            seed: u64::MAX - 3,
            sampler: "sobol".into(),
            spp: 64,
            light_sampler: "bvh".into(),
            width: 3,
            height: 2,
        }
    }

    fn part(start: u32, end: u32, v: f32) -> Part {
        Part::new(
            identity(),
            SampleRange::new(start, end),
            vec![[v, 2.0 * v, 3.0 * v, (end - start) as f32]; 6],
        )
    }

    #[test]
    fn exr_round_trip_keeps_every_bit_and_the_header() {
        let mut p = part(16, 32, 0.1);
        p.add(&part(48, 64, 0.3), "a", "b").unwrap();
        p.sums[4] = [1e-30, f32::MAX, 0.0, 7.0];
        let path = std::env::temp_dir().join(format!("radia-part-{}.exr", std::process::id()));
        write_part(&p, &path).unwrap();
        let q = read_part(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(q.identity, p.identity);
        assert_eq!(q.samples, p.samples);
        let bits = |s: &[[f32; 4]]| s.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&q.sums), bits(&p.sums));
    }

    #[test]
    fn merge_order_does_not_change_the_bits() {
        let parts = [
            part(0, 16, 0.1),
            part(16, 32, 0.7),
            part(32, 48, 1e-3),
            part(48, 64, 3.3),
        ];
        let a = merge(parts.iter().cloned().map(|p| (p, "x".into())).collect()).unwrap();
        let b = merge(
            parts
                .iter()
                .rev()
                .cloned()
                .map(|p| (p, "x".into()))
                .collect(),
        )
        .unwrap();
        assert_eq!(a.samples, vec![SampleRange::new(0, 64)]);
        assert!(a.gaps().is_empty());
        assert_eq!(a.sums, b.sums);
    }

    #[test]
    fn merge_refuses_overlaps_and_other_renders_and_reports_gaps() {
        let err = merge(vec![
            (part(0, 32, 1.0), "a".into()),
            (part(16, 48, 1.0), "b".into()),
        ])
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("16..32") && err.contains("a") && err.contains("b"),
            "{err}"
        );
        let mut other = part(32, 48, 1.0);
        other.identity.seed = 5;
        let err = merge(vec![(part(0, 32, 1.0), "a".into()), (other, "b".into())])
            .unwrap_err()
            .to_string();
        assert!(err.contains("seeds"), "{err}");
        let m = merge(vec![
            (part(0, 16, 1.0), "a".into()),
            (part(32, 48, 1.0), "b".into()),
        ])
        .unwrap();
        assert_eq!(
            m.gaps(),
            vec![SampleRange::new(16, 32), SampleRange::new(48, 64)]
        );
    }
}
