//! `millplan feed`: a feed per block from the cutting forces; and what
//! `millplan force PATH` shares with it (the program, its stock, the model).

use crate::error::{exit, CliResult};
use crate::io::Outputs;
use millplan_driver::feed::{self as lib, FeedRequest, ModelRequest, Prepared, Watch as _};
use millplan_driver::StockSpec;
use std::path::{Path, PathBuf};

/// What the force model cuts with besides the program: the stock, the part,
/// the material and the tools (shared by `force PATH`, `feed` and `robot`).
#[derive(clap::Args, Clone)]
pub struct ForceInputs {
    /// Initial stock: box:auto or box:auto:MARGIN, box:X0,Y0,Z0,X1,Y1,Z1,
    /// cylinder:auto or cylinder:auto:MARGIN, cylinder:CX,CY,Z0,Z1,D, stl:FILE or
    /// offset:MM (the --stl part grown by MM), as in `millplan simulate`.
    #[arg(long)]
    pub stock: Option<String>,
    #[command(flatten)]
    pub part: crate::cmd::args::OptionalPart,
    /// Named material (`millplan force materials` lists them; en-aw-2007
    /// is the paper's).
    #[arg(long)]
    pub material: Option<String>,
    /// A TOML file of further materials (same form as the built-in table).
    #[arg(long)]
    pub materials: Option<PathBuf>,
    /// Cutter for operations whose tool has no geometry, or to override it:
    /// ball:D, flat:D or bull:D:R.
    #[arg(long)]
    pub tool: Option<String>,
    /// Flutes of every tool.
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::FLUTES)]
    pub flutes: usize,
    /// Helix angle, degrees.
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::HELIX_DEG, allow_hyphen_values = true)]
    pub helix: f64,
    /// Spindle speed, 1/min, for the moves of a program that gives none (no
    /// S word, as some CAM systems write finishing programs): the forces
    /// need one. Moves with an S word keep theirs.
    #[arg(long, value_name = "RPM")]
    pub spindle: Option<f64>,
    /// Dexel size of the stock, mm; also the spacing of the poses each move
    /// is loaded at along its length.
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::RESOLUTION)]
    pub resolution: f64,
}

impl ForceInputs {
    /// The program at `path` and the files of the options, as the driver
    /// reads them.
    pub fn files<'a>(
        &'a self,
        path: &'a Path,
        machine: Option<&'a Path>,
        units: &crate::cmd::args::ProgramUnits,
    ) -> CliResult<lib::ModelFiles<'a>> {
        Ok(lib::ModelFiles {
            program: path,
            stl: self.part.stl.as_deref(),
            stl_units: self.part.units.stl_units.map(Into::into),
            materials: self.materials.as_deref(),
            machine,
            read: units.options()?,
        })
    }

    /// The files the run reads besides the program and a machine file.
    pub fn inputs(&self) -> [Option<PathBuf>; 3] {
        let blank = self.stock.as_deref().and_then(StockSpec::file_of);
        [self.part.stl.clone(), self.materials.clone(), blank]
    }
}

/// The program's stock, material and tools (shared by `force PATH` and `feed`).
#[derive(clap::Args, Clone)]
pub struct ModelArgs {
    #[command(flatten)]
    pub inputs: ForceInputs,
    #[command(flatten)]
    pub machine: crate::cmd::args::MachineFile,
    #[command(flatten)]
    pub tool: crate::cmd::args::ForceModel,
    #[command(flatten)]
    pub units: crate::cmd::args::ProgramUnits,
    /// One CSV row per move: loads, feed per tooth, allowed feed, binding limit.
    #[arg(long, value_name = "FILE")]
    pub table: Option<PathBuf>,
    /// HTML report: loads against time with the limits drawn.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    #[command(flatten)]
    pub notes: crate::cmd::args::Quiet,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

impl ModelArgs {
    /// The options as the driver takes them.
    pub fn request(&self) -> ModelRequest {
        let i = &self.inputs;
        ModelRequest {
            stock: i.stock.clone(),
            material: i.material.clone(),
            tool: i.tool.clone(),
            flutes: i.flutes,
            helix: i.helix,
            stickout: self.tool.stickout,
            flute_length: self.tool.flute_length,
            modulus: self.tool.modulus,
            resolution: i.resolution,
            dz: self.tool.dz,
            dphi: self.tool.dphi,
            fixed_grid: self.tool.fixed_grid,
            spindle: i.spindle,
        }
    }

    /// The header rows of a report on the program at `path` against
    /// `limits`: the files by their names, the run's options.
    pub fn report_inputs(
        &self,
        path: &Path,
        p: &Prepared,
        limits: &millplan_driver::feed::FeedLimits,
    ) -> Vec<(String, String)> {
        let names = lib::InputNames::of(path, self.inputs.part.stl.as_deref());
        lib::model_inputs(&names, &self.request(), p, limits)
    }

