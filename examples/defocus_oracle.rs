//! The information bound of the detector bar's defocus row (issue 25),
//! and how near the detector comes to it.
//!
//!     cargo run --release --example defocus_oracle [-- --frames N] [--steps S]
//!
//! For every marker of row 9's scenes (the bar's seeds, `--frames` per
//! cell, 3 by default as `defocus_losses --frames 3`), an ideal reader that
//! is told the marker's true pose, the true defocus and the true noise
//! compares the pixels with every family member at every rotation (steps of
//! 1/S of a half-sector, S = 8 by default), rendered exactly as the
//! simulator renders them: the same rays through 4x4 samples a pixel, the
//! same sampled Gaussian. Blur and light are linear, so a member at a
//! rotation differs from the noise-free render of the scene only by its
//! blurred ring: 255 (ink - paper) G_sigma * (its ring's coverage - the
//! true ring's). The ring is cut into 2n S wedges, each wedge's blurred
//! coverage is formed once, and each member rotation is a sum of wedges,
//! so its squared residual comes from the wedges' Gram matrix.
//!
//! The margin is the log-likelihood ratio LLR = (residual of the best other
//! member at any rotation - residual of the true member's best rotation) /
//! (2 noise sigma^2). The reader names a marker when LLR > 10: a wrong
//! member then has to beat the truth by e^10 in likelihood. The truth's
//! residual per pixel is printed (it must read the noise's variance, 16,
//! plus the rounding's 1/12, or the render is not the simulator's).
//!
//! Beside it, per cell: what the detector names (and names wrongly), and
//! what `model::read_defocused_ring` names on each marker's true outline
//! with the true sigma, and on the detector's outline with the sigma
//! `ellipse::defocus` reads off it (the outline found with
//! `report_unreadable`): so a loss can be told from the information, the
//! model, the outline and the sigma read.

use std::f64::consts::PI;

use whycode::detect::ellipse;
use whycode::detect::ring::model;
use whycode::geometry::{sector_is_black, RING_INNER_RATIO, WHYCODE_WHITE_RATIO};
use whycode::math::{Ellipse, Pcg32, Plane};
use whycode::simulate::{self, match_reports, LooseMarker, Reach, SceneObject, Sighting};
use whycode::{Detector, DetectorConfig, MarkerKind};
use whycode_testkit::scenario::{
    defocused, detector, scene, spread_markers, Families, Print, DEFOCUS_SIGMAS, DEFOCUS_SIZES,
    DEFOCUS_VIEWS,
};

/// The margin (log-likelihood ratio) the ideal reader names a marker with,
/// and a stricter one.
const MARGIN: f64 = 10.0;
const STRICT_MARGIN: f64 = 20.0;

/// A dense patch of pixels at an offset in the frame.
#[derive(Clone)]
struct Patch {
    x0: i64,
    y0: i64,
    w: i64,
    h: i64,
    data: Vec<f64>,
}

impl Patch {
    fn zeros(x0: i64, y0: i64, w: i64, h: i64) -> Patch {
        Patch {
            x0,
            y0,
            w,
            h,
            data: vec![0.0; (w * h) as usize],
        }
    }

    /// The simulator's separable Gaussian (normalised, out to 3 sigma), the
    /// patch grown by the kernel's radius so nothing is cut.
    fn blurred(&self, kernel: &[f64], radius: i64) -> Patch {
        let mut wide = Patch::zeros(self.x0 - radius, self.y0, self.w + 2 * radius, self.h);
        for y in 0..self.h {
            for x in 0..self.w {
                let v = self.data[(y * self.w + x) as usize];
                if v == 0.0 {
                    continue;
                }
                for (k, w) in kernel.iter().enumerate() {
                    // Output at x + k - radius (in self's frame) gets w * v;
                    // the simulator's out[x] = sum_k w_k src[x + k - r], and
                    // the kernel is symmetric.
                    let ox = x + k as i64;
                    wide.data[(y * wide.w + ox) as usize] += w * v;
                }
            }
        }
        let mut out = Patch::zeros(
            self.x0 - radius,
            self.y0 - radius,
            wide.w,
            self.h + 2 * radius,
        );
        for y in 0..wide.h {
            for x in 0..wide.w {
                let v = wide.data[(y * wide.w + x) as usize];
                if v == 0.0 {
                    continue;
                }
                for (k, w) in kernel.iter().enumerate() {
                    let oy = y + k as i64;
                    out.data[(oy * out.w + x) as usize] += w * v;
                }
            }
        }
        out
    }

