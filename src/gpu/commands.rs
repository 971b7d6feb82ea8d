//! Recording of one submission: dispatches grouped into named passes, each pass bracketed by
//! GPU timestamps, a memory barrier after every dispatch so each pass sees the last one's
//! writes, then submit, wait, and the per-pass times.
//!
//! `Commands<'a>` borrows every kernel and buffer it records for 'a, so none can be dropped
//! before the submission has completed.
//!
//! A submission can report its progress (`on_progress`): then it is submitted in parts of a
//! number of dispatches each, waited for, and the hook told how many dispatches are done. The
//! parts run the same commands in the same order, so the results are the same bits; a pass
//! cut between two parts is timed as the sum of its pieces.

use std::marker::PhantomData;
use std::time::Instant;

use ash::vk;

use super::buffer::GpuBuffer;
use super::context::Context;
use super::error::{GpuError, GpuResult, VkContext};
use super::kernel::{descriptor_type, Kernel};
use super::reflect::BindingInfo;
use super::timing::{PassTime, Timings};

/// At most this many passes per submission (two timestamps each).
pub const MAX_PASSES: u32 = 512;
const SETS_PER_POOL: u32 = 64;

pub struct Commands<'a> {
    ctx: Context,
    cb: vk::CommandBuffer,
    descriptor_pools: Vec<vk::DescriptorPool>,
    query_pool: Option<vk::QueryPool>,
    passes: Vec<(String, u32)>,
    open_pass: Option<String>,
    /// Passes timed in earlier parts of the submission (`on_progress`), and the GPU time the
    /// open pass spent in them.
    finished: Vec<PassTime>,
    open_partial_ms: Option<f64>,
    parts_wall_ms: f64,
    dispatches: u32,
    since_part: u32,
    part_dispatches: u32,
    hook: Option<Box<dyn FnMut(u32) + 'a>>,
    _borrows: PhantomData<&'a ()>,
}

