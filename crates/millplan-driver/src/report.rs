//! The optimise report: one page (millplan-report's layout) that opens with
//! the verdict and the inputs, then the passes, before → after, the checks
//! and the plots of spindle speed, feed and F_xy along the program.

use crate::finish::{Summary, Verdict};
use crate::run::Loads;
use millplan_nc::Program;
use millplan_plan::force::ForceRun;
use millplan_plan::machine::Machine;
use millplan_report::html::{report_page, worse_words, Evidence, Notes, TIME_WORSE};
use millplan_report::svg::{line_plot, Series};

/// The names of the inputs as the report shows them.
#[derive(Clone, Debug, Default)]
pub struct InputNames {
    pub program: String,
    pub part: Option<String>,
    pub stock: Option<String>,
    pub machine: String,
    pub material: Option<String>,
    pub output: String,
}

impl InputNames {
    /// The names of a job's files: `machine` the machine file (`None`: the
    /// built-in machine, named `machine_name`).
    pub fn of(
        (program, output): (&std::path::Path, &std::path::Path),
        part: Option<&std::path::Path>,
        (stock, material): (Option<&str>, Option<&str>),
        (machine, machine_name): (Option<&std::path::Path>, &str),
    ) -> InputNames {
        let name = |p: &std::path::Path| p.display().to_string();
        InputNames {
            program: name(program),
            part: part.map(name),
            stock: stock.map(str::to_string),
            machine: machine.map_or_else(|| format!("{machine_name} (built-in)"), name),
            material: material.map(str::to_string),
            output: name(output),
        }
    }
}

/// The notes on the passes of `o` that did not run, and why.
pub fn skipped_notes(o: &crate::Outcome) -> Vec<String> {
    o.passes
        .iter()
        .filter(|p| !p.ran)
        .map(|p| format!("note: pass {} skipped: {}", p.name, p.reason))
        .collect()
}

/// The skipped passes' notes of a run an error stopped after its passes
/// (a run that finished says them once, in its table of passes).
pub fn notes_of(
    ran: &Result<(crate::Outcome, crate::Written), crate::job::JobError>,
) -> Vec<String> {
    match ran {
        Ok(_) => Vec::new(),
        Err(e) => e.notes.clone(),
    }
}

/// The line naming the check that refused the written program of `path`.
pub fn refusal_line(s: &Summary, path: &std::path::Path) -> Option<String> {
    s.refusal().map(|(check, line, m)| match line {
        // A finding on the program as a whole.
        0 => format!("{}: check {check} failed: {m}", path.display()),
        _ => format!("{}:{line}: check {check} failed: {m}", path.display()),
    })
}

/// What the report draws: both programs and their forces.
pub struct Plotted<'a> {
    pub before: &'a Program,
    pub after: &'a Program,
    pub forces_before: Option<&'a ForceRun>,
    pub forces_after: Option<&'a ForceRun>,
    pub machine: &'a Machine,
}

fn pct(a: f64, b: f64) -> String {
    format!("{:+.1} %", 100.0 * (b / a.max(1e-12) - 1.0))
}

/// The verdict in words.
pub fn verdict_line(s: &Summary) -> String {
    let t = format!(
        "cycle time {:.1} s → {:.1} s ({})",
        s.time_before_s,
        s.time_after_s,
        pct(s.time_before_s, s.time_after_s)
    );
    match (s.verdict, s.refusal()) {
        (Verdict::Refused, Some((check, 0, m))) => {
            format!("Refused: check `{check}` failed: {m}; {t}")
        }
        (Verdict::Refused, Some((check, line, m))) => {
            format!("Refused: check `{check}` failed at line {line}: {m}; {t}")
        }
        (Verdict::Improved, _) => {
            let faster = s.time_after_s < s.time_before_s * (1.0 - 1e-3);
            match (faster, nearer_words(s)) {
                (true, Some(v)) => format!("Improved: {t}, {v}, every check passed"),
                (false, Some(v)) => format!("Improved: {v} ({t}), every check passed"),
                _ => format!("Improved: {t}, every check passed"),
            }
        }
        (Verdict::Kept, _) => {
            format!("Kept: nothing measured better ({t}); every check passed")
        }
        // Better in one measure, worse in another.
        _ if s.time_after_s < s.time_before_s * (1.0 - 1e-3) => format!(
            "Not improved: faster ({t}) but further from the cutting speed; the passes' program is written, every check passed"
        ),
        _ => match nearer_words(s) {
            Some(v) => format!(
                "Not improved: {v}, but {t}; the passes' program is written, every check passed"
            ),
            None => format!(
                "Not improved: nothing measured better ({t}); the passes' program is written (the passes' table says what bound each), every check passed"
            ),
        },
    }
}

