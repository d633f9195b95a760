//! `millplan`: the command-line front of the planner. The only crate that touches
//! files, the environment, the terminal and exit codes.

/// `println!` that never panics on a closed or full standard output (see
/// `io::out`).
macro_rules! outln {
    () => {
        $crate::io::out(format_args!(""), true)
    };
    ($($t:tt)*) => {
        $crate::io::out(format_args!($($t)*), true)
    };
}

/// `print!` that never panics (see `io::out`).
macro_rules! out {
    ($($t:tt)*) => {
        $crate::io::out(format_args!($($t)*), false)
    };
}

mod cmd;
mod error;
mod io;
mod limits;
mod progress;
mod timings;

use clap::{Parser, Subcommand};
use error::{EXIT_BAD_INPUT, EXIT_FINDINGS, EXIT_INTERNAL, EXIT_OK};

#[global_allocator]
static ALLOC: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Model-based planner and optimiser for milling NC programs.
///
/// millplan reads the toolpath a CAM system wrote (APT/CL or G-code) and the part
/// (STL), simulates what the machine will do and writes a better NC program.
///
/// Exit codes: 0 success; 1 internal failure (or the system refused: a full
/// disk, a closed standard output); 2 bad input or arguments (the message
/// names file:line:col); 3 a check ran and found problems.
///
/// Resource limits (what a small input may ask for) are in docs/usage.md; raise
/// one with --limit NAME=VALUE or MILLPLAN_LIMITS=NAME=VALUE,….
#[derive(Parser)]
#[command(name = "millplan", version, about, long_about, next_line_help = true)]
struct Cli {
    /// Raise (or lower) a resource limit: moves, expansion, line-bytes,
    /// expression-depth, stl-triangles, stl-extent (mm), memory (MB).
    /// Repeatable; a value may end in k, M or G. For `feed`, `force` and
    /// `optimise` also the cutting loads: fxy (N), torque (N·mm), power
    /// (W), stress (MPa), deflection (mm), and the feed per tooth fz_min,
    /// fz_max (mm), several per option separated by commas (--limit
    /// fxy=300,power=2000).
    #[arg(long = "limit", global = true, value_name = "NAME=VALUE")]
    limit: Vec<String>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    Inspect(cmd::inspect::Args),
    Convert(cmd::convert::Args),
    Post(cmd::post::Args),
    Demo(cmd::demo::Args),
    Wd(cmd::wd::Args),
    Cut(cmd::cut::Args),
    Force(cmd::force::Args),
    Feed(cmd::feed::Args),
    Optimise(cmd::optimise::Args),
    Lobes(cmd::lobes::Args),
    Speed(cmd::speed::Args),
    Directions(cmd::directions::Args),
    Gouge(cmd::gouge::Args),
    Raster(cmd::raster::Args),
    Reorder(cmd::reorder::Args),
    Orient(cmd::orient::Args),
    Setup(cmd::setup::Args),
    Simulate(cmd::simulate::Args),
    Tool(cmd::tool::Args),
    Robot(cmd::robot::Args),
    Thread(cmd::thread::Args),
    Explain(cmd::explain::Args),
    #[command(name = "wd-sweep")]
    WdSweep(cmd::sweep::Args),
    Completions(cmd::completions::Args),
    Man(cmd::completions::ManArgs),
}

/// With `MILLPLAN_SMALL_PAGES=1`, faults this process's fresh memory in 4 KiB
/// pages rather than 2 MiB ones. An opt-in for the machines where it was
/// measured to help: under some hypervisors a fresh transparent huge page
/// costs several times its zeroing (2.6–3.2 ms per MB on a 2-core cloud VM,
/// against 0.4–0.6 ms per MB for small pages; `speed` on a million points
/// faulted about 480 MB of them for 0.6–1.1 s of kernel time), while on
/// bare metal huge pages save page-table walks. Nothing is switched
/// process-wide unless asked for, but by `inspect` (its own choice: it
/// holds one flat array of moves, where huge pages only add slack).
fn small_pages_if_asked() -> bool {
    let asked = std::env::var_os("MILLPLAN_SMALL_PAGES").is_some_and(|v| v == "1");
    if asked {
        small_pages_only();
    }
    asked
}

