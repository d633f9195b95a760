//! `--timings`: the phases a command prints add up to its wall time, so no
//! work goes unnamed. Each command runs on a moderately sized input; the
//! phases' sum is compared with the total the command prints and with the
//! wall time of the process as this test sees it, within 5 %. Scheduling on
//! a busy machine can only lengthen the wall time between two phases or
//! around the process, never make a phase go missing, so a run is repeated
//! up to three times before the test fails.

mod common;

use common::{bin, demo_raster};
use std::time::Instant;

/// The phases (the lines that are not indented, before the total) and the
/// total from a `--timings` table.
fn parse(stderr: &str) -> (Vec<(String, f64)>, Option<f64>) {
    let mut phases = Vec::new();
    let mut total = None;
    for line in stderr.lines() {
        // "   0.123 s  name"; parts are indented two more.
        let Some((num, name)) = line.split_once(" s  ") else {
            continue;
        };
        let Ok(s) = num.trim().parse::<f64>() else {
            continue;
        };
        if name.starts_with("total") {
            total = Some(s);
        } else if num.len() <= 8 {
            phases.push((name.to_string(), s));
        }
    }
    (phases, total)
}

/// Runs `args` with `--timings` until the phases add up to the total and the
/// total to the wall time within 5 % (up to three runs); the last run's
/// figures in the failure message.
fn assert_phases_cover(args: &[&str], ok_codes: &[i32]) {
    let mut last = String::new();
    for _ in 0..3 {
        let t = Instant::now();
        let o = bin().args(args).arg("--timings").output().expect("runs");
        let wall = t.elapsed().as_secs_f64();
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(
            o.status.code().is_some_and(|c| ok_codes.contains(&c)),
            "{args:?}: {stderr}"
        );
        let (phases, total) = parse(&stderr);
        let total = total.unwrap_or_else(|| panic!("{args:?}: no total in\n{stderr}"));
        assert!(phases.len() >= 3, "{args:?}: too few phases in\n{stderr}");
        let sum: f64 = phases.iter().map(|p| p.1).sum();
        // The wall time measured here also holds the process's start and
        // exit (loading, the allocator, freeing at exit), outside any clock
        // the program can read: 20 ms of it are allowed beside the 5 %. The
        // figures are printed to the millisecond: on a run of a few ms their
        // rounding (half a millisecond each) is more than 5 %.
        let rounding = 0.0005 * (phases.len() + 1) as f64;
        if (sum - total).abs() <= 0.05 * total + rounding
            && (wall - total).abs() <= 0.05 * wall + 0.02
        {
            return;
        }
        last = format!("phases {sum:.3} s, total {total:.3} s, wall {wall:.3} s\n{stderr}");
    }
    panic!("{args:?}: the phases do not add up to the wall time: {last}");
}

#[test]
fn speed_phases_add_up_to_the_wall_time() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (stl, apt) = demo_raster(dir.path(), &["--stepover", "0.25", "--step", "0.25"]);
    let out = dir.path().join("out.apt");
    let (stl, apt, out) = (
        stl.to_str().expect("utf8"),
        apt.to_str().expect("utf8"),
        out.to_str().expect("utf8"),
    );
    let args = [
        "speed", apt, "--stl", stl, "--vc", "63", "--fz", "0.125", "--ap", "0.3", "-o", out, "-q",
    ];
    assert_phases_cover(&args, &[0, 3]);
}

#[test]
fn simulate_phases_add_up_to_the_wall_time() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (stl, apt) = demo_raster(dir.path(), &["--stepover", "0.25", "--step", "0.25"]);
    let (stl, apt) = (stl.to_str().expect("utf8"), apt.to_str().expect("utf8"));
    let args = [
        "simulate",
        apt,
        "--stock",
        "box:auto",
        "--resolution",
        "0.2",
        "--stl",
        stl,
        "-q",
    ];
    assert_phases_cover(&args, &[0, 3]);
}

