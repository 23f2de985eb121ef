//! Typed, validated parameters of the techniques: the `[render.wyman]`, `[render.hu_qin]`,
//! `[render.impostor]` and `[render.caustics_map]` tables (docs/scene-format.md lists every key with its default).
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

/// Which surface Wyman 2005 (§3.2) refracts through the second time on a concave object.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BackSurface {
    /// The surface furthest from the eye (yellow point of Fig. 2): shows the geometry users
    /// expect on objects of high depth complexity.
    Furthest,
    /// The second surface from the eye, found by depth peeling (black point of Fig. 2):
    /// smoother, ignores more distant surfaces.
    Second,
}

/// `[render.wyman]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WymanParams {
    pub back_surface: BackSurface,
    /// Also write P2 and T2 to the debug targets `refraction_wyman_p2` / `_t2`.
    pub debug: bool,
}

impl Default for WymanParams {
    fn default() -> Self {
        WymanParams { back_surface: BackSurface::Furthest, debug: false }
    }
}

/// `[render.hu_qin]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HuQinParams {
    /// Binary-search steps for the dividing pixel p_e (Hu & Qin 2007, Fig. 7; "eight steps
    /// ... are sufficient").
    pub search_steps: u32,
    /// Convergence tolerance of the d_T iteration (Fig. 9), as a fraction of the eye's
    /// distance to P1, so that it means the same at every scene scale.
    pub tolerance: f32,
    /// Upper bound on the d_T iterations (Fig. 9 loops until the tolerance is met).
    pub max_iterations: u32,
    /// Section 4's acceleration: assume a back-facing exit, and decide "front-facing" only
    /// when P2 leaves the refractor's silhouette (skips the binary search).
    pub assume_back_facing: bool,
    /// Also write P2 and T2 to the debug targets `refraction_hu_qin_p2` / `_t2`.
    pub debug: bool,
    /// §2.2: look R and T2 up in the impostor rectangles of the nearby diffuse objects
    /// (src/technique/refraction/nearby_impostors.rs) before the environment map.
    pub nearby: bool,
    /// Edge of each impostor texture TEX_i in texels (§2.2.1).
    pub impostor_resolution: u32,
    /// Iterations of the lookup correction (§2.2.2, Fig. 16); 0 = the plain lookup of Fig. 13.
    pub correction_iterations: u32,
    /// Stop correcting when |depth - z| < tolerance x d_i (the rectangle's half side), so that
    /// it means the same at every object size.
    pub correction_tolerance: f32,
    /// Points P + alpha_j Ray, 0 < alpha_j <= d_far, tried as seeds of the correction (Fig. 17).
    pub seed_samples: u32,
    /// §2.2.1 recursive reflections: mirrors/conductors in the impostor textures reflect the
    /// environment only (0) or the impostors of the level below (1, 2, 3).
    pub recursion_depth: u32,
    /// The second interface of a dielectric OBJ_k in its impostor texture (`recursive_exit`).
    pub recursive_exit: RecursiveExit,
}

/// Where a dielectric OBJ_k's refracted ray leaves it inside its impostor texture (Hu & Qin
/// 2007 §2.2.1 with §2.1's exit search in the rectangle's parallel projection).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RecursiveExit {
    /// `"full"`: Fig. 7's dividing pixel and Fig. 5's front/back test, then Fig. 9's search on
    /// OBJ_k's front or back faces.
    Full,
    /// `"back_facing"`: §4's acceleration, the exit assumed back-facing (Fig. 9 on the back
    /// faces only).
    BackFacing,
    /// `"bounding_sphere"`: where T1 leaves OBJ_k's bounding sphere.
    BoundingSphere,
}

impl RecursiveExit {
    pub const NAMES: [&'static str; 3] = ["full", "back_facing", "bounding_sphere"];
    pub fn name(self) -> &'static str {
        match self {
            RecursiveExit::Full => "full",
            RecursiveExit::BackFacing => "back_facing",
            RecursiveExit::BoundingSphere => "bounding_sphere",
        }
    }
    /// Whether the exit search reads OBJ_k's back faces (and front faces with `Full`).
    pub fn uses_layers(self) -> bool {
        self != RecursiveExit::BoundingSphere
    }
}

impl Default for HuQinParams {
    fn default() -> Self {
        HuQinParams {
            search_steps: 8,
            tolerance: 1e-4,
            max_iterations: 32,
            assume_back_facing: false,
            debug: false,
            nearby: true,
            impostor_resolution: 256,
            // "using a good initial point ... we can obtain a satisfactory result after two or
            // three iteration steps" (§2.2.2).
            correction_iterations: 3,
            correction_tolerance: 1e-3,
            seed_samples: 8,
            recursion_depth: 1,
            // Measured (tests/recursion.rs: two balls, a cube, a torus, a cone; docs/scene-format.md):
            // the full search changes at most a few pixels over the back-facing one, and costs
            // the front faces' pass; so §4's acceleration by default.
            recursive_exit: RecursiveExit::BackFacing,
        }
    }
}

