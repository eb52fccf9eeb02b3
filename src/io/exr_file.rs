//! OpenEXR files (docs/design.md "Interfaces"): `range.exr` has one layer with channels X, Y, Z
//! (f32, NaN where there is no data), `label` (u32, exact for every value) and `reason` (u32,
//! why a pixel has no data: src/effects.rs `Reason`); the sensor, shadow and effects settings
//! go into the layer header as TOML text attributes, so `verify` can take them from the
//! sensed image. Compression is ZIP, which is lossless, so files read back
//! bit-identical.
//!
//! Reading trusts nothing in the file. The exr crate allocates an image as large as the
//! header's data window claims before it reads a pixel, and a failed allocation aborts the
//! process, so a 630-byte file claiming 2^29 columns would take a daemon down. The file is
//! therefore read whole (a regular file within the budget, io/input_file.rs), its headers
//! are parsed alone, and every size they claim is checked — each side against
//! [`MAX_IMAGE_SIDE`], the decoded bytes against the memory budget and against what the
//! file's own size can hold at its compression's best ratio — before the pixels are decoded.

use super::{parse_toml, read_input_file, write_atomically, RangeImage};
use crate::effects::{Effects, Reason};
use crate::error::{guard_parser, Error, Result};
use crate::limits::{Bytes, Ledger};
use crate::sensor::{Sensor, MAX_IMAGE_SIDE};
use crate::shadow::ShadowSettings;
use exr::prelude::*;
use std::io::{Cursor, Write};
use std::path::Path;

const SENSOR_ATTRIBUTE: &str = "rangesynth_sensor";
const SHADOW_ATTRIBUTE: &str = "rangesynth_shadow";
const EFFECTS_ATTRIBUTE: &str = "rangesynth_effects";

pub fn write_range_image(path: &Path, image: &RangeImage) -> Result<()> {
    let mut channels: smallvec::SmallVec<[AnyChannel<FlatSamples>; 4]> = smallvec::smallvec![
        AnyChannel::new("X", FlatSamples::F32(image.x.clone())),
        AnyChannel::new("Y", FlatSamples::F32(image.y.clone())),
        AnyChannel::new("Z", FlatSamples::F32(image.z.clone())),
        AnyChannel::new("label", FlatSamples::U32(image.label.clone())),
    ];
    if let Some(reason) = &image.reason {
        channels.push(AnyChannel::new("reason", FlatSamples::U32(reason.clone())));
    }
    if let Some(witness) = &image.witness {
        channels.push(AnyChannel::new("witness", FlatSamples::U32(witness.clone())));
    }
    let mut attributes = LayerAttributes::named("range");
    let mut put = |name: &str, value: Option<String>| -> Result<()> {
        if let Some(text) = value {
            let text = Text::new_or_none(&text).ok_or_else(|| Error::file(path, "settings are not plain ASCII"))?;
            attributes.other.insert(Text::from(name), AttributeValue::Text(text));
        }
        Ok(())
    };
    put(SENSOR_ATTRIBUTE, image.sensor.as_ref().map(toml::to_string).transpose().map_err(|e| Error::file(path, e))?)?;
    put(SHADOW_ATTRIBUTE, image.shadow.map(|s| toml::to_string(&s)).transpose().map_err(|e| Error::file(path, e))?)?;
    put(EFFECTS_ATTRIBUTE, image.effects.map(|s| toml::to_string(&s)).transpose().map_err(|e| Error::file(path, e))?)?;
    write_layer(path, image.width, image.height, attributes, channels)
}

pub fn write_label_image(path: &Path, width: u32, height: u32, label: &[u32]) -> Result<()> {
    let channels = smallvec::smallvec![AnyChannel::new("label", FlatSamples::U32(label.to_vec()))];
    write_layer(path, width, height, LayerAttributes::named("label"), channels)
}

