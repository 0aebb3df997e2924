//! Structure-aware glTF fuzzing (issue 50): each execution parses a seed's JSON, changes its structure (an
//! accessor's type, component type, count, normalization or offsets; a bufferView's stride, length or offset;
//! sparse data with and without a bufferView; attributes pointed at other accessors; removed or duplicated
//! properties; cameras, skins, animations, animation pointers), writes it back, and loads, poses and renders it as `check`,
//! `inspect` and `build` do.
//!
//! Executions run in child processes (this test binary again, as `worker`) under an address-space limit set
//! with `setrlimit`, so an allocation the limit refuses (an abort) is a finding like a panic: the worker writes
//! each input before running it, and the parent keeps the input a dead worker was running, then restarts it at
//! the next execution. Mutants are a pure function of (seed key, execution index), so any finding replays.
//!
//! `VVGEN_FUZZ_EXECS` sets the executions (the suite runs 4 000), `VVGEN_FUZZ_JOBS` the workers (default 1). The
//! long run (docs/fuzzing.md): `VVGEN_FUZZ_EXECS=1000000 VVGEN_FUZZ_JOBS=2 cargo test --release --test it
//! fuzz_gltf_structure -- --nocapture`.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::{json, Value};

use crate::fuzz::Rng;

/// The address space a worker may use: beyond it an allocation fails and the worker aborts (a finding).
const ADDRESS_SPACE: u64 = 4 << 30;

/// The fuzzers' splitmix stream, keyed by (key, execution): every mutant replays from its index alone.
fn keyed(key: u64, exec: u64) -> Rng {
    let mut r = Rng(key.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ exec);
    r.next();
    r
}

/// Numbers a file may declare where a count, offset, stride or index goes.
fn number(rng: &mut Rng) -> Value {
    let n: &[Value] = &[
        json!(0),
        json!(1),
        json!(2),
        json!(3),
        json!(4),
        json!(7),
        json!(255),
        json!(256),
        json!(65535),
        json!(1u64 << 24),
        json!((1u64 << 28) - 1),
        json!(1u64 << 28),
        json!(1u64 << 31),
        json!(1u64 << 32),
        json!(1u64 << 53),
        json!(u64::MAX),
        json!(-1),
        json!(1.5),
    ];
    rng.pick(n).clone()
}

const TYPES: &[&str] = &["SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"];
const COMPONENTS: &[u64] = &[5120, 5121, 5122, 5123, 5125, 5126];
const ATTRIBUTES: &[&str] =
    &["POSITION", "NORMAL", "TANGENT", "TEXCOORD_0", "TEXCOORD_1", "COLOR_0", "JOINTS_0", "WEIGHTS_0"];

/// An index into `doc[array]`, sometimes one past its end.
fn index_into(rng: &mut Rng, doc: &Value, array: &str) -> Value {
    let len = doc.get(array).and_then(Value::as_array).map_or(0, Vec::len);
    json!(rng.below(len + 1))
}

/// The entries of `doc[array]`, mutable.
fn entries<'a>(doc: &'a mut Value, array: &str) -> Option<&'a mut Vec<Value>> {
    doc.get_mut(array).and_then(Value::as_array_mut).filter(|v| !v.is_empty())
}

/// Every object in `v` (JSON pointers), for the generic mutations.
fn objects(v: &Value, at: String, out: &mut Vec<String>) {
    match v {
        Value::Object(m) => {
            out.push(at.clone());
            for (k, x) in m {
                objects(x, format!("{at}/{}", k.replace('~', "~0").replace('/', "~1")), out);
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                objects(x, format!("{at}/{i}"), out);
            }
        }
        _ => {}
    }
}

