"""RobotClient against a real cell: every command of docs/PROTOCOL.md with
its parsed reply, and ERROR replies raised with their code."""

import math
import socket
import time

import pytest

from conftest import Scene
from picksight import RobotClient, RobotError


def test_core_commands(synthetic_cell):
    _, vision = synthetic_cell
    with RobotClient("127.0.0.1", vision.port) as robot:
        robot.ping()
        assert robot.version()
        usages = robot.help()
        assert "| LOCATE <type> |" in usages and "| PING |" in usages
        status = robot.status()
        assert status["frame"] == "vision-px"
        assert status["scale"] is None and status["transform"] is None
        assert status["camera"] == "cam0"
        assert status["models"] == 0
        poses = robot.locate(1)  # no model: every region at its own pose
        assert len(poses) == 4
        assert all(0 <= p.rz < 360 and p.y <= 0 for p in poses)  # y up the image
        info = robot.frame()
        assert info.camera == "cam0" and info.width == 640 and info.height == 480
        assert info.triggered
        assert robot.status()["locates"] == 1
        blobs = robot.blobs()
        assert len(blobs) == 4
        assert blobs[0].area >= blobs[-1].area and isinstance(blobs[0].holes, int)


def test_error_replies_are_raised_with_their_code(synthetic_cell):
    _, vision = synthetic_cell
    with RobotClient("127.0.0.1", vision.port) as robot:
        with pytest.raises(RobotError) as e:
            robot.request("FLY")
        assert e.value.code == 10
        with pytest.raises(RobotError) as e:
            robot.request("LOCATE")
        assert e.value.code == 11 and "usage" in e.value.text
        with pytest.raises(RobotError) as e:
            robot.residuals()
        assert e.value.code == 44
        with pytest.raises(RobotError) as e:
            robot.delete(7)
        assert e.value.code == 40
        with pytest.raises(RobotError) as e:
            robot.compute()
        assert e.value.code == 41
        with pytest.raises(RobotError) as e:
            robot.learn(1)  # four parts in the frame
        assert e.value.code == 31
        with pytest.raises(RobotError) as e:
            robot.request("X" * 5000)
        assert e.value.code == 12
        robot.ping()  # the connection goes on
        with pytest.raises(ValueError):
            robot.request("PING\nPING")


def first_roi(robot, seconds=10):
    """The camera's region once it has opened: until then a ROI read is
    ERROR 20 (its size is not known yet), asked again as a client would."""
    deadline = time.monotonic() + seconds
    while True:
        try:
            return robot.roi()
        except RobotError as e:
            if e.code != 20 or time.monotonic() > deadline:
                raise
            time.sleep(0.05)


def test_camera_settings(synthetic_cell):
    _, vision = synthetic_cell
    with RobotClient("127.0.0.1", vision.port) as robot:
        assert tuple(first_roi(robot)) == (0, 0, 640, 480)
        robot.roi(100, 50, 320, 240)
        assert tuple(robot.roi()) == (100, 50, 320, 240)
        robot.roi_full()
        assert tuple(robot.roi()) == (0, 0, 640, 480)
        # The synthetic camera has no exposure feature.
        with pytest.raises(RobotError) as e:
            robot.exposure()
        assert e.value.code == 22
        with pytest.raises(ValueError):
            robot.roi(1, 2)
        # Trigger mode; the synthetic camera has no trigger input.
        assert robot.camera_mode() == ("SOFTWARE", None, None, None)
        with pytest.raises(RobotError) as e:
            robot.camera_mode("hardware", line="Line1", timeout=2)
        assert e.value.code == 22
        assert robot.camera_mode("free", fps=5) == ("FREE", 5.0, None, None)


