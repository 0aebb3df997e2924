//! `deploy/slurm-array.sbatch` on a real one-node Slurm cluster (issue 19): an array of three shards over the
//! shipped CesiumMan manifest, one task cancelled mid-render and resubmitted alone, a final build chained with
//! `afterany`. The final build runs nothing but the outputs, and every dataset file equals a one-process build's.
//! Needs root and Debian's slurm-wlm and munge (`.ci/run` installs them); skips with the reason otherwise.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use crate::common::{data, tree};

/// The cluster `tests/slurm/cluster.sh` started; stopped (only what it started) when dropped, even on panic.
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new("bash").arg(script()).arg("stop").arg(&self.dir).status();
    }
}

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/slurm/cluster.sh")
}

/// Why this machine cannot run the test, if it cannot.
fn missing() -> Option<String> {
    let uid = Command::new("id").arg("-u").output().ok()?;
    if String::from_utf8_lossy(&uid.stdout).trim() != "0" {
        return Some("needs root to start munged, slurmctld and slurmd".into());
    }
    for tool in ["munged", "slurmctld", "slurmd", "sbatch"] {
        let found = Command::new("sh").args(["-c", &format!("command -v {tool}")]).output().ok()?.status.success();
        if !found {
            return Some(format!("{tool} is not installed (.ci/run installs slurm-wlm and munge with apt)"));
        }
    }
    None
}

