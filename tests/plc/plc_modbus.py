"""What the PLC tests share: the register map of docs/PLC.md, a build-tree
binary read line by line, a robot connection and a pymodbus client with the
trigger handshake. Imported by plc_pymodbus_test.py and
plc_job_pymodbus_test.py (run from this folder)."""
import os
import queue
import socket
import subprocess
import threading
import time

from pymodbus.client import ModbusTcpClient

# docs/PLC.md, register map.
CONTROL, PART_TYPE, STATUS, HEARTBEAT, ERROR_CODE = 0, 1, 10, 11, 12
CALIBRATION, RESULT_FRAME, TRIGGER_COUNT = 13, 14, 15
FRAME_SEQUENCE, PART_COUNT, FIRST_PART, PART_STRIDE = 18, 20, 30, 10
TRIGGER, CLEAR_ERROR, RESULTS_ACK = 1, 2, 4
READY, BUSY, TRIGGER_ACK, RESULTS_VALID, ERROR = 1, 2, 4, 8, 16
ALL_TYPES = 0xFFFF
UNIT = 5


class Process:
    """A build-tree binary whose stdout lines are read by a thread."""

    def __init__(self, argv):
        self.proc = subprocess.Popen(argv, stdout=subprocess.PIPE, text=True)
        self.lines = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.proc.stdout:
            self.lines.put(line.rstrip("\n"))

    def wait_for(self, prefix, timeout=10.0):
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError(f"no line starting with {prefix!r}")
            try:
                line = self.lines.get(timeout=left)
            except queue.Empty:
                continue
            if line.startswith(prefix):
                return line[len(prefix):]

    def stop(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


class Robot:
    def __init__(self, port):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=20)
        self.file = self.sock.makefile("rw", newline="\n")

    def request(self, line):
        self.file.write(line + "\n")
        self.file.flush()
        return self.file.readline().rstrip("\n")


class Plc:
    def __init__(self, port):
        self.client = ModbusTcpClient("127.0.0.1", port=port, timeout=10)
        assert self.client.connect(), "cannot connect to the Modbus port"

    def read(self, address, count=1):
        rr = self.client.read_holding_registers(address, count, slave=UNIT)
        assert not rr.isError(), f"read {address}+{count}: {rr}"
        return rr.registers

    def write(self, address, value):
        rr = self.client.write_register(address, value, slave=UNIT)
        assert not rr.isError(), f"write {address}={value}: {rr}"

    def status(self):
        return self.read(STATUS)[0]

    def wait_for(self, any_bits, timeout=20.0):
        deadline = time.monotonic() + timeout
        while True:
            s = self.status()
            if s & any_bits:
                return s
            assert time.monotonic() < deadline, f"status {s:#x}: none of {any_bits:#x}"
            time.sleep(0.001)

    def trigger(self, part_type):
        """The handshake: wait ready, select, trigger, wait, drop the trigger."""
        self.wait_for(READY)
        self.write(PART_TYPE, part_type)
        self.write(CONTROL, TRIGGER)
        assert self.status() & (BUSY | TRIGGER_ACK | RESULTS_VALID | ERROR)
        self.wait_for(RESULTS_VALID | ERROR)
        self.write(CONTROL, 0)
        return self.status()

    def acknowledge(self):
        self.write(CONTROL, RESULTS_ACK)
        self.write(CONTROL, 0)


def video_server(bin_dir):
    """The video server of both tests: one L-shaped part, no noise, trigger
    mode, on ports it picks (read 'frames ' and 'control ' from it)."""
    return Process([os.path.join(bin_dir, "picksight-video-server"), "--source",
                    "cam0=synthetic:width=640,height=480,parts=1,types=l_shape,seed=3,noise=0",
                    "--frames", "tcp://127.0.0.1:*", "--control", "tcp://127.0.0.1:*",
                    "--mode", "trigger"])


def vision_app(bin_dir, frames, control, data_dir, *extra):
    """A vision app on that server with robot and Modbus ports on 127.0.0.1
    (read 'robot ', 'modbus ' and 'ready' from it), unit UNIT."""
    return Process([os.path.join(bin_dir, "picksight-vision"), "--frames", frames,
                    "--control", control, "--robot-port", "0", "--bind", "127.0.0.1",
                    "--data-dir", data_dir, "--modbus-port", "0", "--modbus-bind",
                    "127.0.0.1", "--modbus-unit", str(UNIT), *extra])
