//! Typed storage buffers sized from what is asked, with upload and readback. Where the device's
//! memory is both device-local and host-visible (lavapipe, integrated GPUs) buffers are mapped
//! directly; on discrete GPUs they live in device-local memory and go through a staging buffer.

use std::marker::PhantomData;
use std::ptr::NonNull;

use ash::vk;
use bytemuck::Pod;

use super::context::Context;
use super::device_info::DeviceKind;
use super::error::{GpuError, GpuResult, VkContext};

/// What a kernel binding needs of a buffer, whatever its element type.
pub trait GpuBuffer {
    fn handle(&self) -> vk::Buffer;
    fn name(&self) -> &str;
    fn byte_size(&self) -> u64;
}

struct RawBuffer {
    ctx: Context,
    buffer: vk::Buffer,
    memory: vk::DeviceMemory,
    bytes: u64,
    mapped: Option<NonNull<u8>>,
    name: String,
}

// The mapping is only touched while the GPU is idle on it (every submit waits).
unsafe impl Send for RawBuffer {}
unsafe impl Sync for RawBuffer {}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Placement {
    Device,
    Staging,
}

impl RawBuffer {
    fn new(ctx: &Context, name: &str, bytes: u64, placement: Placement) -> GpuResult<Self> {
        let info = ctx.info();
        if placement == Placement::Device && bytes > info.max_storage_buffer_range {
            return Err(GpuError::BufferTooLarge {
                name: name.into(),
                bytes,
                limit_name: "maxStorageBufferRange",
                limit: info.max_storage_buffer_range,
            });
        }
        let device = ctx.device();
        // Vulkan forbids empty buffers; an empty one still gets a few bytes.
        let alloc_bytes = bytes.max(16);
        // Uniform too: the scene's constants are a uniform block (scene.glsl: gallivm loads a
        // uniform block's fields once per subgroup, a storage buffer's once per lane).
        let usage = match placement {
            Placement::Device => {
                vk::BufferUsageFlags::STORAGE_BUFFER
                    | vk::BufferUsageFlags::UNIFORM_BUFFER
                    | vk::BufferUsageFlags::TRANSFER_SRC
                    | vk::BufferUsageFlags::TRANSFER_DST
            }
            Placement::Staging => {
                vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST
            }
        };
        let create = vk::BufferCreateInfo::default()
            .size(alloc_bytes)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        let buffer = unsafe { device.create_buffer(&create, None) }.vk("vkCreateBuffer")?;
        let req = unsafe { device.get_buffer_memory_requirements(buffer) };
        let host = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        // Forced staging (IRAD_FORCE_STAGING) places and uses buffers as on a discrete GPU.
        let unified =
            matches!(info.kind, DeviceKind::Cpu | DeviceKind::Integrated) && !ctx.force_staging();
        let (required, preferred) = match placement {
            Placement::Device if unified => (vk::MemoryPropertyFlags::DEVICE_LOCAL, host),
            Placement::Device => (
                vk::MemoryPropertyFlags::DEVICE_LOCAL,
                vk::MemoryPropertyFlags::DEVICE_LOCAL,
            ),
            Placement::Staging => (host, host | vk::MemoryPropertyFlags::HOST_CACHED),
        };
        let Some(type_index) = ctx.memory_type(req.memory_type_bits, required, preferred) else {
            unsafe { device.destroy_buffer(buffer, None) };
            return Err(GpuError::BufferTooLarge {
                name: name.into(),
                bytes,
                limit_name: "memory types (none fits)",
                limit: 0,
            });
        };
        let heap = ctx.heap_size(type_index);
        if req.size > heap {
            unsafe { device.destroy_buffer(buffer, None) };
            return Err(GpuError::BufferTooLarge {
                name: name.into(),
                bytes,
                limit_name: "memory heap size",
                limit: heap,
            });
        }
        let alloc = vk::MemoryAllocateInfo::default()
            .allocation_size(req.size)
            .memory_type_index(type_index);
        let memory = match unsafe { device.allocate_memory(&alloc, None) } {
            Ok(m) => m,
            Err(result) => {
                unsafe { device.destroy_buffer(buffer, None) };
                return Err(match result {
                    vk::Result::ERROR_OUT_OF_DEVICE_MEMORY
                    | vk::Result::ERROR_OUT_OF_HOST_MEMORY => GpuError::BufferTooLarge {
                        name: name.into(),
                        bytes,
                        limit_name: "free memory",
                        limit: heap,
                    },
                    result => GpuError::Vulkan {
                        call: "vkAllocateMemory",
                        result,
                    },
                });
            }
        };
        let mut raw = RawBuffer {
            ctx: ctx.clone(),
            buffer,
            memory,
            bytes,
            mapped: None,
            name: name.to_string(),
        };
        unsafe { device.bind_buffer_memory(buffer, memory, 0) }.vk("vkBindBufferMemory")?;
        // Under forced staging a device buffer is never mapped, even in host-visible memory
        // (lavapipe has no other), so its uploads and readbacks take the staging path.
        let staged = placement == Placement::Device && ctx.force_staging();
        if ctx.memory_flags(type_index).contains(host) && !staged {
            let ptr = unsafe {
                device.map_memory(memory, 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty())
            }
            .vk("vkMapMemory")?;
            raw.mapped = NonNull::new(ptr.cast());
        }
        ctx.name_object(buffer, name);
        Ok(raw)
    }

