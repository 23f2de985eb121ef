//! The baseline passes every technique is measured against and builds on: shadow maps,
//! the G-buffer, deferred shading, the single-interface reflection and refraction (the cost
//! baseline of Wyman 2005, Table 1), and the tone map.
pub mod deferred_shading;
pub mod fullscreen;
pub mod gbuffer;
pub mod shadow_map;
pub mod specular_single;
pub mod tonemap;
