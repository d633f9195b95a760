//! The checks of a written program, run on the program re-read from its own
//! bytes (`millplan_nc::readback`) before it is renamed into place: the
//! read-back itself, then `millplan_plan::safety::check` (IR, machine, tip,
//! stock, gouge, loads) with the job's tools, stock, part and limits.

use millplan_nc::Program;
use millplan_plan::force::{FeedLimits, ForceRun};
use millplan_plan::machine::Machine;
use millplan_plan::safety::Load;

/// A dialect that names tools by number only (G-code) loses their shape:
/// the re-read program's operations take the shapes of the program written,
/// so every later check runs with the same tools; and where its moves are
/// those written one for one, their source lines, so findings name the
/// input's lines.
pub fn same_tools(back: &mut Program, out: &Program) {
    if back.operations.len() != out.operations.len() {
        return;
    }
    for (b, o) in back.operations.iter_mut().zip(&out.operations) {
        if b.moves.len() == o.moves.len() {
            for (x, y) in b.moves.iter_mut().zip(&o.moves) {
                x.line = y.line;
            }
        }
        let Some(ot) = &o.tool else { continue };
        match &mut b.tool {
            Some(bt) if bt.cutter.is_none() => bt.cutter = ot.cutter,
            None => b.tool = Some(ot.clone()),
            _ => {}
        }
    }
}

/// The program whose loads are checked as those of the program written
/// (`back`, read from its bytes): the program the job wrote in memory
/// (`out`) with the feed, spindle speed and feed mode of each move as read
/// back, where the two have the same moves one for one, of the same kinds,
/// every end within the written words' rounding of the other
/// ([`PAIRED_MM`], and `tol`, the tip check's, where that is finer; an
/// unknown coordinate only with an unknown one). Its path is then the one
/// the passes computed on, so the force run finds its engaged cells in what
/// the job's run over the input kept. `None` where the moves do not pair,
/// and for a program with arcs or canned cycles (their centres, depths and
/// cycle feeds are not compared here): the program read back is then
/// checked as it is.
pub fn loads_program(back: &Program, out: &Program, tol: f64) -> Option<Program> {
    if back.operations.len() != out.operations.len() {
        return None;
    }
    let near = PAIRED_MM.min(tol);
    let same = |a: f64, b: f64| (a.is_nan() && b.is_nan()) || (a - b).abs() <= near;
    let mut p = out.clone();
    for (b, o) in back.operations.iter().zip(&mut p.operations) {
        if b.moves.len() != o.moves.len() || !o.arcs.is_empty() || !o.cycles.is_empty() {
            return None;
        }
        for (x, y) in b.moves.iter().zip(&mut o.moves) {
            let kind = std::mem::discriminant(&x.kind) == std::mem::discriminant(&y.kind);
            let end = (0..3).all(|i| same(x.end[i], y.end[i]));
            if !(kind && end) {
                return None;
            }
            y.feed = x.feed;
            y.spindle = x.spindle;
            y.feed_mode = x.feed_mode;
        }
    }
    Some(p)
}

/// How far apart a written end and the end it was written from may lie
/// for [`loads_program`] to pair them, mm: the rounding of three decimals
/// (0.0005 mm), with room for the binary fractions.
pub const PAIRED_MM: f64 = 0.001;

/// Every limited load of every modelled cutting move of `run` (forces of
/// `p`), with its limit at the move's spindle speed (the machine's chart
/// included; power, torque and stress divided by the factor of safety).
pub fn loads_of(p: &Program, run: &ForceRun, l: &FeedLimits, m: &Machine) -> Vec<Load> {
    let mut at = Vec::with_capacity(p.move_count());
    for (oi, op) in p.operations.iter().enumerate() {
        at.extend((0..op.moves.len()).map(|mi| (oi, mi)));
    }
    let mut v = Vec::new();
    for x in run.moves.iter().filter(|x| !x.rapid && !x.unmodelled) {
        let Some(&(op, mv)) = at.get(x.index as usize) else {
            continue;
        };
        // The job always gives its fz range (`fz_max` set), so the tool's
        // diameter, which only picks a material's chip load, is not consulted.
        let lim = l.at(x.rpm, f64::NAN, m);
        let fos = lim.fos.max(1.0);
        let pairs = [
            ("fxy", x.fxy_max, lim.fxy),
            ("torque", x.torque_max, lim.torque.map(|t| t / fos)),
            ("power", x.power_w, lim.power.map(|t| t / fos)),
            ("stress", x.stress_mpa, lim.stress.map(|t| t / fos)),
            ("deflection", x.deflection_mm, lim.deflection),
        ];
        for (name, value, limit) in pairs {
            if let Some(limit) = limit {
                let name = name.to_string();
                v.push(Load {
                    op,
                    mv,
                    name,
                    value,
                    limit,
                });
            }
        }
    }
    v
}

/// Refusing findings a command prints before "and N more".
pub const SHOWN: usize = 20;

/// A refusing finding as a command prints it: `PATH:LINE: check NAME:
/// message`, marked when the input already had it.
pub fn located(
    path: &str,
    c: &millplan_plan::safety::Check,
    f: &millplan_plan::safety::Finding,
) -> String {
    let at = match f.line {
        Some(l) => format!("{path}:{l}"),
        None => path.to_string(),
    };
    let own = if f.in_input {
        " (the input's own fault)"
    } else {
        ""
    };
    format!("{at}: check {}: {}{own}", c.name, f.message)
}

