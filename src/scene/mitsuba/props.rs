//! A plugin element (`<bsdf type="diffuse">`, ...) as its properties and
//! nested or referenced objects, read through typed getters that mark what
//! they read, so that [`Plugin::finish`] refuses every property caustic did
//! not read, as Mitsuba refuses unreferenced properties.

use super::spectrum::SpectrumUse;
use super::transform::parse_transform;
use super::values;
use super::xml::{Element, Origin};
use crate::math::{Vec3, Vec3A};
use crate::scene::load::SceneError;
use glam::Mat4;
use std::cell::Cell;
use std::collections::HashMap;

/// Tags of objects (plugins).
pub const OBJECT_TAGS: &[&str] = &[
    "bsdf",
    "shape",
    "emitter",
    "texture",
    "medium",
    "phase",
    "sensor",
    "film",
    "sampler",
    "rfilter",
    "integrator",
    "volume",
];

/// Tags of properties.
pub const PROPERTY_TAGS: &[&str] = &[
    "integer",
    "float",
    "boolean",
    "string",
    "point",
    "vector",
    "rgb",
    "spectrum",
    "transform",
];

/// Objects inside objects deeper than this, counting each `<ref>` as a level,
/// are refused: the plugin readers recurse through nested and referenced
/// objects, and a chain of thousands of BSDFs each referencing the next
/// would overflow the stack. Real scenes nest a few levels.
pub const MAX_OBJECT_DEPTH: usize = 32;

/// Every object with an `id`, found anywhere in the scene.
pub struct Ids<'a> {
    map: HashMap<&'a str, &'a Element>,
    referenced: std::collections::HashSet<&'a str>,
}

impl<'a> Ids<'a> {
    /// Collects the ids under `root`; an id used twice is an error.
    pub fn collect(root: &'a Element) -> Result<Self, SceneError> {
        let mut map = HashMap::new();
        let mut referenced = std::collections::HashSet::new();
        let mut stack = vec![root];
        while let Some(e) = stack.pop() {
            if e.tag == "ref" {
                if let Some(id) = e.attr("id") {
                    referenced.insert(id);
                }
            }
            if OBJECT_TAGS.contains(&e.tag.as_str()) {
                if let Some(id) = e.attr("id") {
                    if let Some(first) = map.insert(id, e) {
                        let (first, second) = if first.origin.place.line <= e.origin.place.line {
                            (first, e)
                        } else {
                            (e, first)
                        };
                        return Err(second.origin.error(format!(
                            "the id `{id}` is already used at {}:{}",
                            first.origin.file.display(),
                            first.origin.place
                        )));
                    }
                }
            }
            stack.extend(e.children.iter());
        }
        Ok(Self { map, referenced })
    }

    /// True when some `<ref>` names `element`'s id: the element is then a
    /// definition, instantiated where it is referenced.
    pub fn is_referenced(&self, element: &Element) -> bool {
        element.attr("id").is_some_and(|id| self.referenced.contains(id))
    }

    /// The object a `<ref id>` names.
    pub fn get(&self, at: &Element) -> Result<&'a Element, SceneError> {
        let id = at.required("id")?;
        self.map
            .get(id)
            .copied()
            .ok_or_else(|| at.origin.error(format!("<ref id=\"{id}\">: no object has this id")))
    }
}

/// A nested or referenced object of a plugin.
pub struct Child<'a> {
    /// Its `name` (the parameter it fills), if any.
    pub name: Option<&'a str>,
    /// The object's definition.
    pub element: &'a Element,
    /// Where it is written or referenced.
    pub at: &'a Element,
    used: Cell<bool>,
}

/// A colour-valued parameter: a constant or a texture plugin.
pub enum ColourParam<'a> {
    /// A constant linear RGB colour.
    Value(Vec3A),
    /// A `<texture>` (nested or referenced).
    Texture(Plugin<'a>),
}

/// A plugin's element with read tracking.
pub struct Plugin<'a> {
    /// The element defining it.
    pub element: &'a Element,
    /// Its `type` attribute.
    pub kind: &'a str,
    props: Vec<(&'a str, &'a Element, Cell<bool>)>,
    children: Vec<Child<'a>>,
    ids: &'a Ids<'a>,
    /// The objects this one is nested in or referenced from, the outermost
    /// first: a `<ref>` to one of them closes a cycle.
    ancestors: Vec<&'a Element>,
}

