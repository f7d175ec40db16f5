//! Parameter symbols, the preprocessing chain (form removal, S- and L-filter, end effects)
//! and the dispatch that computes only the parameters asked for.

use super::filter::{EndEffects, gaussian_filter_map, gaussian_lowpass_line};
use super::form::{Level, fit_remove_line, fit_remove_map};
use super::profile::{Profile, profile_values};
use super::{MetricsError, areal, material, spatial};
use crate::surface::HeightMap;

macro_rules! params {
    ($($v:ident => $sym:literal, $unit:literal, $what:literal;)*) => {
        /// A parameter, named by its ISO symbol.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Param {
            $(#[doc = $what] $v,)*
        }
        impl Param {
            /// Every parameter, in output order.
            pub const ALL: &'static [Param] = &[$(Param::$v,)*];
            /// The ISO symbol (`Sa`, `RSm`, …), also the JSON key.
            pub fn symbol(self) -> &'static str {
                match self { $(Param::$v => $sym,)* }
            }
            /// Unit of the value.
            pub fn unit(self) -> &'static str {
                match self { $(Param::$v => $unit,)* }
            }
        }
    };
}

params! {
    Sa => "Sa", "µm", "Arithmetic mean height.";
    Sq => "Sq", "µm", "Root-mean-square height.";
    Sp => "Sp", "µm", "Maximum peak height.";
    Sv => "Sv", "µm", "Maximum pit depth (positive).";
    Sz => "Sz", "µm", "Maximum height Sp + Sv.";
    Ssk => "Ssk", "1", "Skewness.";
    Sku => "Sku", "1", "Kurtosis (3 for a Gaussian).";
    Sdq => "Sdq", "µm/µm", "Root-mean-square gradient.";
    Sdr => "Sdr", "%", "Developed interfacial area ratio.";
    Sal => "Sal", "µm", "Autocorrelation length (s = 0.2).";
    Str => "Str", "1", "Texture aspect ratio (NaN when the ACF does not decay in some direction).";
    Std => "Std", "deg", "Texture direction, CCW from +x, y = row index ascending.";
    Ssw => "Ssw", "µm", "Dominant spatial wavelength.";
    Sk => "Sk", "µm", "Core height.";
    Spk => "Spk", "µm", "Reduced peak height.";
    Svk => "Svk", "µm", "Reduced valley depth.";
    Smr1 => "Smr1", "%", "Upper material ratio of the core.";
    Smr2 => "Smr2", "%", "Lower material ratio of the core.";
    Vmp => "Vmp", "µm³/µm²", "Peak material volume at 10 %.";
    Vmc => "Vmc", "µm³/µm²", "Core material volume, 10 % to 80 %.";
    Vvc => "Vvc", "µm³/µm²", "Core void volume, 10 % to 80 %.";
    Vvv => "Vvv", "µm³/µm²", "Valley void volume at 80 %.";
    Sxp => "Sxp", "µm", "Extreme peak height, Smc(2.5 %) − Smc(50 %).";
    Ra => "Ra", "µm", "Arithmetic mean deviation of the profile.";
    Rq => "Rq", "µm", "Root-mean-square deviation of the profile.";
    Rp => "Rp", "µm", "Mean of the section peak heights.";
    Rv => "Rv", "µm", "Mean of the section valley depths.";
    Rz => "Rz", "µm", "Mean of the section heights (ISO 21920-2; Marin et al. 2023, Eq 15).";
    Rt => "Rt", "µm", "Total height over the evaluation length.";
    Rsk => "Rsk", "1", "Profile skewness.";
    Rku => "Rku", "1", "Profile kurtosis.";
    Rdq => "Rdq", "µm/µm", "Root-mean-square profile slope.";
    RSm => "RSm", "µm", "Mean width of the profile elements.";
}

/// Areal parameters in output order.
pub const AREAL_PARAMS: &[Param] = &[
    Param::Sa,
    Param::Sq,
    Param::Sp,
    Param::Sv,
    Param::Sz,
    Param::Ssk,
    Param::Sku,
    Param::Sdq,
    Param::Sdr,
    Param::Sal,
    Param::Str,
    Param::Std,
    Param::Ssw,
    Param::Sk,
    Param::Spk,
    Param::Svk,
    Param::Smr1,
    Param::Smr2,
    Param::Vmp,
    Param::Vmc,
    Param::Vvc,
    Param::Vvv,
    Param::Sxp,
];

