//! Photos of a sheet gathered one at a time: what a front end that shows
//! each photo's markers, the coverage and a first fit as the photos come
//! (the page's Calibrate panel) holds between them, before it calibrates
//! them all with [`super::calibrate`].

use super::{calibrate, calibrate_views, observe, sheet_detector};
use super::{Calibration, CalibrationError, CalibrationOptions, Coverage, ViewPoints};
use crate::detect::{Detection, Detector};
use crate::manifest::Manifest;
use image::GrayImage;

/// A sheet's photos, each read once as it is added.
pub struct SheetPhotos {
    manifest: Manifest,
    detector: Detector,
    /// Each photo's name, pixels and first-round detections.
    photos: Vec<(String, GrayImage, Vec<Detection>)>,
}

/// What the photos so far show.
pub struct Preview {
    /// The photos' size, once there is one.
    pub size: Option<(u32, u32)>,
    /// Each view of the sheet (a page in a photo) and its markers.
    pub views: Vec<ViewPoints>,
    /// Markers per ninth of the image.
    pub coverage: Option<Coverage>,
    /// A first fit on the markers' ellipse centres, or why there is none
    /// yet. The calibration re-reads the centres through the camera it
    /// finds, so its RMS comes out lower.
    pub fit: Result<Calibration, CalibrationError>,
}

impl SheetPhotos {
    /// No photo yet of the sheet `manifest` describes (a legacy sheet, or
    /// one without a family, cannot calibrate).
    pub fn new(manifest: Manifest) -> Result<SheetPhotos, CalibrationError> {
        let detector = Detector::new(sheet_detector(&manifest, None)?);
        Ok(SheetPhotos {
            manifest,
            detector,
            photos: Vec::new(),
        })
    }

    /// Reads one photo; returns how many of the sheet's markers its best
    /// view holds. A photo of another size than the first is refused.
    pub fn add(&mut self, name: &str, image: GrayImage) -> Result<usize, CalibrationError> {
        if let Some((first, first_image, _)) = self.photos.first() {
            if first_image.dimensions() != image.dimensions() {
                return Err(CalibrationError::ImageSizes {
                    first: first.clone(),
                    first_size: [first_image.width(), first_image.height()],
                    name: name.to_string(),
                    size: [image.width(), image.height()],
                });
            }
        }
        self.detector.reset();
        let detections = self.detector.detect(&image);
        let views = observe(&self.manifest, name, &detections, 1.0, None);
        self.photos.push((name.to_string(), image, detections));
        Ok(views.iter().map(|v| v.ids.len()).max().unwrap_or(0))
    }

    /// Forgets the photo added `index`-th (from 0), if there is one.
    pub fn remove(&mut self, index: usize) {
        if index < self.photos.len() {
            self.photos.remove(index);
        }
    }

    /// The views, coverage and first fit of the photos so far.
    pub fn preview(&self, options: &CalibrationOptions) -> Preview {
        let views: Vec<ViewPoints> = self
            .photos
            .iter()
            .flat_map(|(name, _, detections)| {
                observe(&self.manifest, name, detections, options.print_scale, None)
            })
            .collect();
        let size = self.photos.first().map(|(_, image, _)| image.dimensions());
        let coverage = size.map(|(width, height)| Coverage::of(&views, width, height));
        let fit = match size {
            Some((width, height)) => calibrate_views(views.clone(), width, height, options),
            None => Err(CalibrationError::TooFewViews {
                usable: 0,
                skipped: Vec::new(),
            }),
        };
        Preview {
            size,
            views,
            coverage,
            fit,
        }
    }

    /// Calibrates from every photo, as [`calibrate`] does.
    pub fn calibrate(&self, options: &CalibrationOptions) -> Result<Calibration, CalibrationError> {
        let photos: Vec<(String, GrayImage)> = self
            .photos
            .iter()
            .map(|(name, image, _)| (name.clone(), image.clone()))
            .collect();
        calibrate(&self.manifest, &photos, options)
    }
}
