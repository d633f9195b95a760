//! `millplan orient`: lead and tilt per operation by the force model or the
//! machining time (spec process-models §2.4).

use crate::cmd::cut::VariantArg;
use crate::error::{exit, CliResult};
use millplan_driver::orient::{self as lib, OrientRequest};
use millplan_driver::watch::Watch as _;
use millplan_plan::leadtilt::Objective;
use std::path::PathBuf;

/// Choose lead and tilt per ball-end operation (docs/leadtilt.md):
/// a 5° grid over the ranges, then steepest descent from its best node, on
/// F_xy,max of the force model at --fz (--objective fxy) or on the machining
/// time estimated with acceleration, the feed scaled to keep the original
/// F_xy,max (--objective time).
///
/// Lead and tilt are taken in each point's frame of feed f, cross-feed
/// c = n × f and the part's normal n (from the STL at the contact), the
/// ball centre kept where the program has it. The convention is `cut`'s
/// (docs/leadtilt.md): lead a right-handed turn about c, tilt one about f,
/// R = Rx(tilt)·Ry(lead) by default; a positive lead leans the shank toward
/// the feed (the tip trails), a positive tilt toward −c (right of the feed,
/// seen from the shank). `millplan cut` with the lead and tilt reported
/// (and the same --variant, tool, --flutes, --helix, --fz, --n, --ap,
/// --ae) gives the F_xy,max reported. A candidate is refused when the zero-speed tip would
/// cut (negative lead; zero lead, within 0.01°, unless R·(1 − cos tilt) ≥ --ap), when the
/// shank or holder meets the part at any point, or when the machine's rotary
/// axes cannot reach it. Writes the re-oriented CL (tool axes on every
/// point). Exit 3, nothing written, when no operation can be re-oriented.
///
/// With --stock the forces are evaluated on the engagement of the simulated
/// stock instead of one planar pass of --ap and --ae: the program is run
/// through the stock once as it is (a ball centre kept where the program has
/// it removes the same material at any orientation), and at up to --samples
/// moves per operation that remove material (the heaviest cuts, the rest
/// spread along the operation) the stock before the move is kept around the
/// ball; a candidate's F_xy,max is the largest at those moves, and its tip
/// cuts where, with no lead of the feed against the axis, it lies in that
/// material.
///
/// Before it is written the program is checked: the IR verifier, S and F
/// within the machine, every ball centre where the input put it, with
/// --stock no rapid through material and no shank in it (refused also when
/// the input did it, named as the input's), and no gouge into the part, the
/// input's own refused too (a leaned ball by its distance). A check that fails names its line
/// and exits 3 with nothing written, unless --force.
#[derive(clap::Args)]
pub struct Args {
    /// Program with ball-end operations (APT/CL or G-code).
    pub path: PathBuf,
    #[command(flatten)]
    pub part: crate::cmd::args::Part,
    #[command(flatten)]
    pub machine: crate::cmd::args::MachineFile,
    /// Named material (`millplan force materials` lists them).
    #[arg(long)]
    pub material: String,
    /// A TOML file of further materials (same form as the built-in table).
    #[arg(long)]
    pub materials: Option<PathBuf>,
    /// Lead range LO:HI, degrees (positive: the shank toward the feed).
    #[arg(long, default_value = millplan_driver::command_defaults::orient::LEAD_RANGE, allow_hyphen_values = true)]
    pub lead_range: String,
    /// Tilt range LO:HI, degrees (positive: the shank toward −c, right of
    /// the feed seen from the shank).
    #[arg(long, default_value = millplan_driver::command_defaults::orient::TILT_RANGE, allow_hyphen_values = true)]
    pub tilt_range: String,
    /// What to minimise: fxy (F_xy,max at --fz) or time (with the feed
    /// scaled to the original force level).
    #[arg(long, value_enum, default_value = "fxy")]
    pub objective: ObjectiveArg,
    /// Order of the two turns: tilt-then-lead (R = Rx(tilt)·Ry(lead),
    /// axis (sin L, −cos L·sin T, cos L·cos T)) or lead-then-tilt
    /// (R = Ry(lead)·Rx(tilt), axis (sin L·cos T, −sin T, cos L·cos T));
    /// same signs either way, and `cut --variant` takes the
    /// same.
    #[arg(long, value_enum, default_value = "tilt-then-lead")]
    pub variant: VariantArg,
    /// Feed per tooth the forces are evaluated at, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::FZ)]
    pub fz: f64,
    /// Spindle speed, 1/min (default: the program's first cutting S word).
    #[arg(long)]
    pub n: Option<f64>,
    /// Number of flutes.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::FLUTES)]
    pub flutes: usize,
    /// Helix angle, degrees.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::HELIX_DEG)]
    pub helix: f64,
    /// Axial depth of the engagement the forces are evaluated for, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::AP)]
    pub ap: f64,
    /// Stepover of that engagement, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::AE)]
    pub ae: f64,
    /// Initial stock, for the engagement of the simulated stock instead of
    /// --ap/--ae: box:auto or box:auto:MARGIN, box:X0,Y0,Z0,X1,Y1,Z1,
    /// cylinder:auto or cylinder:auto:MARGIN, cylinder:CX,CY,Z0,Z1,D, stl:FILE
    /// or offset:MM (the --stl part grown by MM), as in `millplan simulate`.
    #[arg(long)]
    pub stock: Option<String>,
    /// Dexel size of the stock, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::RESOLUTION)]
    pub resolution: f64,
    /// Most sample moves per operation on the stock.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::SAMPLES)]
    pub samples: usize,
    /// The shank's reach: from the ball centre to the holder's face, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::REACH)]
    pub reach: f64,
    /// Holder as DIAMETER:LENGTH, mm (default: no holder, the shank alone).
    #[arg(long)]
    pub holder: Option<String>,
    #[command(flatten)]
    pub out: crate::cmd::args::ProgramOutput,
    #[command(flatten)]
    pub units: crate::cmd::args::ProgramUnits,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    #[command(flatten)]
    pub notes: crate::cmd::args::Quiet,
    #[command(flatten)]
    pub force: crate::cmd::args::Force,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum ObjectiveArg {
    Fxy,
    Time,
}

fn request(a: &Args) -> OrientRequest {
    OrientRequest {
        lead_range: a.lead_range.clone(),
        tilt_range: a.tilt_range.clone(),
        variant: a.variant.into(),
        objective: match a.objective {
            ObjectiveArg::Fxy => Objective::Fxy,
            ObjectiveArg::Time => Objective::Time,
        },
        fz: a.fz,
        n: a.n,
        flutes: a.flutes,
        helix: a.helix,
        ap: a.ap,
        ae: a.ae,
        reach: a.reach,
        holder: a.holder.clone(),
        material: a.material.clone(),
        stock: a.stock.clone(),
        resolution: a.resolution,
        samples: a.samples,
    }
}

pub fn run(a: Args) -> CliResult<i32> {
    let watch = crate::progress::Watch::new(&a.path, a.notes.quiet, a.summary.json);
    let watch = watch.bars_under_json();
    let c = lib::OrientCommand {
        input: &a.path,
        part: a.part.file(),
        machine: a.machine.machine.as_deref(),
        materials: a.materials.as_deref(),
        output: &a.out.output,
        to: a.out.to.map(Into::into),
        request: request(&a),
        read: a.units.options()?,
        force: a.force.force,
    };
    let r = lib::run_command(&c, &watch)?;
    a.summary.print(&r.summary, |s| s.render_text());
    watch.lap("summary printed");
    watch.print_timings(a.timings.on);
    Ok(exit(r.findings))
}
