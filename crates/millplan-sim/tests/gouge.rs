//! Gouge check against a box: a tool beside a vertical wall gouges by how far
//! it stands inside the wall, and standing exactly at it (or within the
//! tolerance) is not a gouge, whatever the tool's shape.

use millplan_geom::{DVec3, TriMesh};
use millplan_models::cutter::Shape;
use millplan_nc::{parse_program, Program, ReadOptions};
use millplan_sim::dropcutter::DropMesh;
use millplan_sim::gouge::{check, GougeParams};
use millplan_sim::stock::tool::ToolBody;

/// The box [10,110] × [10,110] × [-30,-1], closed.
fn box_mesh() -> DropMesh {
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let (x0, x1, y0, y1, z0, z1) = (10.0, 110.0, 10.0, 110.0, -30.0, -1.0);
    let c = [
        v(x0, y0, z0),
        v(x1, y0, z0),
        v(x1, y1, z0),
        v(x0, y1, z0),
        v(x0, y0, z1),
        v(x1, y0, z1),
        v(x1, y1, z1),
        v(x0, y1, z1),
    ];
    let quads = [
        [0, 3, 2, 1],
        [4, 5, 6, 7],
        [0, 1, 5, 4],
        [1, 2, 6, 5],
        [2, 3, 7, 6],
        [3, 0, 4, 7],
    ];
    let mut soup = Vec::new();
    for q in quads {
        soup.push([c[q[0]], c[q[1]], c[q[2]]]);
        soup.push([c[q[0]], c[q[2]], c[q[3]]]);
    }
    let (mesh, _) = TriMesh::from_soup(&soup);
    DropMesh::new(&mesh)
}

/// A flat end, a ball and a bull-nose cutter of one radius.
fn shapes(radius: f64, corner: f64) -> [Shape; 3] {
    [
        Shape::Flat { radius },
        Shape::Ball { radius },
        Shape::Bull { radius, corner },
    ]
}

/// A pass along the wall y = 10 at depth -20 with the tool axis at `y`.
fn pass(y: f64) -> Program {
    let src = format!(
        "PARTNO WALL\nUNITS/MM\nLOADTL/1\nFEDRAT/500,MMPM\nRAPID\nGOTO/0,{y},20\nGOTO/0,{y},-20\nGOTO/120,{y},-20\nFINI\n"
    );
    parse_program(&src, ReadOptions::default())
        .expect("reads")
        .program
}

#[test]
fn a_tool_at_a_wall_gouges_only_when_inside_it() {
    let part = box_mesh();
    let g = GougeParams::default();
    for sh in shapes(7.0, 2.0) {
        for (inside, gouges) in [
            (-0.01, false),
            (0.0, false),
            (g.tol * 0.5, false),
            (0.05, true),
            (0.5, true),
        ] {
            let p = pass(10.0 - 7.0 + inside);
            let rep = check(&p, &part, |_| Some(ToolBody::new(sh)), &g);
            assert!(rep.points_checked > 0);
            assert_eq!(
                !rep.gouges.is_empty(),
                gouges,
                "{sh:?} {inside} mm inside the wall: {:?}",
                rep.gouges
            );
        }
    }
}

#[test]
fn a_tool_below_the_top_gouges_by_its_depth() {
    // Straight down onto the top face at z = -1: 0.5 mm below it.
    let part = box_mesh();
    let src = "PARTNO TOP\nUNITS/MM\nLOADTL/1\nFEDRAT/500,MMPM\nRAPID\nGOTO/50,50,20\nGOTO/50,50,-1.5\nGOTO/60,50,-1.5\nFINI\n";
    let p = parse_program(src, ReadOptions::default())
        .expect("reads")
        .program;
    let rep = check(
        &p,
        &part,
        |_| Some(ToolBody::new(Shape::Ball { radius: 3.0 })),
        &GougeParams::default(),
    );
    let deepest = rep.gouges.iter().map(|g| g.depth).fold(0.0, f64::max);
    assert!((deepest - 0.5).abs() < 1e-9, "{deepest}");
}

/// The progress of a check counts its sample points up to the total, which
/// is what the report says it checked, and the report is the one `check` gives.
#[test]
fn progress_counts_every_sample_point() {
    let part = box_mesh();
    let g = GougeParams {
        step: 0.001,
        ..GougeParams::default()
    };
    let p = pass(0.0);
    let sh = Shape::Ball { radius: 3.0 };
    let seen = std::sync::Mutex::new(Vec::new());
    let rep = millplan_sim::gouge::check_with_progress(
        &p,
        &part,
        |_| Some(ToolBody::new(sh)),
        &g,
        &|d, t| {
            seen.lock().expect("lock").push((d, t));
        },
    );
    let mut seen = seen.into_inner().expect("lock");
    seen.sort();
    let total = rep.points_checked;
    assert!(total > 2 * millplan_sim::gouge::PROGRESS_EVERY, "{total}");
    assert!(seen.iter().all(|&(d, t)| t == total && d <= total));
    assert_eq!(seen.last(), Some(&(total, total)));
    assert_eq!(seen.len(), total / millplan_sim::gouge::PROGRESS_EVERY + 1);
    let plain = check(&p, &part, |_| Some(ToolBody::new(sh)), &g);
    assert_eq!(plain.points_checked, total);
    assert_eq!(plain.gouges.len(), rep.gouges.len());
}

