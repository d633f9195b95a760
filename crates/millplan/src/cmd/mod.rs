//! One file per subcommand.

pub mod completions;
pub mod convert;
pub mod cut;
pub mod demo;
pub mod directions;
pub mod explain;
pub mod feed;
pub mod force;
pub mod gouge;
pub mod inspect;
pub mod lobes;
pub mod optimise;
pub mod orient;
pub mod post;
pub mod raster;
pub mod reorder;
pub mod setup;
pub mod simulate;
pub mod speed;
pub mod sweep;
pub mod thread;
pub mod tool;
pub mod wd;

use crate::error::{CliError, CliResult};
use clap::ValueEnum;
use millplan_nc::write::{Target, WriteOptions};
use millplan_nc::{LengthUnit, ReadOptions};

/// The physical range of a numeric argument: above (or from) `lo`, up to
/// `hi`, in `unit`.
#[derive(Clone, Copy, Debug)]
pub struct Range {
    pub lo: f64,
    /// `lo` itself is outside (a positive quantity).
    pub lo_open: bool,
    pub hi: f64,
    pub unit: &'static str,
}

impl Range {
    /// Above 0, at most `hi`.
    pub const fn positive(hi: f64, unit: &'static str) -> Range {
        Range {
            lo: 0.0,
            lo_open: true,
            hi,
            unit,
        }
    }

    /// From `lo` to `hi`, both included.
    pub const fn from(lo: f64, hi: f64, unit: &'static str) -> Range {
        Range {
            lo,
            lo_open: false,
            hi,
            unit,
        }
    }

    fn holds(&self, v: f64) -> bool {
        let above = if self.lo_open {
            v > self.lo
        } else {
            v >= self.lo
        };
        above && v <= self.hi
    }
}

/// A raster's `--stepover` (from D/1000) and `--step` for a tool of diameter `d`.
pub fn raster_spacing(d: f64, stepover: f64, step: f64) -> CliResult<()> {
    arg(
        "--stepover",
        stepover,
        Range::from((d / 1000.0).max(0.001), 1000.0, "mm (from D/1000)"),
    )?;
    arg("--step", step, Range::from(0.001, 1000.0, "mm"))?;
    Ok(())
}

/// Checks a numeric argument: finite and in its range, else an error naming
/// the option, the value and the range (exit 2).
pub fn arg(flag: &str, v: f64, r: Range) -> CliResult<f64> {
    if v.is_finite() && r.holds(v) {
        return Ok(v);
    }
    let unit = if r.unit.is_empty() {
        String::new()
    } else {
        format!(" {}", r.unit)
    };
    let lo = millplan_geom::limits::amount(r.lo);
    let hi = millplan_geom::limits::amount(r.hi);
    // 1e-300 as written, not three hundred zeros.
    let v = if v != 0.0 && (v.abs() < 1e-4 || v.abs() >= 1e9) {
        format!("{v:e}")
    } else {
        format!("{v}")
    };
    Err(CliError::input(if r.lo_open {
        format!("{flag} {v}: must be a number above {lo} and at most {hi}{unit}")
    } else {
        format!("{flag} {v}: must be a number from {lo} to {hi}{unit}")
    }))
}

/// Largest tool diameter any argument may give, mm.
pub const MAX_TOOL_D: f64 = 1000.0;
/// Largest feed, mm/min.
pub const MAX_FEED: f64 = 1e6;
/// Largest spindle speed, 1/min.
pub const MAX_SPINDLE: f64 = 1e6;
/// Largest cutting speed, m/min.
pub const MAX_VC: f64 = 1e4;

/// Checks a cutter from `--tool`: its diameter at most [`MAX_TOOL_D`].
pub fn tool_shape(flag: &str, s: &str) -> CliResult<millplan_models::cutter::Shape> {
    let shape = millplan_models::cutter::Shape::parse(s)
        .map_err(|e| CliError::input(format!("{flag} {e}")))?;
    let d = 2.0 * shape.radius();
    if !(d <= MAX_TOOL_D) {
        return Err(CliError::input(format!(
            "{flag} {s}: the diameter must be at most {MAX_TOOL_D} mm"
        )));
    }
    Ok(shape)
}

/// Cutting data for the commands that evaluate spindle control along the way;
/// the defaults are the paper's test conditions. A negative number is taken
/// as a value so that the range check, not the parser, answers it.
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct CuttingData {
    /// Cutting speed, m/min.
    #[arg(long, default_value_t = 63.0, allow_negative_numbers = true)]
    pub vc: f64,
    /// Feed per tooth, mm.
    #[arg(long, default_value_t = 0.125, allow_negative_numbers = true)]
    pub fz: f64,
    /// Number of flutes.
    #[arg(long, default_value_t = 2)]
    pub flutes: u32,
    /// Stock thickness along the surface normal (finishing allowance), mm.
    #[arg(long, default_value_t = 0.3, allow_negative_numbers = true)]
    pub ap: f64,
}

