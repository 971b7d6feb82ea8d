//! The layout contracts between the Rust structs that mirror GLSL structs and the kernels,
//! checked against the committed SPIR-V by naga's reflection (tests only; nothing here is in
//! a release build).
//!
//! Every `#[repr(C)]` mirror declares its layout next to its definition with [`gpu_layout!`]
//! in a `GPU_LAYOUTS` list of its module, and [`mirrors`] gathers those lists. The test
//! `every_mirror_matches_its_glsl_struct` then checks, over every embedded kernel:
//!
//! - each mirror's size equals its GLSL struct's size (naga's span: the members rounded up to
//!   the struct's alignment under the block's std430/std140 rules, so a mirror carries explicit
//!   trailing padding; a push-constant block's span is also what `Kernel::dispatch` asks
//!   `bytes_of(push)` to be), and every array of that struct strides by that size;
//! - each GLSL member's offset equals where the mirror puts it (by name; a Rust field named
//!   differently maps to its member explicitly), and every member but padding (`_pad*`,
//!   `pad*`) has a Rust field; a mismatch names the Rust struct, the GLSL struct, the kernel,
//!   the member and both offsets;
//! - a struct name means one layout in every kernel that uses it in a buffer, uniform or
//!   push-constant block (push-constant blocks are matched per kernel instead: several kernels
//!   name theirs `ShadeParams`);
//! - every struct a kernel uses as a buffer element, a buffer's or uniform's whole content, or
//!   its push-constant block has a mirror, or is in [`WITHOUT_MIRROR`] with the reason; and a
//!   mirror whose GLSL struct or kernel is gone fails, so the list cannot go stale.
//!
//! `binding_numbers_agree_across_kernels` checks the bindings: no two in a kernel share a
//! number (reflection refuses that kernel), and a binding name has one number in every kernel
//! that declares it, but for the [`BINDING_EXCEPTIONS`].

/// A Rust struct's layout as it mirrors a GLSL struct.
pub(crate) struct GpuLayout {
    /// The Rust type's path, for messages.
    pub rust: &'static str,
    pub glsl: Glsl,
    /// `size_of` the Rust type.
    pub size: usize,
    pub fields: &'static [GpuField],
}

/// What a mirror mirrors.
pub(crate) enum Glsl {
    /// The GLSL struct of this name, in whichever kernels declare it (buffer elements, uniform
    /// contents, structs read whole from a buffer).
    Struct(&'static str),
    /// The push-constant block of each of these kernels, whatever its GLSL type name.
    PushConstants(&'static [&'static str]),
}

/// One Rust field's place in the GLSL struct.
pub(crate) struct GpuField {
    /// The Rust field (with the part of it meant, for a field that spans several members).
    pub rust: &'static str,
    /// The GLSL member holding it; `None` for Rust-side padding.
    pub member: Option<&'static str>,
    /// Where the Rust struct puts it.
    pub offset: usize,
    /// Its offset inside the GLSL member (`t_max` is `origin_t_max.w`: 12).
    pub within: usize,
}

