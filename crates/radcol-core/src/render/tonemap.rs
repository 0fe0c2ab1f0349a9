//! From linear radiance to display values: exposure, a tone curve, sRGB.
//!
//! The pipeline, per pixel (or vertex) and channel, is
//!
//! ```text
//! x = L · 2^exposure · a,   y = operator(x) ∈ [0, 1],   out = round(255 · srgb_encode(y))
//! ```
//!
//! where a = 1 without auto exposure, and with it a = 1 / L99, L99 being the
//! 99th percentile (nearest rank) of the Rec. 709 luminance
//! 0.2126 R + 0.7152 G + 0.0722 B over covered pixels (those whose rays hit a
//! surface at least once), so that L99 maps to 1.0 before the operator and the
//! brightest 1 % may saturate. An image that knows where its rays met
//! emitters ([`super::Image::emitted`]) counts only the covered pixels where
//! none did: the exposure follows the light that surfaces reflect, whatever
//! share of the view the lights take (all covered pixels when every one
//! meets a light). When no counted pixel has positive luminance, a = 1. The
//! background is scaled like everything else.
//! Negative and NaN inputs (undershoot of u_n) display as 0.

/// The tone curve applied after exposure, per channel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ToneOperator {
    /// y = clamp(x, 0, 1).
    Linear,
    /// y = x / (1 + x) (Reinhard's global operator, per channel).
    Reinhard,
    /// Narkowicz's fit of the ACES filmic curve,
    /// y = clamp(x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), 0, 1), applied to x as is.
    #[default]
    Aces,
}

/// Exposure and tone curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToneMap {
    /// Exposure in stops: values are multiplied by 2^exposure.
    pub exposure: f64,
    /// Tone curve.
    pub operator: ToneOperator,
    /// Scale so that the 99th luminance percentile of covered pixels maps to 1.0
    /// (before `exposure`, which still applies on top).
    pub auto: bool,
}

impl Default for ToneMap {
    /// Auto exposure, no extra stops, ACES.
    fn default() -> Self {
        Self {
            exposure: 0.0,
            operator: ToneOperator::Aces,
            auto: true,
        }
    }
}

impl ToneOperator {
    /// The curve at x ≥ 0 (NaN and negative x give 0, +∞ gives 1).
    pub fn apply(self, x: f64) -> f64 {
        if x.is_nan() || x <= 0.0 {
            return 0.0;
        }
        if x == f64::INFINITY {
            return 1.0;
        }
        let y = match self {
            ToneOperator::Linear => x,
            ToneOperator::Reinhard => x / (1.0 + x),
            ToneOperator::Aces if x > 1e100 => 1.0,
            ToneOperator::Aces => x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14),
        };
        y.clamp(0.0, 1.0)
    }
}

/// Rec. 709 (sRGB primaries) relative luminance of a linear RGB value.
pub fn luminance(c: [f32; 3]) -> f64 {
    0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
}

