#!/usr/bin/env python3
"""dump_pixels.py DIVE OUT_DIR [DECODED_DIVE]: the pixels of a simulated dive's PNG images (EuRoC layout) as
OpenCV reads them (cv2.IMREAD_UNCHANGED: grey or BGR), OUT_DIR/<cam>/<name>.raw, and OUT_DIR/pixels.json with
their width, height and channels; what euroc_to_mcap.js puts in sensor_msgs/Image messages. Also each image
JPEG-encoded by OpenCV at quality 95, OUT_DIR/<cam>/<name>.jpg (its CompressedImage messages of IMAGES jpeg);
DECODED_DIVE: a copy of the dive whose images are those JPEG bytes decoded by OpenCV (cv2.imdecode), as PNG."""
import json
import os
import shutil
import sys

import cv2
import numpy as np

dive, out = sys.argv[1:3]
decoded = sys.argv[3] if len(sys.argv) > 3 else None
if decoded:
    shutil.copytree(dive, decoded)
shape = None
for cam in ("cam0", "cam1"):
    folder = os.path.join(dive, "mav0", cam, "data")
    os.makedirs(os.path.join(out, cam), exist_ok=True)
    for name in sorted(os.listdir(folder)):
        pixels = cv2.imread(os.path.join(folder, name), cv2.IMREAD_UNCHANGED)
        shape = pixels.shape
        stem = os.path.join(out, cam, os.path.splitext(name)[0])
        with open(stem + ".raw", "wb") as f:
            f.write(pixels.tobytes())
        jpeg = cv2.imencode(".jpg", pixels, [cv2.IMWRITE_JPEG_QUALITY, 95])[1].tobytes()
        with open(stem + ".jpg", "wb") as f:
            f.write(jpeg)
        if decoded:
            cv2.imwrite(os.path.join(decoded, "mav0", cam, "data", name),
                        cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_UNCHANGED))
with open(os.path.join(out, "pixels.json"), "w") as f:
    json.dump({"width": shape[1], "height": shape[0], "channels": shape[2] if len(shape) == 3 else 1}, f)
