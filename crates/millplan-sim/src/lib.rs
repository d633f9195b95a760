//! Simulation against the part: drop-cutter of flat, ball, bull and cone cutters
//! on triangle meshes ([`dropcutter`]), the gouge check of a program
//! ([`gouge`]), finishing rasters made of drop-cutter points ([`raster`]) and
//! tool-direction accessibility on a spherical map ([`access`]), and the
//! stock: material removal and engagement along a program ([`stock`]).

pub mod access;
pub mod dropcutter;
pub mod gouge;
pub mod raster;
pub mod stock;

use millplan_models::cutter::Shape;

/// The cutter shape of an IR tool, when its geometry is known.
pub fn shape_of(c: &millplan_nc::Cutter) -> Option<Shape> {
    Shape::from_iso(c.d, c.r, c.alpha)
}
