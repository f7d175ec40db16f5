//! Batch physics: designed experiments and their factor effects (001 §4), run-out what-if
//! sweeps (002 Eqs 7-8, 14), and regressions of simulated against measured roughness.
//!
//! Every function here takes plain values (cutters, designs, measured cases) and returns
//! plain data; reading the files that describe them is [`crate::config`] and
//! [`crate::io`]'s, drawing and rendering the results [`crate::plot`] and
//! [`crate::report`]'s. Runs and cases are evaluated in parallel with rayon, in a fixed
//! order, so the results do not depend on the thread count.

pub mod atlas;
pub mod brammertz;
pub mod calibrate;
pub mod compare;
pub mod design;
pub mod identify;
pub mod identify_fit;
pub mod identify_map;
pub mod measured;
pub mod montecarlo;
pub mod regression;
pub mod run;
pub mod runout;
pub mod stepover;
pub mod uncertainty;
