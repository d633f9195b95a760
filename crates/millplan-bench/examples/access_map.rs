//! Line-of-sight accessibility of a part on a spherical map, timed:
//! `cargo run --release -p millplan-bench --example access_map -- [PART.stl] [latlon|icosphere]`
//! Without a part it uses the demo surface tessellated to about 100,000
//! triangles; the default grid is the 1,280-cell icosphere. With `tool` it also
//! times tool mode (D10 ball, 40 mm reach, D40 × 60 mm holder). For profiling
//! on a smaller case, `ACCESS_STEP` sets the demo surface's tessellation step
//! (default 0.27 mm) and `ACCESS_LEVEL` the icosphere's level (default 3).

use millplan_geom::analytic::{tessellate, DemoSurface};
use millplan_geom::bvh::Bvh;
use millplan_sim::access::{
    accessibility, best_pole, visibility, Icosphere, LatLon, SphereGrid, ToolModel,
};
use std::time::Instant;

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let mesh = match a
        .first()
        .filter(|s| s.ends_with(".stl") || s.ends_with(".STL"))
    {
        Some(path) => {
            let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
            millplan_geom::stl::read_stl(&bytes)
                .unwrap_or_else(|e| panic!("{path}: {e}"))
                .0
        }
        None => tessellate(&DemoSurface::default(), env_or("ACCESS_STEP", 0.27)),
    };
    let grid: Box<dyn SphereGrid> = if a.iter().any(|s| s == "latlon") {
        Box::new(LatLon::PAPER)
    } else {
        Box::new(Icosphere::new(env_or("ACCESS_LEVEL", 3.0) as u32))
    };
    let t = Instant::now();
    let bvh = Bvh::build(&mesh);
    let build = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let vis = visibility(&mesh, &bvh, grid.as_ref(), 0.0);
    let secs = t.elapsed().as_secs_f64();
    let rays = mesh.len() * grid.len();
    let visible: usize = (0..vis.len()).map(|i| vis.count(i)).sum();
    if a.iter().any(|s| s == "tool") {
        let tool = ToolModel {
            radius: 5.0,
            reach: 40.0,
            holder_radius: 20.0,
            holder_length: 60.0,
        };
        let t = Instant::now();
        let acc = accessibility(&mesh, &bvh, grid.as_ref(), 0.0, &tool);
        let secs = t.elapsed().as_secs_f64();
        let free: usize = (0..acc.len()).map(|i| acc.count(i)).sum();
        // FNV-1a over every facet's cells: runs compare bit for bit.
        let hash = (0..acc.len())
            .flat_map(|i| acc.set(i).iter().copied())
            .fold(0xcbf2_9ce4_8422_2325u64, |h, w| {
                (h ^ w).wrapping_mul(0x0100_0000_01b3)
            });
        println!(
            "tool mode: {secs:.2} s ({:.2}M direction tests/s, {:.1} % free, cones {hash:016x})",
            rays as f64 / secs / 1e6,
            100.0 * free as f64 / rays as f64
        );
    }
    let t = Instant::now();
    let pole = best_pole(&vis, grid.as_ref());
    let search = t.elapsed().as_secs_f64();
    println!(
        "{} triangles, {}: BVH {build:.2} s, visibility {secs:.2} s ({:.1}M direction tests/s, {:.1} % visible), best pole {:.2} s: {pole:?}",
        mesh.len(),
        grid.name(),
        rays as f64 / secs / 1e6,
        100.0 * visible as f64 / rays as f64,
        search
    );
}

/// A number from the environment, or `default` when unset.
fn env_or(name: &str, default: f64) -> f64 {
    std::env::var(name).map_or(default, |v| {
        v.parse().unwrap_or_else(|e| panic!("{name}={v}: {e}"))
    })
}
