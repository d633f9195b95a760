//! The tool library and thread-mill active control (paper 002; spec
//! `kinematics-access-tools.md` §4).
//!
//! - [`db`]: the library in one SQLite file (WAL, versioned migrations, an
//!   append-only decision log), import/export (CSV, JSON, Heidenhain TOOL.T).
//! - [`control`]: the decisions after a laser measurement (Δset check, wear
//!   compensation, worn → sister tool, broken → lock tool and pallet).
//! - [`thread`]: PZ from ISO 13399 insert data and ISO 965-1 thread checks.
//! - [`iso965`]: the ISO 965-1 tolerance tables (values confirmed by two
//!   public sources each) and limits of size derived from them.
//! - [`cycles`]: the NC fragments that measure a tool (Heidenhain, Fanuc macro).

pub mod control;
pub mod cycles;
pub mod db;
pub mod iso965;
pub mod thread;
