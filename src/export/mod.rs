//! Scenes written out for other renderers, so irad's images can be cross-checked there
//! (`irad export`). `mitsuba` writes a Mitsuba 3 scene: XML, one PLY mesh per material and an
//! EXR environment map, mapping irad's conventions (docs/DESIGN.md "Conventions") onto Mitsuba's
//! plugins exactly where Mitsuba has the same model and, where it has not (Phong lobes, spot
//! falloff, the bilinear environment lookup), as the closest fit, listed one line each in
//! `MitsubaExport::approximations`. `ply` writes the meshes.

pub mod mitsuba;
pub mod ply;

pub use mitsuba::{write_mitsuba, ExportError, MitsubaExport};
