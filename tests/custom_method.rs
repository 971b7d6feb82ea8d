//! examples/custom_method.rs under `cargo test`: a method defined outside irad's sources
//! (ambient occlusion with its own kernel and settings table) registered, rendered through the
//! library and through a suite, and checked against its closed forms (the example's `run`).

use crate::common;

#[path = "../examples/custom_method.rs"]
#[allow(dead_code)]
mod example;

#[test]
fn a_method_defined_outside_irad_renders_through_the_library_and_a_suite() {
    common::with_gpu(|ctx| {
        for line in example::run(ctx).unwrap() {
            println!("{line}");
        }
    });
}