    fn dot(&self, other: &Patch) -> f64 {
        let x0 = self.x0.max(other.x0);
        let y0 = self.y0.max(other.y0);
        let x1 = (self.x0 + self.w).min(other.x0 + other.w);
        let y1 = (self.y0 + self.h).min(other.y0 + other.h);
        let mut sum = 0.0;
        for y in y0..y1 {
            let a = ((y - self.y0) * self.w - self.x0) as usize;
            let b = ((y - other.y0) * other.w - other.x0) as usize;
            for x in x0..x1 {
                sum += self.data[a + x as usize] * other.data[b + x as usize];
            }
        }
        sum
    }
}

/// The simulator's kernel (f32 there, so rounded the same way).
fn gaussian_kernel(sigma: f64) -> (Vec<f64>, i64) {
    let radius = (3.0 * sigma).ceil() as i64;
    let kernel: Vec<f32> = (-radius..=radius)
        .map(|k| (-(k * k) as f64 / (2.0 * sigma * sigma)).exp() as f32)
        .collect();
    let total: f32 = kernel.iter().sum();
    (
        kernel.iter().map(|k| f64::from(k / total)).collect(),
        radius,
    )
}

/// What the ideal reader makes of one marker.
struct Verdict {
    /// Log-likelihood ratio of the true member (best rotation) over the
    /// best other member; negative when another member fits better.
    margin: f64,
    /// Mean squared residual per pixel of the truth (should read the noise
    /// variance plus the quantisation's 1/12).
    truth_residual: f64,
}

