//! Reflection of a compute module with naga's SPIR-V front end: the descriptor bindings (by
//! name), the push-constant block's size and the workgroup size. Kernel wrappers never restate
//! these; they only name the bindings they bind.
//!
//! A binding's name is the GLSL instance name of its block, or the block's type name when the
//! block is anonymous (`buffer Values { float values[]; };` is bound as "Values").

use naga::{AddressSpace, ShaderStage};

use super::error::{GpuError, GpuResult};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindingKind {
    StorageBuffer,
    UniformBuffer,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BindingInfo {
    pub name: String,
    pub binding: u32,
    pub kind: BindingKind,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Reflection {
    /// Set 0's bindings, sorted by binding number.
    pub bindings: Vec<BindingInfo>,
    pub push_constant_bytes: u32,
    pub workgroup_size: [u32; 3],
}

pub fn reflect(kernel: &str, spirv: &[u8]) -> GpuResult<Reflection> {
    let fail = |reason: String| GpuError::Reflection {
        kernel: kernel.to_string(),
        reason,
    };
    let module = naga::front::spv::parse_u8_slice(spirv, &naga::front::spv::Options::default())
        .map_err(|e| fail(format!("naga rejected the module: {e}")))?;
    let entry = match module.entry_points.as_slice() {
        [e] if e.stage == ShaderStage::Compute => e,
        _ => return Err(fail("expected exactly one compute entry point".into())),
    };
    let mut bindings = Vec::new();
    let mut push_constant_bytes = 0;
    for (_, var) in module.global_variables.iter() {
        let ty = &module.types[var.ty];
        let name = var
            .name
            .clone()
            .filter(|n| !n.is_empty())
            .or_else(|| ty.name.clone())
            .unwrap_or_default();
        match var.space {
            AddressSpace::Immediate => push_constant_bytes = ty.inner.size(module.to_ctx()),
            AddressSpace::Storage { .. } | AddressSpace::Uniform => {
                let Some(rb) = &var.binding else { continue };
                if rb.group != 0 {
                    return Err(fail(format!(
                        "binding `{name}` is in set {}; irad kernels use set 0 only",
                        rb.group
                    )));
                }
                let kind = if matches!(var.space, AddressSpace::Uniform) {
                    BindingKind::UniformBuffer
                } else {
                    BindingKind::StorageBuffer
                };
                if name.is_empty() {
                    return Err(fail(format!("binding {} has no name", rb.binding)));
                }
                bindings.push(BindingInfo {
                    name,
                    binding: rb.binding,
                    kind,
                });
            }
            AddressSpace::Handle => {
                return Err(fail(format!(
                    "binding `{name}` is an image or sampler; irad kernels bind buffers only"
                )))
            }
            _ => {}
        }
    }
    bindings.sort_by_key(|b| b.binding);
    for pair in bindings.windows(2) {
        if pair[0].name == pair[1].name {
            return Err(fail(format!("two bindings are named `{}`", pair[0].name)));
        }
        // Vulkan refuses a set layout that numbers two bindings alike; say which.
        if pair[0].binding == pair[1].binding {
            return Err(fail(format!(
                "`{}` and `{}` are both binding {}",
                pair[0].name, pair[1].name, pair[0].binding
            )));
        }
    }
    Ok(Reflection {
        bindings,
        push_constant_bytes,
        workgroup_size: entry.workgroup_size,
    })
}
