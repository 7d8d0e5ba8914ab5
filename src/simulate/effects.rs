//! From reflectance to an 8-bit camera image: illumination, blur, noise,
//! quantisation and JPEG, in the order a camera applies them.

use super::Scene;
use crate::math::sample::{Border, Plane};
use crate::math::Pcg32;
use crate::parallel::prelude::*;
use image::GrayImage;

/// Grey level of a perfectly white surface at exposure 1.
const FULL_SCALE: f64 = 255.0;

pub(super) fn develop(scene: &Scene, mut image: Vec<f32>) -> GrayImage {
    let width = scene.camera.width as usize;
    let height = scene.camera.height as usize;
    illuminate(scene, &mut image, width);
    if let Some(motion) = scene.motion_blur {
        if motion.length_px > 0.5 {
            image = motion_blur(&image, width, height, motion.length_px, motion.angle);
        }
    }
    if scene.focus_blur_px > 0.05 {
        image = gaussian_blur(&image, width, height, scene.focus_blur_px);
    }
    let processing = scene.processing;
    if let Some(aberration) = processing.bayer_aberration {
        image = bayer_mosaic(&image, width, height, aberration);
    }
    if scene.noise > 0.0 {
        let mut rng = Pcg32::new(scene.seed, 23);
        for px in image.iter_mut() {
            *px += (scene.noise * rng.gaussian()) as f32;
        }
    }
    if processing.bayer_aberration.is_some() {
        image = demosaic_to_grey(&image, width, height);
    }
    if let Some((amount, sigma)) = processing.sharpen {
        let soft = gaussian_blur(&image, width, height, sigma);
        for (px, s) in image.iter_mut().zip(soft) {
            *px += amount as f32 * (*px - s);
        }
    }
    let mut gray = quantise(&image, scene.camera.width, scene.camera.height);
    if let Some(factor) = processing.video_downscale.filter(|&f| f > 1) {
        gray = video_round_trip(&gray, factor, processing.video_quality);
    }
    match scene.jpeg_quality {
        Some(quality) => jpeg_round_trip(&gray, quality),
        None => gray,
    }
}

/// The 8-bit image of grey values.
fn quantise(image: &[f32], width: u32, height: u32) -> GrayImage {
    let bytes: Vec<u8> = image
        .iter()
        .map(|&g| g.round().clamp(0.0, 255.0) as u8)
        .collect();
    GrayImage::from_raw(width, height, bytes).expect("buffer matches the camera size")
}

/// Luma weights of red, green and blue (ITU-R BT.601), as a camera's
/// grey conversion takes them.
const LUMA: [f32; 3] = [0.299, 0.587, 0.114];

/// Each pixel of a grey scene as an RGGB sensor reads it: its one colour
/// through a lens whose red image is magnified by 1 + `aberration` about
/// the centre and the blue by 1 - `aberration`.
fn bayer_mosaic(image: &[f32], width: usize, height: usize, aberration: f64) -> Vec<f32> {
    let (cu, cv) = (0.5 * width as f64 - 0.5, 0.5 * height as f64 - 0.5);
    let mut out = vec![0f32; image.len()];
    out.par_chunks_mut(width)
        .enumerate()
        .for_each(|(row, line)| {
            for (col, px) in line.iter_mut().enumerate() {
                let scale = match (row % 2, col % 2) {
                    (0, 0) => 1.0 / (1.0 + aberration),
                    (1, 1) => 1.0 / (1.0 - aberration),
                    _ => 1.0,
                };
                let (u, v) = (
                    cu + (col as f64 - cu) * scale,
                    cv + (row as f64 - cv) * scale,
                );
                *px = sample(image, width, height, u, v);
            }
        });
    out
}

