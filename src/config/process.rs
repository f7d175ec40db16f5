//! `process.toml`: the cutting parameters of a run (spindle speed, feed, feed per tooth,
//! depth of cut, and the informative stepover, lead and tilt), units in the key names.
//!
//! ```toml
//! rpm = 15000.0
//! fz_mm = 0.05
//! feed_mm_min = 3000.0
//! ap_mm = 0.2
//! ae_mm = 0.2
//! lead_deg = 15.0
//! tilt_deg = 0.0
//! # process effects beyond geometry (docs/process-effects.md), all off by default:
//! min_chip_um = 2.0          # minimum uncut chip thickness h_min (ploughing)
//! recovery = 1.0             # fraction of a ploughed layer that springs back (0..1)
//! texture_sq_um = 0.1        # seeded Gaussian texture: Sq,
//! texture_corr_um = 20.0     # correlation length (autocorrelation exp(-r²/ℓ²)),
//! texture_seed = 1           # and seed
//! ```
//!
//! Every key is optional; unknown keys and impossible values are rejected with the 1-based
//! line and column of the offending key or value.

use super::ConfigError;
use serde::Deserialize;
use toml::Spanned;

/// The `process.toml` document, values checked (units in the names).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProcessConfig {
    /// Spindle speed, rpm.
    pub rpm: Option<f64>,
    /// Feed per tooth, mm.
    pub fz_mm: Option<f64>,
    /// Feed, mm/min.
    pub feed_mm_min: Option<f64>,
    /// Depth of cut, mm (the stock above the nominal surface).
    pub ap_mm: Option<f64>,
    /// Stepover (radial engagement), mm. Informative: the path sets it.
    pub ae_mm: Option<f64>,
    /// Lead angle, degrees. Informative: the path's tool axis sets it.
    pub lead_deg: Option<f64>,
    /// Side tilt angle, degrees. Informative: the path's tool axis sets it.
    pub tilt_deg: Option<f64>,
    /// Minimum uncut chip thickness, µm.
    pub min_chip_um: Option<f64>,
    /// Elastic recovery of a ploughed layer, 0..1.
    pub recovery: Option<f64>,
    /// Texture Sq, µm.
    pub texture_sq_um: Option<f64>,
    /// Texture correlation length, µm.
    pub texture_corr_um: Option<f64>,
    /// Texture seed.
    pub texture_seed: Option<u64>,
}

/// The process-effect keys shared by `process.toml` and a study's `[process]` table.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EffectsFile {
    /// h_min, µm.
    pub min_chip_um: Option<Spanned<f64>>,
    /// 0..1.
    pub recovery: Option<Spanned<f64>>,
    /// µm.
    pub texture_sq_um: Option<Spanned<f64>>,
    /// µm.
    pub texture_corr_um: Option<Spanned<f64>>,
    /// Seed.
    pub texture_seed: Option<Spanned<i64>>,
}

/// Default texture correlation length when only `texture_sq_um` is given, µm.
pub const DEFAULT_TEXTURE_CORR_UM: f64 = 20.0;