/// Profile parameters in output order.
pub const PROFILE_PARAMS: &[Param] = &[
    Param::Ra,
    Param::Rq,
    Param::Rp,
    Param::Rv,
    Param::Rz,
    Param::Rt,
    Param::Rsk,
    Param::Rku,
    Param::Rdq,
    Param::RSm,
];

impl Param {
    /// Whether this is a profile (R…) parameter.
    pub fn is_profile(self) -> bool {
        PROFILE_PARAMS.contains(&self)
    }

    /// The parameter with this symbol (case-insensitive).
    pub fn from_symbol(s: &str) -> Option<Param> {
        let t = s.trim();
        Param::ALL
            .iter()
            .copied()
            .find(|p| p.symbol().eq_ignore_ascii_case(t))
    }
}

/// The parameters to compute, in output order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamSet(Vec<Param>);

impl ParamSet {
    /// Parse a comma list of symbols (`all` = every parameter of the kind); `profile` says
    /// which kind is expected.
    pub fn parse(list: &str, profile: bool) -> Result<ParamSet, MetricsError> {
        let kind = if profile {
            PROFILE_PARAMS
        } else {
            AREAL_PARAMS
        };
        let mut v = Vec::new();
        for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            if item.eq_ignore_ascii_case("all") {
                v.extend_from_slice(kind);
                continue;
            }
            let p = Param::from_symbol(item).ok_or_else(|| {
                MetricsError::UnknownParam(
                    item.to_string(),
                    kind.iter()
                        .map(|p| p.symbol())
                        .collect::<Vec<_>>()
                        .join(" "),
                )
            })?;
            if p.is_profile() != profile {
                return Err(MetricsError::WrongKind(
                    p.symbol().to_string(),
                    if p.is_profile() {
                        "profile (give ‹profile›)"
                    } else {
                        "areal (drop ‹profile›)"
                    },
                ));
            }
            v.push(p);
        }
        v.sort();
        v.dedup();
        Ok(ParamSet(v))
    }

    /// Every areal or every profile parameter.
    pub fn all(profile: bool) -> ParamSet {
        ParamSet(
            if profile {
                PROFILE_PARAMS
            } else {
                AREAL_PARAMS
            }
            .to_vec(),
        )
    }

    /// The parameters, in output order.
    pub fn params(&self) -> &[Param] {
        &self.0
    }

    pub(crate) fn any(&self, ps: &[Param]) -> bool {
        self.0.iter().any(|p| ps.contains(p))
    }
}

/// Form removal and filters applied before the parameters, in this order: form removal
/// (F-operator), S-filter (Gaussian low-pass λs), L-filter (λc: `z − lowpass(z)`), then
/// optionally the end zones are cut off.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Preprocess {
    /// Form removal.
    pub level: Level,
    /// S-filter nesting index, µm.
    pub lambda_s_um: Option<f64>,
    /// L-filter nesting index, µm.
    pub lambda_c_um: Option<f64>,
    /// Border handling of the filters.
    pub ends: EndEffects,
}

impl Preprocess {
    fn check(&self) -> Result<(), MetricsError> {
        for (n, v) in [
            ("lambda-s", self.lambda_s_um),
            ("lambda-c", self.lambda_c_um),
        ] {
            if let Some(l) = v
                && !(l.is_finite() && l > 0.0)
            {
                return Err(MetricsError::BadSetting(format!(
                    "--{n}-um must be a positive length, got {l}"
                )));
            }
        }
        if let (Some(s), Some(c)) = (self.lambda_s_um, self.lambda_c_um)
            && s >= c
        {
            return Err(MetricsError::BadSetting(format!(
                "lambda-s ({s} µm) must be shorter than lambda-c ({c} µm)"
            )));
        }
        Ok(())
    }

    /// Half the largest nesting index applied, µm (the trimmed border with `Trim`).
    pub fn trim_um(&self) -> f64 {
        match self.ends {
            EndEffects::Reflect => 0.0,
            EndEffects::Trim => self.lambda_c_um.or(self.lambda_s_um).unwrap_or(0.0) / 2.0,
        }
    }
}

