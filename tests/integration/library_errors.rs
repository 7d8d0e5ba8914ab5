//! The library's errors as a program calling it sees them: typed, with the
//! values a caller needs, telling a file it could not read from one whose
//! contents are wrong, and worded as the command line prints them.

use std::path::Path;
use whycode::error::{FileKind, LoadError, LoadProblem, WriteError};
use whycode::render::{RenderError, Template};
use whycode::{Camera, Family, Manifest};

fn missing(dir: &Path, name: &str) -> std::path::PathBuf {
    dir.join(name)
}

#[test]
fn every_reader_says_which_file_and_whether_it_could_be_read() {
    let dir = tempfile::tempdir().unwrap();
    let garbage = dir.path().join("garbage.txt");
    std::fs::write(&garbage, "not what anyone wants\n").unwrap();

    type Reader = fn(&Path) -> Result<(), LoadError>;
    let readers: [(FileKind, Reader); 5] = [
        (FileKind::Image, |p| whycode::load_gray(p).map(drop)),
        (FileKind::Family, |p| Family::load(p).map(drop)),
        (FileKind::Manifest, |p| Manifest::load(p).map(drop)),
        (FileKind::Camera, |p| Camera::load(p).map(drop)),
        (FileKind::Template, |p| Template::load(p).map(drop)),
    ];
    for (kind, read) in readers {
        let absent = missing(dir.path(), "absent.file");
        let err = read(&absent).unwrap_err();
        assert_eq!(err.kind, kind);
        assert!(err.is_io(), "{err}");
        assert_eq!(err.path.as_deref(), Some(absent.as_path()));
        let text = err.to_string();
        assert!(
            text.starts_with(&format!(
                "{}: cannot read {}: ",
                absent.display(),
                kind.noun()
            )),
            "{text}"
        );

        let err = read(&garbage).unwrap_err();
        assert_eq!(err.kind, kind);
        assert!(!err.is_io(), "{err}");
        assert!(text_starts_with_file(&err, &garbage), "{kind:?}: {err}");
        assert!(!err.to_string().contains('\n'), "{err}");
    }
}

fn text_starts_with_file(err: &LoadError, path: &Path) -> bool {
    err.to_string()
        .starts_with(&format!("{}: ", path.display()))
}

#[test]
fn an_image_too_large_is_refused_with_its_size() {
    let limit = whycode::image_io::SizeLimit {
        max_side: 20,
        max_pixels: 1_000_000,
    };
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        &[0u8; 30 * 10],
        30,
        10,
        image::ExtendedColorType::L8,
    )
    .unwrap();
    let err = whycode::decode_gray(Path::new("wide.png"), &png, limit).unwrap_err();
    assert!(matches!(
        err.problem,
        LoadProblem::TooLarge {
            width: 30,
            height: 10,
            ..
        }
    ));
}

#[test]
fn render_errors_carry_their_values() {
    let family = Family::generate(8, 2).unwrap();
    let err = whycode::render::sheet::family_markers(&family, &[1, 9999], 40.0).unwrap_err();
    match err {
        RenderError::IdOutOfRange {
            id,
            bits,
            distance,
            count,
        } => assert_eq!((id, bits, distance, count), (9999, 8, 2, family.len())),
        other => panic!("{other}"),
    }
    let err = whycode::render::Format::from_path(Path::new("sheet.docx")).unwrap_err();
    assert_eq!(
        err.to_string(),
        "sheet.docx: unknown output format '.docx' (use .svg, .pdf or .png)"
    );
    let page = whycode::render::marker_page(
        &whycode::Marker::whycon(40.0),
        &whycode::MarkerOptions::default(),
    )
    .unwrap();
    let err = whycode::render::render_page(&page, -3.0).unwrap_err();
    assert!(matches!(err, RenderError::DpiOutOfRange { dpi } if dpi == -3.0));
}

#[test]
fn write_errors_name_the_output_and_refuse_to_overwrite_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("family.json");
    std::fs::write(&input, "{}").unwrap();
    let err = whycode::io::check_outputs(&[input.as_path()], &[input.as_path()]).unwrap_err();
    assert!(
        matches!(err, WriteError::WouldOverwriteInput { .. }),
        "{err}"
    );
    let nowhere = dir.path().join("no/such/folder/out.json");
    let err = whycode::io::write_atomic(&nowhere, b"{}").unwrap_err();
    assert!(matches!(err, WriteError::NoFolder { .. }), "{err}");
    assert!(
        err.to_string()
            .starts_with(&format!("cannot write {}", nowhere.display())),
        "{err}"
    );
}