/// Runs a Slurm client command against the test cluster, in `dir`, with the job's environment.
fn slurm(c: &Cluster, dir: &Path, args: &[&str], env: &[(&str, &str)]) -> String {
    let out = Command::new(args[0])
        .args(&args[1..])
        .current_dir(dir)
        .env("SLURM_CONF", &c.conf)
        .envs(env.iter().copied())
        .output()
        .unwrap();
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

/// Waits until `done` holds, failing the test past `deadline`.
fn wait_for(what: &str, deadline: Instant, mut done: impl FnMut() -> bool) {
    while !done() {
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// A copy of the shipped manifest with the asset it reads, laid out as in the repository.
fn workspace(dir: &Path) {
    std::fs::create_dir_all(dir.join("manifests")).unwrap();
    std::fs::create_dir_all(dir.join("tests/data/gltf/CesiumMan")).unwrap();
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("manifests/cesium-man.toml");
    std::fs::copy(manifest, dir.join("manifests/cesium-man.toml")).unwrap();
    std::fs::copy(data("gltf/CesiumMan/CesiumMan.glb"), dir.join("tests/data/gltf/CesiumMan/CesiumMan.glb")).unwrap();
}

#[test]
fn a_slurm_array_with_a_resubmitted_task_matches_one_process() {
    if let Some(why) = missing() {
        eprintln!("skipped: {why}");
        return;
    }
    let deadline = Instant::now() + Duration::from_secs(200);
    let root = tempfile::tempdir().unwrap();
    let state = root.path().join("slurm");
    std::fs::create_dir_all(&state).unwrap();
    let started = Command::new("bash").arg(script()).arg("start").arg(&state).output().unwrap();
    let cluster = Cluster { dir: state.clone(), conf: state.join("slurm.conf") };
    assert!(started.status.success(), "{}", String::from_utf8_lossy(&started.stderr));

    let bin = env!("CARGO_BIN_EXE_vvgen");
    // The reference: one process.
    let one = root.path().join("one");
    workspace(&one);
    let out = Command::new(bin).current_dir(&one).args(["-q", "build", "manifests/cesium-man.toml"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));

    let w = root.path().join("array");
    workspace(&w);
    let cache = w.join("cache").display().to_string();
    let sbatch = Path::new(env!("CARGO_MANIFEST_DIR")).join("deploy/slurm-array.sbatch").display().to_string();
    let env = [("VVGEN_SHARDS", "3"), ("VVGEN_BIN", bin), ("VVGEN_CACHE", cache.as_str())];
    let submit = |array: &str| {
        let args = ["sbatch", "--parsable", "-c", "1", array, &sbatch, "manifests/cesium-man.toml"];
        slurm(&cluster, &w, &args, &env)
    };
    let log =
        |job: &str, task: u32| std::fs::read_to_string(w.join(format!("vvgen-{job}_{task}.log"))).unwrap_or_default();
    let running = |job: &str| !slurm(&cluster, &w, &["squeue", "-h", "-j", job], &[]).is_empty();

    // Three shards on a two-CPU node; task 1 is cancelled once it reports progress, mid-render.
    let array = submit("--array=0-2");
    wait_for("task 1 to make progress", deadline, || log(&array, 1).lines().any(|l| l.starts_with("ran ")));
    slurm(&cluster, &w, &["scancel", &format!("{array}_1")], &[]);
    wait_for("the array to end", deadline, || !running(&array));
    assert!(log(&array, 1).contains("CANCELLED"), "{}", log(&array, 1));
    // An index outside 0..N-1 is refused, not run as another partition.
    let stray = submit("--array=3");
    wait_for("the stray task", deadline, || !running(&stray));
    assert!(log(&stray, 3).contains("array index 3 is not below VVGEN_SHARDS=3"), "{}", log(&stray, 3));
    // Redo task 1 alone; the final build waits for everything with afterany (afterok would never run).
    let again = submit("--array=1");
    let dependency = format!("--dependency=afterany:{array},afterany:{again}");
    let wrap = format!("{bin} build manifests/cesium-man.toml");
    let args = ["sbatch", "--parsable", "-c", "2", "-o", "final.log", &dependency, "--wrap", &wrap];
    let last = slurm(&cluster, &w, &args, &[("VVGEN_CACHE", cache.as_str())]);
    wait_for("the final build", deadline, || !running(&again) && !running(&last));
    assert!(log(&again, 1).contains("shard 1/3"), "{}", log(&again, 1));
    let final_log = std::fs::read_to_string(w.join("final.log")).unwrap();
    assert!(final_log.contains("432 images: 432 cached, 0 rendered"), "{final_log}");
    // The final build renders nothing: it draws the previews (which gather every shard's work) and writes.
    let ran = final_log.lines().find_map(|l| l.strip_prefix("ran: ")).unwrap_or_default();
    let kinds: Vec<&str> = ran.split(", ").map(|k| k.split(' ').next().unwrap_or_default()).collect();
    assert!(kinds.iter().all(|k| k.starts_with("preview-") || *k == "write-output"), "{final_log}");
    assert!(kinds.contains(&"write-output"), "{final_log}");

    let (a, b) = (tree(&one.join("out")), tree(&w.join("out")));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (k, v) in &a {
        assert!(v == &b[k], "{k} differs from the one-process build");
    }
    drop(cluster);
    assert!(!state.join("started").exists(), "the daemons the test started are stopped");
}

/// The Kubernetes job tells the same story as the Slurm script: an Indexed Job of VVGEN_SHARDS pods, each running
/// its shard into VVGEN_CACHE on a mounted volume, then a final unsharded build of the same manifest.
#[test]
fn the_kubernetes_jobs_agree_with_the_slurm_script() {
    use yaml_rust2::{Yaml, YamlLoader};
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("deploy/k8s-indexed-job.yaml");
    let docs = YamlLoader::load_from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let [shards, last] = &docs[..] else { panic!("two jobs: the shards and the final build") };
    let container = |job: &Yaml| job["spec"]["template"]["spec"]["containers"][0].clone();
    let env = |job: &Yaml, name: &str| -> Option<String> {
        let c = container(job);
        c["env"].as_vec()?.iter().find(|e| e["name"].as_str() == Some(name))?["value"].as_str().map(String::from)
    };
    let args = |job: &Yaml| container(job)["args"][0].as_str().unwrap().to_string();
    let mounts = |job: &Yaml| -> Vec<String> {
        let c = container(job);
        c["volumeMounts"].as_vec().unwrap().iter().map(|m| m["mountPath"].as_str().unwrap().to_string()).collect()
    };
    assert_eq!(shards["spec"]["completionMode"].as_str(), Some("Indexed"));
    let n = shards["spec"]["completions"].as_i64().unwrap();
    assert_eq!(env(shards, "VVGEN_SHARDS").unwrap().parse::<i64>().unwrap(), n, "VVGEN_SHARDS = completions");
    assert!(shards["spec"]["parallelism"].as_i64().unwrap() <= n);
    assert!(args(shards).contains(r#"--shard "$JOB_COMPLETION_INDEX/$VVGEN_SHARDS""#), "{}", args(shards));
    assert!(!args(last).contains("--shard"), "the final build is unsharded");
    assert_eq!(last["spec"]["suspend"].as_bool(), Some(true), "the final job waits to be resumed");
    for job in [shards, last] {
        assert!(args(job).starts_with(r#"exec "$VVGEN_BIN" build "#), "{}", args(job));
        assert!(env(job, "VVGEN_BIN").is_some());
        let cache = env(job, "VVGEN_CACHE").unwrap();
        assert!(mounts(job).iter().any(|m| cache.starts_with(m.as_str())), "VVGEN_CACHE on a mounted volume");
        let manifest = args(job).split_whitespace().nth(3).unwrap().to_string();
        assert!(mounts(job).iter().any(|m| manifest.starts_with(m.as_str())), "{manifest} on a mounted volume");
    }
    assert_eq!(args(shards).split_whitespace().nth(3), args(last).split_whitespace().nth(3), "one manifest");
}
