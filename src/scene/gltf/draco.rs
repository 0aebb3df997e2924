//! Draco-compressed primitives (`KHR_draco_mesh_compression`, Blender's exporter's "Compression" and
//! glTF-Transform's `draco`). Each is decoded once, when the file loads, by draco-core (a pure-Rust port of Google's
//! decoder), into a buffer of its own; the primitive's attributes and indices are pointed at new accessors over it.
//! Everything after (skins, tangents, splats, keys) then reads plain accessors, as it does for any other file.
//!
//! What the extension says a loader does, and vvgen does: the decoded geometry replaces the accessors' data (their
//! `bufferView`, if any, is a fallback and is ignored); attributes the extension does not name are read as usual.
//! Draco may reorder and add vertices, so the decoded counts are the ones that hold; Blender's importer likewise
//! corrects an accessor whose count disagrees.

use std::collections::BTreeMap;

use draco_core::{DataType, DecoderBuffer, Mesh, MeshDecoder};
use gltf::json::accessor::{ComponentType, GenericComponentType, Type};
use gltf::json::validation::{Checked, USize64};
use gltf::json::{self, Index};

/// The extension's name.
pub(super) const EXTENSION: &str = "KHR_draco_mesh_compression";

/// The extension's object on a primitive.
#[derive(serde::Deserialize)]
struct Compressed {
    #[serde(rename = "bufferView")]
    buffer_view: usize,
    attributes: BTreeMap<String, u32>,
}

/// Decodes every Draco-compressed primitive of `doc`, whose buffers are `buffers` (one is appended, holding the
/// decoded data), and returns the document with those primitives pointed at it, and a warning per primitive whose
/// accessors' counts disagreed with what its data decodes to. A document without the extension is returned as it
/// is.
pub(super) fn decode(doc: gltf::Document, buffers: &mut Vec<Vec<u8>>) -> Result<(gltf::Document, Vec<String>), String> {
    let uses = doc.meshes().any(|m| m.primitives().any(|p| p.extensions().is_some_and(|e| e.contains_key(EXTENSION))));
    if !uses {
        return Ok((doc, Vec::new()));
    }
    let mut root = doc.into_json();
    let mut out = Out { bytes: Vec::new(), accessors: Vec::new() };
    let mut warnings = Vec::new();
    let first_accessor = root.accessors.len();
    for (m, mesh) in root.meshes.iter_mut().enumerate() {
        for (p, prim) in mesh.primitives.iter_mut().enumerate() {
            let Some(ext) = prim.extensions.as_ref().and_then(|e| e.others.get(EXTENSION)) else { continue };
            let at = format!("meshes[{m}].primitives[{p}]");
            let ext: Compressed = serde_json::from_value(ext.clone())
                .map_err(|e| format!("{at}.extensions.{EXTENSION}: {e} (it needs `bufferView` and `attributes`)"))?;
            let geometry = decode_view(&root.buffer_views, buffers, ext.buffer_view)
                .map_err(|e| format!("{at}: its Draco data (bufferView {}) {e}", ext.buffer_view))?;
            let changed = out.primitive(&at, prim, &ext, &geometry, &root.accessors, first_accessor)?;
            if changed {
                warnings.push(format!(
                    "{at}: its accessors' counts differ from what its Draco data decodes to; the decoded geometry is \
                     drawn (as Blender's importer does)"
                ));
            }
        }
    }
    let buffer = super::uri::push_buffer(&mut root, buffers, out.bytes, "decoded Draco geometry");
    for (mut accessor, (offset, length)) in out.accessors {
        accessor.buffer_view = Some(root.push(json::buffer::View {
            buffer,
            byte_length: USize64::from(length),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: None,
            extensions: None,
            extras: Default::default(),
        }));
        root.push(accessor);
    }
    Ok((gltf::Document::from_json_without_validation(root), warnings))
}

/// The decoded data: its bytes (the new buffer) and its accessors, each with its range of them (offset, length),
/// appended to the document's, each over a view of its own, after every primitive is done.
struct Out {
    bytes: Vec<u8>,
    accessors: Vec<(json::Accessor, (usize, usize))>,
}

