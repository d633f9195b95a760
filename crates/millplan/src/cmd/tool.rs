//! `millplan tool`: the tool library and thread-mill active control.

use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::Outputs;
use clap::{Subcommand, ValueEnum};
use millplan_driver::tool::{self as t, Library, ToolError, ToolRequest};
use millplan_tooldb::db::ToolEdit;
use std::path::{Path, PathBuf};

/// The tool library and thread-mill control, for the tool room.
///
/// A typical session: register a tool with its tolerances and insert data
/// (`add`), enter the presetter values (`preset`), generate the measuring
/// program for the control (`cycle`), record the laser's first measurement
/// (`measure --first`) and, after each job, the inspection (`measure`). millplan
/// decides: within tolerance it updates DR/DL; worn beyond RTOL/LTOL it locks the
/// tool and names the sister tool; broken beyond RBREAK/LBREAK it also locks the
/// pallet. Every decision is logged with its reason (`log`).
///
/// The library is one SQLite file: --db, else $MILLPLAN_DB, else
/// ~/.local/share/millplan/tools.db. It is created on first use.
///
/// Exit codes: 0 done; 1 the system refused (the library is locked by another
/// program for longer than 10 s, read-only, or an I/O error); 2 bad arguments,
/// an unknown tool, or a library file millplan cannot use (not a database,
/// damaged, written by a newer millplan), named in the message; 3 `measure`
/// found a problem (setup mismatch, worn or broken: the tool is locked).
/// A library that cannot be read is never taken for an empty one.
#[derive(clap::Args)]
pub struct Args {
    /// Tool library file.
    #[arg(long, global = true)]
    pub db: Option<PathBuf>,
    /// Print JSON on standard output.
    #[arg(long, global = true)]
    pub json: bool,
    #[command(subcommand)]
    pub command: ToolCommand,
}

#[derive(Subcommand)]
pub enum ToolCommand {
    /// Register a tool, or change one (values not given stay as they are).
    Add(AddArgs),
    /// Record the insert mounted on a thread mill (designation, INSL, TP).
    Insert {
        /// Tool number (T).
        number: u32,
        /// Catalogue designation, e.g. "MT LNHU 1403 I1.00 ISO IC908".
        designation: String,
        #[command(flatten)]
        insert: InsertData,
    },
    /// Enter the presetter's length and radius for a tool.
    Preset {
        /// Tool number (T).
        number: u32,
        /// Length, mm.
        #[arg(long)]
        l: f64,
        /// Radius, mm.
        #[arg(long)]
        r: f64,
    },
    /// Record a laser measurement and let millplan decide (wear, worn, broken).
    ///
    /// Decisions: first-accepted and wear-compensated (exit 0: the tool may cut
    /// on); setup-mismatch, worn and broken (exit 3: the tool is locked, and the
    /// pallet too when the tool broke). The decision is printed (with --json as
    /// the `decision` key) and logged either way.
    Measure(MeasureArgs),
    /// List the tools, or show one.
    Show {
        /// Tool number (T); all tools when left out.
        number: Option<u32>,
    },
    /// The decision log (all tools, or one).
    Log {
        /// Tool number (T); every tool's decisions when left out.
        number: Option<u32>,
    },
    /// Import tools from CSV or JSON (all or nothing).
    Import {
        /// CSV (the export's columns) or JSON (a list of tools) file.
        file: PathBuf,
    },
    /// Export the library.
    Export {
        /// csv, json, or tool-t (a Heidenhain TOOL.T-style table).
        #[arg(long, value_enum, default_value = "csv")]
        format: ExportFormat,
        /// Output file (`-`: standard output).
        #[arg(short, long)]
        output: PathBuf,
    },
    /// PZ: the laser's axial measuring point on a thread-mill insert, from
    /// the insert length INSL and the pitch TP (ISO 13399).
    Pz(InsertData),
    /// Write the NC program that measures a tool on the machine's laser.
    Cycle(CycleArgs),
}