/// The sRGB transfer function (IEC 61966-2-1): linear [0, 1] to encoded [0, 1].
pub fn srgb_encode(y: f64) -> f64 {
    let y = if y > 0.0 { y.min(1.0) } else { 0.0 };
    if y <= 0.0031308 {
        12.92 * y
    } else {
        1.055 * y.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse sRGB transfer function: encoded [0, 1] to linear [0, 1].
pub fn srgb_decode(v: f64) -> f64 {
    let v = if v > 0.0 { v.min(1.0) } else { 0.0 };
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

impl ToneMap {
    /// The factor 2^exposure · a applied before the operator, for `values` whose
    /// covered entries are those with `coverage` > 0 (all when `coverage` is None).
    pub fn scale(&self, values: &[[f32; 3]], coverage: Option<&[f32]>) -> f64 {
        let stops = self.exposure.exp2();
        if !self.auto {
            return stops;
        }
        let mut lum: Vec<f64> = values
            .iter()
            .enumerate()
            .filter(|&(i, _)| coverage.is_none_or(|c| c.get(i).is_some_and(|&w| w > 0.0)))
            .map(|(_, &c)| luminance(c))
            .filter(|l| l.is_finite())
            .collect();
        if lum.is_empty() {
            return stops;
        }
        lum.sort_by(f64::total_cmp);
        // Nearest rank: the smallest value with at least 99 % of the values at or below it.
        let rank = ((0.99 * lum.len() as f64).ceil() as usize).clamp(1, lum.len());
        let p99 = lum[rank - 1];
        if p99 > 0.0 {
            stops / p99
        } else {
            stops
        }
    }

    /// Display-referred linear values in [0, 1] (after exposure and operator,
    /// before the sRGB encoding): what glTF vertex colours hold.
    pub fn apply_linear(&self, values: &[[f32; 3]], coverage: Option<&[f32]>) -> Vec<[f32; 3]> {
        let a = self.scale(values, coverage);
        values
            .iter()
            .map(|c| c.map(|x| self.operator.apply(x as f64 * a) as f32))
            .collect()
    }
}

/// Tone-maps linear `values` to 8-bit sRGB (see the module documentation);
/// `coverage` selects the entries auto exposure looks at (None: all).
pub fn tone_map_values(
    values: &[[f32; 3]],
    coverage: Option<&[f32]>,
    tm: &ToneMap,
) -> Vec<[u8; 3]> {
    tm.apply_linear(values, coverage)
        .into_iter()
        .map(|c| c.map(|y| (255.0 * srgb_encode(y as f64)).round() as u8))
        .collect()
}

/// Tone-maps a rendered image to 8-bit sRGB, row-major, top row first.
pub fn tone_map(image: &super::Image, tm: &ToneMap) -> Vec<[u8; 3]> {
    let coverage = (image.coverage.len() == image.rgb.len()).then_some(&image.coverage[..]);
    let reflected: Option<Vec<f32>> = coverage
        .filter(|_| image.emitted.len() == image.rgb.len())
        .map(|c| {
            c.iter()
                .zip(&image.emitted)
                .map(|(&c, &e)| if e > 0.0 { 0.0 } else { c })
                .collect()
        })
        .filter(|r: &Vec<f32>| r.iter().any(|&w| w > 0.0));
    tone_map_values(&image.rgb, reflected.as_deref().or(coverage), tm)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// sRGB at values computed from the standard's formula by hand:
    /// 1.055 · 0.5^(1/2.4) - 0.055 = 0.735356983, and 12.92 · 0.001 = 0.01292;
    /// 50 % linear grey is the well-known 8-bit code 188.
    #[test]
    fn srgb_curve() {
        assert_eq!(srgb_encode(0.0), 0.0);
        crate::assert_close!(srgb_encode(1.0), 1.0, 1e-15);
        crate::assert_close!(srgb_encode(0.5), 0.735_356_983_052_9, 1e-12);
        crate::assert_close!(srgb_encode(0.001), 0.01292, 1e-15);
        crate::assert_close!(srgb_encode(0.18), 0.461_356_129_500_4, 1e-12);
        // The two pieces meet at the breakpoint (to the standard's 4-digit constants).
        let a = 12.92 * 0.0031308;
        let b = 1.055 * 0.0031308f64.powf(1.0 / 2.4) - 0.055;
        crate::assert_close!(a, b, 1e-7);
        for i in 0..=100 {
            let y = i as f64 / 100.0;
            crate::assert_close!(srgb_decode(srgb_encode(y)), y, 1e-12);
        }
        let tm = ToneMap {
            exposure: 0.0,
            operator: ToneOperator::Linear,
            auto: false,
        };
        assert_eq!(
            tone_map_values(&[[0.5, 0.0, 1.0]], None, &tm),
            vec![[188, 0, 255]]
        );
    }

    /// 0 maps to 0 and huge values to 255 under every operator, with and without
    /// exposure; NaN and negative values display as 0.
    #[test]
    fn endpoints() {
        for operator in [
            ToneOperator::Linear,
            ToneOperator::Reinhard,
            ToneOperator::Aces,
        ] {
            for exposure in [-3.0, 0.0, 2.5] {
                let tm = ToneMap {
                    exposure,
                    operator,
                    auto: false,
                };
                let out = tone_map_values(
                    &[
                        [0.0; 3],
                        [1e30, 3e38, f32::INFINITY],
                        [f32::NAN, -1.0, -0.0],
                    ],
                    None,
                    &tm,
                );
                assert_eq!(
                    out,
                    vec![[0; 3], [255; 3], [0; 3]],
                    "{operator:?} {exposure}"
                );
            }
        }
        // Reinhard at 1 is exactly 1/2; ACES at 1 is 2.54/3.16.
        assert_eq!(ToneOperator::Reinhard.apply(1.0), 0.5);
        crate::assert_close!(ToneOperator::Aces.apply(1.0), 2.54 / 3.16, 1e-15);
        // One stop doubles the input to the curve.
        let tm = ToneMap {
            exposure: 1.0,
            operator: ToneOperator::Linear,
            auto: false,
        };
        assert_eq!(tm.apply_linear(&[[0.25; 3]], None), vec![[0.5; 3]]);
    }

    /// Auto exposure: grey levels 1..=100, the 99th percentile (nearest rank) is
    /// 99, so 99 maps to 1.0 and 33 to 1/3; uncovered pixels are ignored.
    #[test]
    fn auto_exposure() {
        let mut values: Vec<[f32; 3]> = (1..=100).map(|i| [i as f32; 3]).collect();
        let mut coverage = vec![1.0f32; 100];
        // A bright uncovered pixel must not change the scale.
        values.push([1e6; 3]);
        coverage.push(0.0);
        let tm = ToneMap {
            exposure: 0.0,
            operator: ToneOperator::Linear,
            auto: true,
        };
        let s = tm.scale(&values, Some(&coverage));
        crate::assert_close!(s, 1.0 / 99.0, 1e-15);
        let lin = tm.apply_linear(&values, Some(&coverage));
        crate::assert_close!(lin[32][0] as f64, 1.0 / 3.0, 1e-7);
        assert_eq!(lin[98], [1.0; 3]);
        // Colour weights: pure green of luminance 0.7152 · g.
        let tm2 = ToneMap {
            exposure: 1.0,
            ..tm
        };
        let s = tm2.scale(&[[0.0, 1.0, 0.0]], None);
        crate::assert_close!(s, 2.0 / 0.7152, 1e-12);
        // All black: no auto scale.
        assert_eq!(tm2.scale(&[[0.0; 3]; 4], None), 2.0);
    }
}
