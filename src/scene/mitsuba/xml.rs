//! A Mitsuba scene file as a tree of elements: the XML read with roxmltree
//! (no DTD, so no entity expansion), the `version` checked, `<default>`
//! parameters and `-D` definitions substituted for `$name` in every
//! attribute, `<include>` files spliced in place and `<path>` folders added
//! to the search path. Every element keeps its file and line:column.
//!
//! Hostile files are bounded before they cost much: include cycles are
//! refused at the include that closes them, and the includes read, the
//! nesting of elements and the bytes that `$` substitution may produce
//! (`<default>`s expanding each other, a billion laughs without a DTD) are
//! capped; the messages name the file, line and column.

use crate::scene::load::{read_scene_text, Place, SceneError};
use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Includes nested deeper than this are refused.
pub const MAX_INCLUDE_DEPTH: usize = 16;

/// Most `<include>`s read in all: without a cap, files that each include
/// the next twice read 2^16 files through 16 levels (an include bomb).
pub const MAX_INCLUDES: usize = 4096;

/// Elements nested deeper than this (includes counted) are refused: the
/// reader and every plugin reader recurse over the nesting, and a file of
/// 30 000 nested elements would overflow the stack. Real scenes nest a
/// handful of levels.
pub const MAX_NESTING: usize = 64;

/// Most folders on the search path: every file name is looked for in each.
pub const MAX_SEARCH_PATH: usize = 256;

/// Longest attribute value that `$` substitution may produce (bytes).
pub const MAX_SUBSTITUTED_VALUE: usize = 1 << 20;

/// Most bytes that `$` substitution may produce over the whole scene:
/// `<default>`s whose values name earlier ones several times each grow
/// exponentially (a billion laughs made of parameters), and many uses of
/// one long value multiply it.
pub const MAX_SUBSTITUTED_TOTAL: usize = 64 << 20;

/// Where an element is written.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Origin {
    /// The file (the scene or an included file).
    pub file: Arc<Path>,
    /// Line and column of the element's start.
    pub place: Place,
}

impl Origin {
    /// The folder of the file: where relative names in it resolve last.
    pub fn dir(&self) -> &Path {
        self.file.parent().unwrap_or(Path::new(""))
    }

    /// This place as the origin of a part of the scene.
    pub fn part(&self) -> crate::scene::Origin {
        crate::scene::Origin::Text {
            path: self.file.to_path_buf(),
            place: self.place,
        }
    }

    /// An error at this place.
    pub fn error(&self, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            path: self.file.to_path_buf(),
            place: self.place,
            message: message.into(),
        }
    }
}

/// One element after substitution and inclusion.
#[derive(Clone, Debug)]
pub struct Element {
    /// The tag (`shape`, `float`, `ref`, ...).
    pub tag: String,
    /// Attributes in file order, `$name` substituted.
    pub attrs: Vec<(String, String)>,
    /// Child elements (comments and whitespace dropped).
    pub children: Vec<Element>,
    /// Where it is written.
    pub origin: Origin,
}

impl Element {
    /// The value of attribute `name`.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs.iter().find(|(n, _)| n == name).map(|(_, v)| v.as_str())
    }

    /// The value of attribute `name`, which must be there.
    pub fn required(&self, name: &str) -> Result<&str, SceneError> {
        self.attr(name)
            .ok_or_else(|| self.origin.error(format!("<{}> needs a `{name}` attribute", self.tag)))
    }

    /// Refuses attributes other than `allowed`.
    pub fn only_attrs(&self, allowed: &[&str]) -> Result<(), SceneError> {
        match self.attrs.iter().find(|(n, _)| !allowed.contains(&n.as_str())) {
            None => Ok(()),
            Some((n, _)) => Err(self.origin.error(format!(
                "<{}> has an unexpected attribute `{n}` (allowed: {})",
                self.tag,
                allowed.join(", ")
            ))),
        }
    }

    /// The directory relative file names in this element resolve against.
    pub fn dir(&self) -> &Path {
        self.origin.dir()
    }
}