    fn write_bytes(&self, data: &[u8]) -> GpuResult<()> {
        debug_assert_eq!(data.len() as u64, self.bytes);
        if data.is_empty() {
            return Ok(());
        }
        if let Some(ptr) = self.mapped {
            unsafe { std::ptr::copy_nonoverlapping(data.as_ptr(), ptr.as_ptr(), data.len()) };
            return Ok(());
        }
        let staging = RawBuffer::new(
            &self.ctx,
            &format!("{} (upload)", self.name),
            self.bytes,
            Placement::Staging,
        )?;
        staging.write_bytes(data)?;
        let region = [vk::BufferCopy::default().size(self.bytes)];
        self.ctx.one_shot(|cb| unsafe {
            self.ctx
                .device()
                .cmd_copy_buffer(cb, staging.buffer, self.buffer, &region);
            device_writes_visible(&self.ctx, cb);
        })
    }

    fn read_bytes(&self, out: &mut [u8]) -> GpuResult<()> {
        debug_assert_eq!(out.len() as u64, self.bytes);
        if out.is_empty() {
            return Ok(());
        }
        if let Some(ptr) = self.mapped {
            unsafe { std::ptr::copy_nonoverlapping(ptr.as_ptr(), out.as_mut_ptr(), out.len()) };
            return Ok(());
        }
        let staging = RawBuffer::new(
            &self.ctx,
            &format!("{} (readback)", self.name),
            self.bytes,
            Placement::Staging,
        )?;
        let region = [vk::BufferCopy::default().size(self.bytes)];
        self.ctx.one_shot(|cb| unsafe {
            let device = self.ctx.device();
            // Earlier submissions' shader and transfer writes, before the copy reads them.
            device_writes_visible(&self.ctx, cb);
            device.cmd_copy_buffer(cb, self.buffer, staging.buffer, &region);
            // A fence wait alone does not make device writes visible to the host.
            let to_host = [vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::HOST_READ)];
            device.cmd_pipeline_barrier(
                cb,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &to_host,
                &[],
                &[],
            );
        })?;
        staging.read_bytes(out)
    }
}

/// A memory barrier from every shader and transfer write recorded before it (in this or an
/// earlier submission of the queue) to every shader and transfer access after it (in this or a
/// later one): a fence wait alone makes device writes available to no later device access. Where
/// buffers are not mapped (discrete GPUs, forced staging), uploads, fills and readbacks are
/// transfers in their own submissions, ordered against the kernels only by this.
///
/// # Safety
/// `cb` must be recording.
unsafe fn device_writes_visible(ctx: &Context, cb: vk::CommandBuffer) {
    let barrier = [vk::MemoryBarrier::default()
        .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
        .dst_access_mask(
            vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::SHADER_WRITE
                | vk::AccessFlags::TRANSFER_READ
                | vk::AccessFlags::TRANSFER_WRITE,
        )];
    ctx.device().cmd_pipeline_barrier(
        cb,
        vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
        vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
        vk::DependencyFlags::empty(),
        &barrier,
        &[],
        &[],
    );
}

impl Drop for RawBuffer {
    fn drop(&mut self) {
        let device = self.ctx.device();
        unsafe {
            if self.mapped.is_some() {
                device.unmap_memory(self.memory);
            }
            device.destroy_buffer(self.buffer, None);
            device.free_memory(self.memory, None);
        }
    }
}

/// A storage buffer of `len` elements of `T`.
pub struct Buffer<T: Pod> {
    raw: RawBuffer,
    len: usize,
    _element: PhantomData<T>,
}

impl<T: Pod> Buffer<T> {
    /// A zero-filled buffer of `len` elements; `name` appears in errors and validation messages.
    pub fn zeroed(ctx: &Context, name: &str, len: usize) -> GpuResult<Self> {
        let buffer = Self::uninit(ctx, name, len)?;
        if let Some(ptr) = buffer.raw.mapped {
            unsafe { std::ptr::write_bytes(ptr.as_ptr(), 0, buffer.raw.bytes as usize) };
        } else {
            let b = buffer.raw.buffer;
            ctx.one_shot(|cb| unsafe {
                ctx.device().cmd_fill_buffer(cb, b, 0, vk::WHOLE_SIZE, 0);
                device_writes_visible(ctx, cb);
            })?;
        }
        Ok(buffer)
    }

    /// A buffer holding a copy of `data`.
    pub fn from_slice(ctx: &Context, name: &str, data: &[T]) -> GpuResult<Self> {
        let buffer = Self::uninit(ctx, name, data.len())?;
        buffer.write(data)?;
        Ok(buffer)
    }

    fn uninit(ctx: &Context, name: &str, len: usize) -> GpuResult<Self> {
        let bytes = (len as u64).saturating_mul(std::mem::size_of::<T>() as u64);
        Ok(Buffer {
            raw: RawBuffer::new(ctx, name, bytes, Placement::Device)?,
            len,
            _element: PhantomData,
        })
    }

    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the host writes and reads this buffer directly through a mapping (false: through
    /// staging copies, as on a discrete GPU or under forced staging).
    pub fn host_mapped(&self) -> bool {
        self.raw.mapped.is_some()
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Overwrites the whole buffer; `data` must have exactly `len()` elements.
    pub fn write(&self, data: &[T]) -> GpuResult<()> {
        if data.len() != self.len {
            return Err(GpuError::BufferLength {
                name: self.raw.name.clone(),
                expected: self.len,
                given: data.len(),
            });
        }
        self.raw.write_bytes(bytemuck::cast_slice(data))
    }

    /// Reads the whole buffer back.
    pub fn read(&self) -> GpuResult<Vec<T>> {
        let mut out = vec![T::zeroed(); self.len];
        self.raw.read_bytes(bytemuck::cast_slice_mut(&mut out))?;
        Ok(out)
    }
}

impl<T: Pod> GpuBuffer for Buffer<T> {
    fn handle(&self) -> vk::Buffer {
        self.raw.buffer
    }
    fn name(&self) -> &str {
        &self.raw.name
    }
    fn byte_size(&self) -> u64 {
        self.raw.bytes
    }
}
