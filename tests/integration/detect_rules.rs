//! The detector's reporting rules (issue 9), as round trips through the
//! simulator: no marker where there is none, no ID from a family of
//! another bit count, the bit count read from the ring in auto mode, and
//! IDs of 8-bit markers down to 12 px.

use std::f64::consts::PI;

use whycode::camera::Camera;
use whycode::detect::{Detection, Detector, DetectorConfig, Target, Unnamed};
use whycode::family::{necklace, Family};
use whycode::geometry::Marker;
use whycode::math::angle::wrap_angle;
use whycode::math::Pcg32;
use whycode::simulate::{
    nearest, render, Background, GroundTruth, LooseMarker, Placement, Scene, SceneObject,
};
use whycode_testkit::desk;
use whycode_testkit::scenes::cast_shadow;

const DIAMETER_M: f64 = 0.05;

fn camera() -> Camera {
    Camera::ideal(640, 480, 60.0)
}

/// One frame of markers: (bits, code, id) each, on a grid.
fn frame(
    markers: &[(u32, u32, u32)],
    diameter_px: f64,
    seed: u64,
) -> (image::GrayImage, GroundTruth) {
    let cam = camera();
    let mut rng = Pcg32::new(seed, 7);
    let mut scene = Scene::new(cam);
    let cols = 4;
    let rows = markers.len().div_ceil(cols);
    for (k, &(bits, code, id)) in markers.iter().enumerate() {
        let u = (k % cols) as f64 * 640.0 / cols as f64 + 80.0;
        let v = (k / cols) as f64 * 480.0 / rows as f64 + 240.0 / rows as f64;
        let tilt = rng.range(0.0, 40.0) * PI / 180.0;
        let roll = rng.range(0.0, 2.0 * PI);
        let marker = Marker::whycode(bits, code, DIAMETER_M * 1000.0);
        let p = Placement::at_pixel(&cam, &marker, (u, v), diameter_px, tilt, 0.0, roll);
        scene
            .objects
            .push(SceneObject::Marker(LooseMarker::new(marker, id, p)));
    }
    scene.noise = 2.0;
    scene.seed = seed;
    render(&scene)
}

fn detector(config: DetectorConfig) -> Detector {
    Detector::new(config)
}

fn with_family(family: &Family) -> Detector {
    detector(DetectorConfig {
        target: Target::WhyCode(family.clone()),
        ..Default::default()
    })
}

#[test]
fn clutter_without_markers_gives_no_report() {
    let cam = Camera::ideal(1280, 720, 60.0);
    let family = Family::generate(8, 2).unwrap();
    for seed in 1..=3 {
        let mut scene = Scene::new(cam);
        scene.background = Background::Clutter { density: 2.0 };
        scene.noise = 2.0;
        scene.seed = seed;
        let (image, _) = render(&scene);
        let found = with_family(&family).detect(&image);
        assert!(found.is_empty(), "seed {seed}, 8-bit family: {found:?}");
        let found = detector(DetectorConfig {
            target: Target::AnyBits { distance: None },
            ..Default::default()
        })
        .detect(&image);
        assert!(found.is_empty(), "seed {seed}, auto bits: {found:?}");
    }
}

#[test]
fn a_legacy_circle_is_reported_by_a_whycode_detector_as_a_marker_without_a_code_ring() {
    // Detection apart from identification: a disc of WhyCon's geometry is a
    // marker whatever its ring says, reported with ID 0 and the reason.
    let cam = camera();
    let mut scene = Scene::new(cam);
    let marker = Marker::whycon(DIAMETER_M * 1000.0);
    let p = Placement::at_pixel(&cam, &marker, (320.0, 240.0), 80.0, 0.3, 0.0, 0.0);
    scene
        .objects
        .push(SceneObject::Marker(LooseMarker::new(marker, 0, p)));
    let (image, _) = render(&scene);
    let family = Family::generate(8, 2).unwrap();
    for report_unreadable in [false, true] {
        let found = detector(DetectorConfig {
            target: Target::WhyCode(family.clone()),
            report_unreadable,
            ..Default::default()
        })
        .detect(&image);
        assert_eq!(found.len(), 1, "{found:?}");
        assert!(!found[0].unreadable && found[0].id == 0, "{found:?}");
        assert_eq!(found[0].unnamed, Some(Unnamed::NoCodeRing), "{found:?}");
    }
    // And legacy settings take it for what it is: no ID by design.
    let legacy = detector(DetectorConfig::default()).detect(&image);
    assert_eq!(legacy.len(), 1);
    assert!(!legacy[0].unreadable && legacy[0].unnamed.is_none());
}