impl EffectsFile {
    /// Check the values (errors at their line and column) and build the engine's
    /// [`crate::surface::Process`]; `tool_min_chip_mm` (edge radius × ratio of the tool file)
    /// is h_min when `min_chip_um` is absent.
    pub fn to_process(
        &self,
        text: &str,
        file: &str,
        tool_min_chip_mm: Option<f64>,
    ) -> Result<crate::surface::Process, ConfigError> {
        let at = |v: &Spanned<f64>, m: String| ConfigError::at(file, text, v.span().start, m);
        let get = |key: &str, v: &Option<Spanned<f64>>, lo: f64, hi: f64, open_lo: bool| match v {
            None => Ok(None),
            Some(s) => {
                let x = *s.get_ref();
                let ok = x.is_finite() && x <= hi && if open_lo { x > lo } else { x >= lo };
                if ok {
                    Ok(Some(x))
                } else {
                    let lo_s = if open_lo { ">" } else { "≥" };
                    Err(at(
                        s,
                        format!("{key} must be {lo_s} {lo} and ≤ {hi}, got {x}"),
                    ))
                }
            }
        };
        let h = get("min_chip_um", &self.min_chip_um, 0.0, 1000.0, false)?;
        let rec = get("recovery", &self.recovery, 0.0, 1.0, false)?;
        let sq = get("texture_sq_um", &self.texture_sq_um, 0.0, 1000.0, false)?;
        let corr = get("texture_corr_um", &self.texture_corr_um, 0.0, 1.0e6, true)?;
        let seed = match &self.texture_seed {
            None => 1,
            Some(s) if *s.get_ref() >= 0 => *s.get_ref() as u64,
            Some(s) => {
                return Err(ConfigError::at(
                    file,
                    text,
                    s.span().start,
                    format!("texture_seed must be ≥ 0, got {}", s.get_ref()),
                ));
            }
        };
        let texture = sq.map(|sq| crate::surface::Texture {
            sq_mm: sq * 1e-3,
            corr_mm: corr.unwrap_or(DEFAULT_TEXTURE_CORR_UM) * 1e-3,
            seed,
        });
        Ok(crate::surface::Process {
            min_chip_mm: h.map_or(tool_min_chip_mm.unwrap_or(0.0), |v| v * 1e-3),
            recovery: rec.unwrap_or(1.0),
            texture,
        })
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ProcessFile {
    rpm: Option<Spanned<f64>>,
    fz_mm: Option<Spanned<f64>>,
    feed_mm_min: Option<Spanned<f64>>,
    ap_mm: Option<Spanned<f64>>,
    ae_mm: Option<Spanned<f64>>,
    lead_deg: Option<Spanned<f64>>,
    tilt_deg: Option<Spanned<f64>>,
    min_chip_um: Option<Spanned<f64>>,
    recovery: Option<Spanned<f64>>,
    texture_sq_um: Option<Spanned<f64>>,
    texture_corr_um: Option<Spanned<f64>>,
    texture_seed: Option<Spanned<i64>>,
}

impl ProcessConfig {
    /// The engine's process effects of this file (h_min from the tool's edge when the file
    /// has no `min_chip_um`).
    pub fn effects(&self, tool_min_chip_mm: Option<f64>) -> crate::surface::Process {
        crate::surface::Process {
            min_chip_mm: self
                .min_chip_um
                .map_or(tool_min_chip_mm.unwrap_or(0.0), |v| v * 1e-3),
            recovery: self.recovery.unwrap_or(1.0),
            texture: self.texture_sq_um.map(|sq| crate::surface::Texture {
                sq_mm: sq * 1e-3,
                corr_mm: self.texture_corr_um.unwrap_or(DEFAULT_TEXTURE_CORR_UM) * 1e-3,
                seed: self.texture_seed.unwrap_or(1),
            }),
        }
    }

    /// Parse `process.toml` text; `file` names it in errors, which give line and column.
    pub fn parse(text: &str, file: &str) -> Result<ProcessConfig, ConfigError> {
        let f: ProcessFile = super::from_toml(text, file)?;
        let effects = EffectsFile {
            min_chip_um: f.min_chip_um.clone(),
            recovery: f.recovery.clone(),
            texture_sq_um: f.texture_sq_um.clone(),
            texture_corr_um: f.texture_corr_um.clone(),
            texture_seed: f.texture_seed.clone(),
        };
        let fx = effects.to_process(text, file, None)?;
        let positive = |key: &str, v: &Option<Spanned<f64>>| -> Result<Option<f64>, ConfigError> {
            match v {
                Some(s) if !(s.get_ref().is_finite() && *s.get_ref() > 0.0) => {
                    Err(ConfigError::at(
                        file,
                        text,
                        s.span().start,
                        format!("{key} must be positive, got {}", s.get_ref()),
                    ))
                }
                Some(s) => Ok(Some(*s.get_ref())),
                None => Ok(None),
            }
        };
        let angle = |key: &str, v: &Option<Spanned<f64>>| -> Result<Option<f64>, ConfigError> {
            match v {
                Some(s) if !(s.get_ref().is_finite() && s.get_ref().abs() <= 90.0) => {
                    Err(ConfigError::at(
                        file,
                        text,
                        s.span().start,
                        format!("{key} must be within ±90°, got {}", s.get_ref()),
                    ))
                }
                Some(s) => Ok(Some(*s.get_ref())),
                None => Ok(None),
            }
        };
        Ok(ProcessConfig {
            rpm: positive("rpm", &f.rpm)?,
            fz_mm: positive("fz_mm", &f.fz_mm)?,
            feed_mm_min: positive("feed_mm_min", &f.feed_mm_min)?,
            ap_mm: positive("ap_mm", &f.ap_mm)?,
            ae_mm: positive("ae_mm", &f.ae_mm)?,
            lead_deg: angle("lead_deg", &f.lead_deg)?,
            tilt_deg: angle("tilt_deg", &f.tilt_deg)?,
            min_chip_um: effects.min_chip_um.as_ref().map(|_| fx.min_chip_mm * 1e3),
            recovery: effects.recovery.as_ref().map(|_| fx.recovery),
            texture_sq_um: fx.texture.map(|t| t.sq_mm * 1e3),
            texture_corr_um: effects.texture_corr_um.as_ref().map(|v| *v.get_ref()),
            texture_seed: fx.texture.map(|t| t.seed),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn process_toml_rejects_unknown_keys_with_position() {
        let err = ProcessConfig::parse("rpm = 15000\nspeed = 3\n", "p.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("p.toml:2:"), "{err}");
        assert!(err.contains("speed"), "{err}");
        let err = ProcessConfig::parse("fz_mm = -0.05\n", "p.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("p.toml:1:9") && err.contains("fz_mm"), "{err}");
        let ok = ProcessConfig::parse(
            "rpm = 15000\nfz_mm = 0.05\nfeed_mm_min = 3000\nap_mm = 0.2\nae_mm = 0.2\nlead_deg = 15\ntilt_deg = 0\n",
            "p.toml",
        )
        .unwrap();
        assert_eq!(ok.rpm, Some(15000.0));
        assert_eq!(ok.lead_deg, Some(15.0));
        assert!(ok.effects(None).is_off());
        let fx = ProcessConfig::parse(
            "min_chip_um = 2.5\nrecovery = 0.8\ntexture_sq_um = 0.1\n",
            "p.toml",
        )
        .unwrap()
        .effects(None);
        assert_eq!(fx.min_chip_mm, 0.0025);
        assert_eq!(fx.recovery, 0.8);
        assert_eq!(fx.texture.unwrap().corr_mm, 0.02);
        let err = ProcessConfig::parse("rpm = 1\nrecovery = 1.5\n", "p.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("p.toml:2:12") && err.contains("recovery"),
            "{err}"
        );
    }

    #[test]
    fn a_bad_value_is_reported_at_its_own_line_not_at_a_comment() {
        // The key also appears in the comment of line 1.
        let err = ProcessConfig::parse("# rpm is the spindle speed\nrpm = 0.0\n", "p.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("p.toml:2:7"), "{err}");
    }
}
