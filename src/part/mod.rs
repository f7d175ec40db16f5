//! The design surface of the real part: a triangle mesh ([`Mesh`], read by `crate::io::mesh`)
//! with a bounding-volume hierarchy for the queries the other stages need — the closest part
//! point to any point (with the part's unit normal there, smoothed across the facets) and the
//! first hit of a ray — and the contact data a path gets from it ([`contact`]).
//!
//! The mesh must be in the frame of the tool path as crest reads it (the MCS of a CLSF when
//! MSYS is not applied, the absolute frame with `--absolute`), in mm, with triangles wound
//! counter-clockwise seen from outside the material: normals point out of the part, towards
//! the tool.
//!
//! Queries use parry3d (f64): `TriMesh` and its QBVH.

pub mod contact;
pub mod derive;
mod mesh;
pub mod stitch;

pub use mesh::{Mesh, MeshCheck, MeshError};

use crate::math::{Point3, Vec3};
use parry3d_f64::query::{PointQueryWithLocation, Ray, RayCast};
use parry3d_f64::shape::TriMesh;

/// The design surface, ready for queries.
pub struct Part {
    mesh: Mesh,
    tri: TriMesh,
    /// Unit normal per vertex (area-weighted mean of the faces around it).
    vertex_normals: Vec<Vec3>,
    /// Unit normal per triangle.
    face_normals: Vec<Vec3>,
}

impl std::fmt::Debug for Part {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Part({} vertices, {} triangles)",
            self.mesh.vertices.len(),
            self.mesh.triangles.len()
        )
    }
}

/// The part point nearest to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest {
    /// The part point, mm.
    pub point: Point3,
    /// The part's unit normal there (out of the material), interpolated from the vertex
    /// normals of its triangle.
    pub normal: Vec3,
    /// The triangle it lies on.
    pub triangle: u32,
    /// Distance from the query point, mm.
    pub distance: f64,
    /// The query point's side: positive outside the material (along the normal).
    pub signed_distance: f64,
}

impl Part {
    /// Index a checked mesh (see [`Mesh::checked`]).
    pub fn new(mesh: Mesh) -> Result<Part, MeshError> {
        let (mesh, _) = mesh.checked()?;
        Ok(Part::from_checked(mesh))
    }

