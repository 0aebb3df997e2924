//! `.blend` sources. Blender itself reads them: run headless (`VVGEN_BLENDER`, else `blender` on the PATH), it
//! evaluates every frame asked for and exports what the manifest selects at that frame as a static glTF
//! (`blend_export.py`); the frames then load as a mesh sequence. Baking per frame, rather than exporting a glTF
//! animation, is what makes each frame what Blender shows: Blender's glTF animation export misses NLA-only
//! actions, some drivers and parent-inverse cases, and every modifier but armatures (measured on the
//! glTF-Blender-IO test scenes, docs/benchmarks.md). Nothing else reads the Blender format as Blender does, so vvgen does
//! not try.
//!
//! The import is an action of the cache, keyed in two steps because some of its inputs are only known once
//! Blender has read the file (the libraries it links and the images it names, like a compiler's header
//! dependencies):
//! - the *listing* key: the `.blend`'s bytes, Blender's version, the export script's bytes and the selection
//!   (`scene`, `object`, `collection`). Its record holds the external files that import read and the file's
//!   frame range (whether anything is animated);
//! - the *import* key: the listing key, each listed file's content (or its absence) and the frames exported
//!   (the manifest's `frames` resolved against that range: the same list however it is spelled). Its record
//!   holds the import's facts (frames, rate, the files written, warnings) and the files themselves, which are
//!   placed (hard-linked) in `blend/<import key>/` of the cache for the mesh-sequence reader.
//!
//! A later build hashes the same files (through the stat cache: unchanged files are not read) and never starts
//! Blender while both keys hold; even Blender's version is remembered per content of its executable.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;

use serde::Deserialize;

use super::input::{BlendSelect, FrameRange};
use super::Error;
use crate::cache::{self, Digest, StatCache, Store};

/// The script Blender runs; its bytes are part of every import key.
const SCRIPT: &str = include_str!("blend_export.py");

/// What the import found out, as `blend_export.py` writes it.
#[derive(Debug, Clone, Deserialize)]
pub struct Info {
    /// Blender's version string.
    pub blender: String,
    /// The scene exported.
    pub scene: String,
    /// Every scene of the file.
    pub scenes: Vec<String>,
    /// The objects exported.
    pub objects: Vec<String>,
    /// The scene's frame rate.
    pub fps: f64,
    /// The scene's first frame.
    pub frame_start: i64,
    /// The scene's last frame (inclusive).
    pub frame_end: i64,
    /// Whether anything in the file is animated (an action, an NLA track or a driver).
    pub animated: bool,
    /// The Blender frames exported, one file `frame_NNNNN.gltf` each (N counting from 0).
    pub frames: Vec<i64>,
    /// Every file written, relative to the import's folder (`/`-separated).
    pub files: Vec<String>,
    /// The external files the file reads (absolute).
    pub deps: Vec<PathBuf>,
    /// What the user should know (modifiers the export does not apply, missing files).
    pub warnings: Vec<String>,
}

/// An imported `.blend`: the folder of glTF frames Blender exported, and what the import found out.
#[derive(Debug)]
pub struct Imported {
    /// The folder holding `frame_NNNNN.gltf` (+Z up, in metres) for each of [`Info::frames`].
    pub dir: PathBuf,
    /// The facts.
    pub info: Info,
    /// Whether Blender ran for it (false: the cache held it).
    pub ran: bool,
}

/// Imports `.blend` sources through a cache.
pub struct Importer<'a> {
    store: &'a Store,
    stat: &'a StatCache,
    note: Option<&'a (dyn Fn(&str) + Sync)>,
    /// Action keys and blobs this importer used (kept by `gc`).
    used: Mutex<Vec<Digest>>,
}

impl std::fmt::Debug for Importer<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Importer").field("store", &self.store.root()).finish_non_exhaustive()
    }
}

