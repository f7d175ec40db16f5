//! The pipelines the commands run, in one place that the command line, the studies and the
//! Python package all call: read the inputs a command names, resolve tool, feed and spindle
//! speed, resample, simulate and measure. Files are read through [`crate::io`]; nothing
//! here prints.

pub mod error;
pub mod inputs;

pub use error::{Error, Result};

pub use inputs::{
    ToolFileError, ToolSource, load_machine, load_process, load_tool, tool_from_text, tool_min_chip,
};
pub use progress::{Progress, Silent};
pub mod air;
pub mod atlas;
pub mod compare;
pub mod contact;
pub mod design;
pub mod feed;
pub mod fields;
pub mod located;
pub mod patch;
pub mod prepare;
pub mod progress;
pub mod report;
pub mod request;
pub mod resample;
pub mod runout;
pub mod sanity;
pub mod select;
pub mod simulate;
pub mod tasks;
pub mod tool;