/// What failed checks of a program at `path` say: the lines to print (the
/// first [`SHOWN`] refusing findings, then how many more) and the first
/// refusal, the run's error; `None` when every check passed.
pub fn refusal(
    checks: &[millplan_plan::safety::Check],
    path: &str,
) -> Option<(Vec<String>, String)> {
    use millplan_plan::safety::{first_refusal, passed};
    if passed(checks) {
        return None;
    }
    let refusing: Vec<_> = checks
        .iter()
        .flat_map(|c| c.refusing().map(move |f| (c, f)))
        .collect();
    let mut lines: Vec<String> = refusing
        .iter()
        .take(SHOWN)
        .map(|(c, f)| located(path, c, f))
        .collect();
    if refusing.len() > SHOWN {
        lines.push(format!("… and {} more", refusing.len() - SHOWN));
    }
    let first = match first_refusal(checks) {
        Some((c, f)) => located(path, c, f),
        None => format!("{path}: a check failed"),
    };
    Some((lines, first))
}

/// Reads `out` (the bytes written for `target` from `p`) back: bytes that
/// do not read, or do not command what `p` does, are a writer's bug and
/// are not written; the error names `output`'s line.
pub fn read_back(
    out: &[u8],
    target: millplan_nc::write::Target,
    p: &Program,
    output: &str,
) -> Result<millplan_nc::readback::ReadBack, String> {
    let tol = millplan_nc::equiv::Tolerance::default();
    let back = millplan_nc::readback::read_back(out, target, p, &tol).map_err(|e| {
        format!("{output}: the program written does not read back ({e}); not written")
    })?;
    if let Err(m) = &back.equiv {
        return Err(format!(
            "{output}:{}: the program written would not command what was made ({m}); not written",
            m.line_b
        ));
    }
    Ok(back)
}

#[cfg(test)]
mod tests {
    use super::*;
    use millplan_nc::{parse_program, ReadOptions};
    use millplan_plan::force::MoveForces;

    fn program(src: &str) -> Program {
        parse_program(src, ReadOptions::default())
            .expect("reads")
            .program
    }

    /// The loads check takes the feeds and speeds read back on the path
    /// computed on only where every end pairs within the rounding of the
    /// written words; else (a step off, an arc, another count of moves) the
    /// program read back is checked as it is.
    #[test]
    fn the_loads_checked_pair_the_written_feeds_with_the_path_within_its_rounding() {
        let out = program(
            "G21 G90\nT1 M6\nS6000 M3\nG0 X0 Y0 Z5\nG1 Z-1.00004 F300\nG1 X10.33333\nM30\n",
        );
        let back =
            program("G21 G90\nT1 M6\nS6600 M3\nG0 X0 Y0 Z5\nG1 Z-1. F450\nG1 X10.3333\nM30\n");
        let p = loads_program(&back, &out, 0.01).expect("pairs");
        let moves: Vec<_> = p.operations.iter().flat_map(|o| &o.moves).collect();
        let read: Vec<_> = back.operations.iter().flat_map(|o| &o.moves).collect();
        let wrote: Vec<_> = out.operations.iter().flat_map(|o| &o.moves).collect();
        assert_eq!(moves.len(), 3);
        for ((m, r), w) in moves.iter().zip(&read).zip(&wrote) {
            assert_eq!((m.feed, m.spindle), (r.feed, r.spindle));
            assert_eq!(
                m.end.to_array().map(f64::to_bits),
                w.end.to_array().map(f64::to_bits)
            );
        }
        assert_eq!(moves[1].feed, 450.0);
        // Off by more than the rounding, or than the tip check's tolerance.
        let off =
            program("G21 G90\nT1 M6\nS6600 M3\nG0 X0 Y0 Z5\nG1 Z-1.002 F450\nG1 X10.3333\nM30\n");
        assert!(loads_program(&off, &out, 0.01).is_none());
        assert!(loads_program(&back, &out, 0.00001).is_none());
        // Another count of moves, or an arc.
        let fewer = program("G21 G90\nT1 M6\nS6600 M3\nG0 X0 Y0 Z5\nG1 Z-1. F450\nM30\n");
        assert!(loads_program(&fewer, &out, 0.01).is_none());
        let arc =
            program("G21 G90\nT1 M6\nS6000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F300\nG2 X10 Y0 I5 J0\nM30\n");
        assert!(loads_program(&arc, &arc, 0.01).is_none());
    }

    #[test]
    fn loads_name_their_move_and_the_charts_limit() {
        let p = program("G21 G90\nT1 M6\nS6000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F300\nG1 X10\nM30\n");
        let mv = |index: u32, fxy: f64| MoveForces {
            index,
            rpm: 6000.0,
            fxy_max: fxy,
            ..MoveForces::default()
        };
        let run = ForceRun {
            moves: vec![mv(1, 90.0), mv(2, 120.0)],
            ..ForceRun::default()
        };
        let l = FeedLimits {
            fxy: Some(100.0),
            torque: None,
            power: None,
            stress: None,
            deflection: None,
            fos: 1.0,
            fz_min: 0.01,
            fz_max: Some(0.1),
            chip_loads: None,
        };
        let v = loads_of(&p, &run, &l, &Machine::default());
        let fxy: Vec<_> = v.iter().filter(|x| x.name == "fxy").collect();
        assert_eq!(fxy.len(), 2);
        assert_eq!((fxy[1].op, fxy[1].mv, fxy[1].value), (0, 2, 120.0));
        let c = millplan_plan::safety::loads(&p, &|_: &Program| v.clone(), 0.005);
        assert!(!c.ok);
        assert_eq!(c.findings[0].line, Some(6), "the move over its limit");
    }
}
