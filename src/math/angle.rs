//! Angle helpers shared by the detector, pose and the simulator.

use std::f64::consts::{PI, TAU};

/// `value` folded into [-period/2, period/2): a difference of directions
/// that repeat every `period` (radians with 2π, degrees with 360).
pub fn wrap_signed(value: f64, period: f64) -> f64 {
    let half = period / 2.0;
    (value + half).rem_euclid(period) - half
}

/// An angle (radians) folded into [-π, π).
pub fn wrap_angle(angle: f64) -> f64 {
    wrap_signed(angle, TAU)
}

/// The unsigned angle (radians, in [0, π]) between two directions.
pub fn angle_between(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(TAU);
    d.min(TAU - d)
}

/// An axis direction has no sign: fold it into (-π/2, π/2].
pub fn normalize_axis_angle(angle: f64) -> f64 {
    let mut a = angle.rem_euclid(PI);
    if a > PI / 2.0 {
        a -= PI;
    }
    a
}

/// `x.floor() as i64` for the small finite values of a sector index,
/// without the library call `floor` is on targets without SSE4.1.
#[inline]
pub(crate) fn floor_to_int(x: f64) -> i64 {
    let i = x as i64;
    if (i as f64) > x {
        i - 1
    } else {
        i
    }
}

/// `k.rem_euclid(n)` as an index, without the integer division for the
/// values within a turn either side, which are nearly all a ring's
/// sector or sample indices.
#[inline]
pub(crate) fn wrap_index(k: i64, n: i64) -> usize {
    let k = if (0..n).contains(&k) {
        k
    } else if (-n..0).contains(&k) {
        k + n
    } else {
        k.rem_euclid(n)
    };
    k as usize
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

    #[test]
    fn directions_wrap_into_one_turn() {
        assert_eq!(wrap_signed(190.0, 360.0), -170.0);
        assert_eq!(wrap_signed(180.0, 360.0), -180.0);
        assert!((wrap_angle(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-12);
        assert!((angle_between(0.1, TAU - 0.1) - 0.2).abs() < 1e-12);
        assert!((angle_between(-PI / 2.0, PI / 2.0) - PI).abs() < 1e-12);
    }
}
