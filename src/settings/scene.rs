//! The manifest's sources and `[transform]` tables as the scene's [`Request`]: file names joined to the
//! manifest's folder, sequences listed, the global table's `up` and `over` handed down to each source as the
//! default they are, and the reach a frame fit sizes to, read off the splits' rigs.

use crate::manifest::source::{AnimationSel, ClipRef, Source, SourceKind};
use crate::manifest::transform::{self as mt, Transform};
use crate::manifest::{framing, sequence, Manifest};
use crate::scene::blend::Importer;
use crate::scene::input::{
    BlendSelect, Center, Clip, Clips, Fit, FrameFile, FrameRange, Ground, Over, Placement, Reach, SourceFile,
    SourceRequest, UpAxis,
};
use crate::scene::{Error, Request, Scene};

// The scene bounds a clip played whole as the manifest bounds `frames`.
const _: () = assert!(crate::scene::input::MAX_FRAMES == crate::manifest::frames::MAX_FRAMES);

/// Opens `m`'s scene; `importer` imports `.blend` sources ([`Scene::open_importing`]).
pub fn open(m: &Manifest, importer: Option<&Importer>) -> Result<Scene, Error> {
    Scene::open_importing(&request(m)?, importer)
}

/// What `m` asks the scene to load. Errors when a sequence's frames cannot be listed.
pub fn request(m: &Manifest) -> Result<Request, Error> {
    let sources = m.sources.iter().map(|(name, s)| source(m, name, s)).collect::<Result<_, _>>()?;
    Ok(Request {
        sources,
        global: placement(&m.transform, &Transform::default()),
        reach: framing::reach(m).map(|r| Reach { radius: r.radius, rig: r.rig }),
        file_lights: m.render.gltf_lights && m.lit(),
    })
}

fn source(m: &Manifest, name: &str, s: &Source) -> Result<SourceRequest, Error> {
    let frames = s.frames().map_or_else(FrameRange::default, |f| FrameRange {
        start: f.start,
        end: f.end,
        count: f.count,
        step: f.step,
        fps: f.fps,
    });
    let file = if let Some(p) = s.plane() {
        SourceFile::Ground(Ground { size: p.size, color: p.color, z: p.z })
    } else {
        let (kind, rel) =
            s.kind().ok_or_else(|| Error::Source { name: name.to_string(), message: "names no file".into() })?;
        let path = m.dir.join(rel);
        match kind {
            SourceKind::Gltf => SourceFile::Gltf { path, scene: s.scene_index() },
            SourceKind::Fbx => SourceFile::Fbx(path),
            SourceKind::Blend => SourceFile::Blend {
                path,
                select: BlendSelect {
                    scene: s.scene_name().map(str::to_string),
                    object: s.object.clone(),
                    collection: s.collection.clone(),
                },
            },
            SourceKind::Mesh => SourceFile::Mesh { path, scene: s.scene_index() },
            SourceKind::PlySequence | SourceKind::MeshSequence => {
                let listed = sequence::resolve(&m.dir, rel, &s.frames().cloned().unwrap_or_default())
                    .map_err(|e| Error::Sequence { name: name.to_string(), message: e.to_string() })?;
                let files = listed.into_iter().map(|f| FrameFile { number: f.number, path: f.path }).collect();
                if kind == SourceKind::PlySequence {
                    SourceFile::PlySequence(files)
                } else {
                    SourceFile::MeshSequence(files)
                }
            }
        }
    };
    Ok(SourceRequest {
        name: name.to_string(),
        file,
        clips: clips(s.animation()),
        frames,
        placement: placement(&s.transform.clone().unwrap_or_default(), &m.transform),
        origin: s.origin().unwrap_or_default(),
        opaque: s.opaque(),
    })
}

/// `animation = …` as the clips that play: `"all"` is every clip; a name or an index, one.
fn clips(sel: Option<&AnimationSel>) -> Clips {
    let one = |r: &ClipRef| match r {
        ClipRef::Index(i) => Clip::Index(*i as usize),
        ClipRef::Name(n) => Clip::Name(n.clone()),
    };
    match sel {
        None => Clips::First,
        Some(AnimationSel::Name(n)) if n == "all" => Clips::All,
        Some(AnimationSel::Name(n)) => Clips::These(vec![Clip::Name(n.clone())]),
        Some(AnimationSel::Index(i)) => Clips::These(vec![Clip::Index(*i as usize)]),
        Some(AnimationSel::Many(v)) => Clips::These(v.iter().map(one).collect()),
    }
}

/// A `[transform]` table as a placement; `outer`'s `up` and `over` are the defaults the table leaves to it (the
/// global table's, for a source's).
fn placement(t: &Transform, outer: &Transform) -> Placement {
    let fit = t.fit().map(|f| match f.frame_margin() {
        Some(margin) => Fit::Frame { margin },
        None => match (f.height, f.radius) {
            (Some(h), _) => Fit::Height(h),
            (None, Some(r)) => Fit::Radius(r),
            (None, None) => Fit::Extent(f.extent.unwrap_or(1.0)),
        },
    });
    Placement {
        up: t.up.or(outer.up).map(|u| match u {
            mt::UpAxis::Y => UpAxis::Y,
            mt::UpAxis::Z => UpAxis::Z,
            mt::UpAxis::NegY => UpAxis::NegY,
            mt::UpAxis::NegZ => UpAxis::NegZ,
            mt::UpAxis::X => UpAxis::X,
            mt::UpAxis::NegX => UpAxis::NegX,
        }),
        matrix: t.matrix(),
        center: t.center.map(|c| match c {
            mt::Center::Bbox => Center::Bbox,
            mt::Center::Centroid => Center::Centroid,
            mt::Center::None => Center::None,
        }),
        fit,
        scale: match t.scale {
            Some(mt::Scale::Uniform(k)) => [k; 3],
            Some(mt::Scale::Axes(a)) => a,
            None => [1.0; 3],
        },
        rotate_deg: t.rotate_deg.unwrap_or([0.0; 3]),
        translate: t.translate.unwrap_or([0.0; 3]),
        over: match t.over.or(outer.over).unwrap_or_default() {
            mt::Over::AllFrames => Over::AllFrames,
            mt::Over::First => Over::First,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_source_takes_the_global_tables_up_and_over_as_defaults() {
        let outer: Transform = toml::from_str("up = \"z\"\nover = \"first\"").unwrap();
        let own: Transform = toml::from_str("up = \"y\"").unwrap();
        let p = placement(&own, &outer);
        assert_eq!((p.up, p.over), (Some(UpAxis::Y), Over::First));
        let p = placement(&Transform::default(), &Transform::default());
        assert_eq!((p.up, p.over, p.fit), (None, Over::AllFrames, None));
        let frame: Transform = toml::from_str("fit = \"frame\"").unwrap();
        assert_eq!(placement(&frame, &outer).fit, Some(Fit::Frame { margin: mt::FRAME_MARGIN }));
    }
}
