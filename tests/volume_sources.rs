//! Volume sources and the view renderer's materials (Ihrke et al. 2007, sections 5.1 and
//! 5.3; src/scene/volume_sources.rs, glsl/eikonal/view.frag): the CPU rasterization of
//! meshes, implicit shapes and lathes against analytic answers, the region override rule,
//! and on the GPU Fresnel reflection, emission, RGB extinction and dispersion against
//! closed forms, the three volume-source scenes and their extremes, and the scene checks.
mod common;

use std::path::PathBuf;

use prism::scene::volume_sources::{mesh_coverage, VolumeFields};
use prism::scene::{self, Mesh, Scene};

/// A scene with only a volume (`volume` is the TOML of `[volume]` and its regions).
fn volume_scene(volume: &str, extra: &str, overrides: &[&str]) -> Result<Scene, String> {
    let text = format!(
        "[camera]\nposition = [0, 0, 4]\ntarget = [0, 0, 0]\nvfov_deg = 40\nwidth = 32\nheight = 32\n\
         {extra}\n{volume}\n"
    );
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    scene::load_str(&text, &dir().join("scene.toml"), &o).map_err(|e| e.to_string())
}

fn fields(volume: &str) -> VolumeFields {
    volume_scene(volume, "", &[]).unwrap().volume.unwrap().fields()
}

thread_local! {
    /// The running test's scratch directory, removed when its thread ends.
    static SCRATCH: common::ScratchDir = common::ScratchDir::new("prism_volume_sources");
}

/// The running test's scratch directory for generated OBJ and EXR files.
fn dir() -> PathBuf {
    SCRATCH.with(|d| d.path().to_path_buf())
}

/// A UV sphere of `stacks` x `slices` as OBJ text (closed: poles are single vertices).
fn sphere_obj(radius: f32, stacks: u32, slices: u32) -> String {
    use std::f32::consts::PI;
    let mut s = String::new();
    s += &format!("v 0 {radius} 0\n");
    for i in 1..stacks {
        let t = PI * i as f32 / stacks as f32;
        for j in 0..slices {
            let p = 2.0 * PI * j as f32 / slices as f32;
            s += &format!("v {} {} {}\n", radius * t.sin() * p.cos(), radius * t.cos(), radius * t.sin() * p.sin());
        }
    }
    s += &format!("v 0 {} 0\n", -radius);
    let ring = |i: u32, j: u32| 2 + (i - 1) * slices + (j % slices); // 1-based OBJ indices
    let bottom = 2 + (stacks - 1) * slices;
    for j in 0..slices {
        s += &format!("f 1 {} {}\n", ring(1, j + 1), ring(1, j));
        for i in 1..stacks - 1 {
            let (a, b, c, d) = (ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j));
            s += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
        }
        s += &format!("f {bottom} {} {}\n", ring(stacks - 1, j), ring(stacks - 1, j + 1));
    }
    s
}

