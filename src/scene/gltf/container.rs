//! The two glTF containers: a `.gltf` is the JSON itself; a `.glb` (recognised by its `glTF`
//! magic, whatever its name) is a 12-byte header (magic, version 2, total length) and chunks
//! of (length, type, data): the JSON chunk first, then an optional BIN chunk, the data of the
//! buffer that has no `uri`. Chunks of other types are skipped, as the specification asks.

/// The JSON text and the BIN chunk's bytes of a glTF file.
#[derive(Debug, PartialEq)]
pub struct Parts<'a> {
    pub json: &'a [u8],
    pub bin: Option<&'a [u8]>,
}

/// A field of the binary layout that is wrong: (field, value, problem).
pub type Fault = (String, String, String);

const JSON: u32 = 0x4E4F_534A;
const BIN: u32 = 0x004E_4942;

/// Whether `bytes` are a binary glTF (by their magic).
pub fn is_glb(bytes: &[u8]) -> bool {
    bytes.starts_with(b"glTF")
}

/// Splits a file into its parts; `glb_by_name` says the file is named `.glb`, so that anything
/// but a GLB header is an error rather than JSON.
pub fn split(bytes: &[u8], glb_by_name: bool) -> Result<Parts<'_>, Fault> {
    if !is_glb(bytes) {
        if glb_by_name {
            let magic: Vec<u8> = bytes.iter().copied().take(4).collect();
            return Err((
                "GLB header magic".into(),
                format!("{:?}", String::from_utf8_lossy(&magic)),
                "a .glb file starts with \"glTF\"".into(),
            ));
        }
        return Ok(Parts {
            json: bytes,
            bin: None,
        });
    }
    let fault = |field: &str, value: String, problem: String| -> Fault {
        (field.to_string(), value, problem)
    };
    if bytes.len() < 12 {
        return Err(fault(
            "GLB header",
            format!("{} bytes", bytes.len()),
            "the file ends inside the 12-byte header".into(),
        ));
    }
    let word =
        |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let version = word(4);
    if version != 2 {
        return Err(fault(
            "GLB header version",
            version.to_string(),
            "irad reads glTF 2.0 binaries (version 2)".into(),
        ));
    }
    let length = word(8) as usize;
    if length > bytes.len() || length < 12 {
        return Err(fault(
            "GLB header length",
            length.to_string(),
            format!(
                "the file has {} bytes (the length counts the whole file, header included)",
                bytes.len()
            ),
        ));
    }
    let body = &bytes[..length];
    let mut at = 12;
    let (mut json, mut bin) = (None, None);
    let mut k = 0;
    while at < body.len() {
        if body.len() - at < 8 {
            return Err(fault(
                &format!("GLB chunk {k}"),
                format!("{} bytes left", body.len() - at),
                "the file ends inside an 8-byte chunk header".into(),
            ));
        }
        let (size, kind) = (word(at) as usize, word(at + 4));
        let start = at + 8;
        if size > body.len() - start {
            return Err(fault(
                &format!("GLB chunk {k} length"),
                size.to_string(),
                format!("only {} bytes follow its header", body.len() - start),
            ));
        }
        let data = &body[start..start + size];
        match (k, kind) {
            (0, JSON) => json = Some(data),
            (0, _) => {
                return Err(fault(
                    "GLB chunk 0 type",
                    format!("{:?}", String::from_utf8_lossy(&kind.to_le_bytes())),
                    "the first chunk must be the JSON chunk (\"JSON\")".into(),
                ))
            }
            (_, BIN) if bin.is_none() => bin = Some(data),
            _ => {}
        }
        // Chunks start on 4-byte boundaries.
        at = (start + size).div_ceil(4) * 4;
        k += 1;
    }
    let json = json.ok_or_else(|| {
        fault(
            "GLB chunk 0",
            "(none)".into(),
            "the file has no JSON chunk".into(),
        )
    })?;
    Ok(Parts { json, bin })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A GLB of `json` and an optional BIN chunk, each padded to 4 bytes.
    pub fn glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
        let mut out = Vec::new();
        let mut chunk = |data: &[u8], kind: &[u8; 4], pad: u8| {
            let mut d = data.to_vec();
            while d.len() % 4 != 0 {
                d.push(pad);
            }
            out.extend((d.len() as u32).to_le_bytes());
            out.extend(kind);
            out.extend(d);
        };
        chunk(json, b"JSON", b' ');
        if let Some(b) = bin {
            chunk(b, b"BIN\0", 0);
        }
        let mut file = b"glTF".to_vec();
        file.extend(2u32.to_le_bytes());
        file.extend(((out.len() + 12) as u32).to_le_bytes());
        file.extend(out);
        file
    }

    #[test]
    fn json_files_pass_through_and_glbs_split() {
        let text = br#"{"asset":{"version":"2.0"}}"#;
        assert_eq!(split(text, false).unwrap().json, text);
        let file = glb(b"{}", Some(&[1, 2, 3]));
        let parts = split(&file, true).unwrap();
        assert_eq!(parts.json, b"{}  ");
        assert_eq!(parts.bin, Some(&[1u8, 2, 3, 0][..]));
        let bare = glb(b"{}", None);
        assert_eq!(split(&bare, false).unwrap().bin, None);
    }

    #[test]
    fn bad_headers_name_the_field() {
        let field = |bytes: &[u8]| split(bytes, true).unwrap_err().0;
        assert_eq!(field(b"{\"asset\":1}"), "GLB header magic");
        assert_eq!(field(b"glTF\x02\0\0"), "GLB header");
        let mut v1 = glb(b"{}", None);
        v1[4] = 1;
        assert_eq!(
            split(&v1, true).unwrap_err(),
            (
                "GLB header version".to_string(),
                "1".to_string(),
                "irad reads glTF 2.0 binaries (version 2)".to_string()
            )
        );
        let mut long = glb(b"{}", None);
        long[8] = 200;
        assert_eq!(field(&long), "GLB header length");
        let mut chunk = glb(b"{}", None);
        chunk[12] = 100;
        assert_eq!(field(&chunk), "GLB chunk 0 length");
        let mut kind = glb(b"{}", None);
        kind[16..20].copy_from_slice(b"BIN\0");
        assert_eq!(field(&kind), "GLB chunk 0 type");
        let mut bare = b"glTF".to_vec();
        bare.extend(2u32.to_le_bytes());
        bare.extend(12u32.to_le_bytes());
        assert_eq!(field(&bare), "GLB chunk 0");
    }
}