/// Bilinear demosaicing of an RGGB mosaic, then the grey a camera's
/// luma gives: each missing colour the mean of its nearest samples.
fn demosaic_to_grey(mosaic: &[f32], width: usize, height: usize) -> Vec<f32> {
    let at = |x: isize, y: isize| {
        let (x, y) = (
            x.clamp(0, width as isize - 1) as usize,
            y.clamp(0, height as isize - 1) as usize,
        );
        mosaic[y * width + x]
    };
    let mut out = vec![0f32; mosaic.len()];
    out.par_chunks_mut(width)
        .enumerate()
        .for_each(|(row, line)| {
            let y = row as isize;
            for (col, px) in line.iter_mut().enumerate() {
                let x = col as isize;
                let cross = 0.25 * (at(x - 1, y) + at(x + 1, y) + at(x, y - 1) + at(x, y + 1));
                let diagonal = 0.25
                    * (at(x - 1, y - 1) + at(x + 1, y - 1) + at(x - 1, y + 1) + at(x + 1, y + 1));
                let across = 0.5 * (at(x - 1, y) + at(x + 1, y));
                let along = 0.5 * (at(x, y - 1) + at(x, y + 1));
                let own = at(x, y);
                let [r, g, b] = match (row % 2, col % 2) {
                    (0, 0) => [own, cross, diagonal],
                    (1, 1) => [diagonal, cross, own],
                    // Green on a red row: red left and right, blue above
                    // and below; on a blue row the other way round.
                    (0, _) => [across, own, along],
                    _ => [along, own, across],
                };
                *px = LUMA[0] * r + LUMA[1] * g + LUMA[2] * b;
            }
        });
    out
}

/// The image as a video stream of `factor` times fewer pixels a side
/// shows it, scaled back up: shrunk by area averaging, JPEG-encoded at
/// `quality`, decoded and enlarged bilinearly.
fn video_round_trip(image: &GrayImage, factor: u32, quality: u8) -> GrayImage {
    let (width, height) = (image.width(), image.height());
    let (small_w, small_h) = ((width / factor).max(1), (height / factor).max(1));
    let small = image::imageops::resize(
        image,
        small_w,
        small_h,
        image::imageops::FilterType::Triangle,
    );
    let coded = jpeg_round_trip(&small, quality);
    image::imageops::resize(&coded, width, height, image::imageops::FilterType::Triangle)
}

/// Light falling off linearly across the frame from 1 to 1/gradient.
fn illuminate(scene: &Scene, image: &mut [f32], width: usize) {
    let height = image.len() / width;
    let (sin, cos) = scene.gradient_angle.sin_cos();
    let ratio = scene.gradient.max(1.0);
    let corners = [
        (0.0, 0.0),
        (width as f64, 0.0),
        (0.0, height as f64),
        (width as f64, height as f64),
    ];
    let along = |u: f64, v: f64| u * cos + v * sin;
    let lo = corners
        .iter()
        .map(|&(u, v)| along(u, v))
        .fold(f64::MAX, f64::min);
    let hi = corners
        .iter()
        .map(|&(u, v)| along(u, v))
        .fold(f64::MIN, f64::max);
    let exposure = scene.exposure * FULL_SCALE;
    let shade = |u: f64, v: f64| {
        scene.shades.iter().fold(1.0, |light, s| {
            let outside = ((u - s.u).hypot(v - s.v) - s.radius_px) / s.soft_px.max(1e-9);
            light * (s.factor + (1.0 - s.factor) * outside.clamp(0.0, 1.0))
        })
    };
    image
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(row, line)| {
            for (col, px) in line.iter_mut().enumerate() {
                let t = (along(col as f64 + 0.5, row as f64 + 0.5) - lo) / (hi - lo).max(1e-9);
                let (u, v) = (col as f64 + 0.5, row as f64 + 0.5);
                let mut light = 1.0 - (1.0 - 1.0 / ratio) * t;
                if !scene.shades.is_empty() {
                    light *= shade(u, v);
                }
                *px = (f64::from(*px) * exposure * light) as f32;
            }
        });
}

/// Bilinear sample with edge clamping.
fn sample(image: &[f32], width: usize, height: usize, u: f64, v: f64) -> f32 {
    Plane::new(image, width, height)
        .at(u, v, Border::Clamp)
        .unwrap_or(0.0)
}

