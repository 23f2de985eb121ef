//! Eikonal rendering of inhomogeneous refractive media (Ihrke et al. 2007): the volume and
//! its view rays, the adaptive wavefront light simulation with its HistoPyramid, and the
//! impostors of the objects around the volume.
pub mod eikonal_light;
pub mod eikonal_nearby;
pub mod eikonal_view;
pub mod histopyramid;
pub mod read_mask;
pub mod volume;
