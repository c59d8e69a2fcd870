//! posemfa command line. Run `posemfa help`.
//!
//! Layout (docs/cli.md): clap's derive API, one module per subcommand (its arguments struct and its `run`),
//! and [`shared`] for the option groups several subcommands take (`#[command(flatten)]`: the inputs and fit
//! options, the fit output, the articulation band, the rig). [`Command`] lists the subcommands; clap writes
//! the help, the errors and (through clap_complete) the shell completions from the same structs, so neither
//! can miss an option.
//!
//! Exit codes: 0, or 1 for every error (a bad command line included: clap's own code would be 2).

/// println! that never panics (a closed pipe, e.g. `| head`, just ends the output).
#[cfg(not(target_arch = "wasm32"))]
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout().lock(), $($t)*);
    }};
}

#[cfg(not(target_arch = "wasm32"))]
mod articulate_report;
#[cfg(not(target_arch = "wasm32"))]
mod bench;
#[cfg(not(target_arch = "wasm32"))]
mod completions;
#[cfg(not(target_arch = "wasm32"))]
mod crossval;
#[cfg(not(target_arch = "wasm32"))]
mod export_gltf;
#[cfg(not(target_arch = "wasm32"))]
mod fit;
#[cfg(not(target_arch = "wasm32"))]
mod generate;
#[cfg(not(target_arch = "wasm32"))]
mod inspect;
#[cfg(not(target_arch = "wasm32"))]
mod interpolate;
#[cfg(not(target_arch = "wasm32"))]
mod pose;
#[cfg(not(target_arch = "wasm32"))]
mod rig_report;
#[cfg(not(target_arch = "wasm32"))]
mod robustness;
#[cfg(not(target_arch = "wasm32"))]
mod shared;
#[cfg(not(target_arch = "wasm32"))]
mod subdivide;

#[cfg(not(target_arch = "wasm32"))]
use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// What posemfa is and what it reads: the top of `posemfa help`.
#[cfg(not(target_arch = "wasm32"))]
fn about() -> String {
    format!(
        "posemfa: learn rigid parts and their motion from registered triangle meshes\n\n\
         Inputs (DIR_OR_FILES): a {}. Poses are numbered from 1.",
        shared::inputs_help()
    )
}

#[cfg(not(target_arch = "wasm32"))]
#[derive(Parser)]
#[command(
    name = "posemfa",
    version,
    about = about(),
    arg_required_else_help = true,
    after_help = "`posemfa help COMMAND` (or `posemfa COMMAND --help`): one command's arguments and options."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Print the fit's trace to stderr: what each stage decided (the coarse mesh, the merge tree's patches, each
    /// round of the part rule, each refinement trial, SQUAREM's extrapolations)
    #[arg(long, global = true)]
    trace: bool,
}

/// Every subcommand, in the order `posemfa help` lists them.
#[cfg(not(target_arch = "wasm32"))]
#[derive(Subcommand)]
enum Command {
    Inspect(inspect::Args),
    Fit(fit::Args),
    Bench(bench::Args),
    Generate(generate::Args),
    Interpolate(interpolate::Args),
    ExportGltf(export_gltf::Args),
    RigReport(rig_report::Args),
    ArticulateReport(articulate_report::Args),
    Robustness(robustness::Args),
    Pose(pose::Args),
    Crossval(crossval::Args),
    Subdivide(subdivide::Args),
    Completions(completions::Args),
}

#[cfg(not(target_arch = "wasm32"))]
fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // help and --version go to stdout (exit 0); a bad command line to stderr, "error: ..." (exit 1)
            let _ = e.print();
            return if e.use_stderr() { ExitCode::FAILURE } else { ExitCode::SUCCESS };
        }
    };
    if cli.trace {
        posemfa::trace::set_sink(Some(Box::new(|line: &str| eprintln!("trace: {line}"))));
    }
    let res = match cli.command {
        Command::Inspect(a) => inspect::run(a),
        Command::Fit(a) => fit::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Generate(a) => generate::run(a),
        Command::Interpolate(a) => interpolate::run(a),
        Command::ExportGltf(a) => export_gltf::run(a),
        Command::RigReport(a) => rig_report::run(a),
        Command::ArticulateReport(a) => articulate_report::run(a),
        Command::Robustness(a) => robustness::run(a),
        Command::Pose(a) => pose::run(a),
        Command::Crossval(a) => crossval::run(a),
        Command::Subdivide(a) => subdivide::run(a),
        Command::Completions(a) => completions::run(a, <Cli as clap::CommandFactory>::command()),
    };
    match res {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The command line is native only: clap is not a dependency on wasm32 (Cargo.toml), so that no wasm build
/// compiles it. `cargo test --target wasm32-unknown-unknown --test '*'` still builds every binary of the
/// package; this one then only says where the command line runs.
#[cfg(target_arch = "wasm32")]
fn main() -> ExitCode {
    eprintln!("error: the posemfa command line runs on native targets only; in a browser use the page (www/)");
    ExitCode::FAILURE
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// clap's own consistency checks: no option twice in one subcommand, defaults that parse, ...
    #[test]
    fn the_command_line_is_well_formed() {
        Cli::command().debug_assert();
    }

    #[test]
    fn flags_refine_paper_whatever_the_order() {
        let cli = Cli::try_parse_from([
            "posemfa",
            "interpolate",
            "d",
            "--paper-root",
            "--paper",
            "--no-residual",
            "--from",
            "1",
        ])
        .map_err(|e| e.to_string());
        // --to, --t, --out are required
        assert!(cli.is_err());
        let words = ["posemfa", "interpolate", "d", "--paper-root", "--paper", "--no-residual"];
        let rest = ["--from", "1", "--to", "2", "--t", "0.5", "--out", "x.obj", "e"];
        let Command::Interpolate(a) = Cli::try_parse_from(words.iter().chain(&rest)).unwrap().command else {
            panic!("not interpolate")
        };
        assert!(a.paper && a.paper_root && a.no_residual);
        assert_eq!(a.fit.input.inputs, vec!["d".to_string(), "e".to_string()]);
    }
}
