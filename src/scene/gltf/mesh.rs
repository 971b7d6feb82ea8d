//! A mesh placed by a node, as world-space triangles: triangles, strips and fans (points and
//! lines skipped with a warning), positions and normals transformed by the node's world matrix
//! (normals by its inverse transpose), a mirroring transform's winding reversed so that the
//! front stays counter-clockwise, texture coordinates v-flipped into irad's convention.

use glam::{DMat3, DMat4, DVec3, Vec2, Vec3};
use gltf::mesh::{Mode, Semantic};

use super::data::{check_accessor, Buffers, INDICES, TEXCOORD, VEC3_F32};
use super::materials::Materials;
use super::Ctx;
use crate::scene::obj::MAX_COORDINATE;
use crate::scene::{SceneError, Triangle};

/// What placing a mesh adds to the scene.
#[derive(Default)]
pub struct Out {
    pub triangles: Vec<Triangle>,
    pub dropped: usize,
}

/// Adds `mesh`, placed by node `node` with `world`, to `out`.
#[allow(clippy::too_many_arguments)]
pub fn place(
    ctx: &mut Ctx,
    doc: &gltf::Document,
    buffers: &Buffers,
    materials: &mut Materials,
    mesh: &gltf::Mesh,
    node: &str,
    world: DMat4,
    out: &mut Out,
) -> Result<(), SceneError> {
    let linear = DMat3::from_mat4(world);
    let mirrored = linear.determinant() < 0.0;
    let normal_matrix = linear.inverse().transpose();
    for primitive in mesh.primitives() {
        let field = format!("meshes[{}].primitives[{}]", mesh.index(), primitive.index());
        let mode = primitive.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            ctx.warn(format!(
                "{field}: mode {mode:?} is skipped (irad renders triangles)"
            ));
            continue;
        }
        let Some(positions) = primitive.get(&Semantic::Positions) else {
            ctx.warn(format!("{field}: no POSITION attribute: skipped"));
            continue;
        };
        let attributes = format!("{field}.attributes");
        check_accessor(
            ctx,
            buffers,
            &positions,
            &format!("{attributes}.POSITION"),
            VEC3_F32,
        )?;
        let count = positions.count();
        let (material, set) = materials.get(ctx, doc, buffers, &primitive.material())?;
        let checked = |semantic: Semantic, name: &str, allowed| -> Result<bool, SceneError> {
            let Some(a) = primitive.get(&semantic) else {
                return Ok(false);
            };
            let field = format!("{attributes}.{name}");
            check_accessor(ctx, buffers, &a, &field, allowed)?;
            if a.count() != count {
                return Err(ctx.invalid(
                    &format!("{field} (accessors[{}])", a.index()),
                    &format!("count {}", a.count()),
                    &format!("differs from POSITION's count {count}"),
                ));
            }
            Ok(true)
        };
        let has_normals = checked(Semantic::Normals, "NORMAL", VEC3_F32)?;
        let has_uvs = checked(
            Semantic::TexCoords(set),
            &format!("TEXCOORD_{set}"),
            TEXCOORD,
        )?;
        if let Some(indices) = primitive.indices() {
            check_accessor(ctx, buffers, &indices, &format!("{field}.indices"), INDICES)?;
        }
        let textured = materials.list[material as usize].albedo_texture.is_some();
        if textured && !has_uvs {
            ctx.warn(format!(
                "{field}: its material's baseColorTexture reads TEXCOORD_{set}, which the \
                 primitive does not have: its texture coordinates are 0 (one texel's colour)"
            ));
        }
        let reader = primitive.reader(buffers.get());
        let missing = || {
            ctx.invalid(
                &field,
                "(unreadable)",
                "an accessor could not be read after its checks (a bug in irad)",
            )
        };
        let p: Vec<[f32; 3]> = reader.read_positions().ok_or_else(missing)?.collect();
        let n: Option<Vec<[f32; 3]>> = if has_normals {
            Some(reader.read_normals().ok_or_else(missing)?.collect())
        } else {
            None
        };
        let uv: Option<Vec<[f32; 2]>> = if has_uvs {
            Some(
                reader
                    .read_tex_coords(set)
                    .ok_or_else(missing)?
                    .into_f32()
                    .collect(),
            )
        } else {
            None
        };
        if let Some(bad) = uv
            .iter()
            .flatten()
            .find(|t| !t.iter().all(|x| x.is_finite()))
        {
            return Err(ctx.invalid(
                &format!("{attributes}.TEXCOORD_{set}"),
                &format!("{bad:?}"),
                "texture coordinates must be finite",
            ));
        }
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..count as u32).collect(),
        };
        if p.len() != count
            || n.as_ref().is_some_and(|n| n.len() != count)
            || uv.as_ref().is_some_and(|uv| uv.len() != count)
        {
            return Err(missing());
        }
        if let Some((k, bad)) = indices
            .iter()
            .enumerate()
            .find(|(_, &i)| i as usize >= count)
        {
            return Err(ctx.invalid(
                &format!("{field}.indices"),
                &format!("{bad} (index {k})"),
                &format!("past the {count} vertices"),
            ));
        }
        let corners = match mode {
            Mode::Triangles => {
                if indices.len() % 3 != 0 {
                    ctx.warn(format!(
                        "{field}: {} indices, not a multiple of 3: the last {} left out",
                        indices.len(),
                        indices.len() % 3
                    ));
                }
                indices
                    .chunks_exact(3)
                    .map(|c| [c[0], c[1], c[2]])
                    .collect()
            }
            // The specification's orders: strip triangle i is (i, i + 1 + i % 2, i + 2 - i % 2),
            // fan triangle i is (i + 1, i + 2, 0).
            Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
                .map(|i| {
                    let odd = i % 2;
                    [indices[i], indices[i + 1 + odd], indices[i + 2 - odd]]
                })
                .collect(),
            _ => (0..indices.len().saturating_sub(2))
                .map(|i| [indices[i + 1], indices[i + 2], indices[0]])
                .collect::<Vec<[u32; 3]>>(),
        };
        let world_p: Vec<Vec3> = p
            .iter()
            .map(|v| {
                world
                    .transform_point3(DVec3::from(v.map(f64::from)))
                    .as_vec3()
            })
            .collect();
        if let Some(bad) = world_p
            .iter()
            .find(|v| !v.is_finite() || v.abs().max_element() > MAX_COORDINATE)
        {
            return Err(ctx.invalid(
                &format!("{node} ({field})"),
                &format!("{bad}"),
                &format!(
                    "a vertex in the world is not finite or past {MAX_COORDINATE:e}, the most \
                     irad's f32 rays and BVH handle"
                ),
            ));
        }
        let world_n: Option<Vec<Vec3>> = n.map(|n| {
            n.iter()
                .map(|v| {
                    (normal_matrix * DVec3::from(v.map(f64::from)))
                        .normalize_or_zero()
                        .as_vec3()
                })
                .collect()
        });
        for mut c in corners {
            if mirrored {
                c.swap(1, 2);
            }
            let positions = c.map(|i| world_p[i as usize]);
            if crate::scene::load::is_degenerate(positions) {
                out.dropped += 1;
                continue;
            }
            let face = (positions[1] - positions[0])
                .cross(positions[2] - positions[0])
                .normalize_or_zero();
            let normals = match &world_n {
                Some(n) => c.map(|i| {
                    let v = n[i as usize];
                    if v == Vec3::ZERO || !v.is_finite() {
                        face
                    } else {
                        v
                    }
                }),
                None => [face; 3],
            };
            let uvs = match &uv {
                Some(uv) => c.map(|i| {
                    let [u, v] = uv[i as usize];
                    Vec2::new(u, 1.0 - v)
                }),
                None => [Vec2::ZERO; 3],
            };
            out.triangles.push(Triangle {
                positions,
                normals,
                material,
                uvs,
            });
        }
    }
    Ok(())
}
