//! Bakes the CSV tables in `spectra/` into Rust arrays (`$OUT_DIR/tables.rs`).
//!
//! Every table is resampled to 1 nm over `LAMBDA_MIN_NM..=LAMBDA_MAX_NM` by linear interpolation,
//! so the renderer looks up any wavelength with one multiply and one lerp.

use std::{env, fs, path::Path};

const LAMBDA_MIN_NM: f64 = 360.0;
const LAMBDA_MAX_NM: f64 = 830.0;

/// Fields of each data row of a CSV file (quoted fields may hold commas), skipping `#` comments
/// and the header line.
fn read_records(path: &Path) -> Vec<Vec<String>> {
    let text = fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .filter(|line| !line.starts_with('#') && !line.trim().is_empty())
        .skip(1)
        .map(|line| {
            let mut fields = vec![String::new()];
            let mut quoted = false;
            for ch in line.chars() {
                match ch {
                    '"' => quoted = !quoted,
                    ',' if !quoted => fields.push(String::new()),
                    _ => fields.last_mut().expect("one field").push(ch),
                }
            }
            fields
        })
        .collect()
}

/// The glass catalogue as a Rust array of `Glass` literals.
fn glass_catalogue(path: &Path) -> String {
    let rows: Vec<String> = read_records(path)
        .iter()
        .map(|f| {
            let number = |i: usize| -> f64 {
                f[i].trim().parse().unwrap_or_else(|e| panic!("{}: {}: field {i}: {e}", path.display(), f[0]))
            };
            format!(
                "Glass {{ name: {:?}, b: [{:?}, {:?}, {:?}, {:?}], c: [{:?}, {:?}, {:?}, {:?}], n_f: {:?}, n_d: {:?}, n_c: {:?}, v_d: {:?}, source: {:?} }}",
                f[0], number(1), number(2), number(3), number(4), number(5), number(6), number(7), number(8),
                number(9), number(10), number(11), number(12), f[13]
            )
        })
        .collect();
    format!(
        "/// The glass catalogue from spectra/glasses.csv.\npub const GLASSES: [Glass; {}] = [{}];\n",
        rows.len(),
        rows.join(", ")
    )
}

/// Rows of numbers from a CSV file, skipping `#` comments and the header line.
fn read_csv(path: &Path) -> Vec<Vec<f64>> {
    read_records(path)
        .iter()
        .map(|fields| {
            fields
                .iter()
                .map(|f| f.trim().parse().unwrap_or_else(|e| panic!("{}: {fields:?}: {e}", path.display())))
                .collect()
        })
        .collect()
}

/// Column `column` of `rows`, linearly interpolated at every whole nanometre of the range.
fn resample(rows: &[Vec<f64>], column: usize) -> Vec<f64> {
    let count = (LAMBDA_MAX_NM - LAMBDA_MIN_NM) as usize + 1;
    (0..count)
        .map(|i| {
            let lambda = LAMBDA_MIN_NM + i as f64;
            let k = rows.partition_point(|row| row[0] <= lambda).clamp(1, rows.len() - 1);
            let (a, b) = (&rows[k - 1], &rows[k]);
            let t = ((lambda - a[0]) / (b[0] - a[0])).clamp(0.0, 1.0);
            a[column] + t * (b[column] - a[column])
        })
        .collect()
}

/// XYZ to linear Rec.709 (IEC 61966-2-1, D65 white).
const XYZ_TO_REC709: [[f64; 3]; 3] = [
    [3.2404542, -1.5371385, -0.4985314],
    [-0.9692660, 1.8760108, 0.0415560],
    [0.0556434, -0.2040259, 1.0572252],
];

fn rust_array(name: &str, values: &[f64]) -> String {
    let body: Vec<String> = values.iter().map(|v| format!("{v:e}")).collect();
    format!(
        "/// Baked from spectra/ at 1 nm.\npub const {name}: [f32; {}] = [{}];\n",
        values.len(),
        body.join(", ")
    )
}

fn main() {
    let dir = Path::new("spectra");
    let cmf = read_csv(&dir.join("cie1931_2deg.csv"));
    let d65 = read_csv(&dir.join("d65.csv"));
    let mut out = format!(
        "/// First wavelength of the tables.\npub const LAMBDA_MIN_NM: f32 = {LAMBDA_MIN_NM:?};\n/// Last wavelength of the tables.\npub const LAMBDA_MAX_NM: f32 = {LAMBDA_MAX_NM:?};\n"
    );
    let (x, y, z) = (resample(&cmf, 1), resample(&cmf, 2), resample(&cmf, 3));
    let d65 = resample(&d65, 1);
    // Normalise D65 to luminance 1: sum(D65 * y_bar) * 1 nm = 1.
    let luminance: f64 = d65.iter().zip(&y).map(|(s, y)| s * y).sum();
    let d65: Vec<f64> = d65.iter().map(|s| s / luminance).collect();
    let white = [0, 1, 2].map(|row| {
        let xyz: [f64; 3] = [&x, &y, &z].map(|bar| d65.iter().zip(bar).map(|(s, b)| s * b).sum());
        (0..3).map(|col| XYZ_TO_REC709[row][col] * xyz[col]).sum::<f64>()
    });
    // Scale each row so that the tabulated D65 maps to exactly (1, 1, 1) (von Kries in RGB).
    let matrix: Vec<f64> = (0..9).map(|k| XYZ_TO_REC709[k / 3][k % 3] / white[k / 3]).collect();
    out += &rust_array("CIE_X", &x);
    out += &rust_array("CIE_Y", &y);
    out += &rust_array("CIE_Z", &z);
    out += &rust_array("D65_NORMALISED", &d65);
    out += &rust_array("XYZ_TO_LINEAR_REC709", &matrix);
    let out_dir = env::var("OUT_DIR").expect("cargo sets OUT_DIR");
    fs::write(Path::new(&out_dir).join("tables.rs"), out).expect("write baked tables");
    let glasses = glass_catalogue(&dir.join("glasses.csv"));
    fs::write(Path::new(&out_dir).join("glasses.rs"), glasses).expect("write the glass catalogue");
    println!("cargo:rerun-if-changed=spectra");
}
