//! Bounding volume hierarchy over triangles, built on the CPU with the surface area
//! heuristic (binned SAH, Wald 2007 "On fast construction of SAH-based bounding volume
//! hierarchies") and traversed both here and in glsl/reference/scene.glsl.
//!
//! Layout (mirrored by the shader): nodes in depth-first order, 32 bytes each, threaded for a
//! traversal without a stack (Smits 1998, "Efficiency issues for ray tracing"). An interior
//! node's left child is the next node and `index` is its skip: the node that follows its
//! subtree, where a ray that misses its box goes on (its right child is its left child's
//! skip). A leaf has `count > 0` triangles starting at `index` in the BVH-ordered triangle
//! list; its skip is the next node. The traversal visits the nodes a stack's left-first
//! traversal would, in the same order, so it finds the same hit; the shader keeps no per-lane
//! stack, which lavapipe would store and load lane by lane.
pub use crate::shader_structs::BvhNode;
use glam::Vec3;

/// Number of SAH bins per axis and the largest leaf.
const BINS: usize = 16;
const MAX_LEAF: usize = 4;
/// Relative cost of a ray-box test against a ray-triangle test in the SAH.
const TRAVERSAL_COST: f32 = 1.0;

#[derive(Clone, Copy, Debug)]
struct Aabb {
    lo: Vec3,
    hi: Vec3,
}

impl Aabb {
    const EMPTY: Aabb = Aabb { lo: Vec3::splat(f32::INFINITY), hi: Vec3::splat(f32::NEG_INFINITY) };
    fn grow(&mut self, p: Vec3) {
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }
    fn merge(&mut self, o: &Aabb) {
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
    }
    fn area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3::ZERO);
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }
}

pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    /// Triangle indices (into the caller's triangle list) in leaf order.
    pub order: Vec<u32>,
}

/// A ray hit: distance and triangle (caller's index).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub triangle: u32,
}

