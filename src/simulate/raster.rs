//! Ray casting of the scene's paper planes into a reflectance image.

use super::{
    background, Blot, LooseMarker, Placement, PrintedSquare, Scene, SceneObject, SheetPage,
};
use crate::camera::Camera;
use crate::geometry::Marker;
use crate::parallel::prelude::*;
use nalgebra::{Matrix3, Vector3};

/// Viewing rays of pixel positions: exact for a distortion-free camera,
/// otherwise bilinear between undistorted rays on a coarse grid (the lens
/// model is smooth, so a 4-pixel grid is accurate to a few thousandths of a
/// pixel and saves inverting the distortion for every sample).
pub(crate) enum RayMap {
    Pinhole {
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
    },
    Grid {
        origin: f64,
        step: f64,
        nx: usize,
        ny: usize,
        rays: Vec<(f64, f64)>,
    },
}

const GRID_STEP: f64 = 4.0;
const GRID_PAD: f64 = 8.0;

impl RayMap {
    pub(crate) fn new(camera: &Camera) -> RayMap {
        if !camera.has_distortion() {
            return RayMap::Pinhole {
                fx: camera.fx,
                fy: camera.fy,
                cx: camera.cx,
                cy: camera.cy,
            };
        }
        let origin = -GRID_PAD;
        let nx = ((f64::from(camera.width) + 2.0 * GRID_PAD) / GRID_STEP).ceil() as usize + 1;
        let ny = ((f64::from(camera.height) + 2.0 * GRID_PAD) / GRID_STEP).ceil() as usize + 1;
        let rays: Vec<(f64, f64)> = (0..nx * ny)
            .into_par_iter()
            .map(|k| {
                let u = origin + (k % nx) as f64 * GRID_STEP;
                let v = origin + (k / nx) as f64 * GRID_STEP;
                camera.undistort(u, v)
            })
            .collect();
        RayMap::Grid {
            origin,
            step: GRID_STEP,
            nx,
            ny,
            rays,
        }
    }

    /// Normalised ideal coordinates (x/z, y/z) of the ray through pixel (u, v).
    #[inline]
    pub(crate) fn ray(&self, u: f64, v: f64) -> (f64, f64) {
        match self {
            RayMap::Pinhole { fx, fy, cx, cy } => ((u - cx) / fx, (v - cy) / fy),
            RayMap::Grid {
                origin,
                step,
                nx,
                ny,
                rays,
            } => {
                let gx = (u - origin) / step;
                let gy = (v - origin) / step;
                // Outside the grid the nearest cell extrapolates linearly.
                let ix = (gx.floor().max(0.0) as usize).min(nx - 2);
                let iy = (gy.floor().max(0.0) as usize).min(ny - 2);
                let tx = gx - ix as f64;
                let ty = gy - iy as f64;
                let at = |i: usize, j: usize| rays[j * nx + i];
                let (a, b, c, d) = (
                    at(ix, iy),
                    at(ix + 1, iy),
                    at(ix, iy + 1),
                    at(ix + 1, iy + 1),
                );
                let lerp2 = |p: f64, q: f64, r: f64, s: f64| {
                    (p * (1.0 - tx) + q * tx) * (1.0 - ty) + (r * (1.0 - tx) + s * tx) * ty
                };
                (lerp2(a.0, b.0, c.0, d.0), lerp2(a.1, b.1, c.1, d.1))
            }
        }
    }
}