impl<'a> Importer<'a> {
    /// An importer storing into `store`, hashing files through `stat`; `note` hears when Blender is started
    /// (it takes seconds: a user should know why the command waits).
    pub fn new(store: &'a Store, stat: &'a StatCache, note: Option<&'a (dyn Fn(&str) + Sync)>) -> Importer<'a> {
        Importer { store, stat, note, used: Mutex::new(Vec::new()) }
    }

    /// The action keys and blobs the imports so far used: what a garbage collection must keep.
    pub fn used(&self) -> Vec<Digest> {
        self.used.lock().expect("BUG: poisoned only by a panic elsewhere").clone()
    }

    /// Imports what `select` selects of `blend` over `frames`, from the cache when both keys hold, else by
    /// running Blender.
    pub fn import(&self, blend: &Path, select: &BlendSelect, frames: &FrameRange) -> Result<Imported, Error> {
        let io = |path: &Path, e: std::io::Error| Error::Io { path: path.to_path_buf(), source: e };
        let content = self.stat.digest(blend).map_err(|e| io(blend, e))?;
        let exe = blender_exe().map_err(|e| Error::Blend { path: blend.to_path_buf(), message: e.to_string() })?;
        let version = self.version(&exe).map_err(|message| Error::Blend { path: blend.to_path_buf(), message })?;
        let spec = FrameSpec { start: frames.start, end: frames.end, count: frames.count, step: frames.step };
        let selection = Selection {
            scene: select.scene.clone(),
            object: select.object.clone(),
            collection: select.collection.clone(),
        };
        let selection_json = serde_json::to_string(&selection).expect("strings serialize");
        let listing_fields = [
            ("file".to_string(), content.hex()),
            ("blender".to_string(), version.clone()),
            ("script".to_string(), Digest::of(SCRIPT.as_bytes()).hex()),
            ("selection".to_string(), selection_json.clone()),
        ];
        let listing = key_of("blend listing", &listing_fields);
        if let Some(got) = self.cached(&listing, &spec)? {
            return Ok(got);
        }
        if let Some(note) = self.note {
            note(&format!("importing {} with {} (once: the cache keeps it)", blend.display(), first_line(&version)));
        }
        // Absolute paths for Blender, which resolves relative ones against its own notion of the working folder.
        let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        let tmp =
            abs(self.store.root()).join("tmp").join(format!("blend-{}-{}", std::process::id(), &listing.hex()[..16]));
        std::fs::create_dir_all(&tmp).map_err(|e| io(&tmp, e))?;
        // The script's arguments: the selection, and the frames as the manifest gives them.
        let mut args = serde_json::to_value(&selection).expect("strings serialize");
        args["frames"] = serde_json::to_value(&spec).expect("numbers serialize");
        let result = self.run(&exe, &abs(blend), &tmp, args, &listing, &listing_fields);
        let _ = std::fs::remove_dir_all(&tmp);
        result
    }

    /// The import recorded under `listing`, when its listed files still hold what they held.
    fn cached(&self, listing: &Digest, spec: &FrameSpec) -> Result<Option<Imported>, Error> {
        let Some(blobs) = self.store.hit(listing, self.stat) else { return Ok(None) };
        let [deps_blob] = blobs[..] else { return Ok(None) };
        let Ok(facts) = self.store.get(&deps_blob) else { return Ok(None) };
        let Ok(facts) = serde_json::from_slice::<Listing>(&facts) else { return Ok(None) };
        let frames = spec.resolve(&facts);
        let (import, _) = self.import_key(listing, &facts.deps, &frames);
        let Some(blobs) = self.store.hit(&import, self.stat) else { return Ok(None) };
        let Some((&info_blob, files)) = blobs.split_first() else { return Ok(None) };
        let Ok(info_bytes) = self.store.get(&info_blob) else { return Ok(None) };
        let Ok(info) = serde_json::from_slice::<Info>(&info_bytes) else { return Ok(None) };
        if info.files.len() != files.len() {
            return Ok(None);
        }
        let dir = self.place(&import, &info, files)?;
        let mut used = self.used.lock().expect("BUG: poisoned only by a panic elsewhere");
        used.extend([*listing, deps_blob, import, info_blob]);
        used.extend(files);
        Ok(Some(Imported { dir, info, ran: false }))
    }

    /// Places the import's files (`blobs`, in the order of `info.files`) in `blend/<import key>/` of the cache.
    fn place(&self, import: &Digest, info: &Info, blobs: &[Digest]) -> Result<PathBuf, Error> {
        let dir = self.store.root().join("blend").join(import.hex());
        for (rel, d) in info.files.iter().zip(blobs) {
            // Written by the export script, but checked: a name never leaves the folder.
            let safe = Path::new(rel).components().all(|c| matches!(c, std::path::Component::Normal(_)));
            if !safe {
                return Err(Error::Blend {
                    path: dir.clone(),
                    message: format!("the import names `{rel}`, outside its folder"),
                });
            }
            let dest = dir.join(rel);
            if let Some(parent) = dest.parent() {
                std::fs::create_dir_all(parent).map_err(|e| Error::Io { path: parent.to_path_buf(), source: e })?;
            }
            self.store.materialize(d, &dest, self.stat).map_err(|e| Error::Blend {
                path: dest.clone(),
                message: format!("cannot place the imported file from the cache: {e}"),
            })?;
        }
        Ok(dir)
    }

    /// The import key: the listing key, each listed file's content (or its absence), and the frames exported.
    fn import_key(&self, listing: &Digest, deps: &[PathBuf], frames: &[i64]) -> (Digest, Vec<(String, String)>) {
        // The frames as first, count and step: the same list however the manifest spelled it.
        let step = if frames.len() > 1 { frames[1] - frames[0] } else { 1 };
        let span = format!("{} + {} x {step}", frames.first().copied().unwrap_or(0), frames.len());
        let mut fields = vec![("listing".to_string(), listing.hex()), ("frames".to_string(), span)];
        for p in deps {
            let d = self.stat.digest(p).map_or_else(|_| "missing".to_string(), |d| d.hex());
            fields.push((format!("reads {}", p.display()), d));
        }
        (key_of("blend import", &fields), fields)
    }

    /// Runs Blender on `blend` into `tmp`, then records the listing and the import.
    fn run(
        &self,
        exe: &Path,
        blend: &Path,
        tmp: &Path,
        mut args: serde_json::Value,
        listing: &Digest,
        listing_fields: &[(String, String)],
    ) -> Result<Imported, Error> {
        let fail = |message: String| Error::Blend { path: blend.to_path_buf(), message };
        // The script beside the export folder, not in it: everything in `out` is the import.
        let script = tmp.join("blend_export.py");
        let out_dir = tmp.join("out");
        std::fs::create_dir_all(&out_dir).map_err(|e| Error::Io { path: out_dir.clone(), source: e })?;
        std::fs::write(&script, SCRIPT).map_err(|e| Error::Io { path: script.clone(), source: e })?;
        args["out"] = serde_json::Value::String(out_dir.to_string_lossy().into_owned());
        // `--factory-startup`: no user preferences or add-ons shape the export. `--disable-autoexec`: a file's
        // own Python (startup scripts, scripted drivers) never runs; Blender's simple driver expressions still do.
        let mut command = Command::new(exe);
        if is_python(exe) {
            // The `bpy` module starts with factory settings; the file is opened without its scripts.
            command.arg("-c").arg(OPEN_THEN_RUN).arg(blend).arg(&script);
        } else {
            let flags = ["-b", "--factory-startup", "--disable-autoexec", "-noaudio"];
            command.args(flags).arg(blend).arg("--python").arg(&script);
        }
        let out = command
            .arg("--")
            .arg(args.to_string())
            .stdin(Stdio::null())
            .output()
            .map_err(|e| fail(format!("cannot run Blender ({}): {e}", exe.display())))?;
        let info_path = out_dir.join("info.json");
        if !out.status.success() || !info_path.is_file() {
            return Err(fail(blender_failure(&out) + &newer_hint(blend, &self.version(exe).unwrap_or_default())));
        }
        let read = |p: &Path| std::fs::read(p).map_err(|e| Error::Io { path: p.to_path_buf(), source: e });
        let info_bytes = read(&info_path)?;
        let info: Info = serde_json::from_slice(&info_bytes)
            .map_err(|e| fail(format!("the export script wrote an unreadable info.json: {e}")))?;
        let cache_err = |e: cache::Error| fail(format!("cannot store the import in the cache: {e}"));
        let facts = Listing {
            deps: info.deps.clone(),
            frame_start: info.frame_start,
            frame_end: info.frame_end,
            animated: info.animated,
        };
        let deps_bytes = serde_json::to_vec(&facts).expect("paths serialize");
        let deps_blob = self.store.put(&deps_bytes, self.stat).map_err(cache_err)?;
        let (import, import_fields) = self.import_key(listing, &info.deps, &info.frames);
        let info_blob = self.store.put(&info_bytes, self.stat).map_err(cache_err)?;
        let mut blobs = vec![info_blob];
        for rel in &info.files {
            blobs.push(self.store.put(&read(&out_dir.join(rel))?, self.stat).map_err(cache_err)?);
        }
        // The import's record first: a listing record always names an import that was recorded.
        for (key, blobs, fields) in
            [(import, blobs.clone(), import_fields.as_slice()), (*listing, vec![deps_blob], listing_fields)]
        {
            let staged = self.store.stage_action(&key, &blobs, fields).map_err(cache_err)?;
            let dest = staged.dest().to_path_buf();
            staged.commit().map_err(|e| Error::Io { path: dest, source: e })?;
        }
        let dir = self.place(&import, &info, &blobs[1..])?;
        let mut used = self.used.lock().expect("BUG: poisoned only by a panic elsewhere");
        used.extend([*listing, deps_blob, import]);
        used.extend(blobs);
        Ok(Imported { dir, info, ran: true })
    }

    /// Blender's version (`blender --version`), remembered per content of the executable; a Python's `bpy`
    /// version, remembered per content of the module's library in a virtual environment's `site-packages`
    /// (the Python's own executable is the same whichever `bpy` it has), else asked on every build.
    fn version(&self, exe: &Path) -> Result<String, String> {
        let derive = || -> Result<String, String> {
            let mut command = Command::new(exe);
            if is_python(exe) {
                command.arg("-c").arg(PRINT_VERSION);
            } else {
                command.arg("--version");
            }
            let out = command
                .stdin(Stdio::null())
                .output()
                .map_err(|e| format!("cannot run Blender ({}): {e}", exe.display()))?;
            let text = String::from_utf8_lossy(&out.stdout);
            // The release and the build hash name the build; the rest (build date, platform) follows from it.
            let lines: Vec<&str> = text
                .lines()
                .map(str::trim)
                .filter(|l| l.starts_with("Blender ") || l.starts_with("build hash"))
                .collect();
            if !out.status.success() || lines.is_empty() {
                return Err(if is_python(exe) {
                    format!(
                        "{} cannot import Blender's `bpy` module: install it there (`pip install bpy==4.5.*`, which \
                         needs Python 3.11), or name Blender itself in VVGEN_BLENDER",
                        exe.display()
                    )
                } else {
                    format!("{} --version did not print a Blender version: is it Blender?", exe.display())
                });
            }
            Ok(lines.join("; "))
        };
        let keyed_by = if is_python(exe) { bpy_library(exe) } else { Some(exe.to_path_buf()) };
        match keyed_by {
            Some(p) => {
                self.stat.derived("blender --version", &p, derive).map_err(|e| format!("{}: {e}", p.display()))?
            }
            None => derive(),
        }
    }
}

/// The selection, as the export script reads it.
#[derive(serde::Serialize)]
struct Selection {
    scene: Option<String>,
    object: Option<String>,
    collection: Option<String>,
}

/// The source's `frames`, in Blender's frame numbers; the rest comes from the file's range.
#[derive(serde::Serialize)]
struct FrameSpec {
    start: Option<i64>,
    end: Option<i64>,
    count: Option<u64>,
    step: Option<u64>,
}

impl FrameSpec {
    /// The Blender frames exported, as `blend_export.py` resolves them (the import key is computed from the
    /// script's list after a run; a disagreement here would only make later lookups miss, never reuse a wrong
    /// import): the manifest's `start` (else the file's first frame), to its `end`, or `count` frames, else the
    /// file's last frame when anything in it is animated (its first otherwise), every `step`.
    fn resolve(&self, facts: &Listing) -> Vec<i64> {
        let step = self.step.unwrap_or(1).max(1) as i64;
        let first = self.start.unwrap_or(facts.frame_start);
        let last = match (self.end, self.count) {
            (Some(e), _) => e,
            (None, Some(c)) => first.saturating_add((c as i64).saturating_sub(1).saturating_mul(step)),
            (None, None) if facts.animated => facts.frame_end,
            (None, None) => first,
        };
        // Bounded as the script bounds it: beyond the limit the script refuses, and so nothing is found here.
        (first..=last).step_by(step as usize).take(MAX_FRAMES + 1).collect()
    }
}

/// What a listing run found out about the file: the files it reads, and its frame range.
#[derive(serde::Serialize, Deserialize)]
struct Listing {
    deps: Vec<PathBuf>,
    frame_start: i64,
    frame_end: i64,
    animated: bool,
}

/// Frames one import may export (`MAX_FRAMES` in `blend_export.py`).
const MAX_FRAMES: usize = 100_000;

/// A key over named fields (the names are keyed too, so no value can pose as another's).
fn key_of(kind: &str, fields: &[(String, String)]) -> Digest {
    let parts: Vec<&[u8]> = fields.iter().flat_map(|(k, v)| [k.as_bytes(), v.as_bytes()]).collect();
    cache::key(kind, &parts)
}

fn first_line(s: &str) -> &str {
    s.split(';').next().unwrap_or(s)
}

/// What to tell a user when Blender did not export: the script's own `vvgen:` line, else Blender's last words.
fn blender_failure(out: &std::process::Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr);
    if let Some(l) = stderr.lines().rev().find_map(|l| l.strip_prefix("vvgen: ")) {
        return l.to_string();
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    let tail: Vec<&str> = stdout.lines().chain(stderr.lines()).filter(|l| !l.trim().is_empty()).collect();
    let tail = tail[tail.len().saturating_sub(6)..].join("\n    ");
    format!("Blender could not export it ({}):\n    {tail}", out.status)
}

/// The Blender release (major, minor) that saved a `.blend`, from its header: `BLENDER-v304` (pointer size,
/// endianness, version) or, from Blender 5, `BLENDER17-01v0500` (header size, format, version). `None` for a
/// compressed file (gzip or zstd: the header is inside) or one that is not a `.blend`.
pub fn saved_by(head: &[u8]) -> Option<(u32, u32)> {
    let rest = head.strip_prefix(b"BLENDER")?;
    let digits = |b: &[u8]| -> Option<u32> {
        b.iter().all(u8::is_ascii_digit).then(|| b.iter().fold(0, |n, d| n * 10 + u32::from(d - b'0')))
    };
    let v = match rest {
        [b'_' | b'-', b'v' | b'V', d @ ..] if d.len() >= 3 => digits(&d[..3])?,
        [_, _, b'-', _, _, b'v' | b'V', d @ ..] if d.len() >= 4 => digits(&d[..4])?,
        _ => return None,
    };
    Some((v / 100, v % 100))
}

/// When Blender failed on a file a newer Blender saved, the way out.
fn newer_hint(blend: &Path, version: &str) -> String {
    let mut head = [0u8; 17];
    let read = std::fs::File::open(blend).and_then(|mut f| std::io::Read::read(&mut f, &mut head));
    let file = read.ok().and_then(|n| saved_by(&head[..n]));
    let ours = version.strip_prefix("Blender ").and_then(|v| {
        let mut it = v.split(|c: char| !c.is_ascii_digit()).filter_map(|n| n.parse::<u32>().ok());
        Some((it.next()?, it.next()?))
    });
    match (file, ours) {
        (Some(f), Some(o)) if f > o => format!(
            "\n  the file was saved by Blender {}.{} and this is Blender {}.{}: run a Blender at least as new \
             (VVGEN_BLENDER=/path/to/blender, or a Python with `pip install bpy==4.5.*`: \
             VVGEN_BLENDER=/path/to/venv/bin/python)",
            f.0, f.1, o.0, o.1
        ),
        _ => String::new(),
    }
}

/// What to do without a Blender: install one, point at it, or export glTF from it.
const WAYS_OUT: &str = "install Blender (Debian/Ubuntu: apt install blender python3-numpy; or blender.org) and put \
                        it on the PATH or in VVGEN_BLENDER, or name a Python with Blender's module in VVGEN_BLENDER \
                        (`pip install bpy==4.5.*` in a Python 3.11 venv: VVGEN_BLENDER=/path/to/venv/bin/python); \
                        or, in Blender, File > Export > glTF 2.0 and use `gltf = \"….glb\"` instead";

/// Why no Blender can read a `.blend`; its message names the ways out.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum NoBlender {
    /// `VVGEN_BLENDER` names something that is not a file.
    #[error("VVGEN_BLENDER is {}, which is not a file: {WAYS_OUT}", .0.display())]
    NotAFile(PathBuf),
    /// No `blender` executable is on the `PATH`.
    #[error("a .blend needs Blender to read it, and none is on the PATH: {WAYS_OUT}")]
    NotOnPath,
}

