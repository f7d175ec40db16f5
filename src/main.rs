//! The `crest` binary: parse the command line, run it, map the outcome to an exit code. The
//! commands live in [`cli`] (one file each); everything they compute is the library's.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
