//! Alpha BLEND as real transparency: surfaces composited over what is behind them in depth order (not in scene
//! order), a transparent surface alone giving partial alpha, and opaque surfaces in front hiding it.

use glam::{Vec3, Vec4};
use vvgen::render::{render, Camera, RenderSettings, Shading};
use vvgen::scene::material::{AlphaMode, Material};
use vvgen::scene::{PosedScene, PrimKind};

/// A square of half-size `r` at height `z`, facing +Z, in a material of linear colour `c`.
fn square(r: f32, z: f32, c: Vec4, blend: bool) -> PosedScene {
    let p = vec![Vec3::new(-r, -r, z), Vec3::new(r, -r, z), Vec3::new(r, r, z), Vec3::new(-r, r, z)];
    let m = Material {
        base_color: c,
        alpha_mode: if blend { AlphaMode::Blend } else { AlphaMode::Opaque },
        ..Material::default()
    };
    PosedScene::single(PrimKind::Triangles, p, vec![Vec3::Z; 4], Vec::new(), vec![0, 1, 2, 0, 2, 3], m)
}

/// `parts` as one scene, in this order (objects 0, 1, …).
fn scene(parts: &[PosedScene]) -> PosedScene {
    let mut out = PosedScene::default();
    vvgen::scene::merge(parts, &mut out);
    out
}

fn pixel(parts: &[PosedScene], x: u32, y: u32) -> [u8; 4] {
    let c = Camera {
        width: 32,
        height: 32,
        fx: 40.0,
        fy: 40.0,
        cx: 16.0,
        cy: 16.0,
        near: 0.1,
        far: 100.0,
        c2w: Camera::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y),
    };
    let f = render(&scene(parts), &c, &RenderSettings { samples: 4, shading: Shading::Unlit, ..Default::default() });
    let i = ((y * 32 + x) * 4) as usize;
    [f.rgba[i], f.rgba[i + 1], f.rgba[i + 2], f.rgba[i + 3]]
}

#[test]
fn blend_surfaces_composite_in_depth_order_whatever_their_scene_order() {
    let red = square(1.0, 0.0, Vec4::new(1.0, 0.0, 0.0, 1.0), false);
    let blue = square(0.6, 0.5, Vec4::new(0.0, 0.0, 1.0, 0.5), true);
    let green = square(0.6, 0.25, Vec4::new(0.0, 1.0, 0.0, 0.5), true);
    // Centre: blue over green over red, in linear light: (0.25, 0.25, 0.5).
    let want = [0.25f32, 0.25, 0.5].map(vvgen::scene::material::linear_to_srgb8);
    for order in [[&red, &green, &blue], [&blue, &green, &red], [&green, &blue, &red]] {
        let parts: Vec<PosedScene> = order.iter().map(|p| (*p).clone()).collect();
        let px = pixel(&parts, 16, 16);
        assert_eq!(px, [want[0], want[1], want[2], 255], "order {:?}", order.map(|p| p.materials[0].base_color));
    }
}

#[test]
fn a_blend_surface_alone_is_partly_transparent_and_hidden_behind_an_opaque_one() {
    let glass = square(0.6, 0.0, Vec4::new(0.0, 0.0, 1.0, 0.5), true);
    // Over the transparent background: its colour at half alpha.
    assert_eq!(pixel(std::slice::from_ref(&glass), 16, 16), [0, 0, 255, 128]);
    // An opaque square in front hides it; one behind shows through it.
    let front = square(1.0, 0.5, Vec4::new(1.0, 1.0, 1.0, 1.0), false);
    assert_eq!(pixel(&[glass.clone(), front], 16, 16), [255, 255, 255, 255]);
    let back = square(1.0, -0.5, Vec4::new(1.0, 1.0, 1.0, 1.0), false);
    let half = vvgen::scene::material::linear_to_srgb8(0.5);
    assert_eq!(pixel(&[glass, back], 16, 16), [half, half, 255, 255]);
}
