//! Conversions from the image crate's images to the workspace's grey frame ([`GreyBuffer`], grey
//! levels 0–255 as f32), so that every caller builds the grey levels the trackers read the same
//! way.
//!
//! - 8-bit grey is taken as is; 16-bit grey is divided by 257 (65 535 ↦ 255).
//! - Colour is reduced with the ITU-R BT.601 luma weights, 0.299 R + 0.587 G + 0.114 B: the
//!   weighting of the luma plane of a Y4M video, so image files and videos give the trackers the
//!   same grey levels. Alpha is ignored.
//! - Float images follow the image crate's convention, 0–1, and are scaled by 255. (The image
//!   crate's own `to_luma32f` gives 0–1 with other weights, BT.709; use
//!   [`grey_from_unit_range`] for a buffer that is already grey in 0–1.)

use std::ops::Deref;

use image::{DynamicImage, ImageBuffer, Luma, LumaA, Pixel, Rgb, Rgba};

use crate::GreyBuffer;

/// An image of the image crate that converts to the workspace's grey frame, in grey levels
/// 0–255 (see the module documentation for the scale of each pixel type).
///
/// # Examples
/// ```
/// use vision_core::{GreyImage, ToGreyBuffer};
///
/// let rgb = image::RgbImage::from_pixel(4, 3, image::Rgb([200, 100, 50]));
/// let grey = rgb.to_grey_buffer();
/// let view = GreyImage::try_from(&grey)?;
/// // 0.299·200 + 0.587·100 + 0.114·50.
/// assert!((view.get(0, 0).unwrap() - 124.2).abs() < 1e-4);
/// let decoded = image::DynamicImage::ImageLuma8(image::GrayImage::from_pixel(4, 3, image::Luma([17])));
/// assert_eq!(decoded.to_grey_buffer().get_pixel(3, 2).0, [17.0]);
/// # Ok::<(), vision_core::Error>(())
/// ```
pub trait ToGreyBuffer {
    /// The grey levels 0–255 of every pixel, row-major.
    fn to_grey_buffer(&self) -> GreyBuffer;
}

/// ITU-R BT.601 luma of 8-bit RGB, in grey levels (the formula of the Y4M luma plane).
fn bt601_u8(p: &[u8]) -> f32 {
    crate::luma_bt601(p[0], p[1], p[2])
}

/// BT.601 luma of RGB already in grey levels 0–255.
fn bt601_f32(r: f32, g: f32, b: f32) -> f32 {
    0.299 * r + 0.587 * g + 0.114 * b
}

/// A 16-bit sample in grey levels 0–255.
fn level_u16(v: u16) -> f32 {
    f32::from(v) / 257.0
}

/// Maps every pixel of `img` to one grey level.
fn map_pixels<P, C>(img: &ImageBuffer<P, C>, f: impl Fn(&[P::Subpixel]) -> f32) -> GreyBuffer
where
    P: Pixel,
    C: Deref<Target = [P::Subpixel]>,
{
    let (w, h) = img.dimensions();
    let data: Vec<f32> = img.pixels().map(|p| f(p.channels())).collect();
    // The length is `w · h` by construction, so `from_raw` cannot fail; an empty buffer is the
    // fallback that the grey image's own checks then refuse.
    GreyBuffer::from_raw(w, h, data).unwrap_or_else(|| GreyBuffer::new(0, 0))
}

impl<C: Deref<Target = [u8]>> ToGreyBuffer for ImageBuffer<Luma<u8>, C> {
    fn to_grey_buffer(&self) -> GreyBuffer {
        map_pixels(self, |p| f32::from(p[0]))
    }
}

impl<C: Deref<Target = [u8]>> ToGreyBuffer for ImageBuffer<LumaA<u8>, C> {
    fn to_grey_buffer(&self) -> GreyBuffer {
        map_pixels(self, |p| f32::from(p[0]))
    }
}

impl<C: Deref<Target = [u16]>> ToGreyBuffer for ImageBuffer<Luma<u16>, C> {
    fn to_grey_buffer(&self) -> GreyBuffer {
        map_pixels(self, |p| level_u16(p[0]))
    }
}

impl<C: Deref<Target = [u16]>> ToGreyBuffer for ImageBuffer<LumaA<u16>, C> {
    fn to_grey_buffer(&self) -> GreyBuffer {
        map_pixels(self, |p| level_u16(p[0]))
    }
}

impl<C: Deref<Target = [u8]>> ToGreyBuffer for ImageBuffer<Rgb<u8>, C> {
    fn to_grey_buffer(&self) -> GreyBuffer {
        map_pixels(self, bt601_u8)
    }
}

impl<C: Deref<Target = [u8]>> ToGreyBuffer for ImageBuffer<Rgba<u8>, C> {
    fn to_grey_buffer(&self) -> GreyBuffer {
        map_pixels(self, bt601_u8)
    }
}

impl<C: Deref<Target = [u16]>> ToGreyBuffer for ImageBuffer<Rgb<u16>, C> {
    fn to_grey_buffer(&self) -> GreyBuffer {
        map_pixels(self, |p| {
            bt601_f32(level_u16(p[0]), level_u16(p[1]), level_u16(p[2]))
        })
    }
}

impl<C: Deref<Target = [u16]>> ToGreyBuffer for ImageBuffer<Rgba<u16>, C> {
    fn to_grey_buffer(&self) -> GreyBuffer {
        map_pixels(self, |p| {
            bt601_f32(level_u16(p[0]), level_u16(p[1]), level_u16(p[2]))
        })
    }
}