/// A mirror's layout: `gpu_layout!(Type as "GlslStruct" { fields })` for a GLSL struct, or
/// `gpu_layout!(Type in ["kernel", ...] { fields })` for the push-constant block of those
/// kernels. The fields list every Rust field, in any order (a missing or unknown one does not
/// compile): `name` for the GLSL member of the same name, `name => "member"` for another
/// name, `name => "member" + 12` for a field inside a member, and `name => pad` for padding.
macro_rules! gpu_layout {
    ($ty:ident as $glsl:literal { $($body:tt)* }) => {
        $crate::gpu::contracts::gpu_layout!(
            @layout $ty, $crate::gpu::contracts::Glsl::Struct($glsl), $($body)*
        )
    };
    ($ty:ident in [$($kernel:literal),+ $(,)?] { $($body:tt)* }) => {
        $crate::gpu::contracts::gpu_layout!(
            @layout $ty, $crate::gpu::contracts::Glsl::PushConstants(&[$($kernel),+]), $($body)*
        )
    };
    (@layout $ty:ident, $glsl:expr, $($field:ident $(=> $target:tt $(+ $within:literal)?)?),+ $(,)?) => {{
        // Every Rust field is listed: this pattern has no `..`, so a field missing from the
        // list does not compile (rustc says "pattern requires `..` due to inaccessible fields").
        const _: fn($ty) = |v: $ty| {
            let $ty { $($field: _),+ } = v; // error here: the list misses a Rust field
        };
        $crate::gpu::contracts::GpuLayout {
            rust: concat!(module_path!(), "::", stringify!($ty)),
            glsl: $glsl,
            size: ::core::mem::size_of::<$ty>(),
            fields: &[$($crate::gpu::contracts::gpu_layout!(
                @field $ty, $field $(=> $target $(+ $within)?)?
            )),+],
        }
    }};
    (@field $ty:ident, $field:ident) => {
        $crate::gpu::contracts::GpuField {
            rust: stringify!($field),
            member: Some(stringify!($field)),
            offset: ::core::mem::offset_of!($ty, $field),
            within: 0,
        }
    };
    (@field $ty:ident, $field:ident => pad) => {
        $crate::gpu::contracts::GpuField {
            rust: stringify!($field),
            member: None,
            offset: ::core::mem::offset_of!($ty, $field),
            within: 0,
        }
    };
    (@field $ty:ident, $field:ident => $member:tt) => {
        $crate::gpu::contracts::gpu_layout!(@field $ty, $field => $member + 0)
    };
    (@field $ty:ident, $field:ident => $member:tt + $within:literal) => {
        $crate::gpu::contracts::GpuField {
            rust: stringify!($field),
            member: Some($member),
            offset: ::core::mem::offset_of!($ty, $field),
            within: $within,
        }
    };
}
pub(crate) use gpu_layout;

