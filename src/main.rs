//! The `ballast` command line: parses the arguments, calls the library and
//! prints (see [`cli`]). Exit codes: 0 on success; 2 for an invalid scene,
//! command line or checkpoint (one line `error: …` on stderr); 1 if a run
//! diverges (its outputs then hold the last good state) or an output file cannot
//! be written.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
