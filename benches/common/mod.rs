//! What more than one benchmark builds: the peers' bumpy torus (bench_python.py `make_mesh_100k`), and how they
//! time a call.

use std::f32::consts::TAU;
use std::hint::black_box;
use std::time::{Duration, Instant};

use glam::{Vec2, Vec3, Vec4};

/// The torus's 500 × 100 vertex grid and 100 000 triangles, with grid uvs and colours by position.
#[allow(dead_code)] // each bench reads the fields it needs
pub struct Torus {
    pub positions: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub colors: Vec<Vec4>,
    pub indices: Vec<u32>,
}

/// The peers' bumpy torus: radius 0.8 around Z, tube radius 0.3 with a 7 × 5 bump pattern.
#[allow(dead_code)] // not every bench draws it
pub fn torus_100k() -> Torus {
    let (nu, nv) = (500usize, 100usize);
    let mut positions = Vec::with_capacity(nu * nv);
    let mut uvs = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            let (u, w) = (TAU * i as f32 / nu as f32, TAU * j as f32 / nv as f32);
            let r = 0.3 * (1.0 + 0.15 * (7.0 * u).sin() * (5.0 * w).cos());
            positions.push(Vec3::new((0.8 + r * w.cos()) * u.cos(), (0.8 + r * w.cos()) * u.sin(), r * w.sin()));
            uvs.push(Vec2::new(i as f32 / nu as f32, j as f32 / nv as f32));
        }
    }
    let (lo, hi) = positions.iter().fold((Vec3::MAX, Vec3::MIN), |(l, h), p| (l.min(*p), h.max(*p)));
    let colors = positions.iter().map(|p| ((*p - lo) / (hi - lo)).extend(1.0)).collect();
    let id = |i: usize, j: usize| ((i % nu) * nv + j % nv) as u32;
    let mut indices = Vec::with_capacity(6 * nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    Torus { positions, uvs, colors, indices }
}

/// Median wall time of `runs` calls of `f`, whose results the optimizer may not drop.
#[allow(dead_code)] // not every bench times with it
pub fn median<T>(runs: usize, mut f: impl FnMut() -> T) -> Duration {
    let mut v: Vec<Duration> = (0..runs)
        .map(|_| {
            let t = Instant::now();
            black_box(f());
            t.elapsed()
        })
        .collect();
    v.sort();
    v[runs / 2]
}