fn write(name: &str, text: &str) -> PathBuf {
    let p = dir().join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const BOX: &str = "[volume]\nbounds = { min = [-1, -1, -1], max = [1, 1, 1] }\n";

#[test]
fn a_voxelized_sphere_mesh_matches_the_analytic_sphere() {
    if !common::in_own_process() {
        return;
    }
    let obj = write("sphere.obj", &sphere_obj(0.7, 96, 192));
    let res = "resolution = [48, 48, 48]\n";
    let mesh =
        fields(&format!("{BOX}{res}[[volume.region]]\nshape = \"mesh\"\nfile = \"{}\"\nn = 1.5\n", obj.display()));
    let sphere = fields(&format!("{BOX}{res}[[volume.region]]\nshape = \"sphere\"\nradius = 0.7\nn = 1.5\n"));
    let (m, s) = (&mesh.coverage[0], &sphere.coverage[0]);
    let inside = |c: &[f32]| c.iter().filter(|&&c| c >= 0.5).count();
    let surface = s.iter().filter(|&&c| c > 0.0 && c < 1.0).count();
    let differ = m.iter().zip(s).filter(|(a, b)| (**a >= 0.5) != (**b >= 0.5)).count();
    let off_surface = m.iter().zip(s).filter(|(a, b)| (**b == 0.0 || **b == 1.0) && (**a - **b).abs() > 0.5).count();
    eprintln!(
        "sphere r 0.7 at 48^3: mesh {} voxels inside, analytic {}, {differ} differ, {surface} surface voxels",
        inside(m),
        inside(s)
    );
    // Only voxels the surface passes through may disagree.
    assert_eq!(off_surface, 0, "voxels away from the surface disagree");
    assert!(differ <= surface, "{differ} voxels differ, more than the {surface} surface voxels");
    // The volumes agree to the tessellation's deficit (the 96 x 192 UV sphere holds 0.05 % less) plus
    // the coverage ramp's discretization (under 0.5 % at 48^3).
    let (vm, vs) = (m.iter().sum::<f32>(), s.iter().sum::<f32>());
    let analytic = 4.0 / 3.0 * std::f32::consts::PI * 0.7f32.powi(3) / (2.0f32 / 48.0).powi(3);
    eprintln!("volume in voxels: mesh {vm:.1}, sdf {vs:.1}, analytic {analytic:.1}");
    assert!((vm / analytic - 1.0).abs() < 0.005, "mesh volume {vm} vs analytic {analytic}");
    assert!((vs / analytic - 1.0).abs() < 0.005, "sdf volume {vs} vs analytic {analytic}");
}

/// A unit cube whose face diagonals and edges lie exactly on sub-rows of the scanline grid:
/// the top-left rule counts each crossing once, so the coverage is exact.
#[test]
fn scanline_voxelization_is_exact_on_shared_edges() {
    if !common::in_own_process() {
        return;
    }
    let mut m = Mesh::default();
    let c = |x: f32, y: f32, z: f32| glam::Vec3::new(x, y, z);
    m.positions = vec![
        c(-0.5, -0.5, -0.5),
        c(0.5, -0.5, -0.5),
        c(0.5, 0.5, -0.5),
        c(-0.5, 0.5, -0.5),
        c(-0.5, -0.5, 0.5),
        c(0.5, -0.5, 0.5),
        c(0.5, 0.5, 0.5),
        c(-0.5, 0.5, 0.5),
    ];
    m.indices = vec![
        0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 3, 7, 6, 3, 6, 2, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5,
    ];
    // Voxels of 1/4: sub-rows at y, z = -0.9375 + k/8 never hit the faces, but the
    // diagonal y = z of the +-x faces is crossed by the sub-rows with j = k.
    for (lo, hi, res) in [(-1.0f32, 1.0f32, 8u32), (-0.5 - 1.0 / 16.0, 0.5 + 3.0 / 16.0, 13)] {
        let (cov, open) = mesh_coverage(&m, glam::Vec3::splat(lo), glam::Vec3::splat(hi), [res; 3]);
        assert_eq!(open, 0, "a closed cube reported open");
        let voxel = (hi - lo) / res as f32;
        let sum: f32 = cov.iter().sum();
        // Exact along x (interval overlap); along y and z the 2 x 2 sub-rows sample the
        // cube's extent as (sub-rows inside) x voxel / 2.
        let rows = (0..2 * res).filter(|&j| (lo + (j as f32 + 0.5) * 0.5 * voxel).abs() < 0.5).count() as f32;
        let expected = (rows * 0.5 * voxel).powi(2) / voxel.powi(3);
        assert!((sum - expected).abs() < 1e-4 * expected, "cube volume {sum} voxels, expected {expected}");
        assert!(cov.iter().all(|&c| (0.0..=1.0).contains(&c)));
    }
    // Remove one triangle: the mesh is open and the rays through the hole prove it.
    m.indices.truncate(33);
    let (_, open) = mesh_coverage(&m, glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0), [8; 3]);
    assert!(open > 0);
}

#[test]
fn a_lathe_of_constant_radius_is_a_cylinder() {
    if !common::in_own_process() {
        return;
    }
    let res = "resolution = [40, 40, 40]\n";
    let lathe = fields(&format!(
        "{BOX}{res}[[volume.region]]\nshape = \"lathe\"\ncenter = [0.1, 0, 0]\nprofile = [[0.55, -0.4], [0.55, 0.5]]\nn = 1.5\n"
    ));
    let cyl = fields(&format!(
        "{BOX}{res}[[volume.region]]\nshape = \"cylinder\"\ncenter = [0.1, -0.4, 0]\nradius = 0.55\nheight = 0.9\nn = 1.5\n"
    ));
    let worst = lathe.coverage[0].iter().zip(&cyl.coverage[0]).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    assert!(worst < 1e-5, "lathe and cylinder coverage differ by {worst}");
    assert!(lathe.coverage[0].iter().filter(|&&c| c == 1.0).count() > 1000, "the cylinder is empty");
    let worst = lathe.index[0].iter().zip(&cyl.index[0]).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    assert!(worst < 1e-5, "lathe and cylinder index differ by {worst}");
    // A different radius is a different solid: the comparison can fail.
    let wider = fields(&format!(
        "{BOX}{res}[[volume.region]]\nshape = \"lathe\"\ncenter = [0.1, 0, 0]\nprofile = [[0.6, -0.4], [0.6, 0.5]]\nn = 1.5\n"
    ));
    let worst = wider.coverage[0].iter().zip(&cyl.coverage[0]).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    assert!(worst > 0.5, "a wider lathe should differ from the cylinder");
}

