//! SPIR-V compiled by `build.rs` from `shaders/` (its list is the one list of shaders),
//! embedded in the binary, and the shaders' side of the Rust↔GLSL contract as reflection
//! found it.
//! `include_bytes!` is not 4-byte aligned, so words are decoded with `ash::util::read_spv`.

use super::GpuContext;
use crate::error::{Error, Result, VkResultExt};
use ash::vk;

include!(concat!(env!("OUT_DIR"), "/shader_list.rs"));

/// What build.rs read back from the compiled shaders: `structs::NAME` (each member's offset
/// by name, `MEMBERS`, `SIZE`), and per shader `spec::SHADER` and `bindings::SHADER` (ids by
/// name). The Rust side of each contract is asserted against it ([`matches_shader_struct`]).
pub mod layout {
    include!(concat!(env!("OUT_DIR"), "/shader_layout.rs"));
}

/// Asserts at compile time that the Rust struct `$rust` holds the fields listed where the
/// shaders' struct `$glsl` (build.rs's reflection) has the members of the same names, that
/// the list names every member, and that both take the same size (to a 16-byte multiple:
/// padding may differ at the end). Reordering or renaming a field on either side fails the
/// build, and so do most additions and retypings (any that move a member or change the size).
macro_rules! matches_shader_struct {
    ($rust:ty, $glsl:ident { $($field:ident),* $(,)? }) => {
        const _: () = {
            use $crate::gpu::shaders::layout::structs::$glsl as glsl;
            $(assert!(
                std::mem::offset_of!($rust, $field) == glsl::$field,
                concat!(stringify!($rust), "::", stringify!($field), " is not where the shaders' ", stringify!($glsl), " has it")
            );)*
            assert!(
                [$(stringify!($field)),*].len() == glsl::MEMBERS,
                concat!(stringify!($rust), " lists fewer members than the shaders' ", stringify!($glsl), " has")
            );
            assert!(
                size_of::<$rust>().next_multiple_of(16) == glsl::SIZE.next_multiple_of(16),
                concat!(stringify!($rust), " and the shaders' ", stringify!($glsl), " differ in size")
            );
        };
    };
}
pub(crate) use matches_shader_struct;

/// Asserts at compile time that each shader binds, from binding 0 on, the resources named,
/// in that order, and no others: the order the Rust side hands its resources to a
/// [`StorageSet`](super::StorageSet) in, checked against the shaders' bindings (build.rs's
/// reflection; a block with no instance name is known by its type's name).
macro_rules! matches_shader_bindings {
    ([$($shader:ident),+ $(,)?] $resources:tt) => {
        $($crate::gpu::shaders::matches_shader_bindings!($shader $resources);)+
    };
    ($shader:ident { $($resource:ident),* $(,)? }) => {
        const _: () = {
            use $crate::gpu::shaders::layout::bindings::$shader as bound;
            let mut binding = 0;
            $(
                assert!(bound::$resource == binding, concat!(stringify!($shader), " binds ", stringify!($resource), " elsewhere"));
                binding += 1;
            )*
            assert!(bound::BINDINGS == binding, concat!(stringify!($shader), " binds other resources too"));
        };
    };
}
pub(crate) use matches_shader_bindings;

/// A shader module that lives only as long as pipeline creation needs it.
pub struct ShaderModule<'a> {
    ctx: &'a GpuContext,
    pub raw: vk::ShaderModule,
}

impl<'a> ShaderModule<'a> {
    pub fn new(ctx: &'a GpuContext, spirv: &[u8], name: &str) -> Result<Self> {
        let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
            .map_err(|e| Error::Unsupported(format!("embedded SPIR-V {name} is malformed: {e}")))?;
        let info = vk::ShaderModuleCreateInfo::default().code(&words);
        // SAFETY: valid SPIR-V from shaderc.
        let raw = unsafe { ctx.device.create_shader_module(&info, None) }.vk(name)?;
        ctx.name_object(raw, name);
        Ok(Self { ctx, raw })
    }
}

impl Drop for ShaderModule<'_> {
    fn drop(&mut self) {
        // SAFETY: modules are not needed once pipelines are created.
        unsafe { self.ctx.device.destroy_shader_module(self.raw, None) };
    }
}
