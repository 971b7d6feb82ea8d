//! A glTF file's binary data: its buffers (the GLB's BIN chunk, data: URIs, files beside the
//! glTF), image bytes, and accessors, checked against their buffers before the `gltf` crate's
//! reader reads them (it slices and asserts without checking sizes first).

use gltf::accessor::{DataType, Dimensions};
use gltf::Document;

use super::uri::{self, Target};
use super::Ctx;
use crate::scene::SceneError;

/// Every buffer's bytes, by index.
pub struct Buffers(pub Vec<Vec<u8>>);

impl Buffers {
    /// Reads every buffer; `bin` is the GLB's BIN chunk.
    pub fn load(ctx: &mut Ctx, doc: &Document, bin: Option<&[u8]>) -> Result<Buffers, SceneError> {
        let mut all = Vec::new();
        for buffer in doc.buffers() {
            let field = format!("buffers[{}]", buffer.index());
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => match bin {
                    Some(b) => b.to_vec(),
                    None => {
                        return Err(ctx.invalid(
                            &format!("{field}.uri"),
                            "(none)",
                            "a buffer without a uri is a .glb's BIN chunk, and this file has \
                             none",
                        ))
                    }
                },
                gltf::buffer::Source::Uri(u) => ctx.read_uri(&format!("{field}.uri"), u)?,
            };
            if data.len() < buffer.length() {
                return Err(ctx.invalid(
                    &format!("{field}.byteLength"),
                    &buffer.length().to_string(),
                    &format!("the buffer's data has only {} bytes", data.len()),
                ));
            }
            all.push(data);
        }
        Ok(Buffers(all))
    }

    /// The bytes of buffer view `view`, checked to lie in its buffer.
    pub fn view<'s>(
        &'s self,
        ctx: &Ctx,
        view: &gltf::buffer::View,
    ) -> Result<&'s [u8], SceneError> {
        let buffer = &self.0[view.buffer().index()];
        let end = view.offset().checked_add(view.length());
        match end.filter(|&e| e <= view.buffer().length()) {
            Some(end) => Ok(&buffer[view.offset()..end]),
            None => Err(ctx.invalid(
                &format!("bufferViews[{}]", view.index()),
                &format!(
                    "byteOffset {} + byteLength {}",
                    view.offset(),
                    view.length()
                ),
                &format!(
                    "runs past the end of buffers[{}] ({} bytes)",
                    view.buffer().index(),
                    view.buffer().length()
                ),
            )),
        }
    }

    /// The reader's access to the buffers.
    pub fn get<'s>(&'s self) -> impl Clone + Fn(gltf::Buffer) -> Option<&'s [u8]> {
        move |b: gltf::Buffer| self.0.get(b.index()).map(Vec::as_slice)
    }
}

impl Ctx {
    /// The bytes a URI names (a data: URI's, or a file's, hashed); `field` names it.
    pub fn read_uri(&mut self, field: &str, u: &str) -> Result<Vec<u8>, SceneError> {
        match uri::resolve(u, &self.base) {
            Ok(Target::Data(bytes)) => Ok(bytes),
            Ok(Target::File(path)) => {
                let bytes = std::fs::read(&path).map_err(|error| SceneError::Read {
                    path: path.display().to_string(),
                    referenced_by: format!("{}: {field} = {}", self.file, uri::shown(u)),
                    error,
                })?;
                self.hash.write(&bytes);
                Ok(bytes)
            }
            Err(problem) => Err(self.invalid(field, &uri::shown(u), &problem)),
        }
    }
}

/// An image's encoded bytes and where they came from.
pub struct ImageData {
    pub bytes: Vec<u8>,
    /// Its file, or the glTF file with `#images[i]` for embedded data.
    pub path: std::path::PathBuf,
    /// `images[i].uri` or `images[i].bufferView`, and its value as written.
    pub field: String,
    pub value: String,
}

