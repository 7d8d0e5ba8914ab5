//! A calibration as the front ends ask for it: `whycode calibrate`'s
//! options, checked once and built into [`CalibrationOptions`].

use super::{limits, within, SpecError};
use crate::calibrate::{CalibrationOptions, Freedom};

/// What the fit may move and how the sheet was printed. `Default` is the
/// command line's `whycode calibrate` without options: every parameter
/// free, printed at 100 %.
#[derive(Debug, Clone, Default)]
pub struct CalibrateSpec {
    /// Hold the principal point at the image centre.
    pub fix_principal_point: bool,
    /// Square pixels (fy = fx).
    pub fix_aspect: bool,
    /// No tangential terms (p1 = p2 = 0).
    pub no_tangential: bool,
    /// No sixth-order radial term (k3 = 0).
    pub no_k3: bool,
    /// The scale the printer applied, as measured on the sheet's scale bar
    /// (0.97 for a 97 % print); 1 when absent.
    pub print_scale: Option<f64>,
}

impl CalibrateSpec {
    /// Checks every option and builds the calibration's options.
    pub fn build(&self) -> Result<CalibrationOptions, SpecError> {
        let print_scale = within(
            "print_scale",
            self.print_scale.unwrap_or(1.0),
            limits::PRINT_SCALE,
        )?;
        Ok(CalibrationOptions {
            freedom: Freedom {
                fix_principal_point: self.fix_principal_point,
                fix_aspect: self.fix_aspect,
                tangential: !self.no_tangential,
                k3: !self.no_k3,
            },
            print_scale,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_implausible_print_scale_names_its_option() {
        let spec = CalibrateSpec {
            print_scale: Some(97.0),
            ..CalibrateSpec::default()
        };
        let err = spec.build().unwrap_err();
        assert_eq!(
            err.message_with(super::super::cli_option),
            "--print-scale: 97 is outside 0.2 to 5"
        );
        let options = CalibrateSpec {
            print_scale: Some(0.97),
            no_k3: true,
            ..CalibrateSpec::default()
        }
        .build()
        .unwrap();
        assert_eq!(options.print_scale, 0.97);
        assert!(!options.freedom.k3 && options.freedom.tangential);
    }
}
