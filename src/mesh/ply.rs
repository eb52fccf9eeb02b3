//! PLY models (ASCII, binary little- and big-endian: every BOP dataset's) through ply-rs-bw,
//! from bytes read safely (io/input_file.rs).
//!
//! A PLY header says how many elements follow, and a parser that trusted it would reserve
//! that much before reading a byte of them. Here the header is parsed alone, every count it
//! claims is checked against what the rest of the file can hold (each element takes at least
//! a byte a value, in text or binary), and what the payload can turn into is charged to the
//! run's budget, all before the payload is parsed. ply-rs-bw reads each element into a type
//! of ours ([`Vertex`], [`Face`], [`Skipped`]), not into a map per element.
//!
//! The model: element `vertex` with scalar properties `x`, `y`, `z`; element `face` with a
//! list property `vertex_indices` (or `vertex_index`), each polygon cut into a fan of
//! triangles. A face property `surface`, `segment` or `label` (an integer) gives the
//! surfaces, numbered in order of first appearance and named `surface <value>`; without one,
//! the mesh is one surface, split into its planar faces as an OBJ without groups is. Any
//! other element (edges, materials) is read past.

use super::surfaces::default_surfaces;
use super::Mesh;
use crate::error::{guard_parser, Error, Result};
use crate::io::read_input_file;
use crate::limits::Ledger;
use crate::untrusted::{parser_error, quoted};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    ElementDef, Encoding, Header, Property, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType,
};
use std::collections::HashMap;
use std::io::Cursor;
use std::path::Path;

/// Bytes parsing takes, at most, per byte of header text (its element and property
/// definitions, its comments), per vertex, per face, per index a face lists (the face's
/// list, as read and as kept) and per triangle (its corners, its surface, the mesh), measured
/// with a counting allocator (tests/memory.rs).
const BYTES_PER_HEADER_BYTE: u64 = 16;
const BYTES_PER_VERTEX: u64 = 64;
const BYTES_PER_FACE: u64 = 64;
const BYTES_PER_INDEX: u64 = 32;
const BYTES_PER_TRIANGLE: u64 = 96;

/// The face properties, in order of preference, whose integer value names a face's surface.
const SURFACE_PROPERTIES: [&str; 3] = ["surface", "segment", "label"];
/// The face property listing a face's vertices, under either of its usual names.
const INDEX_PROPERTIES: [&str; 2] = ["vertex_indices", "vertex_index"];

pub fn load_ply(path: &Path, ledger: &Ledger) -> Result<Mesh> {
    let bytes = read_input_file(path, "model", ledger)?;
    parse_ply(&bytes, &path.display().to_string(), ledger)
}

/// Parses a PLY model held in memory; `name` names it in messages and in the mesh.
pub fn parse_ply(bytes: &[u8], name: &str, ledger: &Ledger) -> Result<Mesh> {
    let invalid = |reason: String| Error::Mesh { name: name.to_string(), reason };
    let header_end = header_length(bytes).ok_or_else(|| invalid("no PLY header: no line `end_header`".into()))?;
    ledger.charge(format_args!("parsing the PLY header of {name}"), header_end as u64 * BYTES_PER_HEADER_BYTE)?;
    let mut reader = Reader::new(Cursor::new(bytes));
    let header = guard_parser(name, "ply-rs-bw's PLY parser", || {
        Parser::<Skipped>::new()
            .read_header(&mut reader)
            .map_err(|e| invalid(format!("not a readable PLY header ({})", parser_error(e))))
    })?;
    let payload = bytes.len() as u64 - reader.get_ref().position();
    let layout = Layout::of(&header).map_err(invalid)?;
    let least = layout.least_bytes(&header, payload).map_err(invalid)?;
    // Beyond the least every element takes, each index a face lists takes its own bytes; a
    // face of n indices (at least 3, checked before any triangle is made) makes n − 2
    // triangles.
    let faces = layout.faces.count as u64;
    let indices = (payload - least) / layout.smallest_index(header.encoding);
    ledger.charge(
        format_args!("parsing {name} ({} vertices, {faces} faces)", layout.vertices.count),
        layout.vertices.count as u64 * BYTES_PER_VERTEX
            + faces * BYTES_PER_FACE
            + indices * BYTES_PER_INDEX
            + indices.saturating_sub(2 * faces) * BYTES_PER_TRIANGLE,
    )?;
    let (vertices, faces) = guard_parser(name, "ply-rs-bw's PLY parser", || {
        let (mut vertices, mut faces) = (Vec::new(), Vec::new());
        for element in header.elements.values() {
            let read = |e: ply_rs_bw::parser::ParseError| {
                invalid(format!("element {} unreadable ({})", quoted(&element.name), parser_error(e)))
            };
            if element.name == layout.vertices.name {
                vertices =
                    Parser::<Vertex>::new().read_payload_for_element(&mut reader, element, &header).map_err(read)?;
            } else if element.name == layout.faces.name {
                faces = Parser::<Face>::new().read_payload_for_element(&mut reader, element, &header).map_err(read)?;
            } else {
                Parser::<Skipped>::new().read_payload_for_element(&mut reader, element, &header).map_err(read)?;
            }
        }
        Ok((vertices, faces))
    })?;
    build(name, vertices, faces, layout.surface.is_some())
}

