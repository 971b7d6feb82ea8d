//! The SPIR-V modules of spv/, embedded at build time (build.rs).

include!(concat!(env!("OUT_DIR"), "/embedded_spv.rs"));

/// The embedded module of kernel `name` (the file stem of `glsl/<group>/<name>.comp`).
pub fn embedded(name: &str) -> Option<&'static [u8]> {
    EMBEDDED
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, bytes)| *bytes)
}

/// Names of every embedded kernel.
pub fn embedded_names() -> impl Iterator<Item = &'static str> {
    EMBEDDED.iter().map(|(n, _)| *n)
}