/// Which conductor Fresnel term the impostor shading uses (Szirmay-Kalos et al. 2005, §3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImpostorFresnel {
    /// The paper's Schlick-like approximation with n and k.
    Approximate,
    /// The exact formula for a complex index (glsl/include/fresnel.glsl).
    Exact,
}

/// When a distance impostor is rendered again (Szirmay-Kalos et al. 2005, §6: "this
/// preparation phase is usually not executed in each frame, only if the object movements
/// are large enough").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImpostorUpdate {
    /// When its object moved farther than `regenerate_distance` from the reference point.
    OnMove,
    /// Every frame (the map's full cost shows in every frame's timing).
    EveryFrame,
}

/// Which distance impostors the specular objects of an effect share (Szirmay-Kalos et al.
/// 2005, §6: "we may generate only a single environment map for all of them, or we may
/// maintain a separate map for each of them").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImpostorMaps {
    /// One map per effect around the mean centre of its objects, without any of them.
    Shared,
    /// One map per specular object, centred on it, holding everything but that object (the
    /// other specular objects appear in it, black as in deferred shading), each regenerated
    /// independently when its own object moves.
    PerObject,
}

/// `[render.impostor]`: distance impostors, `render.reflection = "impostor"` and
/// `render.refraction = "impostor"`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpostorParams {
    /// Edge of each cube face in texels (§6 uses 256).
    pub resolution: u32,
    /// Hit() refinement steps after the initial guesses (§2.2; 0 = d_l of Eq. 4 only).
    pub iterations: u32,
    /// Distance in a separate R32F cube instead of the radiance cube's alpha (§6).
    pub separate_distance: bool,
    pub fresnel: ImpostorFresnel,
    pub update: ImpostorUpdate,
    /// How far an object's centre may move from its map's reference point before the map is
    /// rendered again, as a fraction of the object's bounding radius (scale-free).
    pub regenerate_distance: f32,
    pub maps: ImpostorMaps,
}

impl Default for ImpostorParams {
    fn default() -> Self {
        ImpostorParams {
            resolution: 256,
            iterations: 4,
            separate_distance: false,
            fresnel: ImpostorFresnel::Approximate,
            update: ImpostorUpdate::OnMove,
            regenerate_distance: 0.25,
            maps: ImpostorMaps::Shared,
        }
    }
}

/// `[render.impostor_lightmap]`: light-map caustics with distance impostors (Szirmay-Kalos
/// et al. 2005, §5, Fig. 9), `render.caustics = "impostor_lightmap"`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpostorLightmapParams {
    /// Texels per side of the caustic map rendered from the light (one photon per texel).
    pub caustic_map_size: u32,
    /// Texels per side of each receiver's light map.
    pub lightmap_size: u32,
    /// Support radius of the Gaussian splat in light-map texels (sigma = radius / 2).
    pub filter_radius: f32,
    /// Hit() refinement steps (§2.2) of the photons' rays, in the refractor map and the uv map.
    pub iterations: u32,
    /// Texels per uv cube-map face edge.
    pub uv_map_size: u32,
}

impl Default for ImpostorLightmapParams {
    fn default() -> Self {
        ImpostorLightmapParams {
            caustic_map_size: 128,
            lightmap_size: 256,
            filter_radius: 2.0,
            iterations: 4,
            uv_map_size: 256,
        }
    }
}

impl ImpostorLightmapParams {
    pub const KEYS: &'static [&'static str] =
        &["caustic_map_size", "lightmap_size", "filter_radius", "iterations", "uv_map_size"];

    pub fn from_table(t: Option<&toml::Table>) -> Result<Self, ParamError> {
        let mut p = ImpostorLightmapParams::default();
        for (key, v) in t.into_iter().flatten() {
            match key.as_str() {
                // 2048^2 = 4M photons, each a point sprite: far beyond a CPU device's budget.
                "caustic_map_size" => p.caustic_map_size = integer(key, v, 4, 2048)?,
                // 4096^2 x 16 bytes = 256 MB per receiver.
                "lightmap_size" => p.lightmap_size = integer(key, v, 4, 4096)?,
                // Below sqrt(2)/2 texels a splat centred at a texel corner covers no texel
                // centre and its power would be lost; the point sprite (2 ceil(radius) + 3
                // texels) must stay within the point-size range.
                "filter_radius" => p.filter_radius = number(key, v, 0.75, 16.0)?,
                "iterations" => p.iterations = integer(key, v, 0, 64)?,
                "uv_map_size" => p.uv_map_size = integer(key, v, 4, 4096)?,
                _ => return Err(unknown("impostor_lightmap", key, Self::KEYS)),
            }
        }
        Ok(p)
    }

    pub fn from_settings(r: &RenderSettings) -> Result<Self, ParamError> {
        Self::from_table(r.params.get("impostor_lightmap"))
    }
}

/// How caustics mapping estimates where a refracted or reflected ray meets the receivers
/// (Shah et al. 2007, §III.C-D).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Newton {
    /// The paper's approximation (§III.C, Eq. 1-2): the next distance is the distance from
    /// the ray origin to the receiver point looked up at the current estimate (one texture
    /// fetch per iteration, no derivative).
    Approximate,
    /// The true Newton-Raphson iteration of the appendix (Eq. 4, derivative by the finite
    /// difference of Eq. 5), falling back to bisection when it oscillates (§III.D).
    True,
}