/// A thread-mill insert's length and pitch (ISO 13399).
#[derive(clap::Args, Clone, Copy)]
pub struct InsertData {
    /// Insert length INSL, mm (ISO 13399).
    #[arg(long)]
    pub insl: f64,
    /// Thread pitch TP of the insert, mm (at least 0.2, the finest ISO metric pitch).
    #[arg(long)]
    pub tp: f64,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ExportFormat {
    Csv,
    Json,
    /// Heidenhain TOOL.T-style table.
    ToolT,
}

#[derive(clap::Args)]
pub struct AddArgs {
    /// Tool number (T).
    pub number: u32,
    /// Name shown in lists and logs, e.g. "MTE D13.7".
    #[arg(long)]
    pub name: Option<String>,
    /// mill, ball, thread-mill, drill, …
    #[arg(long)]
    pub kind: Option<String>,
    /// Length (presetter), mm.
    #[arg(long)]
    pub l: Option<f64>,
    /// Radius (presetter), mm.
    #[arg(long)]
    pub r: Option<f64>,
    /// Wear tolerance of the length, mm: worn beyond it, the tool is locked.
    #[arg(long)]
    pub ltol: Option<f64>,
    /// Wear tolerance of the radius, mm: worn beyond it, the tool is locked.
    #[arg(long)]
    pub rtol: Option<f64>,
    /// Breakage limit of the length, mm: beyond it the tool and its pallet are locked.
    #[arg(long)]
    pub lbreak: Option<f64>,
    /// Breakage limit of the radius, mm: beyond it the tool and its pallet are locked.
    #[arg(long)]
    pub rbreak: Option<f64>,
    /// Replacement (sister) tool number.
    #[arg(long)]
    pub sister: Option<u32>,
    /// Tool life, minutes.
    #[arg(long)]
    pub life: Option<f64>,
    /// Insert length INSL (thread mills), mm.
    #[arg(long)]
    pub insl: Option<f64>,
    /// Insert thread pitch TP, mm (at least 0.2, the finest ISO metric pitch).
    #[arg(long)]
    pub tp: Option<f64>,
    /// Any ISO 13399 property, SYMBOL=VALUE (repeatable).
    #[arg(long = "iso", value_parser = parse_kv)]
    pub iso: Vec<(String, String)>,
}

fn parse_kv(s: &str) -> Result<(String, String), String> {
    s.split_once('=')
        .map(|(k, v)| (k.trim().to_ascii_uppercase(), v.trim().to_string()))
        .filter(|(k, _)| !k.is_empty())
        .ok_or_else(|| format!("`{s}`: write SYMBOL=VALUE"))
}

#[derive(clap::Args)]
pub struct MeasureArgs {
    /// Tool number (T).
    pub number: u32,
    /// The first measurement on the machine (compared with the presetter).
    #[arg(long)]
    pub first: bool,
    /// Measured length, mm.
    #[arg(long)]
    pub l: Option<f64>,
    /// Measured radius, mm.
    #[arg(long)]
    pub r: Option<f64>,
    /// Measured radii of the single teeth, mm (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub teeth: Option<Vec<f64>>,
    /// Axial measuring point used, mm (defaults to the PZ of the insert data).
    #[arg(long)]
    pub pz: Option<f64>,
    /// Setup tolerance between presetter and first measurement, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::tool::SETUP_TOL)]
    pub dset: f64,
    /// Pallet in the machine (locked when the tool breaks).
    #[arg(long)]
    pub pallet: Option<String>,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Control {
    Heidenhain,
    Fanuc,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum MeasureArg {
    Length,
    Radius,
    Both,
}

#[derive(clap::Args)]
pub struct CycleArgs {
    /// Tool number (T).
    pub number: u32,
    /// The control the measuring program is written for.
    #[arg(long, value_enum, default_value = "heidenhain")]
    pub control: Control,
    /// First measurement instead of an inspection.
    #[arg(long)]
    pub first: bool,
    /// What the laser measures: length, radius or both.
    #[arg(long, value_enum, default_value = "both")]
    pub measure: MeasureArg,
    /// Clearance height above the laser, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::tool::CLEARANCE)]
    pub clearance: f64,
    /// Measure every tooth.
    #[arg(long)]
    pub per_tooth: bool,
    /// Output file (`-`: standard output).
    #[arg(short, long)]
    pub output: PathBuf,
}

impl From<ToolError> for CliError {
    fn from(e: ToolError) -> Self {
        match e.bad_input {
            true => CliError::input(e.message),
            false => CliError::internal(e.message),
        }
    }
}

/// Writes what a subcommand made to `output` (`-`: standard output), never
/// over the library, and says so; else prints its JSON or text.
fn finish(lib: &Library, json: bool, o: t::ToolOutcome, output: Option<&Path>) -> CliResult<i32> {
    let o = match (&o.file, output) {
        (Some((text, pz)), Some(path)) => {
            let mut w = Outputs::plan(&[lib.path.as_path()], &[("-o", Some(path))], true)?;
            w.write(path, text.as_bytes())?;
            w.commit()?;
            if path.as_os_str() == "-" {
                return Ok(EXIT_OK);
            }
            t::ToolOutcome::written(path, *pz)?
        }
        _ => o,
    };
    crate::cmd::print_summary(json, || o.json, || format!("{}\n", o.text));
    Ok(crate::error::exit(o.problem))
}

pub fn run(a: Args) -> CliResult<i32> {
    // PZ needs no library.
    if let ToolCommand::Pz(InsertData { insl, tp }) = a.command {
        let o = t::pz_command(insl, tp)?;
        crate::cmd::print_summary(a.json, || o.json, || format!("{}\n", o.text));
        return Ok(EXIT_OK);
    }
    use std::env::var_os;
    let (db, xdg, home) = (
        var_os("MILLPLAN_DB"),
        var_os("XDG_DATA_HOME"),
        var_os("HOME"),
    );
    let path = t::library_path(a.db, db, xdg, home)?;
    let mut lib = Library::open(path)?;
    let (req, output) = request(a.command);
    let o = t::command(&mut lib, req)?;
    finish(&lib, a.json, o, output.as_deref())
}

/// The subcommand as the driver takes it, and the file it writes.
fn request(c: ToolCommand) -> (ToolRequest, Option<PathBuf>) {
    match c {
        ToolCommand::Add(x) => (ToolRequest::Add(x.number, edit(x)), None),
        ToolCommand::Insert {
            number,
            designation,
            insert: i,
        } => (
            ToolRequest::Insert(number, designation, (i.insl, i.tp)),
            None,
        ),
        ToolCommand::Preset { number, l, r } => (ToolRequest::Preset(number, (l, r)), None),
        ToolCommand::Measure(x) => (measure(x), None),
        ToolCommand::Show { number } => (ToolRequest::Show(number), None),
        ToolCommand::Log { number } => (ToolRequest::Log(number), None),
        ToolCommand::Import { file } => (ToolRequest::Import(file), None),
        ToolCommand::Export { format, output } => {
            (ToolRequest::Export(format.into()), Some(output))
        }
        ToolCommand::Cycle(x) => cycle(x),
        ToolCommand::Pz(i) => unreachable!("PZ {} {} needs no library", i.insl, i.tp),
    }
}

impl From<ExportFormat> for t::ExportFormat {
    fn from(f: ExportFormat) -> Self {
        match f {
            ExportFormat::Csv => t::ExportFormat::Csv,
            ExportFormat::Json => t::ExportFormat::Json,
            ExportFormat::ToolT => t::ExportFormat::ToolT,
        }
    }
}

fn edit(x: AddArgs) -> ToolEdit {
    ToolEdit {
        name: x.name,
        kind: x.kind,
        l: x.l,
        r: x.r,
        ltol: x.ltol,
        rtol: x.rtol,
        lbreak: x.lbreak,
        rbreak: x.rbreak,
        sister: x.sister,
        life_min: x.life,
        insl: x.insl,
        tp: x.tp,
        iso: x.iso,
    }
}

fn measure(x: MeasureArgs) -> ToolRequest {
    let req = t::MeasureRequest {
        number: x.number,
        first: x.first,
        l: x.l,
        r: x.r,
        teeth: x.teeth,
        pz: x.pz,
        dset: x.dset,
    };
    ToolRequest::Measure(req, x.pallet)
}

fn cycle(x: CycleArgs) -> (ToolRequest, Option<PathBuf>) {
    let c = t::CycleRequest {
        number: x.number,
        control: match x.control {
            Control::Heidenhain => t::CycleControl::Heidenhain,
            Control::Fanuc => t::CycleControl::Fanuc,
        },
        first: x.first,
        measured: match x.measure {
            MeasureArg::Length => t::Measured::Length,
            MeasureArg::Radius => t::Measured::Radius,
            MeasureArg::Both => t::Measured::Both,
        },
        clearance: x.clearance,
        per_tooth: x.per_tooth,
    };
    (ToolRequest::Cycle(c), Some(x.output))
}
