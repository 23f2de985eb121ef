//! Triangle meshes: the common currency of every shape, OBJ loading and validation,
//! and vertex normals that are never NaN.

use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3};

use super::error::ErrorKind;

/// An indexed triangle mesh in world space (after loading).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    /// Unit length, never NaN; one per position.
    pub normals: Vec<Vec3>,
    /// Checker-albedo coordinates (s, t) in metres, one per position.
    pub checker_uv: Vec<Vec2>,
    /// Three per triangle, counter-clockwise seen from the side the normals point to.
    pub indices: Vec<u32>,
}

impl Mesh {
    /// Axis-aligned bounds (min, max); both zero for an empty mesh.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        if self.positions.is_empty() {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        self.positions
            .iter()
            .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), &p| (lo.min(p), hi.max(p)))
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Whether the mesh bounds a solid with its front faces outside: every edge (vertices
    /// welded within 1e-6 of the mesh's size, as a seam's rounded sines leave them;
    /// degenerate triangles left out) is shared by exactly two triangles that run it in
    /// opposite directions, and the enclosed volume is positive. Seen from anywhere outside,
    /// the nearest surface of such a mesh is then a front face and a ray's exit a back face,
    /// so passes looking for either can cull the other.
    pub fn is_closed_outward(&self) -> bool {
        use std::collections::HashMap;
        let (lo, hi) = self.bounds();
        let eps = 1e-6 * (hi - lo).length().max(f32::MIN_POSITIVE);
        // Cells of side eps: a point's twin within eps is in one of the 27 around it.
        let mut cells: HashMap<[i64; 3], Vec<(Vec3, u32)>> = HashMap::new();
        let mut next = 0u32;
        let mut ids = Vec::with_capacity(self.positions.len());
        for &p in &self.positions {
            let cell = ((p - lo) / eps).floor().as_i64vec3().to_array();
            let near = (0..27).find_map(|k| {
                let c = [cell[0] + k % 3 - 1, cell[1] + k / 3 % 3 - 1, cell[2] + k / 9 - 1];
                cells.get(&c)?.iter().find(|(q, _)| (*q - p).length() <= eps).map(|&(_, id)| id)
            });
            let id = near.unwrap_or_else(|| {
                cells.entry(cell).or_default().push((p, next));
                next += 1;
                next - 1
            });
            ids.push(id);
        }
        // Per undirected edge (low id, high id): the runs low -> high minus the runs back.
        let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
        let mut volume = 0.0f64;
        for tri in self.indices.chunks_exact(3) {
            let Some(v) = tri.iter().map(|&i| ids.get(i as usize).copied()).collect::<Option<Vec<u32>>>() else {
                return false;
            };
            if v[0] == v[1] || v[1] == v[2] || v[2] == v[0] {
                continue;
            }
            for (a, b) in [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])] {
                let e = edges.entry((a.min(b), a.max(b))).or_default();
                if a < b {
                    e.0 += 1;
                } else {
                    e.1 += 1;
                }
            }
            let [p0, p1, p2] = [0, 1, 2].map(|k| self.positions[tri[k] as usize].as_dvec3());
            volume += p0.dot(p1.cross(p2)) / 6.0;
        }
        !edges.is_empty() && edges.values().all(|&runs| runs == (1, 1)) && volume > 0.0
    }

    /// Appends `other`, offsetting its indices.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.checker_uv.extend_from_slice(&other.checker_uv);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }

    /// Applies an affine transform to positions and (by the inverse transpose) normals.
    pub fn transform(&mut self, m: Mat4) {
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        let n = Mat3::from_mat4(m).inverse().transpose();
        for v in &mut self.normals {
            // A singular transform (scale 0 is rejected on load, but keep this total)
            // leaves the old normal rather than a NaN.
            *v = (n * *v).try_normalize().unwrap_or(*v);
        }
    }

    /// Sets the checker coordinates to world (x, z), the convention for every shape
    /// except non-horizontal quads.
    pub fn set_checker_uv_xz(&mut self) {
        self.checker_uv = self.positions.iter().map(|p| Vec2::new(p.x, p.z)).collect();
    }

    /// Area-weighted vertex normals. A vertex whose weighted sum vanishes (only
    /// degenerate triangles, or opposite faces cancelling) takes the normal of one of
    /// its non-degenerate faces, and failing that +Y, so no normal is ever NaN.
    pub fn compute_vertex_normals(&mut self) {
        let mut sum = vec![Vec3::ZERO; self.positions.len()];
        let mut any_face = vec![None::<Vec3>; self.positions.len()];
        for tri in self.indices.chunks_exact(3) {
            let [a, b, c] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
            let (Some(&pa), Some(&pb), Some(&pc)) =
                (self.positions.get(a), self.positions.get(b), self.positions.get(c))
            else {
                continue;
            };
            // |cross| is twice the area, so summing it weights by area.
            let w = (pb - pa).cross(pc - pa);
            let face = w.try_normalize();
            for i in [a, b, c] {
                sum[i] += w;
                if any_face[i].is_none() {
                    any_face[i] = face;
                }
            }
        }
        self.normals = sum.iter().zip(&any_face).map(|(s, f)| s.try_normalize().or(*f).unwrap_or(Vec3::Y)).collect();
    }

    /// Replaces any zero-length or non-finite normal with a computed one, and
    /// normalizes the rest (OBJ normals need not be unit length).
    pub(crate) fn repair_normals(&mut self) {
        if self.normals.len() != self.positions.len() {
            self.compute_vertex_normals();
            return;
        }
        if self.normals.iter().any(|n| n.try_normalize().is_none()) {
            let given = std::mem::take(&mut self.normals);
            self.compute_vertex_normals();
            for (n, g) in self.normals.iter_mut().zip(given) {
                if let Some(g) = g.try_normalize() {
                    *n = g;
                }
            }
        } else {
            for n in &mut self.normals {
                *n = n.normalize();
            }
        }
    }
}