/// What a Python with `bpy` runs in place of `blender -b FILE --python SCRIPT`: opens the file by its absolute
/// path (as Blender's command line makes it) with its own scripts off, as `--disable-autoexec` keeps them,
/// then runs the export script, which reads its arguments
/// after `--` as it does inside Blender. Arguments: FILE SCRIPT -- JSON.
const OPEN_THEN_RUN: &str = "import os, runpy, sys, bpy\n\
    bpy.ops.wm.open_mainfile(filepath=os.path.abspath(sys.argv[1]), load_ui=False, use_scripts=False)\n\
    runpy.run_path(sys.argv[2], run_name='__main__')\n";

/// What a Python with `bpy` prints in place of `blender --version`: the lines vvgen keys imports by.
const PRINT_VERSION: &str = "import bpy\n\
    print('Blender', bpy.app.version_string)\n\
    print('build hash:', bpy.app.build_hash.decode())\n";

/// Whether `exe` is a Python with Blender's `bpy` module (the PyPI wheel: `pip install bpy==4.5.*` brings a
/// current Blender where the system's is old, as Debian 12's 3.4 is) rather than Blender: its name says so
/// (`python`, `python3`, `python3.11`).
fn is_python(exe: &Path) -> bool {
    exe.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("python"))
}

/// The `bpy` module's library beside a virtual environment's Python (`…/bin/python` →
/// `…/lib/python3.X/site-packages/bpy/__init__….so`), which names the `bpy` that Python runs.
fn bpy_library(exe: &Path) -> Option<PathBuf> {
    let lib = exe.parent()?.parent()?.join("lib");
    let pythons = std::fs::read_dir(lib).ok()?.filter_map(|e| e.ok().map(|e| e.path()));
    let mut found: Vec<PathBuf> = pythons
        .filter_map(|p| std::fs::read_dir(p.join("site-packages/bpy")).ok())
        .flat_map(|d| d.filter_map(|e| e.ok().map(|e| e.path())))
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str());
            name.is_some_and(|n| n.starts_with("__init__") && n.ends_with(".so"))
        })
        .collect();
    found.sort();
    found.pop()
}