/// An APT file of `n` GOTOs on a zig-zag over a wavy surface; with `axes`
/// each with a tool axis leaning up to 15° to the side (five-axis CL).
fn apt(n: usize, axes: bool) -> String {
    use std::fmt::Write;
    let mut s = String::from("PARTNO TIMINGS\nUNITS/MM\nMULTAX/ON\nCUTTER/10,5,0,5,0,0,0\nLOADTL/1\nSPINDL/6000,RPM,CLW\nFEDRAT/1500,MMPM\n");
    for i in 0..n {
        let (row, k) = (i / 500, i % 500);
        let k = if row % 2 == 0 { k } else { 499 - k };
        let (x, y) = (k as f64 * 0.1, row as f64 * 0.1);
        let z = (x * 0.2).sin() + (y * 0.15).cos();
        let roll = 0.26 * (i as f64 * 0.002).sin();
        if axes {
            let _ = writeln!(
                s,
                "GOTO/{x:.4},{y:.4},{z:.4},0,{:.7},{:.7}",
                roll.sin(),
                roll.cos()
            );
        } else {
            let _ = writeln!(s, "GOTO/{x:.4},{y:.4},{z:.4}");
        }
    }
    s.push_str("FINI\n");
    s
}

#[test]
fn inspect_phases_add_up_to_the_wall_time() {
    let dir = tempfile::tempdir().expect("temp dir");
    let f = dir.path().join("big.apt");
    std::fs::write(&f, apt(400_000, false)).expect("write");
    assert_phases_cover(&["inspect", "--json", f.to_str().expect("utf8")], &[0]);
}

#[test]
fn convert_phases_add_up_to_the_wall_time() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (f, out) = (dir.path().join("big.apt"), dir.path().join("big.nc"));
    std::fs::write(&f, apt(200_000, false)).expect("write");
    let (f, out) = (f.to_str().expect("utf8"), out.to_str().expect("utf8"));
    assert_phases_cover(&["convert", f, "--to", "fanuc", "-o", out, "-q"], &[0]);
}

const TRUNNION: &str = "name = \"A/C trunnion\"\n[spindle]\nmin = 500.0\nmax = 18000.0\naccel = 6000.0\n[feed]\nmax = 20000.0\nrapid = 40000.0\n[kinematics]\nkind = \"table-ac\"\nrot_point = [0.0, 0.0, -100.0]\n[kinematics.first]\nmin = -120.0\nmax = 120.0\n[axes.a]\nvelocity = 9000.0\n[axes.c]\nvelocity = 18000.0\n";

#[test]
fn post_phases_add_up_to_the_wall_time() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (cl, m, out) = (
        dir.path().join("five.apt"),
        dir.path().join("m.toml"),
        dir.path().join("out.nc"),
    );
    std::fs::write(&cl, apt(50_000, true)).expect("write");
    std::fs::write(&m, TRUNNION).expect("write");
    let args = [
        "post",
        cl.to_str().expect("utf8"),
        "--machine",
        m.to_str().expect("utf8"),
        "--g93",
        "-o",
        out.to_str().expect("utf8"),
        "-q",
    ];
    assert_phases_cover(&args, &[0]);
}

/// A pass 1 mm deep along a 30 mm line, in and out by rapids.
const PASS: &str = "UNITS/MM\nCUTTER/10,5\nFEDRAT/500\nSPINDL/6000,CLW\nRAPID\nGOTO/0,0,50\nRAPID\nGOTO/0,0,20\nGOTO/0,0,19\nGOTO/30,0,19\nRAPID\nGOTO/30,0,50\nFINI\n";

/// `feed` and `force` (one clock through the driver's reading, stock and
/// force phases and the binary's writing).
#[test]
fn feed_and_force_phases_add_up_to_the_wall_time() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (p, out) = (dir.path().join("pass.apt"), dir.path().join("out.apt"));
    std::fs::write(&p, PASS).expect("write");
    let p = p.to_str().expect("utf8");
    let model = [
        "--stock",
        "box:auto",
        "--material",
        "al7075",
        "--resolution",
        "0.5",
        "-q",
    ];
    let feed = [&["feed", p, "-o", out.to_str().expect("utf8")][..], &model].concat();
    assert_phases_cover(&feed, &[0, 3]);
    let force = [&["force", p][..], &model].concat();
    assert_phases_cover(&force, &[0, 3]);
}

