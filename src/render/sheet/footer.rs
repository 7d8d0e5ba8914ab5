//! The page footer: a scale bar to check the print against a ruler, and the
//! page caption.

use super::LINE_SPACING;
use crate::render::font::helvetica_width_mm;
use crate::render::page::{Anchor, Item, Page, MM_PER_PT};
use crate::render::template::Template;
use crate::units::trim_float;

/// Height of the page footer (scale bar and page caption) above the bottom margin.
pub(super) const FOOTER_MM: f64 = 11.0;
/// Scale bar thickness and end-tick height, mm.
const BAR_MM: f64 = 0.8;
const TICK_MM: f64 = 2.5;
const TICK_WIDTH_MM: f64 = 0.3;
/// The scale check bar and the page caption along the bottom margin.
pub(super) fn push_footer(
    page: &mut Page,
    template: &Template,
    name: &str,
    number: usize,
    count: usize,
) {
    let left = template.margin_mm;
    let right = template.page_width_mm - template.margin_mm;
    let bottom = template.page_height_mm - template.margin_mm;
    let room = right - left;
    let bar = if template.scale_bar_mm <= room {
        template.scale_bar_mm
    } else {
        // Whole centimetres when the page is too narrow for the asked length.
        ((room / 10.0).floor() * 10.0).max(room.floor().min(10.0))
    };
    page.push(Item::Rect {
        x: left,
        y: bottom - BAR_MM,
        width: bar,
        height: BAR_MM,
        grey: 0,
    });
    for x in [left, left + bar - TICK_WIDTH_MM] {
        page.push(Item::Rect {
            x,
            y: bottom - TICK_MM,
            width: TICK_WIDTH_MM,
            height: TICK_MM,
            grey: 0,
        });
    }
    // Centimetre ticks, so that a ruler can be checked against the bar
    // piece by piece and a wrong scale shows without measuring the whole.
    let mut tick = 10.0;
    while tick < bar - 1.0 {
        page.push(Item::Rect {
            x: left + tick - TICK_WIDTH_MM / 2.0,
            y: bottom - TICK_MM / 2.0,
            width: TICK_WIDTH_MM,
            height: TICK_MM / 2.0,
            grey: 0,
        });
        tick += 10.0;
    }
    let size = template.label_size_pt;
    let baseline = bottom - TICK_MM - 1.2;
    let measure = format!(
        "Print at 100 % (actual size): this bar must measure {} mm",
        trim_float(bar)
    );
    let caption = if name.is_empty() {
        format!("page {number}/{count}")
    } else {
        format!("{name} · page {number}/{count}")
    };
    let caption_baseline =
        if helvetica_width_mm(&measure, size) + helvetica_width_mm(&caption, size) + 5.0 <= room {
            baseline
        } else {
            baseline - LINE_SPACING * size * MM_PER_PT
        };
    page.push(Item::Text {
        x: left,
        y: baseline,
        size_pt: size,
        anchor: Anchor::Start,
        grey: 0,
        text: measure,
    });
    page.push(Item::Text {
        x: right,
        y: caption_baseline,
        size_pt: size,
        anchor: Anchor::End,
        grey: 80,
        text: caption,
    });
}