#[test]
fn no_family_of_another_bit_count_names_a_marker() {
    let bit_counts = [4, 6, 8, 10, 12, 14, 16];
    let families: Vec<Family> = bit_counts
        .iter()
        .flat_map(|&bits| (1..=3).map(move |d| Family::generate(bits, d).unwrap()))
        .collect();
    for printed in &families {
        let ids: Vec<u32> = (1..=printed.len().min(3) as u32).collect();
        let markers: Vec<(u32, u32, u32)> = ids
            .iter()
            .map(|&id| (printed.bits(), printed.code(id).unwrap(), id))
            .collect();
        let seed = u64::from(printed.bits() * 10 + printed.distance());
        let (image, truth) = frame(&markers, 90.0, seed);
        // Its own family names them (so the images are readable).
        let own = with_family(printed).detect(&image);
        for m in &truth.markers {
            let d = nearest(&own, (m.u, m.v), 5.0);
            assert_eq!(
                d.map(|d| d.id),
                Some(m.id),
                "{}-bit d={} read with its own family: {own:?}",
                printed.bits(),
                printed.distance()
            );
        }
        for other in families.iter().filter(|f| f.bits() != printed.bits()) {
            let found = with_family(other).detect(&image);
            for d in &found {
                assert_eq!(
                    d.id,
                    0,
                    "{}-bit d={} read as {}-bit d={}: {d:?}",
                    printed.bits(),
                    printed.distance(),
                    other.bits(),
                    other.distance()
                );
                assert_eq!(d.bits, Some(printed.bits()), "{d:?}");
            }
        }
    }
}

/// A ring too fine to be tested for a long family's count may still show
/// its own, coarser count: a 16-bit marker 40 px across at 34° matched a
/// member of the dense 18-bit family before that count was looked for.
#[test]
fn a_ring_showing_a_coarser_count_names_no_member_of_a_long_family() {
    let sixteen = Family::generate(16, 2).unwrap();
    let eighteen = Family::generate(18, 2).unwrap();
    let cam = camera();
    let mut scene = Scene::new(cam);
    let marker = Marker::whycode(16, sixteen.code(4).unwrap(), DIAMETER_M * 1000.0);
    let tilt = 34.455 * PI / 180.0;
    let p = Placement::at_pixel(&cam, &marker, (80.0, 240.0), 40.0, tilt, 0.0, 1.057);
    scene
        .objects
        .push(SceneObject::Marker(LooseMarker::new(marker, 4, p)));
    scene.noise = 2.0;
    scene.seed = 2;
    let (image, _) = render(&scene);
    let own = with_family(&sixteen).detect(&image);
    assert_eq!(own.iter().map(|d| d.id).collect::<Vec<_>>(), [4], "{own:?}");
    let other = with_family(&eighteen).detect(&image);
    for d in &other {
        assert_eq!(d.id, 0, "{d:?}");
        assert_eq!(d.bits, Some(16), "{d:?}");
    }
}

/// A ring too small to count its sectors matched a member of a family one
/// count off: a 9-bit marker 16 px across at 43° read as ID 10 of the
/// 8-bit family, a 4-bit one as ID 3 of the 5-bit family. Any code of a
/// neighbouring count explains such a ring better than the member.
#[test]
fn a_small_ring_of_a_neighbouring_count_names_no_member() {
    let cam = camera();
    // (printed bits, ID, tilt in degrees, roll, seed), read with a family
    // of `read` bits.
    for (bits, id, tilt, roll, seed, read) in
        [(9, 8, 42.669, 3.8375, 3, 8), (4, 1, 46.889, 3.5450, 0, 5)]
    {
        let printed = Family::generate(bits, 2).unwrap();
        let mut scene = Scene::new(cam);
        let marker = Marker::whycode(bits, printed.code(id).unwrap(), DIAMETER_M * 1000.0);
        let tilt = tilt * PI / 180.0;
        let p = Placement::at_pixel(&cam, &marker, (80.0, 400.0), 16.0, tilt, 0.0, roll);
        scene
            .objects
            .push(SceneObject::Marker(LooseMarker::new(marker, id, p)));
        scene.noise = 2.0;
        scene.seed = seed;
        let (image, _) = render(&scene);
        let other = Family::generate(read, 2).unwrap();
        let found = with_family(&other).detect(&image);
        assert!(
            found.iter().all(|d| d.id == 0),
            "{bits}-bit read as {read}-bit: {found:?}"
        );
    }
}