    /// The program at `path` and the files of the options, as the driver
    /// reads them.
    pub fn files<'a>(&'a self, path: &'a Path) -> CliResult<lib::ModelFiles<'a>> {
        let machine = self.machine.machine.as_deref();
        self.inputs.files(path, machine, &self.units)
    }

    /// The outputs `outs` of a run on the program at `path`, checked against
    /// them and every file the run reads.
    pub fn plan(&self, path: &Path, outs: &[(&str, Option<&Path>)]) -> CliResult<Outputs> {
        let [a, b, c] = self.inputs.inputs();
        let machine = self.machine.machine.as_deref();
        let inputs = [
            Some(path),
            machine,
            a.as_deref(),
            b.as_deref(),
            c.as_deref(),
        ];
        let (table, report) = (self.table.as_deref(), self.report.as_deref());
        let outs = [outs, &[("--table", table), ("--report", report)]].concat();
        Ok(millplan_driver::io::outputs::plan(&inputs, &outs, false)?)
    }
}

pub fn run(a: Args) -> CliResult<i32> {
    let m = &a.model;
    let watch = crate::progress::Watch::new(&a.path, m.notes.quiet, m.summary.json);
    let outputs = m.plan(&a.path, &[("-o", Some(&a.out.output))])?;
    let loads = crate::limits::loads();
    let c = lib::FeedCommand {
        files: m.files(&a.path)?,
        model: m.request(),
        feed: FeedRequest {
            fz_min: a.fz_min,
            fz_max: a.fz_max,
            fos: a.fos,
            feed_accel: a.feed_accel,
        },
        loads: &loads,
        to: a.out.to.map(Into::into),
        output: &a.out.output,
        table: m.table.clone(),
        report: m.report.clone(),
        force: a.force.force,
    };
    let summary = lib::command(&c, outputs, &watch)?;
    m.summary.print(&summary, |s| s.render_text());
    watch.lap("summary printed");
    watch.print_timings(m.timings.on);
    Ok(exit(summary.findings()))
}

/// A feed per block from the cutting forces (the feed iteration of
/// docs/forces.md).
///
/// The program runs stroke by stroke through its stock; each cutting stroke
/// gets the feed per tooth at which the tightest limit is met: --limit
/// fxy=N,torque=N·mm,power=W,stress=MPa,deflection=mm and the machine's
/// spindle chart (power and torque at the block's speed), power, torque and
/// stress divided by --fos. A block takes the smallest of its strokes'. Blocks
/// whose edge meets no material run at the machine file's `[feed] air`, else
/// at the tool's --fz-max times its flutes and speed. Every cutting move is
/// loaded all along it (every dexel of --resolution), not only where it
/// ends. Feeds stay within --fz-min..--fz-max and the machine's feed range;
/// changes between
/// blocks are brought within the feed acceleration by lowering feeds only.
/// Positions, spindle speeds and feed modes are kept; canned cycles keep
/// their feeds. The written program is simulated again: its own prediction;
/// and checked before it is written: S and F within the machine, every tip
/// where the input put it, no rapid, shank or holder in the stock (the
/// input's own are refused before any force is computed).
///
/// Exit codes: 0 done (moves over a limit by at most 0.5 %, within the
/// model's resolution, are reported as such); 2 bad input; 3 the written
/// program still exceeds a limit by more than 0.5 % somewhere (even
/// --fz-min is too much there; the program is written), or a check refused
/// it (nothing written unless --force).
#[derive(clap::Args)]
pub struct Args {
    /// Program (APT/CL or G-code).
    pub path: PathBuf,
    #[command(flatten)]
    pub model: ModelArgs,
    #[command(flatten)]
    pub out: crate::cmd::args::ProgramOutput,
    /// Smallest feed per tooth, mm (at most a tool's largest).
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::FZ_MIN)]
    pub fz_min: f64,
    /// Largest feed per tooth, mm, for every tool (the tool maker's chip
    /// load); default: per tool, the material's chip load at its diameter
    /// (`fz_max` of the materials table), else 0.02·D.
    #[arg(long)]
    pub fz_max: Option<f64>,
    /// Factor of safety on power, torque and stress.
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::FOS)]
    pub fos: f64,
    /// Feed acceleration, mm/s² (default: the machine's smallest linear-axis
    /// acceleration, else 1000).
    #[arg(long)]
    pub feed_accel: Option<f64>,
    #[command(flatten)]
    pub force: crate::cmd::args::Force,
}
