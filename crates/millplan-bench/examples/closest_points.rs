//! Closest-point queries of ball centres along a path: BVH build time and query
//! rate, one thread, with the previous contact as hint (as `millplan speed` does).
//!
//! `cargo run --release -p millplan-bench --example closest_points -- part.stl path.apt [R]`

use millplan_geom::bvh::Bvh;
use millplan_nc::{parse_program, ReadOptions};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (stl, apt) = (&args[1], &args[2]);
    let r: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(5.0);
    let bytes = std::fs::read(stl).expect("read STL");
    let (mesh, _) = millplan_geom::stl::read_stl(&bytes).expect("STL");
    drop(bytes);
    let src = std::fs::read_to_string(apt).expect("read path");
    let parsed = parse_program(&src, ReadOptions::default()).expect("path");
    let centres: Vec<_> = parsed
        .program
        .operations
        .iter()
        .flat_map(|o| o.moves.iter().filter(|m| m.is_cutting()).map(|m| m.end))
        .map(|p| p + glam::DVec3::Z * r)
        .collect();
    let t = Instant::now();
    let bvh = Bvh::build(&mesh);
    let build = t.elapsed().as_secs_f64();
    for _ in 0..2 {
        let t = Instant::now();
        let mut hint = None;
        let mut sum = 0.0;
        for c in &centres {
            if let Some(h) = bvh.closest_near(&mesh, *c, 3.0 * r + 1.3, hint) {
                hint = Some(h.triangle);
                sum += h.distance;
            }
        }
        let q = t.elapsed().as_secs_f64();
        println!(
            "{} triangles, build {build:.3} s; {} queries {q:.3} s ({:.2} µs each), mean distance {:.6}",
            mesh.len(),
            centres.len(),
            q / centres.len() as f64 * 1e6,
            sum / centres.len() as f64
        );
    }
}
