//! Closest-point queries of ball centres along a path: BVH build time and query
//! rate, one thread, with the previous contact as hint (as `millplan speed` does).
//!
//! `cargo run --release -p millplan-bench --example closest_points -- part.stl path.apt [R]`
//!
//! With `ANALYSE=1`, times the contact search alone and the whole analysis
//! (contact, neighbouring passes, working diameter) instead, the fastest of
//! `REPS` runs (default 3).

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
    if std::env::var_os("ANALYSE").is_some() {
        use millplan_models::contact::{analyse, locate, Params, PathPoint, Surface};
        let surface = Surface::new(&mesh);
        // Passes split at links and reversals, as `millplan speed` does.
        let mut pts: Vec<PathPoint> = Vec::new();
        let (mut pass, mut prev) = (0u32, None::<glam::DVec3>);
        for m in parsed
            .program
            .operations
            .iter()
            .flat_map(|o| o.moves.iter())
        {
            if !m.is_cutting() {
                pass += 1;
                continue;
            }
            if let (Some(a), Some(b)) = (prev, pts.last().map(|q| q.cl)) {
                let d = (m.end - b).normalize_or_zero();
                if d.dot(a) < 0.5 {
                    pass += 1;
                }
            }
            if let Some(b) = pts.last().map(|q| q.cl) {
                prev = Some((m.end - b).normalize_or_zero());
            }
            pts.push(PathPoint {
                cl: m.end,
                axis: glam::DVec3::Z,
                pass,
            });
        }
        let p = Params::new(2.0 * r, 0.3);
        // The fastest of REPS runs (3 unless set): the least disturbed by
        // whatever else the machine does.
        let reps: usize = std::env::var("REPS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(3);
        let (mut best_l, mut best_a) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..reps {
            let t = Instant::now();
            let l = locate(&surface, &pts, &p);
            best_l = best_l.min(t.elapsed().as_secs_f64());
            drop(l);
            let t = Instant::now();
            let a = analyse(&surface, &pts, &p);
            best_a = best_a.min(t.elapsed().as_secs_f64());
            drop(a);
        }
        println!(
            "{} points: locate {best_l:.3} s, analyse {best_a:.3} s (fastest of {reps})",
            pts.len()
        );
        return;
    }
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
