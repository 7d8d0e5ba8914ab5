//! numpy arrays in, grey frames out.
//!
//! A C-contiguous uint8 HxW array is read where it lies; everything else
//! (views with strides, Fortran order, uint16, BGR, BGRA) is gathered into
//! a buffer and turned grey by the same function the CLI's image loader
//! uses, so an array and the file it came from give the same detections.

use crate::Error;
use image::{DynamicImage, ImageBuffer, Luma};
use numpy::{
    PyArrayDescrMethods, PyArrayMethods, PyReadonlyArray2, PyReadonlyArray3, PyReadonlyArrayDyn,
    PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use whycode::image_io::{to_gray as loader_gray, MAX_PIXELS, MAX_SIDE};

pub(crate) type GrayView<'a> = ImageBuffer<Luma<u8>, &'a [u8]>;

#[derive(Clone, Copy, PartialEq, Eq)]
enum Depth {
    U8,
    U16,
}

/// The array's layout, checked: height, width, channels (1, 3 or 4) and depth.
struct Layout {
    height: u32,
    width: u32,
    channels: usize,
    depth: Depth,
}

fn layout(array: &Bound<'_, PyUntypedArray>) -> PyResult<Layout> {
    let py = array.py();
    let dtype = array.dtype();
    let depth = if dtype.is_equiv_to(&numpy::dtype::<u8>(py)) {
        Depth::U8
    } else if dtype.is_equiv_to(&numpy::dtype::<u16>(py)) {
        Depth::U16
    } else {
        return Err(Error::value(format!(
            "image: arrays of dtype {} are not supported; pass uint8 or uint16 (for floats in 0..1: (image * 255).round().astype(numpy.uint8))",
            dtype.str()?
        ))
        .into());
    };
    let shape = array.shape();
    let (height, width, channels) = match *shape {
        [h, w] => (h, w, 1),
        [h, w, c] if matches!(c, 1 | 3 | 4) => (h, w, c),
        _ => {
            return Err(Error::value(format!(
                "image: an array of shape {shape:?} is not an image; pass HxW grey, HxWx3 BGR or HxWx4 BGRA"
            ))
            .into())
        }
    };
    if height > MAX_SIDE as usize
        || width > MAX_SIDE as usize
        || (height as u64) * (width as u64) > MAX_PIXELS
    {
        return Err(Error::value(format!(
            "image: {width}x{height} pixels is larger than the supported {MAX_SIDE} px a side and {} megapixels",
            MAX_PIXELS / 1_000_000
        ))
        .into());
    }
    Ok(Layout {
        height: height as u32,
        width: width as u32,
        channels,
        depth,
    })
}

/// Grey pixels of a layout gathered in row-major order (BGR(A) reordered to
/// RGB(A)), converted as the image loader converts a decoded file.
fn to_gray<T: Copy>(
    values: impl Iterator<Item = T>,
    layout: &Layout,
    build: fn(u32, u32, Vec<T>, usize) -> Option<DynamicImage>,
) -> image::GrayImage {
    let mut data: Vec<T> = values.collect();
    if layout.channels >= 3 {
        for pixel in data.chunks_exact_mut(layout.channels) {
            pixel.swap(0, 2);
        }
    }
    let decoded = build(layout.width, layout.height, data, layout.channels)
        .expect("buffer length matches the checked shape");
    loader_gray(decoded)
}

fn build_u8(w: u32, h: u32, data: Vec<u8>, channels: usize) -> Option<DynamicImage> {
    Some(match channels {
        1 => DynamicImage::ImageLuma8(ImageBuffer::from_raw(w, h, data)?),
        3 => DynamicImage::ImageRgb8(ImageBuffer::from_raw(w, h, data)?),
        _ => DynamicImage::ImageRgba8(ImageBuffer::from_raw(w, h, data)?),
    })
}

fn build_u16(w: u32, h: u32, data: Vec<u16>, channels: usize) -> Option<DynamicImage> {
    Some(match channels {
        1 => DynamicImage::ImageLuma16(ImageBuffer::from_raw(w, h, data)?),
        3 => DynamicImage::ImageRgb16(ImageBuffer::from_raw(w, h, data)?),
        _ => DynamicImage::ImageRgba16(ImageBuffer::from_raw(w, h, data)?),
    })
}

/// Runs `work` on the grey frame of `image` with the GIL released.
pub(crate) fn with_gray<R: Send>(
    py: Python<'_>,
    image: &Bound<'_, PyAny>,
    work: impl FnOnce(&GrayView<'_>) -> crate::Result<R> + Send,
) -> PyResult<R> {
    let array = image.cast::<PyUntypedArray>().map_err(|_| {
        Error::value(format!(
            "image: expected a numpy array, got {}",
            image
                .get_type()
                .name()
                .map_or("an object".to_string(), |n| n.to_string())
        ))
    })?;
    let layout = layout(array)?;
    let (w, h) = (layout.width, layout.height);
    let result = if layout.depth == Depth::U8 && layout.channels == 1 && array.is_c_contiguous() {
        let grey: PyReadonlyArrayDyn<'_, u8> = array.extract()?;
        let slice = grey.as_slice().map_err(|e| Error::value(e.to_string()))?;
        py.detach(|| {
            crate::guard(|| {
                let view = ImageBuffer::from_raw(w, h, slice).expect("checked shape");
                work(&view)
            })
        })
    } else if layout.depth == Depth::U8 {
        gathered::<u8, R>(py, array, &layout, build_u8, work)
    } else {
        gathered::<u16, R>(py, array, &layout, build_u16, work)
    };
    Ok(result?)
}

/// Non-contiguous or converted input: the pixels gathered in logical order
/// (typed 2-D and 3-D views iterate far faster than dynamic ones).
fn gathered<T: numpy::Element + Copy + Send + Sync, R: Send>(
    py: Python<'_>,
    array: &Bound<'_, PyUntypedArray>,
    layout: &Layout,
    build: fn(u32, u32, Vec<T>, usize) -> Option<DynamicImage>,
    work: impl FnOnce(&GrayView<'_>) -> crate::Result<R> + Send,
) -> crate::Result<R> {
    if array.ndim() == 2 {
        let values: PyReadonlyArray2<'_, T> = array
            .extract()
            .map_err(|e| Error::value(PyErr::from(e).to_string()))?;
        let view = values.as_array();
        py.detach(|| {
            crate::guard(|| {
                let gray = to_gray(view.iter().copied(), layout, build);
                work(&as_view(&gray))
            })
        })
    } else {
        let values: PyReadonlyArray3<'_, T> = array
            .extract()
            .map_err(|e| Error::value(PyErr::from(e).to_string()))?;
        let view = values.as_array();
        py.detach(|| {
            crate::guard(|| {
                let gray = to_gray(view.iter().copied(), layout, build);
                work(&as_view(&gray))
            })
        })
    }
}

fn as_view(gray: &image::GrayImage) -> GrayView<'_> {
    ImageBuffer::from_raw(gray.width(), gray.height(), gray.as_raw().as_slice()).expect("same size")
}

/// An owned grey frame of `image` (for work that keeps it, like validation).
pub(crate) fn gray_image(py: Python<'_>, image: &Bound<'_, PyAny>) -> PyResult<image::GrayImage> {
    with_gray(py, image, |view| {
        Ok(
            image::GrayImage::from_raw(view.width(), view.height(), view.as_raw().to_vec())
                .expect("same size"),
        )
    })
}

/// A grey image as a new HxW uint8 array.
pub(crate) fn to_array<'py>(
    py: Python<'py>,
    image: image::GrayImage,
) -> PyResult<Bound<'py, numpy::PyArray2<u8>>> {
    let (w, h) = (image.width() as usize, image.height() as usize);
    numpy::PyArray1::from_vec(py, image.into_raw()).reshape([h, w])
}