fn write_layer(
    path: &Path,
    width: u32,
    height: u32,
    attributes: LayerAttributes,
    channels: smallvec::SmallVec<[AnyChannel<FlatSamples>; 4]>,
) -> Result<()> {
    let size = (width as usize, height as usize);
    let layer = Layer::new(size, attributes, Encoding::SMALL_LOSSLESS, AnyChannels::sort(channels));
    write_atomically(path, |file| {
        let mut out = std::io::BufWriter::new(file);
        Image::from_layer(layer).write().to_buffered(&mut out).map_err(|e| exr_error(path, e))?;
        out.flush().map_err(|e| Error::io(path, e))?;
        sort_header_attributes(out.get_mut()).map_err(|e| Error::io(path, e))
    })
}

/// Most bytes of a written file read back to find its header (ours are well under 4 KiB).
const MAX_HEADER_BYTES: u64 = 64 << 10;

/// Puts the header attributes of a file the exr crate just wrote in name order. It writes the
/// attributes it has no field for (ours: the sensor, shadow and effects settings) from a
/// HashMap, in an order that changes from process to process; sorted, the same image always
/// gives the same bytes. The attributes keep their bytes and the header its length, so the
/// offset table after it stays right. A header this cannot take apart is left as it is.
fn sort_header_attributes(file: &mut std::fs::File) -> std::io::Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    let mut header = Vec::new();
    file.seek(SeekFrom::Start(0))?;
    Read::by_ref(file).take(MAX_HEADER_BYTES).read_to_end(&mut header)?;
    let Some(mut attributes) = header_attributes(&header) else {
        return Ok(());
    };
    attributes.sort_by_key(|(name, _)| *name);
    let sorted: Vec<u8> = attributes.iter().flat_map(|(_, bytes)| bytes.iter().copied()).collect();
    file.seek(SeekFrom::Start(HEADER_ATTRIBUTES_START as u64))?;
    file.write_all(&sorted)
}

/// Where a single-part OpenEXR header's attributes start: after the magic number and the
/// version field.
const HEADER_ATTRIBUTES_START: usize = 8;

/// A single-part header's attributes in file order, each its name and its bytes (name, type,
/// size and value); `None` where `file` does not begin with a whole single-part header.
fn header_attributes(file: &[u8]) -> Option<Vec<(&[u8], &[u8])>> {
    const MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
    const MULTIPART: u8 = 0x10; // bit 12 of the version field
    if file.get(..4)? != MAGIC || file.get(5)? & MULTIPART != 0 {
        return None;
    }
    let until_nul = |from: usize| Some(from + file.get(from..)?.iter().position(|&b| b == 0)?);
    let mut attributes = Vec::new();
    let mut at = HEADER_ATTRIBUTES_START;
    while *file.get(at)? != 0 {
        let name_end = until_nul(at)?;
        let size_at = until_nul(name_end + 1)? + 1;
        let size = u32::from_le_bytes(file.get(size_at..size_at + 4)?.try_into().ok()?);
        let end = (size_at + 4).checked_add(usize::try_from(size).ok()?)?;
        attributes.push((&file[at..name_end], file.get(at..end)?));
        at = end;
    }
    Some(attributes)
}

/// Reads a range image (`range.exr` as `render` writes it), charged to `ledger`.
pub fn read_range_image(path: &Path, ledger: &Ledger) -> Result<RangeImage> {
    parse_range_image(&read_input_file(path, "range image", ledger)?, path, ledger)
}

