//! The action graph: every action a build runs, as plain data. Nodes live in one Vec addressed by [`ActionId`];
//! a node's inputs are earlier nodes, so ids are a topological order. Each node carries its key (from the
//! keyed walk in [`super::actions`]) and a label that names it across builds (`render train/3/12 depth`), which
//! is how `plan --explain` finds the last build's version of an action to compare with.
//!
//! What each writer needs is decided here, once; `execute` runs the nodes and `export` only looks their results
//! up, so no cacheable work happens outside the graph.

use std::collections::{BTreeMap, HashMap};

use super::actions::{pass_name, Action, PointSettings};
use super::key::{Explaining, Hashing};
use super::walk::Keying;
use super::{Error, Plan};
use crate::cache::Digest;
use crate::manifest::output::{Output, Writer};
use crate::manifest::render::Pass;
use crate::manifest::Manifest;
use crate::render::Shading;
use crate::scene::{Scene, SourceData};

/// Default number of points in an image dataset's initialization cloud.
pub const DEFAULT_INIT_POINTS: u64 = 100_000;

/// A node's index in [`Graph::nodes`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ActionId(pub u32);

/// One action of the graph.
#[derive(Debug, Clone)]
pub struct Node {
    /// What it does.
    pub action: Action,
    /// Its key: blake3 of its keyed walk.
    pub key: Digest,
    /// The actions whose results it reads, in the order its kind documents.
    pub deps: Vec<ActionId>,
    /// Its name across builds, e.g. `render train/3/12 depth`.
    pub label: String,
}

/// Every action of a build.
#[derive(Debug)]
pub struct Graph<'a> {
    /// The nodes, inputs before the actions that read them.
    pub nodes: Vec<Node>,
    /// What keys read besides the actions.
    pub keying: Keying<'a>,
    index: HashMap<Action, ActionId>,
    by_key: HashMap<Digest, ActionId>,
}