impl<'a> Plugin<'a> {
    /// The plugin `element` (a tag of [`OBJECT_TAGS`]), its references resolved.
    pub fn new(element: &'a Element, ids: &'a Ids<'a>) -> Result<Self, SceneError> {
        Self::inside(element, ids, Vec::new())
    }

    /// This plugin read afresh (nothing marked as read), where it is.
    pub fn fresh(&self) -> Result<Self, SceneError> {
        Self::inside(self.element, self.ids, self.ancestors.clone())
    }

    /// The child `c` as a plugin inside this one; refuses a reference cycle
    /// and nesting deeper than [`MAX_OBJECT_DEPTH`].
    fn nested(&self, c: &Child<'a>) -> Result<Self, SceneError> {
        let mut ancestors = self.ancestors.clone();
        ancestors.push(self.element);
        if ancestors.iter().any(|a| std::ptr::eq(*a, c.element)) {
            let id = c.element.attr("id").unwrap_or("");
            return Err(c.at.origin.error(format!(
                "<ref id=\"{id}\"> is inside the object `{id}` it names (a reference cycle)"
            )));
        }
        if ancestors.len() >= MAX_OBJECT_DEPTH {
            return Err(c.at.origin.error(format!(
                "objects nested more than {MAX_OBJECT_DEPTH} deep (each <ref> counted as a level)"
            )));
        }
        Self::inside(c.element, self.ids, ancestors)
    }

    fn inside(element: &'a Element, ids: &'a Ids<'a>, ancestors: Vec<&'a Element>) -> Result<Self, SceneError> {
        element.only_attrs(&["type", "id", "name"])?;
        let kind = element.required("type")?;
        let mut props: Vec<(&str, &Element, Cell<bool>)> = Vec::new();
        let mut children = Vec::new();
        for c in &element.children {
            let tag = c.tag.as_str();
            if tag == "ref" {
                c.only_attrs(&["id", "name"])?;
                children.push(Child {
                    name: c.attr("name"),
                    element: ids.get(c)?,
                    at: c,
                    used: Cell::new(false),
                });
            } else if OBJECT_TAGS.contains(&tag) || (tag == "spectrum" && c.attr("type").is_some()) {
                children.push(Child {
                    name: c.attr("name"),
                    element: c,
                    at: c,
                    used: Cell::new(false),
                });
            } else if PROPERTY_TAGS.contains(&tag) {
                let name = c.required("name")?;
                if let Some((_, first, _)) = props.iter().find(|(n, _, _)| *n == name) {
                    return Err(c.origin.error(format!(
                        "the property `{name}` is already given at line {}",
                        first.origin.place.line
                    )));
                }
                props.push((name, c, Cell::new(false)));
            } else {
                return Err(c
                    .origin
                    .error(format!("unexpected <{tag}> inside <{} type=\"{kind}\">", element.tag)));
            }
        }
        Ok(Self {
            element,
            kind,
            props,
            children,
            ids,
            ancestors,
        })
    }

    /// Where the plugin is defined.
    pub fn origin(&self) -> &Origin {
        &self.element.origin
    }

    /// `<tag type="kind">` for messages.
    pub fn what(&self) -> String {
        format!("<{} type=\"{}\">", self.element.tag, self.kind)
    }

    /// An error at the plugin.
    pub fn error(&self, message: impl std::fmt::Display) -> SceneError {
        self.origin().error(format!("{}: {message}", self.what()))
    }

    /// The object ids of the scene.
    pub fn ids(&self) -> &'a Ids<'a> {
        self.ids
    }

