//! Buffers: upload and readback, sizes from what is asked, and errors naming the buffer and the
//! sizes when a request exceeds the device.

use crate::common;

use irad::gpu::{Buffer, GpuError};

#[test]
fn upload_readback_and_zeroing() {
    common::with_gpu(|ctx| {
        let data: Vec<u32> = (0..1000).map(|i| i * 7 + 1).collect();
        let b = Buffer::from_slice(ctx, "numbers", &data).unwrap();
        assert_eq!(b.len(), 1000);
        assert_eq!(b.read().unwrap(), data);
        let z = Buffer::<[f32; 4]>::zeroed(ctx, "zeros", 33).unwrap();
        assert_eq!(z.read().unwrap(), vec![[0.0; 4]; 33]);
        let empty = Buffer::<f32>::zeroed(ctx, "empty", 0).unwrap();
        assert!(empty.is_empty() && empty.read().unwrap().is_empty());
    });
}

#[test]
fn writes_of_the_wrong_length_are_errors() {
    common::with_gpu(|ctx| {
        let b = Buffer::<f32>::zeroed(ctx, "four", 4).unwrap();
        let err = b.write(&[1.0; 3]).unwrap_err();
        assert!(
            matches!(&err, GpuError::BufferLength { name, expected: 4, given: 3 } if name == "four"),
            "{err}"
        );
    });
}

#[test]
fn a_buffer_over_max_storage_buffer_range_is_an_error_naming_it_and_the_sizes() {
    common::with_gpu(|ctx| {
        let limit = ctx.info().max_storage_buffer_range;
        let len = (limit / 4 + 1) as usize;
        let err = Buffer::<f32>::zeroed(ctx, "huge table", len).err().unwrap();
        let msg = err.to_string();
        assert!(matches!(err, GpuError::BufferTooLarge { .. }), "{msg}");
        assert!(
            msg.contains("huge table")
                && msg.contains(&(len * 4).to_string())
                && msg.contains(&limit.to_string()),
            "{msg}"
        );
    });
}

/// Forced staging (IRAD_FORCE_STAGING=1, docs/DESIGN.md "Staging"): device buffers stay
/// unmapped, as on a discrete GPU, and uploads, zeroing and readbacks go through staging copies
/// with no validation message; without it lavapipe's buffers are mapped.
#[test]
fn forced_staging_keeps_device_buffers_unmapped_and_still_round_trips() {
    use irad::gpu::{Context, ContextOptions, Validation};
    for force_staging in [false, true] {
        let validation = if irad::gpu::validation_layer_available() {
            Validation::On
        } else {
            Validation::Off
        };
        let ctx = Context::new(&ContextOptions {
            device: None,
            validation,
            force_staging,
        })
        .unwrap();
        let log = ctx.validation_log();
        assert_eq!(ctx.force_staging(), force_staging);
        let data: Vec<u32> = (0..777).map(|i| i * 3 + 5).collect();
        let b = Buffer::from_slice(&ctx, "staged numbers", &data).unwrap();
        let z = Buffer::<[f32; 4]>::zeroed(&ctx, "staged zeros", 9).unwrap();
        assert_eq!(b.read().unwrap(), data);
        assert_eq!(z.read().unwrap(), vec![[0.0; 4]; 9]);
        if force_staging {
            assert!(!b.host_mapped() && !z.host_mapped());
        } else if ctx.info().kind == irad::gpu::DeviceKind::Cpu {
            assert!(b.host_mapped(), "lavapipe's buffers are host-visible");
        }
        drop((b, z, ctx));
        assert!(log.messages().is_empty(), "{:?}", log.messages());
    }
}