impl Out {
    /// Points primitive `prim` (at `at`) at new accessors over `geometry`, its decoded data, for the attributes
    /// its extension `ext` names and for its indices. `accessors` are the document's own (the new ones are
    /// numbered from `first`). Returns whether some declared count differed from the decoded one.
    fn primitive(
        &mut self,
        at: &str,
        prim: &mut json::mesh::Primitive,
        ext: &Compressed,
        geometry: &Mesh,
        accessors: &[json::Accessor],
        first: usize,
    ) -> Result<bool, String> {
        use json::mesh::Mode;
        let points = geometry.num_points();
        let mut changed = false;
        let mode = match prim.mode {
            Checked::Valid(Mode::Triangles | Mode::TriangleStrip) => Mode::Triangles,
            Checked::Valid(Mode::Points) => Mode::Points,
            _ => {
                return Err(format!(
                    "{at}: a Draco-compressed primitive must be TRIANGLES or TRIANGLE_STRIP (or POINTS), the \
                     geometry Draco decodes"
                ))
            }
        };
        for (semantic, index) in prim.attributes.iter_mut() {
            let name = semantic.to_string();
            let Some(&id) = ext.attributes.get(&name) else { continue };
            let declared = accessors
                .get(index.value())
                .ok_or_else(|| format!("{at}.attributes.{name}: accessor {} does not exist", index.value()))?;
            let attribute = geometry.attribute_by_unique_id(id).ok_or_else(|| {
                format!("{at}: its Draco data has no attribute {id}, which the extension names for {name}")
            })?;
            let (Checked::Valid(ty), Checked::Valid(GenericComponentType(ct))) =
                (declared.type_, declared.component_type)
            else {
                return Err(format!("{at}.attributes.{name}: accessor {} has an unknown type", index.value()));
            };
            let values = attribute.read_f32s(points, ty.multiplicity());
            let scale = match attribute.data_type() {
                // A normalized integer attribute read as floats: its values over its type's largest.
                d if attribute.normalized() && ct == ComponentType::F32 => 1.0 / largest(d),
                _ => 1.0,
            };
            let quantize = declared.normalized && !attribute.data_type().is_integral();
            let bytes = encode(&values, scale, ct, quantize).map_err(|e| format!("{at}.attributes.{name}: {e}"))?;
            changed |= declared.count.0 != points as u64;
            let mut accessor = declared.clone();
            (accessor.count, accessor.byte_offset, accessor.sparse) = (USize64::from(points), None, None);
            // The declared bounds described the source, not the decoded values; vvgen never reads them.
            (accessor.min, accessor.max) = (None, None);
            *index = self.push(accessor, bytes, first);
        }
        let corners: Vec<u32> = geometry.faces().iter().flat_map(|f| f.map(|p| p.0)).collect();
        if mode == Mode::Triangles {
            if let Some(i) = prim.indices.and_then(|i| accessors.get(i.value())) {
                changed |= i.count.0 != corners.len() as u64;
            }
            let accessor = json::Accessor {
                buffer_view: None,
                byte_offset: None,
                count: USize64::from(corners.len()),
                component_type: Checked::Valid(GenericComponentType(ComponentType::U32)),
                extensions: None,
                extras: Default::default(),
                type_: Checked::Valid(Type::Scalar),
                min: None,
                max: None,
                name: None,
                normalized: false,
                sparse: None,
            };
            let bytes = corners.iter().flat_map(|c| c.to_le_bytes()).collect();
            prim.indices = Some(self.push(accessor, bytes, first));
        } else {
            prim.indices = None;
        }
        prim.mode = Checked::Valid(mode);
        Ok(changed)
    }

    /// Appends `bytes` as a new view (4-byte aligned, as every component type needs) and `accessor` over it;
    /// returns the accessor's index in the document (the new ones are numbered from `first`).
    fn push(&mut self, accessor: json::Accessor, bytes: Vec<u8>, first: usize) -> Index<json::Accessor> {
        self.bytes.resize(self.bytes.len().next_multiple_of(4), 0);
        self.accessors.push((accessor, (self.bytes.len(), bytes.len())));
        self.bytes.extend_from_slice(&bytes);
        Index::new((first + self.accessors.len() - 1) as u32)
    }
}

/// Decodes the Draco geometry in bufferView `view` (of `views`, over `buffers`).
fn decode_view(views: &[json::buffer::View], buffers: &[Vec<u8>], view: usize) -> Result<Mesh, String> {
    let v = views.get(view).ok_or("does not exist")?;
    let buffer = buffers.get(v.buffer.value()).ok_or("refers to a missing buffer")?;
    let offset = v.byte_offset.map_or(0, |o| o.0);
    let end =
        offset.checked_add(v.byte_length.0).filter(|&e| e <= buffer.len() as u64).ok_or("runs past its buffer")?;
    let mut stream =
        DecoderBuffer::new(&buffer[offset as usize..end as usize]).with_limits(crate::scene::drc::limits());
    let mut mesh = Mesh::new();
    MeshDecoder::new().decode(&mut stream, &mut mesh).map_err(|e| format!("does not decode: {e}"))?;
    Ok(mesh)
}

/// The largest value of integer type `d` (what a normalized value of 1 is stored as).
fn largest(d: DataType) -> f32 {
    match d {
        DataType::Int8 => 127.0,
        DataType::Uint8 => 255.0,
        DataType::Int16 => 32767.0,
        DataType::Uint16 => 65535.0,
        DataType::Int32 => 2147483647.0,
        DataType::Uint32 => 4294967295.0,
        _ => 1.0,
    }
}

/// `values` (each times `scale`) as little-endian components of type `ct`: floats as they are; integers from
/// whole values in the type's range (Draco keeps an integer attribute's type, so a normalized accessor's decoded
/// values are its stored integers already), or, when `quantize` (floats behind a normalized integer accessor),
/// from 0..1 (−1..1) as the spec's normalization reads them back.
fn encode(values: &[f32], scale: f32, ct: ComponentType, quantize: bool) -> Result<Vec<u8>, String> {
    let size = match ct {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    };
    let mut out = Vec::with_capacity(values.len() * size);
    for &v in values {
        let v = v * scale;
        if !v.is_finite() {
            return Err(format!("a decoded value is not finite ({v})"));
        }
        if ct == ComponentType::F32 {
            out.extend_from_slice(&v.to_le_bytes());
            continue;
        }
        let (lo, hi) = match ct {
            ComponentType::I8 => (-128.0, 127.0),
            ComponentType::U8 => (0.0, 255.0),
            ComponentType::I16 => (-32768.0, 32767.0),
            ComponentType::U16 => (0.0, 65535.0),
            _ => (0.0, 4294967295.0),
        };
        let stored = if quantize { (v.clamp(-1.0, 1.0) * hi).round() } else { v };
        if stored.fract() != 0.0 || stored < lo || stored > hi {
            return Err(format!("a decoded value ({v}) does not fit the accessor's {ct:?} components"));
        }
        let s = stored as i64;
        out.extend_from_slice(&s.to_le_bytes()[..size]);
    }
    Ok(out)
}