    /// The property element `name`, marked as read.
    pub fn take(&self, name: &str) -> Option<&'a Element> {
        self.props.iter().find(|(n, _, _)| *n == name).map(|(_, e, used)| {
            used.set(true);
            *e
        })
    }

    /// True when the property `name` is given.
    pub fn has(&self, name: &str) -> bool {
        self.props.iter().any(|(n, _, _)| *n == name) || self.children.iter().any(|c| c.name == Some(name))
    }

    fn value_of<'e>(&self, e: &'e Element) -> Result<&'e str, SceneError> {
        e.only_attrs(&["name", "value"])?;
        e.required("value")
    }

    fn expect(&self, e: &Element, tags: &[&str]) -> Result<(), SceneError> {
        if tags.contains(&e.tag.as_str()) {
            Ok(())
        } else {
            Err(e.origin.error(format!(
                "`{}` of {} is a <{}>; expected <{}>",
                e.attr("name").unwrap_or(""),
                self.what(),
                e.tag,
                tags.join("> or <")
            )))
        }
    }

    /// A `<float>` (or `<integer>`).
    pub fn float(&self, name: &str) -> Result<Option<f32>, SceneError> {
        let Some(e) = self.take(name) else { return Ok(None) };
        self.expect(e, &["float", "integer"])?;
        let text = self.value_of(e)?;
        match values::numbers(text) {
            Ok(n) if n.len() == 1 => Ok(Some(n[0])),
            _ => Err(e.origin.error(format!("`{name}` = `{text}` is not a finite number"))),
        }
    }

    /// A `<float>` that must satisfy `valid` (described by `what`).
    pub fn float_checked(
        &self,
        name: &str,
        default: f32,
        what: &str,
        valid: impl Fn(f32) -> bool,
    ) -> Result<f32, SceneError> {
        let v = self.float(name)?.unwrap_or(default);
        if valid(v) {
            Ok(v)
        } else {
            let at = self.take(name).map_or(self.origin(), |e| &e.origin);
            Err(at.error(format!("`{name}` of {} is {v}; it must be {what}", self.what())))
        }
    }

    /// An `<integer>`.
    pub fn int(&self, name: &str) -> Result<Option<i64>, SceneError> {
        let Some(e) = self.take(name) else { return Ok(None) };
        self.expect(e, &["integer"])?;
        let text = self.value_of(e)?.trim();
        text.parse::<i64>()
            .map(Some)
            .map_err(|_| e.origin.error(format!("`{name}` = `{text}` is not an integer")))
    }

    /// A `<boolean>`.
    pub fn boolean(&self, name: &str) -> Result<Option<bool>, SceneError> {
        let Some(e) = self.take(name) else { return Ok(None) };
        self.expect(e, &["boolean"])?;
        match self.value_of(e)?.trim() {
            "true" | "True" | "1" => Ok(Some(true)),
            "false" | "False" | "0" => Ok(Some(false)),
            other => Err(e.origin.error(format!("`{name}` = `{other}` is not true or false"))),
        }
    }

    /// A `<string>`.
    pub fn string(&self, name: &str) -> Result<Option<&'a str>, SceneError> {
        let Some(e) = self.take(name) else { return Ok(None) };
        self.expect(e, &["string"])?;
        e.only_attrs(&["name", "value"])?;
        e.required("value").map(Some)
    }

    /// A `<string>` among `choices`.
    pub fn choice(&self, name: &str, default: &'a str, choices: &[&str]) -> Result<&'a str, SceneError> {
        let v = self.string(name)?.unwrap_or(default);
        if choices.contains(&v) {
            Ok(v)
        } else {
            let at = self.take(name).map_or(self.origin(), |e| &e.origin);
            Err(at.error(format!(
                "`{name}` of {} is `{v}`; caustic reads {}",
                self.what(),
                choices.join(", ")
            )))
        }
    }

    /// A `<point>` or `<vector>`: `x`, `y`, `z` attributes or `value`.
    pub fn vector(&self, name: &str) -> Result<Option<Vec3>, SceneError> {
        let Some(e) = self.take(name) else { return Ok(None) };
        self.expect(e, &["point", "vector"])?;
        e.only_attrs(&["name", "value", "x", "y", "z"])?;
        if let Some(v) = e.attr("value") {
            return values::vector3(v)
                .map(Some)
                .map_err(|m| e.origin.error(format!("`{name}`: {m}")));
        }
        let c = |a: &str| -> Result<f32, SceneError> {
            match e.attr(a) {
                None => Ok(0.0),
                Some(t) => match values::numbers(t) {
                    Ok(n) if n.len() == 1 => Ok(n[0]),
                    _ => Err(e.origin.error(format!("`{name}`: {a} = `{t}` is not a number"))),
                },
            }
        };
        Ok(Some(Vec3::new(c("x")?, c("y")?, c("z")?)))
    }

    /// A `<transform>`.
    pub fn transform(&self, name: &str) -> Result<Option<Mat4>, SceneError> {
        let Some(e) = self.take(name) else { return Ok(None) };
        self.expect(e, &["transform"])?;
        parse_transform(e).map(Some)
    }

    /// A colour: `<rgb>`, `<spectrum>` (reduced as Mitsuba's RGB variants
    /// reduce it for `usage`), `<float>`, or a texture named `name`.
    pub fn colour(&self, name: &str, usage: SpectrumUse) -> Result<Option<ColourParam<'a>>, SceneError> {
        if let Some(child) = self.child_named(name)? {
            return Ok(Some(ColourParam::Texture(child)));
        }
        let Some(e) = self.take(name) else { return Ok(None) };
        self.expect(e, &["rgb", "spectrum", "float", "integer"])?;
        let c = match e.tag.as_str() {
            "spectrum" if e.attr("value").is_none() => {
                e.only_attrs(&["name", "wavelengths", "values", "filename"])?;
                if e.attr("filename").is_some() {
                    return Err(e.origin.error(format!(
                        "`{name}`: spectra from files are not read; give `value` or `wavelengths` and `values`"
                    )));
                }
                let list =
                    |a: &str| values::numbers(e.required(a)?).map_err(|m| e.origin.error(format!("`{name}` {a}: {m}")));
                values::pairs_to_srgb(&list("wavelengths")?, &list("values")?, usage)
                    .map_err(|m| e.origin.error(format!("`{name}`: {m}")))?
            }
            "spectrum" => {
                values::spectrum(self.value_of(e)?, usage).map_err(|m| e.origin.error(format!("`{name}`: {m}")))?
            }
            "rgb" => values::rgb(self.value_of(e)?).map_err(|m| e.origin.error(format!("`{name}`: {m}")))?,
            _ => {
                let text = self.value_of(e)?;
                match values::numbers(text) {
                    Ok(n) if n.len() == 1 => Vec3A::splat(n[0]),
                    _ => return Err(e.origin.error(format!("`{name}` = `{text}` is not a number"))),
                }
            }
        };
        Ok(Some(ColourParam::Value(c)))
    }

    /// The object whose `name` is `name`, marked as read.
    pub fn child_named(&self, name: &str) -> Result<Option<Plugin<'a>>, SceneError> {
        match self.children.iter().find(|c| c.name == Some(name)) {
            None => Ok(None),
            Some(c) => {
                c.used.set(true);
                self.nested(c).map(Some)
            }
        }
    }

    /// The objects of class `tag` (nested or referenced), marked as read,
    /// with where each is written.
    pub fn children_of(&self, tag: &str) -> Result<Vec<(Plugin<'a>, &'a Element)>, SceneError> {
        let mut out = Vec::new();
        for c in self.children.iter().filter(|c| c.element.tag == tag && !c.used.get()) {
            c.used.set(true);
            out.push((self.nested(c)?, c.at));
        }
        Ok(out)
    }

    /// At most one object of class `tag`.
    pub fn single_child(&self, tag: &str) -> Result<Option<Plugin<'a>>, SceneError> {
        let mut all = self.children_of(tag)?;
        match all.len() {
            0 | 1 => Ok(all.pop().map(|(p, _)| p)),
            _ => Err(all[1]
                .1
                .origin
                .error(format!("{} takes one <{tag}>, not several", self.what()))),
        }
    }

    /// Refuses what was not read: a property caustic does not read is either
    /// a typo or a feature it does not implement, and is never ignored.
    pub fn finish(&self) -> Result<(), SceneError> {
        if let Some((name, e, _)) = self.props.iter().find(|(_, _, used)| !used.get()) {
            return Err(e.origin.error(format!(
                "`{name}` is not a parameter of {} that caustic reads (a misspelling, or a feature it does not implement)",
                self.what()
            )));
        }
        if let Some(c) = self.children.iter().find(|c| !c.used.get()) {
            return Err(c.at.origin.error(format!(
                "{} does not take a <{}>{} here",
                self.what(),
                c.element.tag,
                c.name.map(|n| format!(" named `{n}`")).unwrap_or_default()
            )));
        }
        Ok(())
    }
}