impl<'a> Graph<'a> {
    /// Plans every action of `m`'s outputs over `plan` (the images) and `scene`, keyed by `frame_keys`.
    ///
    /// `environment` is the content key of the `[environment] map`, when there is one.
    pub fn new(
        m: &Manifest,
        plan: &'a Plan,
        scene: &Scene,
        frame_keys: &'a super::keys::FrameKeys,
        environment: Option<Digest>,
    ) -> Result<Graph<'a>, Error> {
        let keying = Keying {
            plan,
            frame_keys: &frame_keys.content,
            frame_lights: &frame_keys.lights,
            frame_lit: &frame_keys.lit,
            frame_shadeless_points: &frame_keys.shadeless_points,
            frame_glossy_glass: &frame_keys.glossy_glass,
            frame_point_casters: &frame_keys.point_casters,
            frame_two_sided: &frame_keys.two_sided,
            render: {
                let mut r = crate::settings::renderer(&m.render, scene.voxel_size());
                if !scene.has_points() {
                    // Splat settings shape nothing without points: no minimum footprint to key.
                    r.splat.min_px = 0.0;
                }
                r.lighting = crate::settings::lighting(m, environment);
                r
            },
            encoding: crate::settings::encoding(&m.render),
            seed: m.dataset.seed,
            manifest: Digest::of(m.text.as_bytes()),
            dataset: m.dataset.name().to_string(),
            // Consecutive frames lie `step / fps` seconds apart: a video of every second frame at 30 fps runs at
            // 15, as long as the motion it shows.
            video_fps_milli: (m
                .sources
                .values()
                .find_map(|s| s.frames().map(|f| f.fps() / f.step() as f64))
                .unwrap_or(30.0)
                * 1000.0)
                .round() as u64,
            points: BTreeMap::new(),
        };
        let mut g = Graph { nodes: Vec::new(), keying, index: HashMap::new(), by_key: HashMap::new() };
        g.keying.points = refusals(m, scene, plan)?;
        for (name, out) in &m.outputs {
            let deps = g.plan_output(m, name, out)?;
            g.add(Action::WriteOutput { output: name.clone() }, format!("write {name}"), deps);
        }
        Ok(g)
    }

    /// Adds `action` reading `deps`, or finds the node already planned with the same action or the same key
    /// (two outputs asking for the same init cloud share one action).
    fn add(&mut self, action: Action, label: String, deps: Vec<ActionId>) -> ActionId {
        if let Some(&id) = self.index.get(&action) {
            return id;
        }
        let dep_keys: Vec<Digest> = deps.iter().map(|d| self.nodes[d.0 as usize].key).collect();
        let mut h = Hashing::new(action.kind().name());
        action.walk(&self.keying, &dep_keys, &mut h);
        let key = h.finish();
        let id = match self.by_key.get(&key) {
            Some(&id) => id,
            None => {
                let id = ActionId(self.nodes.len() as u32);
                self.nodes.push(Node { action: action.clone(), key, deps, label });
                self.by_key.insert(key, id);
                id
            }
        };
        self.index.insert(action, id);
        id
    }

    /// The node planned for `action`.
    pub fn id(&self, action: &Action) -> Option<ActionId> {
        self.index.get(action).copied()
    }

    /// Node `id`.
    pub fn node(&self, id: ActionId) -> &Node {
        &self.nodes[id.0 as usize]
    }

    /// The fields of node `id`'s key, as `(field, value)` pairs: the same walk that made the key.
    pub fn explain(&self, id: ActionId) -> Vec<(String, String)> {
        let n = self.node(id);
        let dep_keys: Vec<Digest> = n.deps.iter().map(|d| self.node(*d).key).collect();
        let mut e = Explaining::default();
        n.action.walk(&self.keying, &dep_keys, &mut e);
        e.0
    }

    /// Ids of every node, in order.
    pub fn ids(&self) -> impl DoubleEndedIterator<Item = ActionId> {
        (0..self.nodes.len() as u32).map(ActionId)
    }

    /// The actions one output needs, planned; returns them as the output's deps.
    fn plan_output(&mut self, m: &Manifest, name: &str, out: &Output) -> Result<Vec<ActionId>, Error> {
        let plan = self.keying.plan;
        let writer = out.writer();
        let mut deps = Vec::new();
        if writer == Writer::PlySequence {
            let s = self.keying.points[name].clone();
            let bounds = s.vox.map(|_| {
                let frames: Vec<usize> = (0..plan.frames).collect();
                self.add(Action::Bounds { frames }, format!("bounds {name}"), vec![])
            });
            // Lit colours read the frame's light action (the renders' own, which reads the prefiltered
            // environment), or for one source the environment itself: the first dep of whichever action samples.
            let env: Vec<ActionId> = if s.environment_dep() {
                vec![self.add(Action::Environment, "environment".into(), vec![])]
            } else {
                vec![]
            };
            let mut frame_ids = Vec::with_capacity(plan.frames);
            for f in 0..plan.frames {
                let light = if s.light_dep() {
                    vec![self.add(Action::Light { frame: f }, format!("light {f}"), env.clone())]
                } else {
                    env.clone()
                };
                let mut inputs = Vec::new();
                if s.reduces() {
                    let a = Action::SampleFrame { output: name.to_string(), frame: f };
                    inputs.push(self.add(a, format!("samples {name}/{f}"), light));
                } else {
                    inputs.extend(&light);
                }
                inputs.extend(bounds);
                let a = Action::PointFrame { output: name.to_string(), frame: f };
                frame_ids.push(self.add(a, format!("points {name}/{f}"), inputs));
            }
            deps.extend(&frame_ids);
            deps.extend(bounds);
            if m.dataset.preview {
                let shown = super::preview::point_frames(plan.frames).iter().map(|&f| frame_ids[f]).collect();
                let a = Action::PreviewStrip { output: name.to_string() };
                deps.push(self.add(a, format!("preview-strip {name}"), shown));
            }
            return Ok(deps);
        }
        // What cannot work was refused before any action was planned (`refusals`).
        let images = plan.images_of(out)?;
        let passes = m.render.passes().to_vec();
        for &i in &images {
            for &pass in &passes {
                deps.push(self.render_pass(i, pass));
            }
        }
        let frames = plan.frames_of(&images);
        let n = out.init_points().unwrap_or(DEFAULT_INIT_POINTS);
        match writer {
            Writer::Dnerf | Writer::Nerfstudio if n > 0 => {
                deps.push(self.add(Action::InitCloud { frames, points: n }, format!("init-cloud {name}"), vec![]));
            }
            Writer::Dnerf | Writer::Nerfstudio => {}
            Writer::InstantNgp => deps.push(self.add(Action::Bounds { frames }, format!("bounds {name}"), vec![])),
            Writer::StaticFrames => {
                for f in frames.into_iter().filter(|_| n > 0) {
                    let a = Action::InitCloud { frames: vec![f], points: n };
                    deps.push(self.add(a, format!("init-cloud {name}/{f}"), vec![]));
                }
            }
            Writer::Colmap | Writer::Dynerf => {
                let background = opaque_background(m);
                let mut composites = std::collections::BTreeMap::new();
                for &i in &images {
                    let rgba = self.render_pass(i, Pass::Rgba);
                    let label = format!("composite {}", image_label(plan, i));
                    let id = self.add(Action::Composite { image: i, background }, label, vec![rgba]);
                    composites.insert(i, id);
                    deps.push(id);
                }
                if writer == Writer::Dynerf {
                    // One video per camera (split, view), its frames in order; a moving camera's (a path split)
                    // is one video of all its images.
                    let mut cameras: std::collections::BTreeMap<(usize, u32), Vec<usize>> = Default::default();
                    for &i in &images {
                        let img = &plan.images[i];
                        let view = if plan.splits[img.split].moving { 0 } else { img.view };
                        cameras.entry((img.split, view)).or_default().push(i);
                    }
                    for ((split, view), mut list) in cameras {
                        list.sort_by_key(|&i| plan.images[i].frame);
                        let inputs = list.iter().map(|i| composites[i]).collect();
                        let label = format!("video {}/{view}", plan.splits[split].name);
                        deps.push(self.add(Action::Video { split, view }, label, inputs));
                    }
                }
                if writer == Writer::Colmap {
                    for &f in &frames {
                        let a = Action::ColmapPoints { frame: f, points: n };
                        deps.push(self.add(a, format!("colmap-points {name}/{f}"), vec![]));
                    }
                } else {
                    deps.push(self.add(Action::Bounds { frames: frames.clone() }, format!("bounds {name}"), vec![]));
                    if n > 0 {
                        let a = Action::InitCloud { frames, points: n };
                        deps.push(self.add(a, format!("init-cloud {name}"), vec![]));
                    }
                }
            }
            Writer::PlySequence => unreachable!("planned above"),
        }
        if m.dataset.preview {
            self.plan_preview(m, name, &images, &mut deps);
        }
        Ok(deps)
    }

    /// The preview of an image output over `images`: a contact sheet per split (when RGBA is rendered), the
    /// rig plot, and the bounds and subject samples the viewer reads; appended to `deps`.
    fn plan_preview(&mut self, m: &Manifest, name: &str, images: &[usize], deps: &mut Vec<ActionId>) {
        use super::preview;
        let plan = self.keying.plan;
        let splits = super::actions::splits_of(plan, images);
        let passes = m.render.passes();
        if passes.contains(&Pass::Rgba) {
            let extras = preview::extra_passes(passes);
            for &s in &splits {
                let mut inputs = Vec::new();
                for i in preview::layout(plan, s).images {
                    inputs.push(self.render_pass(i, Pass::Rgba));
                    for &p in &extras {
                        inputs.push(self.render_pass(i, p));
                    }
                }
                let a = Action::PreviewSheet { split: s, extras: extras.clone() };
                deps.push(self.add(a, format!("preview-sheet {}", plan.splits[s].name), inputs));
            }
        }
        let frames = super::actions::rig_frames(plan, &splits);
        let subject = vec![preview::subject_frame(&frames)];
        let bounds = self.add(Action::Bounds { frames }, format!("bounds {name}"), vec![]);
        let cloud = self.add(
            Action::InitCloud { frames: subject, points: preview::POINTS },
            format!("preview-cloud {name}"),
            vec![],
        );
        let rig = self.add(Action::PreviewRig { splits }, format!("preview-rig {name}"), vec![bounds, cloud]);
        deps.extend([bounds, cloud, rig]);
    }

    fn render_pass(&mut self, image: usize, pass: Pass) -> ActionId {
        let label = format!("render {} {}", image_label(self.keying.plan, image), pass_name(pass));
        // A lit RGBA pass reads its frame's light, which reads the prefiltered environment (the manifest's map, or
        // the built-in studio map).
        let r = &self.keying.render;
        let deps = if pass == Pass::Rgba && r.shading == Shading::Pbr {
            let env = vec![self.add(Action::Environment, "environment".into(), vec![])];
            let frame = self.keying.plan.images[image].frame;
            vec![self.add(Action::Light { frame }, format!("light {frame}"), env)]
        } else {
            vec![]
        };
        self.add(Action::RenderPass { image, pass }, label, deps)
    }
}

