//! Typed, validated parameters of the techniques: the `[render.<technique>]` tables.
//!
//! Each parameter is declared once, in `params!` below: its field and doc comment, its
//! default and its range (numbers) or accepted names (`choice!` enums). From that one
//! declaration come the struct, its `Default`, its parser (`from_table`, `from_settings`),
//! the list of valid keys behind "did you mean" hints, the list of tables the scene loader
//! accepts ([`TABLES`]) and the tables of docs/scene-format.md ([`docs_table`]; a unit test
//! fails when the file is out of date, and `PRISM_BLESS=1` makes it write them).
//!
//! The scene loader checks a table when it reads it, so that a misspelt key or an absurd
//! value is an error naming `file:line` or the `--set` that put it there; the passes parse
//! the same table again into these structs (cannot fail after loading).

use super::RenderSettings;

/// A parameter that is unknown or out of range: the key (under `render.<technique>.`), what
/// is wrong, and what to do.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamError {
    pub key: String,
    pub message: String,
    pub hint: String,
}

impl std::fmt::Display for ParamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}\n  hint: {}", self.message, self.hint)
    }
}

/// A kind of parameter value: how it is read from TOML and how the docs table writes it.
trait Param: Sized {
    /// Where a value must lie: `lo..=hi` for numbers, `()` where the type says it all.
    type Range;
    /// The docs table's type column.
    const TYPE: &'static str;
    fn parse(key: &str, v: &toml::Value, range: &Self::Range) -> Result<Self, ParamError>;
    /// The docs table's range column.
    fn accepted(range: &Self::Range) -> String;
    /// A value (the default) as the docs table writes it.
    fn show(&self) -> String;
    /// A choice's names with what each means, for the docs table's meaning column.
    fn meanings() -> Vec<(&'static str, String)> {
        Vec::new()
    }
    /// How the window edits the value.
    fn control(&self, range: &Self::Range) -> Control;
}

/// A parameter as the window's controls edit it: its value now and what it may be.
#[derive(Debug, Clone, PartialEq)]
pub enum Control {
    Integer {
        value: i64,
        range: std::ops::RangeInclusive<i64>,
    },
    Number {
        value: f64,
        range: std::ops::RangeInclusive<f64>,
    },
    /// A number or `"auto"` (`None`).
    Auto {
        value: Option<f64>,
        range: std::ops::RangeInclusive<f64>,
    },
    Bool(bool),
    Choice {
        value: &'static str,
        names: &'static [&'static str],
    },
}

impl Control {
    /// The value as a `--set` writes it.
    pub fn toml(&self) -> String {
        match self {
            Control::Integer { value, .. } => value.to_string(),
            Control::Number { value, .. } | Control::Auto { value: Some(value), .. } => format!("{value:e}"),
            Control::Auto { value: None, .. } => "\"auto\"".into(),
            Control::Bool(b) => b.to_string(),
            Control::Choice { value, .. } => format!("\"{value}\""),
        }
    }
}

/// One key of a `[render.<table>]` for the window: its name, its meaning and its control.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamView {
    pub key: &'static str,
    pub doc: String,
    pub control: Control,
}

impl Param for u32 {
    type Range = std::ops::RangeInclusive<i64>;
    const TYPE: &'static str = "integer";
    fn parse(key: &str, v: &toml::Value, range: &Self::Range) -> Result<Self, ParamError> {
        let (lo, hi) = (*range.start(), *range.end());
        match v.as_integer() {
            Some(n) if range.contains(&n) => Ok(n as u32),
            _ => Err(ParamError {
                key: key.to_string(),
                message: format!("`{key}` must be an integer from {lo} to {hi}, not {v}"),
                hint: "use a whole number in range".into(),
            }),
        }
    }
    fn accepted(range: &Self::Range) -> String {
        format!("{} to {}", range.start(), range.end())
    }
    fn show(&self) -> String {
        self.to_string()
    }
    fn control(&self, range: &Self::Range) -> Control {
        Control::Integer { value: *self as i64, range: range.clone() }
    }
}

impl Param for f32 {
    type Range = std::ops::RangeInclusive<f64>;
    const TYPE: &'static str = "number";
    fn parse(key: &str, v: &toml::Value, range: &Self::Range) -> Result<Self, ParamError> {
        let (lo, hi) = (*range.start(), *range.end());
        match v.as_float().or_else(|| v.as_integer().map(|i| i as f64)) {
            Some(x) if x.is_finite() && x >= lo && x <= hi => Ok(x as f32),
            _ => Err(ParamError {
                key: key.to_string(),
                message: format!("`{key}` must be a number from {lo:e} to {hi:e}, not {v}"),
                hint: "use a finite number in range".into(),
            }),
        }
    }
    fn accepted(range: &Self::Range) -> String {
        format!("{} to {}", short(*range.start()), short(*range.end()))
    }
    fn show(&self) -> String {
        short(*self)
    }
    fn control(&self, range: &Self::Range) -> Control {
        Control::Number { value: *self as f64, range: range.clone() }
    }
}

/// A number, or `"auto"` (`None`) for a value the technique works out itself.
impl Param for Option<f32> {
    type Range = std::ops::RangeInclusive<f64>;
    const TYPE: &'static str = "number or `\"auto\"`";
    fn parse(key: &str, v: &toml::Value, range: &Self::Range) -> Result<Self, ParamError> {
        if v.as_str() == Some("auto") {
            return Ok(None);
        }
        let (lo, hi) = (*range.start(), *range.end());
        <f32 as Param>::parse(key, v, range).map(Some).map_err(|e| ParamError {
            message: format!("`{key}` must be \"auto\" or a number from {lo:e} to {hi:e}, not {v}"),
            ..e
        })
    }
    fn accepted(range: &Self::Range) -> String {
        format!("`\"auto\"` or {}", <f32 as Param>::accepted(range))
    }
    fn show(&self) -> String {
        self.map_or("`\"auto\"`".into(), short)
    }
    fn control(&self, range: &Self::Range) -> Control {
        Control::Auto { value: self.map(f64::from), range: range.clone() }
    }
}

impl Param for bool {
    type Range = ();
    const TYPE: &'static str = "boolean";
    fn parse(key: &str, v: &toml::Value, _: &()) -> Result<Self, ParamError> {
        v.as_bool().ok_or_else(|| ParamError {
            key: key.to_string(),
            message: format!("`{key}` must be true or false, not {v}"),
            hint: "write a boolean without quotes".into(),
        })
    }
    fn accepted(_: &()) -> String {
        "true, false".into()
    }
    fn show(&self) -> String {
        self.to_string()
    }
    fn control(&self, _: &()) -> Control {
        Control::Bool(*self)
    }
}

/// The shorter of `x`'s plain and exponent forms (`0.75`, `1e-4`, `1e6`), for the docs.
fn short<T: std::fmt::Display + std::fmt::LowerExp>(x: T) -> String {
    let (plain, exp) = (format!("{x}"), format!("{x:e}"));
    if exp.len() < plain.len() {
        exp
    } else {
        plain
    }
}

/// The index of `v` in `names`. A TOML boolean counts as the name it spells, because
/// `--set render.caustics_map.newton=true` arrives as one.
fn choose(key: &str, v: &toml::Value, names: &[&str], hint: &str) -> Result<usize, ParamError> {
    let spelt = v.as_bool().map(|b| if b { "true" } else { "false" });
    let found = v.as_str().or(spelt).and_then(|s| names.iter().position(|n| *n == s));
    found.ok_or_else(|| {
        let quoted: Vec<String> = names.iter().map(|n| format!("\"{n}\"")).collect();
        let listed = match quoted.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
            _ => quoted.concat(),
        };
        ParamError { key: key.to_string(), message: format!("`{key}` must be {listed}, not {v}"), hint: hint.into() }
    })
}

/// Joins a doc comment's lines into one line of a markdown table cell.
fn prose(lines: &[&str]) -> String {
    let words: Vec<&str> = lines.iter().map(|l| l.trim()).filter(|l| !l.is_empty()).collect();
    words.join(" ").replace('|', "\\|")
}

/// One row of a docs table.
fn row<T: Param>(key: &str, doc: &[&str], default: &T, range: &T::Range) -> String {
    let mut meaning = prose(doc);
    for (name, doc) in T::meanings() {
        meaning += &format!(" `\"{name}\"`: {doc}");
    }
    format!("| `{key}` | {} | {} | {} | {meaning} |\n", T::TYPE, default.show(), T::accepted(range))
}