/// Why an OBJ file was rejected; `line` is 1-based.
/// Why OBJ text was refused: the kind, the 1-based line when one is to blame, and a hint.
#[derive(Debug)]
pub struct ObjError {
    pub kind: ErrorKind,
    pub line: Option<usize>,
    pub message: String,
    pub hint: String,
}

fn obj_err(kind: ErrorKind, line: Option<usize>, message: String, hint: &str) -> ObjError {
    ObjError { kind, line, message, hint: hint.to_string() }
}

/// Reads and validates an OBJ file (triangulated, one index per vertex). Normals from
/// the file are kept (normalized); missing ones are computed, area-weighted.
pub(crate) fn load_obj(path: &Path) -> Result<Mesh, ObjError> {
    let text = super::read::read_text(path, super::read::MAX_MESH_BYTES).map_err(|e| {
        obj_err(
            ErrorKind::MissingFile,
            None,
            format!("cannot read mesh file: {e}"),
            "mesh paths are relative to the scene file's directory",
        )
    })?;
    parse_obj(&text)
}

/// Parses OBJ text, as [`load_obj`] does once it has read the file (the fuzz target in
/// fuzz/ calls it with no file). Positions and face indices are checked line by line
/// first, so that an error can name the offending line (tobj reports no lines).
pub fn parse_obj(text: &str) -> Result<Mesh, ObjError> {
    prescan(text)?;
    let opts = tobj::LoadOptions { triangulate: true, single_index: true, ignore_points: true, ignore_lines: true };
    let mut reader = std::io::BufReader::new(text.as_bytes());
    // Materials (mtllib) are ignored: the scene file assigns the material.
    let (models, _materials) = tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed))
        .map_err(|e| {
            obj_err(
                ErrorKind::Mesh,
                None,
                format!("malformed OBJ: {e}"),
                "check the file with a mesh viewer, or re-export it as triangles",
            )
        })?;
    let mut mesh = Mesh::default();
    let mut had_normals = true;
    for model in &models {
        let m = &model.mesh;
        let n = m.positions.len() / 3;
        let mut part = Mesh {
            positions: m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect(),
            normals: m.normals.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect(),
            checker_uv: Vec::new(),
            indices: m.indices.clone(),
        };
        if let Some(bad) = part.indices.iter().find(|&&i| i as usize >= n) {
            return Err(obj_err(
                ErrorKind::Mesh,
                None,
                format!("face index {} is out of range ({n} vertices)", bad + 1),
                "OBJ indices are 1-based and must name an existing vertex",
            ));
        }
        if part.positions.iter().any(|p| !p.is_finite()) {
            return Err(obj_err(
                ErrorKind::Mesh,
                None,
                "a vertex position is not a finite number".to_string(),
                "remove NaN/inf coordinates from the file",
            ));
        }
        had_normals &= part.normals.len() == part.positions.len();
        if part.normals.len() != part.positions.len() {
            part.normals.clear();
        }
        part.checker_uv = vec![Vec2::ZERO; part.positions.len()];
        mesh.append(&part);
    }
    if mesh.indices.is_empty() {
        return Err(obj_err(
            ErrorKind::Mesh,
            None,
            "the OBJ file has no triangles".to_string(),
            "a mesh needs `v` and `f` lines",
        ));
    }
    if had_normals {
        mesh.repair_normals();
    } else {
        mesh.compute_vertex_normals();
    }
    Ok(mesh)
}

