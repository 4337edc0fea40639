//! Arbitrary output variables: what Mitsuba's `aov` integrator (`src/integrators/aov.cpp`)
//! writes beside the image, as typed data. The loader and the CLI's `--aov` parse the same
//! `aovs` string here (`name:type` pairs separated by commas), so both mean the same thing.
//!
//! ```xml
//! <integrator type="aov">
//!     <string name="aovs" value="dd.y:depth,nn:sh_normal,albedo:albedo"/>
//!     <integrator type="path" name="my_image"/>
//! </integrator>
//! ```

/// One kind of AOV and the surface quantity it records at the first hit of the camera ray
/// (every channel 0 where the ray escapes, as Mitsuba zeroes an invalid interaction).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AovKind {
    /// The BSDF's diffuse reflectance (Mitsuba's `BSDF::eval_diffuse_reflectance`).
    Albedo,
    /// Mitsuba's `si.t`: the distance along the camera ray from where it starts, on the near
    /// plane (`near_clip` / cos of the ray's angle to the axis from the pinhole); not the
    /// z-depth.
    Depth,
    /// World-space position.
    Position,
    /// Surface texture coordinates.
    Uv,
    /// Geometric normal (flipped by `flip_normals`, never towards the viewer).
    GeoNormal,
    /// Shading normal, after a `normalmap`/`bumpmap` perturbation (Mitsuba's `BSDF::sh_frame`).
    ShNormal,
    /// ∂p/∂u, ∂p/∂v in world space.
    DpDu,
    DpDv,
    /// Triangle index within its mesh (0 on analytic shapes).
    PrimIndex,
    /// 1 + the shape's index in the scene (0 where nothing was hit), as Mitsuba's scalar
    /// variants count `scene->shapes()`.
    ShapeIndex,
}

impl AovKind {
    /// The type names of the `aovs` string.
    pub const NAMES: [(&'static str, AovKind); 10] = [
        ("albedo", AovKind::Albedo),
        ("depth", AovKind::Depth),
        ("position", AovKind::Position),
        ("uv", AovKind::Uv),
        ("geo_normal", AovKind::GeoNormal),
        ("sh_normal", AovKind::ShNormal),
        ("dp_du", AovKind::DpDu),
        ("dp_dv", AovKind::DpDv),
        ("prim_index", AovKind::PrimIndex),
        ("shape_index", AovKind::ShapeIndex),
    ];

    /// The suffixes Mitsuba gives this kind's channels (`name.R`, `name.T`, `name.X`, ...).
    pub fn channel_suffixes(self) -> &'static [&'static str] {
        match self {
            AovKind::Albedo => &["R", "G", "B"],
            AovKind::Depth => &["T"],
            AovKind::Uv => &["U", "V"],
            AovKind::Position
            | AovKind::GeoNormal
            | AovKind::ShNormal
            | AovKind::DpDu
            | AovKind::DpDv => &["X", "Y", "Z"],
            AovKind::PrimIndex | AovKind::ShapeIndex => &["I"],
        }
    }
}

/// One `name:type` pair of the `aovs` string.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AovOutput {
    pub name: String,
    pub kind: AovKind,
}

impl AovOutput {
    /// The EXR channel names of this output, in Mitsuba's order (`dd.y:depth` gives `dd.y.T`).
    pub fn channels(&self) -> Vec<String> {
        self.kind
            .channel_suffixes()
            .iter()
            .map(|s| format!("{}.{s}", self.name))
            .collect()
    }
}

/// The `aov` integrator: its outputs and the nested integrator that renders the image.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AovDesc {
    pub outputs: Vec<AovOutput>,
    /// The nested integrator's name, when the scene declares one: Mitsuba then writes its
    /// image a second time as the layer `NAME.R, NAME.G, NAME.B, NAME.A` (A = alpha). `None`
    /// for `radia render --aov`, which only adds the AOV layers beside the image.
    pub beauty_layer: Option<String>,
    /// False when the `aov` integrator has no nested integrator: the image is then black, as
    /// Mitsuba's (the AOV integrator's own radiance is 0).
    pub has_beauty: bool,
}

impl AovDesc {
    /// Every channel beyond the image's R, G, B, in Mitsuba's order: the beauty layer's four,
    /// then each output's.
    pub fn channels(&self) -> Vec<String> {
        let mut names = Vec::new();
        if let Some(b) = &self.beauty_layer {
            names.extend(["R", "G", "B", "A"].map(|c| format!("{b}.{c}")));
        }
        for o in &self.outputs {
            names.extend(o.channels());
        }
        names
    }
}

/// Parses an `aovs` string, `name:type` pairs separated by commas (Mitsuba's
/// `string::tokenize` also splits at spaces). Unlike Mitsuba, which only warns about a
/// malformed pair, every error is refused, with the offending pair named.
pub fn parse_aovs(spec: &str) -> Result<Vec<AovOutput>, String> {
    let mut out: Vec<AovOutput> = Vec::new();
    for token in spec.split([',', ' ']).filter(|t| !t.is_empty()) {
        let Some((name, ty)) = token
            .split_once(':')
            .filter(|(n, t)| !n.is_empty() && !t.is_empty() && !t.contains(':'))
        else {
            return Err(format!(
                "invalid AOV specification \"{token}\": expected a <name>:<type> pair"
            ));
        };
        let Some(&(_, kind)) = AovKind::NAMES.iter().find(|(n, _)| *n == ty) else {
            let known: Vec<&str> = AovKind::NAMES.iter().map(|(n, _)| *n).collect();
            let hint = if matches!(ty, "duv_dx" | "duv_dy") {
                " (radia traces no ray differentials)"
            } else {
                ""
            };
            return Err(format!(
                "invalid AOV type \"{ty}\" in \"{token}\"{hint}; radia supports: {}",
                known.join(", ")
            ));
        };
        if out.iter().any(|o| o.name == name) {
            return Err(format!("the AOV name \"{name}\" is used twice"));
        }
        out.push(AovOutput {
            name: name.to_string(),
            kind,
        });
    }
    if out.is_empty() {
        return Err(format!("no AOVs in \"{spec}\""));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_mitsuba_examples_with_its_channel_names() {
        let aovs = parse_aovs("dd.y:depth,nn:sh_normal, albedo:albedo").unwrap();
        let desc = AovDesc {
            outputs: aovs,
            beauty_layer: Some("my_image".into()),
            has_beauty: true,
        };
        assert_eq!(
            desc.channels(),
            [
                "my_image.R",
                "my_image.G",
                "my_image.B",
                "my_image.A",
                "dd.y.T",
                "nn.X",
                "nn.Y",
                "nn.Z",
                "albedo.R",
                "albedo.G",
                "albedo.B"
            ]
        );
    }

    #[test]
    fn refuses_bad_specifications() {
        for (spec, what) in [
            ("dd", "expected a <name>:<type> pair"),
            (":depth", "expected a <name>:<type> pair"),
            ("a:b:c", "expected a <name>:<type> pair"),
            ("d:dpeth", "invalid AOV type \"dpeth\""),
            ("d:duv_dx", "ray differentials"),
            ("d:depth,d:uv", "used twice"),
            (" , ", "no AOVs"),
        ] {
            let e = parse_aovs(spec).unwrap_err();
            assert!(e.contains(what), "{spec}: {e}");
        }
    }
}