/// A scene file read whole.
#[derive(Debug)]
pub struct Document {
    /// The `<scene>` element, includes spliced in.
    pub root: Element,
    /// Where relative file names are looked for: the `<path>` folders
    /// (the latest first), then the main scene file's folder.
    pub search_path: Vec<PathBuf>,
    /// The scene's Mitsuba version (major, minor, patch).
    pub version: (u32, u32, u32),
}

/// Reads `path` with the `defines` (`-D name=value`, before any `<default>`).
pub fn read_document(path: &Path, defines: &[(String, String)]) -> Result<Document, SceneError> {
    let mut reader = Reader {
        params: defines.to_vec(),
        search_path: vec![path.parent().unwrap_or(Path::new("")).to_path_buf()],
        open: Vec::new(),
        includes: 0,
        substituted: 0,
    };
    let (root, version) = reader.read_file(path, 0, 0, None)?;
    Ok(Document {
        root,
        search_path: reader.search_path,
        version,
    })
}

/// Resolves a file named in the scene as Mitsuba's file resolver does:
/// absolute, or the first that exists relative to the `<path>` folders
/// (the latest first) and the main scene file's folder; then relative to
/// the folder of the (included) file that names it.
pub fn resolve(name: &str, dir: &Path, search_path: &[PathBuf]) -> PathBuf {
    if Path::new(name).is_absolute() {
        return PathBuf::from(name);
    }
    search_path
        .iter()
        .map(|d| d.join(name))
        .chain(std::iter::once(dir.join(name)))
        .find(|p| p.exists())
        .unwrap_or_else(|| search_path.first().map_or_else(|| dir.join(name), |d| d.join(name)))
}

struct Reader {
    params: Vec<(String, String)>,
    search_path: Vec<PathBuf>,
    /// The files being read, the scene first (canonical paths where they
    /// resolve): an include naming one of them closes a cycle.
    open: Vec<PathBuf>,
    /// `<include>`s read so far.
    includes: usize,
    /// Bytes produced by `$` substitution so far.
    substituted: usize,
}