/// Average along a centred line segment of `length` pixels.
fn motion_blur(image: &[f32], width: usize, height: usize, length: f64, angle: f64) -> Vec<f32> {
    let taps = (length.ceil() as usize).max(1) * 2 + 1;
    let (sin, cos) = angle.sin_cos();
    let offsets: Vec<(f64, f64)> = (0..taps)
        .map(|k| {
            let t = (k as f64 / (taps - 1) as f64 - 0.5) * length;
            (t * cos, t * sin)
        })
        .collect();
    let mut out = vec![0f32; image.len()];
    out.par_chunks_mut(width)
        .enumerate()
        .for_each(|(row, line)| {
            for (col, px) in line.iter_mut().enumerate() {
                let sum: f32 = offsets
                    .iter()
                    .map(|&(du, dv)| sample(image, width, height, col as f64 + du, row as f64 + dv))
                    .sum();
                *px = sum / taps as f32;
            }
        });
    out
}

/// Above this sigma the exact kernel's cost (six sigma taps a pixel) buys
/// nothing a photograph shows; three box passes take its place.
const EXACT_BLUR_MAX_SIGMA: f64 = 16.0;

/// Separable Gaussian blur with edge clamping: the exact kernel up to
/// [`EXACT_BLUR_MAX_SIGMA`], beyond it three box blurs of the same variance
/// (a constant cost a pixel, so `--blur 500px` takes as long as `--blur 20px`).
pub(crate) fn gaussian_blur(image: &[f32], width: usize, height: usize, sigma: f64) -> Vec<f32> {
    if sigma > EXACT_BLUR_MAX_SIGMA {
        return box_gaussian(image, width, height, sigma);
    }
    let (kernel, radius) = gaussian_kernel(sigma);

    let mut horizontal = vec![0f32; image.len()];
    horizontal
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(row, line)| {
            let src = &image[row * width..(row + 1) * width];
            for (col, px) in line.iter_mut().enumerate() {
                *px = kernel
                    .iter()
                    .enumerate()
                    .map(|(k, w)| {
                        let x = (col as isize + k as isize - radius).clamp(0, width as isize - 1);
                        w * src[x as usize]
                    })
                    .sum();
            }
        });
    let mut out = vec![0f32; image.len()];
    out.par_chunks_mut(width)
        .enumerate()
        .for_each(|(row, line)| {
            for (col, px) in line.iter_mut().enumerate() {
                *px = kernel
                    .iter()
                    .enumerate()
                    .map(|(k, w)| {
                        let y = (row as isize + k as isize - radius).clamp(0, height as isize - 1);
                        w * horizontal[y as usize * width + col]
                    })
                    .sum();
            }
        });
    out
}

/// The normalised Gaussian kernel out to three sigma, and its radius.
fn gaussian_kernel(sigma: f64) -> (Vec<f32>, isize) {
    let radius = (3.0 * sigma).ceil() as isize;
    let mut kernel: Vec<f32> = (-radius..=radius)
        .map(|k| (-(k * k) as f64 / (2.0 * sigma * sigma)).exp() as f32)
        .collect();
    let total: f32 = kernel.iter().sum();
    kernel.iter_mut().for_each(|k| *k /= total);
    (kernel, radius)
}

