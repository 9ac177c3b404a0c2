//! Index of refraction as a function of wavelength: the laws materials can follow.
//!
//! A material's index is one function of wavelength, evaluated at the path's hero wavelength; a
//! path never changes it (unlike renderers that draw a new wavelength at each glass hit).
//! - constant: no dispersion;
//! - Abbe: the `KHR_materials_dispersion` law, `n = max(n_d + (n_d - 1) / V_d (523655 / l^2 -
//!   1.5168), 1)` with l in nm (a two-term Cauchy law through n_d with n_F - n_C = (n_d - 1) / V_d);
//!   the extension stores `dispersion = 20 / V_d`;
//! - Sellmeier: `n^2 = 1 + sum B_k l^2 / (l^2 - C_k)`, l in micrometres (glass makers' law);
//! - a table of (wavelength, index) pairs, interpolated linearly and clamped at the ends;
//! - a named glass of the catalogue in `spectra/glasses.csv`.

use std::sync::Arc;

/// A catalogue glass (from `spectra/glasses.csv`).
#[derive(Clone, Copy, Debug)]
pub struct Glass {
    /// Catalogue name (what materials name in their extras).
    pub name: &'static str,
    /// Sellmeier B coefficients.
    pub b: [f64; 4],
    /// Sellmeier C coefficients, micrometres squared.
    pub c: [f64; 4],
    /// Published index at the F line (486.13 nm), 0 where the source gives none.
    pub n_f: f64,
    /// Published index at the d line (587.56 nm).
    pub n_d: f64,
    /// Published index at the C line (656.27 nm), 0 where the source gives none.
    pub n_c: f64,
    /// Published Abbe number.
    pub v_d: f64,
    /// Where the numbers come from.
    pub source: &'static str,
}

include!(concat!(env!("OUT_DIR"), "/glasses.rs"));

/// Fraunhofer lines (nm): F (hydrogen), d (helium), C (hydrogen).
pub const LAMBDA_F_NM: f32 = 486.1327;
/// The helium d line, where n_d is defined.
pub const LAMBDA_D_NM: f32 = 587.5618;
/// The hydrogen C line.
pub const LAMBDA_C_NM: f32 = 656.2725;

/// How a material's index of refraction depends on wavelength.
#[derive(Clone, Debug, PartialEq)]
pub enum Dispersion {
    /// The same index at every wavelength.
    Constant(f32),
    /// The `KHR_materials_dispersion` law from n_d and the Abbe number.
    Abbe {
        /// Index at the d line.
        n_d: f32,
        /// Abbe number (positive).
        v_d: f32,
    },
    /// Sellmeier coefficients (micrometres).
    Sellmeier {
        /// B coefficients.
        b: [f64; 4],
        /// C coefficients, micrometres squared.
        c: [f64; 4],
    },
    /// (wavelength nm, index) pairs sorted by wavelength.
    Table(Arc<Vec<(f32, f32)>>),
}

impl Dispersion {
    /// The catalogue glass called `name` (case-insensitive; `N-BK7` and `N-SF11` are aliases).
    pub fn glass(name: &str) -> Option<Self> {
        let wanted = name.trim().to_ascii_lowercase();
        let wanted = wanted.strip_prefix("n-").unwrap_or(&wanted);
        GLASSES
            .iter()
            .find(|g| g.name.to_ascii_lowercase() == wanted)
            .map(|g| Dispersion::Sellmeier { b: g.b, c: g.c })
    }