def test_tolerances_read_changed_and_refused(cell_factory):
    _, vision = cell_factory("--source", "cam0=synthetic:width=640,height=480,parts=1,seed=3",
                             "--mode", "trigger")
    with RobotClient("127.0.0.1", vision.port) as robot:
        with pytest.raises(RobotError) as e:
            robot.tolerance(1)  # no model yet
        assert e.value.code == 32
        robot.learn(1, "part")
        before = robot.tolerance(1)
        assert (before.type, before.name) == (1, "part")
        keys = ["area_tolerance", "hu_tolerance", "verify_percent", "edge_tolerance_px",
                "mirror_symmetric"]
        assert list(before.values)[: len(keys)] == keys
        assert isinstance(before.values["mirror_symmetric"], bool)

        after = robot.tolerance(1, area_tolerance=0.25, edge_tolerance_px=2.5,
                                mirror_symmetric=not before.values["mirror_symmetric"])
        assert after.values["area_tolerance"] == pytest.approx(0.25)
        assert after.values["edge_tolerance_px"] == pytest.approx(2.5)
        assert after.values["mirror_symmetric"] != before.values["mirror_symmetric"]
        assert after.values["hu_tolerance"] == before.values["hu_tolerance"]
        assert robot.tolerance(1) == after  # stored: read back the same

        # One bad pair: refused naming its key, and nothing changes.
        with pytest.raises(RobotError) as e:
            robot.tolerance(1, hu_tolerance=1.0, area_tolerance=1.5)
        assert e.value.code == 11 and "area_tolerance" in e.value.text
        with pytest.raises(RobotError) as e:
            robot.tolerance(1, wobble=3)
        assert e.value.code == 11 and "wobble" in e.value.text
        assert robot.tolerance(1) == after
        # LEARN's own judgement of the part's symmetry back: the next LOCATE
        # finds it with the wider area tolerance.
        mirror = before.values["mirror_symmetric"]
        assert robot.tolerance(1, mirror_symmetric=mirror).values["mirror_symmetric"] == mirror
        assert len(robot.locate(1)) == 1

        # A part that looks alike turned keeps its origin at its centre.
        with pytest.raises(RobotError) as e:
            robot.learn_view(1)
        assert e.value.code == 39 and "symmetry" in e.value.text

        # Tried, not stored; then each change taken back, newest first.
        tried = robot.try_learn(2, "again")
        assert (tried.model.type, tried.found, tried.parts) == (2, 1, 1), tried
        assert any(w.startswith("looks like type 1 (part)") for w in tried.warnings), tried
        assert [m.type for m in robot.models()] == [1]
        undone = robot.undo()
        assert undone == (1, True, 2, f"TOLERANCE 1 mirror_symmetric {int(mirror)}"), undone
        assert robot.tolerance(1) == after
        assert robot.undo().left == 1
        assert robot.tolerance(1) == before
        assert robot.undo() == (1, False, 0, "LEARN 1 part")
        assert robot.models() == []
        with pytest.raises(RobotError) as e:
            robot.undo()
        assert e.value.code == 37 and "nothing to undo" in e.value.text


