//! A compute kernel: its embedded SPIR-V, the layout reflected from it, its pipeline, and a
//! dispatch that checks every binding by name against what the shader declares.

use ash::vk;
use bytemuck::Pod;

use super::buffer::GpuBuffer;
use super::commands::Commands;
use super::context::Context;
use super::error::{GpuError, GpuResult, VkContext};
use super::reflect::{reflect, BindingInfo, BindingKind, Reflection};
use super::spirv;

/// One buffer bound to one of a kernel's bindings, by the binding's name.
pub struct Binding<'a> {
    pub name: &'a str,
    pub buffer: &'a dyn GpuBuffer,
}

/// Bytes a uniform block may span on every Vulkan device (the minimum maxUniformBufferRange).
pub const MAX_UNIFORM_BLOCK_BYTES: u64 = 16384;

pub fn bind<'a>(name: &'a str, buffer: &'a dyn GpuBuffer) -> Binding<'a> {
    Binding { name, buffer }
}

pub struct Kernel {
    ctx: Context,
    name: String,
    reflection: Reflection,
    set_layout: vk::DescriptorSetLayout,
    pipeline_layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
}

/// The embedded spv/<group>/<name>.spv, or the error naming the kernel.
fn embedded(name: &str) -> GpuResult<&'static [u8]> {
    spirv::embedded(name).ok_or_else(|| GpuError::KernelNotEmbedded {
        kernel: name.into(),
    })
}

impl Kernel {
    /// The kernel built from the embedded `spv/<group>/<name>.spv`.
    pub fn new(ctx: &Context, name: &str) -> GpuResult<Self> {
        Self::specialized(ctx, name, &[])
    }

    /// The kernel with its specialization constants 0, 1, .. set to `constants` (32-bit
    /// values: a GLSL `layout(constant_id = i) const bool` takes 0 or 1); the module's defaults
    /// stand for ids past the slice.
    pub fn specialized(ctx: &Context, name: &str, constants: &[u32]) -> GpuResult<Self> {
        let bytes = embedded(name)?;
        Self::from_spirv(ctx, name, bytes, constants)
    }

    /// Checks that `spv/<group>/<name>.spv` is embedded and its layout reflects, building nothing.
    pub fn check_embedded(name: &str) -> GpuResult<()> {
        let bytes = embedded(name)?;
        reflect(name, bytes).map(|_| ())
    }

