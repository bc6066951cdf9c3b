#!/usr/bin/python3
"""Jobs selected by a PLC through pymodbus (Debian's python3-pymodbus): the
LOAD_JOB handshake (JOB_NUMBER, LOAD_JOB, JOB_DONE, JOB_IN_FORCE) switching
between two jobs saved over the robot port, each trigger after a switch
answering with the job's own model; a number no job has is ERROR 50 and
changes nothing; a job loaded over the robot port shows in JOB_IN_FORCE.

usage: /usr/bin/python3 plc_job_pymodbus_test.py --bin-dir BUILD/bin
"""
import argparse
import shutil
import sys
import tempfile

from plc_modbus import (CONTROL, ERROR_CODE, PART_COUNT, FIRST_PART, PART_STRIDE, CLEAR_ERROR,
    BUSY, RESULTS_VALID, ERROR, ALL_TYPES, UNIT, Robot, Plc, video_server, vision_app)

# docs/PLC.md, the job registers and bits.
JOB_NUMBER, JOB_IN_FORCE, LOAD_JOB, JOB_DONE = 2, 17, 8, 64


def load_job(plc, number):
    """The LOAD_JOB handshake: number, rising edge, JOB_DONE, edge down."""
    plc.write(JOB_NUMBER, number)
    plc.write(CONTROL, LOAD_JOB)
    s = plc.wait_for(JOB_DONE)
    assert not s & BUSY, hex(s)
    plc.write(CONTROL, 0)
    assert not plc.status() & JOB_DONE
    return s


def located_types(plc):
    """Trigger LOCATE ALL; the types of the parts found."""
    s = plc.trigger(ALL_TYPES)
    assert s & RESULTS_VALID and not s & ERROR, hex(s)
    count = plc.read(PART_COUNT)[0]
    types = [plc.read(FIRST_PART + PART_STRIDE * i)[0] for i in range(count)]
    plc.acknowledge()
    return types


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--bin-dir", required=True)
    args = parser.parse_args()
    data_dir = tempfile.mkdtemp(prefix="picksight-plc-jobs-")
    server = vision = None
    checks = 0
    try:
        server = video_server(args.bin_dir)
        frames = server.wait_for("frames ")
        control = server.wait_for("control ")
        vision = vision_app(args.bin_dir, frames, control, data_dir)
        robot = Robot(int(vision.wait_for("robot ")))
        plc = Plc(int(vision.wait_for("modbus ")))
        vision.wait_for("ready")

        # Two jobs: the part as type 1 (job 1), the same part as type 5 (job 12).
        assert robot.request("LEARN 1 bracket").startswith("OK 1 bracket ")
        assert robot.request("JOB SAVE 1-bracket").startswith("OK 1-bracket 1 0 1 ")
        assert robot.request("FORGET 1") == "OK"
        assert robot.request("LEARN 5 bracket").startswith("OK 5 bracket ")
        assert robot.request("JOB SAVE 12_lid").startswith("OK 12_lid 1 0 1 ")
        assert plc.read(JOB_IN_FORCE) == [12]
        assert located_types(plc) == [5]
        checks += 1

        for number, part_type in ((1, 1), (12, 5), (1, 1)):
            s = load_job(plc, number)
            assert not s & ERROR, (number, hex(s), plc.read(ERROR_CODE))
            assert plc.read(JOB_IN_FORCE) == [number]
            assert located_types(plc) == [part_type], number
            name = "1-bracket" if number == 1 else "12_lid"
            assert robot.request("JOB") == "OK " + name
            checks += 1

        # A number no job has: ERROR 50, the job in force and its answers as before.
        s = load_job(plc, 7)
        assert s & ERROR, hex(s)
        assert plc.read(ERROR_CODE) == [50], plc.read(ERROR_CODE)
        assert plc.read(JOB_IN_FORCE) == [1]
        plc.write(CONTROL, CLEAR_ERROR)
        plc.write(CONTROL, 0)
        assert located_types(plc) == [1]
        checks += 1

        # A number past 9999 is refused by the register itself (exception 3).
        rr = plc.client.write_register(JOB_NUMBER, 10000, slave=UNIT)
        assert rr.isError() and rr.exception_code == 3, rr
        checks += 1

        # A job loaded over the robot port shows in JOB_IN_FORCE.
        assert robot.request("JOB LOAD 12_lid") == "OK 12_lid 1 0 1"
        assert plc.read(JOB_IN_FORCE) == [12]
        assert located_types(plc) == [5]
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
