//! The benchmark gate: a fixed set of reduced workloads, each one run of the
//! `millplan` binary under `valgrind --tool=cachegrind --cache-sim=no` on one
//! thread, whose instruction counts (I refs) are compared with a baseline
//! committed in the repository. Instruction counts repeat from run to run
//! within a fraction of a percent where wall times on a shared machine vary
//! by tens of percent, so a regression shows as a count above its baseline.
//!
//! The inputs are generated here, deterministically, from the same
//! generators as the large benchmark inputs ([`crate::big_apt`] and the
//! others), at sizes that keep the whole gate within minutes.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A count more than this fraction above its baseline fails the gate.
pub const TOLERANCE: f64 = 0.03;

/// One workload: a name and the command line of `millplan`, with `{dir}`
/// standing for the folder of the generated inputs.
#[derive(Clone, Debug)]
pub struct Workload {
    pub name: &'static str,
    pub what: &'static str,
    pub args: &'static [&'static str],
    /// Exit codes that count as a run (a command may exit 3 for findings
    /// about its input and still have done all its work).
    pub ok_codes: &'static [i32],
}

/// The gate's workloads, in the order they run.
pub const WORKLOADS: &[Workload] = &[
    Workload {
        name: "speed",
        what: "speed: 100,000-point D10 ball raster on 200,000 triangles",
        args: &[
            "speed",
            "--stl",
            "{dir}/speed.stl",
            "{dir}/raster_100k.apt",
            "--vc",
            "63",
            "--fz",
            "0.125",
            "--ap",
            "0.3",
            "-o",
            "{dir}/speed_out.apt",
            "-q",
        ],
        ok_codes: &[0],
    },
    Workload {
        name: "inspect",
        what: "inspect --json: 1,000,000 GOTOs",
        args: &["inspect", "--json", "{dir}/big.apt"],
        ok_codes: &[0],
    },
    Workload {
        name: "simulate",
        what: "simulate: the 100,000-point raster, box stock at 0.1 mm",
        args: &[
            "simulate",
            "{dir}/raster_100k.apt",
            "--stock",
            "box:auto",
            "--resolution",
            "0.1",
            "-q",
        ],
        ok_codes: &[0],
    },
    Workload {
        name: "feed",
        what: "feed: 10,000-point raster, offset stock at 0.5 mm, al7075, F_xy and deflection limits, 0.2 mm slices, 4° steps",
        args: &[
            "feed",
            "{dir}/raster_10k.apt",
            "--stock",
            "offset:0.3",
            "--stl",
            "{dir}/part.stl",
            "--material",
            "al7075",
            "--limit",
            "fxy=150,deflection=0.05",
            "--resolution",
            "0.5",
            "--dz",
            "0.2",
            "--dphi",
            "4",
            "-o",
            "{dir}/feed_out.apt",
            "-q",
        ],
        ok_codes: &[0],
    },
    Workload {
        name: "post",
        what: "post --g93: 100,000 five-axis CL points, A/C trunnion",
        args: &[
            "post",
            "{dir}/five_axis_100k.apt",
            "--machine",
            "{dir}/trunnion.toml",
            "--g93",
            "-o",
            "{dir}/post_out.nc",
            "-q",
        ],
        ok_codes: &[0],
    },
    Workload {
        name: "raster",
        what: "raster: drop-cutter D10 ball over the demo part (28,800 triangles), 0.4 mm stepover, 0.25 mm steps",
        args: &[
            "raster",
            "--stl",
            "{dir}/part.stl",
            "--tool",
            "ball:10",
            "--stepover",
            "0.4",
            "--step",
            "0.25",
            "--tol",
            "0",
            "-o",
            "{dir}/raster_out.apt",
            "-q",
        ],
        ok_codes: &[0],
    },
    Workload {
        name: "access",
        what: "setup --tool: tool-mode accessibility, 7,200 triangles x 80 icosphere cells, A/C",
        args: &[
            "setup",
            "--stl",
            "{dir}/access.stl",
            "--type",
            "ca",
            "--tool",
            "10,40,40,60",
            "--grid",
            "icosphere",
            "--cells",
            "80",
            "--json",
            "-q",
        ],
        ok_codes: &[0, 3],
    },
];

