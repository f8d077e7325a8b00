#!/usr/bin/env python3
"""dump_pixels.py DIVE OUT_DIR: the pixels of a simulated dive's PNG images (EuRoC layout) as OpenCV reads
them (cv2.IMREAD_UNCHANGED: grey or BGR), OUT_DIR/<cam>/<name>.raw, and OUT_DIR/pixels.json with their
width, height and channels; what euroc_to_mcap.js puts in sensor_msgs/Image messages."""
import json
import os
import sys

import cv2

dive, out = sys.argv[1:3]
shape = None
for cam in ("cam0", "cam1"):
    folder = os.path.join(dive, "mav0", cam, "data")
    os.makedirs(os.path.join(out, cam), exist_ok=True)
    for name in sorted(os.listdir(folder)):
        pixels = cv2.imread(os.path.join(folder, name), cv2.IMREAD_UNCHANGED)
        shape = pixels.shape
        with open(os.path.join(out, cam, os.path.splitext(name)[0] + ".raw"), "wb") as f:
            f.write(pixels.tobytes())
with open(os.path.join(out, "pixels.json"), "w") as f:
    json.dump({"width": shape[1], "height": shape[0], "channels": shape[2] if len(shape) == 3 else 1}, f)