/// Checks `v` and `f` lines, returning an error that names the first bad line. Every index
/// of a face vertex is checked, texture and normal ones too: tobj resolves a negative one
/// before checking it, so one out of range would reach it as a wrapped-around number.
fn prescan(text: &str) -> Result<(), ObjError> {
    let count = |kind: &str| text.lines().filter(|l| l.split_whitespace().next() == Some(kind)).count() as i64;
    // Positions, texture coordinates, normals: in the whole file, and defined so far.
    let total = [count("v"), count("vt"), count("vn")];
    let mut seen = [0i64; 3];
    for (i, line) in text.lines().enumerate() {
        let ln = Some(i + 1);
        let mut tok = line.split_whitespace();
        match tok.next() {
            Some("v") => {
                seen[0] += 1;
                for axis in ["x", "y", "z"] {
                    let value = tok.next().and_then(|t| t.parse::<f32>().ok());
                    match value {
                        None => {
                            return Err(obj_err(
                                ErrorKind::Mesh,
                                ln,
                                format!("vertex {} has no valid {axis} coordinate", seen[0]),
                                "a `v` line holds three numbers: v x y z",
                            ))
                        }
                        Some(v) if !v.is_finite() => {
                            return Err(obj_err(
                                ErrorKind::Mesh,
                                ln,
                                format!("vertex {} has a non-finite {axis} coordinate ({v})", seen[0]),
                                "remove NaN/inf coordinates from the file",
                            ))
                        }
                        Some(_) => {}
                    }
                }
            }
            Some("vt") => seen[1] += 1,
            Some("vn") => seen[2] += 1,
            Some("f") => {
                let mut count = 0;
                for t in tok {
                    count += 1;
                    let not_index = || {
                        obj_err(
                            ErrorKind::Mesh,
                            ln,
                            format!("face vertex `{t}` is not an index"),
                            "a face vertex is `v`, `v/vt`, `v//vn` or `v/vt/vn` with integer indices",
                        )
                    };
                    for (k, part) in t.split('/').take(3).enumerate() {
                        // Only the position index is required.
                        if part.is_empty() && k > 0 {
                            continue;
                        }
                        let idx: i64 = part.parse().map_err(|_| not_index())?;
                        // Positive indices are 1-based over the whole file; negative ones
                        // count back from the last one defined so far.
                        let ok = if idx > 0 { idx <= total[k] } else { idx < 0 && seen[k] + idx >= 0 };
                        if !ok {
                            let what = ["vertices", "texture coordinates (vt)", "normals (vn)"][k];
                            return Err(obj_err(
                                ErrorKind::Mesh,
                                ln,
                                format!("face index {idx} is out of range (the file has {} {what})", total[k]),
                                "OBJ indices are 1-based and must name an existing vertex",
                            ));
                        }
                    }
                }
                if count < 3 {
                    return Err(obj_err(
                        ErrorKind::Mesh,
                        ln,
                        format!("face has {count} vertices"),
                        "a face needs at least three vertices",
                    ));
                }
            }
            _ => {}
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_outward_meshes_are_told_from_open_or_inside_out_ones() {
        use crate::scene::shapes;
        let c = Vec3::new(0.5, 1.0, -2.0);
        let sphere = shapes::sphere(c, 1.0, 64);
        assert!(sphere.is_closed_outward(), "a sphere (seam and poles welded by position)");
        assert!(shapes::cuboid(c, Vec3::new(1.0, 2.0, 3.0)).is_closed_outward(), "a box with hard edges");
        assert!(shapes::torus(c, 1.0, 0.3, 32).is_closed_outward(), "a torus");
        assert!(!shapes::quad(c, Vec2::ONE, Vec3::Y).is_closed_outward(), "a quad has a boundary");
        assert!(!shapes::open_cylinder(c, 1.0, 0.5, 32).is_closed_outward(), "an open cylinder");
        let mut inside_out = sphere.clone();
        for t in inside_out.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
        assert!(!inside_out.is_closed_outward(), "clockwise from outside: negative volume");
        let mut holed = sphere.clone();
        holed.indices.truncate(holed.indices.len() - 3);
        assert!(!holed.is_closed_outward(), "one triangle missing");
    }

    #[test]
    fn degenerate_triangles_give_finite_unit_normals() {
        // Triangle 0 is fine; triangle 1 has a repeated vertex; triangle 2 is three
        // collinear points; vertex 5 only touches degenerate triangles.
        let text = "v 0 0 0\nv 1 0 0\nv 0 0 -1\nv 2 0 0\nv 3 0 0\nv 4 0 0\n\
                    f 1 2 3\nf 1 1 2\nf 4 5 6\n";
        let m = parse_obj(text).expect("valid obj");
        assert_eq!(m.triangle_count(), 3, "degenerate triangles are kept");
        for n in &m.normals {
            assert!(n.is_finite());
            assert!((n.length() - 1.0).abs() < 1e-5);
        }
        assert!((m.normals[0] - Vec3::Y).length() < 1e-5);
        assert_eq!(m.normals[4], Vec3::Y);
    }

    #[test]
    fn nan_position_names_the_line() {
        let e = parse_obj("# c\nv 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n").unwrap_err();
        assert_eq!(e.line, Some(3));
        assert_eq!(e.kind, ErrorKind::Mesh);
        assert!(e.message.contains("non-finite"), "{}", e.message);
    }

    #[test]
    fn out_of_range_index_names_the_line() {
        let e = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n").unwrap_err();
        assert_eq!(e.line, Some(5));
        assert!(e.message.contains("out of range"), "{}", e.message);
        let e = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n").unwrap_err();
        assert_eq!(e.line, Some(4));
    }

    #[test]
    fn texture_and_normal_indices_out_of_range_name_the_line() {
        // Found by fuzz/ (obj): a relative texture index before that many `vt` lines
        // overflowed tobj's index arithmetic.
        let text = "v 0 0 0\nv 1 0 0\nv 1 001   -1\nv 0 0 -1\nvn 0 1 0\nvt 0 0\nf -4/1/1 1/-3/1 -2/1/1 -1/1/1\n";
        let e = parse_obj(text).unwrap_err();
        assert_eq!(e.line, Some(7));
        assert!(
            e.message.contains("face index -3 is out of range (the file has 1 texture coordinates"),
            "{}",
            e.message
        );
        let e = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n").unwrap_err();
        assert_eq!(e.line, Some(5));
        assert!(e.message.contains("normals"), "{}", e.message);
        // In range, with the texture index left out.
        assert!(parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//-1 3//1\n").is_ok());
    }

    #[test]
    fn quads_are_triangulated_and_negative_indices_work() {
        let m = parse_obj("v 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nf -4 -3 -2 -1\n").unwrap();
        assert_eq!(m.triangle_count(), 2);
        assert!(m.normals.iter().all(|n| (*n - Vec3::Y).length() < 1e-5));
    }

    #[test]
    fn transform_keeps_normals_unit() {
        let mut m = parse_obj("v 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\n").unwrap();
        m.transform(Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2) * Mat4::from_scale(Vec3::splat(2.0)));
        for n in &m.normals {
            assert!((n.length() - 1.0).abs() < 1e-5);
            assert!((*n - Vec3::Z).length() < 1e-5, "{n}");
        }
        assert!((m.positions[1] - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-5);
    }
}
