//! The known surfaces as parts: a triangle mesh of a surface over a field (and a margin
//! around it), fine enough that the facets stay within a chord tolerance of the surface, for
//! `crest synth --part-stl` and tests that need a design surface.

use super::Surface;
use crate::math::{Point3, Vec3};
use crate::part::Mesh;

/// Largest number of triangles a surface mesh may have.
pub const MAX_TRIANGLES: usize = 20_000_000;

/// Why a surface cannot be meshed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// The chord tolerance is not a positive number, mm.
    #[error("tol_mm (the chord tolerance) must be positive, got {0}")]
    Tolerance(f64),
    /// The mesh would have more than [`MAX_TRIANGLES`] triangles.
    #[error(
        "a mesh within {tol_mm} mm needs {triangles} triangles (more than {MAX_TRIANGLES}); raise the tolerance or shrink the field"
    )]
    TooManyTriangles {
        /// The chord tolerance, mm.
        tol_mm: f64,
        /// Triangles the mesh would have.
        triangles: usize,
    },
}

/// A mesh of `surface` over the field `size_mm` (along the passes, across) centred on the
/// origin with passes at `pass_angle_rad` from +x, widened by `margin_mm` on every side
/// (clipped to where the surface is defined), with facets within `tol_mm` of the surface.
/// Triangles face up (+z), out of the material.
pub fn surface_mesh(
    surface: &Surface,
    size_mm: (f64, f64),
    pass_angle_rad: f64,
    margin_mm: f64,
    tol_mm: f64,
) -> Result<Mesh, MeshError> {
    if !(tol_mm.is_finite() && tol_mm > 0.0) {
        return Err(MeshError::Tolerance(tol_mm));
    }
    let du = Vec3::new(pass_angle_rad.cos(), pass_angle_rad.sin(), 0.0);
    let dv = Vec3::new(-du.y, du.x, 0.0);
    let mut half_u = 0.5 * size_mm.0 + margin_mm;
    let mut half_v = 0.5 * size_mm.1 + margin_mm;
    // Stay where the graph is defined.
    if let Some(r) = surface.radius_mm() {
        let lim = 0.97 * r;
        half_v = half_v.min(lim);
        if matches!(surface, Surface::Sphere { .. }) {
            half_u = half_u.min(lim);
            let h = half_u.min(half_v).min(lim / 2f64.sqrt());
            half_u = h;
            half_v = h;
        }
    }
    // The largest curvature along u and along v over the field sets the spacing of each.
    let (mut ku, mut kv) = (0.0f64, 0.0f64);
    let samples = 33;
    for i in 0..samples {
        for j in 0..samples {
            let u = -half_u + 2.0 * half_u * i as f64 / (samples - 1) as f64;
            let v = -half_v + 2.0 * half_v * j as f64 / (samples - 1) as f64;
            let p = du * u + dv * v;
            let t_u = Vec3::new(du.x, du.y, 0.0);
            let t_v = Vec3::new(dv.x, dv.y, 0.0);
            let (fx, fy) = surface.gradient(p.x, p.y);
            let tu = Vec3::new(t_u.x, t_u.y, fx * t_u.x + fy * t_u.y).normalize();
            let tv = Vec3::new(t_v.x, t_v.y, fx * t_v.x + fy * t_v.y).normalize();
            ku = ku.max(surface.normal_curvature(p.x, p.y, &tu).abs());
            kv = kv.max(surface.normal_curvature(p.x, p.y, &tv).abs());
        }
    }
    // Sag of a chord of length h on curvature κ: κ h²/8.
    let spacing = |k: f64, half: f64| {
        if k > 0.0 {
            (8.0 * tol_mm / k).sqrt().min(2.0 * half)
        } else {
            2.0 * half
        }
    };
    let nu = ((2.0 * half_u / spacing(ku, half_u)).ceil() as usize).max(1);
    let nv = ((2.0 * half_v / spacing(kv, half_v)).ceil() as usize).max(1);
    let triangles = 2usize.saturating_mul(nu).saturating_mul(nv);
    if triangles > MAX_TRIANGLES {
        return Err(MeshError::TooManyTriangles { tol_mm, triangles });
    }
    let mut mesh = Mesh::default();
    for j in 0..=nv {
        for i in 0..=nu {
            let u = -half_u + 2.0 * half_u * i as f64 / nu as f64;
            let v = -half_v + 2.0 * half_v * j as f64 / nv as f64;
            let p = du * u + dv * v;
            mesh.vertices
                .push(Point3::new(p.x, p.y, surface.height(p.x, p.y)));
        }
    }
    let at = |i: usize, j: usize| (j * (nu + 1) + i) as u32;
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            mesh.triangles.push([a, b, c]);
            mesh.triangles.push([a, c, d]);
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::part::Part;

    #[test]
    fn a_cylinder_mesh_is_within_its_tolerance_and_faces_up() {
        let s = Surface::ConvexCylinder { radius_mm: 20.0 };
        let mesh = surface_mesh(&s, (4.0, 4.0), 0.0, 1.0, 1e-5).unwrap();
        // 6 mm across at a chord of √(8 · 1e-5 · 20) = 0.04 mm: 150 rows (151 when the
        // quotient rounds up); along x one.
        assert!(
            (300..=302).contains(&mesh.triangles.len()),
            "{}",
            mesh.triangles.len()
        );
        let part = Part::new(mesh).unwrap();
        for y in [-2.5, -0.7, 0.0, 1.3] {
            let cc = Point3::new(0.1, y, s.height(0.1, y));
            let n = s.normal(0.1, y);
            let c = part.closest(&(cc + n));
            // The facets sag by at most the 0.01 µm tolerance.
            assert!(
                (c.signed_distance - 1.0).abs() < 1.1e-5,
                "{y}: {}",
                c.signed_distance
            );
            assert!((c.point - cc).norm() < 1e-4, "{y}: {:?}", c.point);
            assert!(c.normal.angle(&n) < 1e-4);
        }
    }
}
