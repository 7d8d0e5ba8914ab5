//! Rendering speed and size: a sheet of 1,000 markers as PDF must take under
//! 1 s and stay under 2 MB (the size is printed once).

use whycode::family::Family;
use whycode::manifest::FamilyRef;
use whycode::render::sheet::{family_markers, layout, SheetSpec};
use whycode::render::{pdf, raster, svg, Template};

fn main() {
    let spec = thousand_markers();
    let sheet = layout(&spec).unwrap();
    let bytes = pdf::pages_pdf(&sheet.pages, "bench").unwrap();
    println!(
        "1,000 markers (14-bit, 15 mm, A4): {} pages, PDF {:.2} MB",
        sheet.pages.len(),
        bytes.len() as f64 / 1e6
    );
    divan::main();
}

fn thousand_markers() -> SheetSpec {
    let family = Family::generate(14, 1).unwrap();
    let ids: Vec<u32> = (1..=1000).collect();
    SheetSpec {
        markers: family_markers(&family, &ids, 15.0).unwrap(),
        template: Template::builtin("a4").unwrap(),
        name: "bench".into(),
        family: Some(FamilyRef {
            bits: 14,
            distance: 1,
        }),
        legacy: false,
    }
}

/// Layout plus PDF encoding of 1,000 markers: the `whycode sheet` path.
#[divan::bench(sample_count = 10)]
fn sheet_1000_pdf() -> usize {
    let sheet = layout(&thousand_markers()).unwrap();
    pdf::pages_pdf(&sheet.pages, "bench").unwrap().len()
}

#[divan::bench(sample_count = 10)]
fn sheet_1000_svg() -> usize {
    let sheet = layout(&thousand_markers()).unwrap();
    sheet
        .pages
        .iter()
        .map(|p| svg::page_svg(p, "bench").len())
        .sum()
}

/// One A4 page rasterised at 300 dpi (what the self-check does per page).
#[divan::bench(sample_count = 10)]
fn a4_page_raster_300dpi(bencher: divan::Bencher) {
    let sheet = layout(&thousand_markers()).unwrap();
    let page = sheet.pages[0].clone();
    bencher.bench(|| raster::render_page(&page, 300.0).unwrap().len());
}
