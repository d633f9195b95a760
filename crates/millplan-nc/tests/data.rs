//! Every CAM-written file under `../shared/data/` reads, passes the verifier and
//! holds the record counts of `shared/specs/formats.md` section 1 and each folder's
//! PROVENANCE.md. Skipped cleanly when the folder is absent.

use millplan_nc::apt::{parse_apt, AptStats};
use millplan_nc::detect::detect;
use millplan_nc::stats::summarize;
use millplan_nc::{parse_program, verify::verify, Dialect, LengthUnit, Program, ReadOptions};

mod shared_data;

fn data(rel: &str) -> Option<String> {
    let p = shared_data::file(rel)?;
    let b = std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    Some(String::from_utf8_lossy(&b).into_owned())
}

fn read(rel: &str) -> Option<Program> {
    let src = data(rel)?;
    let parsed =
        parse_program(&src, ReadOptions::default()).unwrap_or_else(|e| panic!("{rel}:{e}"));
    verify(&parsed.program).unwrap_or_else(|v| panic!("{rel}: {v:?}"));
    Some(parsed.program)
}

fn apt_stats(rel: &str) -> Option<AptStats> {
    let src = data(rel)?;
    let (_, stats) = parse_apt(&src, detect(&src), ReadOptions::default())
        .unwrap_or_else(|e| panic!("{rel}:{e}"));
    Some(stats)
}

fn count(p: &Program, k: &str) -> usize {
    p.moves().filter(|m| m.kind.name() == k).count()
}

/// (file, dialect, GOTO records, GOTO with i,j,k where published, CIRCLE records)
/// from formats.md §1 and the PROVENANCE files.
const APT: &[(&str, Dialect, usize, Option<usize>, usize)] = &[
    (
        "nx-clsf-ballend-nurbs/nurbs.clsf",
        Dialect::AptNx,
        78,
        None,
        0,
    ),
    (
        "nx-clsf-5axis-varcontour/ust_a2.cls",
        Dialect::AptNx,
        20057,
        Some(4660),
        0,
    ),
    (
        "nx-clsf-5axis-varcontour/ust_a.cls",
        Dialect::AptNx,
        546,
        Some(120),
        0,
    ),
    (
        "nx-clsf-circle-cutcom/cutcom.clsf",
        Dialect::AptNx,
        566,
        None,
        140,
    ),
    (
        "nx-clsf-circle-cutcom/_3_PAZ_125_N2.cls",
        Dialect::AptNx,
        640,
        None,
        300,
    ),
    (
        "nx-clsf-circle-cutcom/standart_drill.clsf",
        Dialect::AptNx,
        2,
        None,
        0,
    ),
    (
        "swcam-apt-stl-pairs/Interface-glue.apt",
        Dialect::AptSolidworks,
        6311,
        Some(0),
        50,
    ),
    (
        "swcam-apt-stl-pairs/RotateThin.apt",
        Dialect::AptSolidworks,
        338,
        Some(0),
        84,
    ),
    (
        "swcam-apt-stl-pairs/boss.apt",
        Dialect::AptSolidworks,
        9814,
        Some(5751),
        1026,
    ),
    (
        "impeller-5axis-goto-fragments/yelun.txt",
        Dialect::AptIso,
        52,
        Some(52),
        0,
    ),
    (
        "impeller-5axis-goto-fragments/pathdata2.txt",
        Dialect::AptIso,
        395,
        Some(395),
        0,
    ),
    (
        "impeller-5axis-goto-fragments/toolpathdata3.txt",
        Dialect::AptIso,
        76,
        Some(76),
        0,
    ),
];

/// GOTO lines with six or more values, counted straight from the text.
fn goto_with_axis_in_text(src: &str) -> usize {
    src.lines()
        .filter(|l| l.trim_start().starts_with("GOTO") && l.split(',').count() >= 6)
        .count()
}

#[test]
fn apt_files_read_with_the_published_counts() {
    for &(rel, dialect, goto, with_axis, circle) in APT {
        let Some(src) = data(rel) else { continue };
        assert_eq!(detect(&src), dialect, "{rel}: dialect");
        let s = apt_stats(rel).expect("present");
        let with_axis = with_axis.unwrap_or_else(|| goto_with_axis_in_text(&src));
        assert_eq!(
            (s.goto, s.goto_with_axis, s.circle),
            (goto, with_axis, circle),
            "{rel}: GOTO / with axis / CIRCLE"
        );
        let p = read(rel).expect("present");
        // Every GOTO is one move (a CIRCLE and its end GOTO make one arc move);
        // NURBS spans add their sampled points.
        if s.nurbs == 0 {
            assert_eq!(p.move_count(), goto, "{rel}: moves");
            assert_eq!(count(&p, "arc"), circle, "{rel}: arcs");
        } else {
            assert!(p.move_count() > goto, "{rel}: sampled NURBS points");
        }
    }
}

