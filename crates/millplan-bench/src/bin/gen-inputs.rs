//! Writes the benchmark inputs to a folder: `big.apt` (1,000,000 GOTOs),
//! `big.stl` (2,000,000 triangles of the demo surface) and `raster_1m.apt` (a D10
//! ball-end raster of about 1,000,000 points over that surface) and
//! `five_axis_100k.apt` and `five_axis_1m.apt` (the same raster with 100,000
//! and 1,000,000 points and a leaning, rolling tool axis), for whole-command
//! timing and peak memory (`/usr/bin/time -v millplan speed ...`).
//! `gen-inputs --access FILE` writes the 98,568-triangle surface of the
//! tool-mode accessibility benchmark (`millplan setup --tool`) instead.

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let [flag, file] = args.as_slice() {
        if flag == "--access" {
            if let Err(e) = std::fs::write(file, millplan_bench::big_stl(98_568)) {
                eprintln!("error: {file}: {e}");
                std::process::exit(1);
            }
            return;
        }
    }
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "bench-inputs".into());
    let dir = std::path::Path::new(&dir);
    if let Err(e) = std::fs::create_dir_all(dir)
        .and_then(|_| std::fs::write(dir.join("big.apt"), millplan_bench::big_apt(1_000_000)))
        .and_then(|_| std::fs::write(dir.join("big.stl"), millplan_bench::big_stl(2_000_000)))
        .and_then(|_| {
            std::fs::write(
                dir.join("raster_1m.apt"),
                millplan_bench::ball_raster_apt(1_000_000),
            )
        })
        .and_then(|_| {
            std::fs::write(
                dir.join("five_axis_100k.apt"),
                millplan_bench::five_axis_apt(100_000),
            )
        })
        .and_then(|_| {
            std::fs::write(
                dir.join("five_axis_1m.apt"),
                millplan_bench::five_axis_apt(1_000_000),
            )
        })
    {
        eprintln!("error: {}: {e}", dir.display());
        std::process::exit(1);
    }
    println!(
        "wrote {}/big.apt and {}/big.stl",
        dir.display(),
        dir.display()
    );
}