/// The flux each caustics-mapping vertex carries (Shah et al. 2007, §III.E).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flux {
    /// The light's intensity times the grid texel's own solid angle (or irradiance times its
    /// area): the flux through the texel, exact for any grid.
    SolidAngle,
    /// Eq. 6: Phi_i = (N_i . L_i) / V of the flux through the object's visible surface, V
    /// counted by an occlusion query on the refractor pass.
    OcclusionQuery,
}

/// `[render.caustics_map]` (Shah et al. 2007).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CausticsMapParams {
    /// Vertices per side of the refractor grid, which is also the resolution of the
    /// refractor textures rendered from the light (§III.B step 2; §III.F uses 128 x 128).
    pub grid: u32,
    /// Iterations of the intersection estimate (§III.D: "a single iteration is sufficient",
    /// Fig. 6 uses 3).
    pub iterations: u32,
    pub newton: Newton,
    /// Standard deviation of the Gaussian point splats, in caustic-map texels (§III.F).
    pub splat_sigma: f32,
    /// Radius in texels of the optional box low-pass filter applied at lookup (§III.F,
    /// "the caustic-map texture can also be low-pass filtered"); 0 = off.
    pub filter: u32,
    /// Texels per side of each caustic-map face (and of the receivers' positions map).
    pub map_size: u32,
    pub flux: Flux,
}

impl Default for CausticsMapParams {
    fn default() -> Self {
        CausticsMapParams {
            grid: 128,
            iterations: 3,
            newton: Newton::Approximate,
            splat_sigma: 1.0,
            filter: 0,
            map_size: 512,
            flux: Flux::SolidAngle,
        }
    }
}

/// What the photon-buffer caustic textures hold (Hu & Qin 2007 §3.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PhotonNormalization {
    /// Irradiance in W/m^2: each photon carries its share of the light's flux (and its
    /// Fresnel and absorption weights), the filter kernel is divided by its sum, and the
    /// result by a texel's area on the rectangle. Comparable with the reference.
    Physical,
    /// The paper's c(u, v) = s * (filtered photon count), a brightness blended with the
    /// receiver's colour: s is an arbitrary scale, so the result is not in physical units.
    Paper,
}

/// `[render.photon_buffer]`: photon-buffer caustics (Hu & Qin 2007 §3,
/// src/technique/caustics/photon_buffer.rs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhotonBufferParams {
    /// Pixels per side of the photon buffer rendered from the light (§3.1; one photon per
    /// pixel). The issue asks for 128 by default.
    pub size: u32,
    /// Texels per side of each caustic texture TEX_CAUSTICS_i (§3.2).
    pub texture_size: u32,
    /// The filter's k (§3.2: "k is equal to 2").
    pub filter_k: u32,
    /// The filter's s (§3.2: "s is equal to 0.01"); used by `normalization = "paper"` only.
    pub filter_s: f32,
    pub normalization: PhotonNormalization,
}

impl Default for PhotonBufferParams {
    fn default() -> Self {
        PhotonBufferParams {
            size: 128,
            texture_size: 512,
            filter_k: 2,
            filter_s: 0.01,
            normalization: PhotonNormalization::Physical,
        }
    }
}

impl PhotonBufferParams {
    pub const KEYS: &'static [&'static str] = &["size", "texture_size", "filter_k", "filter_s", "normalization"];

    pub fn from_table(t: Option<&toml::Table>) -> Result<Self, ParamError> {
        let mut p = PhotonBufferParams::default();
        for (key, v) in t.into_iter().flatten() {
            match key.as_str() {
                // 4096^2 photons is 16M points per rectangle per frame on a CPU device.
                "size" => p.size = integer(key, v, 1, 4096)?,
                "texture_size" => p.texture_size = integer(key, v, 1, 4096)?,
                // (2k+1)^2 taps per texel: k = 16 is already 1089.
                "filter_k" => p.filter_k = integer(key, v, 0, 16)?,
                "filter_s" => p.filter_s = number(key, v, 1e-12, 1e12)?,
                "normalization" => {
                    p.normalization = match v.as_str() {
                        Some("physical") => PhotonNormalization::Physical,
                        Some("paper") => PhotonNormalization::Paper,
                        _ => {
                            return Err(ParamError {
                                key: key.clone(),
                                message: format!("`normalization` must be \"physical\" or \"paper\", not {v}"),
                                hint: "irradiance in W/m^2 (comparable with the reference) or the paper's s * count"
                                    .into(),
                            })
                        }
                    }
                }
                _ => return Err(unknown("photon_buffer", key, Self::KEYS)),
            }
        }
        Ok(p)
    }

    pub fn from_settings(r: &RenderSettings) -> Result<Self, ParamError> {
        Self::from_table(r.params.get("photon_buffer"))
    }
}

fn unknown(technique: &str, key: &str, accepted: &[&str]) -> ParamError {
    let mut hint = format!("render.{technique} takes {}", accepted.join(", "));
    if let Some(c) = closest(key, accepted) {
        hint = format!("did you mean `{c}`? {hint}");
    }
    ParamError { key: key.to_string(), message: format!("unknown parameter `{key}` of render.{technique}"), hint }
}

