//! `millplan completions` and `millplan man`: the shell completions and the
//! manual pages, generated from the same command tree as `--help`.

use crate::error::{CliError, CliResult, EXIT_OK};
use clap::CommandFactory;
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum ShellArg {
    Bash,
    Zsh,
    Fish,
}

/// Print the completion script for a shell.
///
/// bash: `millplan completions bash > ~/.local/share/bash-completion/completions/millplan`;
/// zsh: `millplan completions zsh > ~/.zfunc/_millplan` (with ~/.zfunc in fpath);
/// fish: `millplan completions fish > ~/.config/fish/completions/millplan.fish`.
#[derive(clap::Args)]
pub struct Args {
    /// The shell: bash, zsh or fish.
    #[arg(value_enum)]
    pub shell: ShellArg,
    /// Print `{"shell", "script"}` as JSON instead of the script alone.
    #[arg(long)]
    pub json: bool,
}

/// The completion script for `shell`.
pub fn script(shell: ShellArg) -> Vec<u8> {
    use clap_complete::{generate, Shell};
    let shell = match shell {
        ShellArg::Bash => Shell::Bash,
        ShellArg::Zsh => Shell::Zsh,
        ShellArg::Fish => Shell::Fish,
    };
    let mut out = Vec::new();
    generate(shell, &mut crate::Cli::command(), "millplan", &mut out);
    out
}

pub fn run(a: Args) -> CliResult<i32> {
    crate::io::reader_may_stop_early();
    let s = script(a.shell);
    if a.json {
        let json = serde_json::json!({
            "shell": format!("{:?}", a.shell).to_lowercase(),
            "script": String::from_utf8_lossy(&s),
        });
        outln!("{json}");
    } else {
        out!("{}", String::from_utf8_lossy(&s));
    }
    Ok(EXIT_OK)
}

/// Write the manual pages (roff): millplan.1 and one page per command
/// (millplan-speed.1, millplan-tool-add.1, …).
///
/// Without -o the page of millplan itself is printed. Read one with
/// `man -l millplan.1`, or put the folder on MANPATH (as its man1/).
#[derive(clap::Args)]
pub struct ManArgs {
    /// Folder to write every page into (created if missing).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Print a JSON summary (the pages written, or the page) on standard output.
    #[arg(long)]
    pub json: bool,
}

/// Every command of the tree but `help`, with the names on its path
/// (`["millplan", "tool", "add"]`).
pub fn tree() -> Vec<(Vec<String>, clap::Command)> {
    let mut root = crate::Cli::command();
    root.build();
    let mut all = Vec::new();
    let mut todo = vec![(vec!["millplan".to_string()], root)];
    while let Some((path, c)) = todo.pop() {
        for s in c.get_subcommands().filter(|s| s.get_name() != "help") {
            let sub = [&path[..], &[s.get_name().to_string()]].concat();
            todo.push((sub, s.clone()));
        }
        all.push((path, c));
    }
    all
}

/// Every page of the tree: its file name and its roff text.
pub fn pages() -> CliResult<Vec<(String, Vec<u8>)>> {
    let mut pages = Vec::new();
    for (path, c) in tree() {
        let name = path.join("-");
        let mut roff = Vec::new();
        clap_mangen::Man::new(c.name(name.clone()))
            .render(&mut roff)
            .map_err(|e| CliError::internal(format!("man page {name}: {e}")))?;
        pages.push((format!("{name}.1"), roff));
    }
    pages.sort();
    Ok(pages)
}

fn write_pages(dir: &Path, pages: &[(String, Vec<u8>)]) -> CliResult<Vec<PathBuf>> {
    std::fs::create_dir_all(dir)
        .map_err(|e| CliError::input(format!("{}: cannot create folder: {e}", dir.display())))?;
    let files: Vec<(PathBuf, &[u8])> = pages.iter().map(|(n, r)| (dir.join(n), &r[..])).collect();
    crate::io::write_all(&files)?;
    Ok(files.into_iter().map(|(p, _)| p).collect())
}

pub fn man(a: ManArgs) -> CliResult<i32> {
    let pages = pages()?;
    match (&a.output, a.json) {
        (Some(dir), json) => {
            let paths = write_pages(dir, &pages)?;
            let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
            if json {
                outln!("{}", serde_json::json!({ "pages": names }));
            } else {
                outln!("wrote {} manual pages into {}", names.len(), dir.display());
            }
        }
        (None, json) => {
            let (_, roff) = pages
                .iter()
                .find(|(n, _)| n == "millplan.1")
                .ok_or_else(|| CliError::internal("no page for millplan"))?;
            let text = String::from_utf8_lossy(roff);
            if json {
                outln!(
                    "{}",
                    serde_json::json!({ "page": "millplan.1", "roff": text })
                );
            } else {
                out!("{text}");
            }
        }
    }
    Ok(EXIT_OK)
}
