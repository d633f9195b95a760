//! Simulation against the part: drop-cutter of flat, ball, bull and cone cutters
//! on triangle meshes ([`dropcutter`]), the gouge check of a program
//! ([`gouge`]) and finishing rasters made of drop-cutter points ([`raster`]).

pub mod dropcutter;