/// The A/C trunnion of the `post-rate` benchmark: the pivot 100 mm below
/// the table's surface, A within ±120°, A at 150 °/s and C at 300 °/s.
pub const TRUNNION_TOML: &str = "\
name = \"bench A/C trunnion\"
[spindle]
min = 500.0
max = 18000.0
accel = 6000.0
[feed]
min = 1.0
max = 20000.0
rapid = 40000.0
[kinematics]
kind = \"table-ac\"
rot_point = [0.0, 0.0, -100.0]
[kinematics.first]
min = -120.0
max = 120.0
sign = 1.0
[kinematics.second]
sign = 1.0
[axes.a]
velocity = 9000.0
[axes.c]
velocity = 18000.0
";

/// Writes every input of the gate into `dir`.
pub fn write_inputs(dir: &Path) -> std::io::Result<()> {
    use millplan_geom::analytic::{tessellate, DemoSurface};
    let stl = |step: f64| {
        let mesh = tessellate(&DemoSurface::default(), step);
        let mut out = Vec::new();
        millplan_geom::stl::write_binary_stl(&mesh, "solid millplan gate", &mut out);
        out
    };
    std::fs::create_dir_all(dir)?;
    std::fs::write(dir.join("big.apt"), crate::big_apt(1_000_000))?;
    std::fs::write(dir.join("speed.stl"), crate::big_stl(200_000))?;
    std::fs::write(dir.join("raster_100k.apt"), crate::ball_raster_apt(100_000))?;
    std::fs::write(dir.join("raster_10k.apt"), crate::ball_raster_apt(10_000))?;
    std::fs::write(
        dir.join("five_axis_100k.apt"),
        crate::five_axis_apt(100_000),
    )?;
    std::fs::write(dir.join("trunnion.toml"), TRUNNION_TOML)?;
    // The demo part of `millplan demo` (0.5 mm: 28,800 triangles).
    std::fs::write(dir.join("part.stl"), stl(0.5))?;
    // 60 mm / 1 mm cells: 7,200 triangles.
    std::fs::write(dir.join("access.stl"), stl(1.0))?;
    Ok(())
}

/// The command line of a workload with `{dir}` replaced.
pub fn command_line(w: &Workload, dir: &Path) -> Vec<String> {
    let d = dir.display().to_string();
    w.args.iter().map(|a| a.replace("{dir}", &d)).collect()
}

/// The total instruction count from valgrind's summary on standard error,
/// the line `==PID== I   refs:      1,234,567`.
pub fn parse_i_refs(stderr: &str) -> Option<u64> {
    stderr.lines().find_map(|l| {
        let rest = l.split("I   refs:").nth(1)?;
        rest.trim().replace(',', "").parse().ok()
    })
}

/// A baseline: the count of each workload by name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Baseline {
    pub counts: BTreeMap<String, u64>,
}

impl Baseline {
    /// Reads `name = count` lines; `#` starts a comment. An unreadable line
    /// is an error naming its line number.
    pub fn parse(text: &str) -> Result<Baseline, String> {
        let mut counts = BTreeMap::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let Some((name, value)) = line.split_once('=') else {
                return Err(format!("line {}: expected `name = count`", i + 1));
            };
            let value = value.trim().replace('_', "");
            let count = value
                .parse::<u64>()
                .map_err(|e| format!("line {}: {value:?} is not a count: {e}", i + 1))?;
            counts.insert(name.trim().to_string(), count);
        }
        Ok(Baseline { counts })
    }

    /// The file's text: a header saying how it was made, then one line per
    /// workload with what it runs as its comment.
    pub fn render(&self, made_with: &str) -> String {
        let mut s = String::new();
        s.push_str("# Instruction counts (valgrind cachegrind `I refs`, one thread) of the\n");
        s.push_str("# benchmark gate's workloads: `crates/millplan-bench/gate.sh` fails when a\n");
        s.push_str("# count is more than 3 % above its line here. Made by\n");
        s.push_str("# `crates/millplan-bench/gate.sh --update`");
        if !made_with.is_empty() {
            let _ = write!(s, " with {made_with}");
        }
        s.push_str(";\n# update it in the commit that changes a count on purpose, saying why.\n");
        for w in WORKLOADS {
            if let Some(c) = self.counts.get(w.name) {
                let _ = writeln!(s, "{} = {}  # {}", w.name, group(*c), w.what);
            }
        }
        s
    }
}

