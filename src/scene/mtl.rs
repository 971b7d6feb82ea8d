//! MTL files: `Kd` diffuse albedo, `Ks` and `Ns` one normalized Phong lobe, `Ke` emitted
//! radiance, `map_Kd` an albedo texture that multiplies Kd (docs/DESIGN.md "Scene files",
//! "Textures"); every other key is ignored. Parsed here rather than by
//! tobj so that each value is checked with its file, line, material and key (tobj panics on a
//! short `Kd` line and reports no line numbers). A key a material does not set is 0.

use glam::Vec3;

use super::file::fmt3;
use super::{Material, SceneError, Wrap};

/// A material's `map_Kd` line: the image's path as written (backslashes made slashes),
/// relative to the MTL file, and its wrap (`-clamp on`: clamp, else repeat).
#[derive(Clone, Debug, PartialEq)]
pub struct AlbedoMap {
    /// Index of the material in the file.
    pub material: usize,
    pub line: usize,
    pub path: String,
    pub wrap: Wrap,
    /// Options irad does not apply (named in a warning by the caller).
    pub ignored: Vec<String>,
}

/// The options of `map_Kd` and how many arguments each takes (the MTL specification's).
const MAP_OPTIONS: [(&str, usize); 11] = [
    ("-blendu", 1),
    ("-blendv", 1),
    ("-bm", 1),
    ("-boost", 1),
    ("-cc", 1),
    ("-clamp", 1),
    ("-imfchan", 1),
    ("-mm", 2),
    ("-texres", 1),
    ("-o", 3),
    ("-s", 3),
];

/// Parses a `map_Kd` line's arguments: options, then the file name (which may hold spaces).
fn albedo_map(material: usize, line: usize, args: &str) -> Result<AlbedoMap, String> {
    let mut rest = args.trim();
    let mut wrap = Wrap::Repeat;
    let mut ignored = Vec::new();
    while let Some(option) = rest
        .split_whitespace()
        .next()
        .filter(|w| w.starts_with('-'))
    {
        let Some(&(_, count)) = MAP_OPTIONS
            .iter()
            .chain(&[("-t", 3)])
            .find(|(name, _)| *name == option)
        else {
            return Err(format!("unknown option {option}"));
        };
        rest = rest[option.len()..].trim_start();
        let mut values = Vec::new();
        // -o, -s and -t take 1 to 3 numbers.
        for k in 0..count {
            let Some(word) = rest.split_whitespace().next() else {
                break;
            };
            let numeric = word.parse::<f32>().is_ok();
            if k > 0 && !numeric {
                break;
            }
            values.push(word.to_string());
            rest = rest[word.len()..].trim_start();
        }
        if values.is_empty() {
            return Err(format!("{option} without its value"));
        }
        if option == "-clamp" {
            wrap = match values[0].to_ascii_lowercase().as_str() {
                "on" => Wrap::Clamp,
                "off" => Wrap::Repeat,
                v => return Err(format!("-clamp {v}: expected on or off")),
            };
        } else {
            ignored.push(format!("{option} {}", values.join(" ")));
        }
    }
    if rest.is_empty() {
        return Err("no image file named".into());
    }
    Ok(AlbedoMap {
        material,
        line,
        path: rest.replace('\\', "/"),
        wrap,
        ignored,
    })
}

/// An MTL file's materials and their albedo maps.
#[derive(Debug)]
pub struct MtlFile {
    pub materials: Vec<Material>,
    pub albedo_maps: Vec<AlbedoMap>,
}

/// How far above 1 a channel of Kd + Ks may be before it is refused (decimal rounding in
/// files such as `Kd 0.7` + `Ks 0.3`).
pub const ENERGY_TOLERANCE: f32 = 1e-5;