impl<'a> Commands<'a> {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        let cb = ctx.allocate_command_buffer()?;
        let mut cmd = Commands {
            ctx: ctx.clone(),
            cb,
            descriptor_pools: Vec::new(),
            query_pool: None,
            passes: Vec::new(),
            open_pass: None,
            finished: Vec::new(),
            open_partial_ms: None,
            parts_wall_ms: 0.0,
            dispatches: 0,
            since_part: 0,
            part_dispatches: 0,
            hook: None,
            _borrows: PhantomData,
        };
        cmd.begin()?;
        Ok(cmd)
    }

    /// Begins `cb` and resets the timestamps.
    fn begin(&mut self) -> GpuResult<()> {
        let device = self.ctx.device();
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        unsafe { device.begin_command_buffer(self.cb, &begin) }.vk("vkBeginCommandBuffer")?;
        if self.ctx.info().timestamps() {
            let pool = match self.query_pool {
                Some(pool) => pool,
                None => {
                    let info = vk::QueryPoolCreateInfo::default()
                        .query_type(vk::QueryType::TIMESTAMP)
                        .query_count(2 * MAX_PASSES);
                    let pool =
                        unsafe { device.create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
                    self.query_pool = Some(pool);
                    pool
                }
            };
            unsafe { device.cmd_reset_query_pool(self.cb, pool, 0, 2 * MAX_PASSES) };
        }
        Ok(())
    }

    /// Submits in parts from now on, calling `hook` with the dispatches done after each part
    /// (and not after the last: `submit_and_wait`'s caller knows). A part is one dispatch at
    /// first, then twice or half as many as the last while parts take under 0.05 or over 0.2
    /// s. For progress within long submissions; the results are the same bits.
    pub fn on_progress(&mut self, hook: Box<dyn FnMut(u32) + 'a>) {
        self.part_dispatches = 1;
        self.hook = Some(hook);
    }

    /// Dispatches recorded so far.
    pub fn dispatches(&self) -> u32 {
        self.dispatches
    }

    /// Submits what is recorded, waits, keeps its pass times and begins a new part. A pass
    /// open now goes on in the new part (its two pieces' times are summed).
    fn submit_part(&mut self) -> GpuResult<()> {
        if self.open_pass.is_some() {
            let index = self.passes.len() as u32;
            self.timestamp(2 * index + 1);
        }
        let timings = self.end_submit_and_read()?;
        self.parts_wall_ms += timings.wall_ms;
        let mut times = timings.passes.into_iter();
        for time in times.by_ref().take(self.passes.len()) {
            self.finished.push(time);
        }
        if let Some(piece) = times.next() {
            self.open_partial_ms = add_ms(self.open_partial_ms.or(Some(0.0)), piece.gpu_ms);
        }
        self.passes.clear();
        // Free what the part used and start afresh.
        let device = self.ctx.device();
        unsafe {
            for &pool in &self.descriptor_pools {
                device.destroy_descriptor_pool(pool, None);
            }
        }
        self.descriptor_pools.clear();
        self.ctx.free_command_buffer(self.cb);
        self.cb = self.ctx.allocate_command_buffer()?;
        self.begin()?;
        if self.open_pass.is_some() {
            self.timestamp(0);
        }
        Ok(())
    }

    /// Records the work `record` does as one pass named `name`, timed on the GPU.
    pub fn pass<R>(
        &mut self,
        name: &str,
        record: impl FnOnce(&mut Self) -> GpuResult<R>,
    ) -> GpuResult<R> {
        if let Some(open) = &self.open_pass {
            return Err(GpuError::Pass {
                pass: name.into(),
                reason: format!("passes do not nest (inside `{open}`)"),
            });
        }
        let index = self.passes.len() as u32;
        if index >= MAX_PASSES {
            return Err(GpuError::Pass {
                pass: name.into(),
                reason: format!("over {MAX_PASSES} passes in one submission"),
            });
        }
        self.open_pass = Some(name.to_string());
        self.open_partial_ms = None;
        self.timestamp(2 * index);
        let result = record(self);
        // Parts submitted inside the pass leave its last piece at the first index.
        let index = self.passes.len() as u32;
        self.timestamp(2 * index + 1);
        self.open_pass = None;
        match self.open_partial_ms.take() {
            Some(ms) => self
                .passes
                .push((format!("{PARTIAL}{ms}\u{0}{name}"), index)),
            None => self.passes.push((name.to_string(), index)),
        }
        result
    }

    fn timestamp(&mut self, query: u32) {
        if let Some(pool) = self.query_pool {
            unsafe {
                self.ctx.device().cmd_write_timestamp(
                    self.cb,
                    vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                    pool,
                    query,
                )
            };
        }
    }

    pub(crate) fn record_dispatch(
        &mut self,
        kernel: &'a Kernel,
        buffers: &[(&BindingInfo, &'a dyn GpuBuffer)],
        push: &[u8],
        groups: [u32; 3],
    ) -> GpuResult<()> {
        let (pipeline, layout, set_layout) = kernel.raw();
        let set = self.allocate_set(set_layout)?;
        let device = self.ctx.device();
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
            .iter()
            .map(|(_, b)| {
                [vk::DescriptorBufferInfo::default()
                    .buffer(b.handle())
                    .offset(0)
                    .range(vk::WHOLE_SIZE)]
            })
            .collect();
        let writes: Vec<vk::WriteDescriptorSet> = buffers
            .iter()
            .zip(&infos)
            .map(|((info, _), buffer_info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(info.binding)
                    .descriptor_type(descriptor_type(info.kind))
                    .buffer_info(buffer_info)
            })
            .collect();
        unsafe {
            device.update_descriptor_sets(&writes, &[]);
            device.cmd_bind_pipeline(self.cb, vk::PipelineBindPoint::COMPUTE, pipeline);
            device.cmd_bind_descriptor_sets(
                self.cb,
                vk::PipelineBindPoint::COMPUTE,
                layout,
                0,
                &[set],
                &[],
            );
            if !push.is_empty() {
                device.cmd_push_constants(self.cb, layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            }
            if groups.iter().all(|&g| g > 0) {
                device.cmd_dispatch(self.cb, groups[0], groups[1], groups[2]);
            }
        }
        self.barrier_between_passes();
        self.dispatches += 1;
        self.since_part += 1;
        if self.hook.is_some() && self.since_part >= self.part_dispatches {
            self.since_part = 0;
            let start = Instant::now();
            self.submit_part()?;
            // Parts of about a tenth of a second: one dispatch may take minutes (bir's
            // reverse radiance of 2^20 VPLs), a thousand may take a millisecond.
            let seconds = start.elapsed().as_secs_f64();
            if seconds < 0.05 {
                self.part_dispatches = (2 * self.part_dispatches).min(MAX_PART_DISPATCHES);
            } else if seconds > 0.2 {
                self.part_dispatches = (self.part_dispatches / 2).max(1);
            }
            let done = self.dispatches;
            if let Some(hook) = self.hook.as_mut() {
                hook(done);
            }
        }
        Ok(())
    }

    /// Copies all of `src` into the start of `dst` (as many bytes as the smaller holds).
    pub fn copy(&mut self, src: &'a dyn GpuBuffer, dst: &'a dyn GpuBuffer) {
        let size = src.byte_size().min(dst.byte_size());
        if size > 0 {
            let region = [vk::BufferCopy::default().size(size)];
            unsafe {
                self.ctx
                    .device()
                    .cmd_copy_buffer(self.cb, src.handle(), dst.handle(), &region)
            };
        }
        self.barrier_between_passes();
    }

    /// Copies `size` bytes of `src` from byte `offset` into the start of `dst`.
    pub fn copy_region(
        &mut self,
        src: &'a dyn GpuBuffer,
        offset: u64,
        dst: &'a dyn GpuBuffer,
        size: u64,
    ) {
        let size = size
            .min(dst.byte_size())
            .min(src.byte_size().saturating_sub(offset));
        if size > 0 {
            let region = [vk::BufferCopy::default().src_offset(offset).size(size)];
            unsafe {
                self.ctx
                    .device()
                    .cmd_copy_buffer(self.cb, src.handle(), dst.handle(), &region)
            };
        }
        self.barrier_between_passes();
    }

    /// Fills all of `buffer` with zero bytes.
    pub fn fill_zero(&mut self, buffer: &'a dyn GpuBuffer) {
        unsafe {
            self.ctx
                .device()
                .cmd_fill_buffer(self.cb, buffer.handle(), 0, vk::WHOLE_SIZE, 0)
        };
        self.barrier_between_passes();
    }

    /// Every compute or transfer write before it is visible to every compute or transfer access
    /// after it: recorded after each dispatch, copy and fill.
    fn barrier_between_passes(&mut self) {
        self.barrier(
            vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
            vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::SHADER_WRITE
                | vk::AccessFlags::TRANSFER_READ
                | vk::AccessFlags::TRANSFER_WRITE,
        );
    }

    fn barrier(&mut self, dst_stage: vk::PipelineStageFlags, dst_access: vk::AccessFlags) {
        let barrier = [vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(dst_access)];
        unsafe {
            self.ctx.device().cmd_pipeline_barrier(
                self.cb,
                vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
                dst_stage,
                vk::DependencyFlags::empty(),
                &barrier,
                &[],
                &[],
            )
        };
    }

    fn allocate_set(&mut self, layout: vk::DescriptorSetLayout) -> GpuResult<vk::DescriptorSet> {
        let device = self.ctx.device();
        let layouts = [layout];
        if let Some(&pool) = self.descriptor_pools.last() {
            let info = vk::DescriptorSetAllocateInfo::default()
                .descriptor_pool(pool)
                .set_layouts(&layouts);
            match unsafe { device.allocate_descriptor_sets(&info) } {
                Ok(sets) => return Ok(sets[0]),
                Err(vk::Result::ERROR_OUT_OF_POOL_MEMORY | vk::Result::ERROR_FRAGMENTED_POOL) => {}
                Err(result) => {
                    return Err(GpuError::Vulkan {
                        call: "vkAllocateDescriptorSets",
                        result,
                    })
                }
            }
        }
        let sizes = [
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(SETS_PER_POOL * 16),
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::UNIFORM_BUFFER)
                .descriptor_count(SETS_PER_POOL * 4),
        ];
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(SETS_PER_POOL)
            .pool_sizes(&sizes);
        let pool =
            unsafe { device.create_descriptor_pool(&info, None) }.vk("vkCreateDescriptorPool")?;
        self.descriptor_pools.push(pool);
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(pool)
            .set_layouts(&layouts);
        Ok(unsafe { device.allocate_descriptor_sets(&info) }.vk("vkAllocateDescriptorSets")?[0])
    }

    /// Submits, waits for completion and returns every pass's GPU time and the wall clock.
    pub fn submit_and_wait(mut self) -> GpuResult<Timings> {
        let last = self.end_submit_and_read()?;
        let mut passes = std::mem::take(&mut self.finished);
        passes.extend(last.passes);
        Ok(Timings {
            passes,
            wall_ms: self.parts_wall_ms + last.wall_ms,
        })
    }

    /// Ends `cb`, submits it, waits, and reads the times of `passes` (a pass that went on
    /// from an earlier part gets that part's time added), and of the open pass's piece last.
    fn end_submit_and_read(&mut self) -> GpuResult<Timings> {
        let device = self.ctx.device();
        // Make every write visible to the host reads that follow.
        let barrier = [vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(vk::AccessFlags::HOST_READ)];
        unsafe {
            device.cmd_pipeline_barrier(
                self.cb,
                vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &barrier,
                &[],
                &[],
            );
            device.end_command_buffer(self.cb)
        }
        .vk("vkEndCommandBuffer")?;
        let start = Instant::now();
        self.ctx.submit_and_wait(self.cb)?;
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;

        let open = usize::from(self.open_pass.is_some());
        let mut ticks = vec![0u64; 2 * (self.passes.len() + open)];
        if let (Some(pool), false) = (self.query_pool, ticks.is_empty()) {
            unsafe {
                device.get_query_pool_results(
                    pool,
                    0,
                    &mut ticks,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                )
            }
            .vk("vkGetQueryPoolResults")?;
        }
        let info = self.ctx.info();
        let mask = if info.timestamp_valid_bits >= 64 {
            u64::MAX
        } else {
            (1u64 << info.timestamp_valid_bits) - 1
        };
        let has_pool = self.query_pool.is_some();
        let time = |i: usize| {
            has_pool.then(|| {
                // Masked after subtracting, so a counter of fewer than 64 bits may wrap.
                let (a, b) = (ticks[2 * i], ticks[2 * i + 1]);
                (b.wrapping_sub(a) & mask) as f64 * info.timestamp_period_ns as f64 * 1e-6
            })
        };
        let mut passes: Vec<PassTime> = self
            .passes
            .iter()
            .map(|(name, i)| match name.strip_prefix(PARTIAL) {
                // A pass that began in an earlier part: its earlier pieces' time, then its name.
                Some(rest) => {
                    let (ms, name) = rest.split_once('\u{0}').expect("written by pass()");
                    PassTime {
                        name: name.to_string(),
                        gpu_ms: add_ms(ms.parse().ok(), time(*i as usize)),
                    }
                }
                None => PassTime {
                    name: name.clone(),
                    gpu_ms: time(*i as usize),
                },
            })
            .collect();
        if open == 1 {
            passes.push(PassTime {
                name: String::new(),
                gpu_ms: time(self.passes.len()),
            });
        }
        Ok(Timings { passes, wall_ms })
    }
}

/// Most dispatches in one part of a submission (`on_progress`).
const MAX_PART_DISPATCHES: u32 = 4096;

/// Marks a pass name that carries the time of the pass's pieces in earlier parts.
const PARTIAL: &str = "\u{0}partial:";

fn add_ms(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    a.zip(b).map(|(a, b)| a + b)
}

impl Drop for Commands<'_> {
    fn drop(&mut self) {
        let device = self.ctx.device();
        unsafe {
            for &pool in &self.descriptor_pools {
                device.destroy_descriptor_pool(pool, None);
            }
            if let Some(pool) = self.query_pool {
                device.destroy_query_pool(pool, None);
            }
        }
        self.ctx.free_command_buffer(self.cb);
    }
}