def test_vision_settings_read_changed_refused_and_models_named(cell_factory, tmp_path):
    scene = Scene(tmp_path)
    scene.show([(320, 240, 40)])
    _, vision = cell_factory("--source", f"cam0=file:{scene.path}", "--mode", "trigger")
    with RobotClient("127.0.0.1", vision.port) as robot:
        first = robot.vision_settings()
        assert first.values == {"polarity": "dark", "threshold": "adaptive", "level": 128,
                                "window": 0, "min_area": "auto", "min_hole_area": 0.0}
        assert (first.reteach, first.notes) == ([], [])
        robot.learn(1, "disc")
        scene.show([(160, 240, 40), (320, 240, 40), (480, 240, 40)])
        assert len(robot.locate(1)) == 3

        # Several keys at once; numbers and words as the reply gives them.
        changed = robot.vision_settings(threshold="fixed", level=100, min_area=300.5)
        assert changed.values["threshold"] == "fixed" and changed.values["level"] == 100
        assert changed.values["min_area"] == pytest.approx(300.5)
        # The model lets regions down to the area it was taught with through.
        assert changed.reteach == ["1 (disc) keeps regions from 50.000 px"]
        assert robot.vision_settings().values == changed.values
        assert len(robot.locate(1)) == 3

        # Dark discs on a light surface taken as light parts: the model,
        # taught as dark, is named; the discs are no longer found.
        light = robot.vision_settings(polarity="light")
        assert light.values["polarity"] == "light"
        assert light.reteach == ["1 (disc) taught as dark on its surface"]
        # Most of the frame, the light surface, is now taken for part.
        assert len(light.notes) == 1 and light.notes[0].startswith("hint: "), light.notes
        assert light.notes[0].endswith("need VISION polarity dark"), light.notes
        assert robot.locate(1) == []
        with pytest.raises(RobotError) as e:
            robot.vision_settings(polarity="dark", level=256)
        assert e.value.code == 11 and "level must be" in e.value.text
        with pytest.raises(RobotError) as e:
            robot.vision_settings(wobble=3)
        assert e.value.code == 11 and "no key 'wobble'" in e.value.text
        with pytest.raises(ValueError):
            robot.vision_settings(polarity="dark light")
        assert robot.vision_settings().values["polarity"] == "light"

        back = robot.vision_settings(polarity="dark", threshold="adaptive", min_area="auto")
        assert back.values == dict(first.values, level=100)
        assert back.reteach == []
        assert len(robot.locate(1)) == 3
        assert robot.vision_settings_reset().values == robot.vision_settings().values


def test_a_whole_set_up_calibrate_teach_grip_pick(cell_factory, tmp_path):
    scene = Scene(tmp_path)
    _, vision = cell_factory("--source", f"cam0=file:{scene.path}", "--mode", "trigger")
    with RobotClient("127.0.0.1", vision.port, timeout=20) as robot:
        with pytest.raises(RobotError) as e:
            robot.calcam(10)
        assert e.value.code == 1  # empty scene
        scene.show([(320.3, 240.7, 40)])
        mm_x, mm_y = robot.calcam(10)  # 10 mm radius, 40 px: 0.25 mm per pixel
        assert mm_x == pytest.approx(0.25, rel=0.005)
        assert mm_y == pytest.approx(0.25, rel=0.005)
        assert robot.status()["frame"] == "vision-mm"

        # Robot frame: vision mm turned by 30 degrees and moved.
        a = math.radians(30)

        def to_robot(px, py):
            vx, vy = px * mm_x, -py * mm_y
            return (math.cos(a) * vx - math.sin(a) * vy + 400.0,
                    math.sin(a) * vx + math.cos(a) * vy - 100.0)

        pixels = [(100.2, 90.6), (520.8, 110.1), (480.4, 400.3), (130.7, 380.9)]
        for i, (px, py) in enumerate(pixels):
            scene.show([(px, py, 20)])
            assert robot.store(*to_robot(px, py)) == i + 1
        points = robot.list_points()
        assert [p.id for p in points] == [1, 2, 3, 4]
        assert points[0].xr == pytest.approx(to_robot(*pixels[0])[0], abs=0.01)
        t = robot.compute("LSQ")
        assert (t.dx, t.dy, t.rz) == pytest.approx((400.0, -100.0, 30.0), abs=0.1)
        assert t.rms < 0.1
        assert len(robot.residuals()) == 4
        status = robot.status()
        assert status["frame"] == "robot"
        assert status["transform"] == pytest.approx((t.dx, t.dy, t.rz), abs=0.001)

        scene.show([(250.4, 200.6, 30)])
        model = robot.learn(3, "disc")
        assert (model.type, model.name, model.holes) == (3, "disc", 0)
        assert model.area > 0
        models = robot.models()
        assert [(m.type, m.name) for m in models] == [(3, "disc")]
        assert robot.grasp_add(3, 0, 0, 0) == 1
        assert robot.grasp_add(3, 5, 0, 90) == 2
        assert robot.grasp_list(3)[1] == pytest.approx((5, 0, 90))
        assert robot.gripper_finger(3, 0, 12, 6, 4) == 1
        assert robot.gripper_list(3)[0].width == pytest.approx(6)
        poses = robot.locate(3)
        assert len(poses) == 1
        assert (poses[0].x, poses[0].y) == pytest.approx(to_robot(250.4, 200.6), abs=0.2)
        with pytest.raises(RobotError) as e:
            robot.locate(4)
        assert e.value.code == 32
        robot.gripper_clear(3)
        assert robot.gripper_list(3) == []
        robot.grasp_clear(3)
        assert robot.grasp_list(3) == []
        robot.delete(4)
        assert len(robot.list_points()) == 3
        robot.forget(3)
        assert robot.models() == []


