//! Buffers: upload and readback, sizes from what is asked, and errors naming the buffer and the
//! sizes when a request exceeds the device.

mod common;

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
