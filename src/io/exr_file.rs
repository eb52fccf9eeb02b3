//! OpenEXR files (DESIGN.md "Interfaces"): `range.exr` has one layer with channels X, Y, Z
//! (f32, NaN where there is no data) and `label` (u32, exact for every value); the sensor and
//! shadow settings go into the layer header as TOML text attributes, so `verify` can take
//! them from the sensed image. Compression is ZIP, which is lossless, so files read back
//! bit-identical.

use super::RangeImage;
use crate::error::{Error, Result};
use crate::sensor::Sensor;
use crate::shadow::ShadowSettings;
use exr::prelude::*;
use std::path::Path;

const SENSOR_ATTRIBUTE: &str = "rangesynth_sensor";
const SHADOW_ATTRIBUTE: &str = "rangesynth_shadow";

pub fn write_range_image(path: &Path, image: &RangeImage) -> Result<()> {
    let channels = smallvec::smallvec![
        AnyChannel::new("X", FlatSamples::F32(image.x.clone())),
        AnyChannel::new("Y", FlatSamples::F32(image.y.clone())),
        AnyChannel::new("Z", FlatSamples::F32(image.z.clone())),
        AnyChannel::new("label", FlatSamples::U32(image.label.clone())),
    ];
    let mut attributes = LayerAttributes::named("range");
    let mut put = |name: &str, value: Option<String>| -> Result<()> {
        if let Some(text) = value {
            let text = Text::new_or_none(&text).ok_or_else(|| Error::file(path, "settings are not plain ASCII"))?;
            attributes.other.insert(Text::from(name), AttributeValue::Text(text));
        }
        Ok(())
    };
    put(SENSOR_ATTRIBUTE, image.sensor.map(|s| toml::to_string(&s)).transpose().map_err(|e| Error::file(path, e))?)?;
    put(SHADOW_ATTRIBUTE, image.shadow.map(|s| toml::to_string(&s)).transpose().map_err(|e| Error::file(path, e))?)?;
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
    Image::from_layer(layer).write().to_file(path).map_err(|e| exr_error(path, e))
}

pub fn read_range_image(path: &Path) -> Result<RangeImage> {
    let (width, height, mut channels, attributes) = read_layer(path)?;
    let mut take_f32 = |name: &str| match channels.iter().position(|c| c.name.eq(name)) {
        Some(i) => match channels.swap_remove(i).sample_data {
            FlatSamples::F32(v) => Ok(v),
            _ => Err(Error::file(path, format!("channel {name} must hold 32-bit floats"))),
        },
        None => Err(Error::file(path, format!("has no channel {name} (expected X, Y, Z, label)"))),
    };
    let (x, y, z) = (take_f32("X")?, take_f32("Y")?, take_f32("Z")?);
    let label = take_labels(path, &mut channels)?;
    let setting = |name: &str| match attributes.other.get(&Text::from(name)) {
        Some(AttributeValue::Text(text)) => Some(text.to_string()),
        _ => None,
    };
    let sensor: Option<Sensor> = setting(SENSOR_ATTRIBUTE)
        .map(|t| toml::from_str(&t))
        .transpose()
        .map_err(|e| Error::file(path, format!("its sensor attribute is unreadable: {e}")))?;
    let shadow: Option<ShadowSettings> = setting(SHADOW_ATTRIBUTE)
        .map(|t| toml::from_str(&t))
        .transpose()
        .map_err(|e| Error::file(path, format!("its shadow attribute is unreadable: {e}")))?;
    if let Some(s) = &sensor {
        if (s.width, s.height) != (width, height) {
            return Err(Error::file(
                path,
                format!("its sensor says {}×{} but the image is {width}×{height}", s.width, s.height),
            ));
        }
    }
    Ok(RangeImage { width, height, x, y, z, label, sensor, shadow })
}

/// Reads a label-only image (`label_unshadowed.exr`): width, height, labels.
pub fn read_label_image(path: &Path) -> Result<(u32, u32, Vec<u32>)> {
    let (width, height, mut channels, _) = read_layer(path)?;
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

fn read_layer(path: &Path) -> Result<LayerParts> {
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| exr_error(path, e))?;
    let layer = image.layer_data;
    let (w, h) = (layer.size.width(), layer.size.height());
    let to_u32 = |v: usize| u32::try_from(v).map_err(|_| Error::file(path, "image is too large"));
    Ok((to_u32(w)?, to_u32(h)?, layer.channel_data.list.into_vec(), layer.attributes))
}

fn exr_error(path: &Path, e: exr::error::Error) -> Error {
    match e {
        exr::error::Error::Io(io) => Error::io(path, io),
        other => Error::file(path, format!("not a usable OpenEXR file ({other})")),
    }
}