/// Nesting indices larger than this many times the evaluation length filter nothing useful
/// and would only cost memory (the kernel spans ±λ).
pub const MAX_NESTING_TO_EXTENT: f64 = 100.0;

/// Refuse nesting indices far beyond the data's extent `extent_um`.
fn check_nesting(pp: &Preprocess, extent_um: f64) -> Result<(), MetricsError> {
    for (name, v) in [("λs", pp.lambda_s_um), ("λc", pp.lambda_c_um)] {
        if let Some(v) = v
            && v > MAX_NESTING_TO_EXTENT * extent_um.max(1e-9)
        {
            return Err(MetricsError::BadSetting(format!(
                "the nesting index {name} = {v} µm is more than {MAX_NESTING_TO_EXTENT} times the data's extent ({extent_um} µm)"
            )));
        }
    }
    Ok(())
}

/// Apply the preprocessing chain to a map (returns a new, possibly cropped, map).
pub fn preprocess_map(map: &HeightMap, pp: &Preprocess) -> Result<HeightMap, MetricsError> {
    pp.check()?;
    check_nesting(
        pp,
        (map.nx as f64 * map.dx_um).max(map.ny as f64 * map.dy_um),
    )?;
    let mut m = map.clone();
    if pp.level.degree() > 0 && !fit_remove_map(&mut m, pp.level.degree()) {
        return Err(MetricsError::TooFew(format!(
            "too few valid nodes for a {} fit",
            pp.level.label()
        )));
    }
    if let Some(ls) = pp.lambda_s_um {
        m = gaussian_filter_map(&m, ls);
    }
    if let Some(lc) = pp.lambda_c_um {
        let low = gaussian_filter_map(&m, lc);
        for (z, w) in m.z_um.iter_mut().zip(&low.z_um) {
            *z -= w;
        }
    }
    let t = pp.trim_um();
    if t > 0.0 {
        let bx = if m.nx > 1 {
            (t / m.dx_um - 1e-6).ceil() as usize
        } else {
            0
        };
        let by = if m.ny > 1 {
            (t / m.dy_um - 1e-6).ceil() as usize
        } else {
            0
        };
        if 2 * bx >= m.nx || 2 * by >= m.ny {
            return Err(MetricsError::BadSetting(format!(
                "trimming {t} µm at each border leaves nothing of a {}×{} map",
                m.nx, m.ny
            )));
        }
        let (nx, ny) = (m.nx - 2 * bx, m.ny - 2 * by);
        let mut z = Vec::with_capacity(nx * ny);
        for r in by..by + ny {
            z.extend_from_slice(&m.z_um[r * m.nx + bx..r * m.nx + bx + nx]);
        }
        let mut c = HeightMap::from_rows(nx, ny, m.dx_um, m.dy_um, z)
            .ok_or_else(|| MetricsError::BadSetting("internal: crop size".into()))?;
        c.x0_mm = m.x0_mm + bx as f64 * m.dx_um / 1000.0;
        c.y0_mm = m.y0_mm + by as f64 * m.dy_um / 1000.0;
        m = c;
    }
    Ok(m)
}

/// Apply the preprocessing chain to a profile (1-D polynomial, 1-D Gaussian filters).
pub fn preprocess_profile(p: &Profile, pp: &Preprocess) -> Result<Profile, MetricsError> {
    pp.check()?;
    check_nesting(pp, p.z.len() as f64 * p.step_um)?;
    let mut z = p.z.clone();
    if pp.level.degree() > 0 && !fit_remove_line(&mut z, pp.level.degree()) {
        return Err(MetricsError::TooFew(format!(
            "too few valid samples for a {} fit",
            pp.level.label()
        )));
    }
    if let Some(ls) = pp.lambda_s_um {
        z = gaussian_lowpass_line(&z, ls, p.step_um);
    }
    if let Some(lc) = pp.lambda_c_um {
        let low = gaussian_lowpass_line(&z, lc, p.step_um);
        for (v, w) in z.iter_mut().zip(&low) {
            *v -= w;
        }
    }
    let t = pp.trim_um();
    if t > 0.0 {
        let b = (t / p.step_um - 1e-6).ceil() as usize;
        if 2 * b >= z.len() {
            return Err(MetricsError::BadSetting(format!(
                "trimming {t} µm at each end leaves nothing of a {} µm profile",
                (z.len() as f64 - 1.0) * p.step_um
            )));
        }
        z = z[b..z.len() - b].to_vec();
    }
    Ok(Profile {
        z,
        step_um: p.step_um,
    })
}