#[test]
fn auto_mode_names_the_bit_count_of_every_marker_in_a_mixed_frame() {
    let mut markers = Vec::new();
    let mut families = Vec::new();
    for bits in [4, 5, 6, 8, 10, 12, 14, 16] {
        let family = Family::generate(bits, 2).unwrap();
        let id = family.len() as u32;
        markers.push((bits, family.code(id).unwrap(), id));
        families.push(family);
    }
    let (image, truth) = frame(&markers, 90.0, 5);
    let found = detector(DetectorConfig {
        target: Target::AnyBits { distance: None },
        ..Default::default()
    })
    .detect(&image);
    assert_eq!(found.len(), truth.markers.len(), "{found:?}");
    for m in &truth.markers {
        let d = nearest(&found, (m.u, m.v), 5.0).expect("found");
        assert_eq!(d.bits, Some(m.bits), "{d:?}");
        assert_eq!(
            d.code,
            Some(necklace::min_rotation(m.code, m.bits).0),
            "{d:?}"
        );
        assert_eq!(d.id, 0, "no distance given: {d:?}");
    }
    // With a distance, each ring's ID in the family of its own length.
    let named = detector(DetectorConfig {
        target: Target::AnyBits { distance: Some(2) },
        ..Default::default()
    })
    .detect(&image);
    for m in &truth.markers {
        let d = nearest(&named, (m.u, m.v), 5.0).expect("found");
        assert_eq!((d.bits, d.id), (Some(m.bits), m.id), "{d:?}");
        assert!(d.yaw.is_some(), "{d:?}");
    }
}

/// Section 3's sizes: named (right ID, yaw from the same fit) and found
/// shares of 8-bit d = 2 markers `diameter_px` across, tilted 0-40
/// degrees, over `frames` frames of 16; panics on any wrong ID.
fn small_marker_rates(diameter_px: f64, frames: u64) -> (f64, f64) {
    let family = Family::generate(8, 2).unwrap();
    let mut rng = Pcg32::new(diameter_px as u64, 2);
    let (mut named, mut found_n, mut total) = (0, 0, 0);
    for seed in 0..frames {
        let markers: Vec<(u32, u32, u32)> = (0..16)
            .map(|_| {
                let id = 1 + rng.next_u32() % family.len() as u32;
                (8, family.code(id).unwrap(), id)
            })
            .collect();
        let (image, truth) = frame(&markers, diameter_px, 300 + seed);
        let found = with_family(&family).detect(&image);
        assert!(
            found.len() <= truth.markers.len(),
            "{diameter_px} px: {} reports for {} markers",
            found.len(),
            truth.markers.len()
        );
        for m in &truth.markers {
            total += 1;
            let Some(d) = nearest(&found, (m.u, m.v), 0.3 * diameter_px + 1.0) else {
                continue;
            };
            found_n += 1;
            assert!(
                d.id == 0 || d.id == m.id,
                "wrong ID at {diameter_px} px: {d:?} for {}",
                m.id
            );
            if d.id == m.id {
                named += 1;
                // An 8-bit ring turns by 22.5 degrees a bit; the yaw comes
                // from the same comparison that named the ID.
                let yaw = d.yaw.expect("a named marker has a yaw");
                let error = wrap_angle(yaw - m.yaw);
                assert!(
                    error.abs() < 15.0 * PI / 180.0,
                    "{diameter_px} px: yaw off by {:.1} deg",
                    error.abs() * 180.0 / PI
                );
            }
        }
    }
    (named as f64 / total as f64, found_n as f64 / total as f64)
}

