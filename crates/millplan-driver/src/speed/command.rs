//! `millplan speed`'s run: the outputs checked, the program read and its
//! cycle time estimated on a thread of their own while the part and its
//! surface are built, the pass and its checks, the program written beside
//! the estimate of its time, the table and the report, each phase timed.

use super::*;
use crate::feed::file_name;
use crate::io::inputs::PartFile;
use crate::io::outputs::Outputs;
use crate::io::IoError;
use crate::watch::{enforce, Stop, Watch};
use millplan_nc::write::Target;
use millplan_plan::pipeline::Timing;
use std::path::Path;
use std::time::Instant;

/// A `speed` run as its caller asks for it.
pub struct SpeedCommand<'a> {
    pub input: &'a Path,
    pub part: PartFile<'a>,
    pub machine: Option<&'a Path>,
    pub output: &'a Path,
    /// The output's dialect when given (`--to`).
    pub to: Option<Target>,
    pub table: Option<&'a Path>,
    pub report: Option<&'a Path>,
    pub request: SpeedRequest,
    /// How the program is read (its limits bound the writing too).
    pub read: millplan_nc::ReadOptions,
    /// Whether a program the checks refuse is written anyway.
    pub force: bool,
    /// When the run started: its phases add up from there.
    pub started: Instant,
}

/// What a `speed` run made and wrote.
pub struct SpeedRun {
    pub outcome: Outcome,
    pub machine: Machine,
    pub target: Target,
    /// The cycle time of the input and of the output, s.
    pub times: [f64; 2],
    /// The phases of `--timings`.
    pub timings: Vec<Timing>,
    /// Whether every check passed (else the program was written by `--force`).
    pub checked: bool,
}

impl SpeedRun {
    /// The summary of the run of `c`.
    pub fn report(&self, c: &SpeedCommand) -> Report<'_> {
        let written = (c.output.display().to_string(), self.target);
        self.outcome.report(written, &self.machine, self.times)
    }

    /// Whether the run ends with exit 3: a result that cannot be trusted,
    /// or written only by `--force`.
    pub fn findings(&self) -> bool {
        self.outcome.untrusted() || !self.checked
    }
}

/// Runs `c`, `w` hearing the bytes read, the passes' phases
/// (on a long program) and the checks' refusal.
pub fn run_command(c: &SpeedCommand, w: &dyn Watch) -> Result<SpeedRun, Stop> {
    check(&c.request).map_err(Stop::input)?;
    let outs = [("-o", Some(c.output)), ("--table", c.table)];
    let outs = [&outs[..], &[("--report", c.report)]].concat();
    let inputs = [Some(c.input), Some(c.part.path), c.machine];
    let outputs = crate::io::outputs::plan(&inputs, &outs, false)?;
    let machine = crate::io::inputs::read_machine(c.machine)?;
    let t_setup = c.started.elapsed().as_secs_f64();
    std::thread::scope(|s| {
        let beside = machine.clone();
        let reader = s.spawn(move || read_timed(c, &beside, w));
        let joined = |r: std::thread::ScopedJoinHandle<'_, _>| {
            r.join().unwrap_or_else(|e| std::panic::resume_unwind(e))
        };
        let t = Instant::now();
        let mesh = match c.part.read(&c.read.limits) {
            Ok(m) => m,
            // The program's error first, as when it is read first.
            Err(e) => return Err(joined(reader).err().unwrap_or(e).into()),
        };
        let t_mesh = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let surface = Surface::new(&mesh);
        let t_surface = t.elapsed().as_secs_f64();
        let read: ReadBeside = joined(reader)?;
        let t_inputs = c.started.elapsed().as_secs_f64() - t_setup;
        let times = [t_setup, t_mesh, t_surface, t_inputs];
        control(c, (machine, &mesh, surface), (read, times), outputs, w)
    })
}

/// The program at `c.input` read (`w` hearing the bytes) and then its
/// cycle time on `machine`, each timed.
fn read_timed(c: &SpeedCommand, machine: &Machine, w: &dyn Watch) -> Result<ReadBeside, IoError> {
    let t = Instant::now();
    let mut reading = |done, total| w.reading(done, total);
    let (parsed, _) = crate::io::inputs::read_source(c.input, c.read, &mut reading)?;
    let read_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let time_before = cycle_time(&parsed.program, machine);
    let estimate_s = t.elapsed().as_secs_f64();
    Ok(ReadBeside {
        parsed,
        read_s,
        time_before,
        estimate_s,
    })
}

