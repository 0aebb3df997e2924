//! `vvgen build`: runs [`crate::build::build`] with a progress bar (plain log lines when standard error is not
//! a terminal).

use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;
use std::sync::Mutex;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::{cache_dir, load_manifest_warned, Ui, EXIT_INVALID};
use crate::build::{self, Options, Progress};
use crate::execute::Shard;
use crate::plan::actions::Kind;

struct Display {
    bar: Option<ProgressBar>,
    quiet: bool,
    /// Total, and the last tenth reported (plain mode).
    plain: Mutex<(usize, usize)>,
}

impl Progress for Display {
    fn started(&self, hits: usize, work: usize) {
        if let Some(b) = &self.bar {
            b.set_length(work as u64);
            b.set_message(format!("({hits} cached)"));
        } else if !self.quiet {
            eprintln!("{hits} actions cached, running {work}");
        }
        self.plain.lock().expect("BUG: poisoned only by a panic elsewhere").0 = work;
    }

    fn ran(&self, done: usize) {
        if let Some(b) = &self.bar {
            b.set_position(done as u64);
            return;
        }
        let mut p = self.plain.lock().expect("BUG: poisoned only by a panic elsewhere");
        let tenth = (done * 10).checked_div(p.0).unwrap_or(10);
        if tenth > p.1 && !self.quiet {
            p.1 = tenth;
            eprintln!("ran {done}/{}", p.0);
        }
    }

    fn importing(&self, what: &str) {
        match &self.bar {
            Some(b) => b.println(what),
            None if !self.quiet => eprintln!("{what}"),
            None => {}
        }
    }

    fn waiting(&self, what: &str) {
        if !self.quiet {
            eprintln!("waiting for another build of {what} to finish (its work will be reused)");
        }
    }

    fn writing(&self, name: &str) {
        match &self.bar {
            Some(b) => b.set_message(format!("writing {name}")),
            None if !self.quiet => eprintln!("writing output `{name}`"),
            None => {}
        }
    }
}

/// Above this many images to render in one process, `vvgen build` asks for `--yes` (a mistyped view count
/// should not start a week of rendering silently).
pub const MAX_IMAGES_WITHOUT_YES: usize = 100_000;

/// Parses `K/N` (0 ≤ K < N), as Slurm array jobs number their tasks.
pub(super) fn parse_shard(s: &str) -> Result<Shard, String> {
    let (k, n) = s.split_once('/').ok_or_else(|| format!("`{s}`: expected K/N, e.g. 0/4"))?;
    let (index, count): (u64, u64) = (
        k.trim().parse().map_err(|_| format!("`{k}` is not a shard index"))?,
        n.trim().parse().map_err(|_| format!("`{n}` is not a shard count"))?,
    );
    if count == 0 || index >= count {
        return Err(format!("shard {index}/{count}: need 0 ≤ K < N"));
    }
    Ok(Shard { index, count })
}

/// `vvgen build`: `preview: false` (`--no-preview`) skips the previews for this build.
pub fn run(manifest: &Path, jobs: Option<usize>, opts: Options, preview: bool, ui: Ui) -> anyhow::Result<ExitCode> {
    let Some((mut m, warned)) = load_manifest_warned(manifest, ui) else { return Ok(ExitCode::from(EXIT_INVALID)) };
    let strict = opts.deny_warnings || m.dataset.strict;
    if strict && warned > 0 {
        eprintln!(
            "error: {}: {warned} warning(s), and warnings are errors here (`[dataset] strict` or --deny-warnings)",
            manifest.display()
        );
        return Ok(ExitCode::from(EXIT_INVALID));
    }
    m.dataset.preview &= preview;
    let report = match build_and_report(&m, jobs, opts, ui) {
        Ok(r) => r,
        Err(e) => {
            let stopped = e.downcast_ref::<build::Error>().and_then(interruption);
            let Some((finished, work)) = stopped else { return Err(e) };
            eprintln!(
                "interrupted: {finished} of {work} actions finished and are kept in the cache, and no file was \
                 left half-written; run the same command again to resume where it stopped"
            );
            return Ok(ExitCode::from(EXIT_INTERRUPTED));
        }
    };
    // What the writers warn of is known only once they have written: the datasets stay, the exit says so.
    let late: usize = report.after.iter().chain(&report.outputs).map(|(_, w)| w.warnings.len()).sum();
    if strict && late > 0 {
        eprintln!("error: {}: the writers warned {late} time(s), and warnings are errors here", manifest.display());
        return Ok(ExitCode::from(EXIT_INVALID));
    }
    Ok(ExitCode::SUCCESS)
}

