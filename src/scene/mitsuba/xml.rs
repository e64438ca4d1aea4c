//! A Mitsuba scene file as a tree of elements: the XML read with roxmltree
//! (no DTD, so no entity expansion), the `version` checked, `<default>`
//! parameters and `-D` definitions substituted for `$name` in every
//! attribute, `<include>` files spliced in place and `<path>` folders added
//! to the search path. Every element keeps its file and line:column.

use crate::scene::load::{read_scene_text, Place, SceneError};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Includes nested deeper than this are refused (an include cycle).
pub const MAX_INCLUDE_DEPTH: usize = 16;

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
    };
    let (root, version) = reader.read_file(path, 0, None)?;
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
}

impl Reader {
    /// Reads one file; `include` is the `<include>` element naming it.
    fn read_file(
        &mut self,
        path: &Path,
        depth: usize,
        include: Option<&Origin>,
    ) -> Result<(Element, (u32, u32, u32)), SceneError> {
        let text = read_scene_text(path).map_err(|e| match include {
            Some(at) => at.error(format!("cannot include: {e}")),
            None => e,
        })?;
        let file: Arc<Path> = Arc::from(path);
        let options = roxmltree::ParsingOptions {
            allow_dtd: false,
            ..Default::default()
        };
        let doc = roxmltree::Document::parse_with_options(&text, options).map_err(|e| {
            let pos = e.pos();
            SceneError::Invalid {
                path: path.into(),
                place: Place {
                    line: pos.row as usize,
                    column: pos.col as usize,
                },
                message: format!("not a valid XML file: {e}"),
            }
        })?;
        let root = doc.root_element();
        let origin = origin_of(&doc, root, &file);
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
            self.element(&doc, child, &file, depth, &mut children)?;
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
    fn element(
        &mut self,
        doc: &roxmltree::Document,
        node: roxmltree::Node,
        file: &Arc<Path>,
        depth: usize,
        out: &mut Vec<Element>,
    ) -> Result<(), SceneError> {
        let origin = origin_of(doc, node, file);
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
                let name = element.required("filename")?;
                let path = resolve(name, element.dir(), &self.search_path);
                let (included, _) = self.read_file(&path, depth + 1, Some(&element.origin))?;
                out.extend(included.children);
                return Ok(());
            }
            _ => {}
        }
        let mut element = element;
        for child in node.children() {
            if child.is_element() {
                self.element(doc, child, file, depth, &mut element.children)?;
            } else if child.is_text() && !child.text().unwrap_or("").trim().is_empty() {
                return Err(origin_of(doc, child, file).error(format!(
                    "unexpected text inside <{}>: Mitsuba scenes give values as attributes",
                    element.tag
                )));
            }
        }
        out.push(element);
        Ok(())
    }

    /// Replaces every `$name` by its parameter's value (the longest name
    /// that follows `$`).
    fn substitute(&self, value: &str, origin: &Origin) -> Result<String, SceneError> {
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
            out.push_str(&param.1);
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(out)
    }
}

fn origin_of(doc: &roxmltree::Document, node: roxmltree::Node, file: &Arc<Path>) -> Origin {
    let pos = doc.text_pos_at(node.range().start);
    Origin {
        file: file.clone(),
        place: Place {
            line: pos.row as usize,
            column: pos.col as usize,
        },
    }
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
