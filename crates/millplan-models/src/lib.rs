//! Process models: what happens between the cutter and the part.
//!
//! - [`wd`]: the engagement region of a ball-end mill on a locally planar surface
//!   and its working diameter (spec `working-diameter.md` §1–2), with the
//!   brute-force sampler the tests use as reference.

pub mod wd;
