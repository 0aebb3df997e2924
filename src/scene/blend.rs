//! `.blend` sources. Blender itself reads them: run headless (`VVGEN_BLENDER`, else `blender` on the PATH), it
//! exports what the manifest selects as one binary glTF with every animation baked per frame
//! (`blend_export.py`), which then loads like any glTF. Nothing else reads the Blender format as Blender does
//! (drivers, constraints, linked libraries, its own evaluation), so vvgen does not try.
//!
//! The import is an action of the cache, keyed in two steps because some of its inputs are only known once
//! Blender has read the file (the libraries it links and the images it names, like a compiler's header
//! dependencies):
//! - the *listing* key: the `.blend`'s bytes, Blender's version, the export script's bytes and the selection
//!   (`scene`, `object`, `collection`). Its record holds the list of external files that import read;
//! - the *import* key: the listing key and each listed file's content (or its absence). Its record holds the
//!   glTF and the import's facts (frame range, rate, warnings).
//!
//! A later build hashes the same files (through the stat cache: unchanged files are not read) and never starts
//! Blender while both keys hold; even Blender's version is remembered per content of its executable.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;

use serde::Deserialize;

use super::Error;
use crate::cache::{self, Digest, StatCache, Store};
use crate::manifest::Source;

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
    /// The external files the file reads (absolute).
    pub deps: Vec<PathBuf>,
    /// What the user should know (modifiers the export does not apply, missing files).
    pub warnings: Vec<String>,
}