/// The parameter tables `[render.<technique>]` there are.
pub const TABLES: &[&str] = &[
    "wyman",
    "hu_qin",
    "caustics_map",
    "photon_buffer",
    "impostor",
    "impostor_lightmap",
    "eikonal",
    "tonemap_adaptive",
    "raytrace",
];

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

fn boolean(key: &str, v: &toml::Value) -> Result<bool, ParamError> {
    v.as_bool().ok_or_else(|| ParamError {
        key: key.to_string(),
        message: format!("`{key}` must be true or false, not {v}"),
        hint: "write a boolean without quotes".into(),
    })
}

fn integer(key: &str, v: &toml::Value, lo: i64, hi: i64) -> Result<u32, ParamError> {
    match v.as_integer() {
        Some(n) if (lo..=hi).contains(&n) => Ok(n as u32),
        _ => Err(ParamError {
            key: key.to_string(),
            message: format!("`{key}` must be an integer from {lo} to {hi}, not {v}"),
            hint: "use a whole number in range".into(),
        }),
    }
}

fn number(key: &str, v: &toml::Value, lo: f64, hi: f64) -> Result<f32, ParamError> {
    match v.as_float().or_else(|| v.as_integer().map(|i| i as f64)) {
        Some(x) if x.is_finite() && x >= lo && x <= hi => Ok(x as f32),
        _ => Err(ParamError {
            key: key.to_string(),
            message: format!("`{key}` must be a number from {lo:e} to {hi:e}, not {v}"),
            hint: "use a finite number in range".into(),
        }),
    }
}

impl WymanParams {
    pub const KEYS: &'static [&'static str] = &["back_surface", "debug"];

    pub fn from_table(t: Option<&toml::Table>) -> Result<Self, ParamError> {
        let mut p = WymanParams::default();
        for (key, v) in t.into_iter().flatten() {
            match key.as_str() {
                "back_surface" => {
                    p.back_surface = match v.as_str() {
                        Some("furthest") => BackSurface::Furthest,
                        Some("second") => BackSurface::Second,
                        _ => {
                            return Err(ParamError {
                                key: key.clone(),
                                message: format!("`back_surface` must be \"furthest\" or \"second\", not {v}"),
                                hint: "Wyman 2005 §3.2: the furthest surface, or the second by depth peeling".into(),
                            })
                        }
                    }
                }
                "debug" => p.debug = boolean(key, v)?,
                _ => return Err(unknown("wyman", key, Self::KEYS)),
            }
        }
        Ok(p)
    }

    pub fn from_settings(r: &RenderSettings) -> Result<Self, ParamError> {
        Self::from_table(r.params.get("wyman"))
    }
}

impl HuQinParams {
    pub const KEYS: &'static [&'static str] = &[
        "search_steps",
        "tolerance",
        "max_iterations",
        "assume_back_facing",
        "debug",
        "nearby",
        "impostor_resolution",
        "correction_iterations",
        "correction_tolerance",
        "seed_samples",
        "recursion_depth",
        "recursive_exit",
    ];

    pub fn from_table(t: Option<&toml::Table>) -> Result<Self, ParamError> {
        let mut p = HuQinParams::default();
        for (key, v) in t.into_iter().flatten() {
            match key.as_str() {
                // 2^24 intervals already resolve far below a texel of the largest image.
                "search_steps" => p.search_steps = integer(key, v, 1, 24)?,
                "tolerance" => p.tolerance = number(key, v, 1e-7, 0.5)?,
                "max_iterations" => p.max_iterations = integer(key, v, 1, 1024)?,
                "assume_back_facing" => p.assume_back_facing = boolean(key, v)?,
                "debug" => p.debug = boolean(key, v)?,
                "nearby" => p.nearby = boolean(key, v)?,
                // 2048^2 texels x 16 bytes x MAX_NEARBY_RECTS (8) layers = 512 MiB per rectangle
                // set, a quarter of lavapipe's 2 GiB allocation limit; with several sets the
                // renderer refuses arrays over 1 GiB (src/technique/refraction/nearby_impostors.rs).
                "impostor_resolution" => p.impostor_resolution = integer(key, v, 4, 2048)?,
                // Fig. 16 converges in "two or three" steps; beyond 64 it only burns time.
                "correction_iterations" => p.correction_iterations = integer(key, v, 0, 64)?,
                "correction_tolerance" => p.correction_tolerance = number(key, v, 1e-7, 0.5)?,
                // Each seed is one texture fetch per rectangle per ray.
                "seed_samples" => p.seed_samples = integer(key, v, 1, 256)?,
                // One pass per level (src/technique/refraction/nearby_impostors.rs, MAX_RECURSION).
                "recursion_depth" => p.recursion_depth = integer(key, v, 0, 3)?,
                "recursive_exit" => {
                    p.recursive_exit =
                        match v.as_str() {
                            Some("full") => RecursiveExit::Full,
                            Some("back_facing") => RecursiveExit::BackFacing,
                            Some("bounding_sphere") => RecursiveExit::BoundingSphere,
                            _ => return Err(ParamError {
                                key: key.clone(),
                                message: format!(
                                    "`recursive_exit` must be \"full\", \"back_facing\" or \"bounding_sphere\", \
                                     not {v}"
                                ),
                                hint:
                                    "Hu & Qin 2007 §2.2.1: a dielectric impostor's exit point, by §2.1's whole search \
                                       (Figs. 5, 7, 9) on its front and back faces, by Fig. 9 on its back faces only \
                                       (§4), or where its bounding sphere is left"
                                        .into(),
                            }),
                        }
                }
                _ => return Err(unknown("hu_qin", key, Self::KEYS)),
            }
        }
        Ok(p)
    }

    pub fn from_settings(r: &RenderSettings) -> Result<Self, ParamError> {
        Self::from_table(r.params.get("hu_qin"))
    }
}