/// The share of points off the cutting speed before → after, where it fell.
fn nearer_words(s: &Summary) -> Option<String> {
    match (s.vc_off_before, s.vc_off_after) {
        (Some(b), Some(a)) if a < b - 1e-3 => Some(format!(
            "points off the cutting speed {:.1} % → {:.1} %",
            100.0 * b,
            100.0 * a
        )),
        _ => None,
    }
}

fn loads_row(b: Option<Loads>, a: Option<Loads>) -> Vec<(String, String)> {
    let (Some(b), Some(a)) = (b, a) else {
        return vec![(
            "loads".into(),
            "not computed (no stock or no material)".into(),
        )];
    };
    vec![
        ("max F_xy, N".into(), format!("{:.1} → {:.1}", b.fxy, a.fxy)),
        (
            "max torque, N·mm".into(),
            format!("{:.1} → {:.1}", b.torque, a.torque),
        ),
        (
            "max power, W".into(),
            format!("{:.1} → {:.1}", b.power, a.power),
        ),
        (
            "max deflection, mm".into(),
            format!("{:.4} → {:.4}", b.deflection, a.deflection),
        ),
    ]
}

fn rows(s: &Summary) -> Vec<(String, String)> {
    let mut r = Vec::new();
    for p in &s.passes {
        let state = if p.ran {
            format!("ran, {:.2} s", p.seconds)
        } else {
            "skipped".into()
        };
        r.push((format!("pass {}", p.name), format!("{state}: {}", p.reason)));
    }
    r.push((
        "cycle time (with acceleration), s".into(),
        format!(
            "{:.1} → {:.1} ({})",
            s.time_before_s,
            s.time_after_s,
            pct(s.time_before_s, s.time_after_s)
        ),
    ));
    r.extend(loads_row(s.max_before, s.max_after));
    let share = |x: Option<f64>| x.map_or("–".to_string(), |v| format!("{:.1} %", 100.0 * v));
    r.push((
        "points off the cutting speed".into(),
        format!("{} → {}", share(s.vc_off_before), share(s.vc_off_after)),
    ));
    for c in &s.checks {
        let found = if c.findings.is_empty() {
            "none".to_string()
        } else {
            let line = |l: Option<u32>| l.map_or("–".to_string(), |l| l.to_string());
            let words = |f: &millplan_plan::safety::Finding| {
                let own = if f.in_input { " (in the input)" } else { "" };
                format!("line {}: {}{own}", line(f.line), f.message)
            };
            c.findings
                .iter()
                .take(5)
                .map(words)
                .collect::<Vec<_>>()
                .join("; ")
        };
        let state = if c.ok { "ok" } else { "FAILED" };
        let skipped = c
            .skipped
            .as_deref()
            .map_or(String::new(), |w| format!("; skipped: {w}"));
        r.push((
            format!("check {}", c.name),
            format!(
                "{state} ({} {}{skipped}); findings: {found}",
                c.checked, c.unit
            ),
        ));
    }
    r
}

/// The warnings of a run: what the checks found in the input itself.
pub(crate) fn warnings(s: &Summary) -> Vec<String> {
    // A stock no cut meets: the loads and the stock check say nothing.
    let missed = s
        .passes
        .iter()
        .filter(|p| !p.ran && p.reason == crate::passes::STOCK_MISSED);
    let missed = missed.map(|p| format!("pass {} skipped: {}", p.name, p.reason));
    let found = s
        .checks
        .iter()
        .flat_map(|c| {
            c.findings
                .iter()
                .filter(|f| f.in_input)
                .map(move |f| match f.line {
                    Some(l) => format!(
                        "the input already has this ({}): line {l}: {}",
                        c.name, f.message
                    ),
                    None => format!("the input already has this ({}): {}", c.name, f.message),
                })
        })
        .take(20);
    missed.chain(found).collect()
}

