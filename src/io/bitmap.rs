//! Loading trap bitmaps with the image crate into linear premultiplied RGBA.

use std::path::Path;

use super::IoError;
use crate::palette::color::srgb_to_linear;
use crate::trap::Bitmap;

/// Loads an image file (PNG) as a trap bitmap.
pub fn load_bitmap(path: &Path) -> Result<Bitmap, IoError> {
    if !path.exists() {
        return Err(IoError::caused(path, std::io::Error::new(std::io::ErrorKind::NotFound, "no such file")));
    }
    let img = image::open(path).map_err(|e| IoError::caused(path, e))?.to_rgba8();
    let (w, h) = img.dimensions();
    if w == 0 || h == 0 {
        return Err(IoError::new(path, "the image is empty"));
    }
    let lut: Vec<f32> = (0..256).map(|v| srgb_to_linear(v as f32 / 255.0)).collect();
    let texels = img
        .pixels()
        .map(|p| {
            let a = p[3] as f32 / 255.0;
            [lut[p[0] as usize] * a, lut[p[1] as usize] * a, lut[p[2] as usize] * a, a]
        })
        .collect();
    Ok(Bitmap { width: w as usize, height: h as usize, texels })
}