    pub fn from_spirv(
        ctx: &Context,
        name: &str,
        bytes: &[u8],
        constants: &[u32],
    ) -> GpuResult<Self> {
        let reflection = reflect(name, bytes)?;
        let words = ash::util::read_spv(&mut std::io::Cursor::new(bytes)).map_err(|e| {
            GpuError::Reflection {
                kernel: name.into(),
                reason: format!("not SPIR-V: {e}"),
            }
        })?;
        let device = ctx.device();

        let layout_bindings: Vec<vk::DescriptorSetLayoutBinding> = reflection
            .bindings
            .iter()
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b.binding)
                    .descriptor_type(descriptor_type(b.kind))
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        // Build each object in turn; on failure, destroy what exists so far.
        let mut kernel = Kernel {
            ctx: ctx.clone(),
            name: name.to_string(),
            reflection,
            set_layout: vk::DescriptorSetLayout::null(),
            pipeline_layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
        };
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings);
        kernel.set_layout = unsafe { device.create_descriptor_set_layout(&info, None) }
            .vk("vkCreateDescriptorSetLayout")?;
        let push = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .size(kernel.reflection.push_constant_bytes)];
        let set_layouts = [kernel.set_layout];
        let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if kernel.reflection.push_constant_bytes > 0 {
            info = info.push_constant_ranges(&push);
        }
        kernel.pipeline_layout =
            unsafe { device.create_pipeline_layout(&info, None) }.vk("vkCreatePipelineLayout")?;
        let module_info = vk::ShaderModuleCreateInfo::default().code(&words);
        let module = unsafe { device.create_shader_module(&module_info, None) }
            .vk("vkCreateShaderModule")?;
        let entries: Vec<vk::SpecializationMapEntry> = (0..constants.len() as u32)
            .map(|i| {
                vk::SpecializationMapEntry::default()
                    .constant_id(i)
                    .offset(4 * i)
                    .size(4)
            })
            .collect();
        let specialization = vk::SpecializationInfo::default()
            .map_entries(&entries)
            .data(bytemuck::cast_slice(constants));
        let mut stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main");
        if !constants.is_empty() {
            stage = stage.specialization_info(&specialization);
        }
        let create = [vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(kernel.pipeline_layout)];
        let pipeline =
            unsafe { device.create_compute_pipelines(vk::PipelineCache::null(), &create, None) };
        unsafe { device.destroy_shader_module(module, None) };
        kernel.pipeline = pipeline.map_err(|(_, result)| GpuError::Vulkan {
            call: "vkCreateComputePipelines",
            result,
        })?[0];
        ctx.name_object(kernel.pipeline, name);
        Ok(kernel)
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn bindings(&self) -> &[BindingInfo] {
        &self.reflection.bindings
    }

    pub fn workgroup_size(&self) -> [u32; 3] {
        self.reflection.workgroup_size
    }

    pub fn push_constant_bytes(&self) -> u32 {
        self.reflection.push_constant_bytes
    }

    /// Records a dispatch of `groups` workgroups.
    pub fn dispatch<'a, P: Pod>(
        &'a self,
        cmd: &mut Commands<'a>,
        bindings: &[Binding<'a>],
        push: &P,
        groups: [u32; 3],
    ) -> GpuResult<()> {
        let buffers = self.resolve(bindings)?;
        for (info, buffer) in &buffers {
            if info.kind == BindingKind::UniformBuffer
                && buffer.byte_size() > MAX_UNIFORM_BLOCK_BYTES
            {
                return Err(GpuError::UniformBlockTooLarge {
                    kernel: self.name.clone(),
                    binding: info.name.clone(),
                    bytes: buffer.byte_size(),
                    limit: MAX_UNIFORM_BLOCK_BYTES,
                });
            }
        }
        let push = bytemuck::bytes_of(push);
        if push.len() != self.reflection.push_constant_bytes as usize {
            return Err(GpuError::PushConstantSize {
                kernel: self.name.clone(),
                expected: self.reflection.push_constant_bytes,
                given: push.len(),
            });
        }
        let limit = self.ctx.info().max_workgroup_count;
        if (0..3).any(|i| groups[i] > limit[i]) {
            return Err(GpuError::TooManyWorkgroups {
                kernel: self.name.clone(),
                groups,
                limit,
            });
        }
        cmd.record_dispatch(self, &buffers, push, groups)
    }

    /// Records a dispatch covering `threads` invocations (rounded up to whole workgroups).
    pub fn dispatch_threads<'a, P: Pod>(
        &'a self,
        cmd: &mut Commands<'a>,
        bindings: &[Binding<'a>],
        push: &P,
        threads: [u32; 3],
    ) -> GpuResult<()> {
        let wg = self.reflection.workgroup_size;
        let groups = [0, 1, 2].map(|i| threads[i].div_ceil(wg[i].max(1)));
        self.dispatch(cmd, bindings, push, groups)
    }

    /// Matches the given bindings to the declared ones: every declared binding bound exactly
    /// once, nothing bound that the shader does not declare.
    fn resolve<'a>(
        &self,
        given: &[Binding<'a>],
    ) -> GpuResult<Vec<(&BindingInfo, &'a dyn GpuBuffer)>> {
        let declared = &self.reflection.bindings;
        for (i, b) in given.iter().enumerate() {
            if !declared.iter().any(|d| d.name == b.name) {
                return Err(GpuError::UnknownBinding {
                    kernel: self.name.clone(),
                    binding: b.name.to_string(),
                    declared: declared
                        .iter()
                        .map(|d| d.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", "),
                });
            }
            if given[..i].iter().any(|o| o.name == b.name) {
                return Err(GpuError::DuplicateBinding {
                    kernel: self.name.clone(),
                    binding: b.name.to_string(),
                });
            }
        }
        declared
            .iter()
            .map(|d| match given.iter().find(|b| b.name == d.name) {
                Some(b) => Ok((d, b.buffer)),
                None => Err(GpuError::MissingBinding {
                    kernel: self.name.clone(),
                    binding: d.name.clone(),
                    index: d.binding,
                }),
            })
            .collect()
    }

    pub(crate) fn raw(&self) -> (vk::Pipeline, vk::PipelineLayout, vk::DescriptorSetLayout) {
        (self.pipeline, self.pipeline_layout, self.set_layout)
    }
}

pub(crate) fn descriptor_type(kind: BindingKind) -> vk::DescriptorType {
    match kind {
        BindingKind::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
        BindingKind::UniformBuffer => vk::DescriptorType::UNIFORM_BUFFER,
    }
}

impl Drop for Kernel {
    fn drop(&mut self) {
        let device = self.ctx.device();
        unsafe {
            device.destroy_pipeline(self.pipeline, None);
            device.destroy_pipeline_layout(self.pipeline_layout, None);
            device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
