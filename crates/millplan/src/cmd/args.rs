//! Argument groups that several commands share, declared once and
//! flattened into each (`#[command(flatten)]`): the same option in the same
//! words everywhere, and what the binary does with it in one place.

use crate::cmd::{TargetArg, UnitArg};
use crate::error::CliResult;
use std::path::{Path, PathBuf};

/// The unit of the STL files a command reads.
#[derive(clap::Args, Clone, Copy)]
pub struct PartUnits {
    /// Unit of the numbers of the STL files read (the part, and the blank of
    /// an stl: stock; an STL does not say): mm (default) or inch, converted
    /// to mm on reading.
    #[arg(long, value_enum)]
    pub stl_units: Option<UnitArg>,
}

impl PartUnits {
    /// Reads the part at `stl` (refused without a triangle), in mm.
    pub fn read(&self, stl: &Path) -> CliResult<millplan_geom::TriMesh> {
        Ok(crate::io::read_surface(stl, self.stl_units)?.0)
    }
}

/// The part of the commands that need one: `--stl` and its unit.
#[derive(clap::Args, Clone)]
pub struct Part {
    /// Part surface (STL), in the coordinates of the programs read with it.
    #[arg(long)]
    pub stl: PathBuf,
    #[command(flatten)]
    pub units: PartUnits,
}

impl Part {
    /// The part's file and unit, as the driver's runs read it.
    pub fn file(&self) -> millplan_driver::io::inputs::PartFile<'_> {
        let units = self.units.stl_units.map(Into::into);
        millplan_driver::io::inputs::PartFile {
            path: &self.stl,
            units,
        }
    }
}

/// The part of the commands that can do without one.
#[derive(clap::Args, Clone)]
pub struct OptionalPart {
    /// Part surface (STL), in the program's coordinates: the part --stock
    /// offset:MM grows, and what the command measures or checks against
    /// where its description says so.
    #[arg(long)]
    pub stl: Option<PathBuf>,
    #[command(flatten)]
    pub units: PartUnits,
}

impl OptionalPart {
    /// The part, in mm, when `--stl` is given.
    pub fn read(&self) -> CliResult<Option<millplan_geom::TriMesh>> {
        self.stl.as_deref().map(|p| self.units.read(p)).transpose()
    }
}

/// `--units` of the commands that read a program.
#[derive(clap::Args, Clone, Copy)]
pub struct ProgramUnits {
    /// Unit of the program's numbers, mm or inch, taken instead of what the
    /// file says or implies: for a program that does not say (NX's Haas
    /// posts, bare GOTO files) or says wrongly.
    #[arg(long, value_enum)]
    pub units: Option<UnitArg>,
}

impl ProgramUnits {
    /// The reader's options with this unit and the run's limits.
    pub fn options(&self) -> CliResult<millplan_nc::ReadOptions> {
        crate::cmd::read_options(self.units, None)
    }

    /// Reads the program at `path` and prints its diagnostics (none when
    /// `quiet`).
    pub fn read(&self, path: &Path, quiet: bool) -> CliResult<millplan_nc::Parsed> {
        let parsed = crate::io::read_program(path, self.options()?)?;
        crate::cmd::print_diagnostics(path, &parsed.diagnostics, quiet);
        Ok(parsed)
    }
}

/// `--machine` of the commands for which a machine file is optional.
#[derive(clap::Args, Clone)]
pub struct MachineFile {
    /// Machine file (TOML; examples/machine.toml documents it): spindle and
    /// feed ranges, spindle chart, rapid rate, the axes' limits for the time
    /// estimate, rotary limits and kinematics, the control's dialect, each
    /// used where the command needs it. Default: a built-in typical HSC
    /// machine (three axes, no spindle chart).
    #[arg(long)]
    pub machine: Option<PathBuf>,
}

impl MachineFile {
    /// The machine of the file, or the built-in default.
    pub fn load(&self) -> CliResult<millplan_plan::machine::Machine> {
        crate::cmd::load_machine(self.machine.as_deref())
    }
}

/// The program a command writes, and its dialect.
#[derive(clap::Args, Clone)]
pub struct ProgramOutput {
    /// Output program.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output dialect (default: the machine file's control; else the
    /// output's extension: .nc Fanuc, .mpf Sinumerik, .h Heidenhain, .ngc
    /// LinuxCNC, .apt/.cls APT, .src KRL; else the input's).
    #[arg(long, value_enum)]
    pub to: Option<TargetArg>,
}

/// `--force` of the commands that check what they write.
#[derive(clap::Args, Clone, Copy)]
pub struct Force {
    /// Write the output even when a check before writing refuses it (the
    /// checks are those the command's description names); the findings are
    /// printed and the run ends with exit 3.
    #[arg(long)]
    pub force: bool,
}

/// The force model's tool body and steps (`cut`, `feed`, `force PATH`).
#[derive(clap::Args, Clone, Copy)]
pub struct ForceModel {
    /// Gauge length from the holder face to the tip, mm (default 3·D).
    #[arg(long)]
    pub stickout: Option<f64>,
    /// Fluted length, mm (default: the program's tool height where a program
    /// gives one, else the stick-out); shorter than the stick-out it makes
    /// the tool a stepped cantilever (shank D, flutes 0.8·D).
    #[arg(long)]
    pub flute_length: Option<f64>,
    /// Young's modulus of the tool, N/mm².
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::MODULUS)]
    pub modulus: f64,
    /// Slice length of the force model along the tool's profile, mm: the
    /// largest used (per engagement the model halves it, up to four times,
    /// until F_xy,max and T_max are estimated within 0.4 %), unless
    /// --fixed-grid.
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::DZ)]
    pub dz: f64,
    /// Rotation step of the force model, degrees: the largest used, halved
    /// like --dz.
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::DPHI_DEG)]
    pub dphi: f64,
    /// Use --dz and --dphi as given instead of refining them per engagement
    /// until F_xy,max and T_max converge. Faster on engagements with sharp
    /// force peaks, where the given steps can miss a peak by a few per cent.
    #[arg(long)]
    pub fixed_grid: bool,
}

/// `--json` of the commands with a machine-readable summary.
#[derive(clap::Args, Clone, Copy)]
pub struct SummaryJson {
    /// Print a machine-readable summary (JSON) on standard output; errors too,
    /// as JSON on standard error.
    #[arg(long)]
    pub json: bool,
}

impl SummaryJson {
    /// Prints `v` as JSON (numbers rounded to what they mean), else its text.
    pub fn print<T: serde::Serialize>(&self, v: &T, text: impl FnOnce(&T) -> String) {
        crate::cmd::print_summary(self.json, || v, || text(v));
    }
}

/// `-q` of the commands that warn about their inputs.
#[derive(clap::Args, Clone, Copy)]
pub struct Quiet {
    /// Print no warnings, notes or progress bars (errors still print, and so
    /// does the bar of reading a large file).
    #[arg(long, short)]
    pub quiet: bool,
}

/// `--timings` of the commands that name their phases.
#[derive(clap::Args, Clone, Copy)]
pub struct Timings {
    /// Print the wall time of each phase on standard error (they add up to
    /// the whole run).
    #[arg(long = "timings")]
    pub on: bool,
}
