//! The `lumagraph` command line with `ZonePlate` beside the built-in node kinds: every
//! subcommand (`render`, `plan`, `validate`, `nodes`, `edit`, …) knows it.

use std::process::ExitCode;

fn main() -> ExitCode {
    match lumagraph_example_custom_node::library() {
        Ok(library) => lumagraph::cli::main_with(library),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