impl CuttingData {
    /// Checks every value against its physical range.
    pub fn check(&self) -> CliResult<()> {
        arg("--vc", self.vc, Range::positive(MAX_VC, "m/min"))?;
        arg("--fz", self.fz, Range::positive(10.0, "mm"))?;
        arg("--flutes", self.flutes as f64, Range::from(1.0, 1000.0, ""))?;
        arg("--ap", self.ap, Range::positive(MAX_TOOL_D / 2.0, "mm"))?;
        Ok(())
    }

    /// Spindle-control settings for commands that read only the summary and
    /// the program (no per-point rows).
    pub fn params(&self) -> millplan_plan::speed::SpeedParams {
        let mut p = millplan_plan::speed::SpeedParams::new(self.vc, self.fz, self.flutes, self.ap);
        p.keep_rows = false;
        p
    }
}

/// Prints a JSON summary on standard output, every number rounded to what
/// it means (`round::json`).
pub fn print_json(v: serde_json::Value) {
    let v = crate::round::json(v);
    outln!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
}

/// Output dialect, shared by the writing commands.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum TargetArg {
    Fanuc,
    Sinumerik,
    Heidenhain,
    Linuxcnc,
    Apt,
}

impl From<TargetArg> for Target {
    fn from(t: TargetArg) -> Self {
        match t {
            TargetArg::Fanuc => Target::Fanuc,
            TargetArg::Sinumerik => Target::Sinumerik,
            TargetArg::Heidenhain => Target::Heidenhain,
            TargetArg::Linuxcnc => Target::LinuxCnc,
            TargetArg::Apt => Target::Apt,
        }
    }
}

/// The dialect an output is written in: `--to`, else the output file's
/// extension, else the source's own dialect. Never a silent default: a
/// program whose target none of these names is refused.
pub fn target_for(
    to: Option<TargetArg>,
    output: &std::path::Path,
    source: millplan_nc::Dialect,
) -> crate::error::CliResult<Target> {
    if let Some(t) = to {
        return Ok(t.into());
    }
    if let Some(t) = output
        .extension()
        .and_then(|e| e.to_str())
        .and_then(Target::from_extension)
    {
        return Ok(t);
    }
    Target::of(source).ok_or_else(|| {
        crate::error::CliError::input(format!(
            "{}: say which dialect to write with --to (the file name's extension names none)",
            output.display()
        ))
    })
}

/// The dialect to write for a command that reads a machine file: `--to`;
/// else the machine's control, which the output's extension must not
/// contradict; else as [`target_for`].
pub fn target_with_machine(
    to: Option<TargetArg>,
    output: &std::path::Path,
    machine: &millplan_plan::machine::Machine,
    source: millplan_nc::Dialect,
) -> crate::error::CliResult<Target> {
    millplan_driver::target::output_target(to.map(Into::into), output, Some(machine), source)
        .map_err(crate::error::CliError::input)
}

/// Writes a program for `o.target` as the output `path` of `outputs`, a few
/// megabytes at a time: a large program is never held whole as text. Words
/// written as comments under `--lossy` are printed as warnings located in
/// `source`.
pub fn write_program_file(
    p: &millplan_nc::Program,
    o: WriteOptions,
    outputs: &mut crate::io::Outputs,
    path: &std::path::Path,
    source: &std::path::Path,
    quiet: bool,
) -> crate::error::CliResult<()> {
    use millplan_nc::write::WriteError;
    let o = WriteOptions {
        limits: crate::limits::get(),
        ..o
    };
    let mut failed: Option<WriteError> = None;
    let mut warnings = Vec::new();
    let written = outputs.write_with(path, |f| {
        let mut buf = Vec::new();
        let mut io_error = None;
        let r = {
            let mut sink = |b: &[u8]| {
                f.write_all(b).map_err(|e| {
                    let message = e.to_string();
                    io_error = Some(e);
                    WriteError::new(0, message)
                })
            };
            millplan_nc::write::write_program_to(p, o, &mut buf, Some(&mut sink))
        };
        match (r, io_error) {
            (Ok(w), _) => {
                warnings = w;
                f.write_all(&buf)
            }
            (Err(_), Some(e)) => Err(e),
            (Err(e), None) => {
                failed = Some(e);
                Err(std::io::Error::other("the program cannot be written"))
            }
        }
    });
    match failed {
        // Something the target cannot express: the user's input, not the disk.
        Some(e) => Err(crate::error::CliError::input(located(source, &e))),
        None => {
            print_diagnostics(source, &warnings, quiet);
            written
        }
    }
}