#[test]
fn later_regions_override_earlier_ones() {
    if !common::in_own_process() {
        return;
    }
    let a = "[[volume.region]]\nshape = \"box\"\ncenter = [-0.25, 0, 0]\nsize = [1, 1, 1]\nn = 1.5\nsigma_a = [1, 2, 3]\nemission = 0.5\n";
    let b = "[[volume.region]]\nshape = \"box\"\ncenter = [0.25, 0, 0]\nsize = [1, 1, 1]\nn = [1.3, 1.4, 1.6]\nsigma_s = 4\nhg_g = 0.5\n";
    let res = "resolution = [16, 16, 16]\n";
    let ab = fields(&format!("{BOX}{res}{a}{b}"));
    let ba = fields(&format!("{BOX}{res}{b}{a}"));
    // Voxel (8, 8, 8) (centre (0.0625, 0.0625, 0.0625)) is deep inside both boxes.
    let v = 8 + 16 * (8 + 16 * 8);
    let n = |f: &VolumeFields| [f.index[0][v] + 1.0, f.index[1][v] + 1.0, f.index[2][v] + 1.0];
    assert_eq!(n(&ab), [1.3, 1.4, 1.6], "b given last wins");
    assert_eq!(n(&ba), [1.5, 1.5, 1.5], "a given last wins");
    assert!(ab.dispersive && ba.dispersive);
    assert_eq!(ab.extinction[v], [4.0, 4.0, 4.0, 0.5]);
    assert_eq!(ab.albedo[v][..3], [1.0, 1.0, 1.0]);
    assert_eq!(ab.emission[v][..3], [0.0, 0.0, 0.0]);
    assert_eq!(ba.extinction[v], [1.0, 2.0, 3.0, 0.0]);
    assert_eq!(ba.albedo[v][..3], [0.0, 0.0, 0.0]);
    assert_eq!(ba.emission[v][..3], [0.5, 0.5, 0.5]);
    // Voxel (2, 8, 8) (x = -0.6875) only in a; (13, 8, 8) (x = 0.6875) only in b.
    let (va, vb) = (2 + 16 * (8 + 16 * 8), 13 + 16 * (8 + 16 * 8));
    assert_eq!(ab.index[0][va] + 1.0, 1.5);
    assert_eq!(ab.index[2][vb] + 1.0, 1.6);
    // The boundary indicator marks the index jumps along the row y = z = 0.0625: a's face at
    // x = -0.75 (voxel 2, centre -0.6875, the first covered), b's at x = 0.75 (voxel 13) and
    // b's face x = -0.25 inside a (voxel 6: 1.5 -> [1.3, 1.4, 1.6]); a's face x = 0.25 is
    // hidden inside b (voxel 9), and the air and the interiors are not boundaries.
    let boundary = |f: &VolumeFields, i: usize| f.emission[i + 16 * (8 + 16 * 8)][3];
    let marked: Vec<usize> = (0..16).filter(|&i| boundary(&ab, i) == 1.0).collect();
    assert_eq!(marked, [2, 6, 13], "a then b");
    // b then a: a's faces x = -0.75 (voxel 2) and x = 0.25 (voxel 9, inside b), b's x = 0.75.
    let marked: Vec<usize> = (0..16).filter(|&i| boundary(&ba, i) == 1.0).collect();
    assert_eq!(marked, [2, 9, 13], "b then a");
    // One index everywhere: not dispersive, and a region of n = 1 is no boundary.
    let smoke = fields(&format!("{BOX}{res}[[volume.region]]\nshape = \"box\"\nsize = [1, 1, 1]\nsigma_s = 0.2\n"));
    assert!(!smoke.dispersive);
    assert!(smoke.emission.iter().all(|e| e[3] == 0.0));
}

#[test]
fn the_implicit_shapes_have_their_volumes() {
    if !common::in_own_process() {
        return;
    }
    use std::f32::consts::PI;
    let res = "resolution = [40, 40, 40]\n";
    let voxel = (2.0f32 / 40.0).powi(3);
    let cases = [
        ("shape = \"box\"\nsize = [1.2, 0.8, 1.0]", 1.2 * 0.8 * 1.0),
        ("shape = \"sphere\"\ncenter = [0.1, 0, 0]\nradius = 0.6", 4.0 / 3.0 * PI * 0.216),
        ("shape = \"cylinder\"\nradius = 0.5\nheight = 1.2\ncenter = [0, -0.6, 0]", PI * 0.25 * 1.2),
        // A rounded box: the box minus its edges and corners' rounding.
        (
            "shape = \"rounded_box\"\nsize = [1.2, 1.2, 1.2]\nradius = 0.3",
            1.2f32.powi(3) - (8.0 - 4.0 / 3.0 * PI) * 0.027 - 3.0 * (4.0 - PI) * 0.09 * 0.6,
        ),
        ("shape = \"sphere\"\nradius = 0.3\ntransform = { scale = 2 }", 4.0 / 3.0 * PI * 0.216),
    ];
    for (shape, volume) in cases {
        let f = fields(&format!("{BOX}{res}[[volume.region]]\n{shape}\nn = 1.2\n"));
        let v: f32 = f.coverage[0].iter().sum::<f32>() * voxel;
        eprintln!("{shape:?}: {v:.4} m^3, analytic {volume:.4}");
        assert!((v / volume - 1.0).abs() < 0.01, "{shape}: {v} vs {volume}");
    }
}

