//! Fixed-length arrays of TOML files read exactly. serde's `[T; N]` takes the first N items of
//! a longer TOML array and drops the rest without a word, so `position = [1, 2, 3, 4]` or
//! `resolution = [32, 32, 3]` would load as if the extra numbers were not there. Fields read
//! with `exact` (or `exact_opt` for an optional one) refuse any other length, and the TOML
//! parser's message names the file, line and key.

use serde::de::{Deserialize, Deserializer, Error};

/// `[T; N]` from an array of exactly N items (`#[serde(deserialize_with = "exact")]`).
pub fn exact<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    let items = Vec::<T>::deserialize(d)?;
    let len = items.len();
    items
        .try_into()
        .map_err(|_| D::Error::invalid_length(len, &format!("an array of {N} items").as_str()))
}

/// An optional `[T; N]` from an array of exactly N items
/// (`#[serde(default, deserialize_with = "exact_opt")]`).
pub fn exact_opt<'de, D, T, const N: usize>(d: D) -> Result<Option<[T; N]>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    exact(d).map(Some)
}

#[cfg(test)]
mod tests {
    use serde::Deserialize;

    #[derive(Debug, Deserialize)]
    struct Fields {
        #[serde(deserialize_with = "super::exact")]
        position: [f32; 3],
        #[serde(default, deserialize_with = "super::exact_opt")]
        size: Option<[i64; 2]>,
    }

    fn parse(text: &str) -> Result<Fields, String> {
        toml::from_str(text).map_err(|e| e.to_string())
    }

    #[test]
    fn arrays_of_the_right_length_are_read() {
        let f = parse("position = [1, 2, 3]\nsize = [4, 5]").unwrap();
        assert_eq!((f.position, f.size), ([1.0, 2.0, 3.0], Some([4, 5])));
        assert_eq!(parse("position = [1, 2, 3]").unwrap().size, None);
    }

    #[test]
    fn arrays_too_long_or_too_short_are_refused_with_their_key() {
        for (text, len) in [
            ("position = [1, 2, 3, 4]", 4),
            ("position = [1, 2]", 2),
            ("position = [1, 2, 3]\nsize = [32, 32, 3]", 3),
            ("position = [1, 2, 3]\nsize = [32]", 1),
        ] {
            let e = parse(text).unwrap_err();
            assert!(
                e.contains(&format!("invalid length {len}")) && e.contains("expected an array of"),
                "{text}: {e}"
            );
            let key = if text.contains("size") {
                "size"
            } else {
                "position"
            };
            assert!(e.contains(key), "{text}: {e}");
        }
    }
}
