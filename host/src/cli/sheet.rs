//! `rigctl sheet`: writes the printable trace sheet (SVG, A4, user units mm).

use super::out::errln;
use super::CliError;
use rigctl::io::atomic::{write_atomic, AtomicWriteError};
use rigctl::sheet::{svg::render_svg, ReferencePath};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output SVG file.
    #[arg(long)]
    pub out: PathBuf,
    /// Reference path(s) printed in red; repeat for several.
    #[arg(long = "path", value_enum, default_value = "circle")]
    pub paths: Vec<PathKind>,
}

/// The reference paths the sheet can carry.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathKind {
    /// The thesis circle, radius 100 mm about the sheet origin.
    Circle,
    /// A straight line along x through the origin, 200 mm long.
    Line,
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files().output("--out", Some(&args.out)).check()?;
    let paths: Vec<ReferencePath> = args
        .paths
        .iter()
        .map(|p| match p {
            PathKind::Circle => ReferencePath::Circle,
            PathKind::Line => ReferencePath::Line,
        })
        .collect();
    let svg = render_svg(&paths);
    write_atomic(&args.out, |w| {
        w.write_all(svg.as_bytes())
            .map_err(|source| AtomicWriteError::Io {
                path: args.out.clone(),
                source,
            })
    })?;
    errln!(
        "rigctl sheet: wrote {} (print at 100 %, then measure the corner discs' spacing)",
        args.out.display()
    );
    Ok(())
}
