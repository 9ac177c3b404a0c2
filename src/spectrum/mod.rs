//! Spectra: the baked CIE tables, wavelength sampling, RGB to spectrum, and XYZ to Rec.709.
//!
//! Every path of a pass carries the same four wavelengths ([`Wavelengths`]; Hachisuka's "one
//! wavelength per pass" SPPM extension, with hero wavelength sampling): every quantity on a path
//! is a [`SampledSpectrum`], one lane per wavelength, and the film turns the pass estimate into
//! XYZ with the mean over lanes of `L * cmf(lambda) / p(lambda)`. A path refracted by a
//! dispersive material goes on with its hero wavelength alone.

pub mod blackbody;
pub mod dispersion;
pub mod rgb;
pub mod tables;
pub mod wavelength;

pub use blackbody::{blackbody_colour, Illuminant};
pub use dispersion::Dispersion;
pub use rgb::{RgbSpectrum, Rows, SpectrumImage};
pub use tables::{
    cmf, d65, d65_xyz, linear_rec709_to_xyz, xyz_to_linear_rec709, LAMBDA_MAX_NM, LAMBDA_MIN_NM,
};
pub use wavelength::{
    hero_only, sample_visible_wavelength, visible_wavelength_pdf, SampledSpectrum, Wavelengths, LANES,
};
