//! `millplan convert`'s run: the program read (KRL also as KRL), the
//! dialect, the program resolved and written, the output read back and
//! compared, the program or its KRL split renamed into place.

use super::*;
use crate::io::outputs::Outputs;
use crate::watch::{Stop, Watch};

/// A `convert` run as its caller asks for it.
pub struct ConvertCommand<'a> {
    pub input: &'a Path,
    pub machine: Option<&'a Path>,
    pub output: &'a Path,
    pub convert: ConvertRequest,
    /// How the program is read (its limits bound the writing too).
    pub read: millplan_nc::ReadOptions,
}

/// What a `convert` run wrote.
pub struct Converted {
    pub summary: ConvertSummary,
    /// Whether the output commands what the source does (else written
    /// with `--lossy`, exit 3).
    pub equivalent: bool,
}

/// Runs `c` and writes its output into `outputs` (planned against
/// `inputs`), `w` hearing the work and the laps.
pub fn command(
    c: &ConvertCommand,
    inputs: &[&Path],
    outputs: Outputs,
    w: &dyn Watch,
) -> Result<Converted, Stop> {
    w.lap("arguments and outputs checked");
    let mut reading = |done, total| w.reading(done, total);
    let (parsed, krl) = crate::io::inputs::read_source(c.input, c.read, &mut reading)?;
    w.lap("program read");
    w.diagnostics(&parsed.diagnostics);
    let mut p = parsed.program;
    let machine = crate::io::inputs::read_machine(c.machine)?;
    let req = &c.convert;
    let target = target(req, &machine, c.output, p.source).map_err(Stop::input)?;
    resolve(&mut p, &machine).map_err(|e| Stop::pass(c.input, e))?;
    let mut o = write_options(req, &machine, target);
    o.limits = c.read.limits;
    let mut written = Vec::new();
    let out = match krl.as_ref().map(|k| krl::from_krl(k, target, req.lossy)) {
        Some(Ok(Some(text))) => text.into_bytes(),
        Some(Err(e)) => return Err(crate::io::inputs::krl_error(c.input, e).into()),
        _ => {
            let (out, warnings) = millplan_nc::write::write_program(&p, o)
                .map_err(|e| crate::io::outputs::write_error(c.input, &e))?;
            w.diagnostics_written(&warnings);
            written = warnings;
            out
        }
    };
    w.lap("machine file read, program resolved and written in memory");
    let (input, output) = (
        c.input.display().to_string(),
        c.output.display().to_string(),
    );
    let lossy =
        check_output(&p, &out, target, req.lossy, (&input, &output)).map_err(Stop::Internal)?;
    w.lap("output read back and compared with the program");
    if let Some(l) = &lossy {
        w.warning(l);
    }
    write_out(c, inputs, outputs, target, &out)?;
    w.lap("outputs written and renamed into place");
    // A word written as a comment (--lossy) is one the output does not
    // command: not equivalent, whatever the read-back compares.
    let dropped = written
        .iter()
        .any(|d| d.code == millplan_nc::diag::Code::LossyWord);
    let equivalent = lossy.is_none() && !dropped;
    let mut found = parsed.diagnostics;
    found.extend(written);
    let mut summary =
        ConvertSummary::new((input.as_str(), &found), &p, (&output, target), equivalent);
    if let Some(l) = lossy {
        summary.warnings.push(l);
    }
    Ok(Converted {
        summary,
        equivalent,
    })
}

/// Writes `out` at -o, or with --max-points or --krl-motion its KRL split
/// (a main program and sub-programs beside it).
fn write_out(
    c: &ConvertCommand,
    inputs: &[&Path],
    mut outputs: Outputs,
    target: Target,
    out: &[u8],
) -> Result<(), Stop> {
    let files = krl_files(&c.convert, target, c.output, out).map_err(|e| match e {
        SplitError::Option(m) => Stop::input(m),
        SplitError::Split(m) => Stop::Internal(m),
    })?;
    match files {
        Some(files) => Ok(Outputs::stage_krl(inputs, c.output, &files, 0)?.commit()?),
        None => {
            outputs.write(c.output, out)?;
            Ok(outputs.commit()?)
        }
    }
}
