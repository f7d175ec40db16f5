//! `crest contact`: contact data for a centre-line path — for every cutting posture the
//! point where the cutter touches the part and the part's normal there (from the design
//! surface, or derived from the path when no part is given) — with the deepest gouge and
//! the largest air gap.

use crate::io::mesh::read_part;
use crate::math::{Point3, Vec3};
use crate::part::contact::touch_all;
use crate::part::derive::Inconsistency;
use crate::pipeline::{Error, Result};
use crate::toolpath::{Contact, LowerOptions, MotionKind, Moves, Program};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Default distance within which a cutter touches the part, µm.
pub const DEFAULT_TOLERANCE_UM: f64 = 20.0;

/// Everything `crest contact` is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactRequest {
    /// Tool-path file.
    pub file: PathBuf,
    /// The design surface; `None` derives the contacts from the path.
    pub part: Option<PathBuf>,
    /// `tool.toml`; the file's TLDATA when `None`.
    pub tool: Option<PathBuf>,
    /// Teeth of a TLDATA tool.
    pub teeth: Option<usize>,
    /// Apply MSYS to the path (the part is then in the absolute frame).
    pub absolute: bool,
    /// A cutting posture whose cutter is farther than this from the part gets no contact, µm.
    pub tolerance_um: f64,
    /// Which moves cut (get contact data).
    pub moves: Moves,
}

/// The path with contact data, and what was found.
#[derive(Debug, Clone)]
pub struct ContactRun {
    /// The program, postures carrying the contact data found.
    pub program: Program,
    /// Cutting postures.
    pub postures: usize,
    /// Cutting postures that got a contact.
    pub with_contact: usize,
    /// Cutting postures whose derived contact was inconsistent with the cutter (left out).
    pub inconsistent: usize,
    /// Deepest penetration of the cutter into the part, µm (0 when none).
    pub max_gouge_um: f64,
    /// Largest cutter-to-part distance of a cutting posture, µm (0 when none).
    pub max_gap_um: f64,
    /// Where the tool came from.
    pub tool_source: String,
    /// Where the contacts came from.
    pub source: &'static str,
    /// Non-fatal findings.
    pub warnings: Vec<String>,
}

/// Compute the contact data of `req.file`.
pub fn contact(req: &ContactRequest) -> Result<ContactRun> {
    if !(req.tolerance_um.is_finite() && req.tolerance_um >= 0.0) {
        return Err(Error::field(
            "tolerance_um",
            format!("must be a non-negative number, got {}", req.tolerance_um),
        ));
    }
    let lower = LowerOptions {
        apply_msys: req.absolute,
        ..Default::default()
    };
    let mut program = crate::io::toolpath::read_program_with(&req.file, lower)?;
    // `--moves all`: every feed move cuts while the contacts are found; the kinds are
    // given back before the path is written.
    let kinds: Vec<Vec<MotionKind>> = program
        .paths
        .iter()
        .map(|p| p.postures.iter().map(|q| q.motion).collect())
        .collect();
    req.moves.apply(&mut program);
    let (cutter, tool_source, mut warnings) = super::inputs::resolve_cutter(
        req.tool
            .clone()
            .map(super::inputs::ToolSource::File)
            .as_ref(),
        &program,
        &req.file,
        req.teeth,
        None,
    )?;
    // A cutting posture: one a cutting move ends at (the posture a run starts from is
    // where the tool comes from, often above the part).
    let is_cut =
        |path: &crate::toolpath::Toolpath, i: usize| path.postures[i].motion == MotionKind::Cut;
    let postures: usize = program
        .paths
        .iter()
        .map(|p| (0..p.postures.len()).filter(|&i| is_cut(p, i)).count())
        .sum();
    if postures == 0 {
        return Err(Error::Input(format!(
            "{}: the file has no cutting moves",
            req.file.display()
        )));
    }
    let tol = req.tolerance_um * 1e-3;
    let (mut gouge, mut gap, mut with_contact) = (0.0f64, 0.0f64, 0usize);
    let mut inconsistent = 0;
    let source = match &req.part {
        Some(part_path) => {
            let f = read_part(part_path)?;
            warnings.extend(f.warnings);
            let part = f.part;
            if !crate::part::contact::touch_supported(&cutter) {
                return Err(Error::Request(format!(
                    "{}: contact points from a part need a ball, torus, flat or round-insert cutter; the {} has no closed-form core (leave out ‹part› to derive the contacts from the path)",
                    part_path.display(),
                    cutter.describe()
                )));
            }
            check_orientation(&part, &program, &cutter, part_path)?;
            for path in &mut program.paths {
                let cut: Vec<bool> = (0..path.postures.len()).map(|i| is_cut(path, i)).collect();
                let poses: Vec<Option<(Point3, Vec3)>> = path
                    .postures
                    .iter()
                    .zip(&cut)
                    .map(|(p, &c)| c.then_some((p.position, p.axis)))
                    .collect();
                let found = touch_all(&part, &cutter, &poses);
                for (p, f) in path.postures.iter_mut().zip(found) {
                    let Some(t) = f else { continue };
                    let (cc, n, clear) = (t.cc, t.normal, t.clearance_mm);
                    gouge = gouge.max(-clear);
                    gap = gap.max(clear);
                    if clear <= tol {
                        p.contact = Some(Contact {
                            point: cc,
                            normal: n,
                            normal_derived: false,
                        });
                        with_contact += 1;
                    } else {
                        p.contact = None;
                    }
                }
            }
            "part"
        }
        None => {
            for path in &mut program.paths {
                for p in &mut path.postures {
                    p.contact = None;
                }
            }
            let found = derive_contacts(&mut program, &cutter);
            with_contact = found.with_contact;
            inconsistent = found.inconsistent.len();
            warnings.extend(found.summary());
            "derived from the path"
        }
    };
    for (path, k) in program.paths.iter_mut().zip(&kinds) {
        for (p, m) in path.postures.iter_mut().zip(k) {
            p.motion = *m;
        }
    }
    Ok(ContactRun {
        program,
        postures,
        with_contact,
        inconsistent,
        max_gouge_um: gouge.max(0.0) * 1e3,
        max_gap_um: gap.max(0.0) * 1e3,
        tool_source,
        source,
        warnings,
    })
}

