#!/usr/bin/python3
"""Asks a vision app to LOCATE parts of a type and prints the grasp poses, as
a robot program would (docs/PROTOCOL.md).

    PYTHONPATH=build/python python/examples/locate.py --port 5600 1
"""

import argparse
import sys

from picksight import RobotClient, RobotError


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, default=5600)
    parser.add_argument("type", type=int, help="part type (0..9999)")
    args = parser.parse_args()
    with RobotClient(args.host, args.port) as robot:
        try:
            poses = robot.locate(args.type)
        except RobotError as e:
            print(f"vision refused: {e}", file=sys.stderr)
            return 1
        frame = robot.status()["frame"]
        print(f"{len(poses)} parts of type {args.type} ({frame} frame)")
        for i, p in enumerate(poses, 1):
            print(f"{i:3d}  x={p.x:10.3f}  y={p.y:10.3f}  rz={p.rz:8.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
