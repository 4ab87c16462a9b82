//! The shape of the source tree: no circle of imports of any length, no
//! file importing, through others, a file that imports it (a `mod.rs` only
//! declares and re-exports, so the files below it import what they use
//! from the files that define it).

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

/// What modules re-export: (module, name) → the path it re-exports.
type Reexports = BTreeMap<(Module, String), String>;

/// The file a path used from `module` lives in: the longest prefix of it
/// that names a file, or where that file's `pub use` re-exports the name
/// after it from (a `mod.rs` re-exports what its files define: a file that
/// uses it that way depends on the file that defines it, not on `mod.rs`).
fn resolve(module: &Module, path: &str, files: &BTreeMap<Module, PathBuf>, reexports: &Reexports) -> Option<Module> {
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
    for (k, segment) in segments.iter().enumerate() {
        base.push(segment.to_string());
        if files.contains_key(&base) {
            found = Some((base.clone(), segments.get(k + 1)));
        }
    }
    let (file, next) = found?;
    match next.and_then(|name| reexports.get(&(file.clone(), name.to_string()))) {
        Some(source) if source.as_str() != path => resolve(&file, source, files, reexports).or(Some(file)),
        _ => Some(file),
    }
}

/// The paths of `text`'s `use` statements, with `pub` ones (re-exports)
/// apart.
fn use_paths(text: &str) -> (Vec<String>, Vec<String>) {
    let (mut private, mut public) = (Vec::new(), Vec::new());
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        let line = line.trim_start();
        let (line, exported) = match ["pub(crate) ", "pub(super) ", "pub "]
            .iter()
            .find_map(|v| line.strip_prefix(v))
        {
            Some(rest) => (rest, true),
            None => (line, false),
        };
        if let Some(tree) = line.strip_prefix("use ") {
            let mut statement = tree.to_string();
            while !statement.contains(';') {
                match lines.next() {
                    Some(more) => statement.push_str(more),
                    None => break,
                }
            }
            let out = if exported { &mut public } else { &mut private };
            expand("", statement.split(';').next().unwrap_or(""), out);
        }
    }
    (private, public)
}

/// Every module's re-exports, by the name they give.
fn reexports(files: &BTreeMap<Module, PathBuf>) -> Reexports {
    let mut out = Reexports::new();
    for (module, path) in files {
        let text = std::fs::read_to_string(path).unwrap();
        for reexported in use_paths(&text).1 {
            let name = reexported.rsplit("::").next().unwrap_or("").trim();
            if !name.is_empty() && name != "*" {
                out.insert((module.clone(), name.to_string()), reexported.clone());
            }
        }
    }
    out
}

