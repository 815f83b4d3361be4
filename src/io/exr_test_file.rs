//! Small EXR files for the readers' tests: `N` holds each sample's index, `NF` half its
//! column, so a plane read back shows where every sample came from.

use std::path::Path;

use ::exr::prelude::*;

/// Writes a `w` × `h` scan-line file of `N` (u32, the sample index `y * w + x`) and `NF`
/// (f32, `x / 2`) with `compression` to `path`, its data window's top-left corner at
/// `origin`.
pub(super) fn write_n_nf(path: &Path, (w, h): (usize, usize), origin: (i32, i32), compression: Compression) {
    let channels = SpecificChannels::build()
        .with_channel("N")
        .with_channel("NF")
        .with_pixel_fn(|p: Vec2<usize>| ((p.1 * w + p.0) as u32, p.0 as f32 * 0.5));
    let mut attributes = LayerAttributes::named("deepfield");
    attributes.layer_position = Vec2(origin.0, origin.1);
    let layer = Layer::new(
        (w, h),
        attributes,
        Encoding { compression, blocks: Blocks::ScanLines, line_order: LineOrder::Increasing },
        channels,
    );
    Image::from_layer(layer).write().to_file(path).expect("a test file is written");
}