/// The part's normals must face the tool: most tool centres lie outside the material.
fn check_orientation(
    part: &crate::part::Part,
    program: &Program,
    cutter: &crate::tool::Cutter,
    file: &Path,
) -> Result<()> {
    let rc = cutter.corner_radius_mm();
    let (mut out, mut inside) = (0usize, 0usize);
    for p in program
        .paths
        .iter()
        .flat_map(|t| t.postures.iter())
        .filter(|p| p.motion == MotionKind::Cut)
        .step_by(17)
        .take(400)
    {
        let c = part.closest(&(p.position + p.axis * rc));
        if c.signed_distance >= 0.0 {
            out += 1;
        } else {
            inside += 1;
        }
    }
    if inside > 3 * out.max(1) {
        return Err(Error::Input(format!(
            "{}: the tool lies behind the part's faces at {inside} of {} sampled postures: its triangles face into the material (reverse their winding), or the part is not in the path's frame (crest reads the path in the MCS; ‹absolute› applies MSYS)",
            file.display(),
            inside + out
        )));
    }
    Ok(())
}

/// Thinning cell of the offset points when contacts are derived from the path, mm.
pub const DERIVE_CELL_MM: f64 = 0.1;

/// What deriving contacts from the path found.
#[derive(Debug, Clone, Default)]
pub struct DerivedContacts {
    /// Cutting postures that got a contact.
    pub with_contact: usize,
    /// The postures that got a contact: (path, posture).
    pub given: Vec<(usize, usize)>,
    /// Cutting postures whose derived contact is inconsistent with the cutter and was left
    /// out: (path, posture, why).
    pub inconsistent: Vec<(usize, usize, Inconsistency)>,
}

impl DerivedContacts {
    /// A warning counting the inconsistent contacts by reason, when there are any.
    pub fn summary(&self) -> Option<String> {
        if self.inconsistent.is_empty() {
            return None;
        }
        let mut by: BTreeMap<Inconsistency, usize> = BTreeMap::new();
        for (_, _, why) in &self.inconsistent {
            *by.entry(*why).or_default() += 1;
        }
        let reasons: Vec<String> = by
            .iter()
            .map(|(why, n)| format!("{n}: {}", why.describe()))
            .collect();
        Some(format!(
            "{} of {} contacts derived from the path are inconsistent with the cutter and were left out ({}); heights near them need the part (‹part› PART.stl)",
            self.inconsistent.len(),
            self.with_contact + self.inconsistent.len(),
            reasons.join("; ")
        ))
    }