// ---- the view renderer (GPU) ----

fn no_nan(name: &str, hdr: &[f32]) {
    let bad = hdr.iter().filter(|v| !v.is_finite()).count();
    assert_eq!(bad, 0, "{name}: {bad} non-finite values");
}

/// An environment of constant radiance `l` and a volume scene rendered at 32^2.
fn render_volume(ctx: &std::sync::Arc<prism::gpu::GpuContext>, volume: &str, env: f32, o: &[&str]) -> common::Rendered {
    let env = format!("[environment]\ntype = \"constant\"\nradiance = {env}\n");
    let s = volume_scene(volume, &env, o).unwrap();
    let r = common::render_on(ctx, &s);
    no_nan(volume, &r.hdr);
    r
}

/// Fresnel at normal incidence (Eq. 2's delta rho L_r): an opaque glass slab (sigma_a 1000 /m:
/// nothing crosses its 0.4 m) in a uniform environment of radiance 1 shows exactly the
/// reflected fraction ((n - 1) / (n + 1))^2 at the image centre, whose ray meets the slab
/// at normal incidence. Tolerance 0.002 (5 % of F at n = 1.5): the normal is the summed
/// gradient, exact on the axis; the measured error is below 1e-4.
#[test]
fn fresnel_reflection_at_normal_incidence() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    for n in [1.5f32, 2.4, 1.05] {
        let slab = format!(
            "{BOX}resolution = [48, 48, 48]\n[[volume.region]]\nshape = \"box\"\nsize = [1.6, 1.6, 0.4]\nn = {n}\nsigma_a = 1000\n"
        );
        let r = render_volume(&ctx, &slab, 1.0, &[]);
        let l = r.radiance(16, 16);
        let f = ((n - 1.0) / (n + 1.0)).powi(2);
        eprintln!("n = {n}: centre {l:?}, ((n-1)/(n+1))^2 = {f:.5}");
        for c in l {
            assert!((c - f).abs() < 0.002, "n = {n}: reflected {c}, expected {f}");
        }
        // reflectance = 0 switches the reflection off: the test can fail.
        let off = render_volume(&ctx, &slab.replace("sigma_a = 1000", "sigma_a = 1000\nreflectance = 0"), 1.0, &[]);
        assert!(off.radiance(16, 16)[0] < 1e-4, "{:?}", off.radiance(16, 16));
    }
}

/// The march reads each voxel's band where the CPU put it: the slab of
/// `fresnel_reflection_at_normal_incidence`, off the box's centre on every axis, in a volume of
/// a different resolution on each axis, reflects the same closed-form F at the image centre.
/// A band read at transposed or wrongly strided voxels lies elsewhere along the centre ray,
/// and the reflection vanishes (checked by swapping y and z in view.frag's `band_factor`: 0).
/// Tolerance that of `fresnel_reflection_at_normal_incidence`.
#[test]
fn the_fresnel_band_follows_the_voxel_layout() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let n = 1.5f32;
    let slab = format!(
        "{BOX}resolution = [40, 48, 56]\n[[volume.region]]\nshape = \"box\"\ncenter = [0.3, -0.2, 0.35]\n\
         size = [1.0, 1.0, 0.3]\nn = {n}\nsigma_a = 1000\n"
    );
    let l = render_volume(&ctx, &slab, 1.0, &[]).radiance(16, 16);
    let f = ((n - 1.0) / (n + 1.0)).powi(2);
    for c in l {
        assert!((c - f).abs() < 0.002, "reflected {c}, expected {f}");
    }
}

