//! Shared by the validate tests: a sheet manifest built in code and a
//! simulated phone photo of it.
#![allow(dead_code)]

use whycode::camera::Camera;
use whycode::family::Family;
use whycode::manifest::{FamilyRef, Manifest, PrintedMarker};
use whycode::simulate::{layout, render, Background, GroundTruth, Scene, SceneObject, SheetPage};
use whycode::validate::Observation;

pub const BITS: u32 = 8;
pub const DISTANCE: u32 = 2;

/// An A4 sheet of twelve 45 mm markers, IDs 1-12, in 3 columns and 4 rows.
pub fn a4_manifest() -> Manifest {
    let family = Family::generate(BITS, DISTANCE).unwrap();
    let markers = (0..12u32)
        .map(|k| PrintedMarker {
            id: k + 1,
            code: family.code(k + 1).unwrap(),
            page: 1,
            x_mm: 40.0 + 65.0 * f64::from(k % 3),
            y_mm: 45.0 + 68.0 * f64::from(k / 3),
            diameter_mm: 45.0,
        })
        .collect();
    Manifest {
        format: "whycode-sheet".into(),
        version: 1,
        tool: "validate test".into(),
        family: Some(FamilyRef {
            bits: BITS,
            distance: DISTANCE,
        }),
        legacy: false,
        template: "a4".into(),
        page_size_mm: [210.0, 297.0],
        pages: 1,
        files: Vec::new(),
        markers,
    }
}

pub struct Photo {
    pub print_scale: f64,
    pub blot_ids: Vec<u32>,
    pub tilt_deg: f64,
    pub pan_deg: f64,
    pub roll_deg: f64,
    pub fill: f64,
}

impl Default for Photo {
    fn default() -> Photo {
        Photo {
            print_scale: 1.0,
            blot_ids: Vec::new(),
            tilt_deg: 25.0,
            pan_deg: 12.0,
            roll_deg: 6.0,
            fill: 0.8,
        }
    }
}

pub fn camera() -> Camera {
    Camera::ideal(2000, 1500, 60.0)
}

/// The sheet as a phone would see it: perspective, focus blur, noise, a 3:1
/// light gradient, JPEG, on a table.
pub fn photo(manifest: &Manifest, p: &Photo) -> (image::GrayImage, GroundTruth) {
    let camera = camera();
    let [w, h] = manifest.page_size_mm;
    let distance = layout::distance_to_fill(&camera, w, h, p.fill);
    let placement = layout::centred(
        distance,
        p.tilt_deg.to_radians(),
        p.pan_deg.to_radians(),
        p.roll_deg.to_radians(),
    );
    let mut page = SheetPage::new(manifest.clone(), 1, placement);
    page.print_scale = p.print_scale;
    for &id in &p.blot_ids {
        let entry = manifest.markers.iter().find(|m| m.id == id).unwrap();
        let marker = SheetPage::marker_of(manifest, entry);
        page.blots
            .extend(layout::ring_blots(&marker, entry.x_mm, entry.y_mm, false));
    }
    let mut scene = Scene::new(camera);
    scene.objects.push(SceneObject::Page(page));
    scene.background = Background::Table;
    scene.gradient = 3.0;
    scene.gradient_angle = 0.5;
    scene.focus_blur_px = 1.2;
    scene.noise = 3.0;
    scene.jpeg_quality = Some(88);
    scene.seed = 5;
    render(&scene)
}

/// Detections as a perfect detector would report them: the true ellipses
/// and IDs.
pub fn ideal_observations(truth: &GroundTruth) -> Vec<Observation> {
    truth
        .markers
        .iter()
        .filter(|m| m.visible)
        .map(|m| {
            let e = m.ellipse.expect("visible markers have an outline");
            Observation {
                id: m.id,
                u: e.u,
                v: e.v,
                semi_major: e.semi_major,
                semi_minor: e.semi_minor,
                angle: e.angle,
                yaw: (m.id != 0).then_some(m.yaw),
            }
        })
        .collect()
}
