//! Passes: transformations of the toolpath IR, one file each.
//!
//! | pass | needs | changes |
//! |---|---|---|
//! | [`speed`] | part mesh, ball-end tool, cutting data, machine | *how* (spindle speed and feed per block), never *what* is cut |
//! | [`reorder`] | part mesh, 3-axis ball-end operations | the *order* of the cutting points and the links between them (every point is still cut) |

pub mod checks;
pub mod directions;
pub mod feed;
pub mod force;
pub mod leadtilt;
pub mod machine;
pub mod orient;
pub mod pipeline;
pub mod post;
pub mod reorder;
pub mod safety;
pub mod setup;
pub mod speed;
pub mod timing;