/// The materials of one MTL file, in file order; `file` names it in messages.
pub fn parse(file: &str, text: &str) -> Result<MtlFile, SceneError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut materials: Vec<Material> = Vec::new();
    let mut albedo_maps: Vec<AlbedoMap> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let mut words = line.split_whitespace();
        let Some(key) = words.next() else { continue };
        let line_error = |message: String| SceneError::Line {
            file: file.to_string(),
            line: n,
            message,
        };
        if key == "newmtl" {
            let name = line.trim_start()[6..].trim();
            if name.is_empty() {
                return Err(line_error("newmtl without a material name".into()));
            }
            materials.push(Material {
                name: name.to_string(),
                kd: Vec3::ZERO,
                ks: Vec3::ZERO,
                ns: 0.0,
                ke: Vec3::ZERO,
                albedo_texture: None,
            });
            continue;
        }
        if !matches!(key, "Kd" | "Ks" | "Ke" | "Ns" | "map_Kd") {
            continue;
        }
        let index = materials.len().wrapping_sub(1);
        let Some(m) = materials.last_mut() else {
            return Err(line_error(format!("{key} before any newmtl")));
        };
        if key == "map_Kd" {
            let args = line.trim_start()[6..].trim();
            let map = albedo_map(index, n, args).map_err(|problem| SceneError::Invalid {
                file: file.to_string(),
                field: format!("material `{}` map_Kd (line {n})", m.name),
                value: args.to_string(),
                problem,
            })?;
            albedo_maps.retain(|a| a.material != map.material);
            albedo_maps.push(map);
            continue;
        }
        let values: Vec<&str> = words.collect();
        let field = format!("material `{}` {key} (line {n})", m.name);
        let invalid = |value: String, problem: &str| SceneError::Invalid {
            file: file.to_string(),
            field: field.clone(),
            value,
            problem: problem.to_string(),
        };
        let numbers: Result<Vec<f32>, _> = values.iter().map(|v| v.parse::<f32>()).collect();
        let raw = values.join(" ");
        let Ok(numbers) = numbers else {
            return Err(invalid(
                raw,
                "expected numbers (spectral and xyz colours are not supported)",
            ));
        };
        if key == "Ns" {
            let [ns] = numbers[..] else {
                return Err(invalid(raw, "expected one number"));
            };
            if !(ns.is_finite() && ns >= 0.0) {
                return Err(invalid(ns.to_string(), "must be finite and >= 0"));
            }
            m.ns = ns;
            continue;
        }
        let rgb = match numbers[..] {
            [v] => [v; 3],
            [r, g, b] => [r, g, b],
            _ => return Err(invalid(raw, "expected one or three numbers (r g b)")),
        };
        if !rgb.iter().all(|v| v.is_finite() && *v >= 0.0) {
            return Err(invalid(
                fmt3(rgb),
                "must be finite and >= 0 in every channel",
            ));
        }
        let v = Vec3::from(rgb);
        match key {
            "Kd" => m.kd = v,
            "Ks" => m.ks = v,
            _ => m.ke = v,
        }
    }
    for m in &materials {
        let sum = m.kd + m.ks;
        if sum.max_element() > 1.0 + ENERGY_TOLERANCE {
            return Err(SceneError::Invalid {
                file: file.to_string(),
                field: format!("material `{}` Kd + Ks", m.name),
                value: fmt3(sum.to_array()),
                problem: format!(
                    "Kd = {} plus Ks = {} exceeds 1 in a channel; Kd + Ks <= 1 per channel is \
                     required (energy conservation)",
                    fmt3(m.kd.to_array()),
                    fmt3(m.ks.to_array())
                ),
            });
        }
    }
    Ok(MtlFile {
        materials,
        albedo_maps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_four_keys_and_ignores_the_rest() {
        let text =
            "# c\nnewmtl a b\nKa 1 1 1\nKd 0.5 0.25 0.125\nKs 0.25\nNs 20\nillum 2\nmap_Kd x.png\n\
                    newmtl light\nKe 17 12 4\n";
        let parsed = parse("m.mtl", text).unwrap();
        let m = &parsed.materials;
        assert_eq!(m.len(), 2);
        assert_eq!(m[0].name, "a b");
        assert_eq!(m[0].kd, Vec3::new(0.5, 0.25, 0.125));
        assert_eq!(m[0].ks, Vec3::splat(0.25));
        assert_eq!(m[0].ns, 20.0);
        assert!(!m[0].is_emissive());
        assert_eq!(m[1].kd, Vec3::ZERO);
        assert!(m[1].is_emissive());
        assert_eq!(
            parsed.albedo_maps,
            [AlbedoMap {
                material: 0,
                line: 8,
                path: "x.png".into(),
                wrap: Wrap::Repeat,
                ignored: vec![],
            }]
        );
    }

    #[test]
    fn map_kd_options_are_read_or_named() {
        let text = "newmtl a\nmap_Kd -clamp on -s 2 2 1 -bm 0.5 tex\\my wall.png\n";
        let map = &parse("m.mtl", text).unwrap().albedo_maps[0];
        assert_eq!(map.path, "tex/my wall.png");
        assert_eq!(map.wrap, Wrap::Clamp);
        assert_eq!(map.ignored, ["-s 2 2 1", "-bm 0.5"]);
        let map = &parse("m.mtl", "newmtl a\nmap_Kd -o 0.5 b.jpg\n")
            .unwrap()
            .albedo_maps[0];
        assert_eq!((map.path.as_str(), map.ignored.len()), ("b.jpg", 1));
        for (text, expected) in [
            ("newmtl a\nmap_Kd\n", "no image file named"),
            (
                "newmtl a\nmap_Kd -clamp maybe x.png\n",
                "-clamp maybe: expected on or off",
            ),
            ("newmtl a\nmap_Kd -warp 1 x.png\n", "unknown option -warp"),
        ] {
            let e = parse("m.mtl", text).unwrap_err().to_string();
            assert!(
                e.contains("material `a` map_Kd (line 2)") && e.contains(expected),
                "{e}"
            );
        }
    }

    #[test]
    fn bad_values_are_named() {
        let cases = [
            (
                "newmtl w\nKd 0.5 nan 0.5\n",
                "material `w` Kd (line 2) = [0.5, NaN, 0.5]",
            ),
            (
                "newmtl w\nKe -1 0 0\n",
                "material `w` Ke (line 2) = [-1, 0, 0]",
            ),
            (
                "newmtl w\nKs 0.5 0.5\n",
                "material `w` Ks (line 2) = 0.5 0.5",
            ),
            ("newmtl w\nNs inf\n", "material `w` Ns (line 2) = inf"),
            (
                "newmtl w\nKd spectral x.spd\n",
                "material `w` Kd (line 2) = spectral x.spd",
            ),
            (
                "newmtl w\nKd 0.8\nKs 0.1 0.3 0.1\n",
                "material `w` Kd + Ks = [0.90000004, 1.1, 0.90000004]",
            ),
            ("Kd 1 1 1\n", "m.mtl line 1: Kd before any newmtl"),
        ];
        for (text, expected) in cases {
            let m = parse("m.mtl", text).unwrap_err().to_string();
            assert!(m.starts_with("m.mtl") && m.contains(expected), "{m}");
        }
    }

    #[test]
    fn kd_plus_ks_of_exactly_one_is_allowed() {
        parse("m.mtl", "newmtl w\nKd 0.7\nKs 0.3\n").unwrap();
    }
}
