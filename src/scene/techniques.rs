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
}

impl Default for HuQinParams {
    fn default() -> Self {
        HuQinParams { search_steps: 8, tolerance: 1e-4, max_iterations: 32, assume_back_facing: false, debug: false }
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
        }
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
        }
    }
}

fn unknown(technique: &str, key: &str, accepted: &[&str]) -> ParamError {
    ParamError {
        key: key.to_string(),
        message: format!("unknown parameter `{key}` of render.{technique}"),
        hint: format!("render.{technique} takes {}", accepted.join(", ")),
    }
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
    pub const KEYS: &'static [&'static str] =
        &["search_steps", "tolerance", "max_iterations", "assume_back_facing", "debug"];

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
        &["resolution", "iterations", "separate_distance", "fresnel", "update", "regenerate_distance"];

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
    pub const KEYS: &'static [&'static str] = &["grid", "iterations", "newton", "splat_sigma", "filter", "map_size"];

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
        "impostor" => ImpostorParams::from_table(Some(t)).map(|_| ()),
        "eikonal" => EikonalParams::from_table(Some(t)).map(|_| ()),
        _ => Ok(()),
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

/// `[render.eikonal]`: eikonal rendering of a `[volume]` (src/passes/eikonal.rs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EikonalParams {
    /// Standard deviation of the Gaussian pre-smoothing in voxels (section 5.1: "typically
    /// 0.5 - 1.0 voxels"); 0 keeps the sharp field.
    pub sigma: f32,
    pub integrator: Integrator,
    /// Arc length per step, in voxels (of the smallest voxel edge).
    pub step: f32,
    // --- light simulator (section 5.2; src/passes/eikonal_light.rs) ---
    /// Run the wavefront light simulation when the scene has a light (`light`).
    pub light: bool,
    /// Patches whose flux falls below this fraction of an initial patch's flux are
    /// eliminated (section 5.2.3, "patch termination").
    pub energy_threshold: f32,
    /// Time step of Eqs. 14-15 in voxels of optical path (dS/dt = 1, Eq. 23).
    pub light_dt: f32,
    /// Capacity of the patch list; tessellation beyond it drops the last outputs (counted).
    pub max_patches: u32,
    /// Initial wavefront patches per side (0: the largest volume resolution).
    pub light_patches: u32,
    /// Metres below the volume's box that the irradiance volume also covers, so a floor
    /// just under the volume receives the caustic (issue 7, item 6).
    pub light_below: f32,
    /// Metres the irradiance volume also covers beside the volume's box along x and z (the
    /// receiver area that the volume's refracted light and shadow reach).
    pub light_side: f32,
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
            light_patches: 0,
            light_below: 0.0,
            light_side: 0.0,
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
        "light_patches",
        "light_below",
        "light_side",
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
                "light_patches" => p.light_patches = integer(key, v, 0, 1024)?,
                "light_below" => p.light_below = number(key, v, 0.0, 100.0)?,
                "light_side" => p.light_side = number(key, v, 0.0, 100.0)?,
                _ => return Err(unknown("eikonal", key, Self::KEYS)),
            }
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
        ] {
            let e = ImpostorParams::from_table(Some(&table(t))).unwrap_err();
            assert_eq!(e.key, key, "{t}");
        }
        for (t, key) in [("grid = 1", "grid"), ("newton = \"secant\"", "newton"), ("splat_sigma = 0.1", "splat_sigma")]
        {
            let e = CausticsMapParams::from_table(Some(&table(t))).unwrap_err();
            assert_eq!(e.key, key, "{t}");
        }
        let c = CausticsMapParams::from_table(Some(&table("grid = 64\nnewton = \"true\"\nfilter = 1"))).unwrap();
        assert_eq!((c.grid, c.newton, c.filter), (64, Newton::True, 1));
        // As `--set render.caustics_map.newton=true` gives it: a boolean.
        let c = CausticsMapParams::from_table(Some(&table("newton = true"))).unwrap();
        assert_eq!(c.newton, Newton::True);
        assert!(CausticsMapParams::from_table(Some(&table("newton = false"))).is_err());
        let e = WymanParams::from_table(Some(&table("back_surface = \"first\""))).unwrap_err();
        assert!(e.message.contains("back_surface"), "{e}");
    }
}
