//! What lies behind the paper: a plain surface, a table top, or clutter of
//! shapes that look a little like markers but are not.

use super::{Background, Scene};
use crate::math::Pcg32;
use crate::parallel::prelude::*;

const TABLE_REFLECTANCE: f64 = 0.22;
const CLUTTER_BASE_REFLECTANCE: f64 = 0.5;
const TILE: usize = 32;

/// Reflectance image of the background alone.
pub(super) fn render(scene: &Scene, offsets: &[(f64, f64)]) -> Vec<f32> {
    let width = scene.camera.width as usize;
    let height = scene.camera.height as usize;
    match scene.background {
        Background::Uniform(r) => vec![r.clamp(0.0, 1.0) as f32; width * height],
        Background::Table => {
            let texture = ValueNoise::new(scene.seed, 96.0);
            let mut image = vec![0f32; width * height];
            image
                .par_chunks_mut(width)
                .enumerate()
                .for_each(|(row, line)| {
                    for (col, px) in line.iter_mut().enumerate() {
                        *px = table_at(&texture, col as f64, row as f64) as f32;
                    }
                });
            image
        }
        Background::Clutter { density } => {
            let clutter = Clutter::generate(scene.seed, width, height, density);
            let mut image = vec![0f32; width * height];
            image
                .par_chunks_mut(width)
                .enumerate()
                .for_each(|(row, line)| {
                    let v = row as f64;
                    for (col, px) in line.iter_mut().enumerate() {
                        let u = col as f64;
                        let centre = clutter.at(u, v);
                        let uniform = [(-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)]
                            .iter()
                            .all(|&(du, dv)| clutter.at(u + du, v + dv) == centre);
                        *px = if uniform {
                            centre
                        } else {
                            offsets
                                .iter()
                                .map(|&(du, dv)| clutter.at(u + du, v + dv))
                                .sum::<f32>()
                                / offsets.len() as f32
                        };
                    }
                });
            image
        }
    }
}

fn table_at(texture: &ValueNoise, u: f64, v: f64) -> f64 {
    // Grain: stretched noise along u, plus broad blotches.
    let grain = texture.at(u / 6.0, v * 1.5);
    let broad = texture.at(u + 1000.0, v + 1000.0);
    TABLE_REFLECTANCE * (1.0 + 0.12 * grain + 0.15 * broad)
}

/// Smooth lattice noise in [-1, 1] with a feature size of `scale` pixels.
struct ValueNoise {
    seed: u64,
    scale: f64,
}

impl ValueNoise {
    fn new(seed: u64, scale: f64) -> ValueNoise {
        ValueNoise { seed, scale }
    }

    fn lattice(&self, i: i64, j: i64) -> f64 {
        let mut h = self
            .seed
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add((i as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F))
            .wrapping_add((j as u64).wrapping_mul(0x1656_67B1_9E37_79F9));
        h ^= h >> 33;
        h = h.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
        h ^= h >> 33;
        (h >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }

    fn at(&self, u: f64, v: f64) -> f64 {
        let (x, y) = (u / self.scale, v / self.scale);
        let (i, j) = (x.floor(), y.floor());
        let smooth = |t: f64| t * t * (3.0 - 2.0 * t);
        let (tx, ty) = (smooth(x - i), smooth(y - j));
        let (i, j) = (i as i64, j as i64);
        let top = self.lattice(i, j) * (1.0 - tx) + self.lattice(i + 1, j) * tx;
        let bottom = self.lattice(i, j + 1) * (1.0 - tx) + self.lattice(i + 1, j + 1) * tx;
        top * (1.0 - ty) + bottom * ty
    }
}

/// A clutter shape in pixel coordinates.
enum Shape {
    /// Rotated ellipse (circles included); `hole` > 0 cuts a concentric
    /// hole of that ratio, giving rings of the wrong proportions.
    Ellipse {
        cx: f64,
        cy: f64,
        a: f64,
        b: f64,
        cos: f64,
        sin: f64,
        hole: f64,
    },
    /// Rotated rectangle.
    Rect {
        cx: f64,
        cy: f64,
        half_w: f64,
        half_h: f64,
        cos: f64,
        sin: f64,
    },
    /// Thick line segment.
    Line {
        x0: f64,
        y0: f64,
        dx: f64,
        dy: f64,
        half_width: f64,
    },
}

impl Shape {
    fn contains(&self, u: f64, v: f64) -> bool {
        match *self {
            Shape::Ellipse {
                cx,
                cy,
                a,
                b,
                cos,
                sin,
                hole,
            } => {
                let (x, y) = (u - cx, v - cy);
                let (p, q) = (x * cos + y * sin, -x * sin + y * cos);
                let rho = (p / a).powi(2) + (q / b).powi(2);
                rho <= 1.0 && rho >= hole * hole
            }
            Shape::Rect {
                cx,
                cy,
                half_w,
                half_h,
                cos,
                sin,
            } => {
                let (x, y) = (u - cx, v - cy);
                (x * cos + y * sin).abs() <= half_w && (-x * sin + y * cos).abs() <= half_h
            }
            Shape::Line {
                x0,
                y0,
                dx,
                dy,
                half_width,
            } => {
                let len2 = dx * dx + dy * dy;
                let t = (((u - x0) * dx + (v - y0) * dy) / len2).clamp(0.0, 1.0);
                let (ex, ey) = (u - x0 - t * dx, v - y0 - t * dy);
                ex * ex + ey * ey <= half_width * half_width
            }
        }
    }

