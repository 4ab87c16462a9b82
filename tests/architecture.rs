//! The shape of the source tree: no file imports a file that imports it
//! back (a `mod.rs` only declares and re-exports, so the files below it
//! import what they use from the files that define it).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A module path from the crate root (`["cull", "gpu_walk", "pool"]`).
type Module = Vec<String>;

/// Every `.rs` file under `dir`, by module path.
fn modules(root: &Path, dir: &Path, out: &mut BTreeMap<Module, PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            modules(root, &path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let relative = path.strip_prefix(root).unwrap().with_extension("");
            let mut module: Module = relative.iter().map(|p| p.to_string_lossy().into_owned()).collect();
            if matches!(module.last().map(String::as_str), Some("mod" | "lib" | "main")) {
                module.pop();
            }
            out.insert(module, path);
        }
    }
}

/// The paths a `use` tree names, expanded (`a::{b, c::{d}}` → `a::b`,
/// `a::c::d`).
fn expand(prefix: &str, tree: &str, out: &mut Vec<String>) {
    let tree = tree.trim();
    match tree.find('{') {
        None => out.push(format!("{prefix}{}", tree.split(" as ").next().unwrap_or("").trim())),
        Some(open) => {
            let head = format!("{prefix}{}", &tree[..open]);
            let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
            let (mut depth, mut start) = (0, 0);
            for (i, c) in inner.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        expand(&head, &inner[start..i], out);
                        start = i + 1;
                    }
                    _ => {}
                }
            }
            expand(&head, &inner[start..], out);
        }
    }
}

/// The file a path used from `module` lives in: the longest prefix of it
/// that names a file.
fn resolve(module: &Module, path: &str, files: &BTreeMap<Module, PathBuf>) -> Option<Module> {
    let mut segments: Vec<&str> = path.split("::").map(str::trim).filter(|s| !s.is_empty()).collect();
    let mut base: Module = match segments.first().copied() {
        Some("crate") => {
            segments.remove(0);
            Vec::new()
        }
        Some("super") => {
            let mut base = module.clone();
            while segments.first() == Some(&"super") {
                segments.remove(0);
                base.pop();
            }
            base
        }
        Some("self") => {
            segments.remove(0);
            module.clone()
        }
        Some(first) if files.contains_key(&[module.clone(), vec![first.to_string()]].concat()) => module.clone(),
        _ => return None,
    };
    let mut found = None;
    for segment in segments {
        base.push(segment.to_string());
        if files.contains_key(&base) {
            found = Some(base.clone());
        }
    }
    found
}

/// The files `text` (the source of `module`, its tests left out) imports:
/// by `use`, by a `crate::` path, or by a path through a child module it
/// declares.
fn imports(module: &Module, text: &str, files: &BTreeMap<Module, PathBuf>) -> BTreeSet<Module> {
    let text = text.split("#[cfg(test)]\nmod tests").next().unwrap_or(text);
    let mut found = BTreeSet::new();
    let mut paths = Vec::new();
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        let line = line.trim_start();
        let line = ["pub(crate) ", "pub(super) ", "pub "]
            .iter()
            .find_map(|v| line.strip_prefix(v))
            .unwrap_or(line);
        if let Some(tree) = line.strip_prefix("use ") {
            let mut statement = tree.to_string();
            while !statement.contains(';') {
                match lines.next() {
                    Some(more) => statement.push_str(more),
                    None => break,
                }
            }
            expand("", statement.split(';').next().unwrap_or(""), &mut paths);
        }
    }
    let without_visibility = text.replace("pub(in crate::", "pub(in ");
    for (i, _) in without_visibility.match_indices("crate::") {
        let rest: String = without_visibility[i..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
            .collect();
        paths.push(rest);
    }
    for line in text.lines() {
        let declared = line
            .trim_start()
            .trim_start_matches("pub(crate) ")
            .trim_start_matches("pub ");
        if let Some(name) = declared.strip_prefix("mod ").and_then(|n| n.strip_suffix(';')) {
            let child = [module.clone(), vec![name.to_string()]].concat();
            let used = text
                .match_indices(&format!("{name}::"))
                .any(|(i, _)| !text[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == ':'));
            if files.contains_key(&child) && used {
                found.insert(child);
            }
        }
    }
    for path in paths {
        if let Some(file) = resolve(module, &path, files).filter(|f| f != module) {
            found.insert(file);
        }
    }
    found
}

#[test]
fn no_file_imports_a_file_that_imports_it_back() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = BTreeMap::new();
    modules(&root, &root, &mut files);
    let graph: BTreeMap<&Module, BTreeSet<Module>> = files
        .iter()
        .map(|(module, path)| (module, imports(module, &std::fs::read_to_string(path).unwrap(), &files)))
        .collect();
    let both_ways: Vec<String> = graph
        .iter()
        .flat_map(|(&a, imported)| imported.iter().map(move |b| (a, b)))
        .filter(|&(a, b)| a < b && graph.get(b).is_some_and(|back| back.contains(a)))
        .map(|(a, b)| {
            let name = |m: &Module| files[m].strip_prefix(&root).unwrap_or(&files[m]).display().to_string();
            format!("src/{} <-> src/{}", name(a), name(b))
        })
        .collect();
    assert!(
        both_ways.is_empty(),
        "files importing each other:\n{}",
        both_ways.join("\n")
    );
    // The check sees imports at all: cull/registry.rs imports every mode.
    let registry = graph[&vec!["cull".to_string(), "registry".to_string()]].clone();
    assert!(
        registry.contains(&vec!["cull".to_string(), "vfc".to_string()]),
        "{registry:?}"
    );
    assert!(
        registry.contains(&vec!["cull".to_string(), "gpu_walk".to_string()]),
        "{registry:?}"
    );
}
