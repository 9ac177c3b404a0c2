"""Builds the add-on's installable zips from addon/, with the `caustic` program inside:

    cargo build --release && python tools/build_addon.py [-o dist] [--binary PATH]

- dist/caustic-<version>.zip: a Blender extension (4.2 and later: Preferences > Get Extensions >
  Install from Disk), blender_manifest.toml at its root, naming the platform of the program it
  carries (`platforms`, so Blender refuses it on another);
- dist/caustic-<version>-addon.zip: a plain add-on (Preferences > Add-ons > Install from Disk),
  the package in a `caustic/` folder.

Both carry the program as `bin/caustic` (`target/release/caustic` unless `--binary` names
another), its debug information stripped where `strip` is on PATH (the release build keeps it for
profiling: 41 MB with it); the add-on runs it unless its preferences name another. `--binary none`
leaves it out (the add-on then looks on PATH).
"""
import argparse
import pathlib
import platform
import shutil
import subprocess
import sys
import tempfile
import tomllib
import zipfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
ADDON = ROOT / "addon"


def addon_files():
    """The add-on's files, without caches."""
    return sorted(p for p in ADDON.rglob("*") if p.is_file() and "__pycache__" not in p.parts)


def blender_platform():
    """This machine's platform as Blender's extension manifests name it."""
    system = {"linux": "linux", "darwin": "macos", "win32": "windows"}.get(sys.platform, sys.platform)
    machine = {"x86_64": "x64", "amd64": "x64", "arm64": "arm64", "aarch64": "arm64"}.get(
        platform.machine().lower(), platform.machine().lower())
    return f"{system}-{machine}"


def manifest_with_platform(text, platform_name):
    """The extension manifest naming the one platform its program runs on."""
    lines = [line for line in text.splitlines() if not line.startswith("platforms")]
    at = next(i for i, line in enumerate(lines) if line.startswith("license"))
    lines.insert(at + 1, f'platforms = ["{platform_name}"]')
    return "\n".join(lines) + "\n"


def program_bytes(binary):
    """The program's bytes, without its debug information where `strip` can take it out, and
    whether it did."""
    strip = shutil.which("strip")
    if strip is None:
        return binary.read_bytes(), False
    with tempfile.TemporaryDirectory() as folder:
        copy = pathlib.Path(folder) / "caustic"
        shutil.copyfile(binary, copy)
        stripped = subprocess.run([strip, "--strip-debug", str(copy)], capture_output=True).returncode == 0
        return (copy if stripped else binary).read_bytes(), stripped


def write_zip(path, prefix, program):
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for file in addon_files():
            name = prefix + file.relative_to(ADDON).as_posix()
            if program is not None and file.name == "blender_manifest.toml":
                z.writestr(name, manifest_with_platform(file.read_text(), blender_platform()))
            else:
                z.write(file, name)
        if program is not None:
            info = zipfile.ZipInfo(prefix + "bin/caustic")
            info.external_attr = 0o755 << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(info, program)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-o", "--out", type=pathlib.Path, default=ROOT / "dist", help="output folder (default: dist)")
    parser.add_argument("--binary", default=str(ROOT / "target" / "release" / "caustic"),
                        help="the caustic program to carry (default: target/release/caustic; 'none': none)")
    args = parser.parse_args()
    out = args.out
    binary = None if args.binary == "none" else pathlib.Path(args.binary)
    if binary is not None and not binary.is_file():
        sys.exit(f"build_addon.py: no caustic program at {binary}: run `cargo build --release` first, "
                 "or name one with --binary (or --binary none to leave it out)")
    out.mkdir(parents=True, exist_ok=True)
    version = tomllib.loads((ADDON / "blender_manifest.toml").read_text())["version"]
    extension, legacy = out / f"caustic-{version}.zip", out / f"caustic-{version}-addon.zip"
    program, stripped = program_bytes(binary) if binary is not None else (None, False)
    write_zip(extension, "", program)
    write_zip(legacy, "caustic/", program)
    how = f" ({len(program) / 1e6:.0f} MB{', debug information stripped' if stripped else ''})" if program else ""
    carried = f", carrying {binary}{how} for {blender_platform()}" if binary is not None else ", without the program"
    print(f"wrote {extension} (extension) and {legacy} (plain add-on){carried}")


if __name__ == "__main__":
    main()