    fn bounds(&self) -> (f64, f64, f64, f64) {
        match *self {
            Shape::Ellipse { cx, cy, a, .. } => (cx - a, cy - a, cx + a, cy + a),
            Shape::Rect {
                cx,
                cy,
                half_w,
                half_h,
                ..
            } => {
                let r = half_w.hypot(half_h);
                (cx - r, cy - r, cx + r, cy + r)
            }
            Shape::Line {
                x0,
                y0,
                dx,
                dy,
                half_width,
            } => (
                x0.min(x0 + dx) - half_width,
                y0.min(y0 + dy) - half_width,
                x0.max(x0 + dx) + half_width,
                y0.max(y0 + dy) + half_width,
            ),
        }
    }
}

struct Clutter {
    shapes: Vec<(Shape, f32)>,
    tiles: Vec<Vec<u32>>,
    tile_cols: usize,
    tile_rows: usize,
}

impl Clutter {
    fn generate(seed: u64, width: usize, height: usize, density: f64) -> Clutter {
        let mut rng = Pcg32::new(seed, 11);
        let count = (density.max(0.0) * (width * height) as f64 / 10_000.0).round() as usize;
        let (w, h) = (width as f64, height as f64);
        let mut shapes = Vec::with_capacity(count);
        for _ in 0..count {
            let cx = rng.range(0.0, w);
            let cy = rng.range(0.0, h);
            // Log-uniform sizes: many small shapes, a few large ones.
            let size = (rng.range(4f64.ln(), 120f64.ln())).exp();
            let angle = rng.range(0.0, std::f64::consts::PI);
            let (sin, cos) = angle.sin_cos();
            let grey = rng.range(0.02, 0.95) as f32;
            let shape = match rng.next_u32() % 5 {
                0 => Shape::Ellipse {
                    cx,
                    cy,
                    a: size,
                    b: size,
                    cos,
                    sin,
                    hole: 0.0,
                },
                1 => {
                    // A ring whose hole is clearly not a marker's 0.6 (or
                    // WhyCon's 0.41) of the outer radius.
                    let hole = if rng.next_u32().is_multiple_of(2) {
                        rng.range(0.12, 0.3)
                    } else {
                        rng.range(0.75, 0.92)
                    };
                    Shape::Ellipse {
                        cx,
                        cy,
                        a: size,
                        b: size * rng.range(0.5, 1.0),
                        cos,
                        sin,
                        hole,
                    }
                }
                2 => Shape::Rect {
                    cx,
                    cy,
                    half_w: size,
                    half_h: size * rng.range(0.1, 1.0),
                    cos,
                    sin,
                },
                3 => Shape::Line {
                    x0: cx,
                    y0: cy,
                    dx: 3.0 * size * cos,
                    dy: 3.0 * size * sin,
                    half_width: rng.range(0.5, 4.0),
                },
                _ => Shape::Ellipse {
                    cx,
                    cy,
                    a: size,
                    b: size * rng.range(0.2, 0.9),
                    cos,
                    sin,
                    hole: 0.0,
                },
            };
            shapes.push((shape, grey));
        }
        let tile_cols = width.div_ceil(TILE) + 1;
        let tile_rows = height.div_ceil(TILE) + 1;
        let mut tiles = vec![Vec::new(); tile_cols * tile_rows];
        for (k, (shape, _)) in shapes.iter().enumerate() {
            let (x0, y0, x1, y1) = shape.bounds();
            let tile = |p: f64, n: usize| ((p.max(0.0) / TILE as f64) as usize).min(n - 1);
            for ty in tile(y0, tile_rows)..=tile(y1, tile_rows) {
                for tx in tile(x0, tile_cols)..=tile(x1, tile_cols) {
                    tiles[ty * tile_cols + tx].push(k as u32);
                }
            }
        }
        Clutter {
            shapes,
            tiles,
            tile_cols,
            tile_rows,
        }
    }

    fn at(&self, u: f64, v: f64) -> f32 {
        let tx = ((u.max(0.0) / TILE as f64) as usize).min(self.tile_cols - 1);
        let ty = ((v.max(0.0) / TILE as f64) as usize).min(self.tile_rows - 1);
        self.tiles[ty * self.tile_cols + tx]
            .iter()
            .rev()
            .map(|&k| &self.shapes[k as usize])
            .find(|(shape, _)| shape.contains(u, v))
            .map_or(CLUTTER_BASE_REFLECTANCE as f32, |&(_, grey)| grey)
    }
}