    /// Index a mesh that [`Mesh::checked`] has accepted.
    pub fn from_checked(mesh: Mesh) -> Part {
        let face_normals: Vec<Vec3> = (0..mesh.triangles.len())
            .map(|t| mesh.face_normal(t))
            .collect();
        let mut vertex_normals = vec![Vec3::zeros(); mesh.vertices.len()];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|i| mesh.vertices[i as usize]);
            let area2 = (b - a).cross(&(c - a)).norm();
            for &i in tri {
                vertex_normals[i as usize] += face_normals[t] * area2;
            }
        }
        for n in &mut vertex_normals {
            let len = n.norm();
            if len > 0.0 {
                *n /= len;
            }
        }
        let tri = TriMesh::new(mesh.vertices.clone(), mesh.triangles.clone());
        Part {
            mesh,
            tri,
            vertex_normals,
            face_normals,
        }
    }

    /// The mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The axis-aligned bounding box: (min, max) corners, mm.
    pub fn bounds(&self) -> (Point3, Point3) {
        let mut lo = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut hi = Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
        for v in &self.mesh.vertices {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        (lo, hi)
    }

    /// Whether some triangle meets the box between corners `lo` and `hi`.
    pub fn touches_box(&self, lo: &Point3, hi: &Point3) -> bool {
        use parry3d_f64::bounding_volume::Aabb;
        let aabb = Aabb::new(*lo, *hi);
        let mut hits: Vec<u32> = Vec::new();
        self.tri.qbvh().intersect_aabb(&aabb, &mut hits);
        // The QBVH works on the triangles' boxes: confirm with the triangle itself.
        let cuboid = parry3d_f64::shape::Cuboid::new(aabb.half_extents());
        let at = parry3d_f64::math::Isometry::translation(
            aabb.center().x,
            aabb.center().y,
            aabb.center().z,
        );
        let id = parry3d_f64::math::Isometry::identity();
        hits.iter().any(|&t| {
            let tri = self.tri.triangle(t);
            parry3d_f64::query::intersection_test(&id, &tri, &at, &cuboid).unwrap_or(true)
        })
    }

    /// The smoothed unit normal at point `p` of triangle `t` (barycentric blend of the
    /// vertex normals; the face normal where the blend vanishes).
    pub fn normal_at(&self, t: u32, p: &Point3) -> Vec3 {
        let tri = self.mesh.triangles[t as usize];
        let [a, b, c] = tri.map(|i| self.mesh.vertices[i as usize]);
        let w = barycentric(&a, &b, &c, p);
        let n = self.vertex_normals[tri[0] as usize] * w[0]
            + self.vertex_normals[tri[1] as usize] * w[1]
            + self.vertex_normals[tri[2] as usize] * w[2];
        let len = n.norm();
        if len > 1e-9 {
            n / len
        } else {
            self.face_normals[t as usize]
        }
    }

    /// The part point nearest to `p` on the smooth surface the mesh stands for: the nearest
    /// facet point, then moved (a few ray casts) to where `p` lies along the smoothed normal,
    /// so that a point millimetres away does not see the facets' kinks.
    pub fn closest(&self, p: &Point3) -> Closest {
        let (proj, (t, _)) = self.tri.project_local_point_and_get_location(p, false);
        let facet = self.facet_closest(p, proj.point, t);
        let mut best = facet;
        // Phong-like projection: cast from p against the smoothed normal of the current point.
        for _ in 0..4 {
            if best.distance < 1e-12 {
                break;
            }
            let dir = -best.normal * best.signed_distance.signum();
            let reach = 2.0 * best.distance + 1e-6;
            let Some((_, q, n)) = self.ray(p, &dir, reach) else {
                break;
            };
            let d = p - q;
            let next = Closest {
                point: q,
                normal: n,
                triangle: best.triangle,
                distance: d.norm(),
                signed_distance: d.norm().copysign(d.dot(&n)),
            };
            let moved = (next.point - best.point).norm();
            // Accept only a point that stays near the facet projection (same sheet).
            if (next.distance - facet.distance).abs() > 0.01 * facet.distance + 1e-6 {
                break;
            }
            best = next;
            if moved < 1e-10 {
                break;
            }
        }
        best
    }

    fn facet_closest(&self, p: &Point3, point: Point3, t: u32) -> Closest {
        let normal = self.normal_at(t, &point);
        let d = p - point;
        let distance = d.norm();
        // The side: by the face normal (exact for points over the face), falling back to the
        // smoothed normal at edges and vertices.
        let side = d.dot(&self.face_normals[t as usize]);
        let side = if side.abs() > 1e-12 * (1.0 + distance) {
            side
        } else {
            d.dot(&normal)
        };
        Closest {
            point,
            normal,
            triangle: t,
            distance,
            signed_distance: distance.copysign(side),
        }
    }

    /// The first part point on the ray from `origin` along the unit `dir`, within `max_mm`:
    /// (distance along the ray, point, smoothed normal).
    pub fn ray(&self, origin: &Point3, dir: &Vec3, max_mm: f64) -> Option<(f64, Point3, Vec3)> {
        let ray = Ray::new(*origin, *dir);
        let hit = self
            .tri
            .cast_local_ray_and_get_normal(&ray, max_mm, false)?;
        let p = ray.point_at(hit.time_of_impact);
        let t = match hit.feature {
            parry3d_f64::shape::FeatureId::Face(f) => f % self.mesh.triangles.len() as u32,
            _ => self.closest(&p).triangle,
        };
        Some((hit.time_of_impact, p, self.normal_at(t, &p)))
    }

    /// The part point on the line through `origin` along the unit `dir` (either way) nearest
    /// to `origin`, within `max_mm`: (signed distance along `dir`, point, normal).
    pub fn line(&self, origin: &Point3, dir: &Vec3, max_mm: f64) -> Option<(f64, Point3, Vec3)> {
        let fwd = self.ray(origin, dir, max_mm);
        let back = self.ray(origin, &-dir, max_mm).map(|(t, p, n)| (-t, p, n));
        match (fwd, back) {
            (Some(a), Some(b)) => Some(if a.0.abs() <= b.0.abs() { a } else { b }),
            (a, b) => a.or(b),
        }
    }
}

