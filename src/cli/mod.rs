//! The command-line front end: argument parsing, printing, exit codes. Each subcommand calls one library
//! function; nothing below `cli` prints.

mod build;
mod check;
mod compare;
mod gc;
mod inspect;
mod new;
mod plan;
mod preview;
mod release;
mod up;

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

/// Exit code for an invalid manifest or input.
pub const EXIT_INVALID: u8 = 2;

/// vvgen: datasets of dynamic 6-DoF content from declarative TOML manifests.
#[derive(Debug, Parser)]
#[command(name = "vvgen", version, about, long_about = None)]
#[command(after_help = "Example:\n  vvgen build manifests/cesium-man.toml")]
pub struct Cli {
    /// Print less (errors only).
    #[arg(short, long, global = true)]
    pub quiet: bool,
    /// Print more (repeat for more detail).
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    pub verbose: u8,
    /// When to colour diagnostics.
    #[arg(long, global = true, value_enum, default_value_t = Color::Auto)]
    pub color: Color,
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// `--color`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Color {
    /// Colour when standard error is a terminal and NO_COLOR is unset.
    Auto,
    /// Always colour.
    Always,
    /// Never colour.
    Never,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Check manifests: syntax, types, unknown keys, references, input files. Exit 2 if any is invalid.
    #[command(after_help = "Example:\n  vvgen check manifests/cesium-man.toml manifests/*.toml")]
    Check {
        /// Manifest files.
        #[arg(required = true)]
        manifests: Vec<PathBuf>,
        /// Every warning is an error (exit 2), as `[dataset] strict = true` makes it.
        #[arg(long)]
        deny_warnings: bool,
    },
    /// Build every output of a manifest: plan the images, render them (in parallel), write the datasets.
    #[command(after_help = "Example:\n  vvgen build manifests/cesium-man.toml --jobs 2")]
    Build {
        /// The manifest.
        manifest: PathBuf,
        /// Worker threads (default: one per core).
        #[arg(long, short)]
        jobs: Option<usize>,
        /// Render only shard K of N (0 ≤ K < N) of the missing images into the cache, and write no datasets;
        /// a final unsharded build writes them.
        #[arg(long, value_parser = build::parse_shard)]
        shard: Option<crate::execute::Shard>,
        /// Hash every cached blob and dataset file again instead of trusting size, mtime and inode (finds bit
        /// rot; a damaged blob is rebuilt).
        #[arg(long)]
        verify: bool,
        /// Go ahead even when this process would render more than 100 000 images.
        #[arg(long)]
        yes: bool,
        /// Skip the preview (`preview/` in each dataset: contact sheets, rig plot, viewer) for this build.
        #[arg(long)]
        no_preview: bool,
        /// Every warning is an error (exit 2): the build stops before rendering, as `[dataset] strict = true`
        /// makes it.
        #[arg(long)]
        deny_warnings: bool,
    },
    /// Build a manifest's datasets with their previews (contact sheets, rig plot, point-cloud strip, HTML
    /// viewer); with `--out`, also copy each output's preview to DIR/OUTPUT.
    #[command(after_help = "Example:\n  vvgen preview manifests/cesium-man.toml --out /tmp/look")]
    Preview {
        /// The manifest.
        manifest: PathBuf,
        /// Copy each output's preview to DIR/OUTPUT/ (its viewer links the dataset's images by absolute
        /// path).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Worker threads (default: one per core).
        #[arg(long, short)]
        jobs: Option<usize>,
    },
    /// Show what a build would do: images cached, stale (changed since the last build) and new.
    #[command(after_help = "Example:\n  vvgen plan manifests/cesium-man.toml --explain")]
    Plan {
        /// The manifest.
        manifest: PathBuf,
        /// Say why each stale image is stale.
        #[arg(long)]
        explain: bool,
        /// Print JSON.
        #[arg(long)]
        json: bool,
        /// Hash every cached file again instead of trusting its metadata.
        #[arg(long)]
        verify: bool,
    },
    /// What is built, what is stale, and the cache's size.
    Status {
        /// The manifest.
        manifest: PathBuf,
        /// Hash every cached file again instead of trusting its metadata.
        #[arg(long)]
        verify: bool,
    },
    /// Write vvgen.lock (every file's size and blake3) at each dataset root; refuses while anything is stale.
    Release {
        /// The manifest.
        manifest: PathBuf,
    },
    /// Check a dataset directory against its vvgen.lock: missing, modified and extra files. Exit 1 on any.
    #[command(after_help = "Example:\n  vvgen verify out/cesium-man/cesium-man_dnerf")]
    Verify {
        /// The dataset directory (holding vvgen.lock).
        dir: PathBuf,
    },
    /// Remove cache entries no listed manifest needs, and/or the oldest beyond a size.
    #[command(after_help = "Example:\n  vvgen gc --keep manifests/cesium-man.toml --max-size 20G")]
    Gc {
        /// Keep what these manifests need (default: keep everything, apply only --max-size).
        #[arg(long, num_args = 1..)]
        keep: Vec<PathBuf>,
        /// Size budget, e.g. 500M or 20G.
        #[arg(long, value_parser = gc::parse_size)]
        max_size: Option<u64>,
        /// Keep files younger than this, e.g. 0, 30m, 2h (default 1h: a build running now may not have
        /// recorded its blobs yet).
        #[arg(long, value_parser = gc::parse_age)]
        min_age: Option<std::time::Duration>,
        /// The cache (default: `VVGEN_CACHE`, else the first kept manifest's, else `cache/` here).
        #[arg(long)]
        cache: Option<PathBuf>,
    },
    /// Write a commented manifest to start from, for a glTF, FBX, .blend, PLY, OBJ, STL or Draco file or a folder of
    /// PLY, OBJ, STL or Draco frames: clips, frame count and up axis read off the asset, the NeRF-synthetic recipe
    /// for the rest.
    #[command(
        after_help = "Examples:\n  vvgen new CesiumMan.glb\n  vvgen new frames/ --writer nerfstudio -o scan.toml"
    )]
    New {
        /// The asset: a .gltf/.glb, .fbx, .blend, .ply, .obj or .stl file, or a folder of .ply, .obj or .stl frames.
        asset: PathBuf,
        /// The output's writer.
        #[arg(long, default_value = "dnerf", value_parser = clap::builder::PossibleValuesParser::new(new::WRITERS))]
        writer: String,
        /// Where to write the manifest (default: `<asset name>.toml` here; never overwritten).
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
    /// Print the manifest's JSON Schema (for Taplo / Even Better TOML: completion, hover docs, inline errors).
    #[command(
        after_help = "Example:\n  vvgen schema > vvgen.schema.json   # then `#:schema ./vvgen.schema.json` atop a manifest"
    )]
    Schema,
    /// Score renders or decoded point clouds against the ground truth: images by PSNR and SSIM (whole and inside
    /// the ground truth's alpha), point clouds by MPEG pc_error's D1, D2 and colour PSNR. Exit 2 on input that
    /// does not pair up.
    #[command(after_help = "Examples:
  vvgen compare out/lego_dnerf/test renders/test
  vvgen compare out/lego_dnerf/test renders/ --frames out/lego_dnerf/transforms_test.json --json
  vvgen compare out/man_points decoded/ --peak 1023")]
    Compare {
        /// The ground truth: a folder of images (one split's), a PLY file, or a folder of PLY frames.
        reference: PathBuf,
        /// What to score: renders, or decoded point clouds (the same kind as the ground truth).
        test: PathBuf,
        /// Pair images by this transforms.json's frames, in order, against the test folder's images in name
        /// order (as trainers number their renders).
        #[arg(long)]
        frames: Option<PathBuf>,
        /// What transparent pixels are composited over: white, black, or R,G,B in 0 … 1.
        #[arg(long, default_value = "white")]
        background: String,
        /// The geometry PSNR's peak (1023 for vox10); default: the reference's largest nearest-neighbour
        /// distance, as pc_error.
        #[arg(long)]
        peak: Option<f64>,
        /// The reference's normals, for D2, when its files carry none (pc_error's `-n`): the same points with
        /// normals, a file or a folder of one per frame.
        #[arg(long)]
        normals: Option<PathBuf>,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Show a manifest's scene: sources, clips, frames, bounds, resolved transforms, posed-geometry hashes.
    #[command(
        after_help = "Examples:\n  vvgen inspect manifests/cesium-man.toml\n  vvgen inspect manifests/cesium-man.toml --frame 12 --ply posed.ply"
    )]
    Inspect {
        /// The manifest.
        manifest: PathBuf,
        /// Only this source.
        #[arg(long)]
        source: Option<String>,
        /// Frame to describe and export.
        #[arg(long, default_value_t = 0)]
        frame: usize,
        /// Write the posed, transformed geometry of the frame (normals, colours, faces) to this PLY file.
        #[arg(long)]
        ply: Option<PathBuf>,
    },
}

