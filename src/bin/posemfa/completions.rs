//! `posemfa completions SHELL`: the shell completion script, written by clap_complete from the same
//! definitions as the parser (every subcommand, option and choice).

use clap_complete::Shell;

/// Print the completion script for a shell (bash, zsh, fish, elvish, powershell)
///
/// bash: `posemfa completions bash > ~/.local/share/bash-completion/completions/posemfa`;
/// zsh: `posemfa completions zsh > ~/.zfunc/_posemfa` (with `fpath+=~/.zfunc` before `compinit`);
/// fish: `posemfa completions fish > ~/.config/fish/completions/posemfa.fish`.
#[derive(clap::Args)]
pub struct Args {
    /// The shell
    #[arg(value_name = "SHELL", value_enum)]
    shell: Shell,
}

pub fn run(a: Args, mut command: clap::Command) -> Result<(), String> {
    let mut script = Vec::new();
    clap_complete::generate(a.shell, &mut command, "posemfa", &mut script);
    use std::io::Write;
    // a closed pipe just ends the output, as for every other subcommand
    let _ = std::io::stdout().lock().write_all(&script);
    Ok(())
}