/// A count with `_` between groups of three digits.
pub fn group(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, ch) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push('_');
        }
        out.push(ch);
    }
    out
}

/// The verdict on one workload's count against its baseline.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// Within the tolerance (the ratio new / baseline).
    Pass(f64),
    /// More than the tolerance above the baseline.
    Fail(f64),
    /// No baseline line for this workload.
    New,
}

/// Compares a count with its baseline.
pub fn judge(baseline: Option<u64>, count: u64) -> Verdict {
    match baseline {
        None | Some(0) => Verdict::New,
        Some(b) => {
            let ratio = count as f64 / b as f64;
            if ratio > 1.0 + TOLERANCE {
                Verdict::Fail(ratio)
            } else {
                Verdict::Pass(ratio)
            }
        }
    }
}

/// The line printed for a workload.
pub fn report_line(name: &str, baseline: Option<u64>, count: u64, verdict: &Verdict) -> String {
    match verdict {
        Verdict::New => format!("{name}: {} instructions (no baseline)", group(count)),
        Verdict::Pass(r) | Verdict::Fail(r) => {
            let b = baseline.unwrap_or(0);
            let word = if matches!(verdict, Verdict::Fail(_)) {
                "FAIL"
            } else {
                "ok"
            };
            format!(
                "{name}: {word}: baseline {}, new {}, ratio {r:.4} ({:+.2} %, limit +{:.0} %)",
                group(b),
                group(count),
                (r - 1.0) * 100.0,
                TOLERANCE * 100.0
            )
        }
    }
}

/// Where the baseline lives in the repository, from the crate's folder.
pub fn default_baseline() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("gate-baseline.toml")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_valgrinds_summary() {
        let err = "==42== Cachegrind, a high-precision tracing profiler\n==42== \n==42== I   refs:      1,234,567,890\n";
        assert_eq!(parse_i_refs(err), Some(1_234_567_890));
        assert_eq!(parse_i_refs("no summary"), None);
    }

    #[test]
    fn baseline_round_trips_and_locates_errors() {
        let mut b = Baseline::default();
        b.counts.insert("speed".into(), 1_234_567);
        b.counts.insert("post".into(), 42);
        let text = b.render("rustc 1.0");
        assert!(text.contains("speed = 1_234_567  # speed:"), "{text}");
        assert_eq!(Baseline::parse(&text), Ok(b));
        let e = Baseline::parse("# c\nspeed = 12x\n").expect_err("a bad count");
        assert!(e.starts_with("line 2:"), "{e}");
        let e = Baseline::parse("speed 12").expect_err("no `=`");
        assert!(e.starts_with("line 1:"), "{e}");
    }

    #[test]
    fn three_percent_above_fails_and_below_passes() {
        assert_eq!(judge(Some(1000), 1030), Verdict::Pass(1.03));
        assert!(matches!(judge(Some(1000), 1031), Verdict::Fail(_)));
        assert!(matches!(judge(Some(1000), 1050), Verdict::Fail(_)));
        assert!(matches!(judge(Some(1000), 500), Verdict::Pass(_)));
        assert_eq!(judge(None, 5), Verdict::New);
        let line = report_line("inspect", Some(1000), 1050, &judge(Some(1000), 1050));
        assert!(
            line.contains("inspect: FAIL: baseline 1_000, new 1_050, ratio 1.0500"),
            "{line}"
        );
    }

    #[test]
    fn every_workload_names_existing_inputs() {
        let dir = tempfile::tempdir().expect("temp dir");
        // The inputs themselves are large; only the names are checked here.
        let names = [
            "big.apt",
            "speed.stl",
            "raster_100k.apt",
            "raster_10k.apt",
            "five_axis_100k.apt",
            "trunnion.toml",
            "part.stl",
            "access.stl",
        ];
        for w in WORKLOADS {
            for a in command_line(w, dir.path()) {
                if let Some(f) = a.strip_prefix(&format!("{}/", dir.path().display())) {
                    assert!(
                        names.contains(&f) || f.contains("_out."),
                        "{}: {f} is not generated",
                        w.name
                    );
                }
            }
        }
    }
}