/// One structural change to `doc`.
fn mutate(rng: &mut Rng, doc: &mut Value) {
    let snapshot = doc.clone();
    match rng.below(9) {
        0 | 1 => {
            let Some(list) = entries(doc, "accessors") else { return };
            let i = rng.below(list.len());
            let a = &mut list[i];
            match rng.below(8) {
                0 => a["type"] = json!(rng.pick(TYPES)),
                1 => a["componentType"] = json!(rng.pick(COMPONENTS)),
                2 => a["count"] = number(rng),
                3 => a["normalized"] = json!(!a["normalized"].as_bool().unwrap_or(false)),
                4 => a["byteOffset"] = number(rng),
                5 => {
                    a.as_object_mut().map(|o| o.remove("bufferView"));
                }
                6 => a["bufferView"] = index_into(rng, &snapshot, "bufferViews"),
                _ => {
                    let mut sparse = json!({
                        "count": number(rng),
                        "indices": {"bufferView": index_into(rng, &snapshot, "bufferViews"),
                                    "componentType": *rng.pick(&[5121u64, 5123, 5125]), "byteOffset": number(rng)},
                        "values": {"bufferView": index_into(rng, &snapshot, "bufferViews")}
                    });
                    if rng.below(2) == 0 {
                        a.as_object_mut().map(|o| o.remove("bufferView"));
                    }
                    if rng.below(3) == 0 {
                        sparse["values"].as_object_mut().map(|o| o.remove("bufferView"));
                    }
                    a["sparse"] = sparse;
                }
            }
        }
        2 => {
            let Some(list) = entries(doc, "bufferViews") else { return };
            let i = rng.below(list.len());
            let key = *rng.pick(&["byteStride", "byteLength", "byteOffset", "buffer"]);
            list[i][key] = number(rng);
        }
        3 | 4 => {
            let Some(meshes) = entries(doc, "meshes") else { return };
            let m = rng.below(meshes.len());
            let Some(prims) = meshes[m].get_mut("primitives").and_then(Value::as_array_mut).filter(|p| !p.is_empty())
            else {
                return;
            };
            let p = rng.below(prims.len());
            let prim = &mut prims[p];
            let accessor = index_into(rng, &snapshot, "accessors");
            match rng.below(5) {
                0 | 1 => prim["attributes"][*rng.pick(ATTRIBUTES)] = accessor,
                2 => prim["indices"] = accessor,
                3 => prim["mode"] = json!(rng.below(8)),
                _ => prim["targets"] = json!([{*rng.pick(&["POSITION", "NORMAL", "TANGENT"]): accessor}]),
            }
        }
        5 => {
            let cams = doc.get("cameras").and_then(Value::as_array).map_or(0, Vec::len);
            if cams == 0 || rng.below(3) == 0 {
                let camera = match rng.below(3) {
                    0 => json!({"type": "perspective"}),
                    1 => json!({"type": "orthographic", "perspective": {"yfov": 1.0, "znear": 0.1}}),
                    _ => json!({"type": "perspective", "perspective": {"yfov": number(rng), "znear": number(rng)}}),
                };
                doc["cameras"] = json!([camera]);
                if let Some(n) = entries(doc, "nodes") {
                    let i = rng.below(n.len());
                    n[i]["camera"] = json!(0);
                }
            } else if let Some(c) = entries(doc, "cameras") {
                let i = rng.below(c.len());
                let t = if c[i]["type"] == "perspective" { "orthographic" } else { "perspective" };
                c[i]["type"] = json!(t);
            }
        }
        6 => {
            let joints = index_into(rng, &snapshot, "nodes");
            let ibm = index_into(rng, &snapshot, "accessors");
            match entries(doc, "skins") {
                Some(s) => {
                    let i = rng.below(s.len());
                    if rng.below(2) == 0 {
                        s[i]["joints"] = json!([joints, joints]);
                    } else {
                        s[i]["inverseBindMatrices"] = ibm;
                    }
                }
                None => {
                    doc["skins"] = json!([{"joints": [joints], "inverseBindMatrices": ibm}]);
                    if let Some(n) = entries(doc, "nodes") {
                        let i = rng.below(n.len());
                        n[i]["skin"] = json!(0);
                    }
                }
            }
        }
        7 => {
            let accessor = index_into(rng, &snapshot, "accessors");
            let Some(anims) = entries(doc, "animations") else { return };
            let a = rng.below(anims.len());
            // Half the time: a channel retargeted through `KHR_animation_pointer`, at a node's property, a mesh's
            // weights, a material, or nothing a pointer can name (indices from `number`).
            if rng.below(2) == 0 {
                if let Some(c) = anims[a].get_mut("channels").and_then(Value::as_array_mut).filter(|c| !c.is_empty()) {
                    let i = rng.below(c.len());
                    let k = number(rng);
                    let pointer = match rng.below(5) {
                        0 => format!("/nodes/{k}/{}", rng.pick(&["translation", "rotation", "scale", "weights"])),
                        1 => format!("/meshes/{k}/weights"),
                        2 => format!("/materials/{k}/pbrMetallicRoughness/baseColorFactor"),
                        3 => format!("/nodes/{k}"),
                        _ => String::new(),
                    };
                    c[i]["target"] =
                        json!({"path": "pointer", "extensions": {"KHR_animation_pointer": {"pointer": pointer}}});
                }
                return;
            }
            if let Some(s) = anims[a].get_mut("samplers").and_then(Value::as_array_mut).filter(|s| !s.is_empty()) {
                let i = rng.below(s.len());
                match rng.below(3) {
                    0 => s[i]["input"] = accessor,
                    1 => s[i]["output"] = accessor,
                    _ => s[i]["interpolation"] = json!(rng.pick(&["LINEAR", "STEP", "CUBICSPLINE"])),
                }
            }
        }
        _ => {
            // Generic: remove a property, duplicate an array entry, or set a property to an extreme number.
            let mut at = Vec::new();
            objects(doc, String::new(), &mut at);
            let Some(ptr) = at.get(rng.below(at.len())).cloned() else { return };
            let op = rng.below(3);
            let n = number(rng);
            let Some(obj) = doc.pointer_mut(&ptr).and_then(Value::as_object_mut) else { return };
            let keys: Vec<String> = obj.keys().cloned().collect();
            let Some(key) = keys.get(rng.below(keys.len())).cloned() else { return };
            match op {
                0 => {
                    obj.remove(&key);
                }
                1 => {
                    if let Some(a) = obj.get_mut(&key).and_then(Value::as_array_mut) {
                        if let Some(first) = a.first().cloned() {
                            a.push(first);
                        }
                    }
                }
                _ => {
                    if obj[&key].is_number() {
                        obj[&key] = n;
                    }
                }
            }
        }
    }
}

