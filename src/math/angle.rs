//! Angle helpers shared by the detector, pose and the simulator.

use std::f64::consts::PI;

/// An axis direction has no sign: fold it into (-π/2, π/2].
pub fn normalize_axis_angle(angle: f64) -> f64 {
    let mut a = angle.rem_euclid(PI);
    if a > PI / 2.0 {
        a -= PI;
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_angles_fold_into_half_open_half_turn() {
        for (angle, folded) in [
            (0.0, 0.0),
            (PI, 0.0),
            (-PI / 2.0, PI / 2.0),
            (2.0, 2.0 - PI),
        ] {
            assert!(
                (normalize_axis_angle(angle) - folded).abs() < 1e-12,
                "{angle}"
            );
        }
        assert_eq!(normalize_axis_angle(PI / 2.0), PI / 2.0);
    }
}
