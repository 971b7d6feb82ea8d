//! Timestamps: every pass is reported by name, in order, with its GPU time, beside the wall clock.

use crate::common;

use irad::gpu::{copy::CopyValues, Buffer, Commands};

#[test]
fn passes_are_timed_by_name() {
    common::with_gpu(|ctx| {
        assert!(
            ctx.info().timestamps(),
            "lavapipe and every GPU irad targets have timestamps"
        );
        let copy = CopyValues::new(ctx).unwrap();
        let a = Buffer::<f32>::zeroed(ctx, "a", 1 << 16).unwrap();
        let b = Buffer::<f32>::zeroed(ctx, "b", 1 << 16).unwrap();
        let mut cmd = Commands::new(ctx).unwrap();
        cmd.pass("first copy", |cmd| copy.record(cmd, &a, &b))
            .unwrap();
        cmd.pass("second copy", |cmd| copy.record(cmd, &b, &a))
            .unwrap();
        cmd.pass("first copy", |cmd| copy.record(cmd, &a, &b))
            .unwrap();
        let t = cmd.submit_and_wait().unwrap();
        let names: Vec<&str> = t.passes.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["first copy", "second copy", "first copy"]);
        for p in &t.passes {
            let ms = p.gpu_ms.unwrap();
            assert!((0.0..60_000.0).contains(&ms), "{}: {ms} ms", p.name);
        }
        let both = t.gpu_ms("first copy").unwrap();
        assert!((both - t.passes[0].gpu_ms.unwrap() - t.passes[2].gpu_ms.unwrap()).abs() < 1e-9);
        assert!(t.wall_ms > 0.0);
        assert!(t.to_string().contains("second copy"));
    });
}

#[test]
fn passes_do_not_nest() {
    common::with_gpu(|ctx| {
        let mut cmd = Commands::new(ctx).unwrap();
        let err = cmd
            .pass("outer", |cmd| cmd.pass("inner", |_| Ok(())))
            .unwrap_err();
        assert!(
            err.to_string().contains("inner") && err.to_string().contains("outer"),
            "{err}"
        );
    });
}
