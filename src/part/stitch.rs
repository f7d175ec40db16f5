//! The surface a path's contact points describe, as a triangle mesh: each run of contact
//! points (a pass) is stitched to the run before it, so that a surface derived from the
//! path can be written as an STL (`crest contact FILE -o part.stl`) and given as `--part`
//! where no CAD export is at hand.
//!
//! Two runs are zipped together from their nearest ends (a zig-zag pass runs the other
//! way), each step taking the shorter diagonal. A posture without a contact leaves a hole:
//! no triangle spans it. A triangle is left out when it bridges a
//! gap rather than a pass spacing: when its corner across from the pass edge lies more than
//! [`MAX_SPACINGS`] median spacings away, or when it is turned more than
//! [`MAX_TURN_DEG`] from the normals at its corners. Each strip between two runs is wound
//! so that most of its triangles face the tool (the contact normals' side), as `Part`
//! expects; a triangle of it facing the other way is a fold and is left out too.

use super::Mesh;
use crate::math::{Point3, Vec3};

/// A triangle whose height across the pass is more than this many median pass spacings is
/// left out (it bridges a gap).
pub const MAX_SPACINGS: f64 = 3.0;
/// A triangle turned more than this from the contact normals at its corners is left out,
/// degrees.
pub const MAX_TURN_DEG: f64 = 30.0;

/// The mesh and how many triangles were left out as bridges.
#[derive(Debug, Clone, Default)]
pub struct Stitched {
    /// The surface.
    pub mesh: Mesh,
    /// Triangles left out.
    pub left_out: usize,
}

/// A candidate triangle: its corners (indices), its height across the pass, and whether
/// it spans a posture without a contact.
struct Candidate {
    corners: [u32; 3],
    across: f64,
    hole: bool,
    /// The pair of runs it joins.
    strip: usize,
}

/// A point of a run: its vertex, and whether a posture without a contact lies between it
/// and the point before.
#[derive(Clone, Copy)]
struct Node {
    vertex: u32,
    gap_before: bool,
}

/// Stitch neighbouring runs (passes: per posture its contact point and unit normal, `None`
/// where it has none) into a mesh.
pub fn stitch(runs: &[Vec<Option<(Point3, Vec3)>>]) -> Stitched {
    let mut vertices: Vec<Point3> = Vec::new();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut nodes: Vec<Vec<Node>> = Vec::with_capacity(runs.len());
    for run in runs {
        let mut list = Vec::new();
        let mut gap = false;
        for c in run {
            match c {
                Some((p, n)) => {
                    list.push(Node {
                        vertex: vertices.len() as u32,
                        gap_before: gap && !list.is_empty(),
                    });
                    vertices.push(*p);
                    normals.push(*n);
                    gap = false;
                }
                None => gap = true,
            }
        }
        nodes.push(list);
    }
    let mut candidates: Vec<Candidate> = Vec::new();
    for k in 1..nodes.len() {
        let (a, b) = (&nodes[k - 1], &nodes[k]);
        if a.len() < 2 || b.len() < 2 {
            continue;
        }
        let d = |i: u32, j: u32| (vertices[i as usize] - vertices[j as usize]).norm();
        let (a0, a1) = (a[0].vertex, a[a.len() - 1].vertex);
        let (b0, b1) = (b[0].vertex, b[b.len() - 1].vertex);
        // Run b the same way as a (a gap then lies before the other point of the pair).
        let b: Vec<Node> = if d(a0, b1) + d(a1, b0) < d(a0, b0) + d(a1, b1) {
            (0..b.len())
                .rev()
                .map(|i| Node {
                    vertex: b[i].vertex,
                    gap_before: i + 1 < b.len() && b[i + 1].gap_before,
                })
                .collect()
        } else {
            b.clone()
        };
        let first = candidates.len();
        zip(&vertices, a, &b, &mut candidates);
        for c in &mut candidates[first..] {
            c.strip = k;
        }
    }
    // A strip is wound one way: the way most of its triangles face the tool. A triangle
    // facing the other way is a fold and is left out.
    let facing = |c: &Candidate| {
        let [i, j, k] = c.corners.map(|v| v as usize);
        let n = (vertices[j] - vertices[i]).cross(&(vertices[k] - vertices[i]));
        n.dot(&(normals[i] + normals[j] + normals[k]))
    };
    let mut votes = vec![0i64; nodes.len()];
    for c in &candidates {
        votes[c.strip] += if facing(c) >= 0.0 { 1 } else { -1 };
    }
    // The median height across: the pass spacing.
    let mut across: Vec<f64> = candidates
        .iter()
        .map(|c| c.across)
        .filter(|v| v.is_finite())
        .collect();
    across.sort_by(f64::total_cmp);
    let spacing = across.get(across.len() / 2).copied().unwrap_or(0.0);
    let cos_turn = MAX_TURN_DEG.to_radians().cos();
    let mut mesh = Mesh {
        vertices,
        triangles: Vec::with_capacity(candidates.len()),
    };
    let mut left_out = 0;
    for c in candidates {
        let [i, j, k] = c.corners.map(|v| v as usize);
        let (p, q, r) = (mesh.vertices[i], mesh.vertices[j], mesh.vertices[k]);
        let Some(n) = crate::math::normalize_or_none(&(q - p).cross(&(r - p)), 1e-15) else {
            left_out += 1;
            continue;
        };
        let mean = normals[i] + normals[j] + normals[k];
        let (n, corners) = if votes[c.strip] >= 0 {
            (n, c.corners)
        } else {
            (-n, [c.corners[0], c.corners[2], c.corners[1]])
        };
        let fold = n.dot(&mean) < 0.0;
        let turned = [i, j, k].iter().any(|&v| n.dot(&normals[v]) < cos_turn);
        if c.hole || fold || c.across > MAX_SPACINGS * spacing || turned {
            left_out += 1;
            continue;
        }
        mesh.triangles.push(corners);
    }
    Stitched { mesh, left_out }
}

