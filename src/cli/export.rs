//! `irad export`: a scene written for another renderer (docs/export.md).

use std::path::PathBuf;

use anyhow::Result;
use clap::Subcommand;

use irad::scene;

#[derive(Subcommand)]
pub enum ExportCommand {
    /// Write a Mitsuba 3 scene: DIR/scene.xml (version 3.0.0), one PLY mesh per material and,
    /// with an environment map, DIR/environment.exr. Prints what Mitsuba cannot reproduce
    /// exactly (Phong lobes, spot falloff, ...). Scenes with light-field luminaires are
    /// refused. Render with an RGB variant: `mitsuba -m scalar_rgb DIR/scene.xml`.
    Mitsuba {
        /// Scene TOML file.
        scene: PathBuf,
        /// Output folder (created if missing).
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
    },
}

pub fn run(command: ExportCommand) -> Result<()> {
    match command {
        ExportCommand::Mitsuba { scene, out } => {
            let scene = scene::load(&scene)?;
            let export = irad::export::write_mitsuba(&scene, &out)?;
            for a in &export.approximations {
                println!("approximation: {a}");
            }
            println!(
                "wrote {} and {} file(s) it references in {}",
                export.xml.display(),
                export.files.len(),
                out.display()
            );
            Ok(())
        }
    }
}
