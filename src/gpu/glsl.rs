// GLSL -> SPIR-V with shaderc (glslang), shared by build.rs (which `include!`s this file and
// embeds every shader in the binary) and the window's shader hot reload (src/gpu/mod.rs,
// `compile_shader`), so that both compile with the same options, includes and header.
// Paths are spelt out in full: build.rs has imports of its own.

/// Compile `glsl/<rel>` (a `.vert`, `.frag`, `.comp` or `.geom` under `glsl`) to SPIR-V bytes.
/// `header` is the generated `prism_shared.glsl`. Every file read through `#include` is
/// pushed onto `includes`. Errors read `glsl/dir/file:LINE: error: ...`, naming the shader (or
/// the included file) and the line.
pub fn compile_glsl(
    compiler: &shaderc::Compiler,
    glsl: &std::path::Path,
    rel: &str,
    header: &str,
    includes: &mut Vec<std::path::PathBuf>,
) -> Result<Vec<u8>, String> {
    let file = glsl.join(rel);
    let kind = match file.extension().and_then(|e| e.to_str()) {
        Some("vert") => shaderc::ShaderKind::Vertex,
        Some("frag") => shaderc::ShaderKind::Fragment,
        Some("comp") => shaderc::ShaderKind::Compute,
        Some("geom") => shaderc::ShaderKind::Geometry,
        _ => return Err(format!("glsl/{rel}: not a shader stage (.vert, .frag, .comp or .geom)")),
    };
    let source = std::fs::read_to_string(&file).map_err(|e| format!("glsl/{rel}: {e}"))?;
    // Declared before the options, which borrow them.
    let include_dir = glsl.join("include");
    let root = glsl.parent().map(std::path::Path::to_path_buf).unwrap_or_default();
    let read = std::cell::RefCell::new(Vec::new());
    let mut options = shaderc::CompileOptions::new().map_err(|e| format!("shaderc: {e}"))?;
    options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_2 as u32);
    options.set_optimization_level(shaderc::OptimizationLevel::Performance);
    options.set_generate_debug_info();
    options.set_warnings_as_errors();
    options.set_include_callback(|name, _ty, from, _depth| {
        if name == "prism_shared.glsl" {
            return Ok(shaderc::ResolvedInclude { resolved_name: "prism_shared.glsl".into(), content: header.into() });
        }
        let from_dir = root.join(from).parent().map(std::path::Path::to_path_buf).unwrap_or_default();
        for dir in [include_dir.clone(), from_dir] {
            let p = dir.join(name);
            if let Ok(content) = std::fs::read_to_string(&p) {
                // Relative to the tree's root, so that errors inside includes read
                // glsl/include/x.glsl:LINE.
                let resolved_name = p.strip_prefix(&root).unwrap_or(&p).to_string_lossy().into_owned();
                read.borrow_mut().push(p);
                return Ok(shaderc::ResolvedInclude { resolved_name, content });
            }
        }
        Err(format!("cannot find include \"{name}\" (looked in glsl/include and beside {from})"))
    });
    let result = compiler.compile_into_spirv(&source, kind, &format!("glsl/{rel}"), "main", Some(&options));
    drop(options);
    includes.extend(read.into_inner());
    result.map(|a| a.as_binary_u8().to_vec()).map_err(|e| e.to_string())
}