#[allow(clippy::too_many_arguments)]
fn oracle(
    m: &LooseMarker,
    camera: &whycode::Camera,
    codes: &[u32],
    noisy: &image::GrayImage,
    clean: &image::GrayImage,
    sigma: f64,
    noise: f64,
    ink_minus_paper: f64,
    steps: usize,
) -> Verdict {
    let MarkerKind::WhyCode { bits, code } = m.marker.kind else {
        panic!("a WhyCode marker");
    };
    let r_mm = m.marker.outer_radius();
    let placement = &m.placement;
    let rotation_t = placement.rotation.transpose();
    let normal = placement.normal();
    let n_dot_p = normal.dot(&placement.position);
    let rt_p = rotation_t * placement.position;
    // The simulator's always-supersampled box: the projected disc plus 1.5 px.
    let (mut u0, mut v0, mut u1, mut v1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for k in 0..48 {
        let a = k as f64 / 48.0 * std::f64::consts::TAU;
        let (u, v) = camera
            .project(&placement.to_camera_mm(r_mm * a.cos(), r_mm * a.sin()))
            .expect("in front of the camera");
        u0 = u0.min(u);
        v0 = v0.min(v);
        u1 = u1.max(u);
        v1 = v1.max(v);
    }
    let (x0, y0) = (
        (u0 - 1.5).max(0.0).floor() as i64,
        (v0 - 1.5).max(0.0).floor() as i64,
    );
    let (x1, y1) = (
        (u1 + 1.5).min(f64::from(camera.width) - 1.0).ceil() as i64,
        (v1 + 1.5).min(f64::from(camera.height) - 1.0).ceil() as i64,
    );
    let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
    let sectors = 2 * bits as usize;
    let wedges = sectors * steps;
    let wedge_width = PI / f64::from(bits) / steps as f64;
    let mut cover: Vec<Patch> = (0..wedges).map(|_| Patch::zeros(x0, y0, w, h)).collect();
    let n = 4usize;
    let share = 1.0 / (n * n) as f64;
    for row in y0..=y1 {
        for col in x0..=x1 {
            for k in 0..n * n {
                let du = ((k % n) as f64 + 0.5) / n as f64 - 0.5;
                let dv = ((k / n) as f64 + 0.5) / n as f64 - 0.5;
                let x = (col as f64 + du - camera.cx) / camera.fx;
                let y = (row as f64 + dv - camera.cy) / camera.fy;
                let d = nalgebra::Vector3::new(x, y, 1.0);
                let s = n_dot_p / normal.dot(&d);
                let local = (rotation_t * d) * s - rt_p;
                let (lx, ly) = (local.x * 1000.0, local.y * 1000.0);
                let rho = (lx * lx + ly * ly).sqrt() / r_mm;
                if !(RING_INNER_RATIO..=WHYCODE_WHITE_RATIO).contains(&rho) {
                    continue;
                }
                let angle = ly.atan2(lx).rem_euclid(2.0 * PI);
                // The simulator's sector at the true rotation, and the wedge
                // within it (so rotation 0 is exactly the rendered ring).
                let sector = ((angle / (PI / f64::from(bits))) as usize).min(sectors - 1);
                let within = ((angle / wedge_width) as usize)
                    .clamp(sector * steps, sector * steps + steps - 1);
                cover[within].data[((row - y0) * w + col - x0) as usize] += share;
            }
        }
    }
    let (kernel, radius) = gaussian_kernel(sigma);
    let blurred: Vec<Patch> = cover
        .iter()
        .map(|c| {
            let mut b = c.blurred(&kernel, radius);
            b.data
                .iter_mut()
                .for_each(|v| *v *= 255.0 * ink_minus_paper);
            b
        })
        .collect();
    // q = observed - (clean render with a white ring) = noise + true ring.
    let mut q = Patch::zeros(x0 - radius, y0 - radius, w + 2 * radius, h + 2 * radius);
    for y in 0..q.h {
        for x in 0..q.w {
            let (u, v) = (q.x0 + x, q.y0 + y);
            if u < 0 || v < 0 || u >= i64::from(camera.width) || v >= i64::from(camera.height) {
                continue;
            }
            q.data[(y * q.w + x) as usize] = f64::from(noisy.get_pixel(u as u32, v as u32).0[0])
                - f64::from(clean.get_pixel(u as u32, v as u32).0[0]);
        }
    }
    let true_black: Vec<bool> = (0..wedges)
        .map(|j| sector_is_black(bits, code, (j / steps) as u32))
        .collect();
    for (j, b) in blurred.iter().enumerate() {
        if !true_black[j] {
            continue;
        }
        for y in 0..b.h {
            for x in 0..b.w {
                let (qx, qy) = (b.x0 + x - q.x0, b.y0 + y - q.y0);
                q.data[(qy * q.w + qx) as usize] += b.data[(y * b.w + x) as usize];
            }
        }
    }
    // The truth's residual: q minus the true ring.
    let truth_residual = {
        let mut e = q.clone();
        for (j, b) in blurred.iter().enumerate() {
            if !true_black[j] {
                continue;
            }
            for y in 0..b.h {
                for x in 0..b.w {
                    let (qx, qy) = (b.x0 + x - e.x0, b.y0 + y - e.y0);
                    e.data[(qy * e.w + qx) as usize] -= b.data[(y * b.w + x) as usize];
                }
            }
        }
        e.data.iter().map(|v| v * v).sum::<f64>() / e.data.len() as f64
    };
    // Tight boxes of each blurred wedge (the rest is zero).
    let blurred: Vec<Patch> = blurred.into_iter().map(tight).collect();
    let p: Vec<f64> = blurred.iter().map(|b| b.dot(&q)).collect();
    let mut gram = vec![0.0; wedges * wedges];
    for i in 0..wedges {
        for j in i..wedges {
            let g = blurred[i].dot(&blurred[j]);
            gram[i * wedges + j] = g;
            gram[j * wedges + i] = g;
        }
    }
    // Per rotation: half-sector sums.
    let mut best_true = f64::MAX;
    let mut best_other = f64::MAX;
    let mut gs = vec![0.0; sectors * sectors];
    let mut ps = vec![0.0; sectors];
    for shift in 0..wedges {
        // Half-sector s of the rotated pattern holds wedges shift + s*steps + t.
        let wedge = |s: usize, t: usize| (shift + s * steps + t) % wedges;
        for s in 0..sectors {
            ps[s] = (0..steps).map(|t| p[wedge(s, t)]).sum();
            for u in s..sectors {
                let mut g = 0.0;
                for t in 0..steps {
                    let row = wedge(s, t) * wedges;
                    for t2 in 0..steps {
                        g += gram[row + wedge(u, t2)];
                    }
                }
                gs[s * sectors + u] = g;
                gs[u * sectors + s] = g;
            }
        }
        for &c in codes {
            let x: Vec<bool> = (0..sectors as u32)
                .map(|s| sector_is_black(bits, c, s))
                .collect();
            let mut ssd = 0.0;
            for s in 0..sectors {
                if !x[s] {
                    continue;
                }
                ssd -= 2.0 * ps[s];
                for u in 0..sectors {
                    if x[u] {
                        ssd += gs[s * sectors + u];
                    }
                }
            }
            if c == code {
                best_true = best_true.min(ssd);
            } else {
                best_other = best_other.min(ssd);
            }
        }
    }
    Verdict {
        margin: (best_other - best_true) / (2.0 * noise * noise),
        truth_residual,
    }
}

/// The patch cut to its non-zero rows and columns.
fn tight(p: Patch) -> Patch {
    let (mut xa, mut ya, mut xb, mut yb) = (i64::MAX, i64::MAX, i64::MIN, i64::MIN);
    for y in 0..p.h {
        for x in 0..p.w {
            if p.data[(y * p.w + x) as usize] != 0.0 {
                xa = xa.min(x);
                ya = ya.min(y);
                xb = xb.max(x);
                yb = yb.max(y);
            }
        }
    }
    if xa > xb {
        return Patch::zeros(p.x0, p.y0, 0, 0);
    }
    let mut out = Patch::zeros(p.x0 + xa, p.y0 + ya, xb - xa + 1, yb - ya + 1);
    for y in ya..=yb {
        for x in xa..=xb {
            out.data[((y - ya) * out.w + x - xa) as usize] = p.data[(y * p.w + x) as usize];
        }
    }
    out
}

fn arg<T: std::str::FromStr>(args: &[String], name: &str, default: T) -> T {
    args.iter()
        .position(|a| a == name)
        .and_then(|k| args.get(k + 1))
        .and_then(|n| n.parse().ok())
        .unwrap_or(default)
}

/// One cell's tally.
#[derive(Default)]
struct Cell {
    markers: usize,
    named: usize,
    wrong: usize,
    /// Ideal reader: true member ahead (LLR > 0), named at LLR > MARGIN,
    /// at LLR > STRICT_MARGIN, another member ahead by more than MARGIN.
    ahead: usize,
    oracle: usize,
    strict: usize,
    oracle_wrong: usize,
    margins: Vec<f64>,
    /// The model named right: on the true outline with the true sigma, on
    /// the detector's outline with the sigma read; and named wrong (either).
    model_true: usize,
    model_seen: usize,
    model_wrong: usize,
}

/// The model's reading of `outer` through `sigma`: Some(true) named right,
/// Some(false) named wrong, None no ID.
fn model_names(
    image: &image::GrayImage,
    outer: &Ellipse,
    family: &whycode::Family,
    sigma: f64,
    id: u32,
) -> Option<bool> {
    model::read_defocused_ring(image, outer, family, sigma)
        .filter(|ring| ring.structured && ring.id != 0)
        .map(|ring| ring.id == id)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let frames: usize = arg(&args, "--frames", 3);
    let steps: usize = arg(&args, "--steps", 8);
    let fam8 = Families::default().get(8, 2);
    let codes = fam8.codes().to_vec();
    let mut residuals = Vec::new();
    let mut all = Cell::default();
    println!(
        "| size | view | σ | markers | named (wrong) | ideal: true member ahead | ideal, LLR > {MARGIN} | ideal, LLR > {STRICT_MARGIN} | smallest LLR | median LLR | model, true outline and σ | model, outline and σ read |"
    );
    println!("| --- | --- | --- |{}", " ---: |".repeat(9));
    let mut cell_index = 0u64;
    for &size in &DEFOCUS_SIZES {
        for &view in &DEFOCUS_VIEWS {
            for &sigma in &DEFOCUS_SIGMAS {
                // The bar's seeds, so that the cells are the bar's.
                let seed0 = 1_000_000 + 100 * cell_index;
                cell_index += 1;
                let scenario = defocused(&fam8, size, view, sigma, frames, seed0);
                let cam = scenario.camera();
                let mut det = detector(Some(&fam8), &cam, false);
                let mut outlines_of = Detector::new(DetectorConfig {
                    report_unreadable: true,
                    camera: None,
                    ..det.config().clone()
                });
                let mut cell = Cell::default();
                for f in 0..scenario.frames {
                    let frame = scenario.frame(f, Print::WhyCode);
                    // The same scene again (as `Scenario::frame` builds it),
                    // then without noise.
                    let seed = scenario.seed0 + f as u64;
                    let mut rng = Pcg32::new(seed, 1);
                    let objects = spread_markers(&cam, Some(&fam8), scenario.spread, &mut rng);
                    let mut s = scene(&cam, objects, seed);
                    s.background = simulate::Background::Clutter { density: 1.0 };
                    s.noise = 4.0;
                    s.focus_blur_px = sigma;
                    if f == 0 {
                        let (again, _) = simulate::render(&s);
                        assert!(again == frame.image, "the scene rebuilt is the bar's");
                    }
                    let noise = s.noise;
                    s.noise = 0.0;
                    let (clean, _) = simulate::render(&s);
                    let ink_minus_paper = s.ink_reflectance - s.paper_reflectance;
                    let found: Vec<Sighting> = det
                        .detect(&frame.image)
                        .iter()
                        .map(Sighting::from)
                        .collect();
                    let matched = match_reports(&frame.targets, &found, Reach::default());
                    let outlines: Vec<Ellipse> = outlines_of
                        .detect(&frame.image)
                        .iter()
                        .map(|d| Ellipse {
                            u: d.u,
                            v: d.v,
                            semi_major: d.axes[0],
                            semi_minor: d.axes[1],
                            angle: d.angle,
                        })
                        .collect();
                    let gray = Plane::new(
                        frame.image.as_raw().as_slice(),
                        frame.image.width() as usize,
                        frame.image.height() as usize,
                    );
                    for &(t, d) in &matched.pairs {
                        let target = &frame.targets[t];
                        cell.markers += 1;
                        match d.and_then(|d| found[d].id) {
                            Some(id) if id == target.id => cell.named += 1,
                            Some(_) => cell.wrong += 1,
                            None => {}
                        }
                        // The scene's marker at this target.
                        let at = |m: &LooseMarker| {
                            let (u, v) = cam.project(&m.placement.position).expect("in front");
                            (u - target.u).hypot(v - target.v)
                        };
                        let m = s
                            .objects
                            .iter()
                            .filter_map(|o| match o {
                                SceneObject::Marker(m) => Some(m),
                                _ => None,
                            })
                            .min_by(|a, b| at(a).total_cmp(&at(b)))
                            .expect("a marker");
                        assert_eq!(m.id, target.id);
                        let verdict = oracle(
                            m,
                            &cam,
                            &codes,
                            &frame.image,
                            &clean,
                            sigma,
                            noise,
                            ink_minus_paper,
                            steps,
                        );
                        residuals.push(verdict.truth_residual);
                        cell.margins.push(verdict.margin);
                        cell.ahead += usize::from(verdict.margin > 0.0);
                        cell.oracle += usize::from(verdict.margin > MARGIN);
                        cell.strict += usize::from(verdict.margin > STRICT_MARGIN);
                        cell.oracle_wrong += usize::from(-verdict.margin > MARGIN);
                        // The model on the true outline and sigma.
                        let r = m.marker.outer_radius();
                        let points: Vec<(f64, f64)> = (0..64)
                            .map(|k| {
                                let a = k as f64 / 64.0 * std::f64::consts::TAU;
                                cam.project(&m.placement.to_camera_mm(r * a.cos(), r * a.sin()))
                                    .expect("in front")
                            })
                            .collect();
                        let truth = Ellipse::fit(&points).expect("an ellipse");
                        let right = model_names(&frame.image, &truth, &fam8, sigma, target.id);
                        cell.model_true += usize::from(right == Some(true));
                        cell.model_wrong += usize::from(right == Some(false));
                        // On the detector's outline, with the sigma read.
                        let seen = outlines
                            .iter()
                            .filter(|e| (e.u - truth.u).hypot(e.v - truth.v) < 0.3 * target.size_px)
                            .min_by(|a, b| {
                                let off = |e: &Ellipse| (e.u - truth.u).hypot(e.v - truth.v);
                                off(a).total_cmp(&off(b))
                            });
                        let right = seen.and_then(|e| {
                            let read = ellipse::defocus(gray, e)?;
                            model_names(&frame.image, e, &fam8, read, target.id)
                        });
                        cell.model_seen += usize::from(right == Some(true));
                        cell.model_wrong += usize::from(right == Some(false));
                    }
                }
                cell.margins.sort_by(f64::total_cmp);
                println!(
                    "| {size} px | {view}° | {sigma} | {} | {} ({}) | {} | {} | {} | {:.0} | {:.0} | {} | {} |",
                    cell.markers,
                    cell.named,
                    cell.wrong,
                    cell.ahead,
                    cell.oracle,
                    cell.strict,
                    cell.margins[0],
                    cell.margins[cell.margins.len() / 2],
                    cell.model_true,
                    cell.model_seen,
                );
                all.markers += cell.markers;
                all.named += cell.named;
                all.wrong += cell.wrong;
                all.ahead += cell.ahead;
                all.oracle += cell.oracle;
                all.strict += cell.strict;
                all.oracle_wrong += cell.oracle_wrong;
                all.model_true += cell.model_true;
                all.model_seen += cell.model_seen;
                all.model_wrong += cell.model_wrong;
            }
        }
    }
    let pct = |n: usize| format!("{n} ({:.1} %)", 100.0 * n as f64 / all.markers as f64);
    println!(
        "| all | | | {} | {} ({}) | {} | {} | {} | | | {} | {} |",
        all.markers,
        pct(all.named),
        all.wrong,
        pct(all.ahead),
        pct(all.oracle),
        pct(all.strict),
        pct(all.model_true),
        pct(all.model_seen),
    );
    residuals.sort_by(f64::total_cmp);
    println!(
        "\nideal reader: {} markers with another member ahead by LLR > {MARGIN}; the model named {} wrong",
        all.oracle_wrong, all.model_wrong
    );
    println!(
        "the truth's squared residual per pixel: median {:.2}, 5-95 % {:.2}-{:.2} (noise sigma² + 1/12 = {:.2})",
        residuals[residuals.len() / 2],
        residuals[residuals.len() / 20],
        residuals[residuals.len() * 19 / 20],
        16.0 + 1.0 / 12.0
    );
}
