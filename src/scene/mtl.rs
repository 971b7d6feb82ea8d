//! MTL files: `Kd` diffuse albedo, `Ks` and `Ns` one normalized Phong lobe, `Ke` emitted
//! radiance (docs/DESIGN.md "Scene files"); every other key is ignored. Parsed here rather than by
//! tobj so that each value is checked with its file, line, material and key (tobj panics on a
//! short `Kd` line and reports no line numbers). A key a material does not set is 0.

use glam::Vec3;

use super::file::fmt3;
use super::{Material, SceneError};

/// How far above 1 a channel of Kd + Ks may be before it is refused (decimal rounding in
/// files such as `Kd 0.7` + `Ks 0.3`).
pub const ENERGY_TOLERANCE: f32 = 1e-5;

/// The materials of one MTL file, in file order; `file` names it in messages.
pub fn parse(file: &str, text: &str) -> Result<Vec<Material>, SceneError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut materials: Vec<Material> = Vec::new();
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
            });
            continue;
        }
        if !matches!(key, "Kd" | "Ks" | "Ke" | "Ns") {
            continue;
        }
        let Some(m) = materials.last_mut() else {
            return Err(line_error(format!("{key} before any newmtl")));
        };
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
    Ok(materials)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_four_keys_and_ignores_the_rest() {
        let text =
            "# c\nnewmtl a b\nKa 1 1 1\nKd 0.5 0.25 0.125\nKs 0.25\nNs 20\nillum 2\nmap_Kd x.png\n\
                    newmtl light\nKe 17 12 4\n";
        let m = parse("m.mtl", text).unwrap();
        assert_eq!(m.len(), 2);
        assert_eq!(m[0].name, "a b");
        assert_eq!(m[0].kd, Vec3::new(0.5, 0.25, 0.125));
        assert_eq!(m[0].ks, Vec3::splat(0.25));
        assert_eq!(m[0].ns, 20.0);
        assert!(!m[0].is_emissive());
        assert_eq!(m[1].kd, Vec3::ZERO);
        assert!(m[1].is_emissive());
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
