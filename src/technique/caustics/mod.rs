//! Image-space caustics: caustics mapping (Shah et al. 2007) and Hu & Qin 2007 §3's photon
//! buffer.
pub mod caustics_map;
pub mod photon_buffer;