/// What a plane shows at a point of its own frame (mm).
enum Content<'a> {
    Loose(&'a LooseMarker),
    Square(&'a PrintedSquare),
    Page(PageContent<'a>),
}

/// A page's markers bucketed on a grid, so a lookup tests only nearby ones.
struct PageContent<'a> {
    page: &'a SheetPage,
    half_w: f64,
    half_h: f64,
    cell: f64,
    cols: usize,
    rows: usize,
    buckets: Vec<Vec<usize>>,
    markers: Vec<(Marker, f64, f64)>,
    /// The page's other printed items, rasterised at [`DECOR_PX_PER_MM`].
    decor: Option<image::GrayImage>,
}

/// Resolution of the printed labels and scale bar: 7 pt capitals are 17 px
/// tall, finer than any camera sees them.
const DECOR_PX_PER_MM: f64 = 10.0;

impl<'a> PageContent<'a> {
    fn new(page: &'a SheetPage) -> PageContent<'a> {
        let manifest = &page.manifest;
        let [w, h] = manifest.page_size_mm;
        let markers: Vec<(Marker, f64, f64)> = manifest
            .markers
            .iter()
            .filter(|m| m.page == page.page)
            .map(|m| (SheetPage::marker_of(manifest, m), m.x_mm, m.y_mm))
            .collect();
        let largest = markers
            .iter()
            .map(|m| m.0.diameter_mm)
            .fold(10.0f64, f64::max);
        let cell = largest;
        let cols = (w / cell).ceil().max(1.0) as usize;
        let rows = (h / cell).ceil().max(1.0) as usize;
        let mut buckets = vec![Vec::new(); cols * rows];
        for (k, (marker, x, y)) in markers.iter().enumerate() {
            let r = marker.outer_radius();
            let c0 = (((x - r) / cell).floor().max(0.0) as usize).min(cols - 1);
            let c1 = (((x + r) / cell).floor().max(0.0) as usize).min(cols - 1);
            let r0 = (((y - r) / cell).floor().max(0.0) as usize).min(rows - 1);
            let r1 = (((y + r) / cell).floor().max(0.0) as usize).min(rows - 1);
            for row in r0..=r1 {
                for col in c0..=c1 {
                    buckets[row * cols + col].push(k);
                }
            }
        }
        PageContent {
            page,
            half_w: w / 2.0,
            half_h: h / 2.0,
            cell,
            cols,
            rows,
            buckets,
            markers,
            decor: page
                .decor
                .as_ref()
                .and_then(|d| crate::render::raster::render_page(d, DECOR_PX_PER_MM * 25.4).ok()),
        }
    }

    /// Ink at intended page coordinates (mm from the top-left, y down).
    fn is_black(&self, qx: f64, qy: f64) -> bool {
        if let Some(black) = blot_at(&self.page.blots, qx, qy) {
            return black;
        }
        if qx < 0.0 || qy < 0.0 {
            return false;
        }
        if let Some(decor) = &self.decor {
            let (px, py) = ((qx * DECOR_PX_PER_MM) as u32, (qy * DECOR_PX_PER_MM) as u32);
            if px < decor.width() && py < decor.height() && decor.get_pixel(px, py).0[0] < 128 {
                return true;
            }
        }
        let col = (qx / self.cell) as usize;
        let row = (qy / self.cell) as usize;
        if col >= self.cols || row >= self.rows {
            return false;
        }
        self.buckets[row * self.cols + col].iter().any(|&k| {
            let (marker, mx, my) = &self.markers[k];
            marker.is_black_at(qx - mx, my - qy)
        })
    }
}

fn blot_at(blots: &[Blot], x: f64, y: f64) -> Option<bool> {
    // The last blot painted wins.
    blots
        .iter()
        .rev()
        .find(|b| (x - b.x_mm).powi(2) + (y - b.y_mm).powi(2) <= b.radius_mm * b.radius_mm)
        .map(|b| b.black)
}

/// One paper plane, ready to intersect with viewing rays.
struct PlaneSampler<'a> {
    rotation_t: Matrix3<f64>,
    rotation_t_position: Vector3<f64>,
    normal: Vector3<f64>,
    normal_dot_position: f64,
    content: Content<'a>,
    paper: f32,
    ink: f32,
}

impl<'a> PlaneSampler<'a> {
    fn new(placement: &Placement, content: Content<'a>, scene: &Scene) -> PlaneSampler<'a> {
        let rotation_t = placement.rotation.transpose();
        let normal = placement.normal();
        PlaneSampler {
            rotation_t,
            rotation_t_position: rotation_t * placement.position,
            normal,
            normal_dot_position: normal.dot(&placement.position),
            content,
            paper: scene.paper_reflectance as f32,
            ink: scene.ink_reflectance as f32,
        }
    }

    /// Reflectance where the ray (x, y, 1) meets this plane, `None` if it
    /// misses the paper.
    #[inline]
    fn hit(&self, x: f64, y: f64) -> Option<f32> {
        let d = Vector3::new(x, y, 1.0);
        let nd = self.normal.dot(&d);
        if nd.abs() < 1e-12 {
            return None;
        }
        let s = self.normal_dot_position / nd;
        if s <= 0.0 {
            return None;
        }
        let local = (self.rotation_t * d) * s - self.rotation_t_position;
        let (lx, ly) = (local.x * 1000.0, local.y * 1000.0);
        // The camera is on the printed side when the normal points at it.
        let front = self.normal_dot_position < 0.0;
        let black = match &self.content {
            Content::Loose(m) => {
                if lx.abs() > m.card_half_mm || ly.abs() > m.card_half_mm {
                    return None;
                }
                front && blot_at(&m.blots, lx, ly).unwrap_or_else(|| m.marker.is_black_at(lx, ly))
            }
            Content::Square(q) => {
                if lx.abs() > q.card_half_mm || ly.abs() > q.card_half_mm {
                    return None;
                }
                front && q.is_black_at(lx, ly)
            }
            Content::Page(p) => {
                if lx.abs() > p.half_w || ly.abs() > p.half_h {
                    return None;
                }
                let s = p.page.print_scale;
                let qx = p.half_w + lx / s;
                let qy = p.half_h - ly / s;
                front && p.is_black(qx, qy)
            }
        };
        Some(if black { self.ink } else { self.paper })
    }
}

/// Pixel rectangle, inclusive bounds.
#[derive(Debug, Clone, Copy)]
struct PixelBox {
    x0: usize,
    y0: usize,
    x1: usize,
    y1: usize,
}

/// Pixel bounding box of projected object-frame points (mm); the whole
/// frame when some point cannot be projected (it crosses the camera plane).
fn project_box(
    camera: &Camera,
    placement: &Placement,
    outline: impl Iterator<Item = (f64, f64)>,
    pad: f64,
) -> Option<PixelBox> {
    let (w, h) = (f64::from(camera.width), f64::from(camera.height));
    let (mut u0, mut v0, mut u1, mut v1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for (x, y) in outline {
        match camera.project(&placement.to_camera_mm(x, y)) {
            Some((u, v)) if u.is_finite() && v.is_finite() => {
                u0 = u0.min(u);
                v0 = v0.min(v);
                u1 = u1.max(u);
                v1 = v1.max(v);
            }
            _ => {
                u0 = 0.0;
                v0 = 0.0;
                u1 = w;
                v1 = h;
                break;
            }
        }
    }
    let (u0, v0) = ((u0 - pad).max(0.0), (v0 - pad).max(0.0));
    let (u1, v1) = ((u1 + pad).min(w - 1.0), (v1 + pad).min(h - 1.0));
    if u0 > u1 || v0 > v1 {
        return None;
    }
    Some(PixelBox {
        x0: u0.floor() as usize,
        y0: v0.floor() as usize,
        x1: u1.ceil() as usize,
        y1: v1.ceil() as usize,
    })
}

fn rectangle_outline(half_w: f64, half_h: f64) -> impl Iterator<Item = (f64, f64)> {
    const STEPS: usize = 32;
    (0..4 * STEPS).map(move |k| {
        let t = (k % STEPS) as f64 / STEPS as f64 * 2.0 - 1.0;
        match k / STEPS {
            0 => (t * half_w, -half_h),
            1 => (half_w, t * half_h),
            2 => (-t * half_w, half_h),
            _ => (-half_w, -t * half_h),
        }
    })
}

fn circle_outline(cx: f64, cy: f64, r: f64) -> impl Iterator<Item = (f64, f64)> {
    const STEPS: usize = 48;
    (0..STEPS).map(move |k| {
        let a = k as f64 / STEPS as f64 * std::f64::consts::TAU;
        (cx + r * a.cos(), cy + r * a.sin())
    })
}

/// Sub-pixel sample offsets of an n×n stratified pattern.
fn sample_offsets(n: u32) -> Vec<(f64, f64)> {
    let n = n.max(1);
    let step = 1.0 / f64::from(n);
    (0..n * n)
        .map(|k| {
            (
                (f64::from(k % n) + 0.5) * step - 0.5,
                (f64::from(k / n) + 0.5) * step - 0.5,
            )
        })
        .collect()
}

/// Reflectance image (0..1, row-major) of the whole scene.
pub(crate) fn render_reflectance(scene: &Scene) -> Vec<f32> {
    let camera = &scene.camera;
    let width = camera.width as usize;
    let rays = RayMap::new(camera);
    let offsets = sample_offsets(scene.supersampling);
    let mut image = background::render(scene, &offsets);

    // Painter's order: farthest first, so nearer paper covers it.
    let mut order: Vec<&SceneObject> = scene.objects.iter().collect();
    order.sort_by(|a, b| object_depth(b).total_cmp(&object_depth(a)));

    for object in order {
        let (placement, content, outline, details): (_, _, Vec<(f64, f64)>, Vec<PixelBox>) =
            match object {
                SceneObject::Marker(m) => {
                    let outline = rectangle_outline(m.card_half_mm, m.card_half_mm).collect();
                    let detail = project_box(
                        camera,
                        &m.placement,
                        circle_outline(0.0, 0.0, m.marker.outer_radius()),
                        1.5,
                    );
                    (
                        &m.placement,
                        Content::Loose(m),
                        outline,
                        detail.into_iter().collect(),
                    )
                }
                SceneObject::Square(q) => {
                    let outline = rectangle_outline(q.card_half_mm, q.card_half_mm).collect();
                    // Cells can be thinner than the uniformity test sees.
                    let half = q.side_mm / 2.0;
                    let detail =
                        project_box(camera, &q.placement, rectangle_outline(half, half), 1.5);
                    (
                        &q.placement,
                        Content::Square(q),
                        outline,
                        detail.into_iter().collect(),
                    )
                }
                SceneObject::Page(p) => {
                    let [w, h] = p.manifest.page_size_mm;
                    let outline = rectangle_outline(w / 2.0, h / 2.0).collect();
                    let s = p.print_scale;
                    let details = p
                        .manifest
                        .markers
                        .iter()
                        .filter(|m| m.page == p.page)
                        .filter_map(|m| {
                            // Page frame: origin at the centre, y up.
                            let x = (m.x_mm - w / 2.0) * s;
                            let y = -(m.y_mm - h / 2.0) * s;
                            let r = m.diameter_mm / 2.0 * s;
                            project_box(camera, &p.placement, circle_outline(x, y, r), 1.5)
                        })
                        .collect();
                    (
                        &p.placement,
                        Content::Page(PageContent::new(p)),
                        outline,
                        details,
                    )
                }
            };
        let Some(bounds) = project_box(camera, placement, outline.into_iter(), 2.0) else {
            continue;
        };
        let sampler = PlaneSampler::new(placement, content, scene);
        let detail_mask = DetailMask::new(bounds, &details);
        image
            .par_chunks_mut(width)
            .enumerate()
            .skip(bounds.y0)
            .take(bounds.y1 - bounds.y0 + 1)
            .for_each(|(row, line)| {
                let v = row as f64;
                for (col, px) in line
                    .iter_mut()
                    .enumerate()
                    .take(bounds.x1 + 1)
                    .skip(bounds.x0)
                {
                    let u = col as f64;
                    let below = *px;
                    let sample = |du: f64, dv: f64| {
                        let (x, y) = rays.ray(u + du, v + dv);
                        sampler.hit(x, y)
                    };
                    if !detail_mask.contains(col, row) {
                        let centre = sample(0.0, 0.0);
                        let uniform = [(-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)]
                            .iter()
                            .all(|&(du, dv)| sample(du, dv) == centre);
                        if uniform {
                            if let Some(r) = centre {
                                *px = r;
                            }
                            continue;
                        }
                    }
                    let sum: f32 = offsets
                        .iter()
                        .map(|&(du, dv)| sample(du, dv).unwrap_or(below))
                        .sum();
                    *px = sum / offsets.len() as f32;
                }
            });
    }
    image
}

fn object_depth(object: &SceneObject) -> f64 {
    match object {
        SceneObject::Marker(m) => m.placement.position.norm(),
        SceneObject::Page(p) => p.placement.position.norm(),
        SceneObject::Square(q) => q.placement.position.norm(),
    }
}

/// Pixels that are always supersampled: marker discs and printed squares, whose ring sectors
/// can be thinner than the five-point uniformity test can see.
struct DetailMask {
    bounds: PixelBox,
    stride: usize,
    bits: Vec<bool>,
}

impl DetailMask {
    fn new(bounds: PixelBox, details: &[PixelBox]) -> DetailMask {
        let stride = bounds.x1 - bounds.x0 + 1;
        let rows = bounds.y1 - bounds.y0 + 1;
        let mut bits = vec![false; stride * rows];
        for d in details {
            let (x0, x1) = (d.x0.max(bounds.x0), d.x1.min(bounds.x1));
            let (y0, y1) = (d.y0.max(bounds.y0), d.y1.min(bounds.y1));
            if x0 > x1 || y0 > y1 {
                continue;
            }
            for y in y0..=y1 {
                let base = (y - bounds.y0) * stride;
                bits[base + x0 - bounds.x0..=base + x1 - bounds.x0].fill(true);
            }
        }
        DetailMask {
            bounds,
            stride,
            bits,
        }
    }

    fn contains(&self, x: usize, y: usize) -> bool {
        self.bits[(y - self.bounds.y0) * self.stride + x - self.bounds.x0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_rays_match_exact_undistortion() {
        let mut camera = Camera::ideal(640, 480, 70.0);
        camera.distortion = [-0.25, 0.08, 0.001, -0.0005, 0.0];
        let map = RayMap::new(&camera);
        for &(u, v) in &[(0.0, 0.0), (320.3, 240.7), (639.0, 479.0), (13.25, 401.5)] {
            let (x, y) = map.ray(u, v);
            let (ex, ey) = camera.undistort(u, v);
            // Back to pixels: the interpolation error must stay far below a pixel.
            assert!(((x - ex) * camera.fx).abs() < 0.01, "u={u} v={v}");
            assert!(((y - ey) * camera.fy).abs() < 0.01, "u={u} v={v}");
        }
    }
}