/// Decodes a range image from a file's bytes; `path` names it in messages.
pub fn parse_range_image(bytes: &[u8], path: &Path, ledger: &Ledger) -> Result<RangeImage> {
    let (width, height, mut channels, attributes) = decode_layer(bytes, path, ledger)?;
    let mut take_f32 = |name: &str| match channels.iter().position(|c| c.name.eq(name)) {
        Some(i) => match channels.swap_remove(i).sample_data {
            FlatSamples::F32(v) => Ok(v),
            _ => Err(Error::file(path, format!("channel {name} must hold 32-bit floats"))),
        },
        None => Err(Error::file(path, format!("has no channel {name} (expected X, Y, Z, label)"))),
    };
    let (x, y, z) = (take_f32("X")?, take_f32("Y")?, take_f32("Z")?);
    let label = take_labels(path, &mut channels)?;
    let reason = match channels.iter().position(|c| c.name.eq("reason")) {
        None => None,
        Some(i) => match channels.swap_remove(i).sample_data {
            FlatSamples::U32(codes) => match codes.iter().find(|&&c| Reason::from_code(c).is_none()) {
                Some(bad) => return Err(Error::file(path, format!("its reason channel holds an unknown code {bad}"))),
                None => Some(codes),
            },
            _ => return Err(Error::file(path, "channel reason must hold 32-bit unsigned integers")),
        },
    };
    let witness = match channels.iter().position(|c| c.name.eq("witness")) {
        None => None,
        Some(i) => match channels.swap_remove(i).sample_data {
            FlatSamples::U32(bits) => Some(bits),
            _ => return Err(Error::file(path, "channel witness must hold 32-bit unsigned integers")),
        },
    };
    let setting = |name: &str| match attributes.other.get(&Text::from(name)) {
        Some(AttributeValue::Text(text)) => Some(text.to_string()),
        _ => None,
    };
    let sensor: Option<Sensor> = setting(SENSOR_ATTRIBUTE)
        .map(|t| parse_toml(&t))
        .transpose()
        .map_err(|e| Error::file(path, format!("its sensor attribute is unreadable: {e}")))?;
    let shadow: Option<ShadowSettings> = setting(SHADOW_ATTRIBUTE)
        .map(|t| parse_toml(&t))
        .transpose()
        .map_err(|e| Error::file(path, format!("its shadow attribute is unreadable: {e}")))?;
    let effects: Option<Effects> = setting(EFFECTS_ATTRIBUTE)
        .map(|t| parse_toml(&t))
        .transpose()
        .map_err(|e| Error::file(path, format!("its effects attribute is unreadable: {e}")))?;
    if let Some(e) = &effects {
        e.validate().map_err(|e| Error::file(path, format!("its effects attribute: {e}")))?;
    }
    if let Some(s) = &sensor {
        s.validate().map_err(|e| Error::file(path, format!("its sensor attribute: {e}")))?;
        if (s.width(), s.height()) != (width, height) {
            return Err(Error::file(
                path,
                format!("its sensor says {}×{} but the image is {width}×{height}", s.width(), s.height()),
            ));
        }
    }
    if let (Some(bits), Some(s)) = (&witness, &sensor) {
        let known = s.witnesses.len();
        if let Some(bad) = bits.iter().find(|&&b| known < 32 && b >> known != 0) {
            return Err(Error::file(
                path,
                format!("its witness channel holds {bad:#x}, a bit beyond its sensor's {known} witnesses"),
            ));
        }
    }
    Ok(RangeImage { width, height, x, y, z, label, reason, witness, sensor, shadow, effects })
}

/// Reads a label-only image (`label_unshadowed.exr`), charged to `ledger`: width, height,
/// labels.
pub fn read_label_image(path: &Path, ledger: &Ledger) -> Result<(u32, u32, Vec<u32>)> {
    let bytes = read_input_file(path, "label image", ledger)?;
    let (width, height, mut channels, _) = decode_layer(&bytes, path, ledger)?;
    Ok((width, height, take_labels(path, &mut channels)?))
}

fn take_labels(path: &Path, channels: &mut Vec<AnyChannel<FlatSamples>>) -> Result<Vec<u32>> {
    match channels.iter().position(|c| c.name.eq("label")) {
        Some(i) => match channels.swap_remove(i).sample_data {
            FlatSamples::U32(v) => Ok(v),
            _ => Err(Error::file(path, "channel label must hold 32-bit unsigned integers")),
        },
        None => Err(Error::file(path, "has no channel label")),
    }
}

