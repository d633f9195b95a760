//! The mean force on the tool over a stretch of path: the mean over the
//! poses it was loaded at of each pose's mean over a revolution
//! ([`super::Summary::mean`], tool frame). A pose whose edge meets no
//! material counts as zero force, so a move that cuts over half its length
//! has half the mean of one that cuts all along it. This is the steady
//! (static) part of the load that deflects a compliant machine such as a
//! robot; the ranges of the force table are its fluctuation.

use super::Summary;

/// Running mean of the revolution means of a move's loaded poses (tool
/// frame, N).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MeanForce {
    sum: [f64; 3],
    poses: u32,
}

impl MeanForce {
    /// A pose in material: its mean force over a revolution.
    pub fn add(&mut self, s: &Summary) {
        for (a, m) in self.sum.iter_mut().zip(s.mean) {
            *a += m;
        }
        self.poses += 1;
    }

    /// A pose whose edge met no material (zero force).
    pub fn add_air(&mut self) {
        self.poses += 1;
    }

    /// The poses counted.
    pub fn poses(&self) -> u32 {
        self.poses
    }

    /// The mean force over the poses, tool frame (x along the feed, y = z × x,
    /// z along the axis toward the shank), N; zero without poses.
    pub fn mean(&self) -> [f64; 3] {
        if self.poses == 0 {
            return [0.0; 3];
        }
        self.sum.map(|s| s / self.poses as f64)
    }
}