/// The commands over a part: `raster` writes a coarse finishing pass on
/// the demo part, then `gouge`, `reorder`, `orient` and `setup` run on it.
#[test]
fn part_commands_phases_add_up_to_the_wall_time() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (stl, apt) = demo_raster(dir.path(), &["--stepover", "2", "--step", "1"]);
    let f = |p: &std::path::Path| p.to_str().expect("utf8").to_string();
    let (stl, apt) = (f(&stl), f(&apt));
    let out = |n: &str| f(&dir.path().join(n));
    let (r, o, ra) = (out("r.apt"), out("o.apt"), out("ra.apt"));
    let raster = [
        "raster",
        "--stl",
        &stl,
        "--tool",
        "ball:10",
        "--stepover",
        "2",
        "--step",
        "1",
        "-o",
        &ra,
    ];
    assert_phases_cover(&raster, &[0]);
    assert_phases_cover(&["gouge", &apt, "--stl", &stl, "-q"], &[0, 3]);
    let reorder = ["reorder", &apt, "--stl", &stl, "-o", &r, "-q"];
    assert_phases_cover(&reorder, &[0, 3]);
    let orient = [
        "orient",
        &apt,
        "--stl",
        &stl,
        "--material",
        "al7075",
        "--samples",
        "4",
        "-o",
        &o,
        "-q",
    ];
    assert_phases_cover(&orient, &[0, 3]);
    let setup = [
        "setup", "--type", "ca", "--stl", &stl, "--cells", "200", "-q",
    ];
    assert_phases_cover(&setup, &[0, 3]);
    let opt = out("opt.apt");
    let mut optimise = vec!["optimise", &apt, "--stl", &stl, "-o", &opt, "-q"];
    optimise.extend("--stock offset:0.3 --resolution 1 --material al7075".split(' '));
    assert_phases_cover(&optimise, &[0, 3]);
}

/// The model commands without a program of their own to write: `lobes`,
/// `wd-sweep`, `directions` (rasters made on the demo part) and `robot
/// place` and `robot compensate` under a fixed load.
#[test]
fn model_commands_phases_add_up_to_the_wall_time() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (stl, _) = demo_raster(dir.path(), &["--stepover", "2", "--step", "1"]);
    let f = |p: &std::path::Path| p.to_str().expect("utf8").to_string();
    let stl = f(&stl);
    let out = |n: &str| f(&dir.path().join(n));
    let mut lobes = vec!["lobes", "--slot", "-o"];
    let svg = out("l.svg");
    lobes.push(&svg);
    lobes.extend("--fn 800 --k 2e7 --zeta 0.03 --flutes 2 --kt 700 --kr 0.3".split(' '));
    assert_phases_cover(&lobes, &[0]);
    let sweep = out("sweep");
    let mut wd = vec!["wd-sweep", "-o", &sweep, "--fit"];
    wd.extend("--d 6,10 --ap 0.1,0.5 --alpha 0,30 --af-step 30".split(' '));
    assert_phases_cover(&wd, &[0]);
    let directions = ["directions", "--angles", "0,90", "--stl", &stl];
    assert_phases_cover(&directions, &[0]);
    let path = dir.path().join("robot.apt");
    std::fs::write(&path, apt(400, false)).expect("write");
    let (path, src) = (f(&path), out("r.src"));
    let load = ["--load", "100,50,-20"];
    let place = [&["robot", "place", &path, "--restarts", "1"][..], &load].concat();
    assert_phases_cover(&place, &[0, 3]);
    let pose = ["--pose", "1500,0,500,0", "-o", &src];
    let compensate = [&["robot", "compensate", &path][..], &load, &pose].concat();
    assert_phases_cover(&compensate, &[0]);
}

#[test]
fn the_table_parses_phases_parts_and_total() {
    let (phases, total) = parse(
        "   0.500 s  read\n   0.250 s  speed\n     0.100 s  contact\n   0.800 s  total (wall time of the run)\n",
    );
    assert_eq!(
        phases,
        [("read".to_string(), 0.5), ("speed".to_string(), 0.25)]
    );
    assert_eq!(total, Some(0.8));
}
