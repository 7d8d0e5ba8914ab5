//! The sheet self-check (issue 5): rendered pages are read back by the
//! detector; a sound sheet passes, and a sheet with a wrong, damaged or
//! rotated marker is refused with an error naming that marker.

use crate::support::whycode_in;
use whycode::detect::Target;
use whycode::family::necklace::rotr;
use whycode::family::Family;
use whycode::manifest::FamilyRef;
use whycode::render::check::check_sheet;
use whycode::render::sheet::{family_markers, layout, Sheet, SheetSpec};
use whycode::render::{Item, Template};

fn sheet(bits: u32, distance: u32, ids: &[u32], diameter: f64) -> (Sheet, Family) {
    let family = Family::generate(bits, distance).unwrap();
    let spec = SheetSpec {
        markers: family_markers(&family, ids, diameter).unwrap(),
        template: Template::builtin("a5").unwrap(),
        name: "check".into(),
        family: Some(FamilyRef { bits, distance }),
        legacy: false,
    };
    (layout(&spec).unwrap(), family)
}

/// Replaces the code drawn for the `index`-th marker of page 1 (the
/// manifest keeps the original).
fn redraw(sheet: &mut Sheet, index: usize, code: impl Fn(u32) -> u32) {
    let item = sheet.pages[0]
        .items
        .iter_mut()
        .filter(|i| matches!(i, Item::Marker { .. }))
        .nth(index)
        .unwrap();
    if let Item::Marker { marker, .. } = item {
        if let whycode::geometry::MarkerKind::WhyCode { code: c, .. } = &mut marker.kind {
            *c = code(*c);
        }
    }
}

#[test]
fn sound_sheets_pass_at_print_and_coarse_resolution() {
    for (bits, distance, diameter) in [(8, 2, 30.0), (12, 3, 20.0), (4, 1, 40.0)] {
        let family = Family::generate(bits, distance).unwrap();
        let ids: Vec<u32> = (1..=family.len().min(12) as u32).collect();
        let (sheet, family) = sheet(bits, distance, &ids, diameter);
        let report = check_sheet(&sheet, &Target::WhyCode(family.clone())).unwrap();
        assert_eq!(report.resolutions.len(), 2);
        // The coarse raster makes the markers about 30 px across.
        let coarse_px = diameter / 25.4 * report.resolutions[1];
        assert!((29.0..=31.0).contains(&coarse_px), "{coarse_px}");
        assert_eq!(report.readings, 2 * ids.len());
    }
}

#[test]
fn a_wrong_marker_is_named() {
    let (mut sheet, family) = sheet(8, 2, &[1, 2, 3, 4, 5, 6], 30.0);
    redraw(&mut sheet, 2, |_| family.code(9).unwrap());
    let err = check_sheet(&sheet, &Target::WhyCode(family.clone()))
        .unwrap_err()
        .to_string();
    assert!(err.contains("ID 3 on page 1"), "{err}");
    assert!(err.contains("reads as ID 9"), "{err}");
}

#[test]
fn a_rotated_marker_fails_on_yaw() {
    let (mut sheet, family) = sheet(8, 2, &[1, 2, 3, 4, 5, 6], 30.0);
    // The same necklace turned by one bit: same ID, yaw 45°.
    redraw(&mut sheet, 4, |c| rotr(c, 8, 1));
    let err = check_sheet(&sheet, &Target::WhyCode(family.clone()))
        .unwrap_err()
        .to_string();
    assert!(err.contains("ID 5 on page 1"), "{err}");
    assert!(err.contains("yaw"), "{err}");
}

#[test]
fn a_blotted_ring_is_named() {
    let (mut sheet, family) = sheet(8, 2, &[1, 2, 3, 4, 5, 6], 30.0);
    let (cx, cy) = {
        let m = &sheet.manifest.markers[1];
        (m.x_mm, m.y_mm)
    };
    // A black blot over a third of the ring of ID 2.
    sheet.pages[0].items.push(Item::Rect {
        x: cx,
        y: cy - 9.0,
        width: 9.0,
        height: 9.0,
        grey: 0,
    });
    let err = check_sheet(&sheet, &Target::WhyCode(family.clone()))
        .unwrap_err()
        .to_string();
    assert!(err.contains("ID 2 on page 1"), "{err}");
}

#[test]
fn the_command_checks_by_default_and_says_when_it_does_not() {
    let dir = tempfile::tempdir().unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec![
            "sheet",
            "--bits",
            "10",
            "--ids",
            "1-6",
            "--diameter",
            "25mm",
            "-o",
            "s.pdf",
        ];
        args.extend_from_slice(extra);
        let out = whycode_in(dir.path(), &args);
        assert!(out.status.success());
        String::from_utf8(out.stderr).unwrap()
    };
    let checked = run(&[]);
    assert!(checked.contains("self-check passed"), "{checked}");
    let unchecked = run(&["--no-check"]);
    assert!(unchecked.contains("self-check skipped"), "{unchecked}");
}
