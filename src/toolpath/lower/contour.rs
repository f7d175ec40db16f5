//! NX contact-contour data (`$$ contact contour data`): GOTO positions are the points where
//! the cutter touches the part, not tool tips. With the surface normal there (a 12-number
//! GOTO, or a `CONTACT/x,y,z,nx,ny,nz` record after it) and the cutter (`TLDATA/MILL` or
//! `CUTTER/`), the tip is rebuilt exactly: tip = cc + n·rc − a·rc − w·(R − rc), w the unit
//! radial direction from the axis to the corner circle (−n without its axial part).
//! Without them the position is read as the tip and a warning says what is missing.

use super::Lowerer;
use crate::math::{Point3, Vec3, normalize_or_none};
use crate::toolpath::{Contact, MotionKind, Posture, ToolData};

/// The tool tip of a cutter touching at `cc` with unit normal `n` (out of the material,
/// towards the cutter) and unit tool axis `a`.
pub fn tip_from_contact(tool: &ToolData, cc: &Point3, n: &Vec3, a: &Vec3) -> Point3 {
    let big_r = 0.5 * tool.diameter_mm;
    let rc = tool.corner_radius_mm.clamp(0.0, big_r.max(0.0));
    let rd = big_r - rc;
    let radial = n - a * n.dot(a);
    let w = normalize_or_none(&radial, 1e-12).map_or_else(Vec3::zeros, |r| -r);
    cc + n * rc - a * rc - w * rd
}

impl Lowerer {
    /// Turn the pending posture of a contact-contour GOTO into a tool tip with its contact
    /// data (see the module docs).
    pub(super) fn contact_contour_tip(&mut self, p: &mut Posture) {
        let given = p.contact.take().filter(|c| !c.normal_derived);
        let cutting = matches!(p.motion, MotionKind::Cut | MotionKind::Cycle);
        let Some(c) = given else {
            if cutting {
                self.warn(
                    "contact-contour-normal",
                    p.line,
                    1,
                    "contact contour data: the GOTO gives a contact point without its surface normal (give GOTO/x,y,z,i,j,k,cx,cy,cz,nx,ny,nz or a CONTACT/x,y,z,nx,ny,nz record after it); the tool tip cannot be rebuilt, so the contact point is read as the tool tip".into(),
                );
            }
            return;
        };
        let tool = self.path.as_ref().and_then(|t| t.tool.clone());
        let Some(tool) = tool else {
            self.warn(
                "contact-contour-tool",
                p.line,
                1,
                "contact contour data: rebuilding the tool tip from the contact point and normal needs the cutter (TLDATA/MILL or CUTTER/ before the motion); the contact point is read as the tool tip".into(),
            );
            p.contact = Some(c);
            return;
        };
        let tip = tip_from_contact(&tool, &c.point, &c.normal, &p.axis);
        p.position = tip;
        if let Some(arc) = p.arc.as_mut() {
            // The tip runs on the arc of the same centre and axis through its own end.
            let v = tip - arc.centre;
            let r = (v - arc.axis * arc.axis.dot(&v)).norm();
            if r > 1e-9 {
                arc.radius_mm = r;
            }
        }
        p.contact = Some(Contact {
            point: c.point,
            normal: c.normal,
            normal_derived: false,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn tip_matches_the_synthetic_paths() {
        // The same geometry as `synth::tool_tip`, for a torus, a ball and a flat end.
        for (r, rc) in [(5.0, 1.5), (5.0, 5.0), (4.0, 0.0)] {
            let tool = ToolData {
                kind: "MILL".into(),
                diameter_mm: 2.0 * r,
                corner_radius_mm: rc,
                ..Default::default()
            };
            use crate::tool::{Cutter, Shape};
            let shape = match rc {
                0.0 => Shape::Flat,
                x if x == r => Shape::Ball,
                x => Shape::Torus {
                    corner_radius_mm: x,
                },
            };
            let cutter = Cutter::new(shape, r, 1, 0.0);
            let a = Vec3::new(0.2, -0.1, 1.0).normalize();
            let n = Vec3::new(-0.3, 0.4, 1.0).normalize();
            let cc = Point3::new(1.0, 2.0, 3.0);
            let want = crate::synth::tool_tip(&cutter, &cc, &n, &a);
            assert_relative_eq!(tip_from_contact(&tool, &cc, &n, &a), want, epsilon = 1e-12);
        }
    }

    fn lower(text: &str) -> crate::toolpath::Program {
        let recs = crate::parse::clsf::parse_str(text).unwrap_or_else(|e| panic!("{e}"));
        crate::toolpath::lower_records(&recs, crate::toolpath::LowerOptions::default())
            .unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn contact_points_become_tool_tips() {
        // Ball R 5, axis +Z; contact on the ball at 45° in x: tip = cc + 5 n − 5 a.
        let s = 0.5f64.sqrt();
        let text = format!(
            "TOOL PATH/OP,TOOL,BALL\nTLDATA/MILL,10,5,50,0,0\n$$ Contact Contour Data\nRAPID\nGOTO/0,0,20,0,0,1\nGOTO/1,0,0,0,0,1,1,0,0,{m},0,{s}\nGOTO/2,0,0\nCONTACT/2,0,0,{m},0,{s}\nGOTO/3,0,0\nEND-OF-PATH\n",
            m = -s
        );
        let p = lower(&text);
        let ps = &p.paths[0].postures;
        assert_eq!(ps[0].position, Point3::new(0.0, 0.0, 20.0));
        for (k, x) in [(1, 1.0), (2, 2.0)] {
            assert_relative_eq!(
                ps[k].position,
                Point3::new(x - 5.0 * s, 0.0, 5.0 * s - 5.0),
                epsilon = 1e-12
            );
            let c = ps[k].contact.as_ref().unwrap_or_else(|| panic!("contact"));
            assert!(!c.normal_derived);
            assert_eq!(c.point, Point3::new(x, 0.0, 0.0));
        }
        // The last GOTO has no normal: read as a tip, with a warning that says why.
        assert_eq!(ps[3].position, Point3::new(3.0, 0.0, 0.0));
        assert!(ps[3].contact.is_none());
        assert_eq!(p.warnings.len(), 1, "{:?}", p.warnings);
        assert_eq!(p.warnings[0].at.line, 9);
        assert!(p.warnings[0].message.contains("without its surface normal"));
    }

    #[test]
    fn contact_points_without_a_cutter_are_named() {
        let p = lower(
            "TOOL PATH/OP,TOOL,BALL\n$$ contact contour data\nGOTO/1,0,0,0,0,1,1,0,0,0,0,1\nEND-OF-PATH\n",
        );
        assert_eq!(p.paths[0].postures[0].position, Point3::new(1.0, 0.0, 0.0));
        assert!(
            p.warnings[0].message.contains("needs the cutter"),
            "{:?}",
            p.warnings
        );
    }
}
