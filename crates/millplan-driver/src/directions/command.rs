//! `millplan directions`' run: the cutting data checked, the machine file
//! and the part read, the candidate rasters made within the limits, the
//! candidate paths read, all run under spindle control and ranked.

use super::*;
use crate::io::inputs::PartFile;
use crate::watch::{Stop, Watch};
use millplan_plan::directions::{rank, raster_candidates, Candidate, RankBy};
use millplan_plan::pipeline::Context;
use std::path::{Path, PathBuf};

/// A `directions` run as its caller asks for it.
pub struct DirectionsCommand<'a> {
    pub part: PartFile<'a>,
    pub machine: Option<&'a Path>,
    pub cut: crate::speed::Cutting,
    /// The rasters to generate: one per angle, with this cutter and spacing.
    pub angles: &'a [f64],
    pub tool: &'a str,
    pub stepover: f64,
    pub step: f64,
    /// The candidate programs given, and how they are read (the limits
    /// bound the rasters too).
    pub paths: &'a [PathBuf],
    pub read: millplan_nc::ReadOptions,
    pub by: RankBy,
}

/// Runs `c`, `w` hearing the laps and the bytes of each path read (not
/// its findings).
pub fn run_command(c: &DirectionsCommand, w: &dyn Watch) -> Result<Vec<Ranked>, Stop> {
    c.cut.check().map_err(Stop::input)?;
    let machine = crate::io::inputs::read_machine(c.machine)?;
    let limits = &c.read.limits;
    let mesh = c.part.read(limits)?;
    let cx = Context::new(machine).with_part(&mesh);
    w.lap("machine file and part read");
    let mut candidates = Vec::new();
    if !c.angles.is_empty() {
        let spacing = (c.stepover, c.step);
        let max = limits.moves as f64;
        let (shape, bytes) =
            rasters_within(c.tool, c.angles, spacing, &mesh.bounds(), max).map_err(Stop::input)?;
        crate::limits::check_memory(limits, "the candidate rasters", bytes).map_err(Stop::input)?;
        candidates = raster_candidates(&cx, shape, c.angles, c.stepover, c.step)
            .map_err(|e| Stop::pass(c.part.path, e))?;
        w.lap("candidate rasters made (drop-cutter)");
    }
    for p in c.paths {
        let mut reading = |done, total| w.reading(done, total);
        let (parsed, _) = crate::io::inputs::read_source(p, c.read, &mut reading)?;
        // No findings said: the empty list ends the bar of the bytes read.
        w.diagnostics(&[]);
        candidates.push(Candidate {
            name: p.display().to_string(),
            program: parsed.program,
        });
    }
    if !c.paths.is_empty() {
        w.lap("candidate paths read");
    }
    let ranked =
        rank(candidates, &cx, &c.cut.params(), c.by).map_err(|e| Stop::pass(c.part.path, e))?;
    w.lap("candidates run under spindle control and ranked");
    Ok(ranked)
}
