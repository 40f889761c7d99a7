//! The command line: argument parsing ([`clap`]), progress bars ([`indicatif`],
//! the library's [`RunDisplay`]) and printing around the library. Every run goes
//! through the library's run loop ([`ballast::run`]); the experiments are those
//! of [`ballast::studies`].
//!
//! - `run`: a scene file of either engine ([`run`]);
//! - `figures`: the figures of a finished run folder ([`figures`]);
//! - `deposit`: the scene of a loose pentagon deposit ([`deposit`]);
//! - `saussine …`: the experiments of Saussine et al. (2006) ([`saussine`]);
//! - `compare`: NSCD versus MD on the same loaded sample ([`compare`]);
//! - `track3d …`: the 3D track section ([`track3d`]);
//! - `karrech …`, `luding …`: the ready-made MD tests ([`md_tests`]).

mod cluster;
mod compare;
mod deposit;
mod figures;
mod flags;
mod md_tests;
mod run;
mod saussine;
mod track3d;

use ballast::run::{Progress, RunOutcome, Status};
use ballast::studies::campaigns::StudyReport;
use ballast::studies::saussine::Sample;
use ballast::studies::RunDisplay;
use ballast::Error;
use clap::{Parser, Subcommand};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
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
    /// Draws the figures (PNG + SVG) of a finished run folder of either engine from its files.
    Figures(figures::FiguresArgs),
    /// Writes the scene of a loose pentagon deposit with the Saussine et al. (2006)
    /// grading (circumradii 5, 7.5, 10 mm in the numbers 361 : 242 : 121), ready for `run`.
    Deposit(deposit::DepositArgs),
    /// The numerical experiments of Saussine et al. (2006): sample, loaded scenes, studies.
    #[command(subcommand)]
    Saussine(Box<saussine::SaussineCommand>),
    /// NSCD versus soft-contact MD on the same loaded 2D sample: MD at each overlap ratio,
    /// replicas from perturbed starts, side by side; compare.csv, compare.md, settlement figure.
    Compare(Box<compare::CompareArgs>),
    /// The 3D track section: ballast grains deposited on a sprung sublayer, a sleeper under cyclic load.
    #[command(subcommand)]
    Track3d(Box<track3d::Track3dCommand>),
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
    /// An invalid scene, option, checkpoint or shape is an input error (exit code 2); a
    /// divergence or an I/O error a run error.
    fn from(e: Error) -> Self {
        if e.is_input() {
            Failure::Input(e)
        } else {
            Failure::Run(e)
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
    let _mpi = cluster::init();
    let result = match cli.command {
        Command::Run(args) => run::main(args),
        Command::Figures(args) => figures::main(args),
        Command::Deposit(args) => deposit::main(args),
        Command::Saussine(cmd) => saussine::main(*cmd),
        Command::Compare(args) => compare::main(*args),
        Command::Track3d(cmd) => track3d::main(*cmd),
        Command::Karrech(cmd) => md_tests::karrech_main(cmd),
        Command::Luding(cmd) => md_tests::luding_main(cmd),
    };
    let code = match result {
        Ok(()) => 0,
        Err(Failure::Input(e)) => {
            eprintln!("error: {}", flags::as_flags(&e.one_line()));
            2
        }
        Err(Failure::Run(e)) => {
            eprintln!("error: {}", e.one_line());
            1
        }
    };
    if code != 0 {
        cluster::abort_others(code);
    }
    ExitCode::from(code)
}

/// How the runs of a command show their progress on the terminal (the
/// library's [`RunDisplay`]).
pub(crate) enum Bars {
    /// One bar on stderr; each run's last line printed.
    Single,
    /// No bar; each run's last line printed.
    Quiet,
    /// One bar per run, labelled, in a group (runs side by side); no last lines.
    Group(MultiProgress),
}

impl Bars {
    /// For one run at a time.
    pub(crate) fn single(quiet: bool) -> Self {
        if quiet {
            Bars::Quiet
        } else {
            Bars::Single
        }
    }

    /// For runs side by side.
    pub(crate) fn group(quiet: bool) -> Self {
        if quiet {
            Bars::Quiet
        } else {
            Bars::Group(MultiProgress::new())
        }
    }
}

impl RunDisplay for Bars {
    fn run(&self, label: &str) -> Box<dyn FnMut(&Progress) + '_> {
        let pb = match self {
            Bars::Quiet => ProgressBar::hidden(),
            Bars::Single => ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr()),
            Bars::Group(group) => group.add(ProgressBar::new(0).with_prefix(label.to_string())),
        };
        if let Ok(style) =
            ProgressStyle::with_template("{prefix} {bar:40} {pos}/{len} steps, {msg} [{elapsed_precise} < {eta}]")
        {
            pb.set_style(style);
        }
        let mut bar = Bar { pb, message_at: 0 };
        Box::new(move |p| bar.show(p))
    }

    fn ended(&self, _label: &str, outcome: &RunOutcome) {
        if !matches!(self, Bars::Group(_)) {
            print_outcome(outcome);
        }
    }

    fn sample(&self, sample: &Sample) {
        print_sample(sample);
    }
}

/// The bar of one run, cleared when the run returns.
struct Bar {
    pb: ProgressBar,
    message_at: u64,
}

