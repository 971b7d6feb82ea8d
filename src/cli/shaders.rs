//! `irad shaders`: spv/ rebuilt from glsl/ in a source checkout.

use anyhow::{bail, Result};

use super::shader_tree::ShaderTree;

/// Rebuilds spv/ from glsl/, or with `check` only reports what is stale.
pub fn run(check: bool) -> Result<()> {
    let tree = ShaderTree::source_checkout();
    if check {
        let problems = tree.check()?;
        if problems.is_empty() {
            println!(
                "spv/ is in sync with glsl/ ({} kernels)",
                tree.kernel_names()?.len()
            );
            return Ok(());
        }
        for p in &problems {
            println!("{p}");
        }
        bail!("spv/ is out of sync with glsl/: run `irad shaders` (or `cargo run -- shaders`)");
    }
    let built = tree.rebuild()?;
    println!(
        "built and validated {} kernels into {}: {}",
        built.len(),
        tree.spv_dir().display(),
        built.join(", ")
    );
    println!("rebuild irad (cargo build) to embed them");
    Ok(())
}
