"""Builds the add-on's installable zips from addon/:

    python tools/build_addon.py [-o dist]

- dist/caustic-<version>.zip: a Blender extension (4.2 and later: Preferences > Get Extensions >
  Install from Disk), blender_manifest.toml at its root;
- dist/caustic-<version>-addon.zip: a plain add-on (Preferences > Add-ons > Install from Disk),
  the package in a `caustic/` folder.
"""
import argparse
import pathlib
import tomllib
import zipfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
ADDON = ROOT / "addon"


def addon_files():
    """The add-on's files, without caches."""
    return sorted(p for p in ADDON.rglob("*") if p.is_file() and "__pycache__" not in p.parts)


def write_zip(path, prefix):
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for file in addon_files():
            z.write(file, prefix + file.relative_to(ADDON).as_posix())


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-o", "--out", type=pathlib.Path, default=ROOT / "dist", help="output folder (default: dist)")
    out = parser.parse_args().out
    out.mkdir(parents=True, exist_ok=True)
    version = tomllib.loads((ADDON / "blender_manifest.toml").read_text())["version"]
    extension, legacy = out / f"caustic-{version}.zip", out / f"caustic-{version}-addon.zip"
    write_zip(extension, "")
    write_zip(legacy, "caustic/")
    print(f"wrote {extension} (extension) and {legacy} (plain add-on)")


if __name__ == "__main__":
    main()