#[test]
fn nurbs_file_has_70_splines_and_stays_in_its_published_box() {
    let Some(s) = apt_stats("nx-clsf-ballend-nurbs/nurbs.clsf") else {
        return;
    };
    assert_eq!(s.nurbs, 70);
    let p = read("nx-clsf-ballend-nurbs/nurbs.clsf").expect("present");
    // PROVENANCE: bounding box of GOTO+CNTRL X -254.99..65.99, Y -30.24..468.38,
    // Z 206.84..273.01; a clamped B-spline lies in the hull of its control points.
    let b = p.bounds();
    assert!(b.min.x >= -255.0 && b.max.x <= 66.0, "{b:?}");
    assert!(b.min.y >= -30.25 && b.max.y <= 468.39, "{b:?}");
    assert!(b.min.z >= 206.84 && b.max.z <= 273.02, "{b:?}");
    let c = p.operations[0]
        .tool
        .as_ref()
        .and_then(|t| t.cutter)
        .expect("TLDATA cutter");
    assert_eq!(
        (c.kind, c.d, c.r),
        (millplan_nc::CutterKind::Ball, 30.0, 15.0)
    );
}

#[test]
fn nx_modal_axis_and_mirrored_msys() {
    let Some(p) = read("nx-clsf-5axis-varcontour/ust_a2.cls") else {
        return;
    };
    let op = &p.operations[0];
    let f = op.frame.expect("MSYS frame");
    assert!((f.rot.z_axis.z + 1.0).abs() < 1e-9, "Z = X × Y = (0,0,-1)");
    // All 20 057 moves carry an axis: 3-value GOTOs inherit the last i,j,k.
    assert!(p
        .operations
        .iter()
        .all(|o| o.moves.iter().all(|m| o.axis(m).is_some())));
    let c = op.tool.as_ref().and_then(|t| t.cutter).expect("cutter");
    assert_eq!(
        (c.kind, c.d, c.r),
        (millplan_nc::CutterKind::Bull, 32.0, 5.0)
    );
    assert_eq!(count(&p, "rapid"), 459);
}

/// A user trial: NX arcs ran the long way round (270° where the part has
/// 90° corners), the cutter looping through the part. An arc must leave
/// its start along the move into it (CAM arcs are tangent to their lead
/// lines); every file with CIRCLE records, by NX (MSYS Z turned over, the
/// axis in the absolute frame) and by SOLIDWORKS.
#[test]
fn circle_records_continue_the_moves_into_them() {
    for rel in [
        "nx-clsf-circle-cutcom/cutcom.clsf",
        "nx-clsf-circle-cutcom/_3_PAZ_125_N2.cls",
        "swcam-apt-stl-pairs/RotateThin.apt",
        "swcam-apt-stl-pairs/Interface-glue.apt",
        "swcam-apt-stl-pairs/boss.apt",
    ] {
        let Some(p) = read(rel) else {
            continue;
        };
        let (mut arcs, mut tangent, mut reversed) = (0, 0, 0);
        for op in &p.operations {
            for (i, m) in op.moves.iter().enumerate() {
                let Some(a) = op.arc(m) else { continue };
                if i < 2 || op.arc(&op.moves[i - 1]).is_some() || op.moves[i - 1].is_rapid() {
                    continue;
                }
                let (s, before) = (op.move_start(i), op.move_start(i - 1));
                let into = s - before;
                if into.length() < 0.01 || (s - a.centre).length() < 1e-6 {
                    continue;
                }
                // Counter-clockwise about the arc's axis.
                let leaves = a.normal.cross(s - a.centre).normalize();
                arcs += 1;
                let cos = into.normalize().dot(leaves);
                tangent += usize::from(cos > 0.98);
                reversed += usize::from(cos < -0.98);
            }
        }
        // Some arcs follow a line at an angle (a lead-in), a few turn back
        // from a retract (short arcs in SOLIDWORKS's boss.apt); read the
        // wrong way round, the tangent ones would all turn back.
        assert!(arcs > 0, "{rel}: no arc after a line");
        assert!(
            tangent * 2 >= arcs && tangent >= 10 * reversed,
            "{rel}: of {arcs} arcs {tangent} continue the line into them, {reversed} turn back"
        );
    }
}