/// Zip runs `a` and `b` (the same way round) into triangles, starting from the nearest
/// pair at their starts and taking the shorter diagonal at each step.
fn zip(v: &[Point3], a: &[Node], b: &[Node], out: &mut Vec<Candidate>) {
    let d = |i: u32, j: u32| (v[i as usize] - v[j as usize]).norm();
    // Start where the runs overlap: skip the part of one that lies before the other.
    let nearest = |from: u32, run: &[Node]| {
        (0..run.len())
            .min_by(|&x, &y| d(from, run[x].vertex).total_cmp(&d(from, run[y].vertex)))
            .unwrap_or(0)
    };
    let (mut i, mut j) = {
        let ja = nearest(a[0].vertex, b);
        let ib = nearest(b[0].vertex, a);
        if d(a[0].vertex, b[ja].vertex) <= d(b[0].vertex, a[ib].vertex) {
            (0, ja)
        } else {
            (ib, 0)
        }
    };
    // Height of `apex` across the edge (e0, e1).
    let height = |e0: u32, e1: u32, apex: u32| {
        let (p, q, r) = (v[e0 as usize], v[e1 as usize], v[apex as usize]);
        let e = q - p;
        let len = e.norm();
        if len <= 1e-15 {
            return (r - p).norm();
        }
        e.cross(&(r - p)).norm() / len
    };
    while i + 1 < a.len() || j + 1 < b.len() {
        let advance_a = if i + 1 >= a.len() {
            false
        } else if j + 1 >= b.len() {
            true
        } else {
            d(a[i + 1].vertex, b[j].vertex) <= d(a[i].vertex, b[j + 1].vertex)
        };
        if advance_a {
            let (p, q, r) = (a[i].vertex, a[i + 1].vertex, b[j].vertex);
            out.push(Candidate {
                corners: [p, q, r],
                across: height(p, q, r),
                hole: a[i + 1].gap_before,
                strip: 0,
            });
            i += 1;
        } else {
            let (p, q, r) = (a[i].vertex, b[j + 1].vertex, b[j].vertex);
            out.push(Candidate {
                corners: [p, q, r],
                across: height(r, q, p),
                hole: b[j + 1].gap_before,
                strip: 0,
            });
            j += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Passes over the cylinder z = sqrt(r² − y²) along x, zig-zag, at every `dy` of y.
    fn cylinder_runs(r: f64, dy: f64, passes: usize) -> Vec<Vec<Option<(Point3, Vec3)>>> {
        (0..passes)
            .map(|k| {
                let y = (k as f64 - passes as f64 / 2.0) * dy;
                let z = (r * r - y * y).sqrt();
                let n = Vec3::new(0.0, y / r, z / r);
                let mut run: Vec<Option<(Point3, Vec3)>> = (0..=20)
                    .map(|i| Some((Point3::new(i as f64 * 0.5, y, z), n)))
                    .collect();
                if k % 2 == 1 {
                    run.reverse();
                }
                run
            })
            .collect()
    }

    #[test]
    fn zig_zag_passes_make_a_surface_facing_the_tool() {
        let runs = cylinder_runs(20.0, 0.5, 8);
        let s = stitch(&runs);
        assert_eq!(s.left_out, 0);
        // 7 strips of 20 quads, two triangles each.
        assert_eq!(s.mesh.triangles.len(), 7 * 40);
        for t in 0..s.mesh.triangles.len() {
            let n = s.mesh.face_normal(t);
            assert!(n.z > 0.9, "triangle {t}: {n:?}");
        }
        // Every vertex lies on the cylinder, every triangle within the chord error of it
        // (0.5² / (8 · 20) = 1.6 µm).
        for tri in &s.mesh.triangles {
            let c = tri
                .iter()
                .map(|&i| s.mesh.vertices[i as usize].coords)
                .sum::<Vec3>()
                / 3.0;
            let off = 20.0 - (c.y * c.y + c.z * c.z).sqrt();
            assert!((0.0..2e-3).contains(&off), "{off}");
        }
    }

    #[test]
    fn a_gap_between_regions_is_not_bridged() {
        let mut runs = cylinder_runs(20.0, 0.5, 4);
        // A second region 10 mm across the passes.
        for run in cylinder_runs(20.0, 0.5, 4) {
            runs.push(
                run.into_iter()
                    .map(|c| c.map(|(p, n)| (p + Vec3::new(0.0, 10.0, 0.0), n)))
                    .collect(),
            );
        }
        let s = stitch(&runs);
        assert!(s.left_out >= 20, "{}", s.left_out);
        assert_eq!(s.mesh.triangles.len(), 6 * 40);
    }

    #[test]
    fn a_posture_without_contact_leaves_a_hole() {
        let mut runs = cylinder_runs(20.0, 0.5, 3);
        runs[1][10] = None;
        let s = stitch(&runs);
        // The two edges of pass 1 around the missing point are each in one triangle of
        // either strip: four triangles fewer, and the mesh reads back as a surface.
        assert_eq!(s.mesh.triangles.len(), 2 * 40 - 4, "{}", s.left_out);
        assert!(s.mesh.clone().checked().is_ok());
    }
}