/// Three box blurs per axis whose summed variance is sigma² (the box sizes
/// of Kovesi's "Fast almost-Gaussian filtering").
fn box_gaussian(image: &[f32], width: usize, height: usize, sigma: f64) -> Vec<f32> {
    const PASSES: f64 = 3.0;
    let ideal = (12.0 * sigma * sigma / PASSES + 1.0).sqrt();
    let mut lower = ideal.floor() as usize;
    if lower.is_multiple_of(2) {
        lower -= 1;
    }
    let l = lower as f64;
    let wide_after = ((12.0 * sigma * sigma - PASSES * l * l - 4.0 * PASSES * l - 3.0 * PASSES)
        / (-4.0 * l - 4.0))
        .round() as usize;
    let radii: Vec<usize> = (0..3)
        .map(|pass| {
            if pass < wide_after {
                lower / 2
            } else {
                lower / 2 + 1
            }
        })
        .collect();
    let mut out = image.to_vec();
    let mut line = Vec::new();
    for &r in &radii {
        out.par_chunks_mut(width)
            .for_each(|row| box_pass(row, r, &mut Vec::new()));
    }
    let mut column = vec![0f32; height];
    for col in 0..width {
        for (row, px) in column.iter_mut().enumerate() {
            *px = out[row * width + col];
        }
        for &r in &radii {
            box_pass(&mut column, r, &mut line);
        }
        for (row, px) in column.iter().enumerate() {
            out[row * width + col] = *px;
        }
    }
    out
}

/// One box blur of radius `r` along `values`, edges clamped, by a running sum.
fn box_pass(values: &mut [f32], r: usize, scratch: &mut Vec<f32>) {
    let n = values.len();
    if n == 0 || r == 0 {
        return;
    }
    scratch.clear();
    scratch.extend_from_slice(values);
    let at = |k: isize| scratch[k.clamp(0, n as isize - 1) as usize] as f64;
    let r = r as isize;
    let mut sum: f64 = (-r..=r).map(at).sum();
    let scale = 1.0 / (2 * r + 1) as f64;
    for (i, v) in values.iter_mut().enumerate() {
        *v = (sum * scale) as f32;
        let i = i as isize;
        sum += at(i + r + 1) - at(i - r);
    }
}

/// Encodes and decodes the image as JPEG at `quality`, giving its artefacts.
pub(crate) fn jpeg_round_trip(image: &GrayImage, quality: u8) -> GrayImage {
    let mut bytes = Vec::new();
    let encoder =
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, quality.clamp(1, 100));
    image
        .write_with_encoder(encoder)
        .expect("JPEG encoding into memory cannot fail");
    image::load_from_memory_with_format(&bytes, image::ImageFormat::Jpeg)
        .expect("a JPEG just encoded decodes")
        .to_luma8()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_blur_keeps_mean_and_smooths_a_step() {
        let (w, h) = (40, 10);
        let image: Vec<f32> = (0..w * h)
            .map(|k| if k % w < 20 { 0.0 } else { 100.0 })
            .collect();
        let blurred = gaussian_blur(&image, w, h, 2.0);
        let mean_in: f32 = image.iter().sum::<f32>() / image.len() as f32;
        let mean_out: f32 = blurred.iter().sum::<f32>() / blurred.len() as f32;
        assert!((mean_in - mean_out).abs() < 0.5);
        // The step at x = 19.5 becomes a ramp through the half-way grey.
        assert!((blurred[5 * w + 19] + blurred[5 * w + 20] - 100.0).abs() < 1.0);
        assert!(blurred[5 * w + 17] > 5.0 && blurred[5 * w + 22] < 95.0);
    }

    #[test]
    fn a_wide_blur_by_boxes_matches_the_exact_kernel_closely() {
        let (w, h) = (400, 3);
        let image: Vec<f32> = (0..w * h)
            .map(|k| if k % w < 200 { 0.0 } else { 100.0 })
            .collect();
        let sigma = 17.0;
        let boxes = box_gaussian(&image, w, h, sigma);
        // The exact kernel at the same sigma, skipping the switch.
        let (kernel, radius) = gaussian_kernel(sigma);
        for x in 150..250 {
            let exact: f64 = kernel
                .iter()
                .enumerate()
                .map(|(k, weight)| {
                    let at = (x as isize + k as isize - radius).clamp(0, w as isize - 1);
                    f64::from(weight * image[at as usize])
                })
                .sum();
            assert!(
                (f64::from(boxes[w + x]) - exact).abs() < 1.0,
                "x {x}: {} vs {exact}",
                boxes[w + x]
            );
        }
    }
}