/// Issue 9, section 3: IDs at 12 px >= 95 % and 10 px >= 75 %, markers
/// found at 8 px >= 75 %, never a wrong ID (measured: 100 / 98 / 85 %;
/// the bounds leave a margin for small changes of the simulator).
#[test]
fn small_markers_are_named_at_10_and_12_px_and_found_at_8_px() {
    let (named_12, _) = small_marker_rates(12.0, 3);
    assert!(named_12 >= 0.95, "12 px: {:.0} % named", 100.0 * named_12);
    let (named_10, _) = small_marker_rates(10.0, 3);
    assert!(named_10 >= 0.8, "10 px: {:.0} % named", 100.0 * named_10);
    let (_, found_8) = small_marker_rates(8.0, 3);
    assert!(found_8 >= 0.75, "8 px: {:.0} % found", 100.0 * found_8);
    eprintln!("named 12 px {named_12:.3}, 10 px {named_10:.3}; found 8 px {found_8:.3}");
}

#[test]
fn eight_bit_ids_are_read_at_12_px_and_never_wrong() {
    let family = Family::generate(8, 2).unwrap();
    let mut rng = Pcg32::new(12, 1);
    let (mut named, mut total) = (0, 0);
    for seed in 0..2 {
        let markers: Vec<(u32, u32, u32)> = (0..16)
            .map(|_| {
                let id = 1 + rng.next_u32() % family.len() as u32;
                (8, family.code(id).unwrap(), id)
            })
            .collect();
        let (image, truth) = frame(&markers, 12.0, 100 + seed);
        let found = with_family(&family).detect(&image);
        for m in &truth.markers {
            total += 1;
            if let Some(d) = nearest(&found, (m.u, m.v), 3.0) {
                assert!(
                    d.id == 0 || d.id == m.id,
                    "wrong ID at 12 px: {d:?} for {}",
                    m.id
                );
                named += usize::from(d.id == m.id);
            }
        }
    }
    assert!(named * 10 >= total * 9, "{named} of {total} named at 12 px");
}

/// The desk frames' reports: (8-bit family, auto bits, legacy) detectors.
fn desk_reports(seed: u64) -> [Vec<Detection>; 3] {
    let image = desk::desk_clutter(seed);
    let family = Family::generate(8, 2).unwrap();
    [
        with_family(&family).detect(&image),
        detector(DetectorConfig {
            target: Target::AnyBits { distance: None },
            ..Default::default()
        })
        .detect(&image),
        detector(DetectorConfig::default()).detect(&image),
    ]
}

#[test]
fn desk_clutter_with_text_and_washers_gives_no_phantom() {
    // Stroke-font 'o' and '0' of every weight, washers with a marker-like
    // hole, blobs with an off-centre hole: none is a WhyCode marker. An
    // 8-bit ring below 10 px has too few pixels per sector to refute every
    // round blob, so the rule holds from 10 px. Legacy WhyCon has no ring
    // to test: the white disc's light must weigh as a printed marker's
    // (area, shape, centre, no lighter than the paper round it), and the
    // black ring must be as large as the original's smallest (100 px),
    // below which a bold 'o' of WhyCon's proportions is a marker to any
    // test. What is left are bold 'o's of 13-14 px (3 in 100 frames,
    // 2 in these 20; 35 in 100 before the floor and the paper test).
    let (mut small, mut legacy) = (0, 0);
    for seed in 1..=20 {
        let [family, auto, whycon] = desk_reports(seed);
        for d in &family {
            assert!(2.0 * d.axes[1] < 10.0, "seed {seed}, 8-bit family: {d:?}");
        }
        small += family.len();
        assert!(auto.is_empty(), "seed {seed}, auto bits: {auto:?}");
        legacy += whycon.len();
    }
    assert!(small <= 1, "{small} small 8-bit phantoms in 20 frames");
    assert!(legacy <= 2, "{legacy} legacy phantoms in 20 frames");
}