/// The areal parameters computed by plain passes over the heights (no ACF, spectrum or
/// sort): what [`areal_parameters_of`] computes on any grid, e.g. an `f32` field as read.
/// The first nine of [`AREAL_PARAMS`] (Sa … Sdr).
pub const PASS_PARAMS: &[Param] = AREAL_PARAMS.split_at(9).0;

impl ParamSet {
    /// Whether every parameter is one of [`PASS_PARAMS`].
    pub fn passes_only(&self) -> bool {
        self.0.iter().all(|p| PASS_PARAMS.contains(p))
    }

    /// Peak bytes per node of [`areal_parameters`] on a map in memory, the map's own 8
    /// included (measured, reports/benchmarks.md): the ACF of Sal and Str on the padded
    /// complex lattice, 4 nodes of 16 bytes per node (twice with missing nodes), the
    /// spectrum of Std and Ssw, the sorted
    /// copy of the material-ratio parameters; a levelled or filtered copy adds its own.
    pub fn bytes_per_node(&self, missing: bool, preprocessed: bool) -> u64 {
        self.groups()
            .iter()
            .map(|&(_, b)| match b {
                Group::Acf if missing => 140,
                Group::Acf => 105,
                Group::Spectrum => 35,
                Group::Material => 24,
                Group::Pass => 9,
            })
            .max()
            .unwrap_or(9)
            + if preprocessed { 16 } else { 0 }
    }

    /// The parameters of the set with the work each needs.
    fn groups(&self) -> Vec<(Param, Group)> {
        use Param::*;
        self.0
            .iter()
            .map(|&p| {
                let g = match p {
                    Sal | Str => Group::Acf,
                    Std | Ssw => Group::Spectrum,
                    Sk | Spk | Svk | Smr1 | Smr2 | Vmp | Vmc | Vvc | Vvv | Sxp => Group::Material,
                    _ => Group::Pass,
                };
                (p, g)
            })
            .collect()
    }

    /// The parameters of the set that [`ParamSet::bytes_per_node`] keeps within
    /// `per_node` bytes per node.
    pub fn within(&self, per_node: u64, missing: bool, preprocessed: bool) -> ParamSet {
        ParamSet(
            self.0
                .iter()
                .copied()
                .filter(|&p| ParamSet(vec![p]).bytes_per_node(missing, preprocessed) <= per_node)
                .collect(),
        )
    }
}

/// The work a parameter needs, for memory estimates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Group {
    Pass,
    Material,
    Spectrum,
    Acf,
}

/// The values of the pass parameters in `set` (NaN for the others, filled in by the caller).
fn pass_values<T: areal::Height>(
    g: areal::Grid<'_, T>,
    set: &ParamSet,
) -> Result<Vec<(Param, f64)>, MetricsError> {
    use Param::*;
    let stats = if set.any(&[Sa, Sq, Sp, Sv, Sz, Ssk, Sku]) {
        Some(
            areal::height_stats_of(g.z)
                .ok_or_else(|| MetricsError::TooFew("the map has no valid height".into()))?,
        )
    } else {
        None
    };
    let sdq = set.any(&[Sdq]).then(|| areal::sdq_of(g));
    let sdr = set.any(&[Sdr]).then(|| areal::sdr_percent_of(g));
    Ok(pass_table(set, stats, sdq, sdr))
}

/// The pass parameters of `set` from what was computed (NaN for the others).
pub(crate) fn pass_table(
    set: &ParamSet,
    stats: Option<areal::HeightStats>,
    sdq: Option<f64>,
    sdr: Option<f64>,
) -> Vec<(Param, f64)> {
    use Param::*;
    set.params()
        .iter()
        .map(|&p| {
            let v = match p {
                Sa => stats.map(|s| s.sa),
                Sq => stats.map(|s| s.sq),
                Sp => stats.map(|s| s.sp),
                Sv => stats.map(|s| s.sv),
                Sz => stats.map(|s| s.sz()),
                Ssk => stats.map(|s| s.ssk),
                Sku => stats.map(|s| s.sku),
                Sdq => sdq,
                Sdr => sdr,
                _ => None,
            };
            (p, v.unwrap_or(f64::NAN))
        })
        .collect()
}

