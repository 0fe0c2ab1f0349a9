//! Linear float OpenEXR images: the rendered radiance before any tone mapping.

use super::{Context, Result};
use crate::render::Image;
use exr::prelude::{Image as ExrImage, SpecificChannels, Vec2, WritableImage};
use std::io::{Seek, Write};

/// Writes the radiance of `image` as a single-layer RGB EXR with f32 channels
/// (the exr crate's default lossless compression), top row first.
pub fn write<W: Write + Seek>(w: W, image: &Image) -> Result<()> {
    let (width, height) = (image.width as usize, image.height as usize);
    if width == 0 || height == 0 {
        bail!("EXR: image size {width}×{height} has no pixels");
    }
    if image.rgb.len() != width * height {
        bail!(
            "EXR: {} pixels given for a {width}×{height} image ({} expected)",
            image.rgb.len(),
            width * height
        );
    }
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let [r, g, b] = image.rgb[y * width + x];
        (r, g, b)
    });
    ExrImage::from_channels((width, height), channels)
        .write()
        .to_buffered(w)
        .context("EXR: writing the image")?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use exr::prelude::{read, ReadChannels, ReadLayers};
    use std::io::Cursor;

    /// The exr crate's reader gets back the size and the exact f32 values.
    #[test]
    fn round_trip() {
        let (w, h) = (4u32, 3u32);
        let rgb: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                [
                    i as f32 * 0.125,
                    1.0 / (1.0 + i as f32),
                    1e-3 * i as f32 + 7.5,
                ]
            })
            .collect();
        let image = Image {
            width: w,
            height: h,
            coverage: vec![1.0; rgb.len()],
            rgb: rgb.clone(),
            emitted: Vec::new(),
        };
        let mut bytes = Cursor::new(Vec::new());
        write(&mut bytes, &image).unwrap();
        bytes.set_position(0);
        let back = read()
            .no_deep_data()
            .largest_resolution_level()
            .rgb_channels(
                |size, _| (size, vec![[0.0f32; 3]; size.width() * size.height()]),
                |(size, px): &mut (Vec2<usize>, Vec<[f32; 3]>), pos, (r, g, b): (f32, f32, f32)| {
                    px[pos.y() * size.width() + pos.x()] = [r, g, b];
                },
            )
            .first_valid_layer()
            .all_attributes()
            .from_buffered(bytes)
            .unwrap();
        let (size, px) = &back.layer_data.channel_data.pixels;
        assert_eq!((size.width(), size.height()), (4, 3));
        assert_eq!(px[2 * 4 + 1], [1.125, 1.0 / 10.0, 1e-3 * 9.0 + 7.5]);
        assert_eq!(*px, rgb);
    }

    #[test]
    fn rejects_wrong_length() {
        let image = Image {
            width: 2,
            height: 2,
            rgb: vec![[0.0; 3]; 3],
            coverage: vec![],
            emitted: vec![],
        };
        let err = write(Cursor::new(Vec::new()), &image).unwrap_err();
        assert!(err.to_string().contains("3 pixels"), "{err}");
    }
}
