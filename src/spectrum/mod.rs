//! Spectra: the baked CIE tables, wavelength sampling, RGB to spectrum, and XYZ to Rec.709.
//!
//! Caustic traces one wavelength per pass (Hachisuka's "one wavelength per pass" SPPM extension):
//! every quantity on a path is a scalar at `lambda_nm`, and the film turns the pass estimate into
//! XYZ with `L * cmf(lambda) / p(lambda)`.

pub mod dispersion;
pub mod rgb;
pub mod tables;
pub mod wavelength;

pub use dispersion::Dispersion;
pub use rgb::RgbSpectrum;
pub use tables::{
    cmf, d65, d65_xyz, linear_rec709_to_xyz, xyz_to_linear_rec709, LAMBDA_MAX_NM, LAMBDA_MIN_NM,
};
pub use wavelength::{sample_visible_wavelength, visible_wavelength_pdf};