/// The pass parameters ([`PASS_PARAMS`]) in `set` of any grid, `f64` or `f32` (the same
/// values for the same heights); an error names a parameter that needs a [`HeightMap`].
pub fn areal_parameters_of<T: areal::Height>(
    g: areal::Grid<'_, T>,
    set: &ParamSet,
) -> Result<Vec<(Param, f64)>, MetricsError> {
    if let Some(p) = set.params().iter().find(|p| !PASS_PARAMS.contains(p)) {
        return Err(MetricsError::BadSetting(format!(
            "{} needs the whole height map (not a plain pass)",
            p.symbol()
        )));
    }
    pass_values(g, set)
}

/// Compute the areal parameters in `set` on an (already preprocessed) map.
pub fn areal_parameters(
    map: &HeightMap,
    set: &ParamSet,
) -> Result<Vec<(Param, f64)>, MetricsError> {
    use Param::*;
    let mut out = pass_values(areal::Grid::of(map), set)?;
    let acf = set.any(&[Sal, Str]).then(|| spatial::acf_lengths(map, 0.2));
    let spec = set
        .any(&[Std, Ssw])
        .then(|| spatial::spectrum_direction(map));
    let mr = if set.any(&[Sk, Spk, Svk, Smr1, Smr2, Vmp, Vmc, Vvc, Vvv, Sxp]) {
        Some(material::material_ratio(&map.z_um).ok_or_else(|| {
            MetricsError::TooFew("material-ratio parameters need at least 2 valid heights".into())
        })?)
    } else {
        None
    };
    for (p, out) in out.iter_mut() {
        let v = match p {
            Sal => acf.map(|a| a.sal),
            Str => acf.map(|a| a.str_ratio),
            Std => spec.map(|s| s.std_deg),
            Ssw => spec.map(|s| s.ssw),
            Sk => mr.map(|m| m.sk),
            Spk => mr.map(|m| m.spk),
            Svk => mr.map(|m| m.svk),
            Smr1 => mr.map(|m| m.smr1),
            Smr2 => mr.map(|m| m.smr2),
            Vmp => mr.map(|m| m.vmp),
            Vmc => mr.map(|m| m.vmc),
            Vvc => mr.map(|m| m.vvc),
            Vvv => mr.map(|m| m.vvv),
            Sxp => mr.map(|m| m.sxp),
            _ => continue,
        };
        *out = v.unwrap_or(f64::NAN);
    }
    Ok(out)
}

/// Compute the profile parameters in `set` (`sections` sampling lengths for Rp, Rv, Rz).
pub fn profile_parameters(
    p: &Profile,
    set: &ParamSet,
    sections: usize,
) -> Result<Vec<(Param, f64)>, MetricsError> {
    use Param::*;
    let v = profile_values(p, sections)?;
    Ok(set
        .params()
        .iter()
        .map(|&q| {
            let x = match q {
                Ra => v.ra,
                Rq => v.rq,
                Rp => v.rp,
                Rv => v.rv,
                Rz => v.rz,
                Rt => v.rt,
                Rsk => v.rsk,
                Rku => v.rku,
                Rdq => v.rdq,
                RSm => v.rsm,
                _ => f64::NAN,
            };
            (q, x)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_param_lists() {
        let s = ParamSet::parse("sa, Sq,SA", false).unwrap();
        assert_eq!(s.params(), &[Param::Sa, Param::Sq]);
        assert!(matches!(
            ParamSet::parse("Ra", false),
            Err(MetricsError::WrongKind(..))
        ));
        assert!(matches!(
            ParamSet::parse("Sfoo", false),
            Err(MetricsError::UnknownParam(..))
        ));
        assert_eq!(
            ParamSet::parse("all", true).unwrap().params(),
            PROFILE_PARAMS
        );
    }

    #[test]
    fn symbols_are_unique_ignoring_case() {
        for (i, a) in Param::ALL.iter().enumerate() {
            for b in &Param::ALL[i + 1..] {
                assert!(!a.symbol().eq_ignore_ascii_case(b.symbol()));
            }
        }
        assert_eq!(Param::ALL.len(), AREAL_PARAMS.len() + PROFILE_PARAMS.len());
    }
}