/// Output settings shared by the subcommands.
#[derive(Debug, Clone, Copy)]
pub struct Ui {
    /// Colour diagnostics.
    pub color: bool,
    /// -q
    pub quiet: bool,
    /// -v count
    pub verbose: u8,
}

/// Parses the process arguments and runs the command.
pub fn run() -> ExitCode {
    // A closed pipe (`vvgen plan m.toml | head -3`) ends the process quietly, as it ends `cat`, instead of
    // `println!` panicking on the write error.
    #[cfg(target_os = "linux")]
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let color = match cli.color {
        Color::Always => true,
        Color::Never => false,
        Color::Auto => std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none(),
    };
    let ui = Ui { color, quiet: cli.quiet, verbose: cli.verbose };
    let result = match cli.command {
        Command::Check { manifests, deny_warnings } => check::run(&manifests, deny_warnings, ui),
        Command::Build { manifest, jobs, shard, verify, yes, no_preview, deny_warnings } => {
            let max_images = (!yes).then_some(build::MAX_IMAGES_WITHOUT_YES);
            let opts = crate::build::Options { shard, verify, max_images, deny_warnings, ..Default::default() };
            build::run(&manifest, jobs, opts, !no_preview, ui)
        }
        Command::Preview { manifest, out, jobs } => preview::run(&manifest, out.as_deref(), jobs, ui),
        Command::Plan { manifest, explain, json, verify } => plan::run(&manifest, explain, json, verify, ui),
        Command::Status { manifest, verify } => plan::status(&manifest, verify, ui),
        Command::Release { manifest } => release::release(&manifest, ui),
        Command::Verify { dir } => release::verify(&dir, ui),
        Command::Gc { keep, max_size, min_age, cache } => gc::run(&keep, max_size, min_age, cache, ui),
        Command::Compare { reference, test, frames, background, peak, normals, json } => {
            compare::run(&reference, &test, frames.as_deref(), &background, peak, normals.as_deref(), json)
        }
        Command::Schema => serde_json::to_string_pretty(&crate::manifest::schema::json_schema())
            .map(|text| {
                println!("{text}");
                ExitCode::SUCCESS
            })
            .map_err(anyhow::Error::from),
        Command::New { asset, writer, out } => new::run(&asset, &writer, out.as_deref(), ui),
        Command::Inspect { manifest, source, frame, ply } => {
            inspect::run(&manifest, source.as_deref(), frame, ply.as_ref(), ui)
        }
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            // The library decides what is the input's fault; anything else is a failure.
            match e.downcast_ref::<crate::build::Error>() {
                Some(b) => ExitCode::from(b.exit_code()),
                None if e.downcast_ref::<crate::scene::Error>().is_some() => ExitCode::from(EXIT_INVALID),
                None if e.downcast_ref::<crate::compare::Error>().is_some() => ExitCode::from(EXIT_INVALID),
                None => ExitCode::FAILURE,
            }
        }
    }
}

