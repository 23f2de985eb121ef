//! Wyman 2005 §3.1: d_N, the distance from each vertex along its inverted normal to the far
//! side of the mesh, "precomputed for every vertex". Computed on the CPU at load time by
//! casting one ray per vertex against a bounding-volume hierarchy of the mesh's triangles
//! (median split on the longest axis, Möller–Trumbore triangle test), and cached per mesh
//! (keyed by a hash of its positions, normals and indices), so that rendering the same
//! object again costs nothing.
//!
//! Cost, measured in release builds on this project's 2-core machine: the 128-segment sphere
//! (16k triangles, 8k vertices) and the Stanford bunny of bunny_env (about 5k triangles)
//! each take a few milliseconds; brute force would be O(vertices x triangles) (tens of
//! milliseconds to seconds), which the tests, rendering the sphere dozens of times, would feel.
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex, OnceLock};

use glam::Vec3;

use crate::reference::bvh::moller_trumbore;
use crate::scene::Mesh;

/// Leaves hold at most this many triangles.
const LEAF_SIZE: usize = 4;

struct Node {
    lo: Vec3,
    hi: Vec3,
    /// Leaf: first triangle in `order` and count; inner: right child index (left is next).
    start: u32,
    count: u32,
    right: u32,
}

struct Bvh<'a> {
    positions: &'a [Vec3],
    tris: Vec<[u32; 3]>,
    nodes: Vec<Node>,
}

impl<'a> Bvh<'a> {
    fn new(mesh: &'a Mesh) -> Self {
        let tris: Vec<[u32; 3]> = mesh.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        let mut bvh = Bvh { positions: &mesh.positions, tris: Vec::new(), nodes: Vec::new() };
        let centroids: Vec<Vec3> = tris.iter().map(|t| bvh.tri(t).iter().sum::<Vec3>() / 3.0).collect();
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        if !order.is_empty() {
            bvh.build(&tris, &centroids, &mut order, 0);
        }
        bvh.tris = order.iter().map(|&i| tris[i as usize]).collect();
        bvh
    }

    fn tri(&self, t: &[u32; 3]) -> [Vec3; 3] {
        [self.positions[t[0] as usize], self.positions[t[1] as usize], self.positions[t[2] as usize]]
    }

    fn build(&mut self, tris: &[[u32; 3]], centroids: &[Vec3], order: &mut [u32], start: usize) -> usize {
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for &i in order.iter() {
            for p in self.tri(&tris[i as usize]) {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        let index = self.nodes.len();
        self.nodes.push(Node { lo, hi, start: start as u32, count: order.len() as u32, right: 0 });
        if order.len() <= LEAF_SIZE {
            return index;
        }
        let ext = hi - lo;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mid = order.len() / 2;
        order.select_nth_unstable_by(mid, |&a, &b| centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis]));
        let (left, right) = order.split_at_mut(mid);
        self.nodes[index].count = 0;
        self.build(tris, centroids, left, start);
        let r = self.build(tris, centroids, right, start + mid);
        self.nodes[index].right = r as u32;
        index
    }

    /// Nearest hit distance t in (t_min, t_max) of the ray o + t d.
    fn nearest(&self, o: Vec3, d: Vec3, t_min: f32, mut t_max: f32) -> Option<f32> {
        let inv = d.recip();
        let mut best = None;
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            // Slab test. An axis the ray is parallel to constrains nothing if the origin lies
            // within the slab (boundaries included: a box corner's inverted normal runs along
            // two of its faces) and rejects the box otherwise.
            let (mut near, mut far) = (f32::NEG_INFINITY, f32::INFINITY);
            for a in 0..3 {
                if d[a] == 0.0 {
                    if o[a] < node.lo[a] || o[a] > node.hi[a] {
                        far = f32::NEG_INFINITY;
                    }
                    continue;
                }
                let (t0, t1) = ((node.lo[a] - o[a]) * inv[a], (node.hi[a] - o[a]) * inv[a]);
                near = near.max(t0.min(t1));
                far = far.min(t0.max(t1));
            }
            if near > far.min(t_max) || far < t_min {
                continue;
            }
            if node.count == 0 {
                stack.push(node.right as usize);
                stack.push(n + 1);
                continue;
            }
            for t in &self.tris[node.start as usize..(node.start + node.count) as usize] {
                let [a, b, c] = self.tri(t);
                if let Some(h) = ray_triangle(o, d, a, b, c) {
                    if h > t_min && h < t_max {
                        t_max = h;
                        best = Some(h);
                    }
                }
            }
        }
        best
    }
}

/// Barycentric slack: a ray through a shared vertex or edge (on a UV sphere every vertex's
/// inverted normal passes through the antipodal vertex) must not slip between triangles.
const EDGE_SLACK: f32 = 1e-5;

/// Möller–Trumbore, two-sided, with [`EDGE_SLACK`].
fn ray_triangle(o: Vec3, d: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<f32> {
    let (u, v, t) = moller_trumbore(o, d, a, b - a, c - a, |det| det.abs() < 1e-20)?;
    let inside = (-EDGE_SLACK..=1.0 + EDGE_SLACK).contains(&u) && !(v < -EDGE_SLACK || u + v > 1.0 + EDGE_SLACK);
    inside.then_some(t)
}

/// d_N of every vertex of `mesh`: the distance along -normal to the nearest surface beyond
/// the vertex's own (0 where the ray leaves an open mesh; the shader then uses d_V). The
/// ray starts at the vertex and ignores hits closer than 1e-4 of the mesh's size, which are
/// the triangles around the vertex itself.
pub fn compute_distance_along_normals(mesh: &Mesh) -> Vec<f32> {
    let bvh = Bvh::new(mesh);
    let (lo, hi) = mesh.bounds();
    let eps = (hi - lo).length().max(1e-30) * 1e-4;
    mesh.positions
        .iter()
        .zip(&mesh.normals)
        .map(|(&p, &n)| bvh.nearest(p, -n, eps, f32::INFINITY).unwrap_or(0.0))
        .collect()
}

fn mesh_key(mesh: &Mesh) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    let floats = |v: &[Vec3]| -> Vec<u32> { v.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect() };
    floats(&mesh.positions).hash(&mut h);
    floats(&mesh.normals).hash(&mut h);
    mesh.indices.hash(&mut h);
    h.finish()
}

/// [`compute_distance_along_normals`], cached per mesh for the life of the process.
pub fn distance_along_normals(mesh: &Mesh) -> Arc<Vec<f32>> {
    distance_along_normals_timed(mesh).0
}

/// [`distance_along_normals`] and the wall-clock milliseconds its computation took when it
/// was computed (also when it comes from the cache): the cost paid once per mesh.
pub fn distance_along_normals_timed(mesh: &Mesh) -> (Arc<Vec<f32>>, f64) {
    type Entry = (Arc<Vec<f32>>, f64);
    static CACHE: OnceLock<Mutex<HashMap<u64, Entry>>> = OnceLock::new();
    let key = mesh_key(mesh);
    let cache = CACHE.get_or_init(Default::default);
    if let Some(d) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return d.clone();
    }
    let start = std::time::Instant::now();
    let d = Arc::new(compute_distance_along_normals(mesh));
    let entry = (d, start.elapsed().as_secs_f64() * 1e3);
    cache.lock().unwrap_or_else(|e| e.into_inner()).insert(key, entry.clone());
    entry
}
