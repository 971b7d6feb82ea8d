//! The GLSL -> SPIR-V toolchain: glslangValidator compiles glsl/<group>/<name>.comp into
//! spv/<group>/<name>.spv (committed, embedded by build.rs) and spirv-val checks every module.
//! A group is the folder of the method a kernel belongs to (glsl/ir, glsl/bir, ...; glsl/shared
//! for passes several methods record, glsl/gpu for the GPU core's own); glsl/include holds the
//! included code. Kernel names are unique across groups: kernels are built by name.
//!
//! Target env vulkan1.1 (SPIR-V 1.3): from SPIR-V 1.4 on glslang emits OpCopyLogical, which
//! naga's reflection rejects (docs/DESIGN.md "naga's limits").

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};

pub const TARGET_ENV: &str = "vulkan1.1";

/// A source tree with glsl/<group>/ (kernels), glsl/include/ (shared code) and spv/<group>/
/// (compiled).
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

    /// Every kernel: the stems of glsl/<group>/*.comp, sorted.
    pub fn kernel_names(&self) -> Result<Vec<String>> {
        Ok(self.kernels()?.into_iter().map(|(name, _)| name).collect())
    }

    /// Every kernel by name with its path under glsl/ and spv/ without the extension
    /// (`envmap/shade_env`), sorted by name; two kernels of one name are an error.
    pub fn kernels(&self) -> Result<Vec<(String, PathBuf)>> {
        let mut kernels = grouped_stems(&self.glsl_dir(), "comp", &["include"])?;
        kernels.sort();
        if let Some(w) = kernels.windows(2).find(|w| w[0].0 == w[1].0) {
            bail!(
                "two kernels named {}: glsl/{}.comp and glsl/{}.comp (kernels are built by name)",
                w[0].0,
                w[0].1.display(),
                w[1].1.display()
            );
        }
        Ok(kernels)
    }

    /// spv/<group>/<name>.spv of a kernel at `relative` (`kernels`).
    pub fn spv_path(&self, relative: &Path) -> PathBuf {
        self.spv_dir().join(relative).with_extension("spv")
    }

    /// Compiles glsl/<relative>.comp into `out`.
    pub fn compile(&self, relative: &Path, out: &Path) -> Result<()> {
        let source = self.glsl_dir().join(relative).with_extension("comp");
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
        let kernels = self.kernels()?;
        for (_, relative) in &kernels {
            let out = self.spv_path(relative);
            let folder = out.parent().unwrap_or(&out).to_path_buf();
            std::fs::create_dir_all(&folder)
                .with_context(|| format!("creating {}", folder.display()))?;
            self.compile(relative, &out)?;
            validate(&out)?;
        }
        let wanted: Vec<&PathBuf> = kernels.iter().map(|(_, r)| r).collect();
        for (_, orphan) in grouped_stems(&self.spv_dir(), "spv", &[])?
            .into_iter()
            .filter(|(_, r)| !wanted.contains(&r))
        {
            let path = self.spv_path(&orphan);
            std::fs::remove_file(&path).with_context(|| format!("removing {}", path.display()))?;
        }
        Ok(kernels.into_iter().map(|(name, _)| name).collect())
    }

    /// What is out of sync between glsl/ and spv/: one line per stale, missing or orphan module
    /// (empty when in sync). Compiles into a temporary folder; spv/ is not touched.
    pub fn check(&self) -> Result<Vec<String>> {
        let kernels = self.kernels()?;
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
            for (name, relative) in &kernels {
                let committed = self.spv_path(relative);
                let fresh = scratch.join(format!("{name}.spv"));
                self.compile(relative, &fresh)?;
                let path = relative.display();
                match std::fs::read(&committed) {
                    Err(_) => problems.push(format!(
                        "spv/{path}.spv is missing (glsl/{path}.comp has no module)"
                    )),
                    Ok(bytes) if bytes != std::fs::read(&fresh)? => problems.push(format!(
                        "spv/{path}.spv is stale against glsl/{path}.comp or its includes"
                    )),
                    Ok(_) => {}
                }
            }
            let wanted: Vec<&PathBuf> = kernels.iter().map(|(_, r)| r).collect();
            for (_, orphan) in grouped_stems(&self.spv_dir(), "spv", &[])?
                .into_iter()
                .filter(|(_, r)| !wanted.contains(&r))
            {
                let path = orphan.display();
                problems.push(format!("spv/{path}.spv has no glsl/{path}.comp"));
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

/// (stem, path relative to `dir` without the extension) of every file with `extension` in
/// `dir` and its folders, but the folders named in `skip`.
fn grouped_stems(dir: &Path, extension: &str, skip: &[&str]) -> Result<Vec<(String, PathBuf)>> {
    let mut found = Vec::new();
    let mut folders = vec![PathBuf::new()];
    while let Some(folder) = folders.pop() {
        let full = dir.join(&folder);
        for entry in
            std::fs::read_dir(&full).with_context(|| format!("reading {}", full.display()))?
        {
            let path = entry?.path();
            let name = path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            if path.is_dir() {
                if !(folder.as_os_str().is_empty() && skip.contains(&name.as_str())) {
                    folders.push(folder.join(&name));
                }
            } else if path.extension().is_some_and(|x| x == extension) {
                let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
                found.push((stem.clone(), folder.join(stem)));
            }
        }
    }
    found.sort();
    Ok(found)
}
