fn main() {
    let c = shaderc::Compiler::new().unwrap();
    let r = c.compile_into_spirv("#version 450\nvoid main(){}", shaderc::ShaderKind::Compute, "t.comp", "main", None).unwrap();
    println!("cargo:warning=spirv words {}", r.as_binary().len());
}
