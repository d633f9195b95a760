//! Writes the Bézier vase test part as binary STL:
//! `cargo run --release -p millplan-bench --example vase_stl -- vase.stl [N]`
//! (N × N triangles pairs per patch, default 16).

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = a.first() else {
        eprintln!("usage: vase_stl OUT.stl [N]");
        std::process::exit(2);
    };
    let n = a.get(1).and_then(|s| s.parse().ok()).unwrap_or(16);
    let mesh = millplan_geom::bezier::tessellate_patches(&millplan_geom::bezier::vase(), n);
    let mut bytes = Vec::new();
    millplan_geom::stl::write_binary_stl(&mesh, "millplan Bezier vase", &mut bytes);
    std::fs::write(path, bytes).unwrap_or_else(|e| panic!("{path}: {e}"));
    println!("{path}: {} triangles", mesh.len());
}
