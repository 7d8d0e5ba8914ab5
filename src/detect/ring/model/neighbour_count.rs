//! The neighbouring-count rule: a ring too small to count its sectors can
//! match a member of a family one bit count off, so a member named is
//! withdrawn when some code of a neighbouring count explains the pixels
//! better.

use super::footprint::RingPixels;
use super::{SmallRing, Thresholds};
use crate::detect::ring::manchester;
use crate::family::Family;

impl RingPixels {
    /// [`RingPixels::compare`], with the member withdrawn (ID 0, no yaw)
    /// when a ring of a neighbouring count fits better.
    pub(super) fn read_of_its_count(
        &self,
        family: &Family,
        thresholds: Thresholds,
    ) -> Option<SmallRing> {
        let read = self.compare(family, thresholds)?;
        let refuted = read.id != 0 && self.neighbour_count_fits_better(family, &read);
        Some(SmallRing {
            id: if refuted { 0 } else { read.id },
            yaw: read.yaw.filter(|_| !refuted),
            ..read
        })
    }

    /// Whether the pixels look more like a ring of a neighbouring bit count
    /// (up to two more or fewer than the family's: any aperiodic code of
    /// that count) than like `read`, the family's best member. A ring too
    /// small to count its sectors otherwise matches a member of the family
    /// one count off (a 9-bit marker 16 px across read as ID 10 of the
    /// 8-bit family). Counts whose codes are too many to compare refute
    /// nothing.
    fn neighbour_count_fits_better(&self, family: &Family, read: &SmallRing) -> bool {
        let bits = family.bits();
        [
            bits.saturating_sub(2),
            bits.saturating_sub(1),
            bits + 1,
            bits + 2,
        ]
        .into_iter()
        .filter(|n| manchester::BITS.contains(n))
        .filter_map(|n| Family::generate(n, 1).ok())
        .filter_map(|every| self.compare_beating(&every, Thresholds::SMALL, Some(read.residual)))
        .any(|other| other.residual < read.residual)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{read_small_ring, read_small_ring_of_its_count, SmallRing};
    use crate::detect::ring::test_images::draw;
    use crate::family::Family;
    use crate::geometry::Marker;

    #[test]
    fn a_member_is_withdrawn_when_a_neighbouring_count_explains_the_ring_better() {
        let eight = Family::generate(8, 2).unwrap();
        // A 9-bit ring 14 px across passes for a member of the 8-bit family
        // until rings of its own count are compared too.
        let nine = Family::generate(9, 2).unwrap();
        let marker = Marker::whycode(9, nine.code(10).unwrap(), 50.0);
        let (image, outline) = draw(&marker, 14.0, 24, (12.3, 11.8), 0.7);
        let read = read_small_ring(&image, &outline, &eight).unwrap();
        assert_eq!(read.id, 10, "{read:?}");
        let withdrawn = read_small_ring_of_its_count(&image, &outline, &eight).unwrap();
        let unnamed = SmallRing {
            id: 0,
            yaw: None,
            ..read
        };
        assert_eq!(withdrawn, unnamed);
        // A ring of the family's own count keeps its member.
        for (id, turn) in [(2, 0.3), (7, 2.0)] {
            let marker = Marker::whycode(8, eight.code(id).unwrap(), 50.0);
            let (image, outline) = draw(&marker, 14.0, 24, (12.3, 11.8), turn);
            let ring = read_small_ring_of_its_count(&image, &outline, &eight).unwrap();
            assert_eq!(ring, read_small_ring(&image, &outline, &eight).unwrap());
            assert_eq!(ring.id, id, "{ring:?}");
        }
    }
}
