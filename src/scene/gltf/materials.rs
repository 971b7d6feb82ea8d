//! glTF materials as irad's Lambert plus one normalized Phong lobe (docs/scenes.md "glTF
//! scenes" states the fit and its error), and their base colour textures.
//!
//! The metallic-roughness fit, at normal incidence: F0 = lerp(0.04, base, metallic) is the
//! specular albedo (Ks), the diffuse albedo is what the dielectric part leaves,
//! Kd = base (1 - metallic) (1 - 0.04); Kd + Ks <= 1 for base colours in [0, 1]. The lobe's
//! width: glTF's GGX alpha = roughness^2, as a Phong exponent by the Mitsuba importer's
//! Beckmann fit (`ns_of_alpha`), capped at a mirror's MIRROR_NS.

use std::collections::HashMap;

use glam::Vec3;
use gltf::material::AlphaMode;
use gltf::texture::WrappingMode;

use super::data::{image_bytes, Buffers};
use super::Ctx;
use crate::scene::mitsuba::{ns_of_alpha, MIRROR_NS};
use crate::scene::{Material, SceneError, Texture, Wrap};

/// The dielectric specular albedo glTF's metallic-roughness model assumes (an index of
/// refraction of 1.5).
pub const DIELECTRIC_F0: f32 = 0.04;

/// irad's material parts from glTF's metallic-roughness parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    pub kd: Vec3,
    pub ks: Vec3,
    pub ns: f32,
    /// Whether the exponent was capped at MIRROR_NS (roughness below about 0.084).
    pub capped: bool,
}

/// The fit for base colour `base`, `metallic` and `roughness` (each in [0, 1]).
pub fn metallic_roughness(base: Vec3, metallic: f32, roughness: f32) -> Fit {
    let m = metallic.clamp(0.0, 1.0);
    let ks = Vec3::splat(DIELECTRIC_F0).lerp(base, m);
    let kd = base * (1.0 - m) * (1.0 - DIELECTRIC_F0);
    let alpha = f64::from(roughness.clamp(0.0, 1.0)).powi(2);
    let ns = ns_of_alpha(alpha);
    Fit {
        kd,
        ks,
        ns: ns.min(MIRROR_NS),
        capped: ns > MIRROR_NS,
    }
}

/// The scene's materials and textures, made from glTF materials as primitives use them.
#[derive(Default)]
pub struct Materials {
    pub list: Vec<Material>,
    pub textures: Vec<Texture>,
    /// glTF material (None: the default material) -> (scene material, TEXCOORD set its base
    /// colour texture reads).
    by_gltf: HashMap<Option<usize>, (u32, u32)>,
    /// (image, wrap) -> scene texture.
    texture_index: HashMap<(usize, [Wrap; 2]), u32>,
    decoded: HashMap<usize, Texture>,
    /// Whether any material has a specular part (for the file's one fit warning).
    pub specular: bool,
}

fn wrap(mode: WrappingMode) -> Wrap {
    match mode {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::MirroredRepeat => Wrap::Mirror,
        WrappingMode::ClampToEdge => Wrap::Clamp,
    }
}

fn fmt_vec(v: &[f32]) -> String {
    let parts: Vec<String> = v.iter().map(|x| x.to_string()).collect();
    format!("[{}]", parts.join(", "))
}

impl Materials {
    /// The scene material for `material` and the TEXCOORD set its base colour texture reads
    /// (0 without one), made on first use.
    pub fn get(
        &mut self,
        ctx: &mut Ctx,
        doc: &gltf::Document,
        buffers: &Buffers,
        material: &gltf::Material,
    ) -> Result<(u32, u32), SceneError> {
        if let Some(&found) = self.by_gltf.get(&material.index()) {
            return Ok(found);
        }
        let made = self.make(ctx, doc, buffers, material)?;
        self.by_gltf.insert(material.index(), made);
        Ok(made)
    }

