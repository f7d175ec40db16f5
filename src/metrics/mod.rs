//! Surface metrics: profile (ISO 4287 / ISO 21920-2) and areal (ISO 25178-2) parameters,
//! plane levelling, polynomial form removal and Gaussian S- and L-filters (ISO 16610-21/61).
//!
//! The conventions follow `docs/iso25178.md` §4 so that the numbers agree with surfalize
//! 0.19.2 (and Gwyddion where it computes the same thing):
//!
//! - heights relative to the mean of the (levelled, filtered) data; population moments;
//!   `Sv`, `Rv` positive; `Sku`, `Rku` plain kurtosis (3 for a Gaussian);
//! - `NaN` nodes are excluded, never treated as zero: means over valid nodes, differences
//!   and Sdr cells only where all their nodes are valid, the ACF normalised by the number of
//!   valid overlapping pairs;
//! - `Sdq`: forward differences, each direction averaged over its own count;
//!   `Sdr`: node-based cells, mean of both triangulations, in %;
//! - `Sal`/`Str`: linear unbiased ACF, threshold 0.2·R(0), 4-connected central region, rays to
//!   its outer boundary; `Str` is `NaN` when the region reaches the lag-field border
//!   (the ACF does not decay in some direction, e.g. every 1-D lay);
//! - `Std`: amplitude spectrum of the mean-removed map, 0.5° bins, lower bin edge, measured
//!   counter-clockwise from +x **in the map's own frame (y = row·dy, ascending)**; surfalize
//!   draws row 0 at the top, so its value is `(180 − Std) mod 180`;
//! - material ratio: linear quantiles of the heights, 10 001-point curve for the 40 % window
//!   and the least-squares equivalent line; `A1`, `A2`, `Vm`, `Vv` by exact clipping
//!   (`mean(max(z − c, 0))`), which avoids surfalize's tie bug (iso25178.md §5);
//! - the Birmingham indices Sbi, Sci, Svi are not computed (no reference to check them).
//!
//! Only the parameters asked for are computed ([`ParamSet`]): a quick `Sa` costs two passes
//! over the data, the ACF and the sort are only done for the parameters that need them.
//! [`RowStream`] computes the plain-pass ones of a map fed in pieces of rows (as a file is
//! read), or read by ranges of rows on all threads ([`RowStream::by_parts`]), with the same
//! values.

mod areal;
mod fft;
mod filter;
mod form;
mod material;
mod pair;
mod params;
mod profile;
mod register;
mod spatial;
mod stream;

pub use areal::{
    Grid, Height, HeightStats, height_stats, height_stats_of, sdq, sdq_of, sdr_percent,
    sdr_percent_of,
};
pub use filter::{EndEffects, gaussian_filter_map, gaussian_lowpass_line, gaussian_sigma};
pub use form::{Level, LevelError, fit_remove_line, fit_remove_map};
pub use material::{MaterialRatio, material_ratio};
pub use pair::{Evaluation, Prepared, evaluate_pair, prepare_pair, shifts_at_rotations};
pub use params::{
    AREAL_PARAMS, PASS_PARAMS, PROFILE_PARAMS, Param, ParamSet, Preprocess, areal_parameters,
    areal_parameters_of, preprocess_map, preprocess_profile, profile_parameters,
};
pub use profile::{
    Profile, ProfileSpec, ProfileSpecError, extract_profile, profile_from_points, profile_values,
    rz_ra, sampling_length_mm,
};
pub use register::{
    LaySpectra, LineSpectrum, Placement, ProfileAlignment, align_profile, bilinear,
    correlation_shift, feed_direction_deg, lay_spectra, place, shift_peak_is_coefficient,
    spectral_peak,
};
pub use spatial::{AcfLengths, Spectrum, acf_lengths, spectrum_direction};
pub use stream::RowStream;

/// Errors of the metrics stage.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MetricsError {
    /// A parameter symbol that is not known.
    #[error("unknown parameter {0:?} (known: {1})")]
    UnknownParam(String, String),
    /// A profile parameter asked for a map, or the reverse.
    #[error("{0} is a {1} parameter")]
    WrongKind(String, &'static str),
    /// Too few valid nodes for the computation.
    #[error("too few valid heights: {0}")]
    TooFew(String),
    /// A bad profile specification.
    #[error("bad profile: {0}")]
    BadProfile(String),
    /// A bad filter or levelling setting.
    #[error("bad setting: {0}")]
    BadSetting(String),
}
