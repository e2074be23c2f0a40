//! The `lumagraph` command line with the built-in node kinds (see [`lumagraph::cli`]).

use std::process::ExitCode;

fn main() -> ExitCode {
    lumagraph::cli::main_with(lumagraph::pathtrace::library::with_builtins())
}
