//! Why a scene did not load. Every message names the file, the field (TOML key path, MTL
//! material and key, OBJ line) and the offending value (docs/DESIGN.md principle 8).

/// A scene that could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file could not be read; `referenced_by` says which file and field named it.
    /// (The I/O error is in the message, not the source chain, which anyhow's `{:#}` would
    /// print a second time.)
    #[error("{path}: cannot read it ({referenced_by}): {error}")]
    Read {
        path: String,
        referenced_by: String,
        error: std::io::Error,
    },
    /// The scene file is not valid TOML or does not match the schema (unknown field, wrong
    /// type, missing field); `message` is toml's, with line and column.
    #[error("{file}: {message}")]
    Toml { file: String, message: String },
    /// A value out of its allowed range: a camera, light, environment or failure field, an MTL
    /// material's key (`field` = "material `name` Kd"), an EXR texel.
    #[error("{file}: {field} = {value}: {problem}")]
    Invalid {
        file: String,
        field: String,
        value: String,
        problem: String,
    },
    /// A line of an OBJ or MTL file that cannot be used (1-based `line`).
    #[error("{file} line {line}: {message}")]
    Line {
        file: String,
        line: usize,
        message: String,
    },
    /// A file that cannot be used as a whole (for example one tobj refuses).
    #[error("{file}: {message}")]
    File { file: String, message: String },
    /// Something the scene format names that irad does not load yet.
    #[error("{file}: {field} = {value}: {what} are not supported yet")]
    Unsupported {
        file: String,
        field: String,
        value: String,
        what: String,
    },
    /// No triangle left after loading.
    #[error("{file}: the scene has no triangles{detail}")]
    Empty { file: String, detail: String },
    /// Nothing emits light.
    #[error(
        "{file}: the scene has no light: no triangle with an emissive material (MTL Ke > 0), \
         no [[light]] with positive intensity and no [environment] with positive radiance"
    )]
    NoLight { file: String },
}

impl SceneError {
    /// An `Invalid` error with `suffix` after its field ("at animation frame 3"); others as
    /// they are.
    pub fn in_context(self, suffix: &str) -> SceneError {
        match self {
            SceneError::Invalid {
                file,
                field,
                value,
                problem,
            } => SceneError::Invalid {
                file,
                field: format!("{field} {suffix}"),
                value,
                problem,
            },
            other => other,
        }
    }
}
