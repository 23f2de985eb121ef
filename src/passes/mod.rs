//! One file per technique (../shared/DESIGN.md, rule 10). Each pass owns its pipelines and
//! render pass, declares its reads and writes to the frame graph and records its commands.
//! None of them touches raw Vulkan or records a barrier.
pub mod caustics_map;
pub mod deferred_shading;
pub mod distance_impostor;
pub mod eikonal;
pub mod eikonal_light;
pub mod eikonal_nearby;
pub mod fullscreen;
pub mod gbuffer;
pub mod histopyramid;
pub mod impostor_lightmap;
pub mod nearby_impostors;
pub mod photon_buffer;
pub mod refraction_hu_qin;
pub mod refraction_wyman;
pub mod refractor_layers;
pub mod shadow_map;
pub mod specular_single;
pub mod tonemap;
pub mod wyman_distance;