/// Emission (Eq. 1 with L_e of Eq. 2): a non-absorbing, non-refracting box of emission E
/// and depth 0.5 m along the view adds E x 0.5 to the environment (0 here); with
/// extinction sigma the closed form is E (1 - e^{-sigma d}) / sigma. Tolerance 1 %: the
/// one-voxel coverage ramps at the two faces are symmetric, so the path length is exact
/// up to the trilinear interpolation of the 16-bit coefficients (measured < 0.2 %).
#[test]
fn emission_adds_emission_times_path_length() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let emitter = "[[volume.region]]\nshape = \"box\"\nsize = [1.2, 1.2, 0.5]\nemission = [0.5, 1, 2]\n";
    let r = render_volume(&ctx, &format!("{BOX}resolution = [40, 40, 40]\n{emitter}"), 0.0, &[]);
    let l = r.radiance(16, 16);
    eprintln!("emissive box: centre {l:?}, expected [0.25, 0.5, 1.0]");
    for (c, e) in l.iter().zip([0.25, 0.5, 1.0]) {
        assert!((c - e).abs() < 0.01 * e, "{l:?}");
    }
    // With absorption sigma = [0, 2, 8]: E (1 - e^{-sigma d}) / sigma, d = 0.5.
    let absorbing = format!("{BOX}resolution = [40, 40, 40]\n{emitter}sigma_a = [0, 2, 8]\n");
    let l = render_volume(&ctx, &absorbing, 0.0, &[]).radiance(16, 16);
    let expected = [0.25, 1.0 * (1.0 - (-1.0f32).exp()) / 2.0, 2.0 * (1.0 - (-4.0f32).exp()) / 8.0];
    eprintln!("emissive absorbing box: centre {l:?}, expected {expected:?}");
    for (c, e) in l.iter().zip(expected) {
        assert!((c - e).abs() < 0.02 * e, "{l:?} vs {expected:?}");
    }
}

/// RGB extinction (Eq. 5 with sigma_r = sigma_a + sigma_s): a box of sigma_a = [0.5, 1, 0]
/// and sigma_s = [0, 1, 2] and depth 0.5 m (n = 1) transmits e^{-0.5 (sigma_a + sigma_s)}
/// of a uniform environment of radiance 1 (in-scattering is the light branch's).
#[test]
fn rgb_extinction_is_absorption_plus_scattering() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let b = "[[volume.region]]\nshape = \"box\"\nsize = [1.2, 1.2, 0.5]\nsigma_a = [0.5, 1, 0]\nsigma_s = [0, 1, 2]\nhg_g = 0.5\n";
    let l = render_volume(&ctx, &format!("{BOX}resolution = [40, 40, 40]\n{b}"), 1.0, &[]).radiance(16, 16);
    let expected = [(-0.25f32).exp(), (-1.0f32).exp(), (-1.0f32).exp()];
    eprintln!("extinction box: centre {l:?}, expected {expected:?}");
    for (c, e) in l.iter().zip(expected) {
        assert!((c - e).abs() < 0.01 * e, "{l:?} vs {expected:?}");
    }
}

/// A glass prism with a per-channel index: the glass box (n per channel) is cut by a later
/// region of air (n = 1) whose face is tilted by 20 degrees about y. A ray along -z enters the
/// glass face z = 0.8 at normal incidence and leaves through the tilted face at incidence 20
/// degrees, into the direction asin(n sin 20) - 20 degrees off -z towards +x (Snell, per
/// channel). The environment is a latitude-longitude image of radiance (phi + 100) in every
/// channel at longitude phi (degrees), so each channel of a pixel reads the longitude its
/// own ray left in. Fresnel is off (reflectance 0) so that only the transmitted rays count.
fn prism_scene(n: [f32; 3], tilt: f32, overrides: &[&str]) -> Scene {
    let volume = format!(
        "[volume]\nbounds = {{ min = [-1, -1, -1], max = [1, 1, 1] }}\nresolution = [64, 64, 64]\n\
         [[volume.region]]\nshape = \"box\"\nsize = [1.6, 1.6, 1.2]\ncenter = [0, 0, 0.2]\nn = [{}, {}, {}]\nreflectance = 0\n\
         [[volume.region]]\nshape = \"box\"\nsize = [4, 4, 4]\ncenter = [0, 0, -2]\n\
         transform = {{ rotation = [0, {tilt}, 0] }}\nn = 1\nreflectance = 0\n",
        n[0], n[1], n[2]
    );
    let (w, h) = (720u32, 360u32);
    let mut img = image::Rgb32FImage::new(w, h);
    for (i, _, p) in img.enumerate_pixels_mut() {
        let lon = (i as f32 + 0.5) / w as f32 * 360.0 - 180.0;
        *p = image::Rgb([lon + 100.0; 3]);
    }
    // One file per call: tests run in parallel threads of one process, and one test must not
    // read the image while another rewrites it.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let env = dir().join(format!("longitude_{call}.exr"));
    img.save(&env).unwrap();
    let extra = format!("[environment]\ntype = \"image\"\nfile = \"{}\"\n", env.display());
    // A narrow view from far away: the rays are parallel to -z.
    let mut o = vec!["camera.position=[0, 0, 40]", "camera.vfov_deg=1"];
    o.extend_from_slice(overrides);
    volume_scene(&volume, &extra, &o).unwrap()
}

