//! The GLSL -> SPIR-V toolchain: glslangValidator compiles glsl/<name>.comp into
//! spv/<name>.spv (committed, embedded by build.rs) and spirv-val checks every module.
//!
//! Target env vulkan1.1 (SPIR-V 1.3): from SPIR-V 1.4 on glslang emits OpCopyLogical, which
//! naga's reflection rejects (docs/DESIGN.md "naga's limits").

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};

pub const TARGET_ENV: &str = "vulkan1.1";

/// A source tree with glsl/ (kernels), glsl/include/ (shared code) and spv/ (compiled).
pub struct ShaderTree {
    pub root: PathBuf,
}

impl ShaderTree {
    /// The checkout irad was built from.
    pub fn source_checkout() -> Self {
        ShaderTree {
            root: PathBuf::from(env!("CARGO_MANIFEST_DIR")),
        }
    }

    pub fn glsl_dir(&self) -> PathBuf {
        self.root.join("glsl")
    }

    pub fn spv_dir(&self) -> PathBuf {
        self.root.join("spv")
    }

    /// Every kernel: the stems of glsl/*.comp, sorted.
    pub fn kernel_names(&self) -> Result<Vec<String>> {
        stems(&self.glsl_dir(), "comp")
    }

    /// Compiles glsl/<name>.comp into `out`.
    pub fn compile(&self, name: &str, out: &Path) -> Result<()> {
        let source = self.glsl_dir().join(format!("{name}.comp"));
        let include = format!("-I{}", self.glsl_dir().join("include").display());
        let output = Command::new("glslangValidator")
            .args(["-V", "--target-env", TARGET_ENV, &include, "-o"])
            .arg(out)
            .arg(&source)
            .output()
            .map_err(|e| missing_tool("glslangValidator", "glslang-tools", e))?;
        if !output.status.success() {
            bail!(
                "glslangValidator failed on {}:\n{}{}",
                source.display(),
                String::from_utf8_lossy(&output.stdout),
                String::from_utf8_lossy(&output.stderr)
            );
        }
        Ok(())
    }

    /// Rebuilds spv/ from glsl/: compiles and validates every kernel, removes modules whose
    /// GLSL is gone. Returns the kernels built.
    pub fn rebuild(&self) -> Result<Vec<String>> {
        let names = self.kernel_names()?;
        std::fs::create_dir_all(self.spv_dir())
            .with_context(|| format!("creating {}", self.spv_dir().display()))?;
        for name in &names {
            let out = self.spv_dir().join(format!("{name}.spv"));
            self.compile(name, &out)?;
            validate(&out)?;
        }
        for orphan in stems(&self.spv_dir(), "spv")?
            .into_iter()
            .filter(|s| !names.contains(s))
        {
            let path = self.spv_dir().join(format!("{orphan}.spv"));
            std::fs::remove_file(&path).with_context(|| format!("removing {}", path.display()))?;
        }
        Ok(names)
    }

    /// What is out of sync between glsl/ and spv/: one line per stale, missing or orphan module
    /// (empty when in sync). Compiles into a temporary folder; spv/ is not touched.
    pub fn check(&self) -> Result<Vec<String>> {
        let names = self.kernel_names()?;
        let scratch = std::env::temp_dir().join(format!(
            "irad-shaders-{}-{}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.as_nanos())
                .unwrap_or(0)
        ));
        std::fs::create_dir_all(&scratch)
            .with_context(|| format!("creating {}", scratch.display()))?;
        let result = (|| {
            let mut problems = Vec::new();
            for name in &names {
                let committed = self.spv_dir().join(format!("{name}.spv"));
                let fresh = scratch.join(format!("{name}.spv"));
                self.compile(name, &fresh)?;
                match std::fs::read(&committed) {
                    Err(_) => problems.push(format!(
                        "spv/{name}.spv is missing (glsl/{name}.comp has no module)"
                    )),
                    Ok(bytes) if bytes != std::fs::read(&fresh)? => problems.push(format!(
                        "spv/{name}.spv is stale against glsl/{name}.comp or its includes"
                    )),
                    Ok(_) => {}
                }
            }
            for orphan in stems(&self.spv_dir(), "spv")?
                .into_iter()
                .filter(|s| !names.contains(s))
            {
                problems.push(format!("spv/{orphan}.spv has no glsl/{orphan}.comp"));
            }
            Ok(problems)
        })();
        let _ = std::fs::remove_dir_all(&scratch);
        result
    }
}

/// Runs spirv-val on one module.
pub fn validate(module: &Path) -> Result<()> {
    let output = Command::new("spirv-val")
        .args(["--target-env", TARGET_ENV])
        .arg(module)
        .output()
        .map_err(|e| missing_tool("spirv-val", "spirv-tools", e))?;
    if !output.status.success() {
        bail!(
            "spirv-val rejected {}:\n{}{}",
            module.display(),
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr)
        );
    }
    Ok(())
}

/// Whether a tool answers `--version` (glslangValidator, spirv-val).
#[allow(dead_code)] // tests/shaders.rs compiles this file in and asks
pub fn tool_available(tool: &str) -> bool {
    Command::new(tool)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

fn missing_tool(tool: &str, package: &str, e: std::io::Error) -> anyhow::Error {
    anyhow::anyhow!("{tool} could not be run ({e}): install it with `apt-get install {package}`")
}

fn stems(dir: &Path, extension: &str) -> Result<Vec<String>> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.extension().is_some_and(|x| x == extension))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort();
    Ok(names)
}
