//! `irad info` (the devices and the limits irad depends on) and `irad selfcheck`.

use anyhow::{bail, Result};

use super::selfcheck;
use irad::gpu::{self, Context, ContextOptions, DeviceSelector};

use super::device_line;

pub fn info(selector: Option<&DeviceSelector>) -> Result<()> {
    let devices = gpu::list_devices()?;
    let chosen = gpu::device_info::choose(&devices, selector);
    println!(
        "Vulkan devices ({} found; * marks the one irad uses):",
        devices.len()
    );
    for d in &devices {
        let mark = if chosen.as_ref().ok() == Some(&d.index) {
            "*"
        } else {
            " "
        };
        let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
        println!("{mark} {}: {}", d.index, device_line(d));
        println!(
            "    max storage buffer range   {} bytes ({:.0} MiB)",
            d.max_storage_buffer_range,
            mib(d.max_storage_buffer_range)
        );
        println!(
            "    shared memory / workgroup  {} bytes",
            d.max_compute_shared_memory
        );
        println!(
            "    workgroup                  {} invocations, size {:?}, count {:?}",
            d.max_workgroup_invocations, d.max_workgroup_size, d.max_workgroup_count
        );
        println!(
            "    subgroup size              {} (arithmetic in compute: {})",
            d.subgroup_size,
            yes_no(d.subgroup_arithmetic)
        );
        println!(
            "    f32 atomic add (buffers)   {}",
            yes_no(d.float_atomic_add)
        );
        match d.compute_queue_family {
            Some(family) if d.timestamps() => println!(
                "    timestamps                 yes ({} valid bits, {} ns per tick, queue family {family})",
                d.timestamp_valid_bits, d.timestamp_period_ns
            ),
            Some(family) => println!("    timestamps                 no (queue family {family}): passes get wall-clock times only"),
            None => println!("    compute queue              none: irad cannot use this device"),
        }
        println!(
            "    push constants             {} bytes",
            d.max_push_constants
        );
        println!(
            "    device-local memory        {:.0} MiB (largest heap)",
            mib(d.device_local_heap)
        );
    }
    if ContextOptions::force_staging_from_env()? {
        println!(
            "staging: forced (IRAD_FORCE_STAGING): every buffer device-local only, written and \
             read through staging buffers, as on a discrete GPU"
        );
    }
    chosen?;
    Ok(())
}

fn yes_no(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}

pub fn selfcheck(ctx: &Context) -> Result<()> {
    println!("selfcheck on {}", device_line(ctx.info()));
    let mut failed = 0;
    for &(row_length, row_count) in selfcheck::SCAN_CASES {
        let c = selfcheck::check_scan(ctx, row_length, row_count, 1)?;
        println!(
            "  prefix sum {:>8} x {:<5} max relative error {:.2e} (row totals {:.2e}), tolerance {:.0e}: {}",
            c.row_length,
            c.row_count,
            c.max_relative_error,
            c.max_total_error,
            selfcheck::SCAN_TOLERANCE,
            if c.passed() { "ok" } else { "FAILED" }
        );
        failed += usize::from(!c.passed());
    }
    let log = ctx.validation_log().messages();
    if !log.is_empty() {
        bail!("{} validation message(s), printed above", log.len());
    }
    if failed > 0 {
        bail!("{failed} prefix-sum check(s) over tolerance");
    }
    println!("selfcheck passed");
    Ok(())
}
