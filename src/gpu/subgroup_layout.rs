//! The one assumption irad's scans make about subgroups, checked once per device before any scan
//! runs: glsl/include/workgroup_scan.glsl sums a 64-invocation workgroup in (gl_SubgroupID,
//! lane) order while its callers index their data by gl_LocalInvocationIndex, so the two orders
//! must agree. Every driver seen so far numbers lanes that way (lavapipe at 4 and 8 lanes,
//! NVIDIA, AMD), but the Vulkan spec does not promise it; a device that differs gets an error
//! instead of wrong CDFs. Any subgroup width and partly filled subgroups are fine.

use super::buffer::Buffer;
use super::commands::Commands;
use super::context::Context;
use super::error::{GpuError, GpuResult};
use super::kernel::{bind, Kernel};

/// Invocations per workgroup of the probe and of the scan kernels (scan_layout.glsl).
const WORKGROUP: usize = 64;

/// Runs glsl/gpu/probe_subgroup_layout.comp once and checks its records (`Context` caches the
/// verdict, so this runs once per context).
pub(crate) fn probe(ctx: &Context) -> GpuResult<()> {
    let kernel = Kernel::new(ctx, "probe_subgroup_layout")?;
    let records = Buffer::<[u32; 4]>::zeroed(ctx, "subgroup layout", WORKGROUP)?;
    let mut cmd = Commands::new(ctx)?;
    kernel.dispatch(&mut cmd, &[bind("Layout", &records)], &(), [1, 1, 1])?;
    cmd.submit_and_wait()?;
    lanes_follow_invocation_order(&records.read()?).map_err(|detail| GpuError::SubgroupLayout {
        device: ctx.info().name.clone(),
        detail,
    })
}

/// Whether ordering the records (local index, subgroup id, lane, subgroup size) by (subgroup
/// id, lane) lists the local indices 0, 1, 2, ... in order; the reason when not.
pub fn lanes_follow_invocation_order(records: &[[u32; 4]]) -> Result<(), String> {
    let mut by_lane: Vec<&[u32; 4]> = records.iter().collect();
    by_lane.sort_by_key(|r| (r[1], r[2]));
    for (position, r) in by_lane.iter().enumerate() {
        if r[0] as usize != position {
            return Err(format!(
                "invocation {} is lane {} of subgroup {} (subgroup size {}), so it comes at \
                 position {position} in (subgroup, lane) order",
                r[0], r[2], r[1], r[3]
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn linear(width: u32) -> Vec<[u32; 4]> {
        (0..64u32)
            .map(|i| [i, i / width, i % width, width])
            .collect()
    }

    #[test]
    fn linear_layouts_of_any_width_pass() {
        for width in [1, 4, 8, 16, 32, 64, 128] {
            assert_eq!(
                lanes_follow_invocation_order(&linear(width)),
                Ok(()),
                "{width}"
            );
        }
        // Partly filled subgroups (a 128-wide subgroup half empty; narrower than reported).
        let mut narrow = linear(16);
        narrow.iter_mut().for_each(|r| r[3] = 32);
        assert_eq!(lanes_follow_invocation_order(&narrow), Ok(()));
    }

    #[test]
    fn lanes_in_another_order_are_refused() {
        // Lanes interleaved across two subgroups: invocation i in subgroup i % 2.
        let interleaved: Vec<[u32; 4]> = (0..64u32).map(|i| [i, i % 2, i / 2, 32]).collect();
        let err = lanes_follow_invocation_order(&interleaved).unwrap_err();
        assert!(
            err.contains("invocation 2 is lane 1 of subgroup 0"),
            "{err}"
        );
        // Two invocations of one subgroup in each other's lanes.
        let mut swapped = linear(8);
        swapped[3] = [3, 0, 4, 8];
        swapped[4] = [4, 0, 3, 8];
        let err = lanes_follow_invocation_order(&swapped).unwrap_err();
        assert!(
            err.contains("invocation 4 is lane 3 of subgroup 0"),
            "{err}"
        );
    }
}