    /// A failed check when postures left out as inconsistent reach the grid of `sim`: the
    /// reference surface there is not the one the cutter touched. A posture reaches it
    /// when its lowest point along the grid's normal (its contact, were the surface level
    /// there) lies over the grid and within `TOUCH_MM` of its plane.
    pub fn reaching(
        &self,
        sim: &crate::surface::Simulation,
        program: &Program,
        paths: &[usize],
        cutter: &crate::tool::Cutter,
    ) -> Option<String> {
        const TOUCH_MM: f64 = 0.5;
        let (centre, w) = sim.node_point(sim.map.nx / 2, sim.map.ny / 2);
        let half =
            0.5e-3 * (sim.map.nx as f64 * sim.map.dx_um).hypot(sim.map.ny as f64 * sim.map.dy_um);
        let rc = cutter.corner_radius_mm();
        let rd = cutter.radius_mm - rc;
        let reaching: Vec<_> = self
            .inconsistent
            .iter()
            .filter(|(pi, _, _)| paths.contains(pi))
            .filter(|(pi, i, _)| {
                let p = &program.paths[*pi].postures[*i];
                let a = p.axis.normalize();
                let lowest =
                    p.position + a * rc + crate::part::derive::radial(&w, &a) * rd - w * rc;
                let d = lowest - centre;
                let up = d.dot(&w);
                up.abs() <= TOUCH_MM && (d - w * up).norm() <= half + TOUCH_MM
            })
            .collect();
        let (pi, i, why) = reaching.first()?;
        let p = &program.paths[*pi].postures[*i];
        Some(format!(
            "{} postures whose derived contact is inconsistent reach the grid (the first at {:.4},{:.4},{:.4}: {}): the reference surface there is not the one the cutter touched; give the part (‹part› PART.stl)",
            reaching.len(),
            p.position.x,
            p.position.y,
            p.position.z,
            why.describe()
        ))
    }
}

/// Give every cutting posture of `program` that has no contact data the contact derived
/// from the path (see [`crate::part::derive`]); inconsistent ones are left out and listed.
pub fn derive_contacts(program: &mut Program, cutter: &crate::tool::Cutter) -> DerivedContacts {
    let mut out = DerivedContacts::default();
    for (pi, path) in program.paths.iter_mut().enumerate() {
        let idx: Vec<usize> = (0..path.postures.len())
            .filter(|&i| {
                let p = &path.postures[i];
                p.contact.is_none() && p.motion == MotionKind::Cut
            })
            .collect();
        let poses: Vec<(Point3, Vec3)> = idx
            .iter()
            .map(|&i| (path.postures[i].position, path.postures[i].axis))
            .collect();
        // A posture follows the one before along a cut move when they are neighbours.
        let joined: Vec<bool> = idx
            .iter()
            .enumerate()
            .map(|(k, &i)| k > 0 && idx[k - 1] + 1 == i)
            .collect();
        let got = crate::part::derive::derive(cutter, &poses, &joined, DERIVE_CELL_MM);
        for (k, &i) in idx.iter().enumerate() {
            if let Some((point, normal)) = got.contacts[k] {
                path.postures[i].contact = Some(Contact {
                    point,
                    normal,
                    normal_derived: true,
                });
                out.with_contact += 1;
                out.given.push((pi, i));
            }
            if let Some(why) = got.flags[k] {
                out.inconsistent.push((pi, i, why));
            }
        }
    }
    out
}

/// The surface the contacts of `program` describe, as a mesh ([`crate::part::stitch`]): each
/// run of cutting postures is a pass; a posture without a contact leaves a hole.
pub fn contact_mesh(program: &Program) -> crate::part::stitch::Stitched {
    let mut runs: Vec<Vec<Option<(Point3, Vec3)>>> = Vec::new();
    for path in &program.paths {
        let mut run = Vec::new();
        for p in &path.postures {
            if p.motion == MotionKind::Cut {
                run.push(p.contact.as_ref().map(|c| (c.point, c.normal)));
            } else if !run.is_empty() {
                runs.push(std::mem::take(&mut run));
            }
        }
        if !run.is_empty() {
            runs.push(run);
        }
    }
    crate::part::stitch::stitch(&runs)
}