    fn make(
        &mut self,
        ctx: &mut Ctx,
        doc: &gltf::Document,
        buffers: &Buffers,
        material: &gltf::Material,
    ) -> Result<(u32, u32), SceneError> {
        let (field, label, name) = match material.index() {
            Some(i) => {
                let field = format!("materials[{i}]");
                let label = super::label(&field, material.name());
                let name = material
                    .name()
                    .map_or_else(|| field.clone(), str::to_string);
                (field, label, name)
            }
            None => {
                let name = "(glTF default material)".to_string();
                (name.clone(), name.clone(), name)
            }
        };
        let pbr = material.pbr_metallic_roughness();
        let factor = pbr.base_color_factor();
        let pbr_field = format!("{field}.pbrMetallicRoughness");
        if !factor
            .iter()
            .all(|x| x.is_finite() && (0.0..=1.0).contains(x))
        {
            return Err(ctx.invalid(
                &format!("{pbr_field}.baseColorFactor"),
                &fmt_vec(&factor),
                "each component must be in [0, 1]",
            ));
        }
        let (metallic, roughness) = (pbr.metallic_factor(), pbr.roughness_factor());
        for (key, v) in [("metallicFactor", metallic), ("roughnessFactor", roughness)] {
            if !(v.is_finite() && (0.0..=1.0).contains(&v)) {
                return Err(ctx.invalid(
                    &format!("{pbr_field}.{key}"),
                    &v.to_string(),
                    "must be in [0, 1]",
                ));
            }
        }
        let base = Vec3::new(factor[0], factor[1], factor[2]);
        let mut fit = metallic_roughness(base, metallic, roughness);
        if fit.ks.max_element() > 0.0 {
            self.specular = true;
        }
        if fit.capped {
            ctx.warn(format!(
                "{label}: roughnessFactor {roughness} is nearly a mirror: its Phong exponent is \
                 capped at {MIRROR_NS}"
            ));
        }
        let (mut albedo_texture, mut set) = (None, 0);
        if let Some(info) = pbr.base_color_texture() {
            let tex_field = format!("{pbr_field}.baseColorTexture");
            albedo_texture = Some(self.texture(ctx, doc, buffers, &info.texture(), &tex_field)?);
            set = info.tex_coord();
            if metallic > 0.0 {
                ctx.warn(format!(
                    "{label}: metallicFactor {metallic} with a baseColorTexture: the texture \
                     multiplies the diffuse part only; the specular colour F0 uses \
                     baseColorFactor alone"
                ));
            }
        }
        if pbr.metallic_roughness_texture().is_some() {
            ctx.warn(format!(
                "{label}: pbrMetallicRoughness.metallicRoughnessTexture is ignored (the \
                 factors alone are used)"
            ));
        }
        if material.normal_texture().is_some() {
            ctx.warn(format!(
                "{label}: normalTexture is ignored (the mesh's own normals are used)"
            ));
        }
        if material.occlusion_texture().is_some() {
            ctx.warn(format!(
                "{label}: occlusionTexture is ignored (irad traces occlusion itself)"
            ));
        }
        match material.alpha_mode() {
            AlphaMode::Opaque => {}
            mode => ctx.warn(format!(
                "{label}: alphaMode {mode:?} is rendered opaque (irad has no transparency)"
            )),
        }
        let sum = (fit.kd + fit.ks).max_element();
        if sum > 1.0 + 1e-5 {
            ctx.warn(format!(
                "{label}: Kd {} + Ks {} reflects more than it receives; both scaled by {}",
                fit.kd,
                fit.ks,
                1.0 / sum
            ));
            fit.kd /= sum;
            fit.ks /= sum;
        }
        let ke = self.emission(ctx, doc, buffers, material, &field, &label)?;
        let index = self.list.len() as u32;
        self.list.push(Material {
            name,
            kd: fit.kd,
            ks: fit.ks,
            ns: fit.ns,
            ke,
            albedo_texture,
        });
        Ok((index, set))
    }