/// A byte count for people: `1.2 GB`, `530 MB`, `12 kB` (decimal units, as `du -h --si`).
pub(crate) fn human_bytes(n: u64) -> String {
    let units = ["B", "kB", "MB", "GB", "TB", "PB"];
    let mut v = n as f64;
    let mut u = 0;
    while v >= 1000.0 && u + 1 < units.len() {
        v /= 1000.0;
        u += 1;
    }
    if u == 0 {
        format!("{n} B")
    } else {
        format!("{v:.1} {}", units[u])
    }
}

/// The cache a command uses: `VVGEN_CACHE` when set (shared caches on clusters), else the manifest's.
pub(crate) fn cache_dir(m: &crate::manifest::Manifest) -> PathBuf {
    cache_choice(m).0
}

/// The cache a command uses and why that one, for `status`: a user who finds a second cache asks where it came
/// from.
pub(crate) fn cache_choice(m: &crate::manifest::Manifest) -> (PathBuf, &'static str) {
    match std::env::var_os("VVGEN_CACHE").filter(|p| !p.is_empty()) {
        Some(p) => (PathBuf::from(p), "VVGEN_CACHE"),
        None if m.dataset.cache().is_some() => (crate::build::default_cache_dir(m), "[dataset] cache"),
        None => (crate::build::default_cache_dir(m), "the default: cache/ beside the manifest"),
    }
}

