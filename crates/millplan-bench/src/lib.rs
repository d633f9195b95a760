//! Realistic large inputs for benchmarks: a finishing-path APT file of n GOTOs
//! over the demo surface, a binary STL of a finely tessellated surface, and the
//! same path as an in-memory program.

pub mod gate;

use millplan_geom::analytic::{tessellate, DemoSurface, HeightField};
use millplan_geom::stl::write_binary_stl;
use millplan_nc::{Cutter, Dialect, Move, Operation, Program, Tool};
use std::fmt::Write;

/// Tool-tip points of a zig-zag raster with `n` points over the 60 mm demo surface.
fn raster_points(n: usize) -> impl Iterator<Item = (f64, f64, f64)> {
    let s = DemoSurface::default();
    let per_row = 2000usize;
    (0..n).map(move |i| {
        let row = i / per_row;
        let k = i % per_row;
        let k = if row.is_multiple_of(2) {
            k
        } else {
            per_row - 1 - k
        };
        let x = 60.0 * k as f64 / per_row as f64;
        let y = (row as f64 * 0.03) % 60.0;
        (x, y, s.z(x, y))
    })
}

/// An ISO APT file with `n` GOTO records (about 28 bytes each).
pub fn big_apt(n: usize) -> String {
    let mut s = String::with_capacity(n * 30 + 256);
    s.push_str("PARTNO BENCH\nUNITS/MM\nCUTTER/10,5,0,5,0,0,50\nLOADTL/1\nSPINDL/8000,RPM,CLW\nFEDRAT/2000,MMPM\n");
    for (x, y, z) in raster_points(n) {
        let _ = writeln!(s, "GOTO/{x:.4},{y:.4},{z:.4}");
    }
    s.push_str("FINI\n");
    s
}

/// A binary STL of the demo surface with about `triangles` facets.
pub fn big_stl(triangles: usize) -> Vec<u8> {
    let cells = ((triangles / 2) as f64).sqrt().round().max(1.0);
    let mesh = tessellate(&DemoSurface::default(), 60.0 / cells);
    let mut out = Vec::new();
    write_binary_stl(&mesh, "solid millplan bench", &mut out);
    out
}

/// The raster as a program with `n` linear moves, for writer benchmarks.
pub fn big_program(n: usize) -> Program {
    let mut op = Operation {
        tool: Some(Tool {
            number: Some(1),
            name: None,
            cutter: Some(Cutter::ball(10.0)),
            line: 0,
        }),
        ..Operation::default()
    };
    op.moves.reserve(n);
    for (i, (x, y, z)) in raster_points(n).enumerate() {
        // Spindle varies per point, as after constant-cutting-speed control.
        let mut m = Move::linear(millplan_geom::DVec3::new(x, y, z), 2000.0);
        m.spindle = 6000.0 + (i % 97) as f64 * 10.0;
        op.moves.push(m);
    }
    let mut p = Program::new(Dialect::AptIso);
    p.operations.push(op);
    p
}

/// A ball-end (D10) raster over the demo surface with about `n` points, as APT.
pub fn ball_raster_apt(n: usize) -> String {
    use millplan_nc::generate::{raster, Raster};
    // rows × points per row ≈ n on the 56 mm square inside the margin.
    let spacing = 56.0 / (n as f64).sqrt();
    let (p, _) = raster(
        &DemoSurface::default(),
        &Raster {
            step: spacing,
            stepover: spacing,
            ..Raster::default()
        },
    );
    let mut out = Vec::new();
    // Writing to memory cannot fail.
    let _ = millplan_nc::write::apt::write_apt(
        &p,
        millplan_nc::write::WriteOptions::new(millplan_nc::write::Target::Apt),
        &mut out,
    );
    String::from_utf8(out).unwrap_or_default()
}

/// A five-axis ball-end (D10) finishing path of about `n` points over the demo
/// surface, as APT: the raster of [`ball_raster_apt`] with the tool leaning
/// back 10° from the feed and rolling ±15° to the side along each pass,
/// each point moved so that the ball centre (and so the contact) stays where
/// the vertical raster had it.
pub fn five_axis_apt(n: usize) -> String {
    use millplan_geom::DVec3;
    use millplan_nc::generate::{raster, Raster};
    use std::fmt::Write;
    let spacing = 56.0 / (n as f64).sqrt();
    let (p, _) = raster(
        &DemoSurface::default(),
        &Raster {
            step: spacing,
            stepover: spacing,
            ..Raster::default()
        },
    );
    let r = 5.0;
    let mut s = String::from(
        "PARTNO DEMO_FIVE_AXIS\nUNITS/MM\nMULTAX/ON\nCUTTER/10,5,0,5,0,0,0\nLOADTL/1\nSPINDL/6000,RPM,CLW\n",
    );
    let mut prev: Option<DVec3> = None;
    let mut k = 0usize;
    for op in &p.operations {
        for m in &op.moves {
            let Some(tip) = millplan_nc::known(m.end) else {
                continue;
            };
            let feed = prev.map_or(DVec3::X, |q| (tip - q).with_z(0.0).normalize_or(DVec3::X));
            prev = Some(tip);
            let side = DVec3::Z.cross(feed);
            let roll = (15f64.to_radians()) * (k as f64 * 0.002).sin();
            let lead = 10f64.to_radians();
            let axis = (DVec3::Z * lead.cos() * roll.cos() - feed * lead.sin() + side * roll.sin())
                .normalize();
            k += 1;
            let centre = tip + DVec3::Z * r;
            let q = centre - axis * r;
            if m.is_rapid() {
                let _ = writeln!(s, "RAPID");
            } else if k == 1 || (m.feed > 0.0 && k % 100_000 == 1) {
                let _ = writeln!(s, "FEDRAT/1500,MMPM");
            }
            let _ = writeln!(
                s,
                "GOTO/{:.6},{:.6},{:.6},{:.7},{:.7},{:.7}",
                q.x, q.y, q.z, axis.x, axis.y, axis.z
            );
        }
    }
    s.push_str("END\nFINI\n");
    s
}
