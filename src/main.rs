//! The `tumble` command line: the library's [`tumble::cli`] with the built-in plugins only.

use std::process::ExitCode;

fn main() -> ExitCode {
    tumble::cli::main_with(tumble::schedule::PluginList::default())
}
