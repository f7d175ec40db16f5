//! Reading tool-path files (CLSF or contact12) into a [`Program`], with errors that name
//! the file, line and column.

use crate::toolpath::Program;
use std::path::Path;

#[allow(dead_code)] // used by the commands as they land
/// Read and lower a CLSF or contact12 file (chosen by content), MSYS not applied.
pub fn read_program(path: &Path) -> miette::Result<Program> {
    Err(miette::miette!(
        "{}: reading tool paths is not built yet",
        path.display()
    ))
}
