//! `millplan reorder`'s run: the machine file, the program and the part
//! read, the passes and their checks, the program written, read back and
//! renamed into place beside the report.

use super::*;
use crate::feed::file_name;
use crate::io::inputs::PartFile;
use crate::watch::{enforce, Stop, Watch};
use millplan_nc::write::Target;
use std::path::Path;

/// A `reorder` run as its caller asks for it.
pub struct ReorderCommand<'a> {
    pub input: &'a Path,
    pub part: PartFile<'a>,
    pub machine: Option<&'a Path>,
    pub output: &'a Path,
    /// The output's dialect when given (`--to`).
    pub to: Option<Target>,
    pub report: Option<&'a Path>,
    pub request: ReorderRequest,
    /// The method's name as the option gives it (the report's and the
    /// summary's).
    pub method: String,
    /// How the program is read (its limits bound the writing too).
    pub read: millplan_nc::ReadOptions,
    /// Whether a program the checks refuse is written anyway.
    pub force: bool,
}

/// What a `reorder` run found and wrote.
pub struct ReorderRun {
    pub outcome: Outcome,
    pub checks: Vec<Check>,
    /// Whether every check passed (else the program was written by `--force`).
    pub checked: bool,
}

impl ReorderRun {
    /// The summary of the run of `c`.
    pub fn summary(&self, c: &ReorderCommand) -> Summary<'_> {
        let output = c.output.display().to_string();
        Summary::new(Some(c.method.clone()), &self.outcome, output, &self.checks)
    }
}

/// Runs `c`: the outputs checked against every file it reads, the passes
/// (their phases told to `w` on a long program), the checks, the program
/// written only when they pass or `--force`; `w` hears the laps.
pub fn run_command(c: &ReorderCommand, w: &dyn Watch) -> Result<ReorderRun, Stop> {
    let rp = c.request.params().map_err(Stop::input)?;
    let outs = [("-o", Some(c.output)), ("--report", c.report)];
    let inputs = [Some(c.input), Some(c.part.path), c.machine];
    let mut outputs = crate::io::outputs::plan(&inputs, &outs, false)?;
    let machine = crate::io::inputs::read_machine(c.machine)?;
    w.lap("arguments, machine file and outputs checked");
    let parsed = crate::watch::read_program(c.input, c.read, w)?;
    let source = parsed.program.source;
    let target = crate::target::output_target(c.to, c.output, Some(&machine), source)
        .map_err(Stop::input)?;
    w.lap("program read");
    let mesh = c.part.read(&c.read.limits)?;
    w.lap("part read");
    let long = crate::command_defaults::progress::long_program(&parsed.program);
    let hook = |phase: &str, done: usize, total: usize| {
        if long {
            w.phase(phase, done, total)
        }
    };
    let cx = Context::new(machine).with_part(&mesh).with_progress(&hook);
    let ran = command(&c.request, rp, &cx, &parsed.program);
    w.phases_done();
    let r = ran.map_err(|e| match e {
        ReorderError::Pass(e) => Stop::pass(c.input, e),
        ReorderError::NoOutcome => Stop::Internal("the reorder pass left no outcome".into()),
    })?;
    w.lap("reordered and checked");
    let mut wo = cx.machine.write_options(target);
    wo.limits = c.read.limits;
    let out = crate::watch::write_program(&r.program, wo, c.input, w)?;
    let output = c.output.display().to_string();
    crate::checks::read_back(&out, target, &r.program, &output).map_err(Stop::Internal)?;
    let checked = enforce(&r.checks, c.input, c.force, w)?;
    outputs.write(c.output, &out)?;
    if let Some(path) = c.report {
        let names = (file_name(c.input), file_name(c.part.path));
        let on = (&cx.machine, c.request.cut);
        let html = r.report_html((&parsed.program, &mesh), names, on, c.method.clone());
        outputs.write(path, html.as_bytes())?;
    }
    outputs.commit()?;
    w.lap("outputs written, read back and renamed into place");
    let (outcome, checks) = (r.outcome, r.checks);
    Ok(ReorderRun {
        outcome,
        checks,
        checked,
    })
}
