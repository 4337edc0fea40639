//! Mitsuba 3's named indices of refraction (`include/mitsuba/render/ior.h`) and the RGB
//! complex IORs of its conductor presets (`material="Au"` etc.).

/// Dielectric IORs by name, as Mitsuba's `ior_data` (Hecht, *Optics*, 4th ed.; measured
/// between 0 and 20 °C at about 589 nm). Names are matched case-insensitively, as there.
pub const DIELECTRIC_IORS: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// The IOR of a named dielectric (case-insensitive), as Mitsuba's `lookup_ior`.
pub fn lookup_dielectric_ior(name: &str) -> Option<f32> {
    let lower = name.to_lowercase();
    DIELECTRIC_IORS
        .iter()
        .find(|(n, _)| *n == lower)
        .map(|&(_, v)| v)
}

/// A conductor preset: the RGB real (`eta`) and imaginary (`k`) parts of its IOR.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConductorPreset {
    pub name: &'static str,
    pub eta: [f32; 3],
    pub k: [f32; 3],
}

/// Mitsuba 3.9.1's conductor presets in its RGB variants. Mitsuba reads the spectral curves
/// `data/ior/<name>.{eta,k}.spd` and converts each to an RGB colour
/// (`complex_ior_from_file` → `spectrum_list_to_srgb` in `include/mitsuba/render/ior.h`,
/// clamping out-of-gamut components to 0); radia cannot reproduce that conversion bit for
/// bit, so these are the values Mitsuba 3.9.1 (`scalar_rgb`) itself produces, read back with
/// `mi.traverse(mi.load_dict({"type": "conductor", "material": name}))` for every preset
/// file shipped with it. Names are case-sensitive, as Mitsuba's file names.
pub const CONDUCTOR_PRESETS: &[ConductorPreset] = &[
    ConductorPreset {
        name: "Ag",
        eta: [0.155276194, 0.116727956, 0.138387635],
        k: [4.82835436, 3.12222242, 2.14690113],
    },
    ConductorPreset {
        name: "Al",
        eta: [1.65750086, 0.880404711, 0.521244466],
        k: [9.22381115, 6.26950216, 4.83700418],
    },
    ConductorPreset {
        name: "Au",
        eta: [0.143035978, 0.375307083, 1.44204533],
        k: [3.98299694, 2.38555646, 1.60335922],
    },
    ConductorPreset {
        name: "Be",
        eta: [4.18501234, 3.18502927, 2.78406119],
        k: [3.83546591, 3.0101223, 2.868994],
    },
    ConductorPreset {
        name: "Be_palik",
        eta: [4.18501234, 3.18502927, 2.78406119],
        k: [3.83546591, 3.0101223, 2.868994],
    },
    ConductorPreset {
        name: "Cr",
        eta: [4.36966753, 2.91650534, 1.6549046],
        k: [5.20654678, 4.23130608, 3.75469875],
    },
    ConductorPreset {
        name: "CsI",
        eta: [2.14489961, 1.70231891, 1.66242719],
        k: [0.0, 0.0, 0.0],
    },
    ConductorPreset {
        name: "CsI_palik",
        eta: [2.14489961, 1.70231891, 1.66242719],
        k: [0.0, 0.0, 0.0],
    },
    ConductorPreset {
        name: "Cu",
        eta: [0.201005474, 0.923749506, 1.10221541],
        k: [3.91326213, 2.45304513, 2.14208984],
    },
    ConductorPreset {
        name: "Cu2O",
        eta: [3.55177259, 2.94986963, 2.7518754],
        k: [0.114207022, 0.19389686, 0.606133878],
    },
    ConductorPreset {
        name: "Cu2O_palik",
        eta: [3.55177259, 2.94986963, 2.7518754],
        k: [0.114207022, 0.19389686, 0.606133878],
    },
    ConductorPreset {
        name: "CuO",
        eta: [3.24754095, 2.44780517, 2.21021962],
        k: [0.521089554, 0.570030749, 0.722178936],
    },
    ConductorPreset {
        name: "CuO_palik",
        eta: [3.24754095, 2.44780517, 2.21021962],
        k: [0.521089554, 0.570030749, 0.722178936],
    },
    ConductorPreset {
        name: "Cu_palik",
        eta: [0.213228509, 0.919715405, 1.10241079],
        k: [3.92187333, 2.45733166, 2.13658404],
    },
    ConductorPreset {
        name: "Hg",
        eta: [2.39893866, 1.44002795, 0.909570396],
        k: [6.32758713, 4.37192488, 3.42176366],
    },
    ConductorPreset {
        name: "HgTe",
        eta: [4.77903986, 3.23119617, 2.65990114],
        k: [1.63161266, 1.58081043, 1.72928739],
    },
    ConductorPreset {
        name: "HgTe_palik",
        eta: [4.77903986, 3.23119617, 2.65990114],
        k: [1.63161266, 1.58081043, 1.72928739],
    },
    ConductorPreset {
        name: "Hg_palik",
        eta: [2.39893866, 1.44002795, 0.909570396],
        k: [6.32758713, 4.37192488, 3.42176366],
    },
    ConductorPreset {
        name: "Ir",
        eta: [3.0862999, 2.08219051, 1.61791456],
        k: [5.59215307, 4.06708813, 3.26731205],
    },
    ConductorPreset {
        name: "Ir_palik",
        eta: [3.0862999, 2.08219051, 1.61791456],
        k: [5.59215307, 4.06708813, 3.26731205],
    },
    ConductorPreset {
        name: "K",
        eta: [0.0640431866, 0.0464097671, 0.0381849147],
        k: [2.10419965, 1.34894001, 0.913125873],
    },
    ConductorPreset {
        name: "K_palik",
        eta: [0.0640431866, 0.0464097671, 0.0381849147],
        k: [2.10419965, 1.34894001, 0.913125873],
    },
    ConductorPreset {
        name: "Li",
        eta: [0.265790939, 0.195618317, 0.220948622],
        k: [3.54015493, 2.31112337, 1.66860723],
    },
    ConductorPreset {
        name: "Li_palik",
        eta: [0.265790939, 0.195618317, 0.220948622],
        k: [3.54015493, 2.31112337, 1.66860723],
    },
    ConductorPreset {
        name: "Mo",
        eta: [4.48397398, 3.52513075, 2.77631044],
        k: [4.11143732, 3.42082691, 3.15060735],
    },
    ConductorPreset {
        name: "Mo_palik",
        eta: [4.48397398, 3.52513075, 2.77631044],
        k: [4.11143732, 3.42082691, 3.15060735],
    },
    ConductorPreset {
        name: "Na_palik",
        eta: [0.0602693558, 0.0561409481, 0.061988432],
        k: [3.17927337, 2.11249042, 1.57904112],
    },
    ConductorPreset {
        name: "Nb",
        eta: [3.42007399, 2.79009318, 2.39562941],
        k: [3.44139457, 2.73766613, 2.57974577],
    },
    ConductorPreset {
        name: "Nb_palik",
        eta: [3.42007399, 2.79009318, 2.39562941],
        k: [3.44139457, 2.73766613, 2.57974577],
    },
    ConductorPreset {
        name: "Ni_palik",
        eta: [2.36730456, 1.66337311, 1.46707809],
        k: [4.49881172, 3.05015302, 2.3454392],
    },
    ConductorPreset {
        name: "Rh",
        eta: [2.5857935, 1.86021638, 1.55426335],
        k: [6.78226042, 4.70298719, 3.97607303],
    },
    ConductorPreset {
        name: "Rh_palik",
        eta: [2.5857935, 1.86021638, 1.55426335],
        k: [6.78226042, 4.70298719, 3.97607303],
    },
    ConductorPreset {
        name: "Se",
        eta: [4.05831146, 2.84293509, 2.82085347],
        k: [0.75404954, 0.63844353, 0.521807551],
    },
    ConductorPreset {
        name: "Se-e",
        eta: [5.72284889, 4.1657362, 4.08133841],
        k: [0.871136308, 1.10515749, 1.56532025],
    },
    ConductorPreset {
        name: "Se-e_palik",
        eta: [5.72284889, 4.1657362, 4.08133841],
        k: [0.871136308, 1.10515749, 1.56532025],
    },
    ConductorPreset {
        name: "Se_palik",
        eta: [4.05831146, 2.84293509, 2.82085347],
        k: [0.75404954, 0.63844353, 0.521807551],
    },
    ConductorPreset {
        name: "SnTe",
        eta: [4.52424955, 1.98164499, 1.2815913],
        k: [0.0, 0.0, 0.0],
    },
    ConductorPreset {
        name: "SnTe_palik",
        eta: [4.52424955, 1.98164499, 1.2815913],
        k: [0.0, 0.0, 0.0],
    },
    ConductorPreset {
        name: "Ta",
        eta: [2.06272101, 2.39293885, 2.62792873],
        k: [2.40835977, 1.74148643, 1.9470278],
    },
    ConductorPreset {
        name: "Ta_palik",
        eta: [2.06272101, 2.39293885, 2.62792873],
        k: [2.40835977, 1.74148643, 1.9470278],
    },
    ConductorPreset {
        name: "Te",
        eta: [7.39023352, 4.48210478, 2.63710594],
        k: [3.25602221, 3.52705884, 3.29205418],
    },
    ConductorPreset {
        name: "Te-e",
        eta: [7.50890684, 4.29642868, 2.36998773],
        k: [5.58392859, 4.94720507, 3.99759221],
    },
    ConductorPreset {
        name: "Te-e_palik",
        eta: [7.50890684, 4.29642868, 2.36998773],
        k: [5.58392859, 4.94720507, 3.99759221],
    },
    ConductorPreset {
        name: "Te_palik",
        eta: [7.39023352, 4.48210478, 2.63710594],
        k: [3.25602221, 3.52705884, 3.29205418],
    },
    ConductorPreset {
        name: "ThF4",
        eta: [1.83071363, 1.44222856, 1.38764763],
        k: [0.0, 0.0, 0.0],
    },
    ConductorPreset {
        name: "ThF4_palik",
        eta: [1.83071363, 1.44222856, 1.38764763],
        k: [0.0, 0.0, 0.0],
    },
    ConductorPreset {
        name: "TiC",
        eta: [3.70052838, 2.83742213, 2.58228707],
        k: [3.26563501, 2.3515892, 2.17279053],
    },
    ConductorPreset {
        name: "TiC_palik",
        eta: [3.70052838, 2.83742213, 2.58228707],
        k: [3.26563501, 2.3515892, 2.17279053],
    },
    ConductorPreset {
        name: "TiN",
        eta: [1.64844966, 1.15051603, 1.37982345],
        k: [3.36832809, 1.94349813, 1.10206771],
    },
    ConductorPreset {
        name: "TiN_palik",
        eta: [1.64844966, 1.15051603, 1.37982345],
        k: [3.36832809, 1.94349813, 1.10206771],
    },
    ConductorPreset {
        name: "VC",
        eta: [3.65756607, 2.75273609, 2.53267193],
        k: [3.06830072, 2.19868731, 1.9631927],
    },
    ConductorPreset {
        name: "VC_palik",
        eta: [3.65756607, 2.75273609, 2.53267193],
        k: [3.06830072, 2.19868731, 1.9631927],
    },
    ConductorPreset {
        name: "VN",
        eta: [2.86560225, 2.11918902, 1.94009113],
        k: [3.03224254, 2.05611563, 1.6163063],
    },
    ConductorPreset {
        name: "VN_palik",
        eta: [2.86560225, 2.11918902, 1.94009113],
        k: [3.03224254, 2.05611563, 1.6163063],
    },
    ConductorPreset {
        name: "V_palik",
        eta: [4.27758217, 3.51294875, 2.76107144],
        k: [3.49130082, 2.88945484, 3.11152196],
    },
    ConductorPreset {
        name: "W",
        eta: [4.37081671, 3.30024648, 2.99840736],
        k: [3.50064063, 2.6048739, 2.27323318],
    },
    ConductorPreset {
        name: "a-C",
        eta: [2.94404578, 2.22713637, 1.9681617],
        k: [0.887464881, 0.799298525, 0.815289974],
    },
    ConductorPreset {
        name: "d-C",
        eta: [2.70871973, 2.31882572, 2.22889757],
        k: [0.0, 0.0, 0.0],
    },
    ConductorPreset {
        name: "d-C_palik",
        eta: [2.70871973, 2.31882572, 2.22889757],
        k: [0.0, 0.0, 0.0],
    },
];

/// A conductor preset by name (case-sensitive, as Mitsuba's file lookup).
pub fn lookup_conductor(name: &str) -> Option<&'static ConductorPreset> {
    CONDUCTOR_PRESETS.iter().find(|p| p.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lookups() {
        assert_eq!(lookup_dielectric_ior("BK7"), Some(1.5046));
        assert_eq!(lookup_dielectric_ior("air"), Some(1.000277));
        assert_eq!(lookup_dielectric_ior("glass"), None);
        // MITSUBA-SEMANTICS.md lists Au, Cu and Al.
        let au = lookup_conductor("Au").unwrap();
        assert_eq!(au.eta, [0.143035978, 0.375307083, 1.44204533]);
        assert_eq!(au.k, [3.98299694, 2.38555646, 1.60335922]);
        assert!((lookup_conductor("Cu").unwrap().k[0] - 3.91326).abs() < 1e-5);
        assert!((lookup_conductor("Al").unwrap().eta[0] - 1.6575).abs() < 1e-5);
        assert!(lookup_conductor("au").is_none());
        let mut names: Vec<_> = CONDUCTOR_PRESETS.iter().map(|p| p.name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), CONDUCTOR_PRESETS.len());
    }
}