type LayerParts = (u32, u32, Vec<AnyChannel<FlatSamples>>, LayerAttributes);

fn decode_layer(bytes: &[u8], path: &Path, ledger: &Ledger) -> Result<LayerParts> {
    let image = guard_parser(&path.display().to_string(), "the exr decoder", || {
        check_claimed_sizes(bytes, path, ledger)?;
        check_data_window(bytes, path)?;
        check_blocks(bytes, path)?;
        read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_buffered(Cursor::new(bytes))
            .map_err(|e| exr_error(path, e))
    })?;
    let layer = image.layer_data;
    let (w, h) = (layer.size.width(), layer.size.height());
    let to_u32 = |v: usize| u32::try_from(v).map_err(|_| Error::file(path, "image is too large"));
    Ok((to_u32(w)?, to_u32(h)?, layer.channel_data.list.into_vec(), layer.attributes))
}

/// Checks what every header of the file claims before anything is allocated for it.
fn check_claimed_sizes(bytes: &[u8], path: &Path, ledger: &Ledger) -> Result<()> {
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(|e| exr_error(path, e))?;
    for header in meta.headers.iter() {
        let (w, h) = (header.layer_size.width(), header.layer_size.height());
        if header.deep {
            return Err(Error::file(path, "holds deep data, which a range image never does"));
        }
        // A range image samples every channel at every pixel (and a sampling of 0 would
        // divide by zero in the exr crate's own size arithmetic).
        if let Some(c) = header.channels.list.iter().find(|c| c.sampling != Vec2(1, 1)) {
            return Err(Error::file(
                path,
                format!("channel {} is subsampled ({:?}); range images sample every pixel", c.name, c.sampling),
            ));
        }
        if w > MAX_IMAGE_SIDE as usize || h > MAX_IMAGE_SIDE as usize {
            return Err(Error::file(
                path,
                format!("its header claims a {w}×{h} image; sides are limited to {MAX_IMAGE_SIDE}"),
            ));
        }
        let decoded = header.total_pixel_bytes() as u64;
        let most = (bytes.len() as u64).saturating_mul(best_compression_ratio(header.compression));
        if decoded > most {
            return Err(Error::file(
                path,
                format!(
                    "its header claims a {w}×{h} image of {}, more than its {} can hold ({:?} compression)",
                    Bytes(decoded),
                    Bytes(bytes.len() as u64),
                    header.compression
                ),
            ));
        }
        ledger.charge(format_args!("decoding {} ({w}×{h})", path.display()), decoded)?;
    }
    Ok(())
}

/// Refuses a single-part header whose data window's corners are the wrong way round (its
/// maximum below its minimum), which the exr crate reads as a window of the same size (the
/// last `dataWindow` attribute, the one the crate keeps).
fn check_data_window(bytes: &[u8], path: &Path) -> Result<()> {
    let window = header_attributes(bytes)
        .and_then(|attributes| attributes.into_iter().rfind(|(name, _)| *name == b"dataWindow"))
        .and_then(|(_, attribute)| attribute.get(attribute.len().checked_sub(16)?..));
    let Some(corners) = window else { return Ok(()) };
    let corner = |k: usize| i32::from_le_bytes(corners[4 * k..4 * k + 4].try_into().expect("four bytes"));
    let (x_min, y_min, x_max, y_max) = (corner(0), corner(1), corner(2), corner(3));
    if x_max < x_min || y_max < y_min {
        return Err(Error::file(
            path,
            format!("its data window ({x_min}, {y_min})–({x_max}, {y_max}) ends before it begins"),
        ));
    }
    Ok(())
}