const PRISM_N: [f32; 3] = [1.45, 1.5, 1.6];

/// Dispersion (section 5.3): each channel marches through its own index field, so red,
/// green and blue leave the prism in different directions, in the order of their indices
/// (a non-dispersive prism of n = 1.5 gives one direction in all three). On the CPU the
/// rasterized interface is the tilted plane within a quarter voxel.
#[test]
fn dispersion_separates_the_channels() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let tilt = 20.0f32;
    let s = prism_scene(PRISM_N, tilt, &[]);
    let f = s.volume.as_ref().unwrap().fields();
    assert!(f.dispersive);
    for i in [24u32, 28, 32, 36, 40] {
        let col = |k: u32| f.index[1][(i + 64 * (32 + 64 * k)) as usize] + 1.0;
        let k = (1..64).find(|&k| col(k - 1) <= 1.25 && col(k) > 1.25).unwrap();
        let t = (1.25 - col(k - 1)) / (col(k) - col(k - 1));
        let z = -1.0 + (k as f32 - 0.5 + t) * 2.0 / 64.0;
        let x = -1.0 + (i as f32 + 0.5) * 2.0 / 64.0;
        let plane = -tilt.to_radians().tan() * x;
        assert!((z - plane).abs() < 0.25 * 2.0 / 64.0, "x = {x}: interface at z = {z}, plane at {plane}");
    }
    let lon = |s: &Scene| -> Vec<f32> {
        let r = common::render_on(&ctx, s);
        no_nan("prism", &r.hdr);
        r.radiance(16, 16).iter().map(|v| v - 100.0).collect()
    };
    let rk4 = ["render.eikonal.integrator=\"rk4\""];
    let l = lon(&prism_scene(PRISM_N, tilt, &rk4));
    eprintln!("dispersive prism: exit longitudes {l:?} degrees");
    assert!(l[0] > 5.0 && l[1] - l[0] > 0.5 && l[2] - l[1] > 1.0, "red < green < blue deviation expected: {l:?}");
    let one = lon(&prism_scene([1.5; 3], tilt, &rk4));
    eprintln!("non-dispersive prism: exit longitudes {one:?} degrees");
    assert!((one[0] - one[2]).abs() < 1e-3, "{one:?}");
}

/// Snell per channel: across the centre row of pixels every channel's exit direction is
/// Snell's at both faces (at the centre asin(n sin 20) - 20 degrees: 9.73, 10.87, 13.18 for
/// n = 1.45, 1.5, 1.6). The ray
/// equation through a smoothed plane interface conserves the tangential part of n d, which
/// is Snell's law whatever the smoothing; what remains is the integration and interpolation
/// error of the one-voxel ramp at 64^3. Tolerance 0.3 degree, a tenth of the red-blue
/// separation (3.4 degrees), and a lateral error below one voxel (2/64 m) over the 1.2 m from
/// the face to the box. (A previous version leaked the default reflectance 1 into bands that
/// ask for 0, and the environment's seam, reflected, moved these pixels by up to 15 degrees.)
#[test]
fn dispersion_matches_snell() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let r = common::render_on(&ctx, &prism_scene(PRISM_N, 20.0, &["render.eikonal.integrator=\"rk4\""]));
    let t = 20.0f64.to_radians();
    for i in (0..32).step_by(4) {
        // Pixel i's camera ray leaves at phi_c off -z (towards +x for i > 16; vfov 1 degree);
        // the front face refracts it to asin(sin phi_c / n), the tilted face (its inward
        // normal at longitude -20 degrees) to asin(n sin(phi_g + 20)) from that normal.
        let phi_c = ((2.0 * (i as f64 + 0.5) / 32.0 - 1.0) * 0.5f64.to_radians().tan()).atan();
        let snell: Vec<f32> = PRISM_N
            .iter()
            .map(|&n| {
                let n = n as f64;
                let phi_g = (phi_c.sin() / n).asin();
                ((n * (phi_g + t).sin()).asin() - t).to_degrees() as f32
            })
            .collect();
        let lon: Vec<f32> = r.radiance(i, 16).iter().map(|v| v - 100.0).collect();
        eprintln!("pixel {i}: exit longitudes {lon:?}, Snell {snell:?}");
        for c in 0..3 {
            assert!((lon[c] - snell[c]).abs() < 0.3, "pixel {i} channel {c}: {} vs Snell {}", lon[c], snell[c]);
        }
    }
}

