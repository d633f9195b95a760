//! Serial robots for machining (process-models §4, Schnoes & Zaeh 2019).
//!
//! - [`pose`]: rigid transforms and KUKA's A, B, C angles (R = Rz(A)·Ry(B)·Rx(C)).
//! - [`robot`]: a robot file (TOML): the chain of frames as the paper
//!   tabulates it, virtual joints included, each frame a bushing with three
//!   torsional stiffnesses; the tool; the joint limits. `kr240` is bundled.
//! - [`kin`]: forward kinematics, analytic inverse kinematics for a spherical
//!   wrist with KUKA's Status and Turn, the feasibility of a configuration.
//! - [`stiffness`]: the compliance Jacobian (one axis per joint, 6×8, or three
//!   torsional axes per joint, 6×24), C = J K⁻¹ Jᵀ and the deflection C·w.
//! - [`machining`]: a toolpath on the robot: the load along it, the
//!   deflection at each point, offline compensation, KRL of the compensated
//!   path, the workpiece placement search ([`anneal`]).

pub mod anneal;
pub mod kin;
pub mod machining;
pub mod pose;
pub mod robot;
pub mod stiffness;

pub use kin::{Config, IkError, Joints};
pub use pose::Pose;
pub use robot::{Robot, RobotError};
pub use stiffness::{Compliance, Deflection, Spring, Torsional, Variant};

/// A `$VEL.CP` in m/s to the 6 decimals it is written with.
pub fn round_vel(v: f64) -> f64 {
    (v * 1e6).round() / 1e6
}