/// Refuses a file whose blocks of scan lines do not each lie, once, where its data window puts
/// them: the exr crate places a block by its first row's offset into the window divided by the
/// rows a block holds, rounded toward zero, so a block above the window, or between two
/// blocks' rows, would land silently on other rows.
fn check_blocks(bytes: &[u8], path: &Path) -> Result<()> {
    let reader = exr::block::read(Cursor::new(bytes), false).map_err(|e| exr_error(path, e))?;
    let headers = reader.meta_data().headers.clone();
    let scan_lines = |h: &exr::meta::header::Header| matches!(h.blocks, exr::meta::BlockDescription::ScanLines);
    let mut placed: Vec<Vec<bool>> =
        headers.iter().map(|h| if scan_lines(h) { vec![false; h.chunk_count] } else { Vec::new() }).collect();
    // Through the offset table, as the decoder reads them (not the bytes after it in turn).
    for chunk in reader.filter_chunks(false, |_, _, _| true).map_err(|e| exr_error(path, e))? {
        let chunk = chunk.map_err(|e| exr_error(path, e))?;
        let exr::block::chunk::CompressedBlock::ScanLine(block) = &chunk.compressed_block else { continue };
        let (Some(header), Some(placed)) = (headers.get(chunk.layer_index), placed.get_mut(chunk.layer_index)) else {
            return Err(Error::file(path, format!("a block names part {}, which the file lacks", chunk.layer_index)));
        };
        let lines = header.compression.scan_lines_per_block() as i64;
        let top = i64::from(header.own_attributes.layer_position.y());
        let offset = i64::from(block.y_coordinate) - top;
        let index = (offset >= 0 && offset % lines == 0).then(|| usize::try_from(offset / lines).ok()).flatten();
        match index.and_then(|index| placed.get_mut(index)) {
            Some(seen) if !*seen => *seen = true,
            _ => {
                let bottom = top + header.layer_size.height() as i64 - 1;
                return Err(Error::file(
                    path,
                    format!(
                        "a block of {lines} scan lines starts at row {}, which is not a block's first row of \
                         the data window's rows {top} to {bottom}, or is given twice",
                        block.y_coordinate
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The most decoded bytes one byte of a file can stand for under a compression: deflate's
/// limit (1032:1) for the zip-based ones (PXR24 deflates 3 bytes of each f32), a run of 128
/// bytes in 2 for RLE, and generously for the wavelet and lossy ones.
fn best_compression_ratio(compression: Compression) -> u64 {
    match compression {
        Compression::Uncompressed => 1,
        Compression::RLE => 64,
        Compression::ZIP1 | Compression::ZIP16 => 1032,
        Compression::PXR24 => 1376,
        _ => 1 << 16,
    }
}

fn exr_error(path: &Path, e: exr::error::Error) -> Error {
    match e {
        exr::error::Error::Io(io) => Error::io(path, io),
        other => Error::file(path, format!("not a usable OpenEXR file ({other})")),
    }
}

#[cfg(test)]
mod tests {
    use super::header_attributes;

    /// An attribute as a header stores it: name, type, size and value.
    fn attribute(name: &str, value: &[u8]) -> Vec<u8> {
        let mut bytes = [name.as_bytes(), b"\0string\0"].concat();
        bytes.extend((value.len() as u32).to_le_bytes());
        bytes.extend(value);
        bytes
    }

    #[test]
    fn header_attributes_are_taken_apart_or_left_alone() {
        let (b, a) = (attribute("b", b"xy"), attribute("a", b""));
        let header = [&[0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0][..], &b, &a, &[0], b"pixels"].concat();
        let names: Vec<&[u8]> = header_attributes(&header).unwrap().iter().map(|(name, _)| *name).collect();
        assert_eq!(names, [&b"b"[..], b"a"]);
        assert_eq!(header_attributes(&header).unwrap()[0].1, &b[..]);
        // Cut short anywhere, multi-part, or not OpenEXR at all: nothing to sort.
        let end = 8 + b.len() + a.len();
        assert!((0..=end).all(|cut| header_attributes(&header[..cut]).is_none()));
        let mut multipart = header.clone();
        multipart[5] |= 0x10;
        assert!(header_attributes(&multipart).is_none());
        assert!(header_attributes(b"GIF89a......").is_none());
    }
}
