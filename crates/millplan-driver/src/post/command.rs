//! `millplan post`'s run: the machine file, the CL program read and
//! posted, the posted tips checked, the program written, read back and
//! renamed into place.

use super::*;
use crate::io::outputs::Outputs;
use crate::watch::{enforce, Stop, Watch};
use millplan_nc::readback::ReadBackStream;
use millplan_plan::post::{for_target, post, Posted};

/// A `post` run as its caller asks for it.
pub struct PostCommand<'a> {
    pub input: &'a Path,
    pub machine: &'a Path,
    pub output: &'a Path,
    /// The output's dialect when given (`--to`).
    pub to: Option<Target>,
    pub post: PostRequest,
    /// How the CL file is read (its limits bound the writing too).
    pub read: millplan_nc::ReadOptions,
    /// Whether a program the checks refuse is written anyway.
    pub force: bool,
}

/// What a `post` run wrote and found.
pub struct PostRun {
    pub machine: Machine,
    pub options: PostOptions,
    pub target: Target,
    pub report: PostReport,
    pub checks: Vec<Check>,
    /// Whether every check passed (else the program was written by `--force`).
    pub checked: bool,
}

impl PostRun {
    /// The summary of the post of `c`.
    pub fn summary(&self, c: &PostCommand) -> PostSummary<'_> {
        let (o, machine, target) = (&self.options, &self.machine, self.target);
        let files = (c.input, c.output);
        PostSummary::new(files, o, machine, target, &self.report, &self.checks)
    }
}

/// A post error of the CL file at `path` as the run stops on it.
fn stop(path: &Path, e: &PostError) -> Stop {
    match error(&path.display().to_string(), e) {
        (true, message) => Stop::Refused(message),
        (false, message) => Stop::input(message),
    }
}

/// Runs `c` and writes the posted program into `outputs`, `w` hearing the
/// work and the laps.
pub fn command(c: &PostCommand, mut outputs: Outputs, w: &dyn Watch) -> Result<PostRun, Stop> {
    let machine = crate::io::inputs::read_machine(Some(c.machine))?;
    let o = options(&c.post, &machine).map_err(Stop::input)?;
    let target = target(c.to, c.output, &machine, c.machine).map_err(Stop::input)?;
    w.lap("arguments, machine file and outputs checked");
    let parsed = crate::watch::read_program(c.input, c.read, w)?;
    w.lap("read CL file");
    w.busy(Some("posting"));
    let posted = post(&parsed.program, &machine, &o).map_err(|e| stop(c.input, &e));
    // The CL program stays for the tip check.
    let Posted {
        mut program,
        report,
    } = posted?;
    w.lap("post (IK, DP over the path, linearisation, feeds, time estimates)");
    for_target(&mut program, target).map_err(|e| stop(c.input, &e))?;
    w.busy(None);
    // The checks before the writing, so that the CL program is gone before
    // the G-code text and the program read back from it are made.
    let checks = check_posted(&parsed.program, &program, &machine, o.tol);
    drop(parsed);
    w.lap("checks (IR, machine, tips through the kinematics)");
    let mut wo = write_options(&machine, target);
    wo.limits = c.read.limits;
    let names = (
        &*c.output.display().to_string(),
        &*c.input.display().to_string(),
    );
    if c.output.as_os_str() == "-" {
        // Standard output cannot be taken back: the text is read back
        // before any of it is written.
        let (out, warnings) = millplan_nc::write::write_program(&program, wo)
            .map_err(|e| crate::io::outputs::write_error(c.input, &e))?;
        w.diagnostics_written(&warnings);
        w.lap("G-code written (in memory)");
        read_back_check(&program, &out, &wo, c.post.tol, names).map_err(Stop::Internal)?;
        let checked = enforce(&checks, c.input, c.force, w)?;
        w.lap("written program read back and compared");
        outputs.write(c.output, &out)?;
        outputs.commit()?;
        w.lap("program written");
        return Ok(PostRun {
            machine,
            options: o,
            target,
            report,
            checks,
            checked,
        });
    }
    // A file is staged as it is written, each piece of the text read back
    // as the writer hands it over, and renamed into place only once what
    // it reads as is what was posted: no copy of the whole text is held.
    let tol = read_back_tolerance(c.post.tol);
    let mut back = ReadBackStream::new(wo.target, &program, wo.g93_seconds);
    let mut failed = None;
    let mut tee = |b: &[u8]| {
        if failed.is_none() {
            if let Err(e) = back.feed(b) {
                failed = Some(e);
            }
        }
    };
    let written = outputs.write_program_tee(c.output, &program, wo, c.input, &mut tee);
    w.diagnostics_written(&written?);
    let back = match failed {
        Some(e) => Err(e),
        None => back.finish(&tol),
    };
    w.lap("G-code written, staged and synced, and read back as written");
    read_back_verdict(back, names).map_err(Stop::Internal)?;
    let checked = enforce(&checks, c.input, c.force, w)?;
    outputs.commit()?;
    w.lap("read back compared, program renamed into place");
    let (options, report) = (o, report);
    Ok(PostRun {
        machine,
        options,
        target,
        report,
        checks,
        checked,
    })
}