/// The length of the header, through the first line that starts with `end_header` (a
/// comment that mentions it does not end the header, so it cannot make the header's charge
/// short); `None` without one.
fn header_length(bytes: &[u8]) -> Option<usize> {
    let marker = b"\nend_header";
    let at = bytes.windows(marker.len()).position(|w| w == marker)?;
    let rest = &bytes[at + marker.len()..];
    let line_end = rest.iter().position(|&b| b == b'\n').map_or(rest.len(), |n| n + 1);
    Some(at + marker.len() + line_end)
}

/// The elements and properties of the header that make the model.
struct Layout<'h> {
    vertices: &'h ElementDef,
    faces: &'h ElementDef,
    /// The face list's index type.
    index: ScalarType,
    /// The face property naming surfaces, where there is one.
    surface: Option<&'static str>,
}

impl<'h> Layout<'h> {
    fn of(header: &'h Header) -> std::result::Result<Self, String> {
        let element = |name: &str| {
            header
                .elements
                .get(name)
                .ok_or_else(|| format!("it has no element {} (a PLY model needs one)", quoted(name)))
        };
        let (vertices, faces) = (element("vertex")?, element("face")?);
        for axis in ["x", "y", "z"] {
            match vertices.properties.get(axis).map(|p| &p.data_type) {
                Some(PropertyType::Scalar(_)) => {}
                Some(PropertyType::List(..)) => return Err(format!("vertex property {axis} is a list, not a number")),
                None => return Err(format!("its vertices have no property {axis}")),
            }
        }
        let index = INDEX_PROPERTIES
            .iter()
            .find_map(|name| faces.properties.get(*name))
            .ok_or_else(|| "its faces have no list property vertex_indices (or vertex_index)".to_string())?;
        let PropertyType::List(_, index) = &index.data_type else {
            return Err(format!("face property {} is a number, not a list of vertices", index.name));
        };
        if matches!(index, ScalarType::Float | ScalarType::Double) {
            return Err(format!("face property vertex_indices lists {index:?} values, not integers"));
        }
        let surface = SURFACE_PROPERTIES.into_iter().find(|name| {
            faces.properties.get(*name).is_some_and(|p| {
                matches!(&p.data_type, PropertyType::Scalar(t) if !matches!(t, ScalarType::Float | ScalarType::Double))
            })
        });
        Ok(Self { vertices, faces, index: index.clone(), surface })
    }

    /// The fewest bytes the header's elements take in a payload, refusing counts the payload
    /// cannot hold: every element takes at least its scalars' sizes and its lists' counts in
    /// binary, and two bytes a value (a digit and a separator) in text.
    fn least_bytes(&self, header: &Header, payload: u64) -> std::result::Result<u64, String> {
        let mut least: u64 = 0;
        for element in header.elements.values() {
            let each: u64 = element
                .properties
                .values()
                .map(|p| match (header.encoding, &p.data_type) {
                    (Encoding::Ascii, _) => 2,
                    (_, PropertyType::Scalar(t) | PropertyType::List(t, _)) => scalar_bytes(t),
                })
                .sum();
            least = least.saturating_add((element.count as u64).saturating_mul(each.max(1)));
            if least > payload {
                return Err(format!(
                    "its header claims {} elements {}, which need at least {least} bytes with those before them, \
                     but the file has {payload} after its header",
                    element.count,
                    quoted(&element.name)
                ));
            }
        }
        Ok(least)
    }