/// The verdict as the text summary prints it: its level and why (what
/// failed, what got worse), then the words of [`verdict_line`].
pub fn verdict_text(s: &Summary) -> String {
    format!(
        "{} {}",
        millplan_report::html::headline(&evidence(s), warnings(s).len()),
        verdict_line(s)
    )
}

/// The text summary of `optimise`: the settings and where each came from,
/// the passes (time or skipped, why), the verdict, the checks, and what
/// was written to `output` (or, `withheld`, that nothing was).
pub fn summary_text(s: &Summary, output: &std::path::Path, withheld: bool) -> String {
    use std::fmt::Write as _;
    let mut o = String::new();
    for x in &s.settings {
        let _ = writeln!(o, "  {:<13} {}  ({})", x.name, x.value, x.from);
    }
    for p in &s.passes {
        let state = if p.ran {
            format!("{:>7.2} s", p.seconds)
        } else {
            "skipped".into()
        };
        let _ = writeln!(o, "  {:<8} {state}  {}", p.name, p.reason);
    }
    let _ = writeln!(o, "{}", verdict_text(s));
    for c in &s.checks {
        let skipped = c
            .skipped
            .as_deref()
            .map_or(String::new(), |w| format!(" (skipped: {w})"));
        let ok = if c.ok { "ok" } else { "FAILED" };
        let (name, checked, unit) = (c.name, c.checked, c.unit);
        let _ = writeln!(o, "  check {name:<10} {ok:<6} {checked} {unit}{skipped}");
    }
    // What the verdict's warnings are: the input's own faults.
    for w in warnings(s) {
        let _ = writeln!(o, "  warning: {w}");
    }
    if withheld {
        o.push_str("nothing written (give --force to write it anyway)");
    } else {
        let _ = write!(o, "wrote {} ({})", output.display(), s.dialect);
    }
    o
}

/// The level of a run's verdict, by the one rule of every report.
pub fn level(s: &Summary) -> millplan_report::html::Level {
    millplan_report::html::Level::of(&evidence(s), warnings(s).len())
}

fn notes(s: &Summary, n: &InputNames) -> Notes {
    let mut inputs = vec![("program".to_string(), n.program.clone())];
    let opt = |v: &Option<String>| v.clone().unwrap_or_else(|| "not given".into());
    inputs.push(("part".into(), opt(&n.part)));
    inputs.push(("stock".into(), opt(&n.stock)));
    inputs.push(("machine".into(), n.machine.clone()));
    inputs.push(("material".into(), opt(&n.material)));
    inputs.push(("output".into(), format!("{} ({})", n.output, s.dialect)));
    for x in &s.settings {
        inputs.push((x.name.to_string(), format!("{} ({})", x.value, x.from)));
    }
    let warnings = warnings(s);
    Notes::judged(inputs, warnings, &evidence(s), vec![verdict_line(s)])
}

/// What the optimise verdict is decided from: the checks of the written
/// program, whether the input was kept, and the measures the passes exist
/// for (cycle time, points off the cutting speed) that got worse.
pub fn evidence(s: &Summary) -> Evidence {
    let failed = millplan_report::html::failed_checks(&s.checks);
    let mut worse = Vec::new();
    if s.time_after_s > s.time_before_s * (1.0 + TIME_WORSE) {
        worse.push(worse_words(
            "cycle time",
            s.time_before_s,
            s.time_after_s,
            1,
            "s",
        ));
    }
    if let (Some(b), Some(a)) = (s.vc_off_before, s.vc_off_after) {
        if a > b {
            worse.push(worse_words(
                "points off the cutting speed",
                100.0 * b,
                100.0 * a,
                1,
                "%",
            ));
        }
    }
    // Not better, yet changed: the program written is the passes', so the
    // input is not what is kept; say what did not get better instead.
    let kept = s.verdict == Verdict::Kept;
    let not_better = (s.verdict == Verdict::NotImproved && worse.is_empty()).then(|| {
        format!(
            "nothing measured better than the input (cycle time {:.1} → {:.1} s)",
            s.time_before_s, s.time_after_s
        )
    });
    Evidence {
        failed,
        kept,
        worse,
        not_better,
    }
}

