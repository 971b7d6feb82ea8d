//! The `irad` binary: the command line of src/cli/ over the irad library.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