/// `split/view/frame` of a plan image.
pub fn image_label(plan: &Plan, i: usize) -> String {
    let img = &plan.images[i];
    format!("{}/{}/{}", plan.splits[img.split].name, img.view, img.frame)
}

/// What the outputs ask that cannot work, found from the manifest, the scene and the plan alone: an output with
/// no image, a split name K-Planes misreads, a writer without the `rgba` pass it needs, DyNeRF without
/// synchronized cameras, point settings that contradict the sources. [`Graph::new`] refuses them before it plans
/// an action, and `check` calls it too, so it knows what the build would refuse. Gives the point outputs'
/// resolved settings, by output.
pub fn refusals(m: &Manifest, scene: &Scene, plan: &Plan) -> Result<BTreeMap<String, PointSettings>, Error> {
    let mut points = BTreeMap::new();
    for (name, out) in &m.outputs {
        let writer = out.writer();
        if writer == Writer::PlySequence {
            points.insert(name.clone(), point_settings(m, scene, plan, name, out)?);
            continue;
        }
        let images = plan.images_of(out)?;
        if images.is_empty() {
            return Err(Error::NoImages { output: name.to_string() });
        }
        if writer == Writer::Dnerf {
            if let Some(s) = plan
                .splits
                .iter()
                .find(|s| s.name.contains("_r") && s.images.first().is_some_and(|i| images.contains(i)))
            {
                return Err(Error::SplitName { split: s.name.clone() });
            }
        }
        if matches!(writer, Writer::Colmap | Writer::Dynerf) && !m.render.passes().contains(&Pass::Rgba) {
            return Err(Error::NeedsPass { output: name.to_string(), pass: "rgba" });
        }
        if writer == Writer::Dynerf {
            check_dynerf(plan, &images)?;
        }
    }
    Ok(points)
}