/// (time from the start, value) of every cutting move of a force run.
fn along(f: &ForceRun, v: impl Fn(&millplan_plan::force::MoveForces) -> f64) -> Vec<(f64, f64)> {
    f.moves
        .iter()
        .filter(|m| !m.rapid)
        .map(|m| (m.t_start_s, v(m)))
        .collect()
}

/// (time from the start, value) of every cutting move of a program, the
/// time estimated with acceleration.
fn along_program(
    p: &Program,
    m: &Machine,
    v: impl Fn(&millplan_nc::Move) -> f64,
) -> Vec<(f64, f64)> {
    let e = millplan_plan::timing::estimate_program(p, m);
    let mut t = 0.0;
    let mut out = Vec::new();
    for (mv, dt) in p
        .moves()
        .zip(e.per_move_s.iter().chain(std::iter::repeat(&0.0)))
    {
        if mv.is_cutting() {
            out.push((t, v(mv)));
        }
        t += dt;
    }
    out
}

fn plot(title: &str, ylabel: &str, b: Vec<(f64, f64)>, a: Vec<(f64, f64)>) -> (String, String) {
    let series = [
        Series {
            name: "input",
            color: "#888",
            points: b,
        },
        Series {
            name: "optimised",
            color: "#c33",
            points: a,
        },
    ];
    (
        title.to_string(),
        line_plot(title, "time from the start, s", ylabel, &series),
    )
}

fn figures(p: &Plotted) -> Vec<(String, String)> {
    let m = p.machine;
    let mut v = vec![
        plot(
            "spindle speed",
            "1/min",
            along_program(p.before, m, |x| x.spindle),
            along_program(p.after, m, |x| x.spindle),
        ),
        plot(
            "feed",
            "mm/min",
            along_program(p.before, m, |x| x.feed),
            along_program(p.after, m, |x| x.feed),
        ),
    ];
    if let (Some(b), Some(a)) = (p.forces_before, p.forces_after) {
        v.push(plot(
            "F_xy,max per move (at the programmed feeds' times)",
            "N",
            along(b, |x| x.fxy_max),
            along(a, |x| x.fxy_max),
        ));
    }
    v
}

/// The report page; with `optimise --robot` it ends with the robot
/// section.
pub fn html(s: &Summary, names: &InputNames, p: &Plotted) -> String {
    let page = report_page(
        &format!("millplan optimise: {}", names.program),
        "The program through the passes its inputs allow, written, read back from its own bytes and checked before it was put in place.",
        &notes(s, names),
        &rows(s),
        &figures(p),
    );
    const END: &str = "</body></html>";
    match (&s.robot, page.strip_suffix(END)) {
        (Some(r), Some(body)) => format!("{body}{}{END}", robot_section(r)),
        _ => page,
    }
}