    /// The fewest bytes an index of a face's list takes in the file.
    fn smallest_index(&self, encoding: Encoding) -> u64 {
        match encoding {
            Encoding::Ascii => 2,
            _ => scalar_bytes(&self.index),
        }
    }
}

fn scalar_bytes(t: &ScalarType) -> u64 {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// The mesh of the elements read: each face a fan of triangles from its first vertex.
fn build(name: &str, vertices: Vec<Vertex>, faces: Vec<Face>, has_surfaces: bool) -> Result<Mesh> {
    let invalid = |reason: String| Error::Mesh { name: name.to_string(), reason };
    let positions: Vec<[f64; 3]> = vertices.iter().map(|v| v.position).collect();
    drop(vertices);
    for (f, face) in faces.iter().enumerate() {
        if face.negative_index {
            return Err(invalid(format!("face {f} lists a negative vertex index")));
        }
        if face.indices.len() < 3 {
            return Err(invalid(format!("face {f} lists {} vertices; a face needs at least 3", face.indices.len())));
        }
    }
    let mut triangles = Vec::new();
    let mut triangle_surfaces = Vec::new();
    // Each surface value's id, and the values in order of first appearance.
    let mut surface_ids: HashMap<i64, u32> = HashMap::new();
    let mut surface_values: Vec<i64> = Vec::new();
    for face in &faces {
        let surface = match has_surfaces {
            false => 1,
            true => *surface_ids.entry(face.surface).or_insert_with(|| {
                surface_values.push(face.surface);
                surface_values.len() as u32
            }),
        };
        for k in 1..face.indices.len() - 1 {
            triangles.push([face.indices[0], face.indices[k], face.indices[k + 1]]);
            triangle_surfaces.push(surface);
        }
    }
    drop(faces);
    let surface_names = match has_surfaces {
        true => surface_values.iter().map(|v| format!("surface {v}")).collect(),
        false => vec!["surface1".to_string()],
    };
    let mesh = Mesh::new(name, positions, triangles, triangle_surfaces, surface_names)?;
    Ok(if has_surfaces { mesh } else { default_surfaces(mesh) })
}

/// A PLY vertex: its position; any other property is read past.
struct Vertex {
    position: [f64; 3],
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Self { position: [0.0; 3] }
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let axis = match name {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => return PropertyAccessResult::Ignored,
        };
        if let Some(value) = scalar(&property) {
            self.position[axis] = value;
        }
        PropertyAccessResult::Set
    }
}

/// A PLY face: the vertices it lists, and its surface value (0 where the faces have none).
struct Face {
    indices: Vec<u32>,
    negative_index: bool,
    surface: i64,
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Self { indices: Vec::new(), negative_index: false, surface: 0 }
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if INDEX_PROPERTIES.contains(&name) {
            let list: Vec<i64> = match property {
                Property::ListChar(l) => l.into_iter().map(i64::from).collect(),
                Property::ListUChar(l) => l.into_iter().map(i64::from).collect(),
                Property::ListShort(l) => l.into_iter().map(i64::from).collect(),
                Property::ListUShort(l) => l.into_iter().map(i64::from).collect(),
                Property::ListInt(l) => l.into_iter().map(i64::from).collect(),
                Property::ListUInt(l) => l.into_iter().map(i64::from).collect(),
                _ => return PropertyAccessResult::Ignored,
            };
            self.negative_index |= list.iter().any(|&i| i < 0);
            self.indices = list.into_iter().map(|i| i.clamp(0, i64::from(u32::MAX)) as u32).collect();
        } else if SURFACE_PROPERTIES.contains(&name) {
            self.surface = scalar_integer(&property).unwrap_or(self.surface);
        } else {
            return PropertyAccessResult::Ignored;
        }
        PropertyAccessResult::Set
    }
}

/// An element read only to move past it.
struct Skipped;

impl PropertyAccess for Skipped {
    fn new() -> Self {
        Self
    }
}

fn scalar(property: &Property) -> Option<f64> {
    Some(match *property {
        Property::Float(v) => v.into(),
        Property::Double(v) => v,
        _ => scalar_integer(property)? as f64,
    })
}

fn scalar_integer(property: &Property) -> Option<i64> {
    Some(match *property {
        Property::Char(v) => v.into(),
        Property::UChar(v) => v.into(),
        Property::Short(v) => v.into(),
        Property::UShort(v) => v.into(),
        Property::Int(v) => v.into(),
        Property::UInt(v) => v.into(),
        _ => return None,
    })
}