impl Reader {
    /// Reads one file; `include` is the `<include>` element naming it,
    /// `depth` the includes and `nesting` the elements it is read inside.
    fn read_file(
        &mut self,
        path: &Path,
        depth: usize,
        nesting: usize,
        include: Option<&Origin>,
    ) -> Result<(Element, (u32, u32, u32)), SceneError> {
        let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        if let Some(at) = include {
            if let Some(first) = self.open.iter().position(|p| *p == canonical) {
                let name = |p: &Path| {
                    p.file_name()
                        .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into_owned())
                };
                let chain: Vec<String> = self.open[first..]
                    .iter()
                    .map(|p| name(p))
                    .chain([name(&canonical)])
                    .collect();
                return Err(at.error(format!(
                    "an include cycle: `{}` is already being read ({})",
                    path.display(),
                    chain.join(" → ")
                )));
            }
        }
        let text = read_scene_text(path).map_err(|e| match include {
            Some(at) => at.error(format!("cannot include: {e}")),
            None => e,
        })?;
        self.open.push(canonical);
        let read = self.read_text(path, &text, depth, nesting);
        self.open.pop();
        read
    }

    /// [`Reader::read_file`] once the text is read.
    fn read_text(
        &mut self,
        path: &Path,
        text: &str,
        depth: usize,
        nesting: usize,
    ) -> Result<(Element, (u32, u32, u32)), SceneError> {
        let file: Arc<Path> = Arc::from(path);
        // roxmltree recurses once per level of nesting: a deeper file must
        // be refused before it is parsed.
        if let Some(offset) = too_deep(text, MAX_NESTING + 1) {
            return Err(SceneError::Invalid {
                path: path.into(),
                place: Place::of_offset(text, offset),
                message: format!("elements nested more than {MAX_NESTING} deep"),
            });
        }
        let options = roxmltree::ParsingOptions {
            allow_dtd: false,
            ..Default::default()
        };
        let doc = roxmltree::Document::parse_with_options(text, options).map_err(|e| {
            let pos = e.pos();
            let mut place = Place {
                line: pos.row as usize,
                column: pos.col as usize,
            };
            let mut message = format!("not a valid XML file: {e}");
            if let roxmltree::Error::DtdDetected = e {
                // roxmltree places it at 1:1; the DOCTYPE is where it is.
                if let Some(offset) = text.find("<!DOCTYPE") {
                    place = Place::of_offset(text, offset);
                }
                message = "not a valid XML file: a DTD (`<!DOCTYPE`) is not allowed (its entities could expand without bound)".into();
            }
            SceneError::Invalid {
                path: path.into(),
                place,
                message,
            }
        })?;
        let root = doc.root_element();
        let src = Source {
            file,
            text,
            cursor: Cell::new((0, 1, 1)),
        };
        let origin = src.origin(root);
        if root.tag_name().name() != "scene" {
            return Err(origin.error(format!(
                "the root element is <{}>; a Mitsuba scene file starts with <scene version=\"3.0.0\">",
                root.tag_name().name()
            )));
        }
        let version_text = root
            .attribute("version")
            .ok_or_else(|| origin.error("<scene> needs a `version` attribute (e.g. version=\"3.0.0\")"))?;
        let version = parse_version(version_text)
            .ok_or_else(|| origin.error(format!("`version=\"{version_text}\"` is not major.minor.patch")))?;
        if !(2..=3).contains(&version.0) {
            return Err(origin.error(format!(
                "Mitsuba version {version_text}: caustic reads the formats of Mitsuba 2 and 3 (version 2.x or 3.x)"
            )));
        }
        let mut children = Vec::new();
        for child in root.children().filter(|n| n.is_element()) {
            self.element(&src, child, depth, nesting + 1, &mut children)?;
        }
        let attrs = root
            .attributes()
            .map(|a| (a.name().to_string(), a.value().to_string()))
            .collect();
        Ok((
            Element {
                tag: "scene".into(),
                attrs,
                children,
                origin,
            },
            version,
        ))
    }

    /// Converts `node` and appends what it stands for to `out`: itself, the
    /// contents of an included file, or nothing (`<default>`, `<path>`).
    /// `nesting` counts the elements it is inside, `<scene>` included.
    fn element(
        &mut self,
        src: &Source,
        node: roxmltree::Node,
        depth: usize,
        nesting: usize,
        out: &mut Vec<Element>,
    ) -> Result<(), SceneError> {
        let origin = src.origin(node);
        if nesting > MAX_NESTING {
            return Err(origin.error(format!(
                "elements nested more than {MAX_NESTING} deep (includes counted)"
            )));
        }
        if let Some(ns) = node.tag_name().namespace() {
            return Err(origin.error(format!("unexpected XML namespace `{ns}`")));
        }
        let mut attrs = Vec::new();
        for a in node.attributes() {
            attrs.push((a.name().to_string(), self.substitute(a.value(), &origin)?));
        }
        let element = Element {
            tag: node.tag_name().name().to_string(),
            attrs,
            children: Vec::new(),
            origin,
        };
        match element.tag.as_str() {
            "default" => {
                element.only_attrs(&["name", "value"])?;
                let name = element.required("name")?.to_string();
                let value = element.required("value")?.to_string();
                if !is_identifier(&name) {
                    return Err(element.origin.error(format!("`{name}` is not a parameter name")));
                }
                // The command line's and earlier defaults win.
                if !self.params.iter().any(|(n, _)| *n == name) {
                    self.params.push((name, value));
                }
                return Ok(());
            }
            "path" => {
                element.only_attrs(&["value"])?;
                let dir = resolve(element.required("value")?, element.dir(), &self.search_path);
                if !dir.is_dir() {
                    return Err(element
                        .origin
                        .error(format!("<path>: `{}` is not a folder", dir.display())));
                }
                // A folder already on the path moves to the front, where a
                // repeat would put it: lookups find the same files, and the
                // path cannot grow by repeating one folder.
                let dir = std::fs::canonicalize(&dir).unwrap_or(dir);
                self.search_path.retain(|d| *d != dir);
                if self.search_path.len() >= MAX_SEARCH_PATH {
                    return Err(element
                        .origin
                        .error(format!("more than {MAX_SEARCH_PATH} <path> folders")));
                }
                self.search_path.insert(0, dir);
                return Ok(());
            }
            "include" => {
                element.only_attrs(&["filename"])?;
                if depth + 1 > MAX_INCLUDE_DEPTH {
                    return Err(element.origin.error(format!(
                        "includes nested more than {MAX_INCLUDE_DEPTH} deep (does a file include itself?)"
                    )));
                }
                self.includes += 1;
                if self.includes > MAX_INCLUDES {
                    return Err(element.origin.error(format!(
                        "more than {MAX_INCLUDES} <include>s in all (files including others several times each multiply)"
                    )));
                }
                let name = element.required("filename")?;
                let path = resolve(name, element.dir(), &self.search_path);
                // The included file's elements take the place of the
                // <include>: they nest as deep as it does.
                let (included, _) = self.read_file(&path, depth + 1, nesting - 1, Some(&element.origin))?;
                out.extend(included.children);
                return Ok(());
            }
            _ => {}
        }
        let mut element = element;
        for child in node.children() {
            if child.is_element() {
                self.element(src, child, depth, nesting + 1, &mut element.children)?;
            } else if child.is_text() && !child.text().unwrap_or("").trim().is_empty() {
                return Err(src.origin(child).error(format!(
                    "unexpected text inside <{}>: Mitsuba scenes give values as attributes",
                    element.tag
                )));
            }
        }
        out.push(element);
        Ok(())
    }

    /// Replaces every `$name` by its parameter's value (the longest name
    /// that follows `$`), within [`MAX_SUBSTITUTED_VALUE`] and
    /// [`MAX_SUBSTITUTED_TOTAL`].
    fn substitute(&mut self, value: &str, origin: &Origin) -> Result<String, SceneError> {
        if !value.contains('$') {
            return Ok(value.to_string());
        }
        let mut out = String::with_capacity(value.len());
        let mut rest = value;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let len = after
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(after.len());
            let name = &after[..len];
            if name.is_empty() {
                return Err(origin.error(format!("`{value}`: `$` is not followed by a parameter name")));
            }
            let param = self.params.iter().find(|(n, _)| n == name).ok_or_else(|| {
                origin.error(format!(
                    "`${name}` is not defined: add <default name=\"{name}\" value=\"…\"/> or pass -D {name}=…"
                ))
            })?;
            // Checked before the value is copied: the copy is what grows.
            if out.len() + param.1.len() > MAX_SUBSTITUTED_VALUE {
                return Err(origin.error(format!(
                    "`${name}` makes the value longer than {} MiB (parameters that repeat each other grow exponentially)",
                    MAX_SUBSTITUTED_VALUE >> 20
                )));
            }
            self.substituted += param.1.len();
            if self.substituted > MAX_SUBSTITUTED_TOTAL {
                return Err(origin.error(format!(
                    "`$` parameters expand to more than {} MiB in all (parameters that repeat each other grow exponentially)",
                    MAX_SUBSTITUTED_TOTAL >> 20
                )));
            }
            out.push_str(&param.1);
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(out)
    }
}

