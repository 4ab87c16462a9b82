//! Tests only: WGSL parsed by naga (wgpu's shader compiler), so that every
//! struct a shader shares with Rust is held against Rust's layout.

/// WGSL `source` parsed, or the test fails with the parser's message.
pub(crate) fn parse(source: &str) -> wgpu::naga::Module {
    wgpu::naga::front::wgsl::parse_str(source).unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)))
}

/// The members (name, byte offset) and size of struct `name` in `module`,
/// for tests that hold a shader's structs against what Rust writes.
pub(crate) fn struct_layout(module: &wgpu::naga::Module, name: &str) -> (Vec<(String, u32)>, u32) {
    let (_, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name}"));
    match &ty.inner {
        wgpu::naga::TypeInner::Struct { members, span } => (
            members
                .iter()
                .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                .collect(),
            *span,
        ),
        other => panic!("{name} is {other:?}"),
    }
}