/// A raster over the Bézier vase, whose rim has a vertical inner wall: the
/// drop surface steps there (the cutter drops off the rim into the vase),
/// and a chord across the step from the floor up to the rim cuts through
/// the rim's corner. Rasters at several angles, with every cutter shape,
/// are clean by the gouge check, and they do cross the wall: some moves
/// rise steeply at its foot.
#[test]
fn rasters_over_a_vertical_wall_climb_it_without_cutting_the_corner() {
    use millplan_sim::raster::{raster, RasterParams};
    let mesh = millplan_geom::bezier::tessellate_patches(&millplan_geom::bezier::vase(), 8);
    let part = DropMesh::new(&mesh);
    for sh in shapes(5.0, 1.0) {
        for angle in [0.0, 30.0, 90.0] {
            let p = RasterParams {
                angle_deg: angle,
                stepover: 4.0,
                step: 0.5,
                ..RasterParams::new(sh)
            };
            let prog = raster(&part, &mesh.bounds(), &p);
            let moves = &prog.operations[0].moves;
            // Cutting moves rising more than 5 mm over less than 0.1 mm.
            let climbs = moves
                .windows(2)
                .filter(|w| {
                    let d = w[1].end - w[0].end;
                    w[1].is_cutting() && d.z > 5.0 && d.truncate().length() < 0.1
                })
                .count();
            assert!(
                climbs > 0,
                "{sh:?} at {angle}°: the raster never meets the wall"
            );
            let rep = check(
                &prog,
                &part,
                |_| Some(ToolBody::new(sh)),
                &GougeParams::default(),
            );
            assert!(rep.points_checked > 10_000, "{}", rep.points_checked);
            assert!(
                rep.gouges.is_empty(),
                "{sh:?} at {angle}°: {} gouges, first {:?}",
                rep.gouges.len(),
                rep.gouges.first()
            );
        }
    }
}

/// A plateau (z 0, x up to 0) whose wall drops 5 mm and runs on as a 100:1
/// slope down to a floor 25 mm below: for a flat cutter of radius 2 the drop
/// surface steps at x = 2 and then falls steeply. The raster's points lie
/// at x = 1.97 + 0.25 k, so the step sits in the first quarter of a chord
/// whose quarter points all lie on the slope, below the chord, and whose
/// rise is spread over both halves (Interface-glue.STL and mount_rush.STL
/// showed it). Refined, the chord is halved until the path climbs at the
/// step; unrefined it cut 2.5 mm into the plateau's edge.
#[test]
fn a_step_hidden_in_a_chords_first_quarter_above_a_steep_slope_is_refined() {
    // The profile in x, z (plateau, wall, slope, floor).
    let (x0, x1) = (-10.03, 9.97);
    let profile = [
        (x0, 0.0),
        (0.0, 0.0),
        (0.0, -5.0),
        (0.2, -25.0),
        (x1, -25.0),
    ];
    let rep = flat_raster_over_profile(&profile, 0.25, &GougeParams::default());
    assert!(rep.moves_checked > 100, "{}", rep.moves_checked);
    assert_clean(&rep);
}

/// A gentle 1:10 slope with a thin fin on it (0.02 mm wide, its top 0.55
/// mm up): for a flat cutter of radius 2 the drop surface is a plateau at
/// the fin's top out to x = 2.02, then falls 0.15 mm back onto the slope.
/// The raster's points lie at x = 1.98 + 0.2 k, so a chord from the
/// plateau's last 0.04 mm down to the slope is neither steep nor has a
/// quarter point above it (all three lie on the slope, 0.04-0.11 mm below
/// it), while the plateau stands 0.03 mm above it over its first fifth
/// (mount_rush.stl showed it). A chord whose samples lie off it, either
/// way, is halved: the path keeps within --tol of the drop surface and
/// does not cut the plateau's edge (found by sampling every 2 µm).
#[test]
fn a_chord_whose_samples_all_lie_below_it_is_refined() {
    let (x0, x1) = (-10.02, 9.98);
    let profile = [
        (x0, 0.1 * x0),
        (0.0, 0.0),
        (0.0, 0.55),
        (0.02, 0.55),
        (0.02, 0.002),
        (x1, 0.1 * x1),
    ];
    let fine = GougeParams {
        step: 0.002,
        ..GougeParams::default()
    };
    let rep = flat_raster_over_profile(&profile, 0.2, &fine);
    assert_clean(&rep);
}

