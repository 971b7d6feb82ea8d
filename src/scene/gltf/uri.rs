//! glTF URIs: `data:` URIs (base64 or percent-encoded, RFC 2397) decoded in memory, and relative
//! references (percent-encoded, RFC 3986) resolved against the glTF file's folder. Other schemes
//! (`http:`, `file:`) are refused: a scene's files sit beside it.

use std::path::{Path, PathBuf};

/// Where a URI's bytes are.
#[derive(Debug, PartialEq)]
pub enum Target {
    /// The bytes of a `data:` URI.
    Data(Vec<u8>),
    /// A file relative to the glTF file's folder.
    File(PathBuf),
}

/// Resolves `uri` against `base`. The error says what is wrong with the URI.
pub fn resolve(uri: &str, base: &Path) -> Result<Target, String> {
    if let Some(rest) = strip_prefix_ignore_case(uri, "data:") {
        return data(rest).map(Target::Data);
    }
    // A scheme is letters, digits, `+`, `-`, `.` before the first `:`, and comes before any
    // `/`, `?` or `#` (RFC 3986 4.2: a relative path's first segment has no colon).
    if let Some(colon) = uri.find(':') {
        let scheme = &uri[..colon];
        let is_scheme = scheme.len() > 1
            && scheme.starts_with(|c: char| c.is_ascii_alphabetic())
            && scheme
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'));
        if is_scheme {
            return Err(format!(
                "a `{scheme}:` URI: irad reads data: URIs and files relative to the glTF file"
            ));
        }
    }
    // A query or fragment names no part of a file.
    let path = uri.split(['?', '#']).next().unwrap_or("");
    if path.is_empty() {
        return Err("an empty URI".into());
    }
    let bytes = percent_decode(path)?;
    let text = String::from_utf8(bytes)
        .map_err(|_| "its percent-decoded path is not UTF-8".to_string())?;
    Ok(Target::File(base.join(text)))
}

fn strip_prefix_ignore_case<'a>(text: &'a str, prefix: &str) -> Option<&'a str> {
    let head = text.get(..prefix.len())?;
    head.eq_ignore_ascii_case(prefix)
        .then(|| &text[prefix.len()..])
}

/// The bytes of a data URI after its `data:`: `[mediatype][;base64],payload`.
fn data(rest: &str) -> Result<Vec<u8>, String> {
    let comma = rest
        .find(',')
        .ok_or("a data: URI without the `,` before its data")?;
    let (header, payload) = (&rest[..comma], &rest[comma + 1..]);
    let is_base64 = header
        .rsplit(';')
        .next()
        .is_some_and(|p| p.eq_ignore_ascii_case("base64"));
    if is_base64 {
        base64(payload)
    } else {
        percent_decode(payload)
    }
}

/// Standard base64 (RFC 4648 section 4: `A-Z a-z 0-9 + /`), `=` padding optional.
pub fn base64(text: &str) -> Result<Vec<u8>, String> {
    let bytes = text.as_bytes();
    let padding = bytes.iter().rev().take_while(|&&c| c == b'=').count();
    if padding > 2 {
        return Err(format!("base64 ends in {padding} `=`; at most 2 pad it"));
    }
    let body = &bytes[..bytes.len() - padding];
    if padding > 0 && bytes.len() % 4 != 0 {
        return Err(format!(
            "padded base64 of {} characters, not a multiple of 4",
            bytes.len()
        ));
    }
    if body.len() % 4 == 1 {
        return Err(format!(
            "base64 of {} characters (without padding) is not a whole number of bytes",
            body.len()
        ));
    }
    let mut out = Vec::with_capacity(body.len() / 4 * 3 + 2);
    let (mut acc, mut bits) = (0u32, 0u32);
    for (i, &c) in body.iter().enumerate() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => {
                let shown: String = text[i..].chars().take(1).collect();
                return Err(format!(
                    "{shown:?} at character {i} of the data is not base64 (A-Z, a-z, 0-9, +, /)"
                ));
            }
        };
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Ok(out)
}

/// `%XX` escapes decoded to their bytes; other characters kept as their UTF-8.
pub fn percent_decode(text: &str) -> Result<Vec<u8>, String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = bytes
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| format!("`%` at character {i} is not followed by two hex digits"))?;
            out.push(hex);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    Ok(out)
}

/// `uri` for a message: a data URI cut after its first 40 characters.
pub fn shown(uri: &str) -> String {
    match uri.char_indices().nth(40) {
        Some((cut, _)) if uri.len() > 48 => {
            format!(
                "{:?} ({} characters)",
                format!("{}...", &uri[..cut]),
                uri.len()
            )
        }
        _ => format!("{uri:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_rfc4648_vectors() {
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(coded).unwrap(), plain.as_bytes(), "{coded}");
            // Unpadded is read too.
            assert_eq!(
                base64(coded.trim_end_matches('=')).unwrap(),
                plain.as_bytes()
            );
        }
        assert_eq!(base64("+/8=").unwrap(), [0xfb, 0xff]);
    }

    #[test]
    fn bad_base64_is_refused_by_position() {
        let e = base64("Zm9v!mFy").unwrap_err();
        assert!(e.contains("\"!\" at character 4"), "{e}");
        assert!(base64("Zm9vY").unwrap_err().contains("not a whole number"));
        assert!(base64("Zg=").unwrap_err().contains("multiple of 4"));
        assert!(base64("Z===").is_err());
        assert!(base64("Zg==Zg==").is_err());
    }

    #[test]
    fn data_uris_and_relative_paths() {
        let base = Path::new("scenes/x");
        assert_eq!(
            resolve("data:application/octet-stream;base64,Zm9v", base).unwrap(),
            Target::Data(b"foo".to_vec())
        );
        assert_eq!(
            resolve("data:text/plain,a%20b", base).unwrap(),
            Target::Data(b"a b".to_vec())
        );
        assert_eq!(
            resolve("DATA:;BASE64,Zm8=", base).unwrap(),
            Target::Data(b"fo".to_vec())
        );
        assert_eq!(
            resolve("my%20mesh.bin", base).unwrap(),
            Target::File(base.join("my mesh.bin"))
        );
        assert_eq!(
            resolve("textures/a.png?v=2", base).unwrap(),
            Target::File(base.join("textures/a.png"))
        );
        assert!(resolve("data:base64", base).unwrap_err().contains("`,`"));
        assert!(resolve("https://example.com/a.bin", base)
            .unwrap_err()
            .contains("`https:`"));
        assert!(resolve("a%2.bin", base)
            .unwrap_err()
            .contains("two hex digits"));
        assert!(resolve("", base).is_err());
    }

    #[test]
    fn long_uris_are_cut_in_messages() {
        assert_eq!(shown("a.bin"), "\"a.bin\"");
        let long = format!("data:application/octet-stream;base64,{}", "A".repeat(100));
        let s = shown(&long);
        assert!(s.contains("...") && s.contains("(137 characters)"), "{s}");
    }
}