/// A colour picture as a new HxWx3 uint8 array in BGR order: what the
/// arrays this module takes hold, and what OpenCV shows and writes.
pub(crate) fn bgr_to_array<'py>(
    py: Python<'py>,
    picture: image::RgbImage,
) -> PyResult<Bound<'py, numpy::PyArray3<u8>>> {
    let (w, h) = (picture.width() as usize, picture.height() as usize);
    let mut data = picture.into_raw();
    for pixel in data.chunks_exact_mut(3) {
        pixel.swap(0, 2);
    }
    numpy::PyArray1::from_vec(py, data).reshape([h, w, 3])
}

/// The colours of an 8-bit HxWx3 BGR or HxWx4 BGRA array, as RGB; None for
/// grey and 16-bit arrays (drawn over their grey).
pub(crate) fn colour_image(image: &Bound<'_, PyAny>) -> PyResult<Option<image::RgbImage>> {
    let Ok(array) = image.cast::<PyUntypedArray>() else {
        return Ok(None);
    };
    let layout = layout(array)?;
    if layout.depth != Depth::U8 || layout.channels < 3 {
        return Ok(None);
    }
    let values: PyReadonlyArray3<'_, u8> = array
        .extract()
        .map_err(|e| Error::value(PyErr::from(e).to_string()))?;
    let view = values.as_array();
    let mut rgb = Vec::with_capacity(layout.width as usize * layout.height as usize * 3);
    for pixel in view.rows() {
        rgb.extend_from_slice(&[pixel[2], pixel[1], pixel[0]]);
    }
    Ok(image::RgbImage::from_raw(layout.width, layout.height, rgb))
}

/// Reads an image file into the HxW uint8 grey array the CLI's own loader
/// makes (16-bit files stretched, colour by luma), so detections from it
/// match the CLI's bit for bit.
#[pyfunction]
pub(crate) fn load_image(
    py: Python<'_>,
    path: std::path::PathBuf,
) -> PyResult<Bound<'_, numpy::PyArray2<u8>>> {
    let gray = py.detach(|| crate::guard(|| Ok(whycode::image_io::load_gray(&path)?)))?;
    to_array(py, gray)
}
