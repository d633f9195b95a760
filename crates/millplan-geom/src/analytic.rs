//! Analytic free-form surfaces with exact heights and normals: the bundled demo
//! part and the oracle for tests that need a surface whose answer is known.

use crate::mesh::TriMesh;
use glam::{DVec2, DVec3};

/// A surface z = f(x, y) over a rectangular domain, with its exact gradient.
pub trait HeightField: Sync {
    fn z(&self, x: f64, y: f64) -> f64;
    /// (∂z/∂x, ∂z/∂y).
    fn grad(&self, x: f64, y: f64) -> DVec2;
    /// Domain corners (min, max) in x and y.
    fn domain(&self) -> (DVec2, DVec2);

    /// Unit upward normal.
    fn normal(&self, x: f64, y: f64) -> DVec3 {
        let g = self.grad(x, y);
        DVec3::new(-g.x, -g.y, 1.0).normalize()
    }

    fn point(&self, x: f64, y: f64) -> DVec3 {
        DVec3::new(x, y, self.z(x, y))
    }
}

/// The demo part: a 60 × 60 mm free-form pad with a dome, a saddle-like wave and
/// slopes from 0° to about 40°, the kind of surface ball-end finishing is for.
#[derive(Clone, Copy, Debug)]
pub struct DemoSurface {
    pub size: f64,
}

impl Default for DemoSurface {
    fn default() -> Self {
        DemoSurface { size: 60.0 }
    }
}

impl DemoSurface {
    const DOME_H: f64 = 8.0;
    const DOME_S2: f64 = 180.0; // 2σ² (mm²)
    const WAVE_A: f64 = 1.5;
}

impl HeightField for DemoSurface {
    fn z(&self, x: f64, y: f64) -> f64 {
        let c = self.size / 2.0;
        let (dx, dy) = (x - c, y - c);
        let dome = Self::DOME_H * (-(dx * dx + dy * dy) / Self::DOME_S2).exp();
        let k = std::f64::consts::TAU / self.size;
        let wave = Self::WAVE_A * (k * x).sin() * (0.75 * k * y).cos();
        dome + wave
    }

    fn grad(&self, x: f64, y: f64) -> DVec2 {
        let c = self.size / 2.0;
        let (dx, dy) = (x - c, y - c);
        let e = Self::DOME_H * (-(dx * dx + dy * dy) / Self::DOME_S2).exp();
        let k = std::f64::consts::TAU / self.size;
        let gx = e * (-2.0 * dx / Self::DOME_S2)
            + Self::WAVE_A * k * (k * x).cos() * (0.75 * k * y).cos();
        let gy = e * (-2.0 * dy / Self::DOME_S2)
            - Self::WAVE_A * 0.75 * k * (k * x).sin() * (0.75 * k * y).sin();
        DVec2::new(gx, gy)
    }

    fn domain(&self) -> (DVec2, DVec2) {
        (DVec2::ZERO, DVec2::splat(self.size))
    }
}

/// Triangulates a height field on a regular grid of about `step` mm
/// (two triangles per cell, counter-clockwise seen from +Z).
pub fn tessellate(surface: &dyn HeightField, step: f64) -> TriMesh {
    let (lo, hi) = surface.domain();
    let nx = (((hi.x - lo.x) / step).round() as usize).max(1);
    let ny = (((hi.y - lo.y) / step).round() as usize).max(1);
    let mut vertices = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        let y = lo.y + (hi.y - lo.y) * j as f64 / ny as f64;
        for i in 0..=nx {
            let x = lo.x + (hi.x - lo.x) * i as f64 / nx as f64;
            vertices.push(surface.point(x, y));
        }
    }
    let mut triangles = Vec::with_capacity(2 * nx * ny);
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    for j in 0..ny {
        for i in 0..nx {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    TriMesh {
        vertices,
        triangles,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gradient_matches_finite_differences() {
        let s = DemoSurface::default();
        let h = 1e-6;
        for &(x, y) in &[(3.0, 4.0), (30.0, 30.0), (17.5, 42.25), (59.0, 1.0)] {
            let g = s.grad(x, y);
            let fx = (s.z(x + h, y) - s.z(x - h, y)) / (2.0 * h);
            let fy = (s.z(x, y + h) - s.z(x, y - h)) / (2.0 * h);
            crate::assert_near!(g.x, fx, 1e-6);
            crate::assert_near!(g.y, fy, 1e-6);
        }
    }

    #[test]
    fn tessellation_is_an_open_sheet_facing_up() {
        let m = tessellate(&DemoSurface::default(), 2.0);
        assert_eq!(m.len(), 2 * 30 * 30);
        let e = m.edge_report();
        assert_eq!((e.open, e.non_manifold), (4 * 30, 0));
        assert!((0..m.len()).all(|t| m.facet_normal(t).z > 0.0));
    }
}