/// The section of the robot pass: the tip's deflection under the process
/// load before compensation and what the compensated KRL leaves.
fn robot_section(r: &crate::robot_pass::RobotSummary) -> String {
    let mut h = String::from(
        "<section id=\"robot\"><h2>Robot compensation</h2><p>The tool tip's deflection |Δp| under the process load on the compliant robot, at the commanded points, before compensation; after it, the KRL written is read back and run on the robot model again.</p><table>",
    );
    for (k, v) in r.rows() {
        h.push_str(&format!("<tr><td>{k}</td><td>{v}</td></tr>"));
    }
    h.push_str("</table></section>");
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(verdict: Verdict, times: (f64, f64), vc: (f64, f64), unchanged: bool) -> Summary {
        // As the job's summary: not improved when the passes changed it.
        let verdict = match verdict {
            Verdict::Kept if !unchanged => Verdict::NotImproved,
            v => v,
        };
        Summary {
            verdict,
            level: millplan_report::html::Level::Green,
            warnings: Vec::new(),
            passes: Vec::new(),
            time_before_s: times.0,
            time_after_s: times.1,
            max_before: None,
            max_after: None,
            vc_off_before: Some(vc.0),
            vc_off_after: Some(vc.1),
            checks: Vec::new(),
            settings: Vec::new(),
            dialect: "fanuc".into(),
            moves: 10,
            input_unchanged: unchanged,
            robot: None,
        }
    }

    /// "Kept" says the input is kept only when the program written is the
    /// input; a changed program that measures no better says so instead.
    #[test]
    fn kept_means_the_input_only_when_it_is_written_unchanged() {
        let same = summary(Verdict::Kept, (10.0, 10.0), (0.5, 0.5), true);
        assert!(evidence(&same).kept);
        assert!(!verdict_line(&same).contains("passes' program"));
        let changed = summary(Verdict::Kept, (10.0, 10.0), (0.5, 0.5), false);
        let e = evidence(&changed);
        assert!(!e.kept);
        assert!(e.worse.is_empty(), "nothing got worse: {:?}", e.worse);
        let n = e.not_better.as_deref().unwrap_or_default();
        assert!(n.contains("nothing measured better"), "{n}");
        assert!(verdict_line(&changed).contains("the passes' program is written"));
        assert_eq!(level(&changed), millplan_report::html::Level::Amber);
    }

    /// An improvement names the measure that improved; one measure better
    /// with the other worse is no improvement (a program nearer the cutting
    /// speed that runs twice as long is not what a user asked for), and the
    /// words say both.
    #[test]
    fn improved_names_what_improved_and_a_trade_is_kept() {
        let d = crate::finish::decide;
        assert_eq!(
            d(false, (34.9, 34.0), (Some(0.9), Some(0.1))),
            Verdict::Improved
        );
        assert_eq!(
            d(false, (34.9, 34.9), (Some(0.9), Some(0.1))),
            Verdict::Improved
        );
        assert_eq!(
            d(false, (34.9, 20.0), (Some(0.2), Some(0.2))),
            Verdict::Improved
        );
        assert_eq!(d(false, (34.9, 20.0), (None, None)), Verdict::Improved);
        assert_eq!(
            d(false, (34.9, 68.0), (Some(0.9), Some(0.1))),
            Verdict::Kept
        );
        assert_eq!(
            d(false, (34.9, 20.0), (Some(0.1), Some(0.5))),
            Verdict::Kept
        );
        assert_eq!(
            d(false, (34.9, 34.9), (Some(0.5), Some(0.5))),
            Verdict::Kept
        );
        assert_eq!(
            d(true, (34.9, 20.0), (Some(0.9), Some(0.1))),
            Verdict::Refused
        );
        let vc_only = summary(Verdict::Improved, (34.9, 34.9), (0.9, 0.1), false);
        let line = verdict_line(&vc_only);
        assert!(
            line.starts_with("Improved: points off the cutting speed 90.0 % → 10.0 %"),
            "{line}"
        );
        let both = summary(Verdict::Improved, (20.0, 10.0), (0.9, 0.1), false);
        assert!(verdict_line(&both).starts_with("Improved: cycle time 20.0 s → 10.0 s"));
        let slower = summary(Verdict::Kept, (34.9, 68.0), (0.9, 0.1), false);
        let line = verdict_line(&slower);
        assert!(
            line.starts_with("Not improved: points off the cutting speed 90.0 % → 10.0 %, but cycle time 34.9 s → 68.0 s (+94.8 %)"),
            "{line}"
        );
        assert_eq!(level(&slower), millplan_report::html::Level::Amber);
        let farther = summary(Verdict::Kept, (20.0, 10.0), (0.1, 0.5), false);
        assert!(
            verdict_line(&farther).starts_with("Not improved: faster (cycle time 20.0 s → 10.0 s")
        );
    }
}