fn assert_clean(rep: &millplan_sim::gouge::GougeReport) {
    assert!(
        rep.gouges.is_empty(),
        "{} gouges, deepest {:.3} mm, first {:?}",
        rep.gouges.len(),
        rep.max_depth,
        rep.gouges.first()
    );
}

/// The profile (x, z) run out along y from -5 to 5, rastered along x with
/// a flat cutter of radius 2 at `step` (2 mm stepover), then gouge-checked.
fn flat_raster_over_profile(
    profile: &[(f64, f64)],
    step: f64,
    g: &GougeParams,
) -> millplan_sim::gouge::GougeReport {
    use millplan_sim::raster::{raster, RasterParams};
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let (y0, y1) = (-5.0, 5.0);
    let mut soup = Vec::new();
    for w in profile.windows(2) {
        let ((xa, za), (xb, zb)) = (w[0], w[1]);
        let (a, b) = (v(xa, y0, za), v(xb, y0, zb));
        let (c, d) = (v(xb, y1, zb), v(xa, y1, za));
        soup.push([a, b, c]);
        soup.push([a, c, d]);
    }
    let (mesh, _) = TriMesh::from_soup(&soup);
    let part = DropMesh::new(&mesh);
    let sh = Shape::Flat { radius: 2.0 };
    let p = RasterParams {
        stepover: 2.0,
        step,
        ..RasterParams::new(sh)
    };
    let prog = raster(&part, &mesh.bounds(), &p);
    check(&prog, &part, |_| Some(ToolBody::new(sh)), g)
}

/// A program of one feed move from `a` to `b` with the tool axis `k`.
fn tilted(a: [f64; 3], b: [f64; 3], k: [f64; 3]) -> Program {
    let g = |p: [f64; 3]| {
        format!(
            "GOTO/{},{},{},{},{},{}\n",
            p[0], p[1], p[2], k[0], k[1], k[2]
        )
    };
    let src = format!(
        "PARTNO TILT\nUNITS/MM\nLOADTL/1\nFEDRAT/500,MMPM\n{}{}FINI\n",
        g(a),
        g(b)
    );
    parse_program(&src, ReadOptions::default())
        .expect("reads")
        .program
}

/// A ball end leaned 30° riding the box's top (z = −1) is checked by its
/// distance to the part, not skipped: resting on the face it does not
/// gouge, 0.2 mm lower it gouges 0.2 mm (the face's normal distance), and
/// a tool whose ball is clear of the outside wall but whose flutes lean
/// into it gouges, which the drop-cutter of a vertical tool at its tip
/// would not see. A leaned flat end is still skipped, and counted.
#[test]
fn a_tilted_ball_end_is_checked_by_its_distance_to_the_part() {
    let part = box_mesh();
    let g = GougeParams::default();
    let r = 3.0;
    let ball = ToolBody::new(Shape::Ball { radius: r });
    let (s, c) = (30f64.to_radians().sin(), 30f64.to_radians().cos());
    let k = [s, 0.0, c];
    // The ball's centre r above the face: the tip r below it along the axis.
    let tip_z = |drop: f64| -1.0 + r - r * c - drop;
    for (drop, gouges) in [(0.0, false), (0.2, true)] {
        let z = tip_z(drop);
        let p = tilted([40.0, 50.0, z], [80.0, 50.0, z], k);
        let rep = check(&p, &part, |_| Some(ball), &g);
        // The first move comes from an unknown place.
        assert_eq!(rep.skipped.tilted, 0);
        assert_eq!(rep.moves_checked, 1);
        assert_eq!(!rep.gouges.is_empty(), gouges, "{drop}: {rep:?}");
        if gouges {
            assert!((rep.max_depth - drop).abs() < 1e-3, "{}", rep.max_depth);
        }
    }
    // Beside the outside wall x = 10, below the top, leaning toward it by
    // 45°: the ball's centre is 4.9 mm from the wall, its flutes reach it.
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let p = tilted([3.0, 40.0, -12.0], [3.0, 60.0, -12.0], [h, 0.0, h]);
    let rep = check(&p, &part, |_| Some(ball), &g);
    assert!(!rep.gouges.is_empty(), "{rep:?}");
    let vertical = tilted([3.0, 40.0, -12.0], [3.0, 60.0, -12.0], [0.0, 0.0, 1.0]);
    assert!(check(&vertical, &part, |_| Some(ball), &g)
        .gouges
        .is_empty());
    // A ball without flutes above it clears the wall.
    let short = ToolBody { flute: r, ..ball };
    assert!(check(&p, &part, |_| Some(short), &g).gouges.is_empty());
    let flat = ToolBody::new(Shape::Flat { radius: r });
    let rep = check(&p, &part, |_| Some(flat), &g);
    assert_eq!((rep.skipped.tilted, rep.moves_checked), (1, 0));
}

