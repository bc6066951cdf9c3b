#!/usr/bin/python3
"""The PLC port of a real cell driven by pymodbus (Debian's python3-pymodbus),
a Modbus implementation independent of the server's libmodbus: the
handshake, the float decoding in CDAB word order on unit 5, the poses
against the robot port's LOCATE, and the error paths (no model for the
type, camera down).

usage: /usr/bin/python3 plc_pymodbus_test.py --bin-dir BUILD/bin
"""
import argparse
import shutil
import struct
import sys
import tempfile

from plc_modbus import (CONTROL, STATUS, ERROR_CODE, CALIBRATION, RESULT_FRAME,
    FRAME_SEQUENCE, PART_COUNT, FIRST_PART, PART_STRIDE, CLEAR_ERROR,
    READY, RESULTS_VALID, ERROR, ALL_TYPES, UNIT, Robot, Plc, video_server, vision_app)


def float_cdab(words):
    """Low word first (--modbus-word-order CDAB)."""
    return struct.unpack(">f", struct.pack(">HH", words[1], words[0]))[0]


def u32_cdab(words):
    return words[1] << 16 | words[0]


def parse_locate(reply):
    words = reply.split()
    assert words[0] == "OK", reply
    n = int(words[1])
    return [tuple(map(float, words[2 + 3 * i:5 + 3 * i])) for i in range(n)]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--bin-dir", required=True)
    args = parser.parse_args()
    data_dir = tempfile.mkdtemp(prefix="picksight-pymodbus-")
    server = vision = None
    checks = 0
    try:
        server = video_server(args.bin_dir)
        frames = server.wait_for("frames ")
        control = server.wait_for("control ")
        vision = vision_app(args.bin_dir, frames, control, data_dir, "--modbus-word-order", "CDAB")
        robot = Robot(int(vision.wait_for("robot ")))
        plc = Plc(int(vision.wait_for("modbus ")))
        vision.wait_for("ready")

        assert plc.status() & READY
        assert plc.read(CALIBRATION) == [0]
        reply = robot.request("LEARN 1 bracket")
        assert reply.startswith("OK 1 bracket "), reply
        checks += 2

        # No model for type 2 while type 1 has one: ERROR 32, as on the robot port.
        s = plc.trigger(2)
        assert s & ERROR and not s & RESULTS_VALID, hex(s)
        assert plc.read(ERROR_CODE) == [32]
        plc.write(CONTROL, CLEAR_ERROR)
        plc.write(CONTROL, 0)
        assert not plc.status() & ERROR
        checks += 1

        for part_type in (1, ALL_TYPES):
            s = plc.trigger(part_type)
            assert s & RESULTS_VALID and not s & ERROR, hex(s)
            sequence = u32_cdab(plc.read(FRAME_SEQUENCE, 2))
            frame_reply = robot.request("FRAME").split()
            assert int(frame_reply[2]) == sequence, (frame_reply, sequence)
            assert plc.read(RESULT_FRAME) == [0]
            count = plc.read(PART_COUNT)[0]
            assert count == 1, count
            block = plc.read(FIRST_PART, PART_STRIDE)
            part = (block[0], float_cdab(block[2:4]), float_cdab(block[4:6]),
                    float_cdab(block[6:8]), float_cdab(block[8:10]))
            plc.acknowledge()
            assert plc.status() & READY
            poses = parse_locate(robot.request("LOCATE 1"))
            assert len(poses) == 1, poses
            assert part[0] == 1, part
            assert part[4] > 0.5, part
            for got, want in zip(part[1:4], poses[0]):
                assert abs(got - want) < 0.002, (part, poses)
            checks += 1

        # Reads of registers past the map: exception 2 (illegal data address).
        rr = plc.client.read_holding_registers(190, 1, slave=UNIT)
        assert rr.isError() and rr.exception_code == 2, rr
        rr = plc.client.write_register(STATUS, 1, slave=UNIT)
        assert rr.isError() and rr.exception_code == 2, rr
        checks += 1

        # The camera goes away: the trigger fails with the camera's code.
        server.stop()
        s = plc.trigger(1)
        assert s & ERROR, hex(s)
        assert plc.read(ERROR_CODE)[0] in (20, 21), plc.read(ERROR_CODE)
        assert robot.request("PING") == "OK"
        checks += 1
        plc.client.close()
    except AssertionError as e:
        print(f"FAILED after {checks} checks: {e}")
        print(f"{checks} passed, 1 failed")
        return 1
    finally:
        for p in (vision, server):
            if p:
                p.stop()
        shutil.rmtree(data_dir, ignore_errors=True)
    print(f"{checks} passed, 0 failed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