/// The encoded bytes of `images[index]` (read from the JSON: the crate's `Image::source`
/// panics on an image with neither a uri nor a bufferView and mimeType).
pub fn image_bytes(
    ctx: &mut Ctx,
    doc: &gltf::Document,
    buffers: &Buffers,
    index: usize,
) -> Result<ImageData, SceneError> {
    let field = format!("images[{index}]");
    let embedded = std::path::PathBuf::from(format!("{}#{field}", ctx.file));
    let json = &doc.as_json().images[index];
    match (&json.buffer_view, &json.uri) {
        (Some(view), _) => {
            let view = doc.views().nth(view.value()).ok_or_else(|| {
                ctx.invalid(
                    &format!("{field}.bufferView"),
                    &view.value().to_string(),
                    "names no buffer view of the file",
                )
            })?;
            Ok(ImageData {
                bytes: buffers.view(ctx, &view)?.to_vec(),
                path: embedded,
                field: format!("{field}.bufferView"),
                value: view.index().to_string(),
            })
        }
        (None, Some(u)) => {
            let field = format!("{field}.uri");
            let bytes = ctx.read_uri(&field, u)?;
            let path = match uri::resolve(u, &ctx.base) {
                Ok(Target::File(p)) => p,
                _ => embedded,
            };
            Ok(ImageData {
                bytes,
                path,
                field,
                value: uri::shown(u),
            })
        }
        (None, None) => Err(ctx.invalid(
            &field,
            "(no uri, no bufferView)",
            "an image needs one of them",
        )),
    }
}

/// Checks that `accessor` (named `field`) has one of the `allowed` layouts and that all of its
/// elements, and its sparse indices and values, lie inside their buffer views and buffers; its
/// count is at least 1.
pub fn check_accessor(
    ctx: &Ctx,
    buffers: &Buffers,
    accessor: &gltf::Accessor,
    field: &str,
    allowed: &[(Dimensions, DataType)],
) -> Result<(), SceneError> {
    let name = format!("{field} (accessors[{}])", accessor.index());
    let layout = (accessor.dimensions(), accessor.data_type());
    if !allowed.contains(&layout) {
        let list: Vec<String> = allowed
            .iter()
            .map(|(d, t)| format!("{d:?} {t:?}"))
            .collect();
        return Err(ctx.invalid(
            &name,
            &format!("{:?} {:?}", layout.0, layout.1),
            &format!("irad reads {} here", list.join(" or ")),
        ));
    }
    if accessor.count() == 0 {
        return Err(ctx.invalid(&name, "count 0", "an accessor has at least one element"));
    }
    let size = accessor.size();
    let span = |view: &gltf::buffer::View,
                offset: usize,
                count: usize,
                size: usize,
                what: &str|
     -> Result<(), SceneError> {
        let data = buffers.view(ctx, view)?;
        let stride = view.stride().unwrap_or(size);
        if stride < size {
            return Err(ctx.invalid(
                &format!("bufferViews[{}].byteStride", view.index()),
                &stride.to_string(),
                &format!("smaller than the {size}-byte elements of {name}"),
            ));
        }
        let end = stride
            .checked_mul(count - 1)
            .and_then(|s| s.checked_add(size))
            .and_then(|s| s.checked_add(offset));
        match end {
            Some(end) if end <= data.len() => Ok(()),
            _ => Err(ctx.invalid(
                &name,
                &format!("{what}count {count} from byteOffset {offset}, stride {stride}"),
                &format!(
                    "runs past the end of bufferViews[{}] ({} bytes)",
                    view.index(),
                    data.len()
                ),
            )),
        }
    };
    match accessor.view() {
        Some(view) => span(&view, accessor.offset(), accessor.count(), size, "")?,
        None if accessor.sparse().is_none() => {
            return Err(ctx.invalid(
                &name,
                "(no bufferView)",
                "all zeros by the specification, which irad does not read",
            ))
        }
        None => {}
    }
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        if n == 0 {
            return Err(ctx.invalid(&name, "sparse.count 0", "a sparse accessor has at least 1"));
        }
        let indices = sparse.indices();
        let index_size = match indices.index_type() {
            gltf::accessor::sparse::IndexType::U8 => 1,
            gltf::accessor::sparse::IndexType::U16 => 2,
            gltf::accessor::sparse::IndexType::U32 => 4,
        };
        span(
            &indices.view(),
            indices.offset(),
            n,
            index_size,
            "sparse.indices ",
        )?;
        let values = sparse.values();
        span(&values.view(), values.offset(), n, size, "sparse.values ")?;
    }
    Ok(())
}

/// The layouts irad reads for each attribute.
pub const VEC3_F32: &[(Dimensions, DataType)] = &[(Dimensions::Vec3, DataType::F32)];
pub const TEXCOORD: &[(Dimensions, DataType)] = &[
    (Dimensions::Vec2, DataType::F32),
    (Dimensions::Vec2, DataType::U8),
    (Dimensions::Vec2, DataType::U16),
];
pub const INDICES: &[(Dimensions, DataType)] = &[
    (Dimensions::Scalar, DataType::U8),
    (Dimensions::Scalar, DataType::U16),
    (Dimensions::Scalar, DataType::U32),
];
