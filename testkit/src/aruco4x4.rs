//! ArUco 4x4 bitmaps (OpenCV's `DICT_4X4_50`), to print ArUco tags into
//! simulated scenes at the WhyCode marker's footprint
//! ([`crate::scenario::Print::apply`]). Facts from OpenCV's predefined dictionary: each
//! tag's 16 data cells row by row from the top left, the first cell the
//! code's most significant bit, a 1 bit white; one black border cell
//! around them.

use image::{GrayImage, Luma};

/// How many tags the scenes draw from.
pub const TAGS: u32 = CODES.len() as u32;

/// Cells of the black-bordered square (the white border is the card's).
pub const CELLS: u32 = 6;

const CODES: [u16; 50] = [
    0xb532, 0x0f9a, 0x332d, 0x9946, 0x549e, 0x79cd, 0x9e2e, 0xc4f2, 0xfeda, 0xcf56, 0xf991, 0x11a7,
    0x0eb7, 0x2a0f, 0x24b1, 0x263e, 0x4665, 0x6600, 0x6c5e, 0x76af, 0x868b, 0xb02b, 0xccd5, 0xdd82,
    0xfe47, 0x9471, 0xace4, 0xa554, 0x2123, 0x346f, 0x4415, 0x57b2, 0x9ecf, 0xf0cb, 0x08ae, 0x0929,
    0x1875, 0x04ff, 0x0df6, 0x1c5a, 0x1718, 0x2a28, 0x328c, 0x38b2, 0x24e8, 0x2eeb, 0x2d3f, 0x4b64,
    0x502e, 0x5013,
];

/// Tag `id` (below [`TAGS`]) as a 6x6 bitmap: black border, data inside.
pub fn bitmap(id: u32) -> GrayImage {
    let code = CODES[id as usize];
    let mut image = GrayImage::from_pixel(CELLS, CELLS, Luma([0]));
    for bit in 0..16 {
        if code >> (15 - bit) & 1 == 1 {
            image.put_pixel(1 + bit % 4, 1 + bit / 4, Luma([255]));
        }
    }
    image
}