/// Ctrl-C during a build: the first asks the build to stop ([`crate::execute::INTERRUPT`]: what finished is
/// committed, then the build says what it kept); a second leaves at once (what was committed is still whole:
/// everything lands by rename). Only async-signal-safe calls here (an atomic store, `write`, `_exit`).
#[cfg(target_os = "linux")]
extern "C" fn interrupted(_: libc::c_int) {
    use std::sync::atomic::Ordering;
    if crate::execute::INTERRUPT.swap(true, Ordering::Relaxed) {
        const SAID: &[u8] = b"\ninterrupted again: leaving now; what was committed is kept\n";
        unsafe {
            libc::write(2, SAID.as_ptr().cast(), SAID.len());
            libc::_exit(130);
        }
    }
}

/// The exit code of an interrupted build (128 + SIGINT, as shells report it).
const EXIT_INTERRUPTED: u8 = 130;

/// The counts of an interrupted build (this manifest's or an `after` one's).
fn interruption(e: &build::Error) -> Option<(usize, usize)> {
    match e {
        build::Error::Execute { source, .. } => match **source {
            crate::execute::Error::Interrupted { finished, work } => Some((finished, work)),
            _ => None,
        },
        build::Error::After { source, .. } => interruption(source),
        _ => None,
    }
}

/// Builds `m` with a progress display and prints what the build did.
pub(super) fn build_and_report(
    m: &crate::manifest::Manifest,
    jobs: Option<usize>,
    opts: Options,
    ui: Ui,
) -> anyhow::Result<build::Report> {
    let bar = (!ui.quiet && std::io::stderr().is_terminal()).then(|| {
        let b = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr());
        b.set_style(
            ProgressStyle::with_template("{bar:40} {pos}/{len} actions  {per_sec}  eta {eta}  {msg}")
                .expect("BUG: valid template"),
        );
        b
    });
    let display = Display { bar, quiet: ui.quiet, plain: Mutex::new((0, 0)) };
    #[cfg(target_os = "linux")]
    unsafe {
        libc::signal(libc::SIGINT, interrupted as *const () as libc::sighandler_t);
    }
    let cache = cache_dir(m);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(jobs.unwrap_or(0)).build()?;
    let result = pool.install(|| build::build(m, &cache, opts, &display));
    if let Some(b) = &display.bar {
        b.finish_and_clear();
    }
    let report = result?;
    if !ui.quiet {
        for w in &report.warnings {
            eprintln!("warning: {w}");
        }
        for (name, w) in report.after.iter().chain(&report.outputs) {
            for warning in &w.warnings {
                eprintln!("warning: output `{name}`: {warning}");
            }
            eprintln!("{name}: {} files in {}", w.files.len(), w.root.display());
            let page = format!("{}/index.html", crate::preview::DIR);
            if w.files.iter().any(|(f, _)| *f == page) {
                eprintln!("  preview: {}", w.root.join(&page).display());
            }
        }
        if report.stale_removed > 0 {
            eprintln!("removed {} stale file(s) an earlier build wrote", report.stale_removed);
        }
        let render = report.actions.get(&Kind::RenderPass).copied().unwrap_or_default();
        let rate = if render.seconds > 0.0 { report.renders as f64 / render.seconds } else { 0.0 };
        if report.images > 0 {
            let speed = if report.renders > 0 { format!(" ({rate:.1} images/s)") } else { String::new() };
            eprintln!(
                "{} images: {} cached, {} rendered in {:.2} s{speed}; {:.2} s in all",
                report.images, report.hits, report.renders, render.seconds, report.total_seconds
            );
        } else {
            eprintln!("{:.2} s in all", report.total_seconds);
        }
        let kinds: Vec<String> = report
            .actions
            .iter()
            .filter(|(_, c)| c.ran > 0 || c.elsewhere > 0)
            .map(|(k, c)| {
                let shards = if c.elsewhere > 0 { format!(", {} to other shards", c.elsewhere) } else { String::new() };
                let time = if k.cached() { format!(" in {:.2} s", c.seconds) } else { String::new() };
                format!("{} {}/{}{time}{shards}", k.name(), c.ran, c.planned)
            })
            .collect();
        if report.nothing_to_do() {
            eprintln!("nothing to do: every action cached, every output up to date");
        } else {
            eprintln!("ran: {}", kinds.join(", "));
        }
    }
    Ok(report)
}