/// Opens `m`'s scene as `build` will, importing `.blend` sources through the cache `build` uses (so a later
/// build finds the import done), and saying so when Blender starts.
pub(crate) fn open_scene(m: &crate::manifest::Manifest, ui: Ui) -> anyhow::Result<crate::scene::Scene> {
    use crate::scene::blend;
    if !m.sources.values().any(|s| s.blend().is_some()) {
        return Ok(crate::settings::scene::open(m, None)?);
    }
    let store = crate::cache::Store::open(&cache_choice(m).0)?;
    let stat = store.stat_cache(&m.out_dir(), false);
    let say = |what: &str| eprintln!("{what}");
    let importer = blend::Importer::new(&store, &stat, (!ui.quiet).then_some(&say as &(dyn Fn(&str) + Sync)));
    let scene = crate::settings::scene::open(m, Some(&importer))?;
    // Blender's version, remembered per executable, and the digests hashed: the next command need not redo them.
    let _ = stat.save();
    Ok(scene)
}

/// Loads a manifest, printing its diagnostics; `None` when it is invalid.
pub(crate) fn load_manifest(path: &std::path::Path, ui: Ui) -> Option<crate::manifest::Manifest> {
    load_manifest_warned(path, ui).map(|(m, _)| m)
}

/// [`load_manifest`], with the number of warnings it printed.
pub(crate) fn load_manifest_warned(path: &std::path::Path, ui: Ui) -> Option<(crate::manifest::Manifest, usize)> {
    match crate::settings::load(path) {
        Ok((m, report)) => {
            if !ui.quiet && !report.diagnostics.is_empty() {
                eprint!("{}", report.render(ui.color));
            }
            Some((m, report.diagnostics.len()))
        }
        Err(report) => {
            eprint!("{}", report.render(ui.color));
            None
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn byte_counts_read_as_people_write_them() {
        assert_eq!(super::human_bytes(0), "0 B");
        assert_eq!(super::human_bytes(999), "999 B");
        assert_eq!(super::human_bytes(1_500), "1.5 kB");
        assert_eq!(super::human_bytes(494_696_600_000), "494.7 GB");
        assert_eq!(super::human_bytes(u64::MAX), "18446.7 PB");
    }
}