    /// The names of the catalogue's glasses, for messages.
    pub fn glass_names() -> Vec<&'static str> {
        GLASSES.iter().map(|g| g.name).collect()
    }

    /// A table law, checking that wavelengths increase and indices are at least 1.
    pub fn table(mut pairs: Vec<(f32, f32)>) -> Result<Self, String> {
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        if pairs.is_empty() || pairs.iter().any(|&(l, n)| !(l > 0.0 && n >= 1.0 && n.is_finite())) {
            return Err("an index table needs [wavelength_nm, index] pairs with positive wavelengths and indices >= 1".into());
        }
        Ok(Dispersion::Table(Arc::new(pairs)))
    }

    /// Whether the index changes with wavelength.
    pub fn is_dispersive(&self) -> bool {
        !matches!(self, Dispersion::Constant(_))
    }

    /// The index of refraction at `lambda_nm`.
    pub fn index(&self, lambda_nm: f32) -> f32 {
        match self {
            Dispersion::Constant(n) => *n,
            Dispersion::Abbe { n_d, v_d } => {
                (n_d + (n_d - 1.0) / v_d * (523_655.0 / (lambda_nm * lambda_nm) - 1.5168)).max(1.0)
            }
            Dispersion::Sellmeier { b, c } => {
                let l2 = f64::from(lambda_nm / 1000.0).powi(2);
                let n2 = 1.0 + b.iter().zip(c).map(|(b, c)| b * l2 / (l2 - c)).sum::<f64>();
                n2.max(1.0).sqrt() as f32
            }
            Dispersion::Table(pairs) => {
                let k = pairs.partition_point(|&(l, _)| l <= lambda_nm);
                match k {
                    0 => pairs[0].1,
                    k if k == pairs.len() => pairs[k - 1].1,
                    k => {
                        let ((l0, n0), (l1, n1)) = (pairs[k - 1], pairs[k]);
                        n0 + (n1 - n0) * (lambda_nm - l0) / (l1 - l0)
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Half a unit of the last decimal a source publishes n_d with.
    fn published_tolerance(n: f64) -> f64 {
        let decimals = format!("{n}").split('.').nth(1).map_or(0, str::len);
        0.5 * 10f64.powi(-(decimals as i32)) + 1e-7
    }

    #[test]
    fn catalogue_glasses_match_their_published_indices() {
        assert!(GLASSES.len() >= 6);
        for glass in GLASSES {
            let law = Dispersion::glass(glass.name).unwrap();
            let [n_f, n_d, n_c] = [LAMBDA_F_NM, LAMBDA_D_NM, LAMBDA_C_NM].map(|l| f64::from(law.index(l)));
            let tolerance = published_tolerance(glass.n_d).max(1e-5);
            assert!((n_d - glass.n_d).abs() <= tolerance, "{}: n_d {n_d} vs {}", glass.name, glass.n_d);
            for (got, published) in [(n_f, glass.n_f), (n_c, glass.n_c)] {
                if published > 0.0 {
                    assert!((got - published).abs() <= 1e-5, "{}: {got} vs {published}", glass.name);
                }
            }
            let v_d = (n_d - 1.0) / (n_f - n_c);
            assert!((v_d - glass.v_d).abs() < 0.06, "{}: V_d {v_d} vs {}", glass.name, glass.v_d);
        }
    }

    #[test]
    fn the_khr_law_has_the_abbe_number_it_was_given() {
        let law = Dispersion::Abbe { n_d: 1.5, v_d: 40.0 };
        let [n_f, n_d, n_c] = [486.1, 587.6, 656.3].map(|l| law.index(l));
        // The law's constants are rounded (523655, 1.5168), so n_d and V_d hold to about 1e-4.
        assert!((n_d - 1.5).abs() < 1e-4, "{n_d}");
        assert!(((n_d - 1.0) / (n_f - n_c) - 40.0).abs() < 0.05, "{}", (n_d - 1.0) / (n_f - n_c));
        assert!(n_f > n_d && n_d > n_c);
        assert_eq!(Dispersion::Abbe { n_d: 1.01, v_d: 0.1 }.index(800.0), 1.0);
    }

    #[test]
    fn names_aliases_and_tables() {
        assert_eq!(Dispersion::glass("N-BK7"), Dispersion::glass("bk7"));
        assert!(Dispersion::glass("unobtainium").is_none());
        let table = Dispersion::table(vec![(700.0, 1.5), (400.0, 1.6)]).unwrap();
        assert!((table.index(550.0) - 1.55).abs() < 1e-6);
        assert_eq!(table.index(300.0), 1.6);
        assert!(Dispersion::table(vec![(500.0, 0.9)]).is_err());
    }
}