/// A file being read: where its nodes are.
struct Source<'t> {
    file: Arc<Path>,
    text: &'t str,
    /// The last place asked for: (byte offset, line, column). Places are
    /// asked in document order, so each is counted on from the last, in
    /// linear time over the file (roxmltree's `text_pos_at` counts from the
    /// start at every call: 90 s for a 4 MB scene of 120 000 elements).
    cursor: Cell<(usize, usize, usize)>,
}

impl Source<'_> {
    fn origin(&self, node: roxmltree::Node) -> Origin {
        let pos = node.range().start.min(self.text.len());
        let (mut offset, mut line, mut column) = self.cursor.get();
        if pos < offset {
            (offset, line, column) = (0, 1, 1);
        }
        for c in self.text[offset..pos].chars() {
            if c == '\n' {
                line += 1;
                column = 1;
            } else {
                column += 1;
            }
        }
        self.cursor.set((pos, line, column));
        Origin {
            file: self.file.clone(),
            place: Place { line, column },
        }
    }
}

/// The byte offset of the first element nested deeper than `limit` in
/// XML `text`, if any. Comments, CDATA sections, processing instructions
/// and declarations open no element, and quoted attribute values may hold
/// `>`; text that is not well-formed is left to the parser's error.
fn too_deep(text: &str, limit: usize) -> Option<usize> {
    let bytes = text.as_bytes();
    let find = |from: usize, needle: &[u8]| -> usize {
        bytes[from.min(bytes.len())..]
            .windows(needle.len())
            .position(|w| w == needle)
            .map_or(bytes.len(), |i| from + i + needle.len())
    };
    let mut depth = 0usize;
    let mut i = 0;
    while let Some(lt) = bytes[i..].iter().position(|&b| b == b'<').map(|p| i + p) {
        let rest = &bytes[lt..];
        i = if rest.starts_with(b"<!--") {
            find(lt + 4, b"-->")
        } else if rest.starts_with(b"<![CDATA[") {
            find(lt + 9, b"]]>")
        } else if rest.starts_with(b"<?") {
            find(lt + 2, b"?>")
        } else if rest.starts_with(b"<!") {
            find(lt + 2, b">")
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            find(lt + 2, b">")
        } else {
            // A start tag: to its `>`, outside quotes; `/>` closes it.
            let mut j = lt + 1;
            let mut quote = None;
            while j < bytes.len() {
                match (quote, bytes[j]) {
                    (None, b'"' | b'\'') => quote = Some(bytes[j]),
                    (Some(q), b) if b == q => quote = None,
                    (None, b'>') => break,
                    _ => {}
                }
                j += 1;
            }
            if bytes.get(j.wrapping_sub(1)) != Some(&b'/') {
                depth += 1;
                if depth > limit {
                    return Some(lt);
                }
            }
            j + 1
        };
        if i >= bytes.len() {
            break;
        }
    }
    None
}

