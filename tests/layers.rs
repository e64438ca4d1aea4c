//! The library's modules form layers that import only downward (the order is
//! stated in ARCHITECTURE.md): a module may use modules of lower layers, never
//! one of its own layer or above. Within a top-level module, submodules must
//! not import each other in a circle. Every file is read whole; only its
//! test modules (`#[cfg(test)] mod NAME { … }`, found by brace matching
//! outside comments and literals) are not counted: tests may use anything.
//! Rendering has two doors (ARCHITECTURE.md): `job`, and the integrator's
//! `render*` functions called directly by the modules listed in
//! [`RENDER_CALLERS`].

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

/// The modules that call the integrator's `render*` functions directly
/// instead of through `job` (ARCHITECTURE.md, "Doors to rendering"): the
/// measurements time the integrator alone, the viewer's thread cancels and
/// restarts progressive passes.
const RENDER_CALLERS: &[&str] = &[
    "job",
    "analysis::bench",
    "analysis::converge",
    "analysis::stress",
    "view::worker",
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

/// `text` with comments, string and character literals blanked out (each
/// byte replaced by a space, newlines kept, so offsets stay the same). Doc
/// comments are kept when `keep_docs` (an intra-doc link is a dependency
/// too). Lifetimes (`'a`) are told from character literals (`'a'`, `'\''`)
/// by the closing quote.
fn mask(text: &str, keep_docs: bool) -> String {
    let b = text.as_bytes();
    let mut out = b.to_vec();
    let blank = |out: &mut Vec<u8>, from: usize, to: usize| {
        for c in &mut out[from..to] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
    };
    let mut i = 0;
    while i < b.len() {
        let rest = &b[i..];
        if rest.starts_with(b"//") {
            let end = text[i..].find('\n').map_or(b.len(), |n| i + n);
            let doc = (rest.starts_with(b"///") && !rest.starts_with(b"////")) || rest.starts_with(b"//!");
            if !(doc && keep_docs) {
                blank(&mut out, i, end);
            }
            i = end;
        } else if rest.starts_with(b"/*") {
            // Block comments nest.
            let (mut depth, mut j) = (0usize, i);
            while j < b.len() {
                if b[j..].starts_with(b"/*") {
                    depth += 1;
                    j += 2;
                } else if b[j..].starts_with(b"*/") {
                    depth -= 1;
                    j += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    j += 1;
                }
            }
            blank(&mut out, i, j);
            i = j;
        } else if let Some(hashes) = raw_string_start(rest) {
            // r"…", r#"…"#, br#"…"#: ends at a quote followed by as many #.
            let open = rest.iter().position(|&c| c == b'"').unwrap() + 1;
            let close: Vec<u8> = std::iter::once(b'"').chain(std::iter::repeat_n(b'#', hashes)).collect();
            let end = b[i + open..]
                .windows(close.len())
                .position(|w| w == close.as_slice())
                .map_or(b.len(), |n| i + open + n + close.len());
            blank(&mut out, i, end);
            i = end;
        } else if rest[0] == b'"' || rest.starts_with(b"b\"") {
            let mut j = i + if rest[0] == b'"' { 1 } else { 2 };
            while j < b.len() && b[j] != b'"' {
                j += if b[j] == b'\\' { 2 } else { 1 };
            }
            let end = (j + 1).min(b.len());
            blank(&mut out, i, end);
            i = end;
        } else if rest[0] == b'\'' {
            // A character literal ends at the next quote within a few
            // bytes (an escape or one UTF-8 character); a lifetime has none.
            let end = if rest.get(1) == Some(&b'\\') {
                // The escaped byte may itself be a quote: `'\''`.
                rest.get(3..)
                    .and_then(|r| r.iter().position(|&c| c == b'\''))
                    .map(|n| i + 3 + n + 1)
            } else {
                let len = text[i + 1..].chars().next().map_or(1, char::len_utf8);
                (rest.get(1 + len) == Some(&b'\'')).then_some(i + 2 + len)
            };
            match end {
                Some(end) => {
                    blank(&mut out, i, end);
                    i = end;
                }
                None => i += 1,
            }
        } else {
            i += 1;
        }
    }
    String::from_utf8(out).expect("only ASCII bytes were replaced, by spaces")
}

/// The number of `#` of a raw string literal starting at `s` (`r"`, `r#"`,
/// `br##"` …), or `None`.
fn raw_string_start(s: &[u8]) -> Option<usize> {
    let s = s.strip_prefix(b"b").unwrap_or(s);
    let s = s.strip_prefix(b"r")?;
    let hashes = s.iter().take_while(|&&c| c == b'#').count();
    (s.get(hashes) == Some(&b'"')).then_some(hashes)
}

/// Byte ranges of the test modules in masked code: `#[cfg(test)]`, other
/// attributes, an optional visibility, `mod NAME {`, through the matching
/// `}`. Other `#[cfg(test)]` items (a test-only helper function) stay code.
fn test_modules(masked: &str) -> Vec<(usize, usize)> {
    let b = masked.as_bytes();
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(n) = masked[from..].find("#[cfg(test)]") {
        let start = from + n;
        let mut j = start + "#[cfg(test)]".len();
        let skip_ws = |j: &mut usize| {
            while *j < b.len() && b[*j].is_ascii_whitespace() {
                *j += 1;
            }
        };
        loop {
            skip_ws(&mut j);
            if b[j..].starts_with(b"#[") {
                j += masked[j..].find(']').map_or(b.len() - j, |e| e + 1);
            } else {
                break;
            }
        }
        for vis in ["pub(crate)", "pub(super)", "pub"] {
            if masked[j..].starts_with(vis) {
                j += vis.len();
                skip_ws(&mut j);
                break;
            }
        }
        from = start + 1;
        let Some(after_mod) = masked[j..].strip_prefix("mod") else {
            continue;
        };
        let name = ident_at(after_mod.trim_start());
        if name.is_empty() || !after_mod.starts_with(char::is_whitespace) {
            continue;
        }
        j += "mod".len() + (after_mod.len() - after_mod.trim_start().len()) + name.len();
        skip_ws(&mut j);
        if b.get(j) != Some(&b'{') {
            continue; // `mod tests;`: its file is not under this one.
        }
        let mut depth = 0usize;
        let mut end = b.len();
        for (k, &c) in b.iter().enumerate().skip(j) {
            match c {
                b'{' => depth += 1,
                b'}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = k + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        out.push((start, end));
        from = end;
    }
    out
}

/// The file's code without its test modules, comments (doc comments kept
/// when `keep_docs`) and literals.
fn code_of(text: &str, keep_docs: bool) -> String {
    let ranges = test_modules(&mask(text, false));
    let mut code = mask(text, keep_docs).into_bytes();
    for (from, to) in ranges {
        for c in &mut code[from..to] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
    }
    String::from_utf8(code).expect("only whole ASCII-delimited ranges were blanked")
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

/// Whether masked `code` names the integrator's render entry points: a
/// path `integrator::render…` (the `render` module or a `render_*`
/// function), or `render…` among the names of a grouped
/// `integrator::{…}` import.
fn names_render_entry(code: &str) -> bool {
    let bytes = code.as_bytes();
    let is_render = |name: &str| name == "render" || name.starts_with("render_");
    let mut from = 0;
    while let Some(n) = code[from..].find("integrator::") {
        let at = from + n;
        from = at + 1;
        if at > 0 && (bytes[at - 1].is_ascii_alphanumeric() || bytes[at - 1] == b'_') {
            continue;
        }
        let tail = &code[at + "integrator::".len()..];
        if is_render(ident_at(tail)) {
            return true;
        }
        if let Some(group) = tail.strip_prefix('{') {
            let group = &group[..group.find('}').unwrap_or(group.len())];
            if group.split(',').any(|item| is_render(ident_at(item.trim()))) {
                return true;
            }
        }
    }
    false
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
            let refs = references(&code_of(&text, true), &here);
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
fn only_the_listed_modules_call_the_integrators_render_functions() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut outside = Vec::new();
    let mut seen = BTreeSet::new();
    for f in files.iter().filter(|f| !f.starts_with(src.join("bin"))) {
        let here = module_path(&src, f).join("::");
        if here == "integrator" || here.starts_with("integrator::") {
            continue;
        }
        let text = std::fs::read_to_string(f).unwrap();
        if !names_render_entry(&code_of(&text, false)) {
            continue;
        }
        match RENDER_CALLERS
            .iter()
            .find(|c| here == **c || here.starts_with(&format!("{c}::")))
        {
            Some(c) => {
                seen.insert(*c);
            }
            None => outside.push(format!("{} (`{here}`)", f.display())),
        }
    }
    assert!(
        outside.is_empty(),
        "these call `integrator::render*` but are not doors to rendering (render through `job`, or add \
         the module to RENDER_CALLERS and ARCHITECTURE.md with the reason):\n{}",
        outside.join("\n")
    );
    let stale: Vec<_> = RENDER_CALLERS.iter().filter(|c| !seen.contains(*c)).collect();
    assert!(
        stale.is_empty(),
        "RENDER_CALLERS lists modules that no longer render: {stale:?}"
    );
}

#[test]
fn test_modules_are_cut_by_braces_and_the_rest_of_the_file_is_read() {
    let text = r####"use crate::math::Vec3;
#[cfg(test)]
fn helper() { let _ = crate::job::x(); }
#[cfg(test)]
#[allow(dead_code)]
mod tests {
    fn f() { let s = "}"; let c = '}'; let r = r#"}}"#; /* } */ }
    // }
    use crate::view::anything;
}
pub fn after<'a>(x: &'a str) -> &'a str { let _ = crate::analysis::late(); let q = '\''; x }
/// [`crate::scene::Scene`]
fn g() { let _ = "crate::integrator::render(…)"; }
"####;
    let code = code_of(text, true);
    let refs = references(&code, &["film".to_string()]);
    let tops: BTreeSet<&str> = refs.iter().map(|r| r[0].as_str()).collect();
    // After the test module, the code is read again, and a test-only
    // function (not a module) counts as code.
    assert!(tops.contains("analysis"), "{refs:?}");
    assert!(tops.contains("job"), "{refs:?}");
    // Doc links count; the test module, comments and strings do not.
    assert!(tops.contains("scene"), "{refs:?}");
    assert!(!tops.contains("view"), "{refs:?}");
    assert!(!tops.contains("integrator"), "{refs:?}");
    assert_eq!(code.len(), text.len());
    assert!(!names_render_entry(&code_of(text, false)));
    assert!(names_render_entry("use crate::integrator::{self, render, RenderPlan};"));
    assert!(names_render_entry("let o = integrator::render(s, a, p, setup);"));
    assert!(!names_render_entry(
        "use crate::integrator::{RenderPlan, RenderOutput};"
    ));
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