/// `file:line:col: message` for a writer's error at a source line.
fn located(source: &std::path::Path, e: &millplan_nc::write::WriteError) -> String {
    if e.line > 0 {
        format!("{}:{}:1: {}", source.display(), e.line, e.message)
    } else {
        format!("{}: {}", source.display(), e.message)
    }
}

/// Writes a program for `o.target` into memory; words written as comments
/// under `--lossy` are printed as warnings located in `source`.
pub fn write_program(
    p: &millplan_nc::Program,
    o: WriteOptions,
    source: &std::path::Path,
    quiet: bool,
) -> crate::error::CliResult<Vec<u8>> {
    let o = WriteOptions {
        limits: crate::limits::get(),
        ..o
    };
    let (out, warnings) = millplan_nc::write::write_program(p, o)
        .map_err(|e| crate::error::CliError::input(located(source, &e)))?;
    print_diagnostics(source, &warnings, quiet);
    Ok(out)
}

/// A pass's failure as the command reports it: the input's fault (exit 2,
/// naming the program) or a bug (exit 1).
pub fn pass_error(
    path: &std::path::Path,
    e: millplan_plan::pipeline::PassError,
) -> crate::error::CliError {
    if e.is_input() {
        crate::error::CliError::input(format!("{}: {e}", path.display()))
    } else {
        crate::error::CliError::internal(format!("{}: {e}", path.display()))
    }
}

/// Source unit override shared by the reading commands.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum UnitArg {
    Mm,
    Inch,
}

impl From<UnitArg> for LengthUnit {
    fn from(u: UnitArg) -> Self {
        match u {
            UnitArg::Mm => LengthUnit::Mm,
            UnitArg::Inch => LengthUnit::Inch,
        }
    }
}

/// Scales a mesh read from an STL to mm: `--stl-units inch` multiplies every
/// coordinate by 25.4; mm (the default: an STL does not say) leaves it.
pub fn stl_to_mm(mesh: &mut millplan_geom::TriMesh, units: Option<UnitArg>) {
    if let Some(UnitArg::Inch) = units {
        mesh.map_vertices(|v| v * 25.4);
    }
}

/// Reader options from the common flags, with the limits of this run.
pub fn read_options(units: Option<UnitArg>, feed: Option<f64>) -> CliResult<ReadOptions> {
    let d = ReadOptions::default();
    Ok(ReadOptions {
        units: units.map(Into::into),
        default_feed: match feed {
            Some(f) => arg("--feed", f, Range::positive(MAX_FEED, "mm/min"))?,
            None => d.default_feed,
        },
        limits: crate::limits::get(),
        ..d
    })
}

/// Prints a program's diagnostics to standard error, prefixed with the file name.
pub fn print_diagnostics(path: &std::path::Path, diags: &[millplan_nc::Diagnostic], quiet: bool) {
    if quiet {
        return;
    }
    for d in diags {
        eprintln!(
            "{}",
            crate::error::text(&d.located(&path.display().to_string()))
        );
    }
}

/// The machine from `--machine FILE` (the machine file, or either of the two
/// older single-purpose files), or the built-in default.
pub fn load_machine(
    path: Option<&std::path::Path>,
) -> crate::error::CliResult<millplan_plan::machine::Machine> {
    use crate::error::CliError;
    match path {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .map_err(|e| CliError::input(format!("{}: cannot read: {e}", p.display())))?;
            millplan_plan::machine::Machine::from_toml(&text).map_err(|e| {
                // `file:line:col: field: message` when the error has a place.
                let sep = if e.at.is_some() { ":" } else { ": " };
                CliError::input(format!("{}{sep}{e}", p.display()))
            })
        }
        None => Ok(millplan_plan::machine::Machine::default()),
    }
}

/// The controller-aware time estimate in JSON: total and nominal, what the
/// total is made of, and how many feed blocks the axes hold back.
pub fn time_json(e: &millplan_plan::timing::TimeEstimate) -> serde_json::Value {
    serde_json::json!({
        "model": "acceleration",
        "total_s": e.total_s,
        "nominal_s": e.nominal_s,
        "rapid_s": e.rapid_s,
        "feed_s": e.feed_s,
        "dwell_s": e.dwell_s,
        "overhead": e.overhead(),
        "velocity_limited_blocks": e.velocity_limited_blocks,
        "accel_limited_blocks": e.accel_limited_blocks,
        "planner": e.planner,
        "by_mode": e.by_mode,
    })
}

/// Seconds as `123 s (0:02:03)`.
pub fn hms(t: f64) -> String {
    let t = t.max(0.0);
    format!(
        "{:.0} s ({}:{:02}:{:02})",
        t,
        (t / 3600.0) as u64,
        ((t / 60.0) as u64) % 60,
        (t as u64) % 60
    )
}