/// The moves a check or a simulation leaves out are counted with the source
/// line of the first, so a warning can say where to look: here the first
/// move (line 5), a feed move from wherever the machine stood.
#[test]
fn moves_left_out_name_the_line_of_the_first() {
    use millplan_sim::stock::path::{strokes, PathOptions};
    let src = "PARTNO WALL\nUNITS/MM\nLOADTL/1\nFEDRAT/500,MMPM\nGOTO/0,50,20\nGOTO/0,50,-20\nGOTO/120,50,-20\nFINI\n";
    let p = parse_program(src, ReadOptions::default())
        .expect("reads")
        .program;
    let ball = |_: &millplan_nc::Operation| Some(ToolBody::new(Shape::Ball { radius: 5.0 }));
    let rep = check(&p, &box_mesh(), ball, &GougeParams::default());
    assert_eq!(rep.skipped.unknown_position, 1);
    assert_eq!(rep.skipped.first_line, Some(5));
    assert_eq!(rep.skipped.first(), "; the first at line 5");
    let o = PathOptions {
        chord: 0.01,
        rapid_rate: 10_000.0,
    };
    let s = strokes(&p, ball, &o);
    assert_eq!(
        (s.skipped.unknown_position, s.skipped.first_line),
        (1, Some(5))
    );
    // Without a tool every move is left out, from the operation's first.
    let none = strokes(&p, |_| None, &o);
    assert_eq!(
        (none.skipped.no_tool, none.skipped.first_line),
        (3, Some(5))
    );
    // Nothing left out: no line, no words.
    assert_eq!(
        millplan_sim::stock::path::Unsimulated::default().first(),
        ""
    );
}

/// A user trial: a part read in the wrong unit lay under a corner of the
/// path, and `gouge` called the program clean. The check counts the cutting
/// moves whose tool stands away from the part's footprint (its xy box grown
/// by the radius and `NEAR_PART`) at every sample, and says when that is
/// most of them. A profile beside the part, leaving stock, a plunge through
/// a hole, and a pass that runs off the part stand by it (a review:
/// counting points with material under the tool refused exact contours and
/// drilling; a trial: counting points let one long link to a park position
/// outweigh a whole profile).
#[test]
fn the_moves_away_from_the_part_are_counted() {
    use millplan_sim::gouge::NEAR_PART;
    let part = box_mesh();
    let g = GougeParams::default();
    let ball = |_: &millplan_nc::Operation| Some(ToolBody::new(Shape::Ball { radius: 3.0 }));
    let read = |src: &str| {
        parse_program(src, ReadOptions::default())
            .expect("reads")
            .program
    };
    let apt = |moves: &str| {
        read(&format!(
            "PARTNO T\nUNITS/MM\nLOADTL/1\nFEDRAT/500,MMPM\nRAPID\nGOTO/60,60,20\n{moves}FINI\n"
        ))
    };
    // Cutting moves whose tip passes within 3 + NEAR_PART of the box
    // [10, 110]² at some sample: the plunge, a pass leaving the box, a
    // profile 0.5 mm outside the wall x = 110; the link out to x = 200
    // starts by the part. One move far off: the pass at y = 130.
    let reach = 3.0 + NEAR_PART;
    let p = apt(&format!(
        "GOTO/60,60,-10\nGOTO/150,60,-10\nGOTO/113.5,10,-10\nGOTO/113.5,110,-10\nGOTO/200,200,-10\nGOTO/0,{},-10\n",
        110.0 + reach + 1.0
    ));
    let rep = check(&p, &part, ball, &g);
    assert_eq!((rep.cutting_moves, rep.off_part_moves), (6, 1), "{rep:?}");
    assert!(!rep.mostly_off_part(), "{rep:?}");
    // The part read in inches as mm the other way round: a raster 25.4
    // times as large, most of its moves away from the box.
    let mut raster = String::new();
    for k in 0..20 {
        let y = -500.0 + 150.0 * k as f64;
        raster.push_str(&format!("GOTO/-500,{y},5\nGOTO/2500,{y},5\n"));
    }
    let rep = check(&apt(&raster), &part, ball, &g);
    assert!(rep.gouges.is_empty() && rep.mostly_off_part(), "{rep:?}");
    assert!(rep.off_part_words().contains("does not match the program"));
}
