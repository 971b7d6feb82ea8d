//! Environment switches (IRAD_VALIDATE, IRAD_FORCE_STAGING) read by their value, the way a
//! user means them: `1`, `true`, `yes` (any case) turn a switch on; unset, empty, `0`,
//! `false`, `no` leave it off; anything else is an error naming the variable, so
//! `IRAD_FORCE_STAGING=false` cannot force staging by being present.

use super::error::{GpuError, GpuResult};

/// `value` of the switch `name`, or an error naming both.
pub fn parse(name: &str, value: &str) -> GpuResult<bool> {
    match value.trim().to_ascii_lowercase().as_str() {
        "1" | "true" | "yes" => Ok(true),
        "" | "0" | "false" | "no" => Ok(false),
        _ => Err(GpuError::EnvSwitch {
            name: name.to_string(),
            value: value.to_string(),
        }),
    }
}

/// The switch `name` as the environment sets it (unset: off).
pub fn read(name: &str) -> GpuResult<bool> {
    match std::env::var(name) {
        Ok(v) => parse(name, &v),
        Err(std::env::VarError::NotPresent) => Ok(false),
        Err(std::env::VarError::NotUnicode(v)) => Err(GpuError::EnvSwitch {
            name: name.to_string(),
            value: v.to_string_lossy().into_owned(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_read_not_presence() {
        for on in ["1", "true", "TRUE", "yes", "Yes", " 1 "] {
            assert!(parse("IRAD_X", on).unwrap(), "{on}");
        }
        for off in ["", "0", "false", "False", "no", "NO", " "] {
            assert!(!parse("IRAD_X", off).unwrap(), "{off:?}");
        }
        for junk in ["junk", "2", "on", "off", "y", "-1"] {
            let e = parse("IRAD_X", junk).unwrap_err().to_string();
            assert!(
                e.starts_with(&format!("IRAD_X={junk}:")) && e.contains("1, true or yes"),
                "{e}"
            );
        }
    }
}
