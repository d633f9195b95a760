//! Findings about the inputs that decide whether a result can be trusted: a
//! part mesh with holes or non-manifold edges, tool positions that do not
//! touch the part they are said to cut.

use crate::speed::Summary;
use millplan_geom::TriMesh;
use millplan_nc::diag::{Code, Diagnostic, Severity};

/// Share of cutting points off the part beyond which a result that depends
/// on the contact (working diameter, spindle speed) is not to be trusted.
pub const OFF_SURFACE_LIMIT: f64 = 0.05;

/// The part's open and non-manifold edges, when it has any: near them a
/// drop-cutter or contact query can miss material.
pub fn mesh(mesh: &TriMesh) -> Option<Diagnostic> {
    let e = mesh.edge_report();
    if e.open == 0 && e.non_manifold == 0 {
        return None;
    }
    Some(Diagnostic {
        // An open sheet has a border; edges shared by three or more triangles
        // are always a defect.
        severity: if e.non_manifold > 0 {
            Severity::Warning
        } else {
            Severity::Note
        },
        code: Code::OpenMesh,
        line: 0,
        col: 0,
        message: format!(
            "the part has {} open edges (holes, or the border of an open surface) and {} non-manifold edges of {}: results near them can miss material",
            e.open, e.non_manifold, e.edges
        ),
    })
}

/// Cutting points of a spindle-control run whose tool does not touch the
/// part within tolerance (a different part, a wrong convention or gouges).
pub fn off_surface(s: &Summary) -> Option<Diagnostic> {
    off_surface_points(s.gap_flagged, s.no_contact, s.points)
}

/// [`off_surface`] from the counts: `off` of `points` cutting points off the
/// part, `no_contact` of them without any contact.
pub fn off_surface_points(off: usize, no_contact: usize, points: usize) -> Option<Diagnostic> {
    if off == 0 || points == 0 {
        return None;
    }
    Some(Diagnostic {
        severity: if off as f64 > OFF_SURFACE_LIMIT * points as f64 {
            Severity::Warning
        } else {
            Severity::Note
        },
        code: Code::OffSurface,
        line: 0,
        col: 0,
        message: format!(
            "{off} of {points} cutting points do not touch the part within tolerance ({no_contact} without any contact): the part may not match the program, or the CL points are not tips"
        ),
    })
}

/// Whether so many points are off the part that the result is not to be trusted.
pub fn untrusted(s: &Summary) -> bool {
    s.points > 0 && s.gap_flagged as f64 > OFF_SURFACE_LIMIT * s.points as f64
}
