//! The `[failure]` table of a stability-suite scene (scenes/failure/) checked and turned into a
//! `FailureNote`. Method names are kept as written: the scene loader does not know the methods.

use super::file::FailureFile;
use super::{FailureNote, SceneError};

pub fn build(file: &str, f: &FailureFile) -> Result<FailureNote, SceneError> {
    let invalid = |field: String, value: String, problem: &str| SceneError::Invalid {
        file: file.to_string(),
        field,
        value,
        problem: problem.to_string(),
    };
    if f.methods.is_empty() {
        return Err(invalid(
            "failure.methods".into(),
            "[]".into(),
            "must name at least one method expected to fail",
        ));
    }
    if let Some(i) = f.methods.iter().position(|m| m.trim().is_empty()) {
        return Err(invalid(
            format!("failure.methods[{i}]"),
            format!("{:?}", f.methods[i]),
            "must be a method name (as `irad render --method` spells it)",
        ));
    }
    for (field, value, problem) in [
        (
            "why",
            &f.why,
            "must say in a sentence or two why the methods fail",
        ),
        (
            "source",
            &f.source,
            "must name the paper figure the scene reproduces",
        ),
    ] {
        if value.trim().is_empty() {
            return Err(invalid(
                format!("failure.{field}"),
                format!("{value:?}"),
                problem,
            ));
        }
    }
    Ok(FailureNote {
        methods: f.methods.clone(),
        why: f.why.clone(),
        source: f.source.clone(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn good() -> FailureFile {
        FailureFile {
            methods: vec!["ir".into()],
            why: "light-side VPLs starve.".into(),
            source: "Segovia 06, Fig. 4".into(),
        }
    }

    #[test]
    fn a_good_table_is_kept_as_written() {
        let note = build("s.toml", &good()).unwrap();
        assert_eq!(
            note,
            FailureNote {
                methods: vec!["ir".into()],
                why: "light-side VPLs starve.".into(),
                source: "Segovia 06, Fig. 4".into(),
            }
        );
    }

    #[test]
    fn empty_values_are_named() {
        let cases = [
            (
                FailureFile {
                    methods: vec![],
                    ..good()
                },
                "s.toml: failure.methods = []: ",
            ),
            (
                FailureFile {
                    methods: vec!["ir".into(), " ".into()],
                    ..good()
                },
                "s.toml: failure.methods[1] = \" \": ",
            ),
            (
                FailureFile {
                    why: String::new(),
                    ..good()
                },
                "s.toml: failure.why = \"\": ",
            ),
            (
                FailureFile {
                    source: "\n".into(),
                    ..good()
                },
                "s.toml: failure.source = \"\\n\": ",
            ),
        ];
        for (f, expected) in cases {
            let m = build("s.toml", &f).unwrap_err().to_string();
            assert!(m.starts_with(expected), "{m}");
        }
    }
}
