//! Image-space refraction through two interfaces: Wyman 2005 and Hu & Qin 2007 (with §2.2's
//! impostors of the nearby geometry), and the refractor layers they share; and through one
//! interface onto nearby receivers: a water surface (Shah et al. 2007's scene).
pub mod nearby_impostors;
pub mod oracle;
pub mod refraction_hu_qin;
pub mod refraction_water;
pub mod refraction_wyman;
pub mod refractor_layers;
pub mod wyman_distance;