/// The files `text` (the source of `module`, its tests left out) imports:
/// by `use`, by a `crate::` path, or by a path through a child module it
/// declares.
fn imports(module: &Module, text: &str, files: &BTreeMap<Module, PathBuf>, reexports: &Reexports) -> BTreeSet<Module> {
    let text = text.split("#[cfg(test)]\nmod tests").next().unwrap_or(text);
    let mut found = BTreeSet::new();
    let (private, public) = use_paths(text);
    let mut paths = [private, public].concat();
    // Paths written out in code (not in comments, whose links import
    // nothing, nor in `use` trees, read above).
    let code: String = text
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
        .replace("pub(in crate::", "pub(in ");
    for (i, _) in code.match_indices("crate::") {
        let rest: String = code[i..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
            .collect();
        if !rest.ends_with("::") {
            paths.push(rest);
        }
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
        if let Some(file) = resolve(module, &path, files, reexports).filter(|f| f != module) {
            found.insert(file);
        }
    }
    found
}

/// The circles of `graph`: its strongly connected components of more than
/// one node (Tarjan's algorithm), each in the order of its nodes.
fn circles<N: Ord + Clone>(graph: &BTreeMap<N, BTreeSet<N>>) -> Vec<Vec<N>> {
    struct Walk<'g, N> {
        graph: &'g BTreeMap<N, BTreeSet<N>>,
        index: BTreeMap<&'g N, usize>,
        low: BTreeMap<&'g N, usize>,
        stack: Vec<&'g N>,
        circles: Vec<Vec<N>>,
    }
    impl<'g, N: Ord + Clone> Walk<'g, N> {
        fn visit(&mut self, node: &'g N) {
            let at = self.index.len();
            self.index.insert(node, at);
            self.low.insert(node, at);
            self.stack.push(node);
            for next in self.graph.get(node).into_iter().flatten() {
                let Some((next, _)) = self.graph.get_key_value(next) else {
                    continue;
                };
                if !self.index.contains_key(next) {
                    self.visit(next);
                    let low = self.low[node].min(self.low[next]);
                    self.low.insert(node, low);
                } else if self.stack.contains(&next) {
                    let low = self.low[node].min(self.index[next]);
                    self.low.insert(node, low);
                }
            }
            if self.low[node] == self.index[node] {
                let from = self.stack.iter().rposition(|&n| n == node).unwrap();
                let component: Vec<N> = self.stack.drain(from..).cloned().collect();
                if component.len() > 1 {
                    self.circles.push(component);
                }
            }
        }
    }
    let mut walk = Walk {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        circles: Vec::new(),
    };
    for node in graph.keys() {
        if !walk.index.contains_key(node) {
            walk.visit(node);
        }
    }
    walk.circles
}

#[test]
fn circles_of_any_length_are_found() {
    let graph = |edges: &[(u8, u8)]| {
        let mut g: BTreeMap<u8, BTreeSet<u8>> = BTreeMap::new();
        for &(a, b) in edges {
            g.entry(a).or_default().insert(b);
            g.entry(b).or_default();
        }
        g
    };
    // conservative → targets → context → conservative, as it once was.
    assert_eq!(circles(&graph(&[(1, 2), (2, 3), (3, 1), (3, 4)])), [vec![1, 2, 3]]);
    assert_eq!(circles(&graph(&[(1, 2), (2, 1), (5, 6), (6, 7), (7, 5)])).len(), 2);
    assert!(
        circles(&graph(&[(1, 2), (2, 3), (1, 3)])).is_empty(),
        "a diamond is no circle"
    );
}

#[test]
fn no_file_imports_a_file_that_imports_it_back() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = BTreeMap::new();
    modules(&root, &root, &mut files);
    let reexports = reexports(&files);
    let graph: BTreeMap<Module, BTreeSet<Module>> = files
        .iter()
        .map(|(module, path)| {
            let imported = imports(module, &std::fs::read_to_string(path).unwrap(), &files, &reexports);
            (module.clone(), imported)
        })
        .collect();
    let name = |m: &Module| files[m].strip_prefix(&root).unwrap_or(&files[m]).display().to_string();
    let found: Vec<String> = circles(&graph)
        .iter()
        .map(|circle| {
            let edges: Vec<String> = circle
                .iter()
                .flat_map(|a| graph[a].iter().filter(|b| circle.contains(b)).map(move |b| (a, b)))
                .map(|(a, b)| format!("  src/{} -> src/{}", name(a), name(b)))
                .collect();
            format!("a circle of {} files:\n{}", circle.len(), edges.join("\n"))
        })
        .collect();
    assert!(
        found.is_empty(),
        "files importing themselves through others:\n{}",
        found.join("\n")
    );
    // The check sees imports at all: cull/vfc.rs imports its entry's types
    // and the traversal it runs.
    let vfc = graph[&vec!["cull".to_string(), "vfc".to_string()]].clone();
    for imported in ["mode", "traversal"] {
        assert!(
            vfc.contains(&vec!["cull".to_string(), imported.to_string()]),
            "cull/vfc.rs imports cull/{imported}.rs: {vfc:?}"
        );
    }
}
