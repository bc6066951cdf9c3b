#!/usr/bin/python3
"""Receives a camera's frames from a video server and prints each frame's
header and the subscriber's counters (received, lost, malformed).

    PYTHONPATH=build/python python/examples/watch_frames.py \
        --frames tcp://127.0.0.1:5555 --camera cam0 --count 10
"""

import argparse
import sys

from picksight import FrameSubscriber


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", default="tcp://127.0.0.1:5555", help="frame endpoint")
    parser.add_argument("--camera", default="", help="camera name (default: all)")
    parser.add_argument("--count", type=int, default=0, help="frames to receive (0: for ever)")
    parser.add_argument("--timeout", type=float, default=10.0, help="seconds to wait per frame")
    args = parser.parse_args()
    with FrameSubscriber(args.frames, args.camera) as frames:
        n = 0
        while args.count == 0 or n < args.count:
            frame = frames.receive(timeout=args.timeout)
            if frame is None:
                print(f"no frame within {args.timeout} s", file=sys.stderr)
                return 1
            n += 1
            h = frame.header
            print(f"{h.camera} #{h.sequence} {frame.image.shape} mean={frame.image.mean():.1f} "
                  f"roi=({h.roi_x},{h.roi_y}) triggered={int(h.triggered)}")
        print(f"received={frames.received} lost={frames.lost} malformed={frames.malformed}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
