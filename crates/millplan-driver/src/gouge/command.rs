//! `millplan gouge`'s run: the options checked, the program and the part
//! read, the samples counted against the memory limit before any work, the
//! check.

use super::*;
use crate::io::inputs::PartFile;
use crate::watch::{Stop, Watch};
use std::path::Path;

/// A `gouge` run as its caller asks for it.
pub struct GougeCommand<'a> {
    pub input: &'a Path,
    pub part: PartFile<'a>,
    pub request: GougeRequest,
    /// How the program is read (its limits bound the samples' memory too).
    pub read: millplan_nc::ReadOptions,
}

/// Runs `c`, `w` hearing the laps, the findings on the program and the
/// part and the points checked (on a check long enough to show them).
pub fn run_command(c: &GougeCommand, w: &dyn Watch) -> Result<GougeReport, Stop> {
    let (g, fallback) = params(&c.request).map_err(Stop::input)?;
    let parsed = crate::watch::read_program(c.input, c.read, w)?;
    let path = c.input.display().to_string();
    if fallback.is_none() {
        shape_is_known(&path, &parsed.program).map_err(Stop::input)?;
    }
    w.lap("arguments checked, program read");
    let limits = &c.read.limits;
    let mesh = c.part.read(limits)?;
    let found: Vec<_> = millplan_plan::checks::mesh(&mesh).into_iter().collect();
    w.findings(c.part.path, &found);
    // Counted first: a step of 1e-9 on a long program is refused, not run.
    w.lap("part read");
    let n = sample_count(&parsed.program, fallback, &g);
    let needed = samples_needed(c.request.step, n);
    crate::limits::check_memory(limits, &needed, n * BYTES_PER_SAMPLE).map_err(Stop::input)?;
    let shown = n >= SHOWN_SAMPLES;
    let rep = check(&parsed.program, &mesh, fallback, &g, &|done, _| {
        if shown {
            w.count("gouge check", Some("points"), done, n as usize)
        }
    });
    w.counted();
    w.findings(
        c.input,
        &off_part_finding(&rep).into_iter().collect::<Vec<_>>(),
    );
    w.lap("points checked against the part");
    Ok(rep)
}

/// The error of a run that checked no move of the program at `path` (the
/// moves skipped, by reason), said after its summary.
pub fn nothing_checked(path: &str, rep: &GougeReport) -> Option<String> {
    (rep.moves_checked == 0).then(|| {
        format!(
            "{path}: no move could be checked ({})",
            skipped(&rep.skipped)
        )
    })
}
