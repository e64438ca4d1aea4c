//! The library's modules form layers that import only downward (the order is
//! stated in ARCHITECTURE.md): a module may use modules of lower layers, never
//! one of its own layer or above. Within a top-level module, submodules must
//! not import each other in a circle. Unit-test modules (`#[cfg(test)]`, at
//! the end of a file) are not counted: tests may use anything.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Top-level modules of `src/lib.rs`, bottom layer first. Modules of one
/// layer must not import each other.
const LAYERS: &[&[&str]] = &[
    &["math", "memory"],
    &["limits"],
    &["geometry", "film", "texture"],
    &["io"],
    &["scene"],
    &["accel", "bsdf"],
    &["integrator"],
    &["job"],
    &["analysis", "view"],
];

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

/// Every `.rs` file under `dir`, recursively.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The module path of a file under `src/` (`src/a/b.rs` and `src/a/b/mod.rs`
/// are `["a", "b"]`).
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap();
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    let last = parts.pop().unwrap();
    let stem = last.trim_end_matches(".rs");
    if stem != "mod" && stem != "lib" {
        parts.push(stem.to_string());
    }
    parts
}

/// The file's code without its unit tests and without plain `//` comments
/// (doc comments stay: an intra-doc link is a dependency too).
fn code_of(text: &str) -> String {
    let body = match text.find("#[cfg(test)]") {
        Some(i) => &text[..i],
        None => text,
    };
    body.lines()
        .filter(|l| {
            let t = l.trim_start();
            !t.starts_with("//") || t.starts_with("///") || t.starts_with("//!")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn ident_at(s: &str) -> &str {
    let end = s
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(s.len());
    &s[..end]
}

/// Absolute module paths (as far as two segments) that `code`, in module
/// `here`, refers to through `crate::…`, `crate::{…}` and `super::…`.
fn references(code: &str, here: &[String]) -> BTreeSet<Vec<String>> {
    let mut out = BTreeSet::new();
    let bytes = code.as_bytes();
    let mut i = 0;
    while i < code.len() {
        let rest = &code[i..];
        let boundary = i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_');
        if boundary && rest.starts_with("crate::{") {
            // Grouped import: the top-level names at brace depth 1.
            let mut depth = 0;
            let mut item_start = true;
            for (j, c) in rest["crate::".len()..].char_indices() {
                match c {
                    '{' => {
                        depth += 1;
                        item_start = depth == 1;
                        continue;
                    }
                    '}' => {
                        depth -= 1;
                        if depth == 0 {
                            break;
                        }
                    }
                    ',' if depth == 1 => item_start = true,
                    c if c.is_whitespace() => {}
                    _ if item_start && depth == 1 => {
                        let name = ident_at(&rest["crate::".len() + j..]);
                        let tail = &rest["crate::".len() + j + name.len()..];
                        let mut path = vec![name.to_string()];
                        if let Some(t) = tail.strip_prefix("::") {
                            let second = ident_at(t);
                            if !second.is_empty() {
                                path.push(second.to_string());
                            }
                        }
                        out.insert(path);
                        item_start = false;
                    }
                    _ => {}
                }
            }
            i += "crate::{".len();
            continue;
        }
        if boundary && rest.starts_with("crate::") {
            let t = &rest["crate::".len()..];
            let first = ident_at(t);
            let mut path = vec![first.to_string()];
            if let Some(t2) = t[first.len()..].strip_prefix("::") {
                let second = ident_at(t2);
                if !second.is_empty() {
                    path.push(second.to_string());
                }
            }
            if !first.is_empty() {
                out.insert(path);
            }
            i += "crate::".len();
            continue;
        }
        if boundary && rest.starts_with("super::") {
            let mut base: Vec<String> = here.to_vec();
            let mut t = rest;
            while let Some(after) = t.strip_prefix("super::") {
                base.pop();
                t = after;
            }
            let name = ident_at(t);
            if !name.is_empty() {
                base.push(name.to_string());
                out.insert(base);
            }
            i += "super::".len();
            continue;
        }
        i += rest.chars().next().map_or(1, char::len_utf8);
    }
    out
}

struct Graph {
    /// (file, top module, absolute references)
    files: Vec<(PathBuf, Vec<String>, BTreeSet<Vec<String>>)>,
}

fn graph() -> Graph {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let files = files
        .into_iter()
        .filter(|f| !f.starts_with(src.join("bin")))
        .map(|f| {
            let here = module_path(&src, &f);
            let text = std::fs::read_to_string(&f).unwrap();
            let refs = references(&code_of(&text), &here);
            (f, here, refs)
        })
        .collect();
    Graph { files }
}

#[test]
fn every_top_level_module_has_a_layer() {
    let lib = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs")).unwrap();
    for line in lib.lines() {
        if let Some(name) = line.trim().strip_prefix("pub mod ").and_then(|l| l.strip_suffix(';')) {
            assert!(
                layer_of(name).is_some(),
                "src/lib.rs: module `{name}` is in no layer of tests/layers.rs"
            );
        }
    }
}

#[test]
fn modules_import_only_from_lower_layers() {
    let g = graph();
    let mut violations = Vec::new();
    for (file, here, refs) in &g.files {
        let Some(top) = here.first() else { continue };
        let Some(own) = layer_of(top) else { continue };
        for r in refs {
            let target = &r[0];
            if target == top {
                continue;
            }
            if let Some(layer) = layer_of(target) {
                if layer >= own {
                    violations.push(format!(
                        "{}: `{top}` (layer {own}) uses `{}` (layer {layer})",
                        file.display(),
                        r.join("::")
                    ));
                }
            }
        }
    }
    assert!(
        violations.is_empty(),
        "imports against the layer order:\n{}",
        violations.join("\n")
    );
}

#[test]
fn submodules_form_no_cycles() {
    let g = graph();
    // For each top-level module: edges between its direct children.
    let mut edges: BTreeMap<String, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    for (_, here, refs) in &g.files {
        if here.len() < 2 {
            continue;
        }
        let (top, child) = (&here[0], &here[1]);
        for r in refs {
            if r.len() >= 2 && &r[0] == top && &r[1] != child {
                edges
                    .entry(top.clone())
                    .or_default()
                    .entry(child.clone())
                    .or_default()
                    .insert(r[1].clone());
            }
        }
    }
    for (top, e) in &edges {
        // Depth-first search for a back edge.
        fn visit(
            n: &str,
            e: &BTreeMap<String, BTreeSet<String>>,
            state: &mut BTreeMap<String, u8>,
            stack: &mut Vec<String>,
        ) -> Option<Vec<String>> {
            state.insert(n.to_string(), 1);
            stack.push(n.to_string());
            for m in e.get(n).into_iter().flatten() {
                match state.get(m.as_str()).copied().unwrap_or(0) {
                    1 => {
                        let at = stack.iter().position(|s| s == m).unwrap();
                        let mut cycle = stack[at..].to_vec();
                        cycle.push(m.clone());
                        return Some(cycle);
                    }
                    0 => {
                        if let Some(c) = visit(m, e, state, stack) {
                            return Some(c);
                        }
                    }
                    _ => {}
                }
            }
            stack.pop();
            state.insert(n.to_string(), 2);
            None
        }
        let mut state = BTreeMap::new();
        for n in e.keys() {
            if state.get(n.as_str()).copied().unwrap_or(0) == 0 {
                let cycle = visit(n, e, &mut state, &mut Vec::new());
                assert!(
                    cycle.is_none(),
                    "`{top}`: submodules import each other in a circle: {}",
                    cycle.unwrap().join(" → ")
                );
            }
        }
    }
}

#[test]
fn the_checker_sees_grouped_and_relative_imports() {
    let here = vec!["integrator".to_string(), "photon".to_string(), "emit".to_string()];
    let refs = references(
        "use crate::{math::Vec3A, scene::{Scene, Light}};\nuse super::super::whitted::reflect;\nlet x = crate::job::run();",
        &here,
    );
    for want in [
        vec!["math", "Vec3A"],
        vec!["scene"],
        vec!["integrator", "whitted"],
        vec!["job", "run"],
    ] {
        let want: Vec<String> = want.into_iter().map(String::from).collect();
        assert!(refs.contains(&want), "{want:?} not in {refs:?}");
    }
    // And the layer test would flag an upward import.
    let upward = references("use crate::analysis::memory;", &["scene".to_string()]);
    assert!(upward.iter().any(|r| layer_of(&r[0]) > layer_of("scene")));
}
