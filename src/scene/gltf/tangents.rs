//! Tangents for normal textures where a glTF has no `TANGENT`: MikkTSpace, as the glTF spec asks and as Blender
//! computes them, through `bevy_mikktspace`.

use glam::{Vec2, Vec3, Vec4};

/// An indexed triangle mesh as MikkTSpace reads it, with a tangent slot per vertex.
struct Mesh<'a> {
    positions: &'a [Vec3],
    normals: &'a [Vec3],
    uvs: &'a [Vec2],
    indices: &'a [u32],
    tangents: Vec<Vec4>,
}

impl Mesh<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.indices[face * 3 + vert] as usize
    }
}

impl bevy_mikktspace::Geometry for Mesh<'_> {
    fn num_faces(&self) -> usize {
        self.indices.len() / 3
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.positions[self.vertex(face, vert)].into()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.normals[self.vertex(face, vert)].into()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        // glTF's v grows down the image, MikkTSpace's up: with v flipped, the bitangent points toward the top of
        // the texture, where a normal texture's +Y (green) points.
        let uv = self.uvs[self.vertex(face, vert)];
        [uv.x, 1.0 - uv.y]
    }

    fn set_tangent(&mut self, t: Option<bevy_mikktspace::TangentSpace>, face: usize, vert: usize) {
        // Corners that share a vertex get the same tangent unless MikkTSpace splits them (a mirrored seam); the
        // last corner written wins, in index order, so the result is deterministic.
        let v = self.vertex(face, vert);
        if let Some(t) = t {
            self.tangents[v] = Vec4::from(t.tangent_encoded());
        }
    }
}

/// MikkTSpace tangents (xyz toward +u, w the handedness in glTF's sense) of an indexed triangle list. Vertices
/// MikkTSpace gives nothing (degenerate faces alone) get a zero tangent, which shading reads as "no normal map".
pub fn mikktspace(positions: &[Vec3], normals: &[Vec3], uvs: &[Vec2], indices: &[u32]) -> Vec<Vec4> {
    let mut mesh = Mesh { positions, normals, uvs, indices, tangents: vec![Vec4::ZERO; positions.len()] };
    if uvs.len() != positions.len() || normals.len() != positions.len() {
        return mesh.tangents;
    }
    // The crate's error type has no values: generation cannot fail.
    let _ = bevy_mikktspace::generate_tangents(&mut mesh);
    mesh.tangents
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quad_mapped_u_along_x_and_v_down_y_has_tangent_x_and_bitangent_y() {
        // u grows along +x; v grows along −y (glTF: v = 0 at the top of the image, which is +y here).
        let positions =
            [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let uvs = positions.map(|p| Vec2::new(p.x, 1.0 - p.y));
        let t = mikktspace(&positions, &[Vec3::Z; 4], &uvs, &[0, 1, 2, 0, 2, 3]);
        for t in t {
            assert!(t.truncate().distance(Vec3::X) < 1e-5, "{t}");
            // The bitangent w·(n × t) points to the texture's top: +y.
            let b = Vec3::Z.cross(t.truncate()) * t.w;
            assert!(b.distance(Vec3::Y) < 1e-5, "{b}");
        }
    }
}
