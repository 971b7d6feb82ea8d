//! Every integration test in one test binary: each tests/NAME.rs is a module here (`cargo
//! test --test all NAME::` runs one file's tests). One binary instead of one per file: a fresh
//! clone's CI build linked 33 test binaries, each with the whole library and its dependencies
//! (about 5 s of the 2-core machine apiece), where one link now serves them all. Tests share
//! one process: none may set environment variables or change the working folder.

mod common;

mod bench_suite;
mod bir;
mod browser;
mod buffers;
mod bundles;
mod bvh;
mod cli;
mod compensation;
mod custom_method;
mod determinism;
mod env;
mod export;
mod flip;
mod gltf_import;
mod image;
mod ir;
mod kernels;
mod light_bvh;
mod light_power;
mod lightfield;
mod mitsuba_import;
mod outputs;
mod pixel_hashes;
mod prefix_sum;
mod reference;
mod restir;
mod restir_motion;
mod scene_fuzz;
mod scene_loading;
mod sequences;
mod setting_maxima;
mod shaders;
mod state_across_frames;
mod tables;
mod textures;
mod timing;
mod vpl_reuse;
