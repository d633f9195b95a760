//! Process models: what happens between the cutter and the part.
//!
//! - [`cutter`]: cutter shapes by their profile h(r) (flat, ball, bull, cone).
//! - [`contact`]: where a ball touches the part at each tool position (BVH closest
//!   point, normals, feed direction, uncut side and stepover from the path).
//! - [`wd`]: the engagement region of a ball-end mill on a locally planar surface
//!   and its working diameter (spec `working-diameter.md` §1–2), with the
//!   brute-force sampler the tests use as reference.
//! - [`kinematics`]: forward/inverse kinematics of 5-axis machines (spec
//!   `kinematics-access-tools.md` §1).
//! - [`force`]: mechanistic cutting forces, torque, power, tool bending and the
//!   feed iteration (spec `process-models.md` §0–§2).
//! - [`leadtilt`]: the lead/tilt frame, both conversions and the lead/tilt
//!   search (spec `kinematics-access-tools.md` §2, `process-models.md` §2.4).
//! - [`lobes`]: zero-order stability lobes (spec `process-models.md` §3).
//! - [`regression`]: the least-squares surrogate of thesis 2.

pub mod contact;
pub mod cutter;
pub mod force;
pub mod kinematics;
pub mod leadtilt;
pub mod lobes;
pub mod regression;
pub mod wd;
