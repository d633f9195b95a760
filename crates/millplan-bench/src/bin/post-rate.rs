//! The five-axis post on a large CL file (target: 1,000,000 points with the
//! DP over the path, linearisation and G93 in ≤ 3 s on 2 cores): reads the
//! CL file (default: `five_axis_apt(1_000_000)` generated in memory), posts
//! it for an A/C trunnion in machine coordinates with G93 at 0.01 mm, and
//! prints the time of each phase (read, post, write).
//!
//! Usage: `post-rate [CL-FILE]`.

use millplan_models::kinematics::{KinKind, Kinematics, RotaryAxis};
use millplan_nc::write::{write_program, Target};
use millplan_plan::machine::Machine;
use millplan_plan::post::{post, PostOptions};
use std::time::Instant;

/// CPU seconds (user + system) of this process so far, from
/// `/proc/self/stat` (Linux; 0 elsewhere): on a shared machine the wall time
/// of a phase says little without it.
fn cpu_s() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // The fields after the command name in parentheses.
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<f64> = rest
        .split_whitespace()
        .map(|x| x.parse().unwrap_or(0.0))
        .collect();
    // utime and stime are fields 14 and 15 (11 and 12 after the name), in
    // clock ticks of 1/100 s.
    (f.get(11).copied().unwrap_or(0.0) + f.get(12).copied().unwrap_or(0.0)) / 100.0
}

fn main() {
    let text = match std::env::args().nth(1) {
        Some(path) => match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("error: {path}: {e}");
                std::process::exit(1);
            }
        },
        None => millplan_bench::five_axis_apt(1_000_000),
    };
    let t0 = Instant::now();
    let p = match millplan_nc::parse_program(&text, millplan_nc::ReadOptions::default()) {
        Ok(p) => p.program,
        Err(e) => {
            eprintln!("error: the CL file does not read: {e}");
            std::process::exit(1);
        }
    };
    let read = t0.elapsed().as_secs_f64();
    let mut m = Machine {
        kinematics: Some(Kinematics {
            rot_point: [0.0, 0.0, -100.0],
            first: RotaryAxis {
                min: Some(-120.0),
                max: Some(120.0),
                sign: 1.0,
            },
            ..Kinematics::new(KinKind::TableAc)
        }),
        ..Machine::default()
    };
    m.axes.first.velocity = Some(9000.0);
    m.axes.second.velocity = Some(18000.0);
    let o = PostOptions {
        g93: true,
        tol: 0.01,
        ..PostOptions::default()
    };
    let (t1, c1) = (Instant::now(), cpu_s());
    let posted = match post(&p, &m, &o) {
        Ok(x) => x,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let posting = t1.elapsed().as_secs_f64();
    let posting_cpu = cpu_s() - c1;
    let t2 = Instant::now();
    let bytes = match write_program(&posted.program, m.write_options(Target::Fanuc)) {
        Ok((b, _)) => b.len(),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let writing = t2.elapsed().as_secs_f64();
    let r = &posted.report;
    println!(
        "{} CL points -> {} blocks ({} inserted, {} pole, {} flips, {} slowed), {} bytes of G-code",
        p.move_count(),
        r.blocks,
        r.inserted_points,
        r.pole_blocks,
        r.flips.len(),
        r.slowed_blocks,
        bytes
    );
    println!(
        "read {read:.2} s, post (DP, linearisation, G93, time estimates) {posting:.2} s wall, {posting_cpu:.2} s CPU, write {writing:.2} s; {} threads",
        rayon::current_num_threads()
    );
}
