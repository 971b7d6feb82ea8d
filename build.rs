//! Embeds every committed spv/<group>/*.spv module in the binary (src/gpu/spirv.rs), so irad runs
//! where glslang is not installed; and hashes the Rust sources a reference image depends on
//! (IRAD_REFERENCE_CODE_HASH, part of the benchmark harness's reference cache key).

use std::{env, fs, path::Path};

fn main() {
    let root = env::var("CARGO_MANIFEST_DIR").unwrap();
    let spv = Path::new(&root).join("spv");
    println!("cargo:rerun-if-changed=spv");
    // spv/<group>/<name>.spv: a kernel is found by its name alone (names are unique).
    let mut modules: Vec<(String, String)> = Vec::new();
    let mut folders = vec![spv.clone()];
    while let Some(folder) = folders.pop() {
        println!("cargo:rerun-if-changed={}", folder.display());
        let Ok(dir) = fs::read_dir(&folder) else {
            continue;
        };
        for path in dir.filter_map(|e| e.ok()).map(|e| e.path()) {
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|x| x == "spv") {
                println!("cargo:rerun-if-changed={}", path.display());
                modules.push((
                    path.file_stem().unwrap().to_string_lossy().into_owned(),
                    path.display().to_string(),
                ));
            }
        }
    }
    modules.sort();
    if let Some(w) = modules.windows(2).find(|w| w[0].0 == w[1].0) {
        panic!("two kernels named {}: {} and {}", w[0].0, w[0].1, w[1].1);
    }
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
    reference_code_hash(Path::new(&root));
    git_commit(Path::new(&root));
}

/// The commit the binary is built from and whether its sources differ from it, for the render
/// records (IRAD_GIT_COMMIT: 40 hex digits, "-dirty" appended where src, glsl, spv, the
/// embedded Cornell box, build.rs or the Cargo files differ from the commit; "unknown" outside a git checkout). Rerun where
/// the commit or those sources change.
fn git_commit(root: &Path) {
    // The sources the binary is built from: src, the kernels (glsl, spv) and the Cornell box
    // it embeds (src/scene/load.rs).
    const SOURCES: [&str; 7] = [
        "src",
        "glsl",
        "spv",
        "scenes/cornell-box",
        "build.rs",
        "Cargo.toml",
        "Cargo.lock",
    ];
    for rel in SOURCES {
        println!("cargo:rerun-if-changed={rel}");
    }
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .arg("-C")
            .arg(root)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    // The files naming the commit: HEAD, the branch it points to, packed refs, and HEAD's log,
    // which every commit, checkout and reset appends to (a branch's ref can move from
    // packed-refs to a new loose file that no earlier run knew to watch).
    for path in [
        "HEAD",
        "logs/HEAD",
        "packed-refs",
        &git(&["symbolic-ref", "-q", "HEAD"]).unwrap_or_default(),
    ] {
        if let Some(p) = git(&["rev-parse", "--git-path", path]).filter(|_| !path.is_empty()) {
            let p = root.join(p);
            if p.exists() {
                println!("cargo:rerun-if-changed={}", p.display());
            }
        }
    }
    let commit = match git(&["rev-parse", "HEAD"]) {
        Some(c) if c.len() == 40 => {
            let mut args = vec!["status", "--porcelain", "--"];
            args.extend(SOURCES);
            let dirty = git(&args).is_none_or(|s| !s.is_empty());
            format!("{c}{}", if dirty { "-dirty" } else { "" })
        }
        _ => "unknown".into(),
    };
    println!("cargo:rustc-env=IRAD_GIT_COMMIT={commit}");
}

/// Sources that shape a reference image besides its kernels' SPIR-V (hashed separately at run
/// time): scene loading and upload, the BVH, the GPU core, samplers' tables, the reference's
/// passes and accumulation, and how the harness combines a reference's halves.
const REFERENCE_SOURCES: &[&str] = &[
    "src/scene",
    "src/bvh.rs",
    "src/bvh",
    "src/gpu",
    "src/sampling",
    "src/methods/reference.rs",
    "src/methods/paths.rs",
    "src/methods/gbuffer.rs",
    "src/methods/accumulation.rs",
    "src/methods/progressive.rs",
    "src/methods/direct.rs",
    "src/methods/driver.rs",
    "src/methods/interface.rs",
    "src/methods/registry.rs",
    "src/methods/settings.rs",
    "src/methods/lightfield",
    "src/bench/suite/references.rs",
];

fn reference_code_hash(root: &Path) {
    let mut files = Vec::new();
    for rel in REFERENCE_SOURCES {
        println!("cargo:rerun-if-changed={rel}");
        collect(&root.join(rel), &mut files);
    }
    files.sort();
    // FNV-1a 64 over (relative path, length, bytes) of each file.
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |bytes: &[u8]| {
        for &b in bytes {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for f in &files {
        let bytes = fs::read(f).unwrap();
        let rel = f
            .strip_prefix(root)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        feed(rel.as_bytes());
        feed(&(bytes.len() as u64).to_le_bytes());
        feed(&bytes);
    }
    println!("cargo:rustc-env=IRAD_REFERENCE_CODE_HASH={h:016x}");
}

fn collect(path: &Path, files: &mut Vec<std::path::PathBuf>) {
    if path.is_dir() {
        for entry in fs::read_dir(path).unwrap() {
            collect(&entry.unwrap().path(), files);
        }
    } else if path.extension().is_some_and(|e| e == "rs") {
        files.push(path.to_path_buf());
    }
}
