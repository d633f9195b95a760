//! Tables and reports: the per-point CSV, SVG plots and self-contained HTML pages
//! (no network: everything inline).

pub mod forces;
pub mod html;
pub mod reorder;
pub mod setup;
pub mod sim;
pub mod svg;
pub mod sweep;
pub mod table;
pub mod view3d;