#[test]
fn solidworks_cutters_circles_and_csys() {
    let Some(p) = read("swcam-apt-stl-pairs/Interface-glue.apt") else {
        return;
    };
    let cutters: Vec<_> = p
        .operations
        .iter()
        .filter_map(|o| o.tool.as_ref().and_then(|t| t.cutter))
        .collect();
    // formats.md §2.3: 6.5 drill (α 31°), 14 flat, 14 ball (f = 7).
    assert!(cutters
        .iter()
        .any(|c| c.kind == millplan_nc::CutterKind::Drill
            && (c.alpha.to_degrees() - 31.0).abs() < 1e-9));
    assert!(cutters
        .iter()
        .any(|c| c.kind == millplan_nc::CutterKind::Ball && c.d == 14.0 && c.f == 7.0));
    assert!(cutters
        .iter()
        .any(|c| c.kind == millplan_nc::CutterKind::Flat && c.d == 14.0));
    assert_eq!(p.units.source, LengthUnit::Mm);
    let Some(boss) = read("swcam-apt-stl-pairs/boss.apt") else {
        return;
    };
    // 3+2: CSYS rotates the frame; GOTOs carry the constant axis 1,0,0.
    assert!(boss.operations.iter().any(|o| o.frame.is_some()));
}

#[test]
fn gcode_files_read() {
    // (file, dialect, unit, motion blocks at least)
    let cases: &[(&str, Dialect, LengthUnit, usize)] = &[
        (
            "camotics-ballnose-relief-gcode/bear.nc",
            Dialect::Fanuc,
            LengthUnit::Mm,
            15159,
        ),
        (
            "nx-posted-gcode-samples/roeders_rfm600_finish_profile_mm.ptp",
            Dialect::Fanuc,
            LengthUnit::Mm,
            36746,
        ),
        (
            "nx-posted-gcode-samples/haas_vf2tr_5axis_inch.ptp",
            Dialect::Fanuc,
            LengthUnit::Mm,
            900,
        ),
        (
            "nx-posted-gcode-samples/moriseiki_nmv5000_fanuc_g43-4_mm.ptp",
            Dialect::Fanuc,
            LengthUnit::Mm,
            // Its rotary blocks after a work-offset change are increments from
            // an unknown angle, and its G82 returns to an unknown height: those
            // are kept verbatim, not read as moves.
            490,
        ),
        (
            "nx-posted-gcode-samples/dmu70evo_sinumerik840d_traori_inch.ptp",
            Dialect::Sinumerik,
            LengthUnit::Inch,
            900,
        ),
        (
            "nx-posted-gcode-samples/dmc100_heidenhain_m128_inch.ptp",
            Dialect::Heidenhain,
            LengthUnit::Inch,
            3000,
        ),
        (
            "nx-posted-gcode-samples/bridgeport412_heidenhain_3axis_inch.ptp",
            Dialect::Heidenhain,
            LengthUnit::Inch,
            60,
        ),
        (
            "sinumerik-840d-spinner-u5/Achskreuz.mpf",
            Dialect::Sinumerik,
            LengthUnit::Mm,
            2000,
        ),
        (
            "sinumerik-840d-spinner-u5/Bottle_opener.mpf",
            Dialect::Sinumerik,
            LengthUnit::Mm,
            2000,
        ),
    ];
    for &(rel, dialect, unit, min_moves) in cases {
        let Some(src) = data(rel) else { continue };
        assert_eq!(detect(&src), dialect, "{rel}");
        let p = read(rel).expect("present");
        assert_eq!(p.units.source, unit, "{rel}");
        assert!(
            p.move_count() >= min_moves,
            "{rel}: {} moves",
            p.move_count()
        );
        let s = summarize(&p, 15000.0);
        assert!(s.cutting_mm > 0.0 && s.time_s > 0.0, "{rel}");
    }
    // bear.nc: PROVENANCE counts 15 152 G1 blocks (plus 7 G0).
    if let Some(p) = read("camotics-ballnose-relief-gcode/bear.nc") {
        assert_eq!((count(&p, "linear"), count(&p, "rapid")), (15152, 7));
    }
    // Röders: 36 746 bare G01 blocks.
    if let Some(p) = read("nx-posted-gcode-samples/roeders_rfm600_finish_profile_mm.ptp") {
        assert_eq!(count(&p, "linear"), 36746);
    }
}
