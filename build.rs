//! Compiles the GLSL in `shaders/` to SPIR-V (shaderc, Vulkan 1.2 / SPIR-V 1.5) into
//! OUT_DIR; `src/gpu/shaders.rs` embeds the results. The compiler's log is the build error.

use std::path::{Path, PathBuf};

/// (source, output name, macros defined). One source can yield several variants.
const SHADERS: &[(&str, &str, &[&str])] = &[
    ("raster.vert", "raster.vert.spv", &[]),
    ("raster.frag", "raster_range.frag.spv", &[]),
    ("raster.frag", "raster_range_ties.frag.spv", &["TIES"]),
    ("raster.frag", "raster_shadow.frag.spv", &["SHADOW_VIEW"]),
    ("raster.frag", "raster_shadow_ties.frag.spv", &["SHADOW_VIEW", "TIES"]),
    ("shadow_mask.comp", "shadow_mask.comp.spv", &[]),
    ("shadow_mask.comp", "shadow_mask_words.comp.spv", &["FROM_WORDS"]),
    ("raster.comp", "raster.comp.spv", &[]),
    ("raster.comp", "raster_large.comp.spv", &["LARGE_TRIANGLES"]),
    ("raster.comp", "raster_ties.comp.spv", &["TIES"]),
    ("raster.comp", "raster_large_ties.comp.spv", &["LARGE_TRIANGLES", "TIES"]),
    ("raster_resolve.comp", "raster_resolve.comp.spv", &[]),
    ("raster_resolve.comp", "raster_resolve_shadow.comp.spv", &["SHADOW_VIEW"]),
    ("score.comp", "score.comp.spv", &[]),
    ("effect_grazing.comp", "effect_grazing.comp.spv", &[]),
    ("effect_working_volume.comp", "effect_working_volume.comp.spv", &[]),
    ("effect_reflectivity.comp", "effect_reflectivity.comp.spv", &[]),
    ("effect_edges.comp", "effect_edges.comp.spv", &[]),
    ("effect_dropout.comp", "effect_dropout.comp.spv", &[]),
    ("effect_noise.comp", "effect_noise.comp.spv", &[]),
    ("effect_quantize.comp", "effect_quantize.comp.spv", &[]),
];

fn main() {
    let dir = Path::new("shaders");
    println!("cargo:rerun-if-changed=shaders");
    for entry in std::fs::read_dir(dir).expect("shaders/ exists") {
        println!("cargo:rerun-if-changed={}", entry.expect("readable shaders/").path().display());
    }
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let compiler = shaderc::Compiler::new().expect("shaderc initialises");
    for &(source, output, defines) in SHADERS {
        let path = dir.join(source);
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let kind = match path.extension().and_then(|e| e.to_str()) {
            Some("vert") => shaderc::ShaderKind::Vertex,
            Some("frag") => shaderc::ShaderKind::Fragment,
            Some("comp") => shaderc::ShaderKind::Compute,
            other => panic!("{source}: unknown shader stage {other:?}"),
        };
        let mut options = shaderc::CompileOptions::new().expect("shaderc options");
        options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_2 as u32);
        options.set_optimization_level(shaderc::OptimizationLevel::Performance);
        options.set_warnings_as_errors();
        for name in defines {
            options.add_macro_definition(name, None);
        }
        options.set_include_callback(|name, _, _, _| {
            let include = dir.join(name);
            std::fs::read_to_string(&include)
                .map(|content| shaderc::ResolvedInclude { resolved_name: include.display().to_string(), content })
                .map_err(|e| format!("{}: {e}", include.display()))
        });
        let spirv = compiler
            .compile_into_spirv(&text, kind, &path.display().to_string(), "main", Some(&options))
            .unwrap_or_else(|e| panic!("compiling {source} ({output}):\n{e}"));
        std::fs::write(out.join(output), spirv.as_binary_u8()).expect("OUT_DIR is writable");
    }
}