impl ImpostorParams {
    pub const KEYS: &'static [&'static str] =
        &["resolution", "iterations", "separate_distance", "fresnel", "update", "regenerate_distance", "maps"];

    pub fn from_table(t: Option<&toml::Table>) -> Result<Self, ParamError> {
        let mut p = ImpostorParams::default();
        for (key, v) in t.into_iter().flatten() {
            match key.as_str() {
                // 4096^2 x 6 x 16 bytes = 1.6 GB, near lavapipe's 2 GiB allocation limit.
                "resolution" => p.resolution = integer(key, v, 4, 4096)?,
                "iterations" => p.iterations = integer(key, v, 0, 64)?,
                "separate_distance" => p.separate_distance = boolean(key, v)?,
                "fresnel" => {
                    p.fresnel = match v.as_str() {
                        Some("approximate") => ImpostorFresnel::Approximate,
                        Some("exact") => ImpostorFresnel::Exact,
                        _ => {
                            return Err(ParamError {
                                key: key.clone(),
                                message: format!("`fresnel` must be \"approximate\" or \"exact\", not {v}"),
                                hint: "the paper's n,k approximation (§3) or the exact conductor formula".into(),
                            })
                        }
                    }
                }
                "update" => {
                    p.update = match v.as_str() {
                        Some("on_move") => ImpostorUpdate::OnMove,
                        Some("every_frame") => ImpostorUpdate::EveryFrame,
                        _ => {
                            return Err(ParamError {
                                key: key.clone(),
                                message: format!("`update` must be \"on_move\" or \"every_frame\", not {v}"),
                                hint: "render the maps again when objects move, or every frame".into(),
                            })
                        }
                    }
                }
                "regenerate_distance" => p.regenerate_distance = number(key, v, 0.0, 1e6)?,
                "maps" => {
                    p.maps = match v.as_str() {
                        Some("shared") => ImpostorMaps::Shared,
                        Some("per_object") => ImpostorMaps::PerObject,
                        _ => {
                            return Err(ParamError {
                                key: key.clone(),
                                message: format!("`maps` must be \"shared\" or \"per_object\", not {v}"),
                                hint: "one map for all specular objects of an effect, or one per object (§6)".into(),
                            })
                        }
                    }
                }
                _ => return Err(unknown("impostor", key, Self::KEYS)),
            }
        }
        Ok(p)
    }

    pub fn from_settings(r: &RenderSettings) -> Result<Self, ParamError> {
        Self::from_table(r.params.get("impostor"))
    }
}

impl CausticsMapParams {
    pub const KEYS: &'static [&'static str] =
        &["grid", "iterations", "newton", "splat_sigma", "filter", "map_size", "flux"];

    pub fn from_table(t: Option<&toml::Table>) -> Result<Self, ParamError> {
        let mut p = CausticsMapParams::default();
        for (key, v) in t.into_iter().flatten() {
            match key.as_str() {
                // 4096^2 vertices per face is already 16M splats per face on a CPU device.
                "grid" => p.grid = integer(key, v, 2, 4096)?,
                "iterations" => p.iterations = integer(key, v, 0, 64)?,
                "newton" => {
                    // `--set render.caustics_map.newton=true` arrives as the TOML boolean
                    // true: accept it as the value "true" it spells.
                    p.newton = match (v.as_str(), v.as_bool()) {
                        (Some("approximate"), _) => Newton::Approximate,
                        (Some("true"), _) | (None, Some(true)) => Newton::True,
                        _ => {
                            return Err(ParamError {
                                key: key.clone(),
                                message: format!("`newton` must be \"approximate\" or \"true\", not {v}"),
                                hint: "Shah et al. 2007: the approximate iteration of §III.C or the appendix's".into(),
                            })
                        }
                    }
                }
                // Below half a texel a splat no longer covers the texel grid evenly, and the
                // point size (6 sigma + 1) must stay within lavapipe's point-size range.
                "splat_sigma" => p.splat_sigma = number(key, v, 0.5, 16.0)?,
                "filter" => p.filter = integer(key, v, 0, 16)?,
                "map_size" => p.map_size = integer(key, v, 8, 4096)?,
                "flux" => {
                    p.flux =
                        match v.as_str() {
                            Some("solid_angle") => Flux::SolidAngle,
                            Some("occlusion_query") => Flux::OcclusionQuery,
                            _ => return Err(ParamError {
                                key: key.clone(),
                                message: format!("`flux` must be \"solid_angle\" or \"occlusion_query\", not {v}"),
                                hint: "each vertex's flux: its texel's solid angle, or Eq. 6's (N.L)/V with V counted \
                                       by an occlusion query"
                                    .into(),
                            }),
                        }
                }
                _ => return Err(unknown("caustics_map", key, Self::KEYS)),
            }
        }
        Ok(p)
    }

    pub fn from_settings(r: &RenderSettings) -> Result<Self, ParamError> {
        Self::from_table(r.params.get("caustics_map"))
    }
}

