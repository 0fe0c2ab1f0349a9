//! The error map: element error estimates seen by the camera, as colours on a
//! log scale, with a colour bar along the bottom edge.

use radcol_core::render::Image;

/// The decades the colour scale spans: 10^LOW (dark) … 10^HIGH (bright),
/// of the reflected light: bright is an error as large as the brightest
/// reflected light. Fixed, so that maps of two runs compare by eye.
pub const DECADES: (i32, i32) = (-5, 0);

/// Height of the colour bar in pixels (none on images lower than 4 bars).
const BAR: u32 = 10;

/// Colour of pixels that see no front face.
const NOTHING: [u8; 3] = [38, 38, 38];

/// The colour of a relative error `e` (clamped to the scale).
pub fn colour(e: f64) -> [u8; 3] {
    let (lo, hi) = (DECADES.0 as f64, DECADES.1 as f64);
    let x = if e > 0.0 {
        ((e.log10() - lo) / (hi - lo)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let c = colorous::VIRIDIS.eval_continuous(x);
    [c.r, c.g, c.b]
}

/// Pixels of `image` (a map of relative errors, NaN where no front face was
/// seen: `radcol_core::render::render_element_values`), coloured, with the
/// scale drawn along the bottom: a bar from 10^LOW to 10^HIGH, a white tick at
/// each decade.
pub fn pixels(image: &Image) -> Vec<[u8; 3]> {
    let (w, h) = (image.width, image.height);
    let mut px: Vec<[u8; 3]> = image
        .rgb
        .iter()
        .map(|v| {
            if v[0].is_nan() {
                NOTHING
            } else {
                colour(v[0] as f64)
            }
        })
        .collect();
    if h >= 4 * BAR && w >= 2 {
        let (lo, hi) = DECADES;
        let decades = (hi - lo) as f64;
        for x in 0..w {
            let f = x as f64 / (w - 1) as f64;
            let e = 10f64.powf(lo as f64 + f * decades);
            // A tick where a decade falls in this column.
            let tick =
                (0..=hi - lo).any(|d| ((d as f64 / decades) * (w - 1) as f64).round() as u32 == x);
            for y in h - BAR..h {
                px[(y * w + x) as usize] = if tick && y < h - BAR / 2 {
                    [255, 255, 255]
                } else {
                    colour(e)
                };
            }
        }
    }
    px
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ends of the scale are viridis's ends, values outside are clamped,
    /// and brightness grows with the error.
    #[test]
    fn scale_is_logarithmic_and_clamped() {
        let dark = colour(1e-5);
        assert_eq!(dark, colour(1e-9));
        assert_eq!(dark, colour(0.0));
        assert_eq!(colour(1.0), colour(5.0));
        let lum = |c: [u8; 3]| 0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64;
        let mut last = -1.0;
        for k in -5..=0 {
            let l = lum(colour(10f64.powi(k)));
            assert!(l > last, "decade {k}: {l} after {last}");
            last = l;
        }
    }

    /// Uncovered pixels are grey, the bar runs from dark to bright with a
    /// tick at each of the 6 decades.
    #[test]
    fn pixels_draw_the_bar() {
        let (w, h) = (101u32, 60u32);
        let mut rgb = vec![[1e-3f32; 3]; (w * h) as usize];
        rgb[0] = [f32::NAN; 3];
        let img = Image {
            width: w,
            height: h,
            rgb,
            coverage: vec![1.0; (w * h) as usize],
            emitted: Vec::new(),
        };
        let px = pixels(&img);
        assert_eq!(px[0], NOTHING);
        assert_eq!(px[1], colour(1e-3));
        let bottom = |x: u32| px[((h - 1) * w + x) as usize];
        assert_eq!(bottom(0), colour(1e-5));
        assert_eq!(bottom(w - 1), colour(1.0));
        let top_of_bar = (h - BAR) * w;
        let ticks = (0..w)
            .filter(|&x| px[(top_of_bar + x) as usize] == [255, 255, 255])
            .count();
        assert_eq!(ticks, 6);
    }
}