/// An enum parameter: a doc comment, the name, the hint shown when a value is not one of
/// the names, and each variant with its doc comment and the name it is written as.
macro_rules! choice {
    ($(#[doc = $doc:literal])* $name:ident, hint $hint:literal {
        $($(#[doc = $vdoc:literal])* $variant:ident = $spelt:literal,)*
    }) => {
        $(#[doc = $doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub enum $name {
            $($(#[doc = $vdoc])* $variant,)*
        }

        impl $name {
            /// The names a scene file writes, in declaration order.
            pub const NAMES: [&'static str; [$($spelt),*].len()] = [$($spelt),*];
            const ALL: [Self; [$($spelt),*].len()] = [$(Self::$variant),*];

            pub fn name(self) -> &'static str {
                match self {
                    $(Self::$variant => $spelt,)*
                }
            }
        }

        impl Param for $name {
            type Range = ();
            const TYPE: &'static str = "string";
            fn parse(key: &str, v: &toml::Value, _: &()) -> Result<Self, ParamError> {
                choose(key, v, &Self::NAMES, $hint).map(|i| Self::ALL[i])
            }
            fn accepted(_: &()) -> String {
                Self::NAMES.iter().map(|n| format!("`\"{n}\"`")).collect::<Vec<_>>().join(", ")
            }
            fn show(&self) -> String {
                format!("`\"{}\"`", self.name())
            }
            fn meanings() -> Vec<(&'static str, String)> {
                vec![$(($spelt, prose(&[$($vdoc),*]))),*]
            }
            fn control(&self, _: &()) -> Control {
                Control::Choice { value: self.name(), names: &Self::NAMES }
            }
        }
    };
}

/// `lo..=hi` where a parameter has one, `()` where its type says it all.
macro_rules! range {
    () => {
        ()
    };
    ($range:expr) => {
        $range
    };
}

/// Every parameter table: its doc comment, struct name, `[render.<table>]` name and
/// optionally a check across its keys; then each key with its doc comment (the docs table's
/// meaning), type, default and range. Declaring a table here is all it takes for the
/// scene loader to accept it and for docs/scene-format.md to list it.
macro_rules! params {
    ($(
        $(#[doc = $tdoc:literal])*
        $name:ident $table:literal $(check $check:path)? {
            $($(#[doc = $doc:literal])* $field:ident: $ty:ty = $default:expr $(, $range:expr)?;)*
        }
    )*) => {
        $(
            $(#[doc = $tdoc])*
            #[derive(Debug, Clone, Copy, PartialEq)]
            pub struct $name {
                $($(#[doc = $doc])* pub $field: $ty,)*
            }

            impl Default for $name {
                fn default() -> Self {
                    $name { $($field: $default,)* }
                }
            }

            impl $name {
                pub const KEYS: &'static [&'static str] = &[$(stringify!($field)),*];

                pub fn from_table(t: Option<&toml::Table>) -> Result<Self, ParamError> {
                    let mut p = Self::default();
                    for (key, v) in t.into_iter().flatten() {
                        match key.as_str() {
                            $(stringify!($field) => p.$field = Param::parse(key, v, &range!($($range)?))?,)*
                            _ => return Err(unknown($table, key, Self::KEYS)),
                        }
                    }
                    $($check(&p)?;)?
                    Ok(p)
                }

                pub fn from_settings(r: &RenderSettings) -> Result<Self, ParamError> {
                    Self::from_table(r.params.get($table))
                }
            }
        )*

        /// The parameter tables `[render.<technique>]` there are.
        pub const TABLES: &[&str] = &[$($table),*];

        /// Check the parameter table `[render.<technique>]` if the technique is one of these.
        pub fn check(technique: &str, t: &toml::Table) -> Result<(), ParamError> {
            match technique {
                $($table => $name::from_table(Some(t)).map(|_| ()),)*
                // The scene loader refuses unknown tables before it gets here (`TABLES`).
                _ => unreachable!("render.{technique} is not a technique table"),
            }
        }

        /// `[render.<table>]`'s keys as `settings` have them (defaults where absent), for the
        /// window's controls; `None`: no such table, or it does not parse.
        pub fn controls(table: &str, settings: &RenderSettings) -> Option<Vec<ParamView>> {
            match table {
                $($table => {
                    let p = $name::from_settings(settings).ok()?;
                    Some(vec![$(ParamView {
                        key: stringify!($field),
                        doc: prose(&[$($doc),*]),
                        control: Param::control(&p.$field, &range!($($range)?)),
                    }),*])
                })*
                _ => None,
            }
        }

        /// The markdown table of `[render.<table>]`'s keys (key, type, default, range,
        /// meaning), as docs/scene-format.md holds it.
        pub fn docs_table(table: &str) -> Option<String> {
            let rows: Vec<String> = match table {
                $($table => {
                    let d = $name::default();
                    vec![$(row::<$ty>(stringify!($field), &[$($doc),*], &d.$field, &range!($($range)?))),*]
                })*
                _ => return None,
            };
            Some(format!("| key | type | default | range | meaning |\n|---|---|---|---|---|\n{}", rows.concat()))
        }
    };
}

fn unknown(technique: &str, key: &str, accepted: &[&str]) -> ParamError {
    let mut hint = format!("render.{technique} takes {}", accepted.join(", "));
    if let Some(c) = closest(key, accepted) {
        hint = format!("did you mean `{c}`? {hint}");
    }
    ParamError { key: key.to_string(), message: format!("unknown parameter `{key}` of render.{technique}"), hint }
}

/// The candidate a misspelt `name` most likely meant: the nearest by edit distance, if it is
/// within a third of the name's length (at least 2 edits: `huqin` -> `hu_qin`, `hu_quin` ->
/// `hu_qin`), so that a name unlike every candidate gets no suggestion.
pub fn closest<'a>(name: &str, candidates: &[&'a str]) -> Option<&'a str> {
    let limit = (name.chars().count() / 3).max(2);
    candidates
        .iter()
        .map(|c| (strsim::levenshtein(name, c), *c))
        .filter(|(d, _)| *d <= limit)
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

choice! {
    /// Which surface Wyman 2005 (§3.2) refracts through the second time on a concave object.
    BackSurface, hint "Wyman 2005 §3.2: the furthest surface, or the second (the first back-facing one)" {
        /// The surface furthest from the eye (yellow point of Fig. 2), what the back-face pass
        /// with the depth test reversed keeps (§3.1, §4): shows the geometry users expect on
        /// objects of high depth complexity. The refractor's own, never another's behind it.
        Furthest = "furthest",
        /// The second surface from the eye, "i.e., first backfacing surface" (§3.2, black point
        /// of Fig. 2): the nearest back face; smoother, ignores more distant surfaces. The
        /// refractor's own, also where another refractor lies in front of it.
        Second = "second",
    }
}

choice! {
    /// Which of Wyman 2005's approximations an oracle replaces by the exact tracer's value
    /// (an analysis tool: `prism ablation` measures how much of the error each causes). The
    /// exact values come from tracing T1 from P1 through the reference's geometry
    /// (glsl/reference/trace.glsl), as `render.refraction = "raytrace"` would.
    WymanOracle, hint "an analysis tool: the approximations of Wyman 2005 §3.1-3.2 replaced by the \
                       exact tracer's values" {
        /// The paper's technique.
        None = "none",
        /// §3.1's P2~ = P1 + d~ T1 replaced by T1's exact exit point (and d~ by its distance,
        /// for the absorption); N2 still looked up in the back-normal layer there (§3.2).
        ExitPoint = "exit_point",
        /// §3.2's N2 (the back-normal layer at P2~'s texel, or §3.3's silhouette normal)
        /// replaced by the exact surface normal at T1's exit; P2~ as the paper's.
        ExitNormal = "exit_normal",
        /// Both: the exit point and its normal exact. What remains is the model's own error
        /// (two interfaces, no internal reflection, Fresnel only at P1).
        All = "all",
    }
}

impl WymanOracle {
    /// The ORACLE_* bits of the shader's specialisation constant.
    pub fn bits(self) -> u32 {
        match self {
            WymanOracle::None => 0,
            WymanOracle::ExitPoint => crate::ORACLE_EXIT_POINT,
            WymanOracle::ExitNormal => crate::ORACLE_EXIT_NORMAL,
            WymanOracle::All => crate::ORACLE_EXIT_POINT | crate::ORACLE_EXIT_NORMAL,
        }
    }
}

choice! {
    /// Which of Hu & Qin 2007's approximations an oracle replaces by the exact tracer's value
    /// (an analysis tool, as [`WymanOracle`]).
    HuQinOracle, hint "an analysis tool: the approximations of Hu & Qin 2007 §2.1.2-2.1.4 and \
                       §2.2 replaced by the exact tracer's values" {
        /// The paper's technique.
        None = "none",
        /// §2.1.2-2.1.3's exit (the front/back decision of Fig. 5 and the d_T search of Fig. 9)
        /// replaced by T1's exact exit point, its facing choosing the layer §2.1.4 reads N2
        /// from there.
        ExitPoint = "exit_point",
        /// §2.1.4's N2 (the normal layer at P2's texel) replaced by the exact normal at T1's
        /// exit; P2 as the paper's.
        ExitNormal = "exit_normal",
        /// Both the exit point and its normal exact.
        Exit = "exit",
        /// §2.2's lookup of R (at P1) and T2 (at P2) in the impostor rectangles (Figs. 13,
        /// 16, 17) replaced by the exact hit of the ray against the scene, shown as the
        /// technique shows it: the radiance of TEX_k at that point's texel, in the rectangle
        /// whose TEX_DEPTH_k there is nearest the point's depth (what hides it where every
        /// texture does), OBJ_R itself passed through (its own set does not hold it); the
        /// environment where the ray hits nothing or no texture holds a surface there. No
        /// part of the lookup's search is used.
        Nearby = "nearby",
        /// The exit and the nearby lookup exact. What remains is the model's own error.
        All = "all",
    }
}

impl HuQinOracle {
    /// The ORACLE_* bits of the shader's specialisation constant.
    pub fn bits(self) -> u32 {
        let exit = crate::ORACLE_EXIT_POINT | crate::ORACLE_EXIT_NORMAL;
        match self {
            HuQinOracle::None => 0,
            HuQinOracle::ExitPoint => crate::ORACLE_EXIT_POINT,
            HuQinOracle::ExitNormal => crate::ORACLE_EXIT_NORMAL,
            HuQinOracle::Exit => exit,
            HuQinOracle::Nearby => crate::ORACLE_NEARBY,
            HuQinOracle::All => exit | crate::ORACLE_NEARBY,
        }
    }
}

choice! {
    /// Where a dielectric OBJ_k's refracted ray leaves it inside its impostor texture (Hu & Qin
    /// 2007 §2.2.1 with §2.1's exit search in the rectangle's parallel projection).
    RecursiveExit,
    hint "Hu & Qin 2007 §2.2.1: a dielectric impostor's exit point, by §2.1's whole search \
          (Figs. 5, 7, 9) on its front and back faces, by Fig. 9 on its back faces only (§4), \
          or where its bounding sphere is left" {
        /// OBJ_k's nearest back and front faces (normal and axial depth) are rendered in that
        /// projection (pass `refraction_hu_qin_nearby_back`, once per frame); Fig. 7's binary
        /// search for the dividing pixel p_e along T1's projection (`search_steps` halvings of
        /// the texture's side: OBJ_k lies within its bounding sphere, whose diameter is that
        /// side), Fig. 5's theta_1/theta_2 test with the eye ray V = the projection direction,
        /// then Fig. 9's iterative d_T search on OBJ_k's front or back faces (`max_iterations`,
        /// first step the back faces' thickness at P1, or 1% of d_k on the front faces) and N2
        /// from the matching layer; the bounding sphere where the search finds no face.
        Full = "full",
        /// §4's acceleration, the exit assumed back-facing (Fig. 9 on the back faces only; no
        /// front faces rendered).
        BackFacing = "back_facing",
        /// Where T1 leaves OBJ_k's bounding sphere (O_k, d_k), with its normal; no extra pass
        /// (exact for balls up to their tessellation).
        BoundingSphere = "bounding_sphere",
    }
}

impl RecursiveExit {
    /// Whether the exit search reads OBJ_k's back faces (and front faces with `Full`).
    pub fn uses_layers(self) -> bool {
        self != RecursiveExit::BoundingSphere
    }
}

choice! {
    /// Which conductor Fresnel term the impostor shading uses (Szirmay-Kalos et al. 2005, §3).
    ImpostorFresnel, hint "the paper's n,k approximation (§3) or the exact conductor formula" {
        /// The paper's Schlick-like approximation with n and k, ((n-1)^2 + k^2 + 4n(1-cos)^5) /
        /// ((n+1)^2 + k^2).
        Approximate = "approximate",
        /// The exact formula for a complex index (glsl/include/fresnel.glsl).
        Exact = "exact",
    }
}

choice! {
    /// When a distance impostor is rendered again (Szirmay-Kalos et al. 2005, §6: "this
    /// preparation phase is usually not executed in each frame, only if the object movements
    /// are large enough").
    ImpostorUpdate, hint "render the maps again when objects move, or every frame" {
        /// In the first frame, then when its object moved farther than `regenerate_distance`
        /// from the reference point.
        OnMove = "on_move",
        /// Every frame (the map's full cost shows in every frame's timing).
        EveryFrame = "every_frame",
    }
}

choice! {
    /// Which distance impostors the specular objects of an effect share (Szirmay-Kalos et al.
    /// 2005, §6: "we may generate only a single environment map for all of them, or we may
    /// maintain a separate map for each of them").
    ImpostorMaps, hint "one map for all specular objects of an effect, or one per object (§6)" {
        /// One map per effect around the mean centre of its objects, without any of them.
        Shared = "shared",
        /// One map (and, for refraction, one refractor map) per specular object, centred on
        /// it, holding everything but that object (the other specular objects appear in it,
        /// black as in deferred shading), each regenerated independently when its own object
        /// moves.
        PerObject = "per_object",
    }
}

choice! {
    /// Whether an oracle replaces the result of Szirmay-Kalos et al. 2005's `Hit()` (§2-3: the
    /// guesses d_p and d_l of Eq. 4 refined by Eq. 6) by the exact hit of the same ray against
    /// the scene (glsl/reference/trace.glsl), the impostor's radiance then looked up towards
    /// that exact point (an analysis tool, as [`WymanOracle`]: `prism ablation` measures how
    /// much of the error `Hit()`'s search causes).
    ImpostorOracle, hint "an analysis tool: Hit() of Szirmay-Kalos et al. 2005 §2-3 replaced by the \
                          exact tracer's hit" {
        /// The paper's technique.
        None = "none",
        /// Every `Hit()` in the environment impostor (reflections, §3, and the rays leaving a
        /// refractor, §4) replaced by the exact hit; the refractor map's `Hit()` (§4's second
        /// refraction point) stays the paper's. What remains is the map's own error: its
        /// resolution and its radiance as seen from the reference point.
        Hit = "hit",
    }
}

choice! {
    /// Whether an oracle replaces caustics mapping's receiver estimate (Shah et al. 2007
    /// §III.C, Eq. 1-2: where a grid vertex's refracted or reflected ray meets the receivers,
    /// iterated on the receivers' positions map) by the exact closest hit of the same ray
    /// against the diffuse receivers (glsl/reference/trace.glsl; an analysis tool, as
    /// [`WymanOracle`]: `prism ablation` measures how much of the error the estimate causes).
    CausticsMapOracle, hint "an analysis tool: the receiver estimate of Shah et al. 2007 §III.C \
                             replaced by the exact tracer's hit" {
        /// The paper's technique.
        None = "none",
        /// The receiver hit of every grid vertex's ray (Eq. 1-2, or the appendix's Eq. 4-5
        /// with `newton = "true"`) replaced by the ray's exact closest hit on a diffuse
        /// surface; `iterations` and `newton` then change nothing. The grid, the exit through
        /// the specular object (`exit`), the flux and the splats stay the paper's.
        Receiver = "receiver",
    }
}

choice! {
    /// How caustics mapping estimates where a refracted or reflected ray meets the receivers
    /// (Shah et al. 2007, §III.C-D).
    Newton, hint "Shah et al. 2007: the approximate iteration of §III.C or the appendix's" {
        /// The paper's approximation (§III.C, Eq. 1-2): the next distance is the distance from
        /// the ray origin to the receiver point looked up at the current estimate (one texture
        /// fetch per iteration, no derivative).
        Approximate = "approximate",
        /// The true Newton-Raphson iteration of the appendix (Eq. 4, derivative by the finite
        /// difference of Eq. 5: two lookups per iteration) on the signed distance to the
        /// receiver, falling back to bisection when it oscillates or leaves the bracket
        /// (§III.D).
        True = "true",
    }
}

choice! {
    /// Where caustics mapping's double-surface refraction leaves the object (Shah et al. 2007
    /// §IV: "our algorithm effortlessly accommodates Wyman's image-space double-surface
    /// refraction").
    CausticExit,
    hint "the exit point: Wyman 2005's d_V/d_N interpolation (Shah et al.'s), or prism's march \
          with bisection against the back faces" {
        /// The paper's: Wyman 2005 §3.1, d~ = (theta_t / theta_i) d_V + (1 - theta_t / theta_i)
        /// d_N with d_V the front-to-back distance along the light ray at the texel and d_N
        /// precomputed per vertex along -N; N2 from the back layer at P1 + d~ T1, or
        /// perpendicular to the light's direction outside the silhouette (§3.3).
        Wyman = "wyman",
        /// prism's departure: 16 steps over the objects' bounding diameter bracket the first
        /// point of T1 behind the back faces the light sees, 10 bisections refine it (a root
        /// of the same signed depth function as the receiver estimate's, §III.C).
        March = "march",
    }
}

choice! {
    /// How large each caustics-mapping splat is (Shah et al. 2007 §III.F).
    SplatSize,
    hint "the paper's fixed Gaussian (splat_sigma), or sized by the neighbouring grid vertices' hits" {
        /// The paper's: every splat a Gaussian of `splat_sigma` texels (§III.F).
        Fixed = "fixed",
        /// prism's departure: sigma grows to half the distance, in caustic-map texels,
        /// between the vertex's hit and its grid neighbours' (the beam's local footprint),
        /// never below `splat_sigma` nor above `max_splat_sigma`, so that a diverging beam
        /// stays continuous instead of breaking into dots.
        Footprint = "footprint",
    }
}

choice! {
    /// The flux each caustics-mapping vertex carries (Shah et al. 2007, §III.E).
    Flux,
    hint "each vertex's flux: its texel's solid angle, or Eq. 6's (N.L)/V with V counted by an \
          occlusion query" {
        /// The light's intensity times the grid texel's own solid angle (or irradiance times its
        /// area for a directional light): the flux through the texel, exact for any grid; it
        /// matches the closed-form flux through caustic_sphere's ball within 1%.
        SolidAngle = "solid_angle",
        /// Eq. 6: Phi_i = (N_i . L_i) / V of the flux through the object's visible surface, V
        /// counted by an occlusion query on the front refractor layer (copied into a buffer on
        /// the GPU and read by the splat pass in the same frame). In physical units V cancels
        /// against the visible area it measures, so Eq. 6 differs by its extra N . L (0.58 of
        /// the flux on caustic_sphere, independent of the grid within 1%).
        OcclusionQuery = "occlusion_query",
    }
}

choice! {
    /// What the photon-buffer caustic textures hold (Hu & Qin 2007 §3.2).
    PhotonNormalization,
    hint "irradiance in W/m^2 (comparable with the reference) or the paper's s * count" {
        /// Irradiance in W/m^2: each photon carries its share of the light's flux (intensity
        /// times the photon-buffer pixel's solid angle, or irradiance times its area) times its
        /// Fresnel and Beer-Lambert weights, the filter kernel is divided by its sum (the filter
        /// conserves energy) and the result by a texel's area on the rectangle; receivers turn
        /// it into radiance albedo/pi E. Comparable with the reference, so the default (and
        /// what `prism compare` measures).
        Physical = "physical",
        /// The paper's c(u, v) = s * (filtered photon count), a grey brightness added as
        /// albedo c: s is an arbitrary scale, so the result is not in physical units.
        Paper = "paper",
    }
}

choice! {
    /// Which surface Hu & Qin's nearby lookup (2007 §2.2, glsl/include/nearby.glsl) keeps.
    NearbyLookup, hint "Fig. 13's closest rectangle (the paper's), or the nearest corrected surface over all rectangles" {
        /// Fig. 13: the rectangle hit closest to the ray's origin, corrected by Fig. 16's
        /// steps (prism tries the next rectangle where the final texel is empty).
        Paper = "paper",
        /// prism's departure: every rectangle the ray meets is corrected, with secant steps
        /// that halve where they land on an empty texel, and the nearest corrected surface
        /// along the ray is kept.
        Nearest = "nearest",
    }
}

choice! {
    /// The step of Hu & Qin's d_T iteration (2007 §2.1.3, Fig. 9).
    DTStep, hint "Fig. 9's depth difference (the paper's), or that difference over |T1 . V| (Newton)" {
        /// Fig. 9: Steplength = Flag * (depth - z), a depth difference along the view axis
        /// taken as a distance along T1; it converges linearly where T1 is oblique to V.
        Paper = "paper",
        /// prism's departure: the depth difference divided by |T1 . V| (at least 0.1), the
        /// distance along T1 that closes it for a layer perpendicular to V; fewer iterations
        /// for the same image (glsl/include/hu_qin_exit.glsl gives the measurement). Not the
        /// default: at the default 32 iterations the two differ by less than 1e-4 in FLIP
        /// mean (Newton's lower on both scenes) and by 0.0004 in RMSE (the paper's lower on
        /// bunny_env), at the same cost within the noise (ACCURACY.md, "Fig. 9's d_T step" on
        /// sphere_env and bunny_env).
        Newton = "newton",
    }
}

choice! {
    /// Where Hu & Qin's exit search reads the refractors' front faces (2007 §2.1, Fig. 4's
    /// initial pass: "render normals and depths of the back-facing & front-facing surfaces").
    FrontLayer, hint "\"auto\" (the G-buffer's where every object is a closed refractor) or \"own\" (the paper's pass)" {
        /// The G-buffer's depth and normal where every object of the scene is a dielectric with
        /// a closed outward mesh (src/technique/refraction/refractor_layers.rs
        /// `gbuffer_holds_front_layer`): it holds the nearest front face at every pixel, as the
        /// layer would, so the layers pass draws the back faces only. A front-facing exit's N2
        /// is then the G-buffer's RGBA16F normal instead of the layer's RGBA32F one (N1's
        /// precision): docs/ACCURACY.md ("the front layer") measures what that changes.
        /// Elsewhere, the layer of its own.
        Auto = "auto",
        /// The paper's: the refractors' front faces drawn into a layer of their own.
        Own = "own",
    }
}

choice! {
    /// Whether Hu & Qin's exit search decides the exit's facing first (2007 §2.1.2, Fig. 5 with
    /// Fig. 7's binary search) or assumes a back-facing exit (§4's acceleration).
    BackFacing, hint "\"auto\" (section 4 where every dielectric is a closed object denser than air), true (section 4) or false (section 2.1.2)" {
        /// §4 where every dielectric object of the scene is a closed mesh (not a heightfield)
        /// with an ior of at least 1 in every channel, §2.1.2 otherwise. Light entering a denser
        /// closed object bends towards the normal and "in most cases" (§4) leaves through its
        /// back faces; where it does not, P2 leaves the silhouette and §4 takes the front layer.
        /// docs/ACCURACY.md ("the section 4 acceleration") measures both: on sphere_env (n 1.5)
        /// and bunny_env (n 1.2) the same errors to four digits with §4's shading pass 0.94x and
        /// 0.92x (256^2); on bubble_env (n 0.75, Fig. 2's n_t < n_i, where front-facing exits
        /// are common) §4 raises the RMSE from 0.155 to 0.196; on water_pool (n 1.33, an open
        /// heightfield: the refracted ray has no far side of the water to leave through) from
        /// 0.333 to 0.579 ("Refraction through a water surface").
        Auto = "auto",
        /// §4: assume a back-facing exit.
        True = "true",
        /// §2.1.2: decide the facing by the dividing pixel (the paper's full method).
        False = "false",
    }
}

choice! {
    /// Whether eikonal_view samples its field with the device's trilinear filter.
    HardwareFilter, hint "\"auto\" (where a probe finds the device's filter exact), true or false" {
        /// Where a probe at setup finds that the device's filter interpolates in full
        /// precision (src/technique/eikonal/eikonal_view.rs `filters_in_full_precision`): the
        /// same image as the f32 path to rounding, one fetch instead of eight (lavapipe:
        /// RMS 5.6e-7, the view pass 0.63x; docs/BENCHMARKS.md). Not on a device whose
        /// weights are coarser.
        Auto = "auto",
        /// Always the device's filter, whatever its precision.
        True = "true",
        /// Always eight fetches interpolated in f32.
        False = "false",
    }
}

choice! {
    /// How eikonal_view integrates the ray equation (Ihrke et al. 2007, section 4.1).
    Integrator, hint "Euler of Eqs. 11-12 (Ihrke et al. 2007), the midpoint rule, fourth-order Runge-Kutta \
                      or velocity Verlet" {
        /// Forward Euler, Eqs. 11-12 (the paper's view renderer).
        Euler = "euler",
        /// The explicit midpoint rule of Eqs. 9-10, second order: one field sample per step
        /// besides the step's end sample, which the next step starts from.
        Midpoint = "midpoint",
        /// Classical fourth-order Runge-Kutta of Eqs. 9-10: three field samples per step
        /// besides the end sample.
        Rk4 = "rk4",
        /// Eqs. 9-10 in the parameter tau = integral ds / n, where they become x'' = n grad n,
        /// a right-hand side free of x' (the field sample holds n and grad n), integrated by
        /// velocity Verlet (Störmer-Verlet): second order like the midpoint rule, with no field
        /// sample besides the end sample, the cost of Euler. Each step's tau is `step` over n
        /// where it starts, so that it moves about `step` of arc length, as the others do.
        Verlet = "verlet",
    }
}

choice! {
    /// How the eikonal light simulator advances its particles along the equal-time ray
    /// equation, Eqs. 14-15 (Ihrke et al. 2007, section 5.2.1).
    LightIntegrator, hint "forward Euler of Eqs. 14-15 (Ihrke et al. 2007 §5.2.1), the midpoint rule or fourth-order Runge-Kutta" {
        /// Forward Euler of Eqs. 14-15, x += dt v / n^2, v += dt grad n / n (the paper's
        /// scheme, Eqs. 11-12 in the equal-time parameter): one field fetch per particle.
        Euler = "euler",
        /// The explicit midpoint rule of Eqs. 14-15, second order: two field fetches per
        /// particle.
        Midpoint = "midpoint",
        /// Classical fourth-order Runge-Kutta of Eqs. 14-15: four field fetches per particle.
        Rk4 = "rk4",
    }
}

choice! {
    /// How the eikonal light simulator records each step of a wavefront patch in the
    /// irradiance and direction volumes (Ihrke et al. 2007, section 5.2.2).
    LightVoxelization, hint "prism's additive track-length estimate or the paper's highest-energy ray per voxel (§5.2.2)" {
        /// Every ray's flux x track length / voxel volume, splatted trilinearly and summed
        /// (glsl/eikonal/light_step.glsl): finite at a focus and the voxel's mean there.
        TrackLength = "track_length",
        /// The paper's: the patch's midpoint writes its differential irradiance dE = flux /
        /// area (Eq. 17) and its direction into the voxel holding it, where it is the highest
        /// energy yet ("we limit ourselves to storing only one incoming light direction,
        /// corresponding to the highest energy ray passing a particular voxel").
        HighestEnergy = "highest_energy",
    }
}

choice! {
    /// How the track-length voxelization records a deposit's direction of travel (the vector
    /// irradiance of the direction volume, light_common.glsl `accum`).
    LightDirectionSplat, hint "the deposit's direction splatted trilinearly like its irradiance, or into the voxel holding its centre" {
        /// Trilinearly, over the eight voxels its irradiance goes to: 24 atomic additions
        /// per deposit.
        Trilinear = "trilinear",
        /// Into the voxel holding the deposit's centre, with its weight summed beside it: 4
        /// atomic additions. The direction volume is then the mean direction of the rays
        /// whose deposits were centred in each voxel.
        Nearest = "nearest",
    }
}

choice! {
    /// Which voxels of the irradiance and direction volumes the eikonal light simulator
    /// deposits into (src/technique/eikonal/read_mask.rs).
    LightDeposits, hint "only the voxels that receivers and scattering read, or every voxel the light crosses" {
        /// The voxels near a surface that can receive the light and, in a scattering volume,
        /// the volume's box: everything the renderer looks up, the same values there.
        Read = "read",
        /// Every voxel a patch crosses, as the paper's volumes hold them.
        Everywhere = "everywhere",
    }
}

choice! {
    /// What exit and reflected view rays of the eikonal volume meet besides the environment
    /// (src/technique/eikonal/eikonal_nearby.rs).
    EikonalNearby,
    hint "what rays leaving the volume meet: exact quads (Ihrke et al. 2007 Fig. 7), Hu & Qin \
          2007 impostor rectangles, or the environment only" {
        /// The environment only (section 5.3 as written).
        Off = "off",
        /// Every non-dielectric object through Hu & Qin 2007 §2.2's impostor rectangles around
        /// the box's centre (pass `eikonal_nearby`; their textures carry the same simulated
        /// irradiance; mirrors and conductors in them reflect the environment only).
        Impostor = "impostor",
        /// Ihrke et al. 2007 §6, Fig. 7 ("a ray-plane intersection in the fragment shader"):
        /// diffuse quads and boxes (at most 64 triangles in all) are intersected exactly and
        /// shaded like deferred shading, with the light simulation's irradiance where it
        /// reaches them (the caustic and shadow under the volume); the other non-dielectric
        /// objects through impostor rectangles.
        Exact = "exact",
    }
}

params! {
    /// `[render.wyman]`: Wyman 2005 (src/technique/refraction/refraction_wyman.rs).
    WymanParams "wyman" {
        /// The second interface on concave objects (Wyman 2005 §3.2).
        back_surface: BackSurface = BackSurface::Furthest;
        /// Also write the exit point P2 and direction T2 of every refracting pixel to the debug
        /// targets `refraction_wyman_p2` and `refraction_wyman_t2` (`Renderer::read_target`).
        debug: bool = false;
        /// An analysis tool, not a rendering setting: replace §3.1's exit point and/or §3.2's
        /// exit normal by the exact tracer's (the reference's BVH and spheres, bound only when
        /// this is not `"none"`, so the paper's technique pays nothing for it).
        oracle: WymanOracle = WymanOracle::None;
    }

    /// `[render.hu_qin]`: Hu & Qin 2007 §2 and §4 (src/technique/refraction/refraction_hu_qin.rs).
    HuQinParams "hu_qin" {
        /// Binary-search steps for the dividing pixel p_e (Hu & Qin 2007, Fig. 7; "eight steps
        /// ... are sufficient"): the search interval is 0.75 of the image, so 8 steps resolve
        /// 0.75/256 of it.
        // 2^24 intervals already resolve far below a texel of the largest image.
        search_steps: u32 = 8, 1..=24;
        /// Convergence tolerance of the d_T iteration (Fig. 9): it stops when its step is below
        /// this fraction of the eye's distance to P1, so that it means the same at every scene
        /// scale.
        tolerance: f32 = 1e-4, 1e-7..=0.5;
        /// Upper bound on the d_T iterations (Fig. 9 loops until the tolerance is met).
        max_iterations: u32 = 32, 1..=1024;
        /// The d_T iteration's step (Fig. 9) in the camera view: the paper's depth difference,
        /// or that difference over |T1 . V|, a Newton step (the impostor textures of §2.2.1
        /// keep the paper's).
        d_t_step: DTStep = DTStep::Paper;
        /// Keep the d_T iteration inside the interval where its residual changes sign, halving
        /// the interval where a step would leave it, and stop when it is below `tolerance`
        /// (prism's departure, in the camera view; the impostor textures of §2.2.1 keep the
        /// paper's). Where the layer has no root along T1 (a grazing exit between two texels'
        /// depths, a fold hiding the exit surface), Fig. 9's iteration oscillates until
        /// `max_iterations`; this stops at the layer's jump instead. false: Fig. 9 as printed.
        d_t_bracket: bool = true;
        /// Section 4's acceleration: skip the binary search, assume a back-facing exit, and
        /// decide "front-facing" (the front-facing layer) only when P2 leaves the refractor's
        /// silhouette.
        assume_back_facing: BackFacing = BackFacing::Auto;
        /// Where the exit search reads the refractors' front faces: the G-buffer's where it
        /// holds them (every object a closed refractor), or a layer drawn for them alone.
        front_layer: FrontLayer = FrontLayer::Auto;
        /// Also write P2 and T2 to the debug targets `refraction_hu_qin_p2` and
        /// `refraction_hu_qin_t2`, as for `wyman`.
        debug: bool = false;
        /// An analysis tool, not a rendering setting: replace the exit point, the exit normal
        /// and/or the nearby lookup by the exact tracer's (bound only when this is not
        /// `"none"`, as `render.wyman.oracle`).
        oracle: HuQinOracle = HuQinOracle::None;
        /// §2.2: the reflected ray R (at P1) and the exit ray T2 (at P2) see the scene's other
        /// objects (diffuse, mirrors, conductors, other dielectrics) through impostor
        /// rectangles (Fig. 13; src/technique/refraction/nearby_impostors.rs) before the
        /// environment map; false: the environment only (§2.1 alone). Without another object
        /// there is nothing to stand in for and no `refraction_hu_qin_nearby` pass.
        nearby: bool = true;
        /// Edge in texels of each impostor texture TEX_i (§2.2.1).
        // 2048^2 texels x 16 bytes x MAX_NEARBY_RECTS (8) layers = 512 MiB per rectangle
        // set, a quarter of lavapipe's 2 GiB allocation limit; with several sets the
        // renderer refuses arrays over 1 GiB (src/technique/refraction/nearby_impostors.rs).
        impostor_resolution: u32 = 256, 4..=2048;
        /// Iterations of the lookup correction against TEX_DEPTH_i (§2.2.2, Fig. 16); 0 = the
        /// plain rectangle lookup of Fig. 13 ("two or three iteration steps" suffice, §2.2.2).
        // "using a good initial point ... we can obtain a satisfactory result after two or
        // three iteration steps" (§2.2.2); beyond 64 it only burns time.
        correction_iterations: u32 = 3, 0..=64;
        /// Which rectangle's corrected surface the refraction pass's R and T2 see (§2.2,
        /// glsl/include/nearby.glsl): Fig. 13's closest rectangle, or the nearest corrected
        /// surface over all rectangles (prism's departure; on sphere_nearby at 256² it removes
        /// the dark arc where rays to the back wall's foot met the floor's rectangle first,
        /// and the rim speckle of steps landing on empty texels: tests/nearby.rs,
        /// docs/ACCURACY.md, docs/refraction.md).
        // Default by RMSE against the reference on the bundled scenes (lavapipe, 96², 64 spp,
        // no photons): sphere_nearby 0.0225 paper -> 0.0169 nearest (tests/nearby.rs);
        // two_glass_balls over ball A 0.04971 -> 0.04223, over ball B 0.05121 -> 0.03583
        // (tests/recursion.rs). tests/recursion.rs's environment-lit variants with B a glass
        // cube or torus go the other way over A (0.24519 -> 0.28241, 0.23299 -> 0.25043).
        nearby_lookup: NearbyLookup = NearbyLookup::Nearest;
        /// The same choice for the lookup inside the impostor textures of the recursive levels
        /// (`recursion_depth` >= 1).
        // The paper's by default, by RMSE against the reference (refraction pass "nearest"):
        // on tests/nearby.rs's mirror bunny behind the ball (96², 64 spp, no photons, depth 1,
        // whole image) "nearest" raises it from 0.01559 to 0.01781, and the mean over the
        // pixels depth 1 changes overshoots the reference's (0.0737 against 0.0539); on
        // two_glass_balls (whole image, 96², `prism compare`) it lowers it only from 0.01957
        // to 0.01925 (0.02315 and 0.02316 with the refraction pass "paper").
        recursive_lookup: NearbyLookup = NearbyLookup::Paper;
        /// Stop correcting when the point's depth is within this fraction of d_i (the
        /// rectangle's half side) of the texture's depth, |depth - z| < tolerance x d_i, so that
        /// it means the same at every object size.
        correction_tolerance: f32 = 1e-3, 1e-7..=0.5;
        /// Points P + alpha_j Ray, alpha_j = d_far (j+1)/N, tried as seeds of the correction
        /// (Fig. 17); 1 = start at the rectangle hit P_rect.
        // Each seed is one texture fetch per rectangle per ray.
        seed_samples: u32 = 8, 1..=256;
        /// §2.2.1 recursive reflections and refractions (Fig. 24g): mirrors, conductors and
        /// dielectrics among the nearby objects get impostors whose textures show them
        /// reflecting (and refracting) the environment only (0) or the impostors of the level
        /// below of their own rectangle set (n: `refraction_hu_qin_nearby_r1` ... `_rn`, one
        /// more rendering of every specular texture per level, the diffuse ones being rendered
        /// once at level 0 and copied into the other array of the ping-pong by
        /// `refraction_hu_qin_nearby_copy`; none when no rectangle stands for a specular object,
        /// e.g. one glass ball among diffuse objects).
        // One pass per level (src/technique/refraction/nearby_impostors.rs, MAX_RECURSION).
        recursion_depth: u32 = 1, 0..=3;
        /// §2.2.1 ("we render TEX_k using the above method"): where the refracted ray leaves a
        /// dielectric OBJ_k in its impostor texture, found with §2.1's search in the
        /// rectangle's parallel projection (glsl/include/hu_qin_exit.glsl, shared with the main
        /// pass).
        // Measured (tests/recursion.rs: two balls, a cube, a torus, a cone; docs/scene-format.md):
        // the full search changes at most a few pixels over the back-facing one, and costs
        // the front faces' pass; so §4's acceleration by default.
        recursive_exit: RecursiveExit = RecursiveExit::BackFacing;
    }

    /// `[render.impostor]`: distance impostors (Szirmay-Kalos et al. 2005),
    /// `render.reflection = "impostor"` and `render.refraction = "impostor"`.
    ImpostorParams "impostor" {
        /// Texels per cube face edge (§6: the paper's game uses 256).
        // 4096^2 x 6 x 16 bytes = 1.6 GB, near lavapipe's 2 GiB allocation limit.
        resolution: u32 = 256, 4..=4096;
        /// Refinement steps of `Hit()` after the initial guesses (§2.2; 0 = d_l of Eq. 4 only).
        iterations: u32 = 4, 0..=64;
        /// Store the distance in a separate R32F cube instead of the radiance cube's alpha (§6).
        separate_distance: bool = false;
        /// The conductor Fresnel term (§3).
        fresnel: ImpostorFresnel = ImpostorFresnel::Approximate;
        /// When the maps are rendered (§6).
        update: ImpostorUpdate = ImpostorUpdate::OnMove;
        /// How far an object's centre may move from its map's reference point before the map
        /// is rendered again, in bounding radii of the largest object (scale-free).
        regenerate_distance: f32 = 0.25, 0.0..=1e6;
        /// Which maps the specular objects share (§6). The passes stay the same: the map pass
        /// renders every map that is due, the shading pass draws once per object.
        maps: ImpostorMaps = ImpostorMaps::Shared;
        /// An analysis tool: `"hit"` replaces `Hit()`'s result in the environment impostor by
        /// the exact hit of the same ray (binds the exact tracer; default `"none"`, as
        /// `render.wyman.oracle`).
        oracle: ImpostorOracle = ImpostorOracle::None;
    }

    /// `[render.impostor_lightmap]`: light-map caustics with distance impostors (Szirmay-Kalos
    /// et al. 2005, §5, Fig. 9), `render.caustics = "impostor_lightmap"`.
    ImpostorLightmapParams "impostor_lightmap" {
        /// Texels per side of each light's caustic map (one photon per texel).
        // 2048^2 = 4M photons, each a point sprite: far beyond a CPU device's budget.
        caustic_map_size: u32 = 128, 4..=2048;
        /// Texels per side of each receiver's light map.
        // 4096^2 x 16 bytes = 256 MB per receiver.
        lightmap_size: u32 = 256, 4..=4096;
        /// Support radius of the Gaussian splat in light-map texels (sigma = radius / 2).
        // Below sqrt(2)/2 texels a splat centred at a texel corner covers no texel
        // centre and its power would be lost; the point sprite (2 ceil(radius) + 3
        // texels) must stay within the point-size range.
        filter_radius: f32 = 2.0, 0.75..=16.0;
        /// `Hit()` refinement steps (§2.2) of the photons' rays, in the refractor map and the
        /// uv map.
        iterations: u32 = 4, 0..=64;
        /// Texels per uv cube-map face edge.
        uv_map_size: u32 = 256, 4..=4096;
        /// Draw the photons of a 2 x 2 block of caustic-map texels as one point sprite whose
        /// fragments add their four Gaussians, where their centres lie within 2 ceil(radius)
        /// light-map texels of each other (elsewhere, across a fold of the caustic, one sprite
        /// per photon as the paper draws them): the same light map up to the order of the
        /// float additions, for about a quarter of the sprites, which a CPU device sets up at
        /// a fixed cost each. `false`: one sprite per caustic-map texel (§5).
        block_splats: bool = true;
    }

    /// `[render.caustics_map]`: caustics mapping (Shah et al. 2007,
    /// src/technique/caustics/caustics_map.rs).
    CausticsMapParams "caustics_map" {
        /// Vertices per side of the refractor grid (128 = 128 x 128), which is also the
        /// resolution of the refractor textures rendered from the light (§III.B step 2; §III.F
        /// uses 128 x 128): one face fitted to the specular objects' bounding sphere, or six
        /// cube faces for a point light within 1/0.9 of its radius.
        // 4096^2 vertices per face is already 16M splats per face on a CPU device.
        grid: u32 = 128, 2..=4096;
        /// Iterations of the receiver-intersection estimate (§III.D: "a single iteration is
        /// sufficient", Fig. 6 uses 3); 0 = the receiver straight along the light ray. The exit
        /// point of double-surface refraction is estimated apart (`exit`).
        iterations: u32 = 3, 0..=64;
        /// The intersection estimate (§III.C-D).
        newton: Newton = Newton::Approximate;
        /// Standard deviation of the Gaussian point splats, in caustic-map texels (§III.F); the
        /// point is 2 ceil(3 sigma) + 1 texels wide and its weights sum to 1.
        // Below half a texel a splat no longer covers the texel grid evenly, and the
        // point size (6 sigma + 1) must stay within lavapipe's point-size range.
        splat_sigma: f32 = 1.0, 0.5..=16.0;
        /// Radius in texels of the optional box low-pass filter applied at lookup ((2 filter +
        /// 1)^2 taps; §III.F, "the caustic-map texture can also be low-pass filtered"); 0 = off.
        filter: u32 = 0, 0..=16;
        /// Texels per side of each caustic-map face (and of the receivers' positions map).
        map_size: u32 = 512, 8..=4096;
        /// The flux each vertex carries (§III.E).
        flux: Flux = Flux::SolidAngle;
        /// Where double-surface refraction leaves the object (§IV with Wyman 2005).
        // Measured at 256^2 against the reference (docs/techniques.md, "Shah et al. 2007"):
        // RMSE march 0.256, wyman 0.501 on caustic_sphere; 0.0979 and 0.0981 on caustic_bunny.
        exit: CausticExit = CausticExit::March;
        /// How large each splat is (§III.F).
        // The paper's by default: on caustic_bunny at 256^2 the footprint splats change RMSE
        // from 0.0979 to 0.0978 and cost about three times the splat pass (docs/techniques.md).
        splat: SplatSize = SplatSize::Fixed;
        /// The largest sigma, in caustic-map texels, a footprint splat may take
        /// (`splat = "footprint"`): a grid vertex whose neighbours' hits scatter further (at
        /// a silhouette, or across a fold of the caustic) is clamped to it.
        // The point is 2 ceil(3 sigma) + 1 texels wide: 16 keeps it at 97, within lavapipe's
        // point-size range, and its fill cost bounded.
        max_splat_sigma: f32 = 8.0, 0.5..=16.0;
        /// An analysis tool: `"receiver"` replaces the receiver estimate (§III.C) by the exact
        /// hit of the same ray (binds the exact tracer; default `"none"`, as
        /// `render.wyman.oracle`).
        oracle: CausticsMapOracle = CausticsMapOracle::None;
    }

    /// `[render.photon_buffer]`: photon-buffer caustics (Hu & Qin 2007 §3,
    /// src/technique/caustics/photon_buffer.rs).
    PhotonBufferParams "photon_buffer" {
        /// Pixels per side of the photon buffer rendered from the light, per light face (§3.1;
        /// one photon per pixel).
        // 4096^2 photons is 16M points per rectangle per frame on a CPU device.
        size: u32 = 128, 1..=4096;
        /// Texels per side of each caustic texture TEX_CAUSTICS_i (§3.2). Measured RMSE against
        /// the reference on caustic_sphere at 128^2 (64 spp, 2^22 photons) with size 128 and
        /// k = 2, texture 256 / 512 / 1024: 0.366 / 0.262 / 0.173 (caustics_map: 0.171); the
        /// filter's cost grows with the texels.
        texture_size: u32 = 512, 1..=4096;
        /// The filter's k (§3.2: "k is equal to 2"): c(u, v) sums (2k + 1)^2 texels weighted
        /// sqrt(1 + 2k^2 - (i^2 + j^2)). On caustic_sphere at 128^2 (texture 512) k = 1 / 2 / 3
        /// gave RMSE 0.202 / 0.262 / 0.319 at size 128: the wider filter blurs the ball lens's
        /// focus.
        // (2k+1)^2 taps per texel: k = 16 is already 1089.
        filter_k: u32 = 2, 0..=16;
        /// The filter's s (§3.2: "s is equal to 0.01"), an arbitrary brightness; used by
        /// `normalization = "paper"` only.
        filter_s: f32 = 0.01, 1e-12..=1e12;
        /// What the caustic textures hold (§3.2).
        normalization: PhotonNormalization = PhotonNormalization::Physical;
        /// Iterations of §2.2.2's depth correction (Fig. 16) of each photon's (u, v): from the
        /// ray's hit with RECT_k towards its hit with the receiver itself, against the
        /// receiver's depth seen along O_R O_k (`photon_buffer_receivers`), so that the photon
        /// is counted where deferred shading's parallel projection of the receiver looks it up
        /// (§3.3); 0 = the rectangle hit of §3.1 alone, exact only for receivers lying in
        /// their rectangle's plane.
        // "two or three iteration steps" (§2.2.2), as render.hu_qin.correction_iterations;
        // beyond 64 it only burns time.
        correction_iterations: u32 = 3, 0..=64;
        /// Sum the photons that land in one caustic texel before the filter, and draw one
        /// kernel per texel reached instead of one per photon (§3.2's filter is linear in the
        /// counts, so the texture is the same up to the rounding of the float additions).
        /// Where a lens focuses light many photons share a texel: caustic_sphere's 12 156
        /// photons land in 672 texels (the scatter 9.2 -> 1.5 ms at 512^2 on lavapipe). The
        /// power is summed in 64-bit fixed point, so the same photons give the same texture
        /// to the bit on every run. Needs vertex-shader stores
        /// (`vertexPipelineStoresAndAtomics`); a device without them draws one kernel per
        /// photon, as `false` does, the paper's order of work.
        merge_texels: bool = true;
    }

    /// `[render.eikonal]`: eikonal rendering of a `[volume]` (Ihrke et al. 2007,
    /// src/technique/eikonal/eikonal_view.rs).
    EikonalParams "eikonal" check tile_fits {
        /// Standard deviation of the Gaussian pre-smoothing of the index field in voxels
        /// (section 5.1: "typically 0.5 - 1.0 voxels"); 0 keeps the sharp field.
        // 8 voxels already blur a 64^3 volume to a third of its width.
        sigma: f32 = 0.75, 0.0..=8.0;
        /// How the view rays integrate the ray equation (section 4.1).
        integrator: Integrator = Integrator::Euler;
        /// Arc length per step, in voxels (of the smallest voxel edge).
        // Below 0.01 voxel a 256^3 volume needs more than 10^5 steps per ray.
        step: f32 = 0.5, 0.01..=4.0;
        /// Cross regions where the smoothed index is constant and the material volumes are zero
        /// (the air in the box, the inside of a constant-index object) in straight leaps to
        /// their edge instead of `step`-long steps: there grad n = 0, so Eqs. 9-10 give a
        /// straight ray exactly (a map of voxels, src/technique/eikonal/volume.rs `weak_reach`;
        /// with `weak_gradient`, also where the index changes little). false marches at `step`
        /// everywhere, as the paper does.
        leaps: bool = true;
        /// With `leaps`: where the smoothed index changes by less than this per voxel (|grad n|
        /// times the smallest voxel edge) at every voxel a field sample may read, whole steps
        /// merge into one integrator step as long as that region allows (the tails of a
        /// boundary's smoothing, where a step of `step` bends the ray by almost nothing; Eq. 10
        /// bends it by less than this per voxel travelled; src/technique/eikonal/volume.rs,
        /// `weak_reach`). 0 merges steps only where the index is exactly constant. At 1e-3,
        /// the default, eikonal_sphere's view pass takes 0.77-0.79x the time of 0, with FLIP
        /// within the reference's noise and a lower RMSE (docs/BENCHMARKS.md, docs/ACCURACY.md).
        // Above 0.1 the merged steps would cross the steep middle of a smoothed boundary.
        weak_gradient: f32 = 1e-3, 0.0..=0.1;
        /// Stop a view ray once its transmittance (Eq. 5's T, after extinction and Fresnel
        /// reflection) is below this in every channel it carries: what lies beyond would add at
        /// most this fraction of its radiance. 0 marches every ray to the end, as the paper does.
        // 1 would stop every ray at its first step, before any light reached it.
        min_transmittance: f32 = 1e-4, 0.0..=0.5;
        /// Sample the smoothed index field with the device's trilinear filtering (one
        /// filtered fetch, zero beyond the box by a transparent-black border) instead of eight
        /// fetches interpolated in f32, in the view renderer and in the light simulator. GPUs interpolate with reduced-precision weights (8
        /// fractional bits on many), which perturbs the gradient the rays follow;
        /// docs/BENCHMARKS.md has the time and the image difference. Used where the device
        /// filters RGBA32F linearly and the index has one channel (a dispersive volume's
        /// three slabs would blend into each other); elsewhere the f32 path runs.
        hardware_filtering: HardwareFilter = HardwareFilter::Auto;
        // --- light simulator (section 5.2; src/technique/eikonal/eikonal_light.rs) ---
        /// Run the light simulator (§4.2, §5.2) when the scene has a light: every light's
        /// wavefront (per channel for a per-channel index) is traced through the volume into an
        /// irradiance and a direction volume, used for single scattering and by the
        /// `eikonal_light` pass for diffuse receivers inside the irradiance volume. It runs once
        /// when the renderer is created.
        light: bool = true;
        /// Patches whose flux falls below this fraction of the largest initial patch's flux are
        /// eliminated (section 5.2.3, "patch termination").
        // 1 would eliminate every patch at its first step; 0 keeps them all.
        energy_threshold: f32 = 1e-4, 0.0..=0.99;
        /// Time step of the equal-time ray equation (Eqs. 14-15) in voxels of optical path
        /// (dS/dt = 1, Eq. 23).
        // Above 2 voxels a patch skips voxels between two depositions.
        light_dt: f32 = 0.5, 0.01..=2.0;
        /// How the light simulator integrates Eqs. 14-15 (section 5.2.1), independent of the
        /// view rays' `integrator`: "euler" is the paper's; "midpoint" takes 0.82x RK4's
        /// simulation time at 128^3 with a lower FLIP and a 0.15% higher RMSE (ranked,
        /// docs/ACCURACY.md); RK4, the default, has the lowest RMSE.
        light_integrator: LightIntegrator = LightIntegrator::Rk4;
        /// How each step of a patch is recorded in the irradiance and direction volumes
        /// (section 5.2.2): "track_length", the default, sums every ray's flux x track length
        /// / voxel volume, splatted trilinearly; "highest_energy" is the paper's, one ray per
        /// voxel, the one of highest dE = flux / area (Eq. 17). docs/ACCURACY.md compares them.
        voxelization: LightVoxelization = LightVoxelization::TrackLength;
        /// Steps per track-length deposit of a patch that travels on: 1 deposits every step's
        /// chord; 2 adds every other step's chord together with the next one's, one trilinear
        /// splat per voxel of travel at `light_dt` = 0.5 and half the deposits' atomics:
        /// 0.86-0.90x the simulation's time with the default `direction_splat` (0.74-0.79x
        /// with "trilinear"), images within the reference's noise of every = 1's, straight
        /// light with a ripple of up to 1.6% (docs/BENCHMARKS.md, docs/ACCURACY.md).
        light_deposit_every: u32 = 1, 1..=2;
        /// How a track-length deposit's direction of travel enters the direction volume:
        /// "nearest", the default, the voxel holding its centre with its weight beside it (4
        /// atomic additions, not 24: 0.67-0.72x the simulation's time at equal errors, docs/
        /// BENCHMARKS.md and docs/ACCURACY.md), or "trilinear" like its irradiance, whose
        /// receivers' light is then exactly linear in the lights.
        direction_splat: LightDirectionSplat = LightDirectionSplat::Nearest;
        /// Which voxels the light simulator deposits into: "read", the default, only those
        /// that the renderer looks the light up in (within two voxels of a surface that is
        /// not clear glass, and a scattering volume's box), where they hold the same light as
        /// with "everywhere", which deposits into every voxel the light crosses, as the paper
        /// does. Air and the inside of a clear object are read by nothing; their deposits are
        /// most of the step kernel's atomics (docs/BENCHMARKS.md).
        light_deposits: LightDeposits = LightDeposits::Read;
        /// Fresnel loss in the light transport: a patch crossing a boundary band (the view
        /// renderer's, where the smoothed index crosses a jump) keeps the transmitted share
        /// 1 - rho F of its flux, F the exact Fresnel reflectance for unpolarised light between
        /// the indices at the band's ends and rho the region's reflectance factor: the
        /// factor tau of Eq. 5's T(t) (section 4.1) on the light's side. false, the default,
        /// transmits everything, as the paper's light simulator does (sections 4.2, 5.2 leave
        /// the wavefront's flux to absorption alone). docs/ACCURACY.md compares them.
        light_fresnel: bool = false;
        /// Steps of the patch list between two compactions (the HistoPyramid and the output
        /// generator, section 5.2.3; glsl/eikonal/light_step.glsl): after the first, a patch
        /// steps on only while it is retained, so every patch takes the same steps as with a
        /// compaction after every step (1, the paper's synchronous wavefront), but the list
        /// is rebuilt less often. docs/BENCHMARKS.md has the times.
        // Beyond 64 nearly every patch has stopped long before the compaction.
        light_substeps: u32 = 4, 1..=64;
        /// Straight steps a patch may take after its integrated step in one dispatch of the
        /// step kernel, while each corner stays in a region where the smoothed index is
        /// constant (the brick map of volume.rs `uniform_reach`, or beyond the field's box), where Eqs.
        /// 14-15 move it in a straight line exactly: each is classified and deposited as a step
        /// of its own, so the wavefront is the same to rounding in fewer dispatches
        /// (glsl/eikonal/light_step.glsl). 0: every step integrated, as the paper does. Only
        /// with the track-length voxelization, `light_deposit_every` = 1 and no
        /// `light_fresnel`; otherwise 0. docs/BENCHMARKS.md has the times.
        light_leaps: u32 = 16, 0..=1024;
        /// Capacity of the patch list (one storage-buffer binding; a spill list of the same
        /// size beside it). The initial wavefront is simulated in tiles (`tile_patches`); the
        /// patches a step produces past the list are spilled and continued by a later run (the
        /// steps between two readbacks are as many as the spill list can hold at the growth
        /// observed), and only a run whose spill list overflows too is taken back (rerun with negative
        /// deposits) and split into four, so nothing is dropped unless a tile of a single patch
        /// overflows; that count is reported (`prism render` prints it, bench JSON
        /// `light_simulation.dropped_patches`, `spilled_patches`, `split_tiles`, `runs`).
        // A list of 900 000 patches of 128 bytes is 110 MiB: one storage-buffer
        // binding may span at most 128 MiB (lavapipe's maxStorageBufferRange).
        max_patches: u32 = 1 << 19, 4..=900_000;
        /// Initial patches per tile of the wavefront, at most `max_patches` (an error above
        /// it); 0: max_patches / 8. Tiles run one after the other into the same volumes (the
        /// additive deposits make the result independent of the tiling up to f32 rounding).
        // A tile larger than the list could not even be uploaded.
        tile_patches: u32 = 0, 0..=900_000;
        /// Keep patches whose orientation flipped (they crossed a wavefront singularity, a
        /// focus) instead of discarding them (section 5.2.3; false is the paper). The paper
        /// discards them because flux / area is infinite there; the track-length deposit (flux
        /// x track length / voxel volume, trilinear) stays finite, and the light past a focus
        /// reaches the floor: on eikonal_sphere half of the ball's light crosses the caustic
        /// before the floor (tests/eikonal_light.rs).
        keep_crossed: bool = true;
        /// Simulate only the initial patches whose straight beam from the light comes near
        /// the medium (a voxel whose index differs from air or which absorbs, widened by the
        /// smoothing's reach); the others cross nothing but air, where light travels straight
        /// with E = I / r^2 (point) or E (directional), and their light is added in closed form
        /// (glsl/eikonal/light_resolve.glsl). false simulates every patch, as the paper does.
        skip_air: bool = true;
        /// Add the deposits to the irradiance accumulator with the device's float atomics
        /// (VK_EXT_shader_atomic_float's shaderImageFloat32AtomicAdd) where it has them; false,
        /// or a device without them: a compare-and-swap loop on the f32 bits (core Vulkan).
        /// Both give the same sums up to the order of f32 additions; docs/BENCHMARKS.md has
        /// their times.
        float_atomics: bool = true;
        /// Initial wavefront patches per side (per cube face for a point light inside the box's
        /// bounding sphere); 0: the largest volume resolution. Clamped so that the initial
        /// wavefront has at most 900000 patches (948 per side, 387 per face for six faces).
        light_patches: u32 = 0, 0..=1024;
        /// Metres below the volume's box that the irradiance volume also covers (whole
        /// voxels), so that a floor just under the volume receives the caustic.
        light_below: f32 = 0.0, 0.0..=100.0;
        /// Metres the irradiance volume also covers beside the volume's box along -x, +x, -z
        /// and +z (the receiver area that the volume's refracted light and shadow reach).
        light_side: f32 = 0.0, 0.0..=100.0;
        // Nearby geometry for exit and reflected rays.
        /// What rays leaving the volume (and rays its boundaries reflect) meet before the
        /// environment. The default is the more accurate one measured against the reference:
        /// at 128² (16 spp, 2^20 photons) eikonal_sphere's RMSE is 0.614 off, 0.543 exact,
        /// 0.552 impostor, and eikonal_wine_glass's 0.240, 0.215, 0.213 (the impostor slightly
        /// ahead there; FLIP mean 0.158, 0.160, 0.160). docs/images/eikonal_sphere_nearby.png
        /// and eikonal_wine_glass_nearby.png show off | exact | impostor | reference at 128².
        nearby: EikonalNearby = EikonalNearby::Exact;
        /// Correction iterations of the impostor lookup (Hu & Qin 2007 Fig. 16; 0: the plain
        /// lookup of Fig. 13).
        // As render.hu_qin.correction_iterations: beyond 64 the lookup has converged or cycles.
        nearby_iterations: u32 = 3, 0..=64;
        /// Texels per edge of each impostor texture TEX_i (RGBA32F).
        // As render.hu_qin.impostor_resolution (one RGBA32F layer per object).
        nearby_resolution: u32 = 256, 4..=2048;
    }

    /// `[render.raytrace]`: exact ray tracing with deterministic splitting
    /// (src/technique/raytrace.rs).
    RaytraceParams "raytrace" {
        /// Specular interactions a branch may make (the reference's `max_depth` and its
        /// default).
        // The shader keeps one pending branch per depth in a fixed array.
        max_depth: u32 = 16, 1..=crate::RAYTRACE_MAX_DEPTH as i64;
        /// A branch whose largest throughput channel (with the (n_i/n_t)^2 radiance scaling)
        /// falls below this is dropped; what a dropped branch would have carried out of a
        /// dielectric of index n is at most `cutoff` n^2 of its radiance.
        // Below 1e-6 a concave refractor's branches multiply for no visible change.
        cutoff: f32 = 1e-3, 1e-6..=1.0;
        /// Photons traced each frame for the caustics that the branches' diffuse vertices
        /// gather (the reference's photon kernel, a new set every frame); 0: no caustics.
        /// The default is the reference's photons per sample (2^22 over 64 samples, as in the
        /// window's A/B view), so that a frame's caustic has the noise of one exact sample's.
        // Above 2^20 the photon map outgrows what a frame should hold (64 MiB with its grid);
        // the A/B view offers at most 2^18 per sample.
        photons_per_frame: u32 = 65_536, 0..=1 << 20;
        /// Radius of the photon density estimate in pixel footprints on the receiver (the
        /// pixel's angle times the distance travelled along the branch, over sqrt(cos)), at
        /// most 1% of the scene's radius, as the reference's initial radius. The default is
        /// the reference's: the disk inscribed in the pixel's footprint, whose estimate is the
        /// caustic near the pixel's average that the reference converges to. Larger radii
        /// lower the noise (photons within r grow as r^2) and blur the caustic over r.
        // Below 0.01 footprints a disk holds almost no photon; above 16 it blurs over 32 pixels.
        gather_radius: f32 = 0.5, 0.01..=16.0;
        /// Frames averaged at most into the image shown (the pass `raytrace_accumulate`):
        /// frame n since the last change is blended into the running mean with weight
        /// 1/(n+1), and after this many frames the mean is held. Any change starts it again:
        /// the camera, the window size, a live update of the scene or its parameters, a moved
        /// object or light, the water's animation. What differs between the frames is the
        /// photon batch (a new one every frame), so the mean's caustic has the noise of
        /// `accumulate` times `photons_per_frame` photons; everything else in a frame is a
        /// function of the scene and is its own mean, and without photons nothing is
        /// accumulated. 1: no accumulation, every frame shown as traced. The default, 64,
        /// leaves 1/sqrt(64) = 1/8 of a single frame's noise.
        // Beyond 2^16 frames the f32 running mean's rounding (about 2^-24 of the value per
        // frame, 2^-8 after 2^16 frames) approaches the noise left (2^-8 of a frame's).
        accumulate: u32 = 64, 1..=1 << 16;
    }

    /// `[render.tonemap_adaptive]`: the adaptive tone map of `render.tonemap = "adaptive"`
    /// (Ihrke et al. 2007 §5.3 after Krawczyk, Myszkowski & Seidel 2005;
    /// src/technique/baseline/tonemap.rs).
    TonemapAdaptiveParams "tonemap_adaptive" {
        /// Reinhard et al. 2002's L_white in units of the scaled luminance; `"auto"` (`None`):
        /// the largest scaled luminance of the frame, at least 1 (Reinhard's own choice is the
        /// largest; with 1 the curve is the identity L_d = L for images that never exceed 1).
        // Below 1e-3 almost every pixel maps to white; above 1e6 the curve is L/(1+L).
        white: Option<f32> = None, 1e-3..=1e6;
        /// The key a (Reinhard: 0.18 for an average scene); `"auto"` (`None`): Krawczyk et al.
        /// 2005's a = 1.03 - 2 / (2 + log10(L_a + 1)) (§3.1, Eq. 11).
        // Reinhard's keys run from 0.045 (low key) to 0.72 (high key); 0 would be black.
        key: Option<f32> = None, 1e-3..=4.0;
        /// The delta of the log-average L_avg = exp(mean(log(delta + L_w))), in cd/m^2: keeps
        /// black pixels from sending the average to 0 (Reinhard et al. 2002, Eq. 1).
        // 0 would let one black pixel make L_avg 0 (log 0); above 1e3 cd/m^2 it
        // dominates every luminance a scene is lit with.
        delta: f32 = 1e-4, 1e-12..=1e3;
        /// Time constant of the rods' adaptation in seconds (Krawczyk et al. 2005, Eq. 6: 0.4
        /// s), blended with the cones' by the rods' sensitivity 0.04 / (0.04 + L_a) (Eqs. 7,
        /// 12); 0: instant.
        // 0 s is instant adaptation (allowed); an hour is a frozen state.
        tau_rod: f32 = 0.4, 0.0..=3600.0;
        /// Time constant of the cones' adaptation in seconds (Krawczyk et al. 2005, Eq. 6: 0.1
        /// s).
        tau_cone: f32 = 0.1, 0.0..=3600.0;
        /// cd/m^2 per unit of the scene's radiance: the absolute scale that the key and the
        /// rod/cone blend depend on (1: radiance read as cd/m^2).
        luminance_scale: f32 = 1.0, 1e-6..=1e6;
    }
}

/// A tile of the initial wavefront must fit the patch list (Ihrke et al. 2007 §5.2).
fn tile_fits(p: &EikonalParams) -> Result<(), ParamError> {
    if p.tile_patches > p.max_patches {
        return Err(ParamError {
            key: "tile_patches".into(),
            message: format!(
                "`tile_patches` = {} exceeds `max_patches` = {}: a tile must fit the patch list",
                p.tile_patches, p.max_patches
            ),
            hint: "use at most max_patches / 4 (room for tessellation), or 0 for max_patches / 8".into(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(s: &str) -> toml::Table {
        s.parse().unwrap()
    }

    #[test]
    fn defaults_and_values() {
        assert_eq!(HuQinParams::from_table(None).unwrap(), HuQinParams::default());
        let p = HuQinParams::from_table(Some(&table("search_steps = 4\ntolerance = 0.01\nassume_back_facing = true")))
            .unwrap();
        assert_eq!((p.search_steps, p.tolerance, p.assume_back_facing), (4, 0.01, BackFacing::True));
        for (name, exit) in RecursiveExit::NAMES.iter().zip([
            RecursiveExit::Full,
            RecursiveExit::BackFacing,
            RecursiveExit::BoundingSphere,
        ]) {
            let p = HuQinParams::from_table(Some(&table(&format!("recursive_exit = \"{name}\"")))).unwrap();
            assert_eq!((p.recursive_exit, p.recursive_exit.name()), (exit, *name));
        }
        for (name, lookup) in NearbyLookup::NAMES.iter().zip([NearbyLookup::Paper, NearbyLookup::Nearest]) {
            let t = format!("nearby_lookup = \"{name}\"\nrecursive_lookup = \"{name}\"");
            let p = HuQinParams::from_table(Some(&table(&t))).unwrap();
            assert_eq!((p.nearby_lookup, p.recursive_lookup), (lookup, lookup));
        }
        let w = WymanParams::from_table(Some(&table("back_surface = \"second\""))).unwrap();
        assert_eq!(w.back_surface, BackSurface::Second);
    }

    #[test]
    fn bad_values_name_the_key() {
        for (t, key) in [
            ("search_steps = 0", "search_steps"),
            ("search_steps = 100000", "search_steps"),
            ("tolerance = -1.0", "tolerance"),
            ("max_iterations = 0", "max_iterations"),
            ("steps = 3", "steps"),
            ("impostor_resolution = 1", "impostor_resolution"),
            ("impostor_resolution = 100000", "impostor_resolution"),
            ("correction_iterations = -1", "correction_iterations"),
            ("correction_iterations = 1000", "correction_iterations"),
            ("correction_tolerance = 0", "correction_tolerance"),
            ("correction_tolerance = nan", "correction_tolerance"),
            ("seed_samples = 0", "seed_samples"),
            ("nearby = 3", "nearby"),
            ("recursion_depth = 4", "recursion_depth"),
            ("recursive_exit = \"sphere\"", "recursive_exit"),
            ("recursive_exit = 1", "recursive_exit"),
            ("recursive_exit = \"back_layer\"", "recursive_exit"),
        ] {
            let e = HuQinParams::from_table(Some(&table(t))).unwrap_err();
            assert_eq!(e.key, key, "{t}");
            assert!(e.message.contains(key), "{e}");
        }
        for (t, key) in [
            ("resolution = 2", "resolution"),
            ("iterations = 65", "iterations"),
            ("fresnel = \"schlick\"", "fresnel"),
            ("update = \"never\"", "update"),
            ("regenerate_distance = -1", "regenerate_distance"),
            ("iteration = 3", "iteration"),
            ("maps = \"one\"", "maps"),
            ("maps = 2", "maps"),
        ] {
            let e = ImpostorParams::from_table(Some(&table(t))).unwrap_err();
            assert_eq!(e.key, key, "{t}");
        }
        for (t, key) in [
            ("caustic_map_size = 2", "caustic_map_size"),
            ("lightmap_size = 100000", "lightmap_size"),
            ("filter_radius = 0.1", "filter_radius"),
            ("filter_radius = nan", "filter_radius"),
            ("iterations = -1", "iterations"),
            ("size = 3", "size"),
        ] {
            let e = ImpostorLightmapParams::from_table(Some(&table(t))).unwrap_err();
            assert_eq!(e.key, key, "{t}");
        }
        for (t, key) in [
            ("grid = 1", "grid"),
            ("newton = \"secant\"", "newton"),
            ("splat_sigma = 0.1", "splat_sigma"),
            ("flux = \"area\"", "flux"),
        ] {
            let e = CausticsMapParams::from_table(Some(&table(t))).unwrap_err();
            assert_eq!(e.key, key, "{t}");
        }
        let c = CausticsMapParams::from_table(Some(&table("grid = 64\nnewton = \"true\"\nfilter = 1"))).unwrap();
        assert_eq!((c.grid, c.newton, c.filter), (64, Newton::True, 1));
        // As `--set render.caustics_map.newton=true` gives it: a boolean.
        let c = CausticsMapParams::from_table(Some(&table("newton = true"))).unwrap();
        assert_eq!(c.newton, Newton::True);
        assert!(CausticsMapParams::from_table(Some(&table("newton = false"))).is_err());
        for (t, key) in [
            ("size = 0", "size"),
            ("texture_size = 0", "texture_size"),
            ("filter_k = 17", "filter_k"),
            ("filter_s = 0", "filter_s"),
            ("normalization = \"none\"", "normalization"),
            ("k = 2", "k"),
        ] {
            let e = PhotonBufferParams::from_table(Some(&table(t))).unwrap_err();
            assert_eq!(e.key, key, "{t}");
        }
        let p =
            PhotonBufferParams::from_table(Some(&table("size = 64\nfilter_k = 3\nnormalization = \"paper\""))).unwrap();
        assert_eq!((p.size, p.filter_k, p.normalization), (64, 3, PhotonNormalization::Paper));
        assert_eq!(PhotonBufferParams::from_table(None).unwrap(), PhotonBufferParams::default());
        let e = WymanParams::from_table(Some(&table("back_surface = \"first\""))).unwrap_err();
        assert!(e.message.contains("back_surface"), "{e}");
    }

    /// `text` with the table between each `[render.<table>]`'s markers generated afresh.
    fn splice_docs_tables(text: &str) -> Result<String, String> {
        let mut out = text.to_string();
        for t in TABLES {
            let begin = format!("<!-- BEGIN generated [render.{t}]");
            let end = format!("<!-- END generated [render.{t}] -->");
            let b = out.find(&begin).ok_or(format!("no `{begin}: ... -->` line"))?;
            let body = b + out[b..].find("-->\n").ok_or("a marker without its `-->`")? + 4;
            let e = body + out[body..].find(&end).ok_or(format!("no `{end}` line"))?;
            out.replace_range(body..e, &docs_table(t).expect("a declared table"));
        }
        Ok(out)
    }

    /// docs/scene-format.md holds every table's generated key list between marker comments;
    /// `PRISM_BLESS=1` writes them.
    #[test]
    fn scene_format_docs_list_every_parameter() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene-format.md");
        let text = std::fs::read_to_string(&path).unwrap();
        let fresh = splice_docs_tables(&text).unwrap_or_else(|e| panic!("docs/scene-format.md: {e}"));
        if std::env::var_os("PRISM_BLESS").is_some() {
            std::fs::write(&path, &fresh).unwrap();
        } else {
            assert!(
                fresh == text,
                "docs/scene-format.md's parameter tables are out of date: \
                 PRISM_BLESS=1 cargo test --release --lib scene_format_docs writes them"
            );
        }
    }
}
