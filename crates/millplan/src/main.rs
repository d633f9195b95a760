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
/// Resource limits (what a small input may ask for) are in README.md; raise
/// one with --limit NAME=VALUE or MILLPLAN_LIMITS=NAME=VALUE,….
#[derive(Parser)]
#[command(name = "millplan", version, about, long_about)]
struct Cli {
    /// Raise (or lower) a resource limit: moves, expansion, line-bytes,
    /// expression-depth, stl-triangles, stl-extent (mm), memory (MB).
    /// Repeatable; a value may end in k, M or G. For `feed` and `force`
    /// also the cutting loads: fxy (N), torque (N·mm), power (W), stress
    /// (MPa), deflection (mm), several per option separated by commas
    /// (--limit fxy=300,power=2000).
    #[arg(long = "limit", global = true, value_name = "NAME=VALUE")]
    limit: Vec<String>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    Inspect(cmd::inspect::Args),
    Convert(cmd::convert::Args),
    Demo(cmd::demo::Args),
    Wd(cmd::wd::Args),
    Cut(cmd::cut::Args),
    Force(cmd::force::Args),
    Feed(cmd::feed::Args),
    Lobes(cmd::lobes::Args),
    Speed(cmd::speed::Args),
    Directions(cmd::directions::Args),
    Gouge(cmd::gouge::Args),
    Raster(cmd::raster::Args),
    Reorder(cmd::reorder::Args),
    Setup(cmd::setup::Args),
    Simulate(cmd::simulate::Args),
    Tool(cmd::tool::Args),
    Thread(cmd::thread::Args),
    Explain(cmd::explain::Args),
    #[command(name = "wd-sweep")]
    WdSweep(cmd::sweep::Args),
}

/// With `MILLPLAN_SMALL_PAGES=1`, faults this process's fresh memory in 4 KiB
/// pages rather than 2 MiB ones. An opt-in for the machines where it was
/// measured to help: under some hypervisors a fresh transparent huge page
/// costs several times its zeroing (2.6–3.2 ms per MB on a 2-core cloud VM,
/// against 0.4–0.6 ms per MB for small pages; `speed` on a million points
/// faulted about 480 MB of them for 0.6–1.1 s of kernel time), while on
/// bare metal huge pages save page-table walks. Nothing is switched
/// process-wide unless asked for.
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

fn main() {
    no_panic_on_closed_output();
    small_pages_if_asked();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
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
        eprintln!("error: {}", error::shorten(&e.message));
        std::process::exit(e.code);
    }
    io::remove_staged_on_signals();
    let r = run(cli.command);
    let failure = io::stdout_failure();
    if let Err(e) = &r {
        eprintln!("error: {}", error::shorten(&e.message));
    } else if let Some(f) = &failure {
        eprintln!("error: standard output: {f}: the output is cut short");
    }
    std::process::exit(exit_code(&r, failure.as_deref()));
}

fn run(command: Command) -> error::CliResult<i32> {
    match command {
        Command::Inspect(a) => cmd::inspect::run(a),
        Command::Convert(a) => cmd::convert::run(a),
        Command::Demo(a) => cmd::demo::run(a),
        Command::Wd(a) => cmd::wd::run(a),
        Command::Cut(a) => cmd::cut::run(a),
        Command::Force(a) => cmd::force::run(a),
        Command::Feed(a) => cmd::feed::run(a),
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
        Command::Thread(a) => cmd::thread::run(a),
        Command::Explain(a) => cmd::explain::run(a),
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
