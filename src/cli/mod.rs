//! The command line: argument parsing ([`clap`]), progress bars ([`indicatif`])
//! and printing around the library. Every run goes through the library's run
//! loop ([`ballast::run`]).
//!
//! - `run`: a scene file of either engine ([`run`]);
//! - `deposit`: the scene of a loose pentagon deposit ([`deposit`]);
//! - `saussine …`: the experiments of Saussine et al. (2006) ([`saussine`],
//!   [`studies`]);
//! - `karrech …`, `luding …`: the ready-made MD tests ([`md_tests`]).

mod deposit;
mod md_tests;
mod run;
mod saussine;
mod studies;

use ballast::run::{Progress, RunOptions, RunOutcome, Status};
use ballast::Error;
use clap::{Parser, Subcommand};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::Path;
use std::process::ExitCode;

#[derive(Debug, Parser)]
#[command(name = "ballast", version, about = "Granular mechanics under cyclic loading (railway ballast settlement)")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Runs a scene and writes its outputs to a directory.
    Run(run::RunArgs),
    /// Writes the scene of a loose pentagon deposit with the Saussine et al. (2006)
    /// grading (circumradii 5, 7.5, 10 mm in the numbers 361 : 242 : 121), ready for `run`.
    Deposit(deposit::DepositArgs),
    /// The numerical experiments of Saussine et al. (2006): sample, loaded scenes, studies.
    #[command(subcommand)]
    Saussine(saussine::SaussineCommand),
    /// The MD sample of Karrech et al. (2007), Table 1: deposit, cyclic plate load.
    #[command(subcommand)]
    Karrech(md_tests::KarrechCommand),
    /// The cyclic triaxial box of David, García-Rojo, Herrmann & Luding: compression, cycles.
    #[command(subcommand)]
    Luding(md_tests::LudingCommand),
}

/// Why a command failed, and its exit code.
pub(crate) enum Failure {
    /// Invalid input (scene, option, checkpoint): exit code 2.
    Input(Error),
    /// The run or its outputs failed: exit code 1.
    Run(Error),
}

impl From<Error> for Failure {
    /// An invalid scene, option or checkpoint is an input error; a divergence or
    /// an I/O error a run error.
    fn from(e: Error) -> Self {
        match e {
            Error::Scene(_) => Failure::Input(e),
            _ => Failure::Run(e),
        }
    }
}

/// An input error with this message.
pub(crate) fn input(msg: String) -> Failure {
    Failure::Input(Error::Scene(msg))
}

/// Runs the command line.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run::main(args),
        Command::Deposit(args) => deposit::main(args),
        Command::Saussine(cmd) => saussine::main(cmd),
        Command::Karrech(cmd) => md_tests::karrech_main(cmd),
        Command::Luding(cmd) => md_tests::luding_main(cmd),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Input(e)) => {
            eprintln!("error: {}", one_line(&e));
            ExitCode::from(2)
        }
        Err(Failure::Run(e)) => {
            eprintln!("error: {}", one_line(&e));
            ExitCode::from(1)
        }
    }
}

/// The error's message on a single line.
pub(crate) fn one_line(e: &Error) -> String {
    e.to_string().split_whitespace().collect::<Vec<_>>().join(" ")
}

/// How a run shows its progress: hidden, its own bar, or a bar in a group of
/// runs side by side (with a label).
#[derive(Clone, Default)]
pub(crate) enum Display {
    #[default]
    Bar,
    Quiet,
    Group(MultiProgress, String),
}

/// Runs the scene file `scene` into `out` with a progress bar, and prints the
/// run's last line (the end, or where it stopped).
pub(crate) fn run_scene(scene: &Path, out: &Path, opts: &RunOptions, display: &Display) -> Result<RunOutcome, Failure> {
    let pb = match display {
        Display::Quiet => ProgressBar::hidden(),
        Display::Bar => ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr()),
        Display::Group(group, label) => group.add(ProgressBar::new(0).with_prefix(label.clone())),
    };
    if let Ok(style) =
        ProgressStyle::with_template("{prefix} {bar:40} {pos}/{len} steps, {msg} [{elapsed_precise} < {eta}]")
    {
        pb.set_style(style);
    }
    let mut message_at = 0;
    let mut progress = |p: &Progress| {
        if pb.is_hidden() {
            return;
        }
        if pb.length() != Some(p.end_step) {
            pb.set_length(p.end_step);
        }
        pb.set_position(p.step);
        if p.step >= message_at {
            message_at = p.step + (p.end_step / 1000).max(1);
            let cycles = match (p.cycles, p.settlement) {
                (Some((c, total)), Some(s)) => format!(", cycle {c} of {total}, settlement {:.3} mm", 1e3 * s),
                (Some((c, total)), None) => format!(", cycle {c} of {total}"),
                _ => String::new(),
            };
            pb.set_message(format!("t = {:.4} s, Ek = {:.3e} J{cycles}", p.time, p.kinetic_energy));
        }
    };
    let result = ballast::run::run_file(scene, out, opts, &mut progress);
    pb.finish_and_clear();
    let outcome = result?;
    if !matches!(display, Display::Group(..)) {
        print_outcome(&outcome);
    }
    Ok(outcome)
}

/// The last line of a run.
pub(crate) fn print_outcome(o: &RunOutcome) {
    let r = &o.report;
    match o.status {
        Status::Stopped => println!(
            "stopped at step {} of {} (t = {:.6} s) after {:.2} s; continue with --resume",
            o.step, o.end_step, o.time, o.elapsed_s
        ),
        Status::Ended(end) => {
            let solver = match r.unconverged_steps {
                Some(0) => ", every step converged".to_string(),
                Some(n) => format!(
                    ", {n} steps stopped at the iteration cap before the solver's tolerance (see README, \
                     \"not converged\")"
                ),
                None => String::new(),
            };
            println!(
                "{} steps to t = {:.6} s{} in {:.2} s ({:.3e} body-steps/s on {} threads): {} bodies, final kinetic \
                 energy {:.3e} J, max overlap {:.3e} m{solver}; outputs in {}",
                o.step,
                o.time,
                if end == ballast::io::RunEnd::Equilibrium { " (equilibrium reached)" } else { "" },
                o.elapsed_s,
                r.body_steps_per_s,
                r.threads,
                r.bodies,
                o.kinetic_energy,
                r.max_overlap_m,
                o.out.display()
            );
        }
    }
}