def test_a_closed_port_is_a_connection_error():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))  # bound, not listening: connections are refused
    port = s.getsockname()[1]
    with pytest.raises(ConnectionRefusedError):
        RobotClient("127.0.0.1", port, timeout=2)
    s.close()


def test_no_reply_in_time_is_a_timeout_and_closes_the_client():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(1)  # accepts (the kernel does) and never answers
    robot = RobotClient("127.0.0.1", s.getsockname()[1], timeout=0.2)
    with pytest.raises(TimeoutError):
        robot.ping()
    with pytest.raises(OSError):
        robot.ping()  # closed: a late reply can never be taken for another's
    s.close()


def test_jobs_saved_listed_loaded_and_refused(cell_factory, tmp_path):
    scene = Scene(tmp_path)
    scene.show([(320, 240, 40)])
    _, vision = cell_factory("--source", f"cam0=file:{scene.path}", "--mode", "trigger")
    with RobotClient("127.0.0.1", vision.port) as robot:
        assert robot.job_current() is None
        robot.learn(1, "disc")
        saved = robot.job_save("1-discs")
        assert (saved.name, saved.models, saved.calibrated) == ("1-discs", 1, False)
        assert saved.bytes > 0
        robot.forget(1)
        robot.learn(2, "disc")
        robot.job_save("2-other")
        assert robot.job_list() == ["1-discs", "2-other"]
        loaded = robot.job_load("1-discs")
        assert (loaded.name, loaded.models, loaded.bytes) == ("1-discs", 1, None)
        assert [m.type for m in robot.models()] == [1]
        assert robot.job_current() == "1-discs"
        with pytest.raises(RobotError) as e:
            robot.job_load("nothing")
        assert e.value.code == 50
        with pytest.raises(RobotError) as e:
            robot.job_save("../x")
        assert e.value.code == 54
        robot.job_delete("2-other")
        assert robot.job_list() == ["1-discs"]


def test_learn_view_reads_the_part_again_and_undo_takes_it_back(cell_factory):
    _, vision = cell_factory(
        "--source", "cam0=synthetic:width=640,height=480,parts=1,types=l_shape,seed=3,scene_every=1",
        "--mode", "trigger")
    with RobotClient("127.0.0.1", vision.port) as robot:
        with pytest.raises(RobotError) as e:
            robot.learn_view(1)  # nothing taught
        assert e.value.code == 32
        robot.learn(1, "bracket")
        view = robot.learn_view(1)
        assert (view.type, view.name, view.views) == (1, "bracket", 2), view
        assert abs(view.dx) < 0.5 and abs(view.dy) < 0.5 and view.spread >= 0, view
        assert view.reading is not None and abs(view.reading[0]) < 1, view
        assert robot.learn_view(1, at=(0, 0, 640, 480)).views == 3
        assert robot.undo().change == "LEARNVIEW 1 AT 0 0 640 480"
        assert robot.learn_view(1).views == 3
