//! Spectra: the baked CIE tables, wavelength sampling, RGB to spectrum, and XYZ to Rec.709.
//!
//! Caustic traces one wavelength per pass (Hachisuka's "one wavelength per pass" SPPM extension):
//! every quantity on a path is a scalar at `lambda_nm`, and the film turns the pass estimate into
//! XYZ with `L * cmf(lambda) / p(lambda)`.

pub mod rgb;
pub mod tables;
pub mod wavelength;

pub use rgb::RgbSpectrum;
pub use tables::{cmf, d65, d65_xyz, xyz_to_linear_rec709};
pub use wavelength::{sample_visible_wavelength, visible_wavelength_pdf};