fn small_pages_only() {
    #[cfg(target_os = "linux")]
    {
        // Refused only by kernels before 3.15; huge pages then stay allowed.
        let _ = rustix::thread::disable_transparent_huge_pages(true);
    }
}

/// Standard output is written through `outln!`, which never panics; should
/// a write to it or to standard error panic all the same (a library's
/// print), the run ends with a message and exit 1, never 101.
fn no_panic_on_closed_output() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let p = info.payload();
        let msg = p
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| p.downcast_ref::<&str>().copied())
            .unwrap_or("");
        if let Some(why) = msg.strip_prefix("failed printing to stdout: ") {
            eprintln!("error: standard output: {why}");
            std::process::exit(EXIT_INTERNAL);
        }
        if msg.starts_with("failed printing to stderr") {
            std::process::exit(EXIT_INTERNAL);
        }
        default(info)
    }));
}

/// The exit code of a run that returned `r`, after writing standard output
/// failed with `failure` (if it did): a success becomes 1, what a check found
/// (3) and errors stay.
fn exit_code(r: &Result<i32, error::CliError>, failure: Option<&str>) -> i32 {
    match (r, failure) {
        (Ok(code), None) => *code,
        (Ok(EXIT_FINDINGS), Some(_)) => EXIT_FINDINGS,
        (Ok(_), Some(_)) => EXIT_INTERNAL,
        (Err(e), _) => e.code,
    }
}

/// Whether the command line asks for JSON (`--json` before any `--`): then
/// errors are JSON too, also those of arguments clap refuses.
fn json_requested() -> bool {
    std::env::args_os()
        .skip(1)
        .take_while(|a| a != "--")
        .any(|a| a == "--json")
}

/// Prints an error on standard error: `error: message`, or under `--json`
/// one line `{"error": {…}}`.
fn print_error(message: &str, exit: i32, usage: bool, json: bool) {
    if json {
        eprintln!("{}", error::json(message, exit, usage));
    } else {
        eprintln!("error: {}", error::text(message));
    }
}

fn main() {
    no_panic_on_closed_output();
    small_pages_if_asked();
    let json = json_requested();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) if e.use_stderr() && json => {
            let what = millplan_driver::message::usage_line(&e.to_string());
            print_error(&what, EXIT_BAD_INPUT, true, true);
            std::process::exit(EXIT_BAD_INPUT);
        }
        Err(e) => {
            let code = if e.use_stderr() {
                EXIT_BAD_INPUT
            } else {
                EXIT_OK
            };
            // Help or version text that cannot be written is a failure too.
            if let Err(f) = e.print() {
                eprintln!("error: standard output: {f}");
                std::process::exit(EXIT_INTERNAL);
            }
            std::process::exit(code);
        }
    };
    if let Err(e) = limits::init(&cli.limit) {
        print_error(&e.message, e.code, false, json);
        std::process::exit(e.code);
    }
    io::remove_staged_on_signals();
    let r = run(cli.command);
    let failure = io::stdout_failure();
    if let Err(e) = &r {
        print_error(&e.message, e.code, false, json);
    } else if let Some(f) = &failure {
        let m = format!("standard output: {f}: the output is cut short");
        print_error(&m, EXIT_INTERNAL, false, json);
    }
    std::process::exit(exit_code(&r, failure.as_deref()));
}