/// An imported `.blend`: the glTF Blender exported, and what the import found out.
#[derive(Debug)]
pub struct Imported {
    /// A binary glTF, +Z up, in metres.
    pub glb: Vec<u8>,
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
        self.used.lock().unwrap().clone()
    }

    /// Imports `blend` as source `s` selects, from the cache when both keys hold, else by running Blender.
    pub fn import(&self, blend: &Path, s: &Source) -> Result<Imported, Error> {
        let io = |path: &Path, e: std::io::Error| Error::Io { path: path.to_path_buf(), source: e };
        let content = self.stat.digest(blend).map_err(|e| io(blend, e))?;
        let exe = blender_exe().map_err(|message| Error::Blend { path: blend.to_path_buf(), message })?;
        let version = self.version(&exe).map_err(|message| Error::Blend { path: blend.to_path_buf(), message })?;
        let selection = Selection {
            scene: s.scene_name().map(str::to_string),
            object: s.object.clone(),
            collection: s.collection.clone(),
        };
        let selection_json = serde_json::to_string(&selection).expect("strings serialize");
        let listing_fields = [
            ("file".to_string(), content.hex()),
            ("blender".to_string(), version.clone()),
            ("script".to_string(), Digest::of(SCRIPT.as_bytes()).hex()),
            ("selection".to_string(), selection_json.clone()),
        ];
        let listing = key_of("blend listing", &listing_fields);
        if let Some(got) = self.cached(&listing)? {
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
        let result = self.run(&exe, &abs(blend), &tmp, &selection_json, &listing, &listing_fields);
        let _ = std::fs::remove_dir_all(&tmp);
        result
    }

    /// The import recorded under `listing`, when its listed files still hold what they held.
    fn cached(&self, listing: &Digest) -> Result<Option<Imported>, Error> {
        let Some(blobs) = self.store.hit(listing, self.stat) else { return Ok(None) };
        let [deps_blob] = blobs[..] else { return Ok(None) };
        let Ok(deps) = self.store.get(&deps_blob) else { return Ok(None) };
        let Ok(deps) = serde_json::from_slice::<Vec<PathBuf>>(&deps) else { return Ok(None) };
        let (import, _) = self.import_key(listing, &deps);
        let Some(blobs) = self.store.hit(&import, self.stat) else { return Ok(None) };
        let [glb, info] = blobs[..] else { return Ok(None) };
        let (Ok(glb_bytes), Ok(info_bytes)) = (self.store.get(&glb), self.store.get(&info)) else { return Ok(None) };
        let Ok(info_value) = serde_json::from_slice::<Info>(&info_bytes) else { return Ok(None) };
        self.used.lock().unwrap().extend([*listing, deps_blob, import, glb, info]);
        Ok(Some(Imported { glb: glb_bytes, info: info_value, ran: false }))
    }

    /// The import key: the listing key and each listed file's content, or its absence.
    fn import_key(&self, listing: &Digest, deps: &[PathBuf]) -> (Digest, Vec<(String, String)>) {
        let mut fields = vec![("listing".to_string(), listing.hex())];
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
        selection_json: &str,
        listing: &Digest,
        listing_fields: &[(String, String)],
    ) -> Result<Imported, Error> {
        let fail = |message: String| Error::Blend { path: blend.to_path_buf(), message };
        let script = tmp.join("blend_export.py");
        std::fs::write(&script, SCRIPT).map_err(|e| Error::Io { path: script.clone(), source: e })?;
        let mut args: serde_json::Value = serde_json::from_str(selection_json).expect("written above");
        args["out"] = serde_json::Value::String(tmp.to_string_lossy().into_owned());
        // `--factory-startup`: no user preferences or add-ons shape the export. `--disable-autoexec`: a file's
        // own Python (startup scripts, scripted drivers) never runs; Blender's simple driver expressions still do.
        let out = Command::new(exe)
            .args(["-b", "--factory-startup", "--disable-autoexec", "-noaudio"])
            .arg(blend)
            .arg("--python")
            .arg(&script)
            .arg("--")
            .arg(args.to_string())
            .stdin(Stdio::null())
            .output()
            .map_err(|e| fail(format!("cannot run Blender ({}): {e}", exe.display())))?;
        let glb_path = tmp.join("scene.glb");
        let info_path = tmp.join("info.json");
        if !out.status.success() || !glb_path.is_file() || !info_path.is_file() {
            return Err(fail(blender_failure(&out)));
        }
        let read = |p: &Path| std::fs::read(p).map_err(|e| Error::Io { path: p.to_path_buf(), source: e });
        let (glb, info_bytes) = (read(&glb_path)?, read(&info_path)?);
        let info: Info = serde_json::from_slice(&info_bytes)
            .map_err(|e| fail(format!("the export script wrote an unreadable info.json: {e}")))?;
        let cache_err = |e: cache::Error| fail(format!("cannot store the import in the cache: {e}"));
        let deps_bytes = serde_json::to_vec(&info.deps).expect("paths serialize");
        let deps_blob = self.store.put(&deps_bytes, self.stat).map_err(cache_err)?;
        let (import, import_fields) = self.import_key(listing, &info.deps);
        let glb_blob = self.store.put(&glb, self.stat).map_err(cache_err)?;
        let info_blob = self.store.put(&info_bytes, self.stat).map_err(cache_err)?;
        // The import's record first: a listing record always names an import that was recorded.
        for (key, blobs, fields) in
            [(import, vec![glb_blob, info_blob], import_fields.as_slice()), (*listing, vec![deps_blob], listing_fields)]
        {
            let staged = self.store.stage_action(&key, &blobs, fields).map_err(cache_err)?;
            let dest = staged.dest().to_path_buf();
            staged.commit().map_err(|e| Error::Io { path: dest, source: e })?;
        }
        self.used.lock().unwrap().extend([*listing, deps_blob, import, glb_blob, info_blob]);
        Ok(Imported { glb, info, ran: true })
    }

    /// Blender's version (`blender --version`), remembered per content of the executable.
    fn version(&self, exe: &Path) -> Result<String, String> {
        let derive = || -> Result<String, String> {
            let out = Command::new(exe)
                .arg("--version")
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
                return Err(format!("{} --version did not print a Blender version: is it Blender?", exe.display()));
            }
            Ok(lines.join("; "))
        };
        self.stat.derived("blender --version", exe, derive).map_err(|e| format!("{}: {e}", exe.display()))?
    }
}

/// The selection the manifest makes, as the export script reads it.
#[derive(serde::Serialize)]
struct Selection {
    scene: Option<String>,
    object: Option<String>,
    collection: Option<String>,
}

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

/// The Blender to run: `VVGEN_BLENDER`, else `blender` on the PATH; the error names the ways out.
pub fn blender_exe() -> Result<PathBuf, String> {
    const WAYS_OUT: &str = "install Blender (Debian/Ubuntu: apt install blender python3-numpy; or blender.org) and \
                            put it on the PATH or in VVGEN_BLENDER; or, in Blender, File > Export > glTF 2.0 and \
                            use `gltf = \"….glb\"` instead";
    if let Some(p) = std::env::var_os("VVGEN_BLENDER").filter(|p| !p.is_empty()) {
        let p = PathBuf::from(p);
        return if p.is_file() {
            Ok(p)
        } else {
            Err(format!("VVGEN_BLENDER is {}, which is not a file: {WAYS_OUT}", p.display()))
        };
    }
    let found = std::env::var_os("PATH").and_then(|path| {
        std::env::split_paths(&path).map(|d| d.join("blender")).find(|p| p.is_file() && executable(p))
    });
    found.ok_or_else(|| format!("a .blend needs Blender to read it, and none is on the PATH: {WAYS_OUT}"))
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