/// The pass over the program read, its checks, the outputs.
fn control(
    c: &SpeedCommand,
    (machine, mesh, surface): (Machine, &millplan_geom::TriMesh, Surface),
    (read, times): (ReadBeside, [f64; 4]),
    mut outputs: Outputs,
    w: &dyn Watch,
) -> Result<SpeedRun, Stop> {
    let parsed = read.parsed;
    if let Some(why) = nothing_to_control(&parsed.program) {
        return Err(Stop::Refused(format!("{}: {why}", c.input.display())));
    }
    w.diagnostics(&parsed.diagnostics);
    let source = parsed.program.source;
    let target = crate::target::output_target(c.to, c.output, Some(&machine), source)
        .map_err(Stop::input)?;
    let long = crate::command_defaults::progress::long_program(&parsed.program);
    let hook = |phase: &str, done: usize, total: usize| {
        if long {
            w.phase(phase, done, total)
        }
    };
    let mut cx = Context::new(machine)
        .with_surface(surface)
        .with_progress(&hook);
    record_reading(&cx, times, [read.read_s, read.estimate_s]);
    let ran = command(&c.request, &mut cx, mesh, parsed.program);
    w.phases_done();
    let out = ran.map_err(|e| match e {
        SpeedError::Pass(e) => Stop::pass(c.input, e),
        SpeedError::NoSummary => Stop::Internal("the speed pass left no summary".into()),
    })?;
    let checked = enforce(&out.checks, c.input, c.force, w)?;
    // The part's findings (open edges, points off the part) are the
    // verdict's warnings: the summary says them, once.
    let time_after = write(c, &cx, &out.program, &mut outputs, target, w)?;
    let times = [read.time_before, time_after];
    cx.time("table and report", || -> Result<(), Stop> {
        if let Some(t) = c.table {
            outputs.write(t, out.table_csv().as_bytes())?;
        }
        if let Some(r) = c.report {
            let names = (file_name(c.input), file_name(c.part.path));
            let html = out.report_html(names, &cx.machine, c.request.cut, times);
            outputs.write(r, html.as_bytes())?;
        }
        Ok(())
    })?;
    cx.time("outputs renamed into place", || outputs.commit())?;
    Ok(SpeedRun {
        outcome: out,
        timings: cx.timings(),
        machine: cx.machine,
        target,
        times,
        checked,
    })
}

/// Writes the program at `c.output` while its cycle time is estimated
/// beside it; the estimate.
fn write(
    c: &SpeedCommand,
    cx: &Context,
    p: &Program,
    outputs: &mut Outputs,
    target: Target,
    w: &dyn Watch,
) -> Result<f64, Stop> {
    let t = Instant::now();
    let mut wo = cx.machine.write_options(target);
    wo.limits = c.read.limits;
    let (written, time_after, [write_s, estimate_s]) = write_beside(p, &cx.machine, || {
        outputs.write_program(c.output, p, wo, c.input)
    });
    w.diagnostics_written(&written?);
    cx.record("  program written and synced", write_s);
    cx.record("  time estimate of the output (beside it)", estimate_s);
    let t_write = t.elapsed().as_secs_f64();
    cx.record("program written, its time estimated", t_write);
    Ok(time_after)
}

#[cfg(test)]
mod tests {
    use super::*;
    use millplan_geom::analytic::{tessellate, DemoSurface};
    use millplan_nc::generate::{raster, Raster};

    /// A watch that says nothing.
    struct Silent;

    impl Watch for Silent {
        fn reading(&self, _: u64, _: u64) {}
        fn diagnostics(&self, _: &[Diagnostic]) {}
        fn strokes(&self, _: usize, _: usize) {}
        fn forces_done(&self) {}
    }

    /// The program read on its own thread comes with the estimate of its
    /// cycle time that `cycle_time` gives; when both the program and the
    /// part fail to read, the program's error is the run's, as when it is
    /// read first; a run on both writes the program.
    #[test]
    fn the_program_is_read_beside_the_part() {
        let dir = tempfile::tempdir().expect("tmp");
        let s = DemoSurface::default();
        let (prog, _) = raster(&s, &Raster::default());
        let mut wo = millplan_nc::write::WriteOptions::new(Target::Apt);
        wo.limits = crate::limits::defaults();
        let (text, _) = millplan_nc::write::write_program(&prog, wo).expect("writes");
        let (input, stl) = (dir.path().join("p.apt"), dir.path().join("part.stl"));
        std::fs::write(&input, text).expect("program");
        let mut bytes = Vec::new();
        millplan_geom::stl::write_binary_stl(&tessellate(&s, 1.5), "part", &mut bytes);
        std::fs::write(&stl, bytes).expect("part");
        let (missing, output) = (dir.path().join("none.apt"), dir.path().join("o.apt"));
        let no_part = dir.path().join("none.stl");
        let machine = Machine::default();
        let mut c = SpeedCommand {
            input: &input,
            part: PartFile {
                path: &stl,
                units: None,
            },
            machine: None,
            output: &output,
            to: None,
            table: None,
            report: None,
            request: super::super::tests::request(),
            read: millplan_nc::ReadOptions {
                limits: crate::limits::defaults(),
                ..Default::default()
            },
            force: true,
            started: Instant::now(),
        };
        let read = read_timed(&c, &machine, &Silent).expect("reads");
        assert_eq!(read.time_before, cycle_time(&read.parsed.program, &machine));
        assert!(run_command(&c, &Silent).is_ok());
        assert!(output.exists());
        c.input = &missing;
        c.part.path = &no_part;
        let Err(Stop::Io(e)) = run_command(&c, &Silent) else {
            panic!("no program, no part")
        };
        assert!(e.message.contains("none.apt"), "{}", e.message);
        assert!(!e.message.contains("none.stl"), "{}", e.message);
    }
}
