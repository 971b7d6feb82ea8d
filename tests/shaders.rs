//! spv/ is in sync with glsl/ (recompiled with glslangValidator and compared byte for byte) and
//! spirv-val accepts every module. CI installs glslang and spirv-tools, so there these always
//! run; elsewhere a missing tool skips with a note.

use crate::common;

// The shader build belongs to the binary (`irad shaders`), not the library's API: the test
// compiles its source file in.
#[path = "../src/cli/shader_tree.rs"]
#[allow(dead_code)]
mod shader_tree;

use shader_tree::{tool_available, validate, ShaderTree};

fn tools_present(tool: &str) -> bool {
    if tool_available(tool) {
        return true;
    }
    assert!(!common::under_ci(), "{tool} is not installed under CI");
    eprintln!("note: {tool} not installed; skipping");
    false
}

#[test]
fn spv_is_in_sync_with_glsl() {
    if !tools_present("glslangValidator") {
        return;
    }
    let tree = ShaderTree::source_checkout();
    let problems = tree.check().unwrap();
    assert!(
        problems.is_empty(),
        "run `irad shaders`:\n{}",
        problems.join("\n")
    );
}

#[test]
fn spirv_val_accepts_every_module() {
    if !tools_present("spirv-val") {
        return;
    }
    let tree = ShaderTree::source_checkout();
    let kernels = tree.kernels().unwrap();
    assert!(!kernels.is_empty());
    for (_, relative) in kernels {
        validate(&tree.spv_path(&relative)).unwrap();
    }
}

#[test]
fn every_kernel_source_is_embedded() {
    let tree = ShaderTree::source_checkout();
    let embedded: Vec<&str> = irad::gpu::spirv::embedded_names().collect();
    assert_eq!(
        embedded,
        tree.kernel_names()
            .unwrap()
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>()
    );
}