    /// emissiveFactor times KHR_materials_emissive_strength, times the emissive texture's
    /// mean linear colour (with a warning).
    fn emission(
        &mut self,
        ctx: &mut Ctx,
        doc: &gltf::Document,
        buffers: &Buffers,
        material: &gltf::Material,
        field: &str,
        label: &str,
    ) -> Result<Vec3, SceneError> {
        let factor = material.emissive_factor();
        if !factor.iter().all(|x| x.is_finite() && *x >= 0.0) {
            return Err(ctx.invalid(
                &format!("{field}.emissiveFactor"),
                &fmt_vec(&factor),
                "each component must be finite and >= 0",
            ));
        }
        let strength = material.emissive_strength().unwrap_or(1.0);
        if !(strength.is_finite() && strength >= 0.0) {
            return Err(ctx.invalid(
                &format!("{field}.extensions.KHR_materials_emissive_strength.emissiveStrength"),
                &strength.to_string(),
                "must be finite and >= 0",
            ));
        }
        let mut ke = Vec3::from(factor) * strength;
        if let Some(info) = material.emissive_texture() {
            let image = info.texture().source().index();
            let texture = self.decode(
                ctx,
                doc,
                buffers,
                image,
                &format!("{field}.emissiveTexture"),
                [Wrap::Repeat; 2],
            )?;
            let n = texture.texels.len().max(1) as f64;
            let mean = texture
                .texels
                .iter()
                .fold(glam::DVec3::ZERO, |s, t| s + t.as_dvec3())
                / n;
            let mean = mean.as_vec3();
            if ke.max_element() > 0.0 {
                ctx.warn(format!(
                    "{label}: emissiveTexture as its mean linear colour {mean} times the \
                     emissive factor (irad's emission is uniform over a material)"
                ));
            }
            ke *= mean;
        }
        if ke.max_element() > 0.0 && material.double_sided() {
            ctx.warn(format!(
                "{label}: doubleSided, but irad's emission is one-sided: it emits on the front \
                 (counter-clockwise) side only"
            ));
        }
        Ok(ke)
    }

    /// The scene texture of a glTF texture (its image with its sampler's wrap modes).
    fn texture(
        &mut self,
        ctx: &mut Ctx,
        doc: &gltf::Document,
        buffers: &Buffers,
        texture: &gltf::Texture,
        field: &str,
    ) -> Result<u32, SceneError> {
        let sampler = texture.sampler();
        let modes = [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())];
        let image = texture.source().index();
        if let Some(&i) = self.texture_index.get(&(image, modes)) {
            return Ok(i);
        }
        let decoded = self.decode(ctx, doc, buffers, image, field, modes)?;
        let index = self.textures.len() as u32;
        self.textures.push(Texture {
            wrap: modes,
            ..decoded
        });
        self.texture_index.insert((image, modes), index);
        Ok(index)
    }

    /// `image` decoded (once per image), with wrap modes `modes`.
    fn decode(
        &mut self,
        ctx: &mut Ctx,
        doc: &gltf::Document,
        buffers: &Buffers,
        image: usize,
        field: &str,
        modes: [Wrap; 2],
    ) -> Result<Texture, SceneError> {
        if let Some(t) = self.decoded.get(&image) {
            return Ok(Texture {
                wrap: modes,
                ..t.clone()
            });
        }
        let data = image_bytes(ctx, doc, buffers, image)?;
        let texture =
            crate::scene::texture::decode(&data.bytes, &data.path, modes).map_err(|problem| {
                ctx.invalid(&format!("{field} ({})", data.field), &data.value, &problem)
            })?;
        self.decoded.insert(image, texture.clone());
        Ok(texture)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectrics_metals_and_roughness() {
        // A rough dielectric: 96% of the base colour diffuse, 4% specular, a broad lobe.
        let f = metallic_roughness(Vec3::new(0.5, 0.25, 1.0), 0.0, 1.0);
        assert_eq!(f.kd, Vec3::new(0.48, 0.24, 0.96));
        assert_eq!(f.ks, Vec3::splat(0.04));
        assert_eq!(f.ns, 0.0);
        assert!(!f.capped);
        // A metal: no diffuse part, the base colour specular.
        let f = metallic_roughness(Vec3::new(1.0, 0.77, 0.34), 1.0, 0.5);
        assert_eq!(f.kd, Vec3::ZERO);
        assert_eq!(f.ks, Vec3::new(1.0, 0.77, 0.34));
        // alpha = 0.25: Ns = (1 / 0.0625 - 1) / 2.
        assert_eq!(f.ns, 7.5);
        // Smooth surfaces are capped at a mirror's exponent.
        let f = metallic_roughness(Vec3::ONE, 1.0, 0.0);
        assert_eq!((f.ns, f.capped), (MIRROR_NS, true));
        // Kd + Ks <= 1 for every base colour and metallic in [0, 1].
        for b in [0.0, 0.3, 1.0] {
            for m in [0.0, 0.25, 0.5, 1.0] {
                let f = metallic_roughness(Vec3::splat(b), m, 0.5);
                assert!((f.kd + f.ks).max_element() <= 1.0 + 1e-6, "{b} {m}");
            }
        }
    }
}
