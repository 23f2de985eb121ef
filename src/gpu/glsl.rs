// GLSL -> SPIR-V with shaderc (glslang), shared by build.rs (which `include!`s this file and
// embeds every shader in the binary) and the window's shader hot reload (src/gpu/mod.rs,
// `compile_shader`), so that both compile with the same options, includes and header.
// Paths are spelt out in full: build.rs has imports of its own.

/// A specialisation constant a shader declares: `layout(constant_id = id) const ty name`.
/// Pipelines set constants by name (src/gpu/pipeline.rs); the SPIR-V alone cannot say which
/// names a shader has, since glslang drops the constants a shader never reads.
#[derive(Clone, Debug, PartialEq)]
pub struct SpecConstant {
    pub name: String,
    pub id: u32,
    /// The GLSL type: `uint`, `int`, `float` or `bool`.
    pub ty: String,
}

/// Every `layout(constant_id = N) const TYPE NAME` outside a `//` comment of `source`.
pub fn spec_constants(source: &str) -> Vec<SpecConstant> {
    let mut out = Vec::new();
    for line in source.lines() {
        let line = line.split("//").next().unwrap_or_default();
        let Some((_, rest)) = line.split_once("constant_id") else { continue };
        let Some((id, rest)) = rest.trim_start().strip_prefix('=').and_then(|r| r.split_once(')')) else { continue };
        let Ok(id) = id.trim().parse() else { continue };
        let mut words = rest.split_whitespace();
        let (Some("const"), Some(ty), Some(name)) = (words.next(), words.next(), words.next()) else { continue };
        let name: String = name.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
        out.push(SpecConstant { name, id, ty: ty.to_string() });
    }
    out
}

/// A compiled shader: its SPIR-V bytes and the specialisation constants its source (with
/// its includes) declares.
pub struct Compiled {
    pub spirv: Vec<u8>,
    pub specs: Vec<SpecConstant>,
}

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
) -> Result<Compiled, String> {
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
                read.borrow_mut().push((p, content.clone()));
                return Ok(shaderc::ResolvedInclude { resolved_name, content });
            }
        }
        Err(format!("cannot find include \"{name}\" (looked in glsl/include and beside {from})"))
    });
    let result = compiler.compile_into_spirv(&source, kind, &format!("glsl/{rel}"), "main", Some(&options));
    drop(options);
    let mut specs = spec_constants(&source);
    for (p, content) in read.into_inner() {
        specs.extend(spec_constants(&content));
        includes.push(p);
    }
    // A guarded include read twice declares its constants once.
    specs.sort_by_key(|s| s.id);
    specs.dedup();
    let spirv = result.map_err(|e| e.to_string())?.as_binary_u8().to_vec();
    Ok(Compiled { spirv, specs })
}