impl<C: Deref<Target = [f32]>> ToGreyBuffer for ImageBuffer<Rgb<f32>, C> {
    fn to_grey_buffer(&self) -> GreyBuffer {
        map_pixels(self, |p| 255.0 * bt601_f32(p[0], p[1], p[2]))
    }
}

impl<C: Deref<Target = [f32]>> ToGreyBuffer for ImageBuffer<Rgba<f32>, C> {
    fn to_grey_buffer(&self) -> GreyBuffer {
        map_pixels(self, |p| 255.0 * bt601_f32(p[0], p[1], p[2]))
    }
}

impl ToGreyBuffer for DynamicImage {
    /// Every variant by its own pixel type (above); a variant added to the image crate later is
    /// read through its RGB float form.
    fn to_grey_buffer(&self) -> GreyBuffer {
        match self {
            DynamicImage::ImageLuma8(i) => i.to_grey_buffer(),
            DynamicImage::ImageLumaA8(i) => i.to_grey_buffer(),
            DynamicImage::ImageRgb8(i) => i.to_grey_buffer(),
            DynamicImage::ImageRgba8(i) => i.to_grey_buffer(),
            DynamicImage::ImageLuma16(i) => i.to_grey_buffer(),
            DynamicImage::ImageLumaA16(i) => i.to_grey_buffer(),
            DynamicImage::ImageRgb16(i) => i.to_grey_buffer(),
            DynamicImage::ImageRgba16(i) => i.to_grey_buffer(),
            DynamicImage::ImageRgb32F(i) => i.to_grey_buffer(),
            DynamicImage::ImageRgba32F(i) => i.to_grey_buffer(),
            other => other.to_rgb32f().to_grey_buffer(),
        }
    }
}

/// A grey f32 buffer in the image crate's 0–1 scale (what `DynamicImage::to_luma32f` gives) as
/// the workspace's grey frame in 0–255: every value times 255.
///
/// # Examples
/// ```
/// use vision_core::grey_from_unit_range;
///
/// let unit = image::ImageBuffer::from_pixel(2, 2, image::Luma([0.5f32]));
/// assert_eq!(grey_from_unit_range(&unit).get_pixel(1, 1).0, [127.5]);
/// ```
pub fn grey_from_unit_range<C: Deref<Target = [f32]>>(
    img: &ImageBuffer<Luma<f32>, C>,
) -> GreyBuffer {
    map_pixels(img, |p| 255.0 * p[0])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::GreyImage;
    use image::{GrayImage, RgbImage};

    #[test]
    fn eight_bit_images_keep_their_grey_levels() {
        let grey = GrayImage::from_fn(5, 3, |x, y| Luma([(40 * x + 7 * y) as u8]));
        let g = grey.to_grey_buffer();
        assert_eq!(g.dimensions(), (5, 3));
        for (x, y, p) in grey.enumerate_pixels() {
            assert_eq!(g.get_pixel(x, y).0, [f32::from(p[0])]);
        }
        // Through DynamicImage, with or without alpha, the same levels.
        let dynamic = DynamicImage::ImageLuma8(grey.clone());
        assert_eq!(dynamic.to_grey_buffer(), g);
        assert_eq!(
            DynamicImage::ImageLumaA8(dynamic.to_luma_alpha8()).to_grey_buffer(),
            g
        );
        // 16-bit grey: 65 535 is 255, and the 8-bit value v written as 257·v is v.
        let wide = DynamicImage::ImageLuma16(dynamic.to_luma16());
        assert_eq!(wide.to_grey_buffer(), g);
    }

    #[test]
    fn colour_is_reduced_with_the_bt601_weights() {
        let rgb = RgbImage::from_fn(4, 2, |x, y| {
            image::Rgb([60 * x as u8, 100 + 50 * y as u8, 255])
        });
        let g = rgb.to_grey_buffer();
        for (x, y, p) in rgb.enumerate_pixels() {
            let expected =
                0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2]);
            assert_eq!(g.get_pixel(x, y).0, [expected]);
        }
        let dynamic = DynamicImage::ImageRgb8(rgb);
        assert_eq!(dynamic.to_grey_buffer(), g);
        // Alpha is ignored; 16-bit and float colour give the same levels to f32 rounding.
        for other in [
            DynamicImage::ImageRgba8(dynamic.to_rgba8()),
            DynamicImage::ImageRgb16(dynamic.to_rgb16()),
            DynamicImage::ImageRgba16(dynamic.to_rgba16()),
            DynamicImage::ImageRgb32F(dynamic.to_rgb32f()),
            DynamicImage::ImageRgba32F(dynamic.to_rgba32f()),
        ] {
            let h = other.to_grey_buffer();
            assert_eq!(h.dimensions(), g.dimensions());
            for (a, b) in h.as_raw().iter().zip(g.as_raw()) {
                assert!((a - b).abs() < 1e-3, "{a} vs {b}");
            }
        }
    }

    #[test]
    fn unit_range_grey_is_scaled_to_grey_levels() {
        let grey = GrayImage::from_fn(3, 3, |x, y| Luma([(90 * x + 10 * y) as u8]));
        let unit = DynamicImage::ImageLuma8(grey.clone()).to_luma32f();
        let g = grey_from_unit_range(&unit);
        for (a, b) in g.as_raw().iter().zip(grey.to_grey_buffer().as_raw()) {
            assert!((a - b).abs() < 1e-3, "{a} vs {b}");
        }
        // An empty image converts to an empty buffer, which the grey image refuses.
        let empty = GrayImage::new(0, 4).to_grey_buffer();
        assert!(GreyImage::try_from(&empty).is_err());
    }
}
