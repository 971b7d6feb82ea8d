//! Embeds every committed spv/*.spv module in the binary (src/gpu/spirv.rs), so irad runs
//! where glslang is not installed.

use std::{env, fs, path::Path};

fn main() {
    let root = env::var("CARGO_MANIFEST_DIR").unwrap();
    let spv = Path::new(&root).join("spv");
    println!("cargo:rerun-if-changed=spv");
    let mut modules: Vec<(String, String)> = fs::read_dir(&spv)
        .map(|dir| {
            dir.filter_map(|e| e.ok())
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|x| x == "spv"))
                .map(|p| {
                    println!("cargo:rerun-if-changed={}", p.display());
                    (
                        p.file_stem().unwrap().to_string_lossy().into_owned(),
                        p.display().to_string(),
                    )
                })
                .collect()
        })
        .unwrap_or_default();
    modules.sort();
    let mut out = String::from("/// Every module of spv/, by kernel name, sorted.\npub static EMBEDDED: &[(&str, &[u8])] = &[\n");
    for (name, path) in &modules {
        out += &format!("    ({name:?}, include_bytes!({path:?})),\n");
    }
    out += "];\n";
    fs::write(
        Path::new(&env::var("OUT_DIR").unwrap()).join("embedded_spv.rs"),
        out,
    )
    .unwrap();
}
