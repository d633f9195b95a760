//! Drop-cutter heights for a list of points, for side-by-side runs with other
//! drop-cutter implementations:
//! `cargo run --release -p millplan-bench --example drop_points -- part.stl D points.csv out.csv`
//! (points.csv: `x,y` per line; out.csv: `x,y,z`; D: ball diameter). Prints the
//! throughput of the drop itself.

use millplan_geom::DVec2;
use millplan_models::cutter::Shape;
use millplan_sim::dropcutter::DropMesh;
use std::fmt::Write;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() != 5 {
        eprintln!("usage: drop_points PART.stl BALL_DIAMETER POINTS.csv OUT.csv");
        std::process::exit(2);
    }
    let bytes = std::fs::read(&a[1]).unwrap_or_else(|e| panic!("{}: {e}", a[1]));
    let (mesh, _) =
        millplan_geom::stl::read_stl(&bytes).unwrap_or_else(|e| panic!("{}: {e}", a[1]));
    let d: f64 = a[2]
        .parse()
        .unwrap_or_else(|_| panic!("diameter `{}`", a[2]));
    let pts: Vec<DVec2> = std::fs::read_to_string(&a[3])
        .unwrap_or_else(|e| panic!("{}: {e}", a[3]))
        .lines()
        .filter_map(|l| {
            let mut it = l.split(',').map(|v| v.trim().parse::<f64>());
            Some(DVec2::new(it.next()?.ok()?, it.next()?.ok()?))
        })
        .collect();
    let dm = DropMesh::new(&mesh);
    let t = std::time::Instant::now();
    let z = dm.drop_many(&Shape::Ball { radius: d / 2.0 }, &pts);
    let secs = t.elapsed().as_secs_f64();
    let mut out = String::new();
    for (p, z) in pts.iter().zip(&z) {
        let _ = writeln!(
            out,
            "{},{},{}",
            p.x,
            p.y,
            z.map(|d| d.z).unwrap_or(f64::NAN)
        );
    }
    std::fs::write(&a[4], out).unwrap_or_else(|e| panic!("{}: {e}", a[4]));
    println!(
        "{} points in {:.3} s: {:.0} points/s",
        pts.len(),
        secs,
        pts.len() as f64 / secs
    );
}