/// Issue 25's last phantom: a bold stroke-font 'O' 10.7 x 8.4 px across
/// (10 pt at 3 px/mm, pen 2.4 times the font's, ink grey 50 on paper of
/// reflectance 0.45) was reported as an 8-bit marker without an ID. Its
/// ring is too small for the structure test, and the best of the family's
/// member rotations fits its lopsided hole within the structure ratio; its
/// light, stretched along the outline's major axis as no marker's is,
/// refutes it. The letter still reaches the ring test (it is reported as
/// unreadable on request), so the rule is what drops it.
#[test]
fn a_bold_letter_o_of_eleven_px_is_no_marker() {
    let mut scene = Scene::new(Camera::ideal(1280, 720, 60.0));
    scene.background = Background::Uniform(0.45);
    scene.noise = 2.0;
    scene.seed = 208;
    let (mut image, _) = render(&scene);
    desk::stroke_letters(
        &mut image,
        "O O O 0 0 o o o",
        (100.0, 400.0),
        10.0,
        2.4,
        50.0,
    );
    let family = Family::generate(8, 2).unwrap();
    let found = with_family(&family).detect(&image);
    assert!(found.is_empty(), "{found:?}");
    let refuted = detector(DetectorConfig {
        target: Target::WhyCode(family),
        report_unreadable: true,
        ..Default::default()
    })
    .detect(&image);
    assert!(
        refuted
            .iter()
            .any(|d| d.unreadable && 2.0 * d.axes[0] > 10.0 && (d.u - 102.5).abs() < 2.0),
        "the 'O' no longer reaches the ring test: {refuted:?}"
    );
}

/// Markers of `diameters` pasted on desk clutter, each on its own paper
/// card: the image and where (u, v, diameter px) each marker is.
fn markers_on_desk(
    kind: impl Fn(usize) -> (Marker, u32),
    diameters: &[f64],
    seed: u64,
) -> (image::GrayImage, Vec<(f64, f64, f64, u32)>) {
    let cam = Camera::ideal(1280, 720, 60.0);
    let mut image = desk::desk_clutter(seed);
    let mut scene = Scene::new(cam);
    let mut rng = Pcg32::new(seed, 11);
    let cols = 8;
    for (k, &diameter) in diameters.iter().enumerate() {
        let u = (k % cols) as f64 * 1280.0 / cols as f64 + 80.0;
        let v = (k / cols) as f64 * 180.0 + 90.0;
        let tilt = rng.range(0.0, 30.0) * PI / 180.0;
        let roll = rng.range(0.0, 2.0 * PI);
        let (marker, id) = kind(k);
        let p = Placement::at_pixel(&cam, &marker, (u, v), diameter, tilt, 0.0, roll);
        scene
            .objects
            .push(SceneObject::Marker(LooseMarker::new(marker, id, p)));
    }
    scene.background = Background::Uniform(0.45);
    scene.noise = 2.0;
    scene.seed = seed;
    let (markers, truth) = render(&scene);
    let mut placed = Vec::new();
    for m in &truth.markers {
        // The card reaches 1.5 R from the centre.
        let reach = 0.75 * m.diameter_px;
        let (x0, x1) = ((m.u - reach).floor() as u32, (m.u + reach).ceil() as u32);
        let (y0, y1) = ((m.v - reach).floor() as u32, (m.v + reach).ceil() as u32);
        for y in y0..=y1 {
            for x in x0..=x1 {
                if (f64::from(x) - m.u).hypot(f64::from(y) - m.v) <= reach {
                    image.put_pixel(x, y, *markers.get_pixel(x, y));
                }
            }
        }
        placed.push((m.u, m.v, m.diameter_px, m.id));
    }
    (image, placed)
}