#[test]
fn the_volume_source_scenes_render_without_nan() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(true);
    for name in ["eikonal_wine_glass", "eikonal_amber_bunny", "eikonal_dispersion_cube"] {
        // A coarse initial wavefront (16^2 patches per light instead of one per voxel face):
        // the light simulation still runs through each scene's fields.
        let s = common::scene(name, 48, &["volume.resolution=[48, 48, 48]", "render.eikonal.light_patches=16"]);
        let r = common::render_on(&ctx, &s);
        no_nan(name, &r.hdr);
        assert!(r.passes.contains(&"eikonal_view".to_string()), "{name}: {:?}", r.passes);
        // The object changes the view: the centre differs from the scene without a volume.
        let mut empty = s.clone();
        empty.volume = None;
        let e = common::render_on(&ctx, &empty);
        let changed =
            r.hdr.chunks(4).zip(e.hdr.chunks(4)).filter(|(a, b)| (0..3).any(|c| (a[c] - b[c]).abs() > 1e-3)).count();
        eprintln!("{name}: {changed} of {} pixels changed by the volume", 48 * 48);
        assert!(changed > 100, "{name}: the volume changes only {changed} pixels");
    }
}

#[test]
fn extremes_give_no_nan() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let glass = "[[volume.region]]\nshape = \"rounded_box\"\nsize = [1.4, 1.4, 1.4]\nradius = 0.3\nn = 1.5\nsigma_a = [0.1, 0.2, 0.3]\nemission = 0.2\n";
    let cases: Vec<(String, Vec<&str>)> = vec![
        // Sharp boundaries: no smoothing at all.
        (format!("{BOX}resolution = [32, 32, 32]\n{glass}"), vec!["render.eikonal.sigma=0"]),
        // Total internal reflection inside: a dense core seen at grazing angles.
        (format!("{BOX}resolution = [32, 32, 32]\n{}", glass.replace("n = 1.5", "n = 3.5")), vec![]),
        (format!("{BOX}resolution = [1, 1, 1]\n{glass}"), vec![]),
        (format!("{BOX}resolution = [7, 40, 3]\n{glass}"), vec!["render.eikonal.sigma=2"]),
        (format!("{BOX}resolution = [32, 32, 32]\n{}", glass.replace("n = 1.5", "n = 1.0001")), vec![]),
        (format!("{BOX}resolution = [32, 32, 32]\n{}", glass.replace("n = 1.5", "n = 10")), vec![]),
        (format!("{BOX}resolution = [32, 32, 32]\n{}", glass.replace("n = 1.5", "n = [1.2, 2.5, 9]")), vec![]),
        (format!("{BOX}resolution = [32, 32, 32]\n{}", glass.replace("n = 1.5", "n = 0.5")), vec![]),
        (
            format!(
                "{BOX}resolution = [32, 32, 32]\n{}",
                glass.replace("sigma_a = [0.1, 0.2, 0.3]", "sigma_a = 10000")
            ),
            vec![],
        ),
        (format!("{BOX}resolution = [32, 32, 32]\n{}", glass.replace("emission = 0.2", "emission = 10000")), vec![]),
    ];
    for (volume, o) in cases {
        // Both integrators around one prepared volume (common::render_each).
        let integrators = ["euler", "rk4"];
        let scenes: Vec<_> = integrators
            .iter()
            .map(|integrator| {
                let mut o = o.clone();
                let i = format!("render.eikonal.integrator=\"{integrator}\"");
                o.push(&i);
                volume_scene(&volume, "[environment]\ntype = \"grid\"\n", &o).unwrap()
            })
            .collect();
        for (integrator, r) in integrators.iter().zip(common::render_each(&ctx, &scenes)) {
            no_nan(&format!("{volume} {o:?} {integrator}"), &r.hdr);
        }
    }
}

