//! `millplan feed`'s run: the input read and its stock built, its own
//! collisions refused, the limits, the feed pass, the written program's
//! forces and checks, the outputs written together.

use super::*;
use crate::io::outputs::Outputs;
use crate::watch::{enforce, Stop, Watch};
use std::path::{Path, PathBuf};

/// A `feed` run as its caller asks for it.
pub struct FeedCommand<'a> {
    /// The program and the files of the options, and how they are read
    /// (the read limits bound the writing too).
    pub files: ModelFiles<'a>,
    pub model: ModelRequest,
    pub feed: FeedRequest,
    /// The load limits of `--limit NAME=VALUE`.
    pub loads: &'a [(String, String)],
    /// The output's dialect when given (`--to`).
    pub to: Option<millplan_nc::write::Target>,
    pub output: &'a Path,
    /// One CSV row per move (`--table`).
    pub table: Option<PathBuf>,
    /// The HTML report (`--report`).
    pub report: Option<PathBuf>,
    /// Whether a program the checks refuse is written anyway.
    pub force: bool,
}

/// Runs `c` and writes its outputs into `outputs`, `w` hearing the work
/// and the laps; the summary (its findings decide the exit code).
pub fn command(c: &FeedCommand, mut outputs: Outputs, w: &dyn Watch) -> Result<FeedSummary, Stop> {
    let (req, path) = (&c.model, c.files.program);
    w.lap("arguments and outputs checked");
    let p = prepare(&c.files, req, w)?;
    let own = input_collisions(&p, req).map_err(Stop::input)?;
    enforce(&[own], path, c.force, w)?;
    w.lap("the input's rapids, shank and holder on the stock");
    let params = feed_params(&c.feed, req, &p, c.loads).map_err(Stop::input)?;
    let target = crate::target::output_target(c.to, c.output, Some(&p.machine), p.program.source)
        .map_err(Stop::input)?;
    w.lap("limits (learned from the input's forces when none is given), output dialect");
    let ran = schedule(&p, params, req, &|phase, done, total| {
        w.phase(phase, done, total)
    });
    w.phases_done();
    let s = ran.map_err(|e| match e {
        ScheduleError::Pass(e) => Stop::pass(path, e),
        ScheduleError::Missing => Stop::Internal("the feed pass left no result".into()),
    })?;
    stopped_spindle(&path.display().to_string(), &s.before).map_err(Stop::input)?;
    w.lap("feeds scheduled (the input's forces, the feed iteration)");
    let s2 = program_strokes(req, &s.program, p.machine.rapid).map_err(Stop::input)?;
    let total = s2.strokes.len();
    w.strokes(0, total);
    let after = forces_after(&p, &s, &s2, &|d| w.strokes(d, total));
    w.forces_done();
    let after = after.map_err(Stop::input)?;
    let checks = checks(&p, &s.program, req).map_err(Stop::input)?;
    enforce(&checks, path, c.force, w)?;
    w.lap("written program simulated again and checked");
    let mut wo = p.machine.write_options(target);
    wo.limits = c.files.read.limits;
    w.diagnostics_written(&outputs.write_program(c.output, &s.program, wo, path)?);
    let output = c.output.display().to_string();
    let summary = FeedSummary::new(&p, &s, (&after, checks), &output, target.name());
    if let Some(t) = &c.table {
        outputs.write(t, loads_csv(&s.before).as_bytes())?;
    }
    if let Some(r) = &c.report {
        let names = InputNames::of(path, c.files.stl);
        let inputs = model_inputs(&names, req, &p, &s.params.limits);
        let limits = &s.params.limits;
        let html = feed_report(inputs, &summary, &s.before, &after, limits, &p.machine);
        outputs.write(r, html.as_bytes())?;
    }
    outputs.commit()?;
    w.lap("outputs written, checked and renamed into place");
    Ok(summary)
}