#[test]
fn markers_on_desk_clutter_are_all_reported() {
    let diameters: Vec<f64> = (0..32).map(|k| 14.0 + (k % 8) as f64 * 2.5).collect();
    let family = Family::generate(8, 2).unwrap();
    for seed in [3, 4] {
        let (image, placed) = markers_on_desk(
            |k| {
                let id = 1 + (k as u32 * 7 + seed as u32) % family.len() as u32;
                (
                    Marker::whycode(8, family.code(id).unwrap(), DIAMETER_M * 1000.0),
                    id,
                )
            },
            &diameters,
            seed,
        );
        let found = with_family(&family).detect(&image);
        for &(u, v, diameter, id) in &placed {
            let d = nearest(&found, (u, v), 0.3 * diameter + 1.0);
            assert!(
                d.is_some_and(|d| d.id == id || d.id == 0),
                "seed {seed}: {diameter:.0} px marker {id} at ({u:.0}, {v:.0}): {d:?}"
            );
        }
        let (image, placed) = markers_on_desk(
            |_| (Marker::whycon(DIAMETER_M * 1000.0), 0),
            &diameters,
            seed,
        );
        let found = detector(DetectorConfig::default()).detect(&image);
        for &(u, v, diameter, _) in &placed {
            assert!(
                nearest(&found, (u, v), 0.3 * diameter + 1.0).is_some(),
                "seed {seed}: legacy {diameter:.0} px marker at ({u:.0}, {v:.0})"
            );
        }
    }
}

#[test]
fn a_shadow_edge_across_the_ring_keeps_the_id() {
    // The ring's white half-sectors in the shade fall below its black ones
    // in the light: read as under even light, every bit keeps its edge.
    let family = Family::generate(8, 2).unwrap();
    let mut rng = Pcg32::new(5, 3);
    for case in 0..12u32 {
        let id = 1 + case % family.len() as u32;
        let (mut image, truth) = frame(
            &[(8, family.code(id).unwrap(), id)],
            70.0,
            40 + u64::from(case),
        );
        let m = &truth.markers[0];
        let angle = rng.range(0.0, 2.0 * PI);
        // The edge crosses the ring on one side of the centre or the other.
        let offset = rng.range(-0.3, 0.3) * m.diameter_px / 2.0;
        let through = (m.u - offset * angle.sin(), m.v + offset * angle.cos());
        cast_shadow(&mut image, through, angle, 0.3, 12.0);
        let found = with_family(&family).detect(&image);
        let d = nearest(&found, (m.u, m.v), 5.0);
        assert!(
            d.is_some_and(|d| d.id == id),
            "case {case}: marker {id}, shadow at {offset:.1} px, {:.0}°: {found:?}",
            angle.to_degrees()
        );
    }
}

#[test]
fn bold_letters_of_whycon_proportions_are_mostly_no_legacy_marker() {
    // A stroke-font 'o' drawn with a pen about 0.59 of its half-height has
    // WhyCon's hole ratio, but the pen keeps its width all round: the hole
    // is narrower across than the outline, and its light does not add up
    // to a printed disc's, which the weighing of the white disc shows
    // down to letters of some 12 px; smaller ones are below the original's
    // size floor (of 126 letters 9-16 px tall, 50 pass the edge tests
    // alone, 21 the weighing too, 5 the floor too). A printed legacy
    // marker beside them is always found.
    let cam = Camera::ideal(1280, 720, 60.0);
    let mut letters = 0;
    for (k, size_pt) in [12.0, 14.0, 16.0, 18.0, 20.0, 22.0].into_iter().enumerate() {
        for (j, weight) in [1.9, 2.0, 2.1, 2.2, 2.3, 2.4, 2.5].into_iter().enumerate() {
            let mut scene = Scene::new(cam);
            let marker = Marker::whycon(DIAMETER_M * 1000.0);
            let p = Placement::at_pixel(&cam, &marker, (900.0, 360.0), 40.0, 0.0, 0.0, 0.0);
            scene
                .objects
                .push(SceneObject::Marker(LooseMarker::new(marker, 0, p)));
            scene.background = Background::Uniform(0.85);
            scene.noise = 2.0;
            scene.seed = (10 * k + j) as u64;
            let (mut image, _) = render(&scene);
            desk::stroke_letters(&mut image, "o o o", (100.0, 400.0), size_pt, weight, 30.0);
            let found = detector(DetectorConfig::default()).detect(&image);
            assert!(
                nearest(&found, (900.0, 360.0), 3.0).is_some(),
                "{size_pt} pt, weight {weight}: {found:?}"
            );
            letters += found.len() - 1;
        }
    }
    assert!(
        letters <= 5,
        "{letters} of 126 bold letters taken for markers"
    );
}
