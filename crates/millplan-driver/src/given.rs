//! The inputs of a job from what its caller was given (`millplan optimise`
//! and the Python binding's `optimise`): the options checked with one set
//! of ranges and messages, the stock parsed and an `stl:` blank read, the
//! tool library applied to the program.

use crate::io::{inputs, IoError};
use crate::job::{Inputs, Options, OptionsRequest};
use crate::tools::{self, Library, ToolError};
use millplan_geom::limits::Limits;
use millplan_geom::TriMesh;
use millplan_models::force::materials::Materials;
use millplan_nc::{LengthUnit, Program};
use millplan_plan::machine::Machine;
use millplan_sim::stock::spec::StockSpec;

/// What a job was given, its files read by the caller but for an `stl:`
/// stock's blank.
pub struct Given<'a> {
    /// The program as read.
    pub program: Program,
    pub part: Option<TriMesh>,
    /// `--stock` as written.
    pub stock: Option<&'a str>,
    /// The unit of an `stl:` blank's numbers.
    pub stl_units: Option<LengthUnit>,
    /// The limits the blank is read within.
    pub limits: Limits,
    /// The machine of a machine file; `None`: millplan's default.
    pub machine: Option<Machine>,
    pub materials: Materials,
    pub material: Option<String>,
    pub library: Option<&'a Library>,
    pub options: OptionsRequest,
}

/// Why the inputs cannot be made.
#[derive(Debug)]
pub enum GivenError {
    /// An option out of its range or unreadable; the message names it.
    Option(String),
    /// The tool library refuses a tool the program calls, at its line.
    Tool(ToolError),
    /// The blank's file.
    Io(IoError),
}

impl Inputs {
    /// The inputs of a job: the library's tools applied to the program,
    /// the stock parsed (and an `stl:` blank read), every option checked.
    pub fn given(g: Given) -> Result<Inputs, GivenError> {
        let mut program = g.program;
        let library = match g.library {
            Some(l) => tools::apply(&mut program, l).map_err(GivenError::Tool)?,
            None => Vec::new(),
        };
        let stock = g
            .stock
            .map(|s| StockSpec::parse(s).map_err(|e| GivenError::Option(format!("--stock {e}"))))
            .transpose()?;
        let blank = match &stock {
            Some(s) => inputs::read_blank(s, &g.limits, g.stl_units).map_err(GivenError::Io)?,
            None => None,
        };
        let options = Options::checked(&g.options).map_err(GivenError::Option)?;
        Ok(Inputs {
            program,
            part: g.part,
            stock,
            blank,
            machine_given: g.machine.is_some(),
            machine: g.machine.unwrap_or_default(),
            materials: g.materials,
            material: g.material,
            options,
            library,
        })
    }
}
