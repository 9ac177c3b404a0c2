"""Writes the CIE tables in spectra/ from the colour-science package (PyPI).

Sources (as distributed by colour-science, which reproduces the CIE's own data):
- CIE 1931 2-degree standard observer colour-matching functions, 1 nm, 360-830 nm
  (CIE 018:2019 / CIE 015:2018, the CIE's "CIE_xyz_1931_2deg" dataset).
- CIE standard illuminant D65, 5 nm, 300-830 nm (ISO 11664-2 / CIE S 014-2, CIE's "CIE_std_illum_D65").

Run: python spectra/export_tables.py   (needs `pip install colour-science`)
"""
import pathlib

import colour

HERE = pathlib.Path(__file__).parent


def write(name, header, source, rows):
    with open(HERE / name, "w") as f:
        f.write(f"# {source}\n")
        f.write(header + "\n")
        for row in rows:
            f.write(",".join(f"{v:.8g}" for v in row) + "\n")


cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
write(
    "cie1931_2deg.csv",
    "lambda_nm,x_bar,y_bar,z_bar",
    f"CIE 1931 2-degree standard observer, 1 nm; via colour-science {colour.__version__}",
    [(w, *cmfs[w]) for w in range(360, 831)],
)
d65 = colour.SDS_ILLUMINANTS["D65"]
write(
    "d65.csv",
    "lambda_nm,relative_power",
    f"CIE standard illuminant D65, 5 nm; via colour-science {colour.__version__}",
    [(w, d65[w]) for w in range(300, 831, 5)],
)
