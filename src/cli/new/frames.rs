//! The frames `vvgen new` writes: a folder's glob as its files spell their extension, and a clip's or take's
//! frame count at 30 fps, within what a manifest takes.

use std::path::PathBuf;

/// The glob that matches a folder's frames of extension `e` (lower case) among `files`, as their names spell it:
/// globs are case-sensitive, so a camera's `FRAME_0001.PLY` needs `*.PLY`, and a folder of both spellings a
/// class per letter (`*.[pP][lL][yY]`).
pub(super) fn frames_glob(files: &[PathBuf], e: &str) -> String {
    let spelt: std::collections::BTreeSet<String> = files
        .iter()
        .filter_map(|p| p.extension().map(|x| x.to_string_lossy().into_owned()))
        .filter(|x| x.eq_ignore_ascii_case(e))
        .collect();
    match spelt.len() {
        1 => format!("*.{}", spelt.first().expect("one")),
        _ => {
            let class = |c: char| format!("[{}{}]", c.to_ascii_lowercase(), c.to_ascii_uppercase());
            format!("*.{}", e.chars().map(class).collect::<String>())
        }
    }
}

/// The comment line listing clip (or take) `i`, named `name`, of `seconds`: the `frames` that cover it at 30 fps,
/// within the most a manifest takes ([`crate::manifest::frames::MAX_FRAMES`]), so that the line copied as it is
/// checks clean (ufbx's corpus has takes of 92 hours: ten million frames).
pub(super) fn clip_line(i: usize, name: &str, seconds: f32) -> String {
    let (n, most) = (frames_covering(seconds), crate::manifest::frames::MAX_FRAMES as usize);
    match n <= most {
        true => format!("#   {i}: `{name}`, {seconds:.3} s: frames = {{ count = {n}, fps = 30 }}"),
        false => format!(
            "#   {i}: `{name}`, {seconds:.3} s: frames = {{ count = {most}, fps = 30 }}   # its first {most} of {n} \
             frames at 30 fps (the most a manifest takes)"
        ),
    }
}

/// Frames at 30 fps from 0 that cover a clip of `seconds`, its last pose included.
pub(super) fn frames_covering(seconds: f32) -> usize {
    (seconds as f64 * 30.0 + 1e-4).floor() as usize + 1
}

/// The most frames `vvgen new` asks of a clip: 10 minutes at 30 fps. Longer clips are most often a timeline left
/// at its end by the exporter (ufbx's corpus has takes of 92 hours); a whole one is a `count` away.
pub(super) const LONGEST: usize = 18_000;

/// The `frames` line for a first clip (glTF) or take (FBX) of `n` frames at 30 fps: all of it, or its first
/// [`LONGEST`] frames, saying so.
pub(super) fn first_clip_frames(n: usize, clip: &str) -> String {
    if n <= LONGEST {
        format!("frames = {{ count = {n}, fps = 30 }}   # the first {clip}'s length at 30 fps")
    } else {
        format!(
            "frames = {{ count = {LONGEST}, fps = 30 }}   # the first {} minutes of the first {clip}, which has {n} \
             frames at 30 fps; raise `count` for more (at most {})",
            LONGEST / 30 / 60,
            crate::manifest::frames::MAX_FRAMES
        )
    }
}