/// Barycentric coordinates of `p` (projected on the triangle's plane) in triangle a, b, c,
/// clamped to the triangle.
fn barycentric(a: &Point3, b: &Point3, c: &Point3, p: &Point3) -> [f64; 3] {
    let v0 = b - a;
    let v1 = c - a;
    let v2 = p - a;
    let d00 = v0.dot(&v0);
    let d01 = v0.dot(&v1);
    let d11 = v1.dot(&v1);
    let d20 = v2.dot(&v0);
    let d21 = v2.dot(&v1);
    let den = d00 * d11 - d01 * d01;
    if den.abs() < 1e-300 {
        return [1.0 / 3.0; 3];
    }
    let v = ((d11 * d20 - d01 * d21) / den).clamp(0.0, 1.0);
    let w = ((d00 * d21 - d01 * d20) / den).clamp(0.0, 1.0);
    let s = (v + w).max(1.0);
    let (v, w) = (v / s, w / s);
    [1.0 - v - w, v, w]
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// A cylinder of radius `r` about the x axis, |x| ≤ `half`, the upper half (z ≥ 0),
    /// `n` facets around the half circle.
    pub(crate) fn half_cylinder(r: f64, half: f64, n: usize) -> Mesh {
        let mut m = Mesh::default();
        for i in 0..=n {
            let phi = std::f64::consts::PI * i as f64 / n as f64;
            let (y, z) = (-r * phi.cos(), r * phi.sin());
            m.vertices.push(Point3::new(-half, y, z));
            m.vertices.push(Point3::new(half, y, z));
        }
        for i in 0..n as u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            // Outward normals (away from the axis).
            m.triangles.push([a, b, c]);
            m.triangles.push([b, d, c]);
        }
        m
    }

    #[test]
    fn closest_point_and_normal_on_a_fine_cylinder() {
        let part = Part::new(half_cylinder(20.0, 5.0, 2000)).unwrap();
        let phi = 1.2f64;
        let q = Point3::new(0.3, -25.0 * phi.cos(), 25.0 * phi.sin());
        let c = part.closest(&q);
        let exact = Point3::new(0.3, -20.0 * phi.cos(), 20.0 * phi.sin());
        // The facets (π/2000 apart) sag by 6 nm; the point 5 mm out lands within 0.1 µm of
        // the exact cylinder (the contact requirement is 1 µm), the normal within 1e-4 rad (0.006°;
        // the requirement is 0.1°).
        assert!((c.point - exact).norm() < 1e-4, "{:?}", c.point);
        let n = Vec3::new(0.0, -phi.cos(), phi.sin());
        assert!(c.normal.angle(&n) < 1e-4, "{}", c.normal.angle(&n));
        assert_relative_eq!(c.signed_distance, 5.0, epsilon = 1e-5);
        let inside = part.closest(&Point3::new(0.0, 0.0, 19.0));
        assert_relative_eq!(inside.signed_distance, -1.0, epsilon = 1e-4);
    }

    #[test]
    fn lines_hit_the_part_either_way() {
        let part = Part::new(half_cylinder(20.0, 5.0, 400)).unwrap();
        let (t, p, n) = part
            .line(&Point3::new(0.0, 0.0, 25.0), &Vec3::z(), 100.0)
            .unwrap();
        assert_relative_eq!(t, -5.0, epsilon = 1e-9);
        assert_relative_eq!(p.z, 20.0, epsilon = 1e-9);
        assert!(n.angle(&Vec3::z()) < 1e-9);
        assert!(
            part.ray(&Point3::new(0.0, 0.0, 25.0), &Vec3::z(), 100.0)
                .is_none()
        );
    }
}
