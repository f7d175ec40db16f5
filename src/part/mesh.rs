//! A triangle mesh of the design surface as read from a file (vertices in mm, triangles as
//! vertex indices) and the checks that make it usable: finite vertices, no duplicate
//! triangles, consistent winding; degenerate (zero-area) triangles are dropped and counted.

use crate::math::{Point3, Vec3};
use std::collections::HashMap;

/// A triangle mesh: vertices (mm) and triangles (indices into `vertices`, counter-clockwise
/// seen from outside the material, so that the right-hand normal points out of the part).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions, mm.
    pub vertices: Vec<Point3>,
    /// Triangles, indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

/// Why a mesh cannot describe a design surface. Triangle and vertex numbers are 0-based
/// indices in file order (the readers translate them to lines where the format has lines).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// No triangle at all (or none left after dropping degenerate ones).
    #[error("the mesh has no triangle")]
    Empty,
    /// A vertex with a NaN or infinite coordinate.
    #[error("triangle {triangle}: vertex {vertex} is not finite")]
    NotFinite {
        /// The first triangle that uses it.
        triangle: usize,
        /// The vertex.
        vertex: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle}: vertex index {vertex} is out of range ({count} vertices)")]
    BadIndex {
        /// The triangle.
        triangle: usize,
        /// The index.
        vertex: usize,
        /// Number of vertices.
        count: usize,
    },
    /// Two triangles with the same three vertices.
    #[error("triangle {triangle} repeats triangle {first}")]
    Duplicate {
        /// The repeat.
        triangle: usize,
        /// The first one.
        first: usize,
    },
    /// Two neighbouring triangles run their shared edge the same way: their normals point to
    /// opposite sides.
    #[error(
        "triangle {triangle} is wound against its neighbour {neighbour} (their shared edge runs the same way in both)"
    )]
    Winding {
        /// The triangle.
        triangle: usize,
        /// The neighbour it disagrees with.
        neighbour: usize,
    },
    /// An edge shared by more than two triangles (not a surface).
    #[error("triangle {triangle}: an edge is shared by more than two triangles")]
    NonManifold {
        /// The third triangle on the edge.
        triangle: usize,
    },
}

/// What [`Mesh::checked`] found and did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshCheck {
    /// Degenerate (zero-area) triangles dropped: their indices in the input.
    pub degenerate: Vec<usize>,
    /// Vertices merged because they had the same coordinates.
    pub welded: usize,
}

impl Mesh {
    /// A mesh from triangle corners given one triangle at a time (STL): vertices with the
    /// same coordinates are shared.
    pub fn from_corners(corners: &[[Point3; 3]]) -> Mesh {
        let mut index: HashMap<[u64; 3], u32> = HashMap::new();
        let mut vertices = Vec::new();
        let mut triangles = Vec::with_capacity(corners.len());
        for tri in corners {
            let mut t = [0u32; 3];
            for (k, p) in tri.iter().enumerate() {
                // -0.0 and 0.0 are the same point.
                let key = [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits);
                t[k] = *index.entry(key).or_insert_with(|| {
                    vertices.push(*p);
                    (vertices.len() - 1) as u32
                });
            }
            triangles.push(t);
        }
        Mesh {
            vertices,
            triangles,
        }
    }

    /// The unit normal of triangle `t` by its winding (zero for a degenerate triangle).
    pub fn face_normal(&self, t: usize) -> Vec3 {
        let [a, b, c] = self.triangles[t].map(|i| self.vertices[i as usize]);
        let n = (b - a).cross(&(c - a));
        let len = n.norm();
        if len > 0.0 { n / len } else { Vec3::zeros() }
    }

