//! Formats vvgen does not read but a newcomer brings, and for each the tool that turns it into one vvgen reads.

/// What to do with a file in a format vvgen does not read but a newcomer brings (by its extension): the tool
/// that turns it into one vvgen reads. `None` for any other name.
pub fn way_out_of(path: &std::path::Path) -> Option<String> {
    let name = path.file_name()?.to_string_lossy().into_owned();
    let ext = path.extension()?.to_string_lossy().to_ascii_lowercase();
    let stem = name.strip_suffix(&format!(".{ext}")).unwrap_or(&name).trim_end_matches(".compressed");
    Some(match ext.as_str() {
        // Gaussian splatting's packed and web forms: PlayCanvas's converter reads them all.
        "splat" | "ksplat" | "spz" | "sog" => format!(
            "{name}: Gaussian splats in the .{ext} form, which vvgen does not read: `npx @playcanvas/splat-transform \
             \"{name}\" \"{stem}.ply\"` writes them in 3D Gaussian splatting's PLY layout, which vvgen reads"
        ),
        "abc" | "usd" | "usda" | "usdc" | "usdz" | "dae" | "3ds" | "x3d" | "wrl" => {
            // Blender 4.2 moved its 3DS and X3D/VRML importers out to extensions (4.5 LTS has neither built in).
            let how = match ext.as_str() {
                "3ds" => {
                    "File → Import, once the \"Autodesk 3DS format\" extension is added from Edit → Preferences → \
                          Get Extensions"
                }
                "x3d" | "wrl" => {
                    "File → Import, once the \"Web3D X3D/VRML2 format\" extension is added from Edit → \
                                  Preferences → Get Extensions"
                }
                _ => "File → Import; a blender.org build reads Alembic and USD",
            };
            format!(
                "{name}: vvgen does not read .{ext} files: import it in Blender ({how}), save it as a .blend and name \
                 that (`vvgen new \"{stem}.blend\"`): Blender then evaluates every frame for vvgen"
            )
        }
        // Geometry processing's format (libigl's and ModelNet's meshes); Blender has no importer for it either.
        "off" => format!(
            "{name}: vvgen does not read .off files (nor does Blender): `pip install trimesh`, then `python -c \
             \"import trimesh; trimesh.load('{name}').export('{stem}.ply')\"` writes it as a PLY mesh, which vvgen \
             reads"
        ),
        // The Point Cloud Library's format (ASCII, binary or compressed): Open3D reads each and writes the PLY.
        "pcd" => format!(
            "{name}: vvgen does not read .pcd files: `pip install open3d`, then `python -c \"import open3d as o3d; \
             o3d.io.write_point_cloud('{stem}.ply', o3d.io.read_point_cloud('{name}'))\"` writes it as a PLY point \
             cloud (normals and colours kept), which vvgen reads"
        ),
        // LiDAR (ASPRS LAS, LASzip-compressed LAZ): laspy reads both; Open3D writes the PLY in double precision,
        // which keeps a georeferenced survey's detail (`vvgen new` then reads it relative to an `origin`).
        "las" | "laz" => format!(
            "{name}: vvgen does not read .{ext} (LiDAR) files: `pip install \"laspy[lazrs]\" open3d`, then `python -c \
             \"import laspy, numpy as np, open3d as o3d; l = laspy.read('{name}'); p = \
             o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.c_[l.x, l.y, l.z])); c = np.c_[l.red, l.green, \
             l.blue] if 'red' in l.point_format.dimension_names else None; p.colors = o3d.utility.Vector3dVector(c \
             / (65535 if c.max() > 255 else 255)) if c is not None else p.colors; \
             o3d.io.write_point_cloud('{stem}.ply', p)\"` writes it as a PLY point cloud in double precision \
             (colours kept), which vvgen reads; a LAS file's heights are its z: `up = \"z\"`"
        ),
        _ => return None,
    })
}
