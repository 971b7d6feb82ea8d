//! Kernels: every embedded module reflects and builds a pipeline; layouts come from the SPIR-V;
//! bindings and push constants that do not match the shader are errors naming kernel and binding.

use crate::common;

use irad::gpu::reflect::{reflect, BindingKind};
use irad::gpu::spirv::{embedded, embedded_names};
use irad::gpu::{bind, Buffer, Commands, GpuError, Kernel};

#[test]
fn every_embedded_module_reflects_and_builds_a_pipeline() {
    let names: Vec<&str> = embedded_names().collect();
    assert!(
        names.contains(&"scan_blocks")
            && names.contains(&"reduce_blocks")
            && names.contains(&"copy_values")
    );
    common::with_gpu(|ctx| {
        for name in names {
            let kernel = Kernel::new(ctx, name).unwrap_or_else(|e| panic!("{e}"));
            assert!(!kernel.bindings().is_empty(), "{name} reflects no bindings");
        }
    });
}

#[test]
fn reflection_reads_bindings_push_constants_and_workgroup_size() {
    let r = reflect("scan_blocks", embedded("scan_blocks").unwrap()).unwrap();
    let names: Vec<(&str, u32)> = r
        .bindings
        .iter()
        .map(|b| (b.name.as_str(), b.binding))
        .collect();
    assert_eq!(
        names,
        [
            ("Values", 0),
            ("BlockOffsets", 1),
            ("Scanned", 2),
            ("RowTotals", 3)
        ]
    );
    assert!(r
        .bindings
        .iter()
        .all(|b| b.kind == BindingKind::StorageBuffer));
    assert_eq!(r.push_constant_bytes, 16);
    assert_eq!(r.workgroup_size, [64, 1, 1]);
}

#[test]
fn a_kernel_that_is_not_embedded_is_an_error() {
    common::with_gpu(|ctx| {
        let err = Kernel::new(ctx, "no_such_kernel").err().unwrap();
        assert!(err.to_string().contains("no_such_kernel"), "{err}");
    });
}

#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct CopyParams {
    vec4_count: u32,
    pad: [u32; 3],
}

#[test]
fn binding_mismatches_are_errors_naming_kernel_and_binding() {
    common::with_gpu(|ctx| {
        let kernel = Kernel::new(ctx, "copy_values").unwrap();
        let a = Buffer::<f32>::zeroed(ctx, "a", 16).unwrap();
        let b = Buffer::<f32>::zeroed(ctx, "b", 16).unwrap();
        let p = CopyParams {
            vec4_count: 4,
            pad: [0; 3],
        };
        let mut cmd = Commands::new(ctx).unwrap();

        let err = kernel.dispatch(
            &mut cmd,
            &[
                bind("Source", &a),
                bind("Destination", &b),
                bind("Extra", &b),
            ],
            &p,
            [1, 1, 1],
        );
        let msg = err.unwrap_err().to_string();
        assert!(
            msg.contains("copy_values")
                && msg.contains("Extra")
                && msg.contains("Source, Destination"),
            "{msg}"
        );

        let err = kernel
            .dispatch(&mut cmd, &[bind("Source", &a)], &p, [1, 1, 1])
            .unwrap_err();
        assert!(
            matches!(&err, GpuError::MissingBinding { kernel, binding, index: 1 } if kernel == "copy_values" && binding == "Destination"),
            "{err}"
        );

        let err = kernel
            .dispatch(
                &mut cmd,
                &[bind("Source", &a), bind("Source", &b)],
                &p,
                [1, 1, 1],
            )
            .unwrap_err();
        assert!(matches!(err, GpuError::DuplicateBinding { .. }), "{err}");

        let err = kernel
            .dispatch(
                &mut cmd,
                &[bind("Source", &a), bind("Destination", &b)],
                &7u32,
                [1, 1, 1],
            )
            .unwrap_err();
        assert!(
            matches!(
                err,
                GpuError::PushConstantSize {
                    expected: 16,
                    given: 4,
                    ..
                }
            ),
            "{err}"
        );

        let err = kernel
            .dispatch(
                &mut cmd,
                &[bind("Source", &a), bind("Destination", &b)],
                &p,
                [u32::MAX, 1, 1],
            )
            .unwrap_err();
        assert!(matches!(err, GpuError::TooManyWorkgroups { .. }), "{err}");

        // The correct dispatch still works after the rejected ones.
        a.write(&(0..16).map(|i| i as f32).collect::<Vec<_>>())
            .unwrap();
        kernel
            .dispatch(
                &mut cmd,
                &[bind("Destination", &b), bind("Source", &a)],
                &p,
                [1, 1, 1],
            )
            .unwrap();
        cmd.submit_and_wait().unwrap();
        assert_eq!(
            b.read().unwrap(),
            (0..16).map(|i| i as f32).collect::<Vec<_>>()
        );
    });
}
