#!/usr/bin/python3
"""Lists a video server's cameras with their settings and statistics, and
optionally saves a snapshot of one as a PGM/PPM file.

    PYTHONPATH=build/python python/examples/camera_info.py \
        --control tcp://127.0.0.1:5556 --snap cam0 --out cam0.pgm
"""

import argparse
import sys

from picksight import CameraControl, ControlError
from picksight import picksight_pb2 as pb


def save_pnm(path, image):
    """Netpbm needs no imaging library: PGM for mono, PPM (RGB) for colour."""
    if image.ndim == 2:
        head, data = b"P5", image
    else:
        head, data = b"P6", image[:, :, ::-1]  # BGR to RGB
    with open(path, "wb") as f:
        f.write(head + b"\n%d %d\n255\n" % (image.shape[1], image.shape[0]))
        f.write(data.tobytes())


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--control", default="tcp://127.0.0.1:5556", help="control endpoint")
    parser.add_argument("--snap", metavar="CAMERA", help="take a snapshot of this camera")
    parser.add_argument("--out", default="snap.pnm", help="where to save the snapshot")
    args = parser.parse_args()
    with CameraControl(args.control) as control:
        try:
            stats = {c.camera: c for c in control.statistics().cameras}
            for camera in control.list_cameras():
                s = stats.get(camera.name)
                print(f"{camera.name}: {camera.source} {camera.state} "
                      f"{pb.AcquisitionMode.Name(camera.mode).lower()} "
                      f"acquired={s.frames_acquired if s else 0} fps={s.fps if s else 0:.1f}")
            if args.snap:
                frame = control.snap(args.snap)
                save_pnm(args.out, frame.image)
                print(f"{args.out}: {frame.image.shape} sequence {frame.sequence}")
        except ControlError as e:
            print(f"video server: {e}", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
