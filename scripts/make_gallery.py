#!/usr/bin/python3
"""Copies chosen preview frames of the paper's scenes into docs/images/paper/, shrunk for the README.

usage: make_gallery.py BAKES_DIR [OUT_DIR]
BAKES_DIR holds one folder per scene as bench/run_paper_table.sh leaves them (build/paper_bakes:
<scene>/preview.####.png). The frame shown for each scene is listed below (the moment the figure
of the paper shows). Writes <scene>.png, 320 pixels wide, palette-quantized to stay small.
"""
import os
import sys

from PIL import Image

FRAMES = {
    "tst": 85,           # snapped: the left toy magnet against the sphere
    "tst_same": 30,
    "bowl_spheres": 40,  # the cluster hanging under the magnet as it is lifted
    "bowl_2008": 48,     # the characters carried out of the bowl
    "supercube": 30,     # levitating
    "dragon_low": 16,    # balls held on the dragon
    "dragon_high": 16,
    "field_lines": 1,
}


def main(argv):
    bakes = argv[0]
    out = argv[1] if len(argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "docs", "images", "paper")
    os.makedirs(out, exist_ok=True)
    total = 0
    for scene, frame in FRAMES.items():
        src = os.path.join(bakes, scene, f"preview.{frame:04d}.png")
        if not os.path.exists(src):
            print(f"missing {src}", file=sys.stderr)
            continue
        im = Image.open(src).convert("RGB")
        w = 320
        im = im.resize((w, round(im.height * w / im.width)), Image.LANCZOS)
        im = im.quantize(colors=128, method=Image.Quantize.MEDIANCUT)
        dst = os.path.join(out, f"{scene}.png")
        im.save(dst, optimize=True)
        total += os.path.getsize(dst)
        print(f"{dst}: frame {frame}, {os.path.getsize(dst) // 1024} KB")
    print(f"{total // 1024} KB in all")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