/// Check the parameter table `[render.<technique>]` if the technique is one of these.
pub fn check(technique: &str, t: &toml::Table) -> Result<(), ParamError> {
    match technique {
        "wyman" => WymanParams::from_table(Some(t)).map(|_| ()),
        "hu_qin" => HuQinParams::from_table(Some(t)).map(|_| ()),
        "caustics_map" => CausticsMapParams::from_table(Some(t)).map(|_| ()),
        "photon_buffer" => PhotonBufferParams::from_table(Some(t)).map(|_| ()),
        "impostor" => ImpostorParams::from_table(Some(t)).map(|_| ()),
        "impostor_lightmap" => ImpostorLightmapParams::from_table(Some(t)).map(|_| ()),
        "eikonal" => EikonalParams::from_table(Some(t)).map(|_| ()),
        "tonemap_adaptive" => TonemapAdaptiveParams::from_table(Some(t)).map(|_| ()),
        "raytrace" => RaytraceParams::from_table(Some(t)).map(|_| ()),
        // The scene loader refuses unknown tables before it gets here (`TABLES`).
        _ => unreachable!("render.{technique} is not a technique table"),
    }
}

/// `[render.tonemap_adaptive]`: the adaptive tone map of `render.tonemap = "adaptive"`
/// (Ihrke et al. 2007 §5.3 after Krawczyk, Myszkowski & Seidel 2005; src/technique/baseline/tonemap.rs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TonemapAdaptiveParams {
    /// Reinhard et al. 2002's L_white in units of the scaled luminance; `None` ("auto"):
    /// the largest scaled luminance of the frame, at least 1 (Reinhard's own choice is the
    /// largest; with 1 the curve is the identity for images that never exceed 1).
    pub white: Option<f32>,
    /// The key a; `None` ("auto"): Krawczyk et al. 2005's a = 1.03 - 2 / (2 + log10(L_a + 1))
    /// (§3.1, Eq. 11).
    pub key: Option<f32>,
    /// The delta of the log-average L_avg = exp(mean(log(delta + L_w))), in cd/m^2: keeps
    /// black pixels from sending the average to 0 (Reinhard et al. 2002, Eq. 1).
    pub delta: f32,
    /// Time constants of the rods and the cones in seconds (Krawczyk et al. 2005, Eq. 6: 0.4 s
    /// and 0.1 s), blended by the rods' sensitivity 0.04 / (0.04 + L_a) (Eqs. 7, 12).
    pub tau_rod: f32,
    pub tau_cone: f32,
    /// cd/m^2 per unit of the scene's radiance: the absolute scale that the key and the
    /// rod/cone blend depend on (1: radiance read as cd/m^2).
    pub luminance_scale: f32,
}

impl Default for TonemapAdaptiveParams {
    fn default() -> Self {
        TonemapAdaptiveParams { white: None, key: None, delta: 1e-4, tau_rod: 0.4, tau_cone: 0.1, luminance_scale: 1.0 }
    }
}

impl TonemapAdaptiveParams {
    pub const KEYS: &'static [&'static str] = &["white", "key", "delta", "tau_rod", "tau_cone", "luminance_scale"];

    pub fn from_table(t: Option<&toml::Table>) -> Result<Self, ParamError> {
        let mut p = TonemapAdaptiveParams::default();
        // "auto" or a number in range.
        let auto_or = |key: &str, v: &toml::Value, lo: f64, hi: f64| -> Result<Option<f32>, ParamError> {
            if v.as_str() == Some("auto") {
                return Ok(None);
            }
            number(key, v, lo, hi).map(Some).map_err(|e| ParamError {
                message: format!("`{key}` must be \"auto\" or a number from {lo:e} to {hi:e}, not {v}"),
                ..e
            })
        };
        for (key, v) in t.into_iter().flatten() {
            match key.as_str() {
                // Below 1e-3 almost every pixel maps to white; above 1e6 the curve is L/(1+L).
                "white" => p.white = auto_or(key, v, 1e-3, 1e6)?,
                // Reinhard's keys run from 0.045 (low key) to 0.72 (high key); 0 would be black.
                "key" => p.key = auto_or(key, v, 1e-3, 4.0)?,
                // 0 would let one black pixel make L_avg 0 (log 0); above 1e3 cd/m^2 it
                // dominates every luminance a scene is lit with.
                "delta" => p.delta = number(key, v, 1e-12, 1e3)?,
                // 0 s is instant adaptation (allowed); an hour is a frozen state.
                "tau_rod" => p.tau_rod = number(key, v, 0.0, 3600.0)?,
                "tau_cone" => p.tau_cone = number(key, v, 0.0, 3600.0)?,
                "luminance_scale" => p.luminance_scale = number(key, v, 1e-6, 1e6)?,
                _ => return Err(unknown("tonemap_adaptive", key, Self::KEYS)),
            }
        }
        Ok(p)
    }

    pub fn from_settings(r: &RenderSettings) -> Result<Self, ParamError> {
        Self::from_table(r.params.get("tonemap_adaptive"))
    }
}