/// A seed: its path (side-car files resolve beside it), its JSON, and a GLB's binary chunk.
struct Seed {
    path: PathBuf,
    json: Value,
    bin: Option<Vec<u8>>,
}

fn seeds() -> Vec<Seed> {
    let mut out = Vec::new();
    let mut stack = vec![crate::common::data("gltf"), crate::common::data("wide")];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            let ext = p.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
            let bytes = std::fs::read(&p).unwrap();
            if bytes.len() > 2 << 20 {
                continue;
            }
            match ext.as_str() {
                "gltf" => {
                    if let Ok(json) = serde_json::from_slice(&bytes) {
                        out.push(Seed { path: p, json, bin: None });
                    }
                }
                "glb" => {
                    let glb = gltf::Glb::from_slice(&bytes).unwrap();
                    let json = serde_json::from_slice(&glb.json).unwrap();
                    out.push(Seed { path: p, json, bin: glb.bin.map(|b| b.into_owned()) });
                }
                _ => {}
            }
        }
    }
    out.sort_by(|a, b| a.path.cmp(&b.path));
    out
}

/// Execution `exec`'s input: a seed with one to three structural changes, as file bytes.
fn input(seeds: &[Seed], key: u64, exec: u64) -> (PathBuf, Vec<u8>) {
    let mut rng = keyed(key, exec);
    let seed = &seeds[rng.below(seeds.len())];
    let mut doc = seed.json.clone();
    for _ in 0..1 + rng.below(3) {
        mutate(&mut rng, &mut doc);
    }
    let json = serde_json::to_vec(&doc).unwrap();
    let bytes = match &seed.bin {
        None => json,
        Some(bin) => {
            let glb = gltf::Glb {
                header: gltf::binary::Header { magic: *b"glTF", version: 2, length: 0 },
                json: json.into(),
                bin: Some(bin.as_slice().into()),
            };
            glb.to_vec().unwrap()
        }
    };
    (seed.path.clone(), bytes)
}

/// What `check`, `inspect` and `build` do with a glTF source: load, pose (at rest and into the clips), render.
fn target(path: &Path, bytes: &[u8]) {
    let Ok(asset) = vvgen::scene::gltf::load_slice(bytes, path, None) else { return };
    let clips: Vec<usize> = (0..asset.animations.len()).collect();
    let mut posed = vvgen::scene::PosedScene {
        materials: std::sync::Arc::new(asset.materials.clone()),
        textures: std::sync::Arc::clone(&asset.textures),
        ..Default::default()
    };
    let mut scratch = vvgen::scene::gltf::PoseScratch::default();
    for t in [0.0, 0.7] {
        asset.pose(&clips, t, glam::Mat4::IDENTITY, &mut scratch, &mut posed);
    }
    crate::fuzz::render_small(&posed);
}

fn crash_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("target/fuzz-crashes")
}

