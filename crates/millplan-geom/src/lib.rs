//! Geometry shared by every millplan crate: f64 vectors and frames, one tolerance
//! policy, bounding boxes, indexed triangle meshes, the STL reader and the
//! resource limits every crate checks.
//!
//! Units inside millplan are millimetres and radians; conversions happen only at
//! front and back ends.

pub mod aabb;
pub mod analytic;
pub mod bezier;
pub mod bvh;
pub mod frame;
pub mod limits;
pub mod mesh;
pub mod optimize;
pub mod stl;
pub mod tol;

pub use aabb::Aabb;
pub use frame::Frame;
pub use glam::{DMat3, DVec2, DVec3};
pub use limits::Limits;
pub use mesh::TriMesh;
