"""Converts an EXR (Caustic's Combined.R/G/B, or R/G/B as Blender writes) to an sRGB PNG for viewing.

    python tools/exr_to_png.py renders/frame_0001.exr out.png [--exposure STOPS]

Needs `pip install OpenEXR numpy pillow`.
"""
import argparse

import numpy as np
import OpenEXR
from PIL import Image


def srgb_image(exr, exposure=0.0):
    """The EXR's colour as an 8-bit sRGB PIL image."""
    with OpenEXR.File(str(exr), separate_channels=True) as f:
        channels = f.channels()
        prefix = "Combined." if "Combined.R" in channels else ""
        rgb = np.stack([channels[prefix + c].pixels for c in "RGB"], axis=-1).astype(np.float64)
    rgb *= 2.0 ** exposure
    srgb = np.where(rgb <= 0.0031308, 12.92 * rgb, 1.055 * np.power(np.clip(rgb, 0, None), 1 / 2.4) - 0.055)
    return Image.fromarray((np.clip(srgb, 0, 1) * 255 + 0.5).astype(np.uint8))


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("exr")
    parser.add_argument("png")
    parser.add_argument("--exposure", type=float, default=0.0, help="stops to add before display")
    args = parser.parse_args()
    srgb_image(args.exr, args.exposure).save(args.png)


if __name__ == "__main__":
    main()
