//! Tracks drawn on a frame, for looking at a tracker's output on video: each box outlined in
//! its id's colour, with the id written above it. The rectangles are imageproc's; the digits
//! are a 3 × 5 pixel font drawn here (imageproc's text needs a font file, which a test machine
//! may not have).

use image::{Rgb, RgbImage};
use imageproc::drawing::{draw_filled_rect_mut, draw_hollow_rect_mut};
use imageproc::rect::Rect;
use tracker_model::BoundingBox;

use crate::{PixelFormat, Result, VideoFrame};

/// Twelve colours far apart in hue and lightness, cycled by id (a neighbour's id never shares
/// its colour).
const PALETTE: [[u8; 3]; 12] = [
    [230, 25, 75],
    [60, 180, 75],
    [255, 225, 25],
    [0, 130, 200],
    [245, 130, 48],
    [145, 30, 180],
    [70, 240, 240],
    [240, 50, 230],
    [210, 245, 60],
    [250, 190, 212],
    [0, 128, 128],
    [255, 255, 255],
];

/// The colour of track `id`.
pub fn colour_of(id: u64) -> [u8; 3] {
    PALETTE[(id % PALETTE.len() as u64) as usize]
}

/// The digits 0-9, five rows of three bits each (bit 2 is the left column).
const DIGITS: [[u8; 5]; 10] = [
    [0b111, 0b101, 0b101, 0b101, 0b111],
    [0b010, 0b110, 0b010, 0b010, 0b111],
    [0b111, 0b001, 0b111, 0b100, 0b111],
    [0b111, 0b001, 0b111, 0b001, 0b111],
    [0b101, 0b101, 0b111, 0b001, 0b001],
    [0b111, 0b100, 0b111, 0b001, 0b111],
    [0b111, 0b100, 0b111, 0b101, 0b111],
    [0b111, 0b001, 0b010, 0b010, 0b010],
    [0b111, 0b101, 0b111, 0b101, 0b111],
    [0b111, 0b101, 0b111, 0b001, 0b111],
];

/// Pixels per font pixel: digits 6 × 10 px, legible on a 768 × 576 frame.
const SCALE: i32 = 2;

/// `frame` as RGB with every `(id, box)` drawn: a two-pixel outline and the id on a dark
/// label above the box (inside it when the box touches the top edge). Parts off the image are
/// clipped.
pub fn draw_tracks(frame: &VideoFrame, tracks: &[(u64, BoundingBox)]) -> Result<VideoFrame> {
    let rgb = match frame.format() {
        PixelFormat::Rgb => frame.data().to_vec(),
        PixelFormat::Grey => frame.data().iter().flat_map(|&v| [v, v, v]).collect(),
    };
    let (w, h) = (frame.width(), frame.height());
    let Some(mut image) = RgbImage::from_raw(w as u32, h as u32, rgb) else {
        unreachable!("a VideoFrame holds width × height × channels bytes");
    };
    for (id, b) in tracks {
        let colour = Rgb(colour_of(*id));
        let (left, top) = (b.left.round() as i32, b.top.round() as i32);
        let (width, height) = (
            b.width.round().max(1.0) as u32,
            b.height.round().max(1.0) as u32,
        );
        draw_hollow_rect_mut(
            &mut image,
            Rect::at(left, top).of_size(width, height),
            colour,
        );
        if width > 2 && height > 2 {
            let inner = Rect::at(left + 1, top + 1).of_size(width - 2, height - 2);
            draw_hollow_rect_mut(&mut image, inner, colour);
        }
        draw_label(&mut image, *id, left, top, colour);
    }
    VideoFrame::new(w, h, PixelFormat::Rgb, image.into_raw())
}

/// The id's digits on a black label whose bottom-left corner is (left, top), or just inside
/// the box's top when that would leave the image.
fn draw_label(image: &mut RgbImage, id: u64, left: i32, top: i32, colour: Rgb<u8>) {
    let digits: Vec<usize> = id
        .to_string()
        .bytes()
        .map(|c| usize::from(c - b'0'))
        .collect();
    let (glyph_w, glyph_h) = (3 * SCALE, 5 * SCALE);
    let label_w = (glyph_w + SCALE) * digits.len() as i32 + SCALE;
    let label_h = glyph_h + 2 * SCALE;
    let y0 = if top - label_h >= 0 {
        top - label_h
    } else {
        top
    };
    draw_filled_rect_mut(
        image,
        Rect::at(left, y0).of_size(label_w as u32, label_h as u32),
        Rgb([0, 0, 0]),
    );
    for (k, &d) in digits.iter().enumerate() {
        let x0 = left + SCALE + k as i32 * (glyph_w + SCALE);
        for (row, bits) in DIGITS[d].iter().enumerate() {
            for col in 0..3 {
                if bits & (0b100 >> col) != 0 {
                    let at = Rect::at(x0 + col * SCALE, y0 + SCALE + row as i32 * SCALE);
                    draw_filled_rect_mut(image, at.of_size(SCALE as u32, SCALE as u32), colour);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn a_box(left: f64, top: f64) -> BoundingBox {
        BoundingBox {
            left,
            top,
            width: 10.0,
            height: 20.0,
        }
    }

    #[test]
    fn the_outline_and_label_are_drawn_in_the_ids_colour() {
        let frame = VideoFrame::filled(64, 64, PixelFormat::Grey, 128).unwrap();
        let drawn = draw_tracks(&frame, &[(7, a_box(20.0, 30.0))]).unwrap();
        assert_eq!(drawn.format(), PixelFormat::Rgb);
        let colour = colour_of(7);
        // Corners and edges of the outline, two pixels thick.
        for (x, y) in [(20, 30), (29, 49), (21, 31), (25, 30), (20, 40)] {
            assert_eq!(drawn.pixel(x, y), &colour[..], "({x}, {y})");
        }
        // Inside the box the frame is untouched.
        assert_eq!(drawn.pixel(25, 40), &[128, 128, 128][..]);
        // The label sits above the box: black background, the digit 7's top row in colour
        // (3 × 5 font at scale 2: the top row spans x 22..28, y 18..20).
        assert_eq!(drawn.pixel(20, 16), &[0, 0, 0][..]);
        assert_eq!(drawn.pixel(22, 18), &colour[..]);
        assert_eq!(drawn.pixel(26, 18), &colour[..]);
        // Below the top row of a 7, the left column is empty.
        assert_eq!(drawn.pixel(22, 22), &[0, 0, 0][..]);
    }

    #[test]
    fn boxes_off_the_image_are_clipped() {
        let frame = VideoFrame::filled(16, 16, PixelFormat::Rgb, 0).unwrap();
        let tracks = [(123_456, a_box(-5.0, -5.0)), (1, a_box(12.0, 14.0))];
        let drawn = draw_tracks(&frame, &tracks).unwrap();
        assert_eq!((drawn.width(), drawn.height()), (16, 16));
    }

    #[test]
    fn neighbouring_ids_differ_in_colour() {
        for id in 0..40 {
            assert_ne!(colour_of(id), colour_of(id + 1));
        }
    }
}
