//! The patch step of `crest simulate --patch-near`: the patch placed on the surface nearest
//! the point (the part's, else the cut surface's contacts), oriented along the local feed;
//! a point in the air refused with its distance to the surface, and a patch that only
//! engage or retract moves reach flagged.

use super::prepare::Prepared;
use crate::math::{Frame, Point3, Vec3};
use crate::pipeline::{Error, Result};
use crate::resample::Sample;
use crate::surface::{GridFrame, GridSpec};
use crate::toolpath::Moves;

/// A placed patch.
#[derive(Debug, Clone)]
pub struct Placed {
    /// The oriented grid.
    pub grid: GridSpec,
    /// Distance from the point to the cut surface and its tolerance, mm.
    pub distance_mm: Option<(f64, f64)>,
    /// A failed check (the patch is reached by engage and retract moves only).
    pub failed: Option<String>,
}

/// Place a patch of `length_mm` × `width_mm` at the surface point nearest `point`.
pub fn place(
    prep: &Prepared,
    moves: Moves,
    samples: &[Sample],
    point: [f64; 3],
    length_mm: f64,
    width_mm: f64,
) -> Result<Placed> {
    let file = &prep.file;
    let cutter = &prep.cutter;
    let q = Point3::new(point[0], point[1], point[2]);
    let far = 2.0 * cutter.radius_mm;
    let with_part = prep.part.is_some();
    let is_cut = |pi: usize, i: usize| prep.is_cut(pi, i);
    // The cut surface near q: the contacts of the cut moves, else (a part) their CL points.
    let near_cut = super::air::nearest(&prep.program, &prep.paths, &q, far, with_part, is_cut);
    let mut distance_mm = None;
    // A point in the air (on a lead-in arc, a rapid) is refused with its distance.
    if let Some(n) = &near_cut {
        let tol = super::air::tolerance_mm(n, cutter.radius_mm);
        let (d, at) = match &prep.part {
            Some(p) => {
                let c = p.closest(&q).point;
                ((c - q).norm(), c)
            }
            None => (n.off_surface_mm(cutter.radius_mm), n.point),
        };
        distance_mm = Some((d, tol));
        // `--moves all` simulates as crest did before (a patch reached by engage or
        // retract moves only is then a failed check, below).
        if d > tol && moves == Moves::Cut {
            return Err(Error::Request(format!(
                "{file}: ‹patch_near› {},{},{} is {d:.3} mm from the surface the cut moves define (off it along its normal; nearest point {:.4},{:.4},{:.4}), more than the tolerance {tol:.3} mm (the larger of {} mm and {} × the local stepover{}): the point is in the air, on an approach, engage or retract move or a rapid; pick a point on a finishing region (`crest inspect ‹regions›` lists them), or simulate every feed move with ‹moves› all",
                point[0],
                point[1],
                point[2],
                at.x,
                at.y,
                at.z,
                super::air::MIN_TOLERANCE_MM,
                super::air::STEPOVERS,
                n.stepover_mm.map_or_else(
                    || format!(
                        ", unknown: the tool radius {} mm stands for it",
                        cutter.radius_mm
                    ),
                    |s| format!(" {s:.3} mm")
                ),
            )));
        }
    }
    let (centre, normal) = match &prep.part {
        Some(p) => {
            let c = p.closest(&q);
            (c.point, c.normal)
        }
        None => {
            let best = samples
                .iter()
                .filter_map(|s| Some((s.contact?, s.normal?)))
                .min_by(|a, b| (a.0 - q).norm().total_cmp(&(b.0 - q).norm()));
            let Some(b) = best else {
                return Err(Error::Request(format!(
                    "{file}: no contact point near {},{},{}",
                    point[0], point[1], point[2]
                )));
            };
            b
        }
    };
    // With every feed move simulated: is the patch reached by cut moves at all?
    let mut failed = None;
    if moves == Moves::All
        && let Some((_, tol)) = distance_mm
    {
        let was_cut = |pi: usize, i: usize| prep.cut_kinds[pi][i];
        let cut_only =
            super::air::nearest(&prep.program, &prep.paths, &centre, far, with_part, was_cut);
        let away = cut_only.map_or(f64::INFINITY, |c| c.distance_mm);
        if away > tol {
            failed = Some(format!(
                "the patch at {:.4},{:.4},{:.4} is reached by engage and retract moves only ({}): its heights are those of lead-in or lead-out arcs, not of the finishing passes",
                centre.x,
                centre.y,
                centre.z,
                if away.is_finite() {
                    format!("the nearest cut move's surface is {away:.3} mm away")
                } else {
                    "the path has no cut move".to_string()
                }
            ));
        }
    }
    // The patch centre must lie within the tool radius of the cutter somewhere.
    let rc = cutter.corner_radius_mm();
    let near = samples
        .iter()
        .map(|s| ((s.position + s.axis * rc) - centre).norm() - rc)
        .fold(f64::INFINITY, f64::min);
    if near > cutter.radius_mm {
        return Err(Error::Request(format!(
            "{file}: the patch centre {:.4},{:.4},{:.4} is {near:.3} mm from the nearest cutter position, farther than the tool radius {} mm: the path does not cut there",
            centre.x, centre.y, centre.z, cutter.radius_mm
        )));
    }
    let feed = samples
        .iter()
        .min_by(|a, b| {
            (a.position - centre)
                .norm()
                .total_cmp(&(b.position - centre).norm())
        })
        .map_or_else(Vec3::x, |s| s.feed_dir);
    let f = Frame::tool(&normal, &feed);
    Ok(Placed {
        grid: GridSpec::Oriented {
            frame: GridFrame {
                origin: centre,
                u: f.x,
                v: f.y,
                w: f.z,
            },
            length_mm,
            width_mm,
        },
        distance_mm,
        failed,
    })
}