    /// Check the mesh and drop its degenerate triangles. Errors name the first offending
    /// triangle (0-based, in file order).
    pub fn checked(mut self) -> Result<(Mesh, MeshCheck), MeshError> {
        let mut report = MeshCheck::default();
        let n = self.vertices.len();
        let mut keep = Vec::with_capacity(self.triangles.len());
        let mut original = Vec::with_capacity(self.triangles.len());
        for (t, tri) in self.triangles.iter().enumerate() {
            for &v in tri {
                let v = v as usize;
                if v >= n {
                    return Err(MeshError::BadIndex {
                        triangle: t,
                        vertex: v,
                        count: n,
                    });
                }
                if !self.vertices[v].coords.iter().all(|c| c.is_finite()) {
                    return Err(MeshError::NotFinite {
                        triangle: t,
                        vertex: v,
                    });
                }
            }
            let [a, b, c] = tri.map(|i| self.vertices[i as usize]);
            let area2 = (b - a).cross(&(c - a)).norm();
            let scale = (b - a).norm().max((c - a).norm()).max((c - b).norm());
            if tri[0] == tri[1]
                || tri[1] == tri[2]
                || tri[0] == tri[2]
                || area2 <= 1e-12 * scale * scale
            {
                report.degenerate.push(t);
                continue;
            }
            keep.push(*tri);
            original.push(t);
        }
        if keep.is_empty() {
            return Err(MeshError::Empty);
        }
        // Duplicates: the same vertex set.
        let mut seen: HashMap<[u32; 3], usize> = HashMap::new();
        for (k, tri) in keep.iter().enumerate() {
            let mut key = *tri;
            key.sort_unstable();
            if let Some(&first) = seen.get(&key) {
                return Err(MeshError::Duplicate {
                    triangle: original[k],
                    first: original[first],
                });
            }
            seen.insert(key, k);
        }
        // Winding: every directed edge appears at most once; an edge used twice in the same
        // direction means the two triangles disagree.
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        let mut undirected: HashMap<(u32, u32), u8> = HashMap::new();
        for (k, tri) in keep.iter().enumerate() {
            for e in 0..3 {
                let (a, b) = (tri[e], tri[(e + 1) % 3]);
                let uses = undirected.entry((a.min(b), a.max(b))).or_insert(0);
                *uses += 1;
                if *uses > 2 {
                    return Err(MeshError::NonManifold {
                        triangle: original[k],
                    });
                }
                if let Some(&other) = directed.get(&(a, b)) {
                    return Err(MeshError::Winding {
                        triangle: original[k],
                        neighbour: original[other],
                    });
                }
                directed.insert((a, b), k);
            }
        }
        self.triangles = keep;
        Ok((self, report))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Mesh {
        Mesh {
            vertices: vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(1.0, 1.0, 0.0),
                Point3::new(0.0, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn a_good_quad_passes_and_faces_up() {
        let (m, r) = quad().checked().unwrap();
        assert_eq!(m.triangles.len(), 2);
        assert!(r.degenerate.is_empty());
        assert_eq!(m.face_normal(0), Vec3::z());
    }

    #[test]
    fn bad_meshes_name_the_triangle() {
        let mut m = quad();
        m.triangles[1] = [0, 3, 2];
        assert_eq!(
            m.checked().unwrap_err(),
            MeshError::Winding {
                triangle: 1,
                neighbour: 0
            }
        );
        let mut m = quad();
        m.triangles.push([2, 0, 1]);
        assert_eq!(
            m.checked().unwrap_err(),
            MeshError::Duplicate {
                triangle: 2,
                first: 0
            }
        );
        let mut m = quad();
        m.vertices[3].x = f64::NAN;
        assert_eq!(
            m.checked().unwrap_err(),
            MeshError::NotFinite {
                triangle: 1,
                vertex: 3
            }
        );
        assert_eq!(Mesh::default().checked().unwrap_err(), MeshError::Empty);
        let mut m = quad();
        m.triangles.push([0, 1, 9]);
        assert!(matches!(
            m.checked(),
            Err(MeshError::BadIndex { triangle: 2, .. })
        ));
    }

    #[test]
    fn degenerate_triangles_are_dropped_and_counted() {
        let mut m = quad();
        m.vertices.push(Point3::new(2.0, 0.0, 0.0));
        m.triangles.push([0, 1, 4]); // collinear
        m.triangles.push([1, 1, 2]); // repeated index
        let (m, r) = m.checked().unwrap();
        assert_eq!(m.triangles.len(), 2);
        assert_eq!(r.degenerate, vec![2, 3]);
    }

    #[test]
    fn corners_are_welded() {
        let p = |x: f64, y: f64| Point3::new(x, y, 0.0);
        let m = Mesh::from_corners(&[
            [p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)],
            [p(0.0, 0.0), p(1.0, 1.0), p(-0.0, 1.0)],
        ]);
        assert_eq!(m.vertices.len(), 4);
        assert_eq!(m.triangles[1], [0, 2, 3]);
    }
}