/// Every mirror, from each module's `GPU_LAYOUTS` (a module left out here leaves its list
/// unused, which the dead-code lint reports).
pub(crate) fn mirrors() -> Vec<&'static GpuLayout> {
    use crate::methods as m;
    [
        crate::bvh::GPU_LAYOUTS,
        crate::trace::GPU_LAYOUTS,
        crate::scene::gpu::GPU_LAYOUTS,
        crate::scene::texture_upload::GPU_LAYOUTS,
        crate::gpu::copy::GPU_LAYOUTS,
        crate::gpu::prefix_sum::GPU_LAYOUTS,
        m::bir::light_cdf::GPU_LAYOUTS,
        m::bir::resample::GPU_LAYOUTS,
        m::bir::reverse::GPU_LAYOUTS,
        m::bsdf_draws::GPU_LAYOUTS,
        m::bundles::light_vertices::GPU_LAYOUTS,
        m::bundles::paths::GPU_LAYOUTS,
        m::bundles::ray_bundles::GPU_LAYOUTS,
        m::compensation::GPU_LAYOUTS,
        m::direct_alpha::GPU_LAYOUTS,
        m::envmap::cube::GPU_LAYOUTS,
        m::envmap::pyramid::GPU_LAYOUTS,
        m::envmap::shade::GPU_LAYOUTS,
        m::equirect_table::GPU_LAYOUTS,
        m::gbuffer::GPU_LAYOUTS,
        m::ir::filter::GPU_LAYOUTS,
        m::ir::gather::GPU_LAYOUTS,
        m::ir::walk::GPU_LAYOUTS,
        m::ir::reuse::GPU_LAYOUTS,
        m::lightfield::GPU_LAYOUTS,
        m::lightfield::tables::GPU_LAYOUTS,
        m::paths::GPU_LAYOUTS,
        m::restir::kernels::GPU_LAYOUTS,
        crate::sampling::light_bvh::GPU_LAYOUTS,
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// GLSL structs that kernels use in their interface and that have no Rust mirror, and why.
pub(crate) const WITHOUT_MIRROR: &[(&str, &str)] = &[
    (
        "LoopCuts",
        "one uint flag (bvh.glsl); the host holds it as a Buffer<u32> of 1",
    ),
    (
        "Diagnostics",
        "one uint counter (radiance.glsl); the host holds it as a Buffer<u32> of 1",
    ),
    (
        "ResampleStats",
        "two uint counters (resample_vpls.comp); the host holds them as a Buffer<u32> of 2",
    ),
    (
        "SideWeights",
        "one vec4 (resample_vpls.comp, update_side_weights.comp); the host holds it as a \
         Buffer<[f32; 4]> of 1",
    ),
    (
        "LightQuery",
        "sample_light_bvh.comp's input, a test kernel's: tests/light_bvh.rs writes it as \
         [Vec4; 2] (p and u, n)",
    ),
    (
        "CdfState",
        "build_light_cdf.comp's carry between its dispatches, GPU-only: the host only zeroes it",
    ),
];

/// Bindings numbered unlike the other kernels that declare the same name: (kernel, binding
/// name, its number there, why).
pub(crate) const BINDING_EXCEPTIONS: &[(&str, &str, u32, &str)] = &[
    (
        "scan_blocks",
        "Scanned",
        2,
        "the prefix sum is generic: its bindings name roles (Values 0 .. RowTotals 3), \
         not bir's buffers of those names",
    ),
    (
        "scan_blocks",
        "RowTotals",
        3,
        "the prefix sum is generic: its bindings name roles (Values 0 .. RowTotals 3), \
         not bir's buffers of those names",
    ),
    (
        "weigh_luminaire_columns",
        "LuminaireTexels",
        0,
        "a table-building kernel that numbers its own bindings from 0 (luminaire_tables.glsl \
         binds the same buffer at 30)",
    ),
    (
        "transpose_luminaire_columns",
        "ColumnCdf",
        0,
        "a table-building kernel that numbers its own bindings from 0 (luminaire_tables.glsl \
         binds the same buffer at 31)",
    ),
];

#[cfg(test)]
mod tests {
    use std::collections::{BTreeMap, BTreeSet};
    use std::fmt::Write;

    use naga::{AddressSpace, ArraySize, Handle, Module, Type, TypeInner};

    use super::{mirrors, Glsl, GpuLayout, BINDING_EXCEPTIONS, WITHOUT_MIRROR};
    use crate::gpu::reflect::reflect;
    use crate::gpu::spirv::EMBEDDED;

    struct Kernel {
        name: &'static str,
        module: Module,
    }

    fn kernels() -> Vec<Kernel> {
        assert!(EMBEDDED.len() > 30, "spv/ is not embedded");
        EMBEDDED
            .iter()
            .map(|&(name, bytes)| Kernel {
                name,
                module: naga::front::spv::parse_u8_slice(bytes, &Default::default())
                    .unwrap_or_else(|e| panic!("{name}: naga rejects the module: {e}")),
            })
            .collect()
    }

    /// How a kernel's interface uses a struct.
    #[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Debug)]
    enum Use {
        /// A buffer's element, its or a uniform's whole content, or a struct inside one.
        Shared,
        /// The kernel's push-constant block.
        PushConstants,
    }

    /// The structs of `kernel`'s buffers, uniforms and push constants. A block whose one
    /// member is an array of structs or a struct (`buffer Vpls { Vpl vpls[]; }`, `uniform
    /// SceneParams { SceneConstants scene; }`) is a wrapper: its element is what the host
    /// mirrors. Other blocks count themselves (`buffer ResampleStats { uint a; uint b; }`).
    fn interface_structs(module: &Module) -> Vec<(Handle<Type>, Use)> {
        let mut out = Vec::new();
        // `ty` used as `kind`, and the structs inside it as shared structs.
        let push = |ty: Handle<Type>, kind: Use, out: &mut Vec<_>| {
            let mut stack = vec![(ty, kind)];
            while let Some((ty, kind)) = stack.pop() {
                let TypeInner::Struct { members, .. } = &module.types[ty].inner else {
                    continue;
                };
                if !out.contains(&(ty, kind)) {
                    out.push((ty, kind));
                }
                for m in members {
                    stack.push((element(module, m.ty), Use::Shared));
                }
            }
        };
        for (_, var) in module.global_variables.iter() {
            let kind = match var.space {
                AddressSpace::Immediate => Use::PushConstants,
                AddressSpace::Storage { .. } | AddressSpace::Uniform => Use::Shared,
                _ => continue,
            };
            let block = var.ty;
            if kind == Use::Shared {
                if let TypeInner::Struct { members, .. } = &module.types[block].inner {
                    if let [only] = members.as_slice() {
                        let inner = element(module, only.ty);
                        if only.offset == 0 && is_struct(module, inner) {
                            push(inner, Use::Shared, &mut out);
                            continue;
                        }
                        if inner != only.ty {
                            continue; // an array of scalars or vectors
                        }
                    }
                }
            }
            push(block, kind, &mut out);
        }
        out
    }

    /// The element type of an array (of arrays), else `ty`.
    fn element(module: &Module, mut ty: Handle<Type>) -> Handle<Type> {
        while let TypeInner::Array { base, .. } = module.types[ty].inner {
            ty = base;
        }
        ty
    }

    fn is_struct(module: &Module, ty: Handle<Type>) -> bool {
        matches!(module.types[ty].inner, TypeInner::Struct { .. })
    }

    fn name(module: &Module, ty: Handle<Type>) -> &str {
        module.types[ty].name.as_deref().unwrap_or("<unnamed>")
    }

    /// A type's layout without its member names: sizes, offsets, strides, scalar types (an
    /// atomic counts as its scalar).
    fn signature(module: &Module, ty: Handle<Type>) -> String {
        match &module.types[ty].inner {
            TypeInner::Struct { members, span } => {
                let members: Vec<String> = members
                    .iter()
                    .map(|m| format!("@{} {}", m.offset, signature(module, m.ty)))
                    .collect();
                format!("{{{} bytes: {}}}", span, members.join(", "))
            }
            TypeInner::Array { base, size, stride } => {
                let n = match size {
                    ArraySize::Constant(n) => n.to_string(),
                    _ => String::new(),
                };
                format!("[{}; {n} stride {stride}]", signature(module, *base))
            }
            // naga's front end turns the members a kernel uses atomically into atomics, leaving
            // the struct as declared in the arena too: one layout.
            TypeInner::Atomic(scalar) => format!("{:?}", TypeInner::Scalar(*scalar)),
            other => format!("{other:?}"),
        }
    }

    /// The offset just past a struct's last member.
    fn members_end(module: &Module, ty: Handle<Type>) -> u32 {
        let TypeInner::Struct { members, .. } = &module.types[ty].inner else {
            unreachable!()
        };
        members
            .iter()
            .map(|m| m.offset + module.types[m.ty].inner.size(module.to_ctx()))
            .max()
            .unwrap_or(0)
    }

    fn is_padding(member: &str) -> bool {
        member.starts_with("_pad") || member.starts_with("pad")
    }

    /// Compares `layout` with the GLSL struct `ty` of `module`, declared in the kernels `k`
    /// names, appending each mismatch.
    fn compare(
        layout: &GpuLayout,
        module: &Module,
        ty: Handle<Type>,
        k: &str,
        errors: &mut Vec<String>,
    ) {
        let TypeInner::Struct { members, span } = &module.types[ty].inner else {
            unreachable!()
        };
        let (rust, glsl) = (layout.rust, name(module, ty));
        if layout.size != *span as usize {
            errors.push(format!(
                "{rust} is {} bytes, but GLSL {glsl} (in {k}) is {span} (its last member ends \
                 at {})",
                layout.size,
                members_end(module, ty)
            ));
        }
        for field in layout.fields {
            let Some(member) = field.member else { continue };
            let Some(m) = members.iter().find(|m| m.name.as_deref() == Some(member)) else {
                let names: Vec<&str> = members.iter().filter_map(|m| m.name.as_deref()).collect();
                errors.push(format!(
                    "{rust}: field `{}` maps to member `{member}`, which GLSL {glsl} (in {k}) \
                     lacks (its members: {})",
                    field.rust,
                    names.join(", ")
                ));
                continue;
            };
            let glsl_offset = m.offset as usize + field.within;
            if glsl_offset != field.offset {
                let at = if field.within > 0 {
                    format!("`{member}` + {}", field.within)
                } else {
                    format!("`{member}`")
                };
                errors.push(format!(
                    "{rust}: GLSL {glsl} (in {k}) member {at} is at offset {glsl_offset}, but \
                     Rust field `{}` is at offset {}",
                    field.rust, field.offset
                ));
            }
        }
        for m in members {
            let member = m.name.as_deref().unwrap_or("");
            if !is_padding(member) && !layout.fields.iter().any(|f| f.member == Some(member)) {
                errors.push(format!(
                    "{rust}: GLSL {glsl} (in {k}) member `{member}` (offset {}) has no Rust field",
                    m.offset
                ));
            }
        }
    }

    #[test]
    fn every_mirror_matches_its_glsl_struct() {
        let kernels = kernels();
        let mirrors = mirrors();
        let mut errors = Vec::new();

        // Every named struct of every kernel, and the interface's uses of them.
        let mut by_name: BTreeMap<&str, Vec<(&Kernel, Handle<Type>)>> = BTreeMap::new();
        let mut shared: BTreeMap<&str, Vec<(&Kernel, Handle<Type>)>> = BTreeMap::new();
        let mut push_blocks: BTreeMap<&str, Handle<Type>> = BTreeMap::new();
        for kernel in &kernels {
            for (ty, t) in kernel.module.types.iter() {
                if let (Some(n), TypeInner::Struct { .. }) = (&t.name, &t.inner) {
                    by_name.entry(n).or_default().push((kernel, ty));
                }
            }
            for (ty, kind) in interface_structs(&kernel.module) {
                match kind {
                    Use::Shared => shared
                        .entry(name(&kernel.module, ty))
                        .or_default()
                        .push((kernel, ty)),
                    Use::PushConstants => {
                        push_blocks.insert(kernel.name, ty);
                    }
                }
            }
        }

        // One layout per shared struct name.
        let mirrored: BTreeSet<&str> = mirrors
            .iter()
            .filter_map(|l| match l.glsl {
                Glsl::Struct(n) => Some(n),
                Glsl::PushConstants(_) => None,
            })
            .collect();
        for n in shared.keys().copied().chain(mirrored.iter().copied()) {
            let Some(uses) = by_name.get(n) else { continue };
            let (k0, t0) = uses[0];
            let s0 = signature(&k0.module, t0);
            for &(k, t) in &uses[1..] {
                let s = signature(&k.module, t);
                if s != s0 {
                    errors.push(format!(
                        "GLSL struct {n} has two layouts: {s0} in {} and {s} in {}",
                        k0.name, k.name
                    ));
                }
            }
        }

        // Each mirror against each kernel's struct.
        let mut claimed: BTreeMap<&str, &str> = BTreeMap::new();
        for layout in &mirrors {
            match layout.glsl {
                Glsl::Struct(n) => {
                    let Some(uses) = by_name.get(n) else {
                        errors.push(format!(
                            "{}: no kernel declares a GLSL struct {n}",
                            layout.rust
                        ));
                        continue;
                    };
                    // Once per distinct declaration (layout and member names), naming the
                    // kernels that share it.
                    let mut declarations: BTreeMap<String, Vec<(&Kernel, Handle<Type>)>> =
                        BTreeMap::new();
                    for &(kernel, ty) in uses {
                        let m = &kernel.module;
                        let TypeInner::Struct { members, .. } = &m.types[ty].inner else {
                            unreachable!()
                        };
                        let names: Vec<&str> =
                            members.iter().filter_map(|x| x.name.as_deref()).collect();
                        let key = format!("{} {}", signature(m, ty), names.join(","));
                        declarations.entry(key).or_default().push((kernel, ty));
                    }
                    for same in declarations.values() {
                        let mut ks: Vec<&str> = same.iter().map(|(k, _)| k.name).collect();
                        ks.dedup();
                        let k = match ks.as_slice() {
                            [one] => one.to_string(),
                            [first, rest @ ..] => {
                                format!("{first} and {} other kernels", rest.len())
                            }
                            [] => unreachable!(),
                        };
                        let (kernel, ty) = same[0];
                        compare(layout, &kernel.module, ty, &k, &mut errors);
                    }
                    // Arrays of it stride by the Rust size.
                    for kernel in &kernels {
                        let m = &kernel.module;
                        for (_, t) in m.types.iter() {
                            if let TypeInner::Array { base, stride, .. } = t.inner {
                                if m.types[base].name.as_deref() == Some(n)
                                    && stride as usize != layout.size
                                {
                                    errors.push(format!(
                                        "{}: {} bytes, but an array of GLSL {n} (in {}) strides \
                                         by {stride}",
                                        layout.rust, layout.size, kernel.name
                                    ));
                                }
                            }
                        }
                    }
                }
                Glsl::PushConstants(names) => {
                    for &k in names {
                        let Some(kernel) = kernels.iter().find(|x| x.name == k) else {
                            errors.push(format!("{}: no kernel is named {k}", layout.rust));
                            continue;
                        };
                        let Some(&ty) = push_blocks.get(k) else {
                            errors
                                .push(format!("{}: kernel {k} has no push constants", layout.rust));
                            continue;
                        };
                        if let Some(other) = claimed.insert(k, layout.rust) {
                            errors.push(format!(
                                "kernel {k}'s push constants are mirrored twice: by {other} and {}",
                                layout.rust
                            ));
                        }
                        compare(layout, &kernel.module, ty, k, &mut errors);
                    }
                }
            }
        }

        // Every interface struct has a mirror or a reason not to.
        let excused: BTreeSet<&str> = WITHOUT_MIRROR.iter().map(|&(n, _)| n).collect();
        for (n, uses) in &shared {
            if !mirrored.contains(n) && !excused.contains(n) {
                let ks: BTreeSet<&str> = uses.iter().map(|(k, _)| k.name).collect();
                errors.push(format!(
                    "GLSL struct {n} (in {}) has no Rust mirror: declare one with gpu_layout! \
                     or say why not in WITHOUT_MIRROR",
                    ks.into_iter().collect::<Vec<_>>().join(", ")
                ));
            }
        }
        for n in &excused {
            if mirrored.contains(n) {
                errors.push(format!("{n} is in WITHOUT_MIRROR but has a mirror"));
            } else if !shared.contains_key(n) {
                errors.push(format!(
                    "{n} is in WITHOUT_MIRROR but no kernel's interface uses it"
                ));
            }
        }
        for (k, &ty) in &push_blocks {
            if !claimed.contains_key(k) {
                let kernel = kernels.iter().find(|x| x.name == *k).unwrap();
                errors.push(format!(
                    "kernel {k}'s push constants (GLSL {}) have no Rust mirror",
                    name(&kernel.module, ty)
                ));
            }
        }

        let mut report = String::new();
        for e in &errors {
            writeln!(report, "  {e}").unwrap();
        }
        assert!(
            errors.is_empty(),
            "{} layout contract(s) broken:\n{report}",
            errors.len()
        );
        // The lists are what the test ran over (a sanity floor, not a count to keep in step).
        assert!(mirrors.len() >= 48 && shared.len() >= 15 && push_blocks.len() >= 34);
    }

    #[test]
    fn binding_numbers_agree_across_kernels() {
        let mut numbers: BTreeMap<String, BTreeMap<u32, Vec<&str>>> = BTreeMap::new();
        let mut excepted = BTreeSet::new();
        for &(kernel, bytes) in EMBEDDED {
            // Reflection refuses a kernel that gives two bindings one number.
            let reflection = reflect(kernel, bytes).unwrap_or_else(|e| panic!("{e}"));
            for b in &reflection.bindings {
                let exception = BINDING_EXCEPTIONS
                    .iter()
                    .find(|&&(k, n, _, _)| k == kernel && n == b.name);
                if let Some(&(_, n, number, _)) = exception {
                    assert_eq!(
                        b.binding, number,
                        "{kernel} binds {n} at {}, not at its BINDING_EXCEPTIONS number",
                        b.binding
                    );
                    excepted.insert((kernel, n));
                    continue;
                }
                numbers
                    .entry(b.name.clone())
                    .or_default()
                    .entry(b.binding)
                    .or_default()
                    .push(kernel);
            }
        }
        let mut errors = Vec::new();
        for (name, by_number) in &numbers {
            if by_number.len() > 1 {
                let places: Vec<String> = by_number
                    .iter()
                    .map(|(n, ks)| format!("{n} in {}", ks.join(", ")))
                    .collect();
                errors.push(format!("binding {name} is numbered {}", places.join("; ")));
            }
        }
        for &(kernel, name, number, _) in BINDING_EXCEPTIONS {
            if !excepted.contains(&(kernel, name)) {
                errors.push(format!("BINDING_EXCEPTIONS: {kernel} declares no {name}"));
            } else if numbers.get(name).is_none_or(|b| b.contains_key(&number)) {
                errors.push(format!(
                    "BINDING_EXCEPTIONS: {kernel}'s {name} at {number} is no exception (no other \
                     kernel declares it, or they number it alike)"
                ));
            }
        }
        assert!(errors.is_empty(), "{}", errors.join("\n"));
    }
}