/// `[render.raytrace]`: exact ray tracing with deterministic splitting
/// (src/technique/raytrace.rs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RaytraceParams {
    /// Specular interactions a branch may make (the reference's `max_depth`, its default).
    pub max_depth: u32,
    /// Throughput below which a branch is dropped (its largest channel).
    pub cutoff: f32,
}

impl Default for RaytraceParams {
    fn default() -> Self {
        RaytraceParams { max_depth: 16, cutoff: 1e-3 }
    }
}

impl RaytraceParams {
    pub const KEYS: &'static [&'static str] = &["max_depth", "cutoff"];

    pub fn from_table(t: Option<&toml::Table>) -> Result<Self, ParamError> {
        let mut p = RaytraceParams::default();
        for (key, v) in t.into_iter().flatten() {
            match key.as_str() {
                // The shader keeps one pending branch per depth in a fixed array.
                "max_depth" => p.max_depth = integer(key, v, 1, crate::RAYTRACE_MAX_DEPTH as i64)?,
                // Below 1e-6 a concave refractor's branches multiply for no visible change.
                "cutoff" => p.cutoff = number(key, v, 1e-6, 1.0)?,
                _ => return Err(unknown("raytrace", key, Self::KEYS)),
            }
        }
        Ok(p)
    }

    pub fn from_settings(r: &RenderSettings) -> Result<Self, ParamError> {
        Self::from_table(r.params.get("raytrace"))
    }
}

/// How eikonal_view integrates the ray equation (Ihrke et al. 2007, section 4.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Integrator {
    /// Forward Euler, Eqs. 11-12 (the paper's view renderer).
    Euler,
    /// Classical fourth-order Runge-Kutta of Eqs. 9-10.
    Rk4,
}

// What exit and reflected view rays meet besides the environment.
/// `render.eikonal.nearby` (src/technique/eikonal/eikonal_nearby.rs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EikonalNearby {
    /// The environment only (section 5.3 as written).
    Off,
    /// Hu & Qin 2007 §2.2 impostor rectangles around the volume for every nearby object.
    Impostor,
    /// Ihrke et al. 2007 §6, Fig. 7: an exact ray/quad intersection for quad receivers (the
    /// other nearby objects through impostor rectangles).
    Exact,
}

/// `[render.eikonal]`: eikonal rendering of a `[volume]` (src/technique/eikonal/eikonal_view.rs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EikonalParams {
    /// Standard deviation of the Gaussian pre-smoothing in voxels (section 5.1: "typically
    /// 0.5 - 1.0 voxels"); 0 keeps the sharp field.
    pub sigma: f32,
    pub integrator: Integrator,
    /// Arc length per step, in voxels (of the smallest voxel edge).
    pub step: f32,
    // --- light simulator (section 5.2; src/technique/eikonal/eikonal_light.rs) ---
    /// Run the wavefront light simulation when the scene has a light (`light`).
    pub light: bool,
    /// Patches whose flux falls below this fraction of an initial patch's flux are
    /// eliminated (section 5.2.3, "patch termination").
    pub energy_threshold: f32,
    /// Time step of Eqs. 14-15 in voxels of optical path (dS/dt = 1, Eq. 23).
    pub light_dt: f32,
    /// Capacity of the patch list (one storage-buffer binding); a tile of the initial
    /// wavefront whose tessellation outgrows it is taken back and split into four.
    pub max_patches: u32,
    /// Initial patches per tile of the wavefront (0: max_patches / 8), simulated one tile
    /// after the other into the same volumes.
    pub tile_patches: u32,
    /// Keep patches whose orientation flipped (they crossed a wavefront singularity, a
    /// focus) instead of discarding them (section 5.2.3; false is the paper). The paper
    /// discards them because flux / area is infinite there; the track-length deposit stays
    /// finite, and the light past a focus reaches the floor: on eikonal_sphere half of the
    /// ball's light crosses the caustic before the floor (tests/eikonal_light.rs).
    pub keep_crossed: bool,
    /// Initial wavefront patches per side (0: the largest volume resolution).
    pub light_patches: u32,
    /// Metres below the volume's box that the irradiance volume also covers, so a floor
    /// just under the volume receives the caustic.
    pub light_below: f32,
    /// Metres the irradiance volume also covers beside the volume's box along x and z (the
    /// receiver area that the volume's refracted light and shadow reach).
    pub light_side: f32,
    // Nearby geometry for exit and reflected rays.
    pub nearby: EikonalNearby,
    /// Fig. 16 correction iterations of the impostor lookup (0: the plain lookup of Fig. 13).
    pub nearby_iterations: u32,
    /// Edge of each impostor texture TEX_i in texels.
    pub nearby_resolution: u32,
}