fn parse_version(text: &str) -> Option<(u32, u32, u32)> {
    let mut parts = text.trim().split('.').map(|p| p.parse::<u32>().ok());
    let version = (parts.next()??, parts.next()??, parts.next()??);
    parts.next().is_none().then_some(version)
}

/// A `-D` / `<default>` parameter name.
pub fn is_identifier(name: &str) -> bool {
    !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nesting_is_counted_outside_comments_quotes_and_declarations() {
        let open = |n: usize| "<a>".repeat(n);
        assert_eq!(too_deep(&open(3), 3), None);
        assert_eq!(too_deep(&open(4), 3), Some(9));
        // Self-closing tags, closing tags, and `>` or `/>` inside quotes.
        let text = "<a><b/><c x='>'/><d y=\"/>\"></d><e></e></a><f><g><h>";
        assert_eq!(too_deep(text, 3), None);
        assert_eq!(too_deep(&format!("{text}<i>"), 3), Some(text.len()));
        // Tags inside comments, CDATA, processing instructions and
        // declarations open nothing.
        let hidden = "<?xml version=\"1.0\"?><!-- <a><a><a><a> --><![CDATA[<a><a><a><a>]]><!DOCTYPE x><a><a>";
        assert_eq!(too_deep(hidden, 2), None);
        // An unterminated comment or tag ends the scan.
        assert_eq!(too_deep("<a><!-- <a><a>", 1), None);
        assert_eq!(too_deep("<a><b x='>", 1), Some(3));
    }

    #[test]
    fn places_are_counted_on_from_the_last_in_any_order() {
        let text = "<scene>\n  <é/>\n<b/></scene>";
        let doc = roxmltree::Document::parse(text).unwrap();
        let src = Source {
            file: Arc::from(Path::new("s.xml")),
            text,
            cursor: Cell::new((0, 1, 1)),
        };
        let nodes: Vec<_> = doc.descendants().filter(|n| n.is_element()).collect();
        let place = |i: usize| src.origin(nodes[i]).place;
        assert_eq!(place(2), Place { line: 3, column: 1 });
        // Asked out of order: counted again from the start.
        assert_eq!(place(1), Place { line: 2, column: 3 });
        assert_eq!(place(0), Place { line: 1, column: 1 });
        for (i, n) in nodes.iter().enumerate() {
            let pos = doc.text_pos_at(n.range().start);
            assert_eq!(
                place(i),
                Place {
                    line: pos.row as usize,
                    column: pos.col as usize
                }
            );
        }
    }
}