/// The DyNeRF layout is synchronized video: every camera of every split at every frame, but for path splits,
/// which are written beside them as one video each. At least one split must be synchronized.
fn check_dynerf(plan: &Plan, images: &[usize]) -> Result<(), Error> {
    let mut seen = Vec::new();
    for &i in images {
        let s = plan.images[i].split;
        if !seen.contains(&s) {
            seen.push(s);
        }
    }
    let fixed: Vec<usize> = seen.iter().copied().filter(|&s| !plan.splits[s].moving).collect();
    let Some(&first) = fixed.first().or(seen.first()) else { return Ok(()) };
    if fixed.is_empty() {
        return Err(Error::NotSynchronized { split: plan.splits[first].name.clone() });
    }
    let frames = &plan.splits[first].frames;
    for s in fixed {
        let sp = &plan.splits[s];
        if sp.time != crate::manifest::split::TimeMode::All || &sp.frames != frames {
            return Err(Error::NotSynchronized { split: sp.name.clone() });
        }
    }
    Ok(())
}

/// The background that opaque exports bake in: the manifest's, else white (NeRF-synthetic's convention).
pub fn opaque_background(m: &Manifest) -> [u8; 3] {
    use crate::manifest::render::Background;
    match m.render.background() {
        Some(Background::Named(n)) if n == "black" => [0, 0, 0],
        Some(Background::Rgb(c)) => c.map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u8),
        _ => [255, 255, 255],
    }
}

/// Resolves a `ply-sequence` output's settings against the scene, refusing combinations that cannot work.
fn point_settings(m: &Manifest, scene: &Scene, plan: &Plan, name: &str, out: &Output) -> Result<PointSettings, Error> {
    let source = match out.source() {
        Some(n) => {
            let i = scene
                .source_index(n)
                .ok_or_else(|| Error::NoSource { output: name.into(), source_name: n.to_string() })?;
            Some((i, n.to_string()))
        }
        None => None,
    };
    // Correspondence needs one topology over time: meshes, not per-frame point clouds (of the sources sampled).
    let sampled: Vec<&crate::scene::LoadedSource> = match &source {
        Some((i, _)) => vec![&scene.sources[*i]],
        None => scene.sources.iter().collect(),
    };
    let fixed_topology =
        sampled.iter().all(|s| !matches!(s.data, SourceData::Sequence(_) | SourceData::MeshSequence(_)));
    let correspondence = out.correspondence.unwrap_or(fixed_topology && plan.frames > 1);
    let invalid = |why: &str| Error::PointSettings { output: name.into(), why: why.into() };
    if correspondence && !fixed_topology {
        return Err(invalid("`correspondence` needs mesh sources (a PLY sequence has no fixed surface)"));
    }
    if out.motion && (!correspondence || out.voxel().is_some() || out.vox().is_some()) {
        return Err(invalid("`motion` needs correspondence and no `voxel`/`vox` (merged points have no track)"));
    }
    Ok(PointSettings {
        points: out.points().unwrap_or(0),
        source,
        correspondence,
        motion: out.motion,
        voxel: out.voxel(),
        vox: out.vox(),
        reduce: out.reduce.unwrap_or_default(),
        position: out.position.unwrap_or_default(),
        color_average: out.color_average.unwrap_or_default(),
        color: out.color.unwrap_or_default(),
        format: out.format.unwrap_or_default(),
        pattern: out.file_pattern(m.dataset.name()),
    })
}