impl Default for EikonalParams {
    fn default() -> Self {
        EikonalParams {
            sigma: 0.75,
            integrator: Integrator::Euler,
            step: 0.5,
            light: true,
            energy_threshold: 1e-4,
            light_dt: 0.5,
            max_patches: 1 << 19,
            tile_patches: 0,
            keep_crossed: true,
            light_patches: 0,
            light_below: 0.0,
            light_side: 0.0,
            nearby: EikonalNearby::Exact,
            nearby_iterations: 3,
            nearby_resolution: 256,
        }
    }
}

impl EikonalParams {
    pub const KEYS: &'static [&'static str] = &[
        "sigma",
        "integrator",
        "step",
        "light",
        "energy_threshold",
        "light_dt",
        "max_patches",
        "tile_patches",
        "keep_crossed",
        "light_patches",
        "light_below",
        "light_side",
        "nearby",
        "nearby_iterations",
        "nearby_resolution",
    ];

    pub fn from_table(t: Option<&toml::Table>) -> Result<Self, ParamError> {
        let mut p = EikonalParams::default();
        for (key, v) in t.into_iter().flatten() {
            match key.as_str() {
                // 8 voxels already blur a 64^3 volume to a third of its width.
                "sigma" => p.sigma = number(key, v, 0.0, 8.0)?,
                "integrator" => {
                    p.integrator = match v.as_str() {
                        Some("euler") => Integrator::Euler,
                        Some("rk4") => Integrator::Rk4,
                        _ => {
                            return Err(ParamError {
                                key: key.clone(),
                                message: format!("`integrator` must be \"euler\" or \"rk4\", not {v}"),
                                hint: "Euler of Eqs. 11-12 (Ihrke et al. 2007) or fourth-order Runge-Kutta".into(),
                            })
                        }
                    }
                }
                // Below 0.01 voxel a 256^3 volume needs more than 10^5 steps per ray.
                "step" => p.step = number(key, v, 0.01, 4.0)?,
                "light" => p.light = boolean(key, v)?,
                // 1 would eliminate every patch at its first step; 0 keeps them all.
                "energy_threshold" => p.energy_threshold = number(key, v, 0.0, 0.99)?,
                // Above 2 voxels a patch skips voxels between two depositions.
                "light_dt" => p.light_dt = number(key, v, 0.01, 2.0)?,
                // A list of 900 000 patches of 144 bytes is 124 MiB: one storage-buffer
                // binding may span at most 128 MiB (lavapipe's maxStorageBufferRange).
                "max_patches" => p.max_patches = integer(key, v, 4, 900_000)?,
                // A tile larger than the list could not even be uploaded.
                "tile_patches" => p.tile_patches = integer(key, v, 0, 900_000)?,
                "keep_crossed" => p.keep_crossed = boolean(key, v)?,
                "light_patches" => p.light_patches = integer(key, v, 0, 1024)?,
                "light_below" => p.light_below = number(key, v, 0.0, 100.0)?,
                "light_side" => p.light_side = number(key, v, 0.0, 100.0)?,
                "nearby" => {
                    p.nearby = match v.as_str() {
                        Some("exact") => EikonalNearby::Exact,
                        Some("impostor") => EikonalNearby::Impostor,
                        Some("off") => EikonalNearby::Off,
                        _ => {
                            return Err(ParamError {
                                key: key.clone(),
                                message: format!("`nearby` must be \"exact\", \"impostor\" or \"off\", not {v}"),
                                hint: "what rays leaving the volume meet: exact quads (Ihrke et al. 2007 Fig. 7), \
                                       Hu & Qin 2007 impostor rectangles, or the environment only"
                                    .into(),
                            })
                        }
                    }
                }
                // As render.hu_qin.correction_iterations: beyond 64 the lookup has converged or cycles.
                "nearby_iterations" => p.nearby_iterations = integer(key, v, 0, 64)?,
                // As render.hu_qin.impostor_resolution (one RGBA32F layer per object).
                "nearby_resolution" => p.nearby_resolution = integer(key, v, 4, 2048)?,
                _ => return Err(unknown("eikonal", key, Self::KEYS)),
            }
        }
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
        Ok(p)
    }

    pub fn from_settings(r: &RenderSettings) -> Result<Self, ParamError> {
        Self::from_table(r.params.get("eikonal"))
    }
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
        assert_eq!((p.search_steps, p.tolerance, p.assume_back_facing), (4, 0.01, true));
        for (name, exit) in RecursiveExit::NAMES.iter().zip([
            RecursiveExit::Full,
            RecursiveExit::BackFacing,
            RecursiveExit::BoundingSphere,
        ]) {
            let p = HuQinParams::from_table(Some(&table(&format!("recursive_exit = \"{name}\"")))).unwrap();
            assert_eq!((p.recursive_exit, p.recursive_exit.name()), (exit, *name));
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
}
