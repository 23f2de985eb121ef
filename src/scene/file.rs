//! The scene file as written: serde structs, `--set` overrides and the map from dotted
//! key paths to places in the text.
//!
//! Loading goes text -> `toml_edit` document (syntax errors) -> overrides applied in
//! place (layout kept, so untouched keys keep their line numbers) -> effective text ->
//! serde structs (unknown keys and wrong types, with spans) -> semantic checks in
//! `mod.rs`, which name dotted paths that [`Source::error`] turns into `file:line:col`.
//!
//! Shape, light, material and environment tables are flat structs with every key any
//! variant takes, rather than serde's internally tagged enums: those buffer their
//! contents and lose the spans that errors need. Which keys a given `type` or `shape`
//! accepts is checked by [`check_keys`].

use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;

use super::error::{ErrorKind, Location, SceneError};

/// A colour or spectral quantity written as a scalar (grey) or `[r, g, b]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Rgb(pub [f32; 3]);

impl<'de> Deserialize<'de> for Rgb {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Rgb;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or an [r, g, b] array of numbers")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Rgb, E> {
                Ok(Rgb([v as f32; 3]))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Rgb, E> {
                Ok(Rgb([v as f32; 3]))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Rgb, E> {
                Ok(Rgb([v as f32; 3]))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Rgb, A::Error> {
                let mut c = [0.0f32; 3];
                for (i, slot) in c.iter_mut().enumerate() {
                    *slot = seq.next_element::<f32>()?.ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<f32>()?.is_some() {
                    return Err(de::Error::invalid_length(4, &self));
                }
                Ok(Rgb(c))
            }
        }
        d.deserialize_any(V)
    }
}

/// A flat table: the keys every variant (`type` or `shape`) takes, then the optional keys
/// that only some variants take, each declared once; `present()` names the variant keys a
/// table has, for [`check_keys`].
macro_rules! flat_table {
    (
        $(#[doc = $doc:literal])*
        struct $name:ident { $($(#[$attr:meta])* pub $field:ident: $ty:ty,)* }
        variant keys { $($key:ident: $kty:ty,)* }
    ) => {
        $(#[doc = $doc])*
        #[derive(Debug, Deserialize)]
        #[serde(deny_unknown_fields)]
        pub(crate) struct $name {
            $($(#[$attr])* pub $field: $ty,)*
            $(pub $key: Option<$kty>,)*
        }

        impl $name {
            pub fn present(&self) -> Vec<&'static str> {
                let keys = [$((stringify!($key), self.$key.is_some())),*];
                keys.into_iter().filter(|(_, p)| *p).map(|(k, _)| k).collect()
            }
        }
    };
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileScene {
    pub name: Option<String>,
    /// One line saying what the scene shows (`prism scenes` lists it).
    pub description: Option<String>,
    pub camera: FileCamera,
    pub environment: Option<FileEnvironment>,
    #[serde(default)]
    pub lights: Vec<FileLight>,
    #[serde(default)]
    pub materials: BTreeMap<String, FileMaterial>,
    #[serde(default)]
    pub objects: Vec<FileObject>,
    /// An inhomogeneous refractive volume (src/scene/volume.rs, eikonal rendering).
    pub volume: Option<FileVolume>,
    /// Checked by hand in `mod.rs`: besides the known keys it holds technique
    /// parameter tables (`[render.<technique>]`) that the techniques validate.
    pub render: Option<toml::Table>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileCamera {
    pub position: [f32; 3],
    pub target: [f32; 3],
    pub up: Option<[f32; 3]>,
    pub vfov_deg: Option<f32>,
    pub width: Option<u32>,
    pub height: Option<u32>,
}

flat_table! {
    struct FileEnvironment {
        #[serde(rename = "type")]
        pub kind: String,
    }
    variant keys {
        radiance: Rgb,
        file: String,
    }
}

flat_table! {
    struct FileLight {
        #[serde(rename = "type")]
        pub kind: String,
    }
    variant keys {
        position: [f32; 3],
        intensity: Rgb,
        direction: [f32; 3],
        irradiance: Rgb,
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileChecker {
    pub a: Rgb,
    pub b: Rgb,
    pub size: f32,
}

flat_table! {
    struct FileMaterial {
        #[serde(rename = "type")]
        pub kind: String,
    }
    variant keys {
        albedo: Rgb,
        checker: FileChecker,
        reflectance: Rgb,
        eta: Rgb,
        k: Rgb,
        ior: Rgb,
        absorption: Rgb,
    }
}

#[derive(Debug, Default, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileTransform {
    pub translation: Option<[f32; 3]>,
    pub rotation: Option<[f32; 3]>,
    pub scale: Option<f32>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileFit {
    pub extent: f32,
    pub center: Option<[f32; 3]>,
    pub floor: Option<f32>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileWave {
    pub amplitude: f32,
    #[serde(default)]
    pub kx: f32,
    #[serde(default)]
    pub kz: f32,
    #[serde(default)]
    pub omega: f32,
    #[serde(default)]
    pub phase: f32,
}

flat_table! {
    struct FileObject {
        pub name: Option<String>,
        pub material: String,
        pub shape: String,
        pub transform: Option<FileTransform>,
    }
    variant keys {
        center: [f32; 3],
        radius: f32,
        segments: u32,
        size: Vec<f32>,
        normal: [f32; 3],
        major_radius: f32,
        minor_radius: f32,
        height: f32,
        profile: Vec<[f32; 2]>,
        resolution: [u32; 2],
        waves: Vec<FileWave>,
        time: f32,
        file: String,
        fit: FileFit,
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileBounds {
    pub min: [f32; 3],
    pub max: [f32; 3],
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileVolume {
    pub name: Option<String>,
    pub bounds: FileBounds,
    pub resolution: [u32; 3],
    /// Optional: without it the box holds air (n = 1).
    pub index: Option<FileIndex>,
    pub attenuation: Option<Rgb>,
    // The base material of the profile's region (src/scene/volume_sources.rs).
    pub sigma_s: Option<Rgb>,
    pub hg_g: Option<f32>,
    pub emission: Option<Rgb>,
    pub reflectance: Option<f32>,
    /// `[[volume.region]]`: material regions rasterized over the profile, later ones on top.
    #[serde(default)]
    pub region: Vec<FileRegion>,
}

flat_table! {
    /// One `[[volume.region]]`: a shape (flat keys, like the objects) and its material.
    struct FileRegion {
        pub name: Option<String>,
        pub shape: String,
        pub transform: Option<FileTransform>,
        pub n: Option<Rgb>,
        pub sigma_a: Option<Rgb>,
        pub sigma_s: Option<Rgb>,
        pub hg_g: Option<f32>,
        pub emission: Option<Rgb>,
        pub reflectance: Option<f32>,
    }
    variant keys {
        center: [f32; 3],
        radius: f32,
        size: [f32; 3],
        height: f32,
        profile: Vec<[f32; 2]>,
        file: String,
        fit: FileFit,
    }
}

flat_table! {
    /// `volume.index`: one flat struct for every profile `type`, like the shapes.
    struct FileIndex {
        #[serde(rename = "type")]
        pub kind: String,
    }
    variant keys {
        n: f32,
        center: [f32; 3],
        radius: f32,
        n0: f32,
        gradient: [f32; 3],
    }
}

/// Checks that a table of the given variant (`what`, e.g. "shape `sphere`") has every
/// key in `required` and nothing outside `allowed`. `table` is its dotted path.
pub(crate) fn check_keys(
    src: &Source,
    table: &str,
    what: &str,
    present: &[&'static str],
    allowed: &[&str],
    required: &[&str],
) -> Result<(), SceneError> {
    for key in present {
        if !allowed.contains(key) {
            return Err(src.key_error(
                ErrorKind::Schema,
                &format!("{table}.{key}"),
                format!("key `{key}` is not used by {what}"),
                format!("{what} takes {}", list(allowed)),
            ));
        }
    }
    for key in required {
        if !present.contains(key) {
            return Err(src.error(
                ErrorKind::Schema,
                table,
                format!("{what} needs `{key}`"),
                format!("add `{key} = ...`; {what} takes {}", list(allowed)),
            ));
        }
    }
    Ok(())
}

/// `a, b, c` with backticks, for hints.
pub(crate) fn list(items: &[&str]) -> String {
    if items.is_empty() {
        return "no keys".to_string();
    }
    items.iter().map(|s| format!("`{s}`")).collect::<Vec<_>>().join(", ")
}

/// One `--set key=value` override.
#[derive(Debug, Clone)]
pub(crate) struct Override {
    /// As the user wrote it, for error messages.
    pub raw: String,
    pub path: Vec<String>,
    pub value: toml_edit::Value,
}

impl Override {
    pub fn dotted(&self) -> String {
        self.path.join(".")
    }
}

/// Most segments in a `--set` key: the deepest scene key has a handful, and applying an
/// override recurses once per segment.
pub(crate) const MAX_OVERRIDE_DEPTH: usize = 64;

pub(crate) fn parse_override(raw: &str) -> Result<Override, SceneError> {
    let fail = |message: &str| SceneError::Override {
        set: raw.to_string(),
        message: message.to_string(),
        hint: "write `--set dotted.key=value`, e.g. `--set objects.0.radius=0.5` or `--set render.refraction=single`"
            .to_string(),
    };
    let (key, value) = raw.split_once('=').ok_or_else(|| fail("no `=` in the override"))?;
    let key = key.trim();
    if key.is_empty() {
        return Err(fail("empty key"));
    }
    if key.split('.').count() > MAX_OVERRIDE_DEPTH {
        return Err(fail(&format!("the dotted key has more than {MAX_OVERRIDE_DEPTH} segments")));
    }
    let path: Vec<String> = key.split('.').map(|s| s.trim().to_string()).collect();
    if path.iter().any(|s| s.is_empty()) {
        return Err(fail("empty segment in the dotted key"));
    }
    let text = value.trim();
    // A TOML value if it parses as one, otherwise the raw text as a string, so that
    // `render.refraction=wyman` needs no shell-quoted quotes.
    let value = match text.parse::<toml_edit::Value>() {
        Ok(v) => v,
        Err(_) => toml_edit::Value::from(text),
    };
    Ok(Override { raw: raw.to_string(), path, value })
}

/// Applies `ov` to `doc`. The last key may be new (a key left at its default); missing
/// intermediate tables are created only under `render` (technique parameters are
/// open-ended); anywhere else the tables on the path must exist.
pub(crate) fn apply_override(doc: &mut toml_edit::DocumentMut, ov: &Override) -> Result<(), SceneError> {
    let create = ov.path[0] == "render";
    let segs: Vec<&str> = ov.path.iter().map(String::as_str).collect();
    SetPath { segs: &segs, create }
        .table(doc.as_table_mut(), 0, ov.value.clone())
        .map_err(|(message, hint)| SceneError::Override { set: ov.raw.clone(), message, hint })
}

type SetError = (String, String);

fn missing(segs: &[&str], depth: usize) -> SetError {
    let at = segs[..=depth].join(".");
    if depth + 1 == segs.len() && depth > 0 {
        // The table exists but does not write this key: it may be a misspelling, or
        // a real key left at its default, which must be written to be overridden
        // (so that the file, not the command line, decides what a scene holds).
        return (
            format!("`{at}` is not written in the scene file"),
            format!(
                "check the spelling against docs/scene-format.md; if `{}` is a real key \
                 taking its default, write it in the file to override it (only keys under \
                 `render` are created)",
                segs[depth]
            ),
        );
    }
    (
        format!("`{at}` does not exist in the scene"),
        "an override may only change a key the scene file already has (new keys are \
         allowed only under `render`); check the spelling against docs/scene-format.md"
            .to_string(),
    )
}

/// The dotted path of an override, and whether missing tables on it may be created.
struct SetPath<'a> {
    segs: &'a [&'a str],
    create: bool,
}

impl SetPath<'_> {
    fn table(&self, t: &mut dyn toml_edit::TableLike, depth: usize, value: toml_edit::Value) -> Result<(), SetError> {
        let seg = self.segs[depth];
        let last = depth + 1 == self.segs.len();
        if last {
            match t.get_mut(seg) {
                Some(item) => replace_item(item, value, self.segs, depth),
                // A key of an existing table may be added: it may be a real key left at its
                // default. A misspelt one is then rejected by the schema (deny_unknown_fields),
                // with an error that names this override.
                None => {
                    t.insert(seg, toml_edit::Item::Value(value));
                    Ok(())
                }
            }
        } else {
            if t.get(seg).is_none() {
                if !self.create {
                    return Err(missing(self.segs, depth));
                }
                t.insert(seg, toml_edit::Item::Table(toml_edit::Table::new()));
            }
            match t.get_mut(seg) {
                Some(item) => self.item(item, depth + 1, value),
                None => Err(missing(self.segs, depth)),
            }
        }
    }

    fn item(&self, item: &mut toml_edit::Item, depth: usize, value: toml_edit::Value) -> Result<(), SetError> {
        match item {
            toml_edit::Item::Table(t) => self.table(t, depth, value),
            toml_edit::Item::ArrayOfTables(aot) => {
                let len = aot.len();
                let idx = index(self.segs, depth, len)?;
                match aot.get_mut(idx) {
                    Some(_) if depth + 1 == self.segs.len() => Err((
                        format!("`{}` is a whole table", self.segs[..=depth].join(".")),
                        "set its keys one at a time, e.g. `objects.0.radius=0.5`".to_string(),
                    )),
                    Some(t) => self.table(t, depth + 1, value),
                    None => Err(missing(self.segs, depth)),
                }
            }
            toml_edit::Item::Value(v) => self.value(v, depth, value),
            toml_edit::Item::None => Err(missing(self.segs, depth)),
        }
    }

    fn value(&self, v: &mut toml_edit::Value, depth: usize, value: toml_edit::Value) -> Result<(), SetError> {
        match v {
            toml_edit::Value::InlineTable(t) => self.table(t, depth, value),
            toml_edit::Value::Array(a) => {
                let idx = index(self.segs, depth, a.len())?;
                if depth + 1 == self.segs.len() {
                    let decor = a.get(idx).map(|old| old.decor().clone());
                    let mut value = value;
                    if let Some(decor) = decor {
                        *value.decor_mut() = decor;
                    }
                    a.replace(idx, value);
                    Ok(())
                } else {
                    match a.get_mut(idx) {
                        Some(inner) => self.value(inner, depth + 1, value),
                        None => Err(missing(self.segs, depth)),
                    }
                }
            }
            _ => Err((
                format!("`{}` is a {}, not a table or array", self.segs[..depth].join("."), v.type_name()),
                "remove the extra segments after the key".to_string(),
            )),
        }
    }
}

fn index(segs: &[&str], depth: usize, len: usize) -> Result<usize, SetError> {
    let at = segs[..depth].join(".");
    let idx: usize = segs[depth].parse().map_err(|_| {
        (
            format!("`{at}` is an array; `{}` is not an index", segs[depth]),
            format!("use a 0-based index, e.g. `{at}.0`"),
        )
    })?;
    if idx >= len {
        return Err((
            format!("`{at}` has {len} entries; index {idx} is out of range"),
            format!("use an index from 0 to {}", len.saturating_sub(1)),
        ));
    }
    Ok(idx)
}

fn replace_item(
    item: &mut toml_edit::Item,
    value: toml_edit::Value,
    segs: &[&str],
    depth: usize,
) -> Result<(), SetError> {
    match item {
        toml_edit::Item::Value(old) => {
            // Keep the old value's surrounding whitespace and trailing comment.
            let mut value = value;
            *value.decor_mut() = old.decor().clone();
            *old = value;
            Ok(())
        }
        _ => Err((format!("`{}` is a table", segs[..=depth].join(".")), "set its keys one at a time".to_string())),
    }
}

/// The effective scene text and what is needed to point errors into it.
pub(crate) struct Source {
    pub file: PathBuf,
    pub text: String,
    spans: Spans,
    pub overrides: Vec<Override>,
}

impl Source {
    fn new(file: &Path, text: String, overrides: Vec<Override>) -> Self {
        let mut spans = Spans::default();
        if let Ok(doc) = toml_edit::ImDocument::parse(text.as_str()) {
            spans.table(doc.as_table(), "");
        }
        Source { file: file.to_path_buf(), text, spans, overrides }
    }

    /// The override whose path is `path` or a parent of it.
    fn override_for(&self, path: &str) -> Option<&Override> {
        self.overrides.iter().rev().find(|o| {
            let d = o.dotted();
            path == d || path.starts_with(&format!("{d}."))
        })
    }

    /// The override whose key or value contains byte `offset` of the effective text
    /// (an unknown-field error points at the key an override added).
    fn override_at(&self, offset: usize) -> Option<&Override> {
        let within = |r: &Range<usize>| r.start <= offset && offset < r.end.max(r.start + 1);
        self.overrides.iter().rev().find(|o| {
            let d = o.dotted();
            self.spans.values.get(&d).is_some_and(within) || self.spans.keys.get(&d).is_some_and(within)
        })
    }

    fn span(&self, map: &HashMap<String, Range<usize>>, path: &str) -> Option<Range<usize>> {
        // A missing key is reported at the nearest enclosing table that exists.
        let mut p = path;
        loop {
            if let Some(r) = map.get(p).or_else(|| self.spans.values.get(p)) {
                return Some(r.clone());
            }
            p = &p[..p.rfind('.')?];
        }
    }

    /// Where the value at dotted `path` (or its nearest existing parent) is.
    pub fn location(&self, path: &str) -> Location {
        self.location_of(self.span(&self.spans.values, path).map(|r| r.start))
    }

    pub fn location_of(&self, offset: Option<usize>) -> Location {
        match offset {
            Some(o) => Location::at_offset(&self.file, &self.text, o),
            None => Location::file(&self.file),
        }
    }

    /// An error about the value at dotted `path`.
    pub fn error(&self, kind: ErrorKind, path: &str, message: String, hint: String) -> SceneError {
        let at = self.location_of(self.span(&self.spans.values, path).map(|r| r.start));
        SceneError::Invalid { kind, at, set: self.override_for(path).map(|o| o.raw.clone()), message, hint }
    }

    /// An error about the key at dotted `path` (e.g. a key the variant does not take).
    pub fn key_error(&self, kind: ErrorKind, path: &str, message: String, hint: String) -> SceneError {
        let at = self.location_of(self.span(&self.spans.keys, path).map(|r| r.start));
        SceneError::Invalid { kind, at, set: self.override_for(path).map(|o| o.raw.clone()), message, hint }
    }

    /// A serde error from deserializing the effective text.
    fn schema_error(&self, e: toml::de::Error) -> SceneError {
        let offset = e.span().map(|r| r.start);
        let message = e.message().trim().to_string();
        let hint = if message.contains("unknown field") {
            "remove or correct the key; docs/scene-format.md lists every key"
        } else if message.contains("missing field") {
            "add the key; docs/scene-format.md lists the required keys"
        } else {
            "check the value's type against docs/scene-format.md"
        };
        SceneError::Invalid {
            kind: ErrorKind::Schema,
            at: self.location_of(offset),
            set: offset.and_then(|o| self.override_at(o)).map(|o| o.raw.clone()),
            message,
            hint: hint.to_string(),
        }
    }
}

fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

/// Byte ranges of the values and keys of a TOML document, by dotted path.
#[derive(Default)]
struct Spans {
    /// Dotted path -> byte range of the value (tables: their header or braces).
    values: HashMap<String, Range<usize>>,
    /// Dotted path -> byte range of the key.
    keys: HashMap<String, Range<usize>>,
}

impl Spans {
    fn table(&mut self, t: &dyn toml_edit::TableLike, prefix: &str) {
        for (k, item) in t.iter() {
            let path = join(prefix, k);
            if let Some(r) = t.key(k).and_then(|key| key.span()) {
                self.keys.insert(path.clone(), r);
            }
            self.item(item, &path);
        }
    }

    fn value_at(&mut self, path: &str, span: Option<Range<usize>>) {
        if let Some(r) = span {
            self.values.insert(path.to_string(), r);
        }
    }

    fn item(&mut self, item: &toml_edit::Item, path: &str) {
        self.value_at(path, item.span());
        match item {
            toml_edit::Item::Table(t) => self.table(t, path),
            toml_edit::Item::ArrayOfTables(aot) => {
                for (i, t) in aot.iter().enumerate() {
                    let p = format!("{path}.{i}");
                    self.value_at(&p, t.span());
                    self.table(t, &p);
                }
            }
            toml_edit::Item::Value(v) => self.value(v, path),
            toml_edit::Item::None => {}
        }
    }

    fn value(&mut self, v: &toml_edit::Value, path: &str) {
        self.value_at(path, v.span());
        match v {
            toml_edit::Value::InlineTable(t) => self.table(t, path),
            toml_edit::Value::Array(a) => {
                for (i, e) in a.iter().enumerate() {
                    self.value(e, &format!("{path}.{i}"));
                }
            }
            _ => {}
        }
    }
}

/// Parses `text` (the contents of `origin`), applies `overrides` and deserializes.
pub(crate) fn parse(text: &str, origin: &Path, overrides: &[String]) -> Result<(FileScene, Source), SceneError> {
    let mut doc: toml_edit::DocumentMut = text.parse().map_err(|e: toml_edit::TomlError| {
        let offset = e.span().map(|r| r.start);
        // toml_edit's message carries its own rendering of the line; keep the first
        // line of its explanation, which says what was expected.
        let message = e.message().lines().find(|l| !l.trim().is_empty()).unwrap_or("invalid TOML").trim().to_string();
        SceneError::Invalid {
            kind: ErrorKind::Syntax,
            at: match offset {
                Some(o) => Location::at_offset(origin, text, o),
                None => Location::file(origin),
            },
            set: None,
            message: format!("malformed TOML: {message}"),
            hint: "fix the TOML syntax at this place (strings need quotes, arrays brackets, \
                   one `key = value` per line)"
                .to_string(),
        }
    })?;
    let mut parsed = Vec::with_capacity(overrides.len());
    for raw in overrides {
        let ov = parse_override(raw)?;
        apply_override(&mut doc, &ov)?;
        parsed.push(ov);
    }
    let effective = doc.to_string();
    let src = Source::new(origin, effective, parsed);
    let scene: FileScene = toml::from_str(&src.text).map_err(|e| src.schema_error(e))?;
    Ok((scene, src))
}

/// A deterministic form of the effective scene (keys sorted, comments and layout
/// dropped), so that equal scenes hash equally whatever their formatting.
pub(crate) fn canonical(src: &Source) -> String {
    match src.text.parse::<toml::Table>() {
        Ok(t) => toml::to_string(&t).unwrap_or_else(|_| src.text.clone()),
        Err(_) => src.text.clone(),
    }
}