impl Bar {
    fn show(&mut self, p: &Progress) {
        let pb = &self.pb;
        if pb.is_hidden() {
            return;
        }
        if pb.length() != Some(p.end_step) {
            pb.set_length(p.end_step);
        }
        pb.set_position(p.step);
        if p.step >= self.message_at {
            self.message_at = p.step + (p.end_step / 1000).max(1);
            let cycles = match (p.cycles, p.settlement) {
                (Some((c, total)), Some(s)) => format!(", cycle {c} of {total}, settlement {:.3} mm", 1e3 * s),
                (Some((c, total)), None) => format!(", cycle {c} of {total}"),
                _ => String::new(),
            };
            pb.set_message(format!("t = {:.4} s, Ek = {:.3e} J{cycles}", p.time, p.kinetic_energy));
        }
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        self.pb.finish_and_clear();
    }
}

/// The bar of an accelerated run (hidden with `quiet`): cycles reached of the
/// target, computed cycles, settlement, ETA.
pub(crate) fn cycle_bar(quiet: bool) -> ProgressBar {
    let pb =
        if quiet { ProgressBar::hidden() } else { ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr()) };
    if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} cycles, {msg} [{elapsed_precise} < {eta}]") {
        pb.set_style(style);
    }
    pb
}

/// Shows an accelerated run's progress on its bar.
pub(crate) fn show_cycles(pb: &ProgressBar, p: &ballast::settlement::AccelerationProgress) {
    if pb.length() != Some(p.target) {
        pb.set_length(p.target);
    }
    pb.set_position(p.cycle);
    pb.set_message(format!("{} computed, settlement {:.4} mm", p.computed, 1e3 * p.settlement));
}

/// The last line of an accelerated run.
pub(crate) fn print_acceleration(s: &ballast::settlement::AccelerationSummary, out: &std::path::Path) {
    println!(
        "{} cycles ({} computed, {:.2}x) in {:.2} s with {} jumps ({} law): settlement {:.4e} m; end: {}; outputs in {}",
        s.total_cycles,
        s.computed_cycles,
        s.gained,
        s.wall_time_s,
        s.jumps,
        s.law.name(),
        s.settlement_m,
        s.end,
        out.display()
    );
}

/// The last line of a run.
pub(crate) fn print_outcome(o: &RunOutcome) {
    let r = &o.report;
    for c in &o.solver_changes {
        println!(
            "resumed at step {} (t = {:.6} s) with {} = {} (was {}); recorded in {}",
            c.step,
            c.time_s,
            c.key,
            c.after,
            c.before,
            o.out.join(ballast::io::layout::SOLVER_CHANGES).display()
        );
    }
    match o.status {
        Status::Stopped => println!(
            "stopped at step {} of {} (t = {:.6} s) after {:.2} s; continue with --resume",
            o.step, o.end_step, o.time, o.elapsed_s
        ),
        Status::Ended(end) => {
            let solver = match r.unconverged_steps {
                Some(0) => ", every step converged".to_string(),
                Some(n) => format!(
                    ", {n} steps stopped at the iteration cap before the solver's tolerance (worst final criterion \
                     {:.3e}; see README, \"not converged\")",
                    r.worst_unconverged_criterion.unwrap_or(0.0)
                ),
                None => String::new(),
            };
            println!(
                "{} steps to t = {:.6} s{} in {:.2} s ({:.3e} body-steps/s on {} threads): {} bodies, final kinetic \
                 energy {:.3e} J, max overlap {:.3e} m at the end ({:.3e} m during the run){solver}; outputs in {}",
                o.step,
                o.time,
                if end == ballast::run::RunEnd::Equilibrium { " (equilibrium reached)" } else { "" },
                o.elapsed_s,
                r.body_steps_per_s,
                r.threads,
                r.bodies,
                o.kinetic_energy,
                r.final_max_overlap_m,
                r.max_overlap_m,
                o.out.display()
            );
        }
    }
}

/// The line of a deposited sample.
pub(crate) fn print_sample(s: &Sample) {
    let r = &s.report;
    println!(
        "sample {}: {} grains, layer {:.1} mm thick; weight {:.2} N, sublayer {:.2} N, walls {:.2} N (balance error \
         {:.2e}); mean overlap {:.2e} m, max {:.2e} m; solid fraction {:.3}, coordination {:.2} ({:.0} % rattlers)",
        s.path.display(),
        r.grains,
        1e3 * r.thickness_m,
        r.weight_n,
        r.sublayer_reaction_n,
        r.wall_friction_n,
        r.balance_error,
        r.mean_overlap_m,
        r.max_overlap_m,
        r.solid_fraction,
        r.coordination,
        100.0 * r.rattler_fraction
    );
}

/// The failed runs of a study (stderr), its summary table and where its outputs are.
pub(crate) fn print_study(r: &StudyReport) {
    for (label, e) in &r.failed {
        eprintln!("run {label} failed: {e}");
    }
    let Some(table) = &r.table else {
        println!(
            "task done (runs in {}); --summarize-only writes the summary once every task has run",
            r.runs.display()
        );
        return;
    };
    println!("{}", table.header.join("  "));
    for row in &table.rows {
        println!("{}", row.join("  "));
    }
    println!("summary: {}; runs in {}", table.path.display(), r.runs.display());
}
