//! Distance impostors (Szirmay-Kalos et al. 2005): localized reflection and refraction (§3,
//! §4) and light-map caustics (§5).
pub mod distance_impostor;
pub mod impostor_lightmap;