/// The Blender to run: `VVGEN_BLENDER`, else `blender` on the PATH.
pub fn blender_exe() -> Result<PathBuf, NoBlender> {
    if let Some(p) = std::env::var_os("VVGEN_BLENDER").filter(|p| !p.is_empty()) {
        let p = PathBuf::from(p);
        return if p.is_file() { Ok(p) } else { Err(NoBlender::NotAFile(p)) };
    }
    let found = std::env::var_os("PATH").and_then(|path| {
        std::env::split_paths(&path).map(|d| d.join("blender")).find(|p| p.is_file() && executable(p))
    });
    found.ok_or(NoBlender::NotOnPath)
}

#[cfg(unix)]
fn executable(p: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    p.metadata().is_ok_and(|m| m.permissions().mode() & 0o111 != 0)
}

#[cfg(not(unix))]
fn executable(_: &Path) -> bool {
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_header_says_which_blender_saved_the_file() {
        assert_eq!(saved_by(b"BLENDER-v304REND"), Some((3, 4)));
        assert_eq!(saved_by(b"BLENDER_V278REND"), Some((2, 78)));
        assert_eq!(saved_by(b"BLENDER17-01v0500"), Some((5, 0)));
        assert_eq!(saved_by(b"BLENDER-v30"), None);
        assert_eq!(saved_by(b"\x28\xb5\x2f\xfd compressed"), None);
        assert_eq!(saved_by(b"BLENDER-vabc"), None);
    }
}