#[test]
fn invalid_regions_give_clear_errors() {
    if !common::in_own_process() {
        return;
    }
    let open = write("open.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\n");
    let r = |body: &str| format!("{BOX}resolution = [8, 8, 8]\n[[volume.region]]\n{body}\n");
    let cases = [
        (r("shape = \"lathe\"\nprofile = [[0.5, 0]]"), "at least 2"),
        (r("shape = \"lathe\"\nprofile = [[-0.5, 0], [0.5, 1]]"), "r >= 0"),
        (r("shape = \"lathe\"\nprofile = [[0, 0], [0, 1]]"), "no area"),
        (r("shape = \"sphere\"\nradius = 0.5\nn = 0"), "refractive index"),
        (r("shape = \"sphere\"\nradius = 0.5\nn = [1.5, -1, 1.5]"), "refractive index"),
        (r("shape = \"sphere\"\nradius = 0.5\nn = nan"), "finite"),
        (r("shape = \"sphere\"\nradius = 0.5\nn = 11"), "refractive index"),
        (r("shape = \"sphere\"\nradius = -0.5"), "radius"),
        (r("shape = \"sphere\"\nradius = 0.5\nsigma_a = -1"), "sigma_a"),
        (r("shape = \"sphere\"\nradius = 0.5\nsigma_s = 1e6"), "at most"),
        (r("shape = \"sphere\"\nradius = 0.5\nemission = inf"), "finite"),
        (r("shape = \"sphere\"\nradius = 0.5\nhg_g = 1"), "hg_g"),
        (r("shape = \"sphere\"\nradius = 0.5\nreflectance = 2"), "reflectance"),
        (r("shape = \"sphere\"\nradius = 0.5\nsize = [1, 1, 1]"), "size"),
        (r("shape = \"torus\"\nradius = 0.5"), "unknown region shape"),
        (r("shape = \"box\"\nsize = [1, 0, 1]"), "size"),
        (r("shape = \"rounded_box\"\nsize = [1, 1, 1]\nradius = 0.6"), "rounding"),
        (r("shape = \"cylinder\"\nradius = 0.5"), "height"),
        (r("shape = \"mesh\"\nfile = \"no_such_mesh.obj\""), "no_such_mesh.obj"),
        (r(&format!("shape = \"mesh\"\nfile = \"{}\"", open.display())), "not closed"),
        (format!("{BOX}resolution = [8, 8, 8]\nhg_g = -2\n"), "hg_g"),
        (format!("{BOX}resolution = [8, 8, 8]\nemission = -1\n"), "emission"),
    ];
    for (volume, expected) in cases {
        match volume_scene(&volume, "", &[]) {
            Ok(_) => panic!("accepted:\n{volume}"),
            Err(e) => {
                assert!(e.contains(expected), "expected `{expected}` in:\n{e}");
                assert!(e.contains("scene.toml"), "the error should name the file:\n{e}");
            }
        }
    }
}

/// The reference (src/reference, glsl/reference/volume.glsl, VOLUME_FIELDS) traces the same
/// fields: on the opaque slab it reflects ((n - 1) / (n + 1))^2 of a uniform environment at
/// normal incidence (a Monte Carlo estimate: 64 paths in each of the 8 x 8 centre pixels,
/// standard deviation 0.003, tolerance 0.01), and through the emissive box it sees E d.
#[test]
fn the_reference_traces_the_same_fields() {
    if !common::in_own_process() {
        return;
    }
    use prism::reference::{Reference, ReferenceSettings};
    let ctx = common::context(false);
    // Only the centre matters: 8 x 8 pixels through the middle quarter of the 32 x 32 view's
    // angle (tan(20 deg) / 4 = tan(5.2 deg)), the region of its 8 x 8 centre pixels.
    let centre = ["camera.width=8", "camera.height=8", "camera.vfov_deg=10.4"];
    let run = |volume: &str, env: f32, spp: u32| {
        let env = format!("[environment]\ntype = \"constant\"\nradiance = {env}\n");
        let s = volume_scene(volume, &env, &centre).unwrap();
        let settings = ReferenceSettings { spp, photons: 0, ..ReferenceSettings::default() };
        let mut r = Reference::new(&ctx, &s, &settings).expect("reference");
        r.run_all(|_, _| {}).unwrap();
        assert_eq!(r.non_finite_values(), 0);
        let img = r.image();
        drop(r);
        common::assert_no_validation_errors(&ctx);
        // The mean of the 8 x 8 pixels.
        let mut m = [0.0f32; 3];
        for p in img.chunks(4) {
            for c in 0..3 {
                m[c] += p[c] / 64.0;
            }
        }
        m
    };
    let slab = format!(
        "{BOX}resolution = [48, 48, 48]\n[[volume.region]]\nshape = \"box\"\nsize = [1.6, 1.6, 0.4]\nn = 1.5\nsigma_a = 1000\n"
    );
    let f = run(&slab, 1.0, 64);
    eprintln!("reference, opaque slab n = 1.5: {f:?}, expected 0.04");
    for c in f {
        assert!((c - 0.04).abs() < 0.01, "{f:?}");
    }
    let emitter = format!(
        "{BOX}resolution = [40, 40, 40]\n[[volume.region]]\nshape = \"box\"\nsize = [1.2, 1.2, 0.5]\nemission = [0.5, 1, 2]\n"
    );
    let e = run(&emitter, 0.0, 1);
    eprintln!("reference, emissive box: {e:?}, expected [0.25, 0.5, 1.0]");
    for (c, x) in e.iter().zip([0.25, 0.5, 1.0]) {
        assert!((c - x).abs() < 0.01 * x, "{e:?}");
    }
}
