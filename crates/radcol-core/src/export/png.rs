//! 8-bit sRGB PNG images.

use super::{Context, Result};
use std::io::Write;

/// Writes `pixels` (sRGB-encoded, row-major, top row first) as an 8-bit RGB PNG
/// with an sRGB chunk (perceptual intent).
pub fn write<W: Write>(w: W, width: u32, height: u32, pixels: &[[u8; 3]]) -> Result<()> {
    if width == 0 || height == 0 {
        bail!("PNG: image size {width}×{height} has no pixels");
    }
    if pixels.len() as u64 != width as u64 * height as u64 {
        bail!(
            "PNG: {} pixels given for a {width}×{height} image ({} expected)",
            pixels.len(),
            width as u64 * height as u64
        );
    }
    let mut encoder = ::png::Encoder::new(w, width, height);
    encoder.set_color(::png::ColorType::Rgb);
    encoder.set_depth(::png::BitDepth::Eight);
    encoder.set_source_srgb(::png::SrgbRenderingIntent::Perceptual);
    let mut writer = encoder.write_header().context("PNG: writing the header")?;
    writer
        .write_image_data(pixels.as_flattened())
        .context("PNG: writing the pixels")?;
    writer.finish().context("PNG: finishing the stream")?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    /// The png crate's decoder reads back the size, the sRGB chunk and every pixel.
    #[test]
    fn round_trip() {
        let (w, h) = (5u32, 3u32);
        let pixels: Vec<[u8; 3]> = (0..w * h)
            .map(|i| [i as u8 * 10, 255 - i as u8, (i * i) as u8])
            .collect();
        let mut bytes = Vec::new();
        write(&mut bytes, w, h, &pixels).unwrap();
        let decoder = ::png::Decoder::new(Cursor::new(&bytes));
        let mut reader = decoder.read_info().unwrap();
        let info = reader.info();
        assert_eq!((info.width, info.height), (w, h));
        assert_eq!(info.color_type, ::png::ColorType::Rgb);
        assert_eq!(info.bit_depth, ::png::BitDepth::Eight);
        assert_eq!(info.srgb, Some(::png::SrgbRenderingIntent::Perceptual));
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let frame = reader.next_frame(&mut buf).unwrap();
        let data = &buf[..frame.buffer_size()];
        assert_eq!(data.len(), 45);
        // Pixel (x = 3, y = 2) is number 13.
        let i = (2 * w + 3) as usize * 3;
        assert_eq!(&data[i..i + 3], &[130, 242, 169]);
        assert_eq!(data, pixels.as_flattened());
    }

    #[test]
    fn rejects_wrong_length() {
        let err = write(Vec::new(), 2, 2, &[[0; 3]; 3]).unwrap_err();
        assert!(err.to_string().contains("3 pixels"), "{err}");
        assert!(write(Vec::new(), 0, 2, &[]).is_err());
    }
}
