use super::*;
use crate::sampling::pass_sample;
use crate::spectrum::xyz_to_linear_rec709;

/// Adds `passes` passes in which every pixel sees `radiance(lambda)`.
fn film_of(passes: u64, radiance: impl Fn(f32) -> f32) -> Film {
    let mut film = Film::new(2, 1, FilmMode::Spectral, 0, false);
    for i in 0..passes {
        let lambda = Wavelengths::sampled(pass_sample(5, i));
        let pixel =
            (SampledSpectrum::from_array(lambda.nm.to_array().map(&radiance)), SampledSpectrum::ZERO, 1.0);
        film.add_pass(&lambda, 0.1, |_| pixel);
    }
    film
}

#[test]
fn a_spectrum_proportional_to_d65_is_exactly_grey_after_any_number_of_passes() {
    for passes in [1, 3, 17] {
        let rgb = film_of(passes, |l| 0.25 * d65(l)).rgb()[0];
        assert!((rgb - DVec3::splat(0.25)).abs().max_element() < 1e-6, "{passes} passes: {rgb}");
    }
}

#[test]
fn one_wavelength_shows_white_as_luminance_one_in_its_own_colour() {
    for lambda in [450.0, 550.0, 650.0] {
        let mut film = Film::new(1, 1, FilmMode::Monochromatic { lambda_nm: lambda }, 0, false);
        let white = SampledSpectrum::splat(0.5 * d65(lambda));
        film.add_pass(&Wavelengths::single(lambda, 1.0), 0.1, |_| (white, SampledSpectrum::ZERO, 1.0));
        let rgb = film.rgb()[0];
        let luminance = 0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z;
        assert!((luminance - 0.5).abs() < 1e-3 && rgb.min_element() >= -1e-9, "{lambda}: {rgb}");
    }
    let blue = film_rgb_at(450.0);
    let red = film_rgb_at(650.0);
    assert!(blue.z > blue.x && red.x > red.z);
}

fn film_rgb_at(lambda: f32) -> DVec3 {
    xyz_to_linear_rec709(display_xyz(lambda))
}

#[test]
fn spectral_bins_average_the_spectral_radiance_of_their_band() {
    let mut film = Film::new(1, 1, FilmMode::Spectral, 47, false);
    for i in 0..10_000 {
        let lambda = Wavelengths::sampled(pass_sample(9, i));
        film.add_pass(&lambda, 0.1, |_| (SampledSpectrum::splat(2.0), SampledSpectrum::ZERO, 1.0));
    }
    let bands: Vec<f64> = film.bins.sums.iter().map(|s| s / film.passes as f64).collect();
    // A flat spectrum of 2 per nm: every 10 nm band averages 2.
    assert!(bands.iter().all(|b| (b - 2.0).abs() < 0.1), "{bands:?}");
    assert_eq!(film.bins.channel_name(0), "Spectral.365nm");
}

/// Passes and differences, added on blocks of pixels in parallel, land on the pixels they
/// name across block boundaries, spectral bands included: the same sums, bit for bit, as
/// adding them pixel by pixel.
#[test]
fn passes_and_differences_land_on_their_pixels_across_blocks() {
    let (pixels, bands) = (10_000, 3);
    let mut film = Film::new(5000, 2, FilmMode::Spectral, bands, false);
    let lambda = Wavelengths::sampled(pass_sample(3, 0));
    let estimate = |i: usize| (SampledSpectrum::splat(i as f32), SampledSpectrum::splat(0.5), (i % 2) as f32);
    let own = |i: usize| (SampledSpectrum::splat(2.0 * i as f32), SampledSpectrum::ZERO, 1.0);
    film.add_pass(&lambda, 0.1, estimate);
    let changed: Vec<usize> = (0..pixels).filter(|i| i % 977 == 3 || (4095..=4096).contains(i)).collect();
    film.add_differences(&lambda, 0.1, changed.len(), |k| {
        (changed[k], own(changed[k]), estimate(changed[k]))
    });
    let weights = film.pass_weights(&lambda, 0.1);
    for i in 0..pixels {
        let (mut sums, mut pixel_bands) = (PixelSums { passes: 1, ..PixelSums::default() }, vec![0.0; bands]);
        add_estimate(&weights, &mut sums, &mut pixel_bands, estimate(i), 1.0);
        if changed.contains(&i) {
            add_estimate(&weights, &mut sums, &mut pixel_bands, own(i), 1.0);
            add_estimate(&weights, &mut sums, &mut pixel_bands, estimate(i), -1.0);
        }
        assert_eq!(film.pixels[i], sums, "pixel {i}");
        assert_eq!(film.bins.sums[i * bands..(i + 1) * bands], pixel_bands[..], "pixel {i}'s bands");
    }
    assert!(changed.len() > 10 && film.bins.sums.iter().any(|&b| b != 0.0));
}

#[test]
fn non_finite_estimates_are_counted_and_do_not_poison_the_pixel() {
    let film = film_of(16, |l| if l < 550.0 { f32::NAN } else { d65(l) });
    assert!(film.non_finite_estimates > 0);
    assert!(film.rgb().iter().all(|c| c.is_finite()));
}