/// Möller & Trumbore 1997 for the ray `o + t d` and the triangle (a, a + e1, a + e2): the
/// barycentrics (u, v) and t of the ray's meeting with the triangle's plane, or `None` where
/// `parallel(det)` says the ray runs (nearly) in that plane. Each caller decides which (u,
/// v, t) hit, as the shader it mirrors does.
pub fn moller_trumbore(
    o: Vec3,
    d: Vec3,
    a: Vec3,
    e1: Vec3,
    e2: Vec3,
    parallel: impl Fn(f32) -> bool,
) -> Option<(f32, f32, f32)> {
    let p = d.cross(e2);
    let det = e1.dot(p);
    if parallel(det) {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - a;
    let u = s.dot(p) * inv;
    let q = s.cross(e1);
    Some((u, d.dot(q) * inv, e2.dot(q) * inv))
}

/// Möller-Trumbore ray/triangle intersection, the same arithmetic as the shader's
/// `intersect_triangle`: any hit with t > 0 (callers pick the winner with [`better`]).
pub fn intersect_triangle(o: Vec3, d: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<f32> {
    let (u, v, t) = moller_trumbore(o, d, a, b - a, c - a, |det| det.abs() < 1e-30)?;
    let inside = (0.0..=1.0).contains(&u) && !(v < 0.0 || u + v > 1.0);
    (inside && t > 0.0).then_some(t)
}

/// The hit rule shared with the shader: closer, or equally close with a lower triangle index,
/// so that BVH and brute force agree even on shared edges.
pub fn better(t: f32, triangle: u32, best: Option<Hit>, t_max: f32) -> bool {
    match best {
        None => t < t_max,
        Some(h) => t < h.t || (t == h.t && triangle < h.triangle),
    }
}

impl Bvh {
    /// Build over triangles given by their three corners.
    pub fn build(triangles: &[[Vec3; 3]]) -> Bvh {
        let n = triangles.len();
        let bounds: Vec<Aabb> = triangles
            .iter()
            .map(|t| {
                let mut b = Aabb::EMPTY;
                t.iter().for_each(|&p| b.grow(p));
                b
            })
            .collect();
        let centroids: Vec<Vec3> = bounds.iter().map(|b| (b.lo + b.hi) * 0.5).collect();
        let mut order: Vec<u32> = (0..n as u32).collect();
        let mut nodes = Vec::with_capacity(2 * n.max(1));
        if n == 0 {
            // One empty node with an inverted box: every ray misses it.
            return Bvh { nodes: vec![BvhNode { lo: [1.0; 3], index: 0, hi: [-1.0; 3], count: 0 }], order };
        }
        Self::build_node(&bounds, &centroids, &mut order, 0, n, &mut nodes);
        Bvh { nodes, order }
    }

    fn build_node(
        bounds: &[Aabb],
        centroids: &[Vec3],
        order: &mut [u32],
        start: usize,
        end: usize,
        nodes: &mut Vec<BvhNode>,
    ) {
        let mut bb = Aabb::EMPTY;
        let mut cb = Aabb::EMPTY;
        for &t in &order[start..end] {
            bb.merge(&bounds[t as usize]);
            cb.grow(centroids[t as usize]);
        }
        let me = nodes.len();
        nodes.push(BvhNode {
            lo: bb.lo.to_array(),
            index: start as u32,
            hi: bb.hi.to_array(),
            count: (end - start) as u32,
        });
        let count = end - start;
        if count <= MAX_LEAF {
            return;
        }
        // Binned SAH over the axis-aligned centroid bounds.
        let mut best = (f32::INFINITY, 0usize, 0usize);
        let extent = cb.hi - cb.lo;
        for axis in 0..3 {
            if extent[axis] <= 0.0 {
                continue;
            }
            let mut bins = [(Aabb::EMPTY, 0usize); BINS];
            let scale = BINS as f32 / extent[axis];
            let bin_of = |t: u32| (((centroids[t as usize][axis] - cb.lo[axis]) * scale) as usize).min(BINS - 1);
            for &t in &order[start..end] {
                let b = &mut bins[bin_of(t)];
                b.0.merge(&bounds[t as usize]);
                b.1 += 1;
            }
            // Sweep: cost of splitting after bin i.
            let mut right_area = [0f32; BINS];
            let mut right_count = [0usize; BINS];
            let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
            for i in (1..BINS).rev() {
                acc.merge(&bins[i].0);
                cnt += bins[i].1;
                right_area[i] = acc.area();
                right_count[i] = cnt;
            }
            let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
            for i in 0..BINS - 1 {
                acc.merge(&bins[i].0);
                cnt += bins[i].1;
                if cnt == 0 || right_count[i + 1] == 0 {
                    continue;
                }
                let cost = acc.area() * cnt as f32 + right_area[i + 1] * right_count[i + 1] as f32;
                if cost < best.0 {
                    best = (cost, axis, i);
                }
            }
        }
        // Stay a leaf when splitting costs more (SAH) or no split exists (identical
        // centroids), unless the leaf would exceed 16 triangles.
        let leaf_cost = bb.area() * count as f32;
        let split_cost = TRAVERSAL_COST * bb.area() + best.0;
        if count <= 16 && (!best.0.is_finite() || split_cost >= leaf_cost) {
            return;
        }
        let mid = if best.0.is_finite() {
            let (_, axis, split) = best;
            let scale = BINS as f32 / extent[axis];
            let slice = &mut order[start..end];
            let mut i = 0;
            for j in 0..slice.len() {
                let c = centroids[slice[j] as usize][axis];
                if ((((c - cb.lo[axis]) * scale) as usize).min(BINS - 1)) <= split {
                    slice.swap(i, j);
                    i += 1;
                }
            }
            start + i
        } else {
            // All centroids coincide: split the list in half so leaves stay small.
            start + count / 2
        };
        nodes[me].count = 0;
        Self::build_node(bounds, centroids, order, start, mid, nodes);
        Self::build_node(bounds, centroids, order, mid, end, nodes);
        nodes[me].index = nodes.len() as u32;
    }

    /// Closest hit with t in (0, t_max), traversing the tree; `triangles` in caller order.
    pub fn intersect(&self, triangles: &[[Vec3; 3]], o: Vec3, d: Vec3, t_max: f32) -> Option<Hit> {
        // No triangles: the one node's inverted box still passes the slab test (its min and
        // max swap), and as a node without a count it would read as interior.
        if self.order.is_empty() {
            return None;
        }
        let inv = d.recip();
        let mut best: Option<Hit> = None;
        let mut closest = t_max;
        let mut i = 0;
        while i < self.nodes.len() {
            let node = &self.nodes[i];
            let hit = slab(o, inv, Vec3::from(node.lo), Vec3::from(node.hi), closest);
            // Into the subtree (a leaf's is itself), or past it.
            i = if hit || node.count > 0 { i + 1 } else { node.index as usize };
            if hit && node.count > 0 {
                for k in node.index..node.index + node.count {
                    let tri = self.order[k as usize];
                    let [a, b, c] = triangles[tri as usize];
                    if let Some(t) = intersect_triangle(o, d, a, b, c) {
                        if better(t, tri, best, t_max) {
                            closest = t;
                            best = Some(Hit { t, triangle: tri });
                        }
                    }
                }
            }
        }
        best
    }
}

/// Ray/box slab test for t in [0, t_max].
pub fn slab(o: Vec3, inv_d: Vec3, lo: Vec3, hi: Vec3, t_max: f32) -> bool {
    let t0 = (lo - o) * inv_d;
    let t1 = (hi - o) * inv_d;
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(t_max);
    near <= far
}

/// Closest hit by testing every triangle (the ground truth for BVH tests).
pub fn brute_force(triangles: &[[Vec3; 3]], o: Vec3, d: Vec3, t_max: f32) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    for (i, [a, b, c]) in triangles.iter().enumerate() {
        if let Some(t) = intersect_triangle(o, d, *a, *b, *c) {
            if better(t, i as u32, best, t_max) {
                best = Some(Hit { t, triangle: i as u32 });
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bunny() -> Vec<[Vec3; 3]> {
        let s = crate::scene::load(&crate::scene::benchmark_scene_path("bunny_env"), &[]).unwrap();
        let m = &s.objects[0].mesh;
        m.indices.chunks(3).map(|t| [0, 1, 2].map(|k| m.positions[t[k] as usize])).collect()
    }

    /// Deterministic pseudo-random numbers for tests (SplitMix64).
    pub(crate) fn rng(state: &mut u64) -> f32 {
        *state = state.wrapping_add(0x9E3779B97F4A7C15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }

    #[test]
    fn bvh_agrees_exactly_with_brute_force_on_the_bunny() {
        let tris = bunny();
        let bvh = Bvh::build(&tris);
        let mut s = 7u64;
        let mut hits = 0;
        for _ in 0..4000 {
            // Rays from a sphere of radius 3 towards random points near the bunny.
            let o = Vec3::new(rng(&mut s) - 0.5, rng(&mut s) - 0.5, rng(&mut s) - 0.5).normalize() * 3.0;
            let target = Vec3::new(rng(&mut s) - 0.5, rng(&mut s) - 0.5, rng(&mut s) - 0.5) * 1.6;
            let d = (target - o).normalize();
            let a = bvh.intersect(&tris, o, d, f32::INFINITY);
            let b = brute_force(&tris, o, d, f32::INFINITY);
            assert_eq!(a, b, "ray {o} {d}");
            hits += a.is_some() as u32;
        }
        assert!(hits > 1000, "too few rays hit ({hits}): the test would prove little");
    }

    #[test]
    fn leaves_cover_every_triangle_once() {
        let tris = bunny();
        let bvh = Bvh::build(&tris);
        let mut seen = vec![0u32; tris.len()];
        for n in &bvh.nodes {
            if n.count > 0 {
                for k in n.index..n.index + n.count {
                    seen[bvh.order[k as usize] as usize] += 1;
                }
            }
        }
        assert!(seen.iter().all(|&c| c == 1));
        assert!(bvh.nodes.iter().all(|n| n.count as usize <= 16));
    }

    /// Each interior node's skip is the node after its subtree: the end of its right child's,
    /// which begins at its left child's skip.
    #[test]
    fn skips_follow_the_subtrees() {
        let tris = bunny();
        let bvh = Bvh::build(&tris);
        fn end(nodes: &[BvhNode], i: usize) -> usize {
            if nodes[i].count > 0 {
                i + 1
            } else {
                end(nodes, end(nodes, i + 1))
            }
        }
        for (i, n) in bvh.nodes.iter().enumerate() {
            if n.count == 0 {
                assert_eq!(n.index as usize, end(&bvh.nodes, i), "node {i}");
            }
        }
        assert_eq!(end(&bvh.nodes, 0), bvh.nodes.len());
    }

    #[test]
    fn degenerate_input_builds() {
        // Identical triangles (all centroids equal) and zero-area triangles.
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let bvh = Bvh::build(&vec![t; 100]);
        assert!(bvh.intersect(&vec![t; 100], Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, f32::INFINITY).is_some());
        let flat = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        let bvh = Bvh::build(&vec![flat; 10]);
        assert!(bvh.intersect(&vec![flat; 10], Vec3::new(0.5, 0.0, 1.0), -Vec3::Z, f32::INFINITY).is_none());
        assert_eq!(Bvh::build(&[]).nodes.len(), 1);
        assert!(Bvh::build(&[]).intersect(&[], Vec3::ZERO, Vec3::ONE.normalize(), f32::INFINITY).is_none());
    }
}