fn run(command: Command) -> error::CliResult<i32> {
    match command {
        Command::Inspect(a) => cmd::inspect::run(a),
        Command::Convert(a) => cmd::convert::run(a),
        Command::Post(a) => cmd::post::run(a),
        Command::Demo(a) => cmd::demo::run(a),
        Command::Wd(a) => cmd::wd::run(a),
        Command::Cut(a) => cmd::cut::run(a),
        Command::Force(a) => cmd::force::run(a),
        Command::Feed(a) => cmd::feed::run(a),
        Command::Optimise(a) => cmd::optimise::run(a),
        Command::Orient(a) => cmd::orient::run(a),
        Command::Lobes(a) => cmd::lobes::run(a),
        Command::Speed(a) => cmd::speed::run(a),
        Command::WdSweep(a) => cmd::sweep::run(a),
        Command::Directions(a) => cmd::directions::run(a),
        Command::Gouge(a) => cmd::gouge::run(a),
        Command::Raster(a) => cmd::raster::run(a),
        Command::Reorder(a) => cmd::reorder::run(a),
        Command::Setup(a) => cmd::setup::run(a),
        Command::Simulate(a) => cmd::simulate::run(a),
        Command::Tool(a) => cmd::tool::run(a),
        Command::Robot(a) => cmd::robot::run(a),
        Command::Thread(a) => cmd::thread::run(a),
        Command::Explain(a) => cmd::explain::run(a),
        Command::Completions(a) => cmd::completions::run(a),
        Command::Man(a) => cmd::completions::man(a),
    }
}

#[cfg(test)]
mod help_tests {
    /// Every command of the tree with its path (`millplan tool add`).
    fn commands() -> Vec<(String, clap::Command)> {
        let tree = crate::cmd::completions::tree().into_iter();
        tree.map(|(path, c)| (path.join(" "), c)).collect()
    }

    /// Every command says what it does, and every option and argument of every
    /// command says what it is.
    #[test]
    fn every_command_option_and_argument_has_help() {
        let mut missing = Vec::new();
        let empty = |h: Option<&clap::builder::StyledStr>| {
            h.is_none_or(|h| h.to_string().trim().is_empty())
        };
        for (path, c) in commands() {
            if empty(c.get_about()) && empty(c.get_long_about()) {
                missing.push(path.clone());
            }
            for a in c.get_arguments() {
                if matches!(a.get_id().as_str(), "help" | "version") {
                    continue;
                }
                if empty(a.get_help()) && empty(a.get_long_help()) {
                    missing.push(format!("{path} {}", a.get_id()));
                }
            }
        }
        assert!(commands().len() > 20, "the walk found the subcommands");
        assert!(missing.is_empty(), "without help: {missing:#?}");
    }

    /// Every command that reads an STL can be told its unit.
    #[test]
    fn every_stl_reader_takes_stl_units() {
        for (path, c) in commands() {
            let ids: Vec<&str> = c.get_arguments().map(|a| a.get_id().as_str()).collect();
            if ids.contains(&"stl") {
                assert!(
                    ids.contains(&"stl_units"),
                    "{path} reads --stl without --stl-units"
                );
            }
        }
    }

    /// One layout for every command's help: the text of an option on the
    /// line after its name, never beside it.
    #[test]
    fn every_help_has_one_layout() {
        for (path, mut c) in commands() {
            let help = c.render_long_help().to_string();
            for line in help.lines() {
                let t = line.trim_start();
                // `-o, --output` or `--stl`, not a possible value (`- latlon: …`).
                let option = t.starts_with('-')
                    && t.chars()
                        .nth(1)
                        .is_some_and(|c| c == '-' || c.is_ascii_alphanumeric());
                let option = option || (t.starts_with('<') && line.starts_with("  "));
                assert!(
                    !(option && t.trim_end().contains("  ")),
                    "{path}: `{line}` has its help beside it"
                );
            }
        }
    }
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    /// The kernel reports the process's huge-page setting in
    /// /proc/self/status (Linux 5.0 and later; older kernels skip the check).
    #[test]
    fn small_pages_when_asked() {
        std::env::set_var("MILLPLAN_SMALL_PAGES", "1");
        assert!(super::small_pages_if_asked());
        std::env::set_var("MILLPLAN_SMALL_PAGES", "0");
        assert!(!super::small_pages_if_asked());
        let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
        if let Some(line) = status.lines().find(|l| l.starts_with("THP_enabled:")) {
            assert_eq!(line.split_whitespace().nth(1), Some("0"), "{line}");
        }
    }
}