/// The worker: runs executions `start..end` of `key` when `VVGEN_FUZZ_WORKER` says so (otherwise nothing: in the
/// suite's own run it passes at once). Writes each input to `current` first; reports panics as files.
#[test]
fn worker() {
    let Ok(spec) = std::env::var("VVGEN_FUZZ_WORKER") else { return };
    let f: Vec<&str> = spec.split(':').collect();
    let (key, start, end, current) = (f[0].parse().unwrap(), f[1].parse().unwrap(), f[2].parse().unwrap(), f[3]);
    let seeds = seeds();
    std::panic::set_hook(Box::new(|_| {}));
    for exec in start..end {
        let (path, bytes) = input(&seeds, key, exec);
        std::fs::write(current, format!("{exec}\n")).unwrap();
        if catch_unwind(AssertUnwindSafe(|| target(&path, &bytes))).is_err() {
            let dir = crash_dir();
            std::fs::create_dir_all(&dir).unwrap();
            std::fs::write(dir.join(format!("structure-{key}-{exec}.gltf-or-glb")), &bytes).unwrap();
            println!("vvgen-fuzz panic {exec} {}", path.display());
        }
    }
    println!("vvgen-fuzz done {end}");
}

/// Runs executions `start..end` in workers under the address-space limit; returns the findings.
fn run_range(key: u64, start: u64, end: u64, job: usize) -> Vec<String> {
    let exe = std::env::current_exe().unwrap();
    let current = std::env::temp_dir().join(format!("vvgen-fuzz-{}-{job}", std::process::id()));
    let mut findings = Vec::new();
    let mut at = start;
    while at < end {
        let mut cmd = Command::new(&exe);
        cmd.args(["--exact", "fuzz_structure::worker", "--nocapture", "--test-threads", "1"])
            .env("VVGEN_FUZZ_WORKER", format!("{key}:{at}:{end}:{}", current.display()))
            .env("RAYON_NUM_THREADS", "1");
        // SAFETY: setrlimit is async-signal-safe; the closure touches nothing else.
        unsafe {
            std::os::unix::process::CommandExt::pre_exec(&mut cmd, || {
                let lim =
                    libc::rlimit { rlim_cur: ADDRESS_SPACE as libc::rlim_t, rlim_max: ADDRESS_SPACE as libc::rlim_t };
                if libc::setrlimit(libc::RLIMIT_AS, &lim) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        let out = cmd.output().unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        // (libtest may print its own `test … ` before a line: match anywhere in it.)
        findings.extend(stdout.lines().filter_map(|l| l.find("vvgen-fuzz panic").map(|i| l[i..].to_string())));
        if stdout.contains("vvgen-fuzz done") {
            break;
        }
        // The worker died (an allocation over the limit aborts it): keep the input it was running, go on.
        let exec: u64 = std::fs::read_to_string(&current).ok().and_then(|s| s.trim().parse().ok()).unwrap_or(at);
        let (path, bytes) = input(&seeds(), key, exec);
        let dir = crash_dir();
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join(format!("structure-{key}-{exec}-abort.gltf-or-glb"));
        std::fs::write(&file, &bytes).unwrap();
        let why = String::from_utf8_lossy(&out.stderr).lines().rev().take(3).collect::<Vec<_>>().join(" | ");
        findings.push(format!("vvgen-fuzz abort {exec} {} ({}): {why}", path.display(), out.status));
        at = exec + 1;
    }
    let _ = std::fs::remove_file(&current);
    findings
}

#[test]
fn fuzz_gltf_structure() {
    let n: u64 = std::env::var("VVGEN_FUZZ_EXECS").ok().and_then(|v| v.parse().ok()).unwrap_or(4000);
    let jobs: u64 = std::env::var("VVGEN_FUZZ_JOBS").ok().and_then(|v| v.parse().ok()).unwrap_or(1).max(1);
    assert!(!seeds().is_empty());
    let t0 = std::time::Instant::now();
    let findings: Vec<String> = std::thread::scope(|s| {
        let handles: Vec<_> =
            (0..jobs).map(|j| s.spawn(move || run_range(50, n * j / jobs, n * (j + 1) / jobs, j as usize))).collect();
        handles.into_iter().flat_map(|h| h.join().unwrap()).collect()
    });
    assert!(findings.is_empty(), "{} findings in {n} executions:\n{}", findings.len(), findings.join("\n"));
    eprintln!("fuzz gltf structure: {n} executions in {:.0} s, no panic, no abort", t0.elapsed().as_secs_f64());
}
