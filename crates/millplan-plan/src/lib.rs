//! Passes: transformations of the toolpath IR, one file each.
//!
//! | pass | needs | changes |
//! |---|---|---|
//! | [`speed`] | part mesh, ball-end tool, cutting data, machine | *how* (spindle speed and feed per block), never *what* is cut |

pub mod machine;
pub mod speed;
