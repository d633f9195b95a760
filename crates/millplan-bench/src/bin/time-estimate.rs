//! The controller-aware time estimate (`millplan_plan::timing`) on large
//! inputs:
//!
//! 1. BLOCKS machine-axis blocks (default 1,000,000): a five-axis finishing
//!    path of 0.2–1 mm chords along a wavy curve with A and C turning,
//!    feeds varying, a rapid every 5,000 blocks, on the example machine
//!    (examples/machine.toml: per-axis velocities, accelerations and jerks).
//!    Target: well under a second.
//! 2. The generated five-axis APT program of `five_axis_apt` (POINTS points,
//!    default 100,000) read and timed through the example machine's
//!    kinematics: nominal (length / feed) against the estimate with
//!    acceleration, the effect the paper's time table (T9b) is about.
//!
//! Usage: `time-estimate [BLOCKS] [POINTS]`.

use millplan_plan::machine::Machine;
use millplan_plan::timing::{estimate_axes, estimate_program, AxisMove, MoveKind};

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args
        .next()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let points: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let text = include_str!("../../../../examples/machine.toml");
    let machine = match Machine::from_toml(text) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("examples/machine.toml: {e}");
            std::process::exit(1);
        }
    };
    let mut s = 0x9e3779b97f4a7c15u64;
    let mut r = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut moves = Vec::with_capacity(n);
    let (mut x, mut a) = (0.0f64, 0.0f64);
    for k in 0..n {
        let step = 0.2 + 0.8 * r();
        x += step;
        a = (a + 0.05 * (r() - 0.5)).clamp(-60.0, 20.0);
        let target = [
            (x * 0.01).sin() * 200.0,
            (x * 0.013).cos() * 150.0,
            -50.0 + 10.0 * (x * 0.002).sin(),
            a,
            0.0,
            (x * 0.05) % 360.0,
        ];
        let kind = if k % 5000 == 0 {
            MoveKind::Rapid
        } else {
            MoveKind::Feed {
                nominal_min: step / (1000.0 + 4000.0 * r()),
            }
        };
        moves.push(AxisMove { target, kind });
    }
    let cpu0 = cpu_seconds();
    let t = std::time::Instant::now();
    let e = estimate_axes([0.0; 6], &moves, &machine);
    let secs = t.elapsed().as_secs_f64();
    let cpu = cpu_seconds().zip(cpu0).map(|(b, a)| b - a);
    println!(
        "{n} blocks in {secs:.3} s elapsed{}: estimate {:.1} s, nominal {:.1} s ({:+.1} %)",
        cpu.map_or(String::new(), |c| format!(", {c:.2} s CPU")),
        e.total_s,
        e.nominal_s,
        100.0 * e.overhead()
    );
    let apt = millplan_bench::five_axis_apt(points);
    let parsed = match millplan_nc::parse_program(&apt, millplan_nc::ReadOptions::default()) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("generated program: {e}");
            std::process::exit(1);
        }
    };
    let p = &parsed.program;
    let t = std::time::Instant::now();
    let on_example = estimate_program(p, &machine);
    let secs = t.elapsed().as_secs_f64();
    let on_default = estimate_program(p, &Machine::default());
    let three_axis = Machine {
        kinematics: None,
        axes: Default::default(),
        ..machine.clone()
    };
    let tip_only = estimate_program(p, &{
        let mut m = three_axis;
        m.axes.x = machine.axes.x;
        m.axes.y = machine.axes.y;
        m.axes.z = machine.axes.z;
        m
    });
    println!(
        "five-axis program, {} moves ({secs:.3} s to time): nominal {:.2} min",
        p.move_count(),
        on_example.nominal_s / 60.0
    );
    for (name, e) in [
        ("example machine, A/C through the kinematics", &on_example),
        ("example machine's X Y Z only (tool tip)", &tip_only),
        ("built-in machine (conservative defaults)", &on_default),
    ] {
        println!(
            "  {name:<46} {:>8.2} min ({:+.1} % on nominal; {} of {} feed blocks below their feed)",
            e.total_s / 60.0,
            100.0 * e.overhead(),
            e.accel_limited_blocks + e.velocity_limited_blocks,
            e.per_move_s.len()
        );
    }
}

/// User + system CPU time of this process from /proc/self/stat (Linux; clock
/// ticks of 1/100 s).
fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}
