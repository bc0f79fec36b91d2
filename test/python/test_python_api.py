"""The Python module laser_raycast, against distances worked out by hand and against cast_scan.

Run by the README's test command (catkin's run_tests, through pytest: CMakeLists.txt), in the
devel space's environment: package:// URIs resolve and `import laser_raycast` finds the module.
"""

import math
import os
import pydoc
import subprocess
import threading
import time

import numpy as np
import pytest

import laser_raycast as lr

DEMO_ROOM = "package://laser_raycast/worlds/demo_room.urdf"

# A wall x in [5, 5.2], |y| <= 10, |z| <= 2.5 on the link "world", and a box 0.4 m wide on a
# prismatic joint along y: at joint value q its centre is at (3, 2 + q, 0).
WALL_URDF = """<robot name="walls">
  <link name="world">
    <visual><origin xyz="5.1 0 0"/><geometry><box size="0.2 20 5"/></geometry></visual>
  </link>
  <link name="slider">
    <visual><geometry><box size="0.4 0.4 0.4"/></geometry></visual>
  </link>
  <joint name="slide" type="prismatic">
    <parent link="world"/><child link="slider"/>
    <origin xyz="3 2 0"/><axis xyz="0 1 0"/><limit lower="-5" upper="5" effort="1" velocity="1"/>
  </joint>
</robot>"""


def pose(x=0.0, y=0.0, z=0.0, yaw=0.0):
    m = np.eye(4)
    m[0, 0] = m[1, 1] = math.cos(yaw)
    m[0, 1], m[1, 0] = -math.sin(yaw), math.sin(yaw)
    m[:3, 3] = (x, y, z)
    return m


def cast_scan_binary():
    """cast_scan of the same build as the module (the devel space's lib directory)."""
    module_dir = os.path.dirname(lr._laser_raycast.__file__)
    devel = os.path.abspath(os.path.join(module_dir, "..", "..", "..", ".."))
    path = os.path.join(devel, "lib", "laser_raycast", "cast_scan")
    if not os.path.exists(path):
        pytest.skip("no cast_scan beside the module (an installed package)")
    return path


@pytest.fixture(scope="module")
def walls():
    return lr.Scene.from_urdf(WALL_URDF)


def test_a_fan_sees_the_wall_at_the_range_worked_out_by_hand(walls):
    pattern = lr.Pattern.fan(-0.3, 0.3, samples=61)
    xs = np.linspace(-2.0, 1.0, 7)
    poses = np.stack([pose(x, -4.0) for x in xs])  # beside the slider, which stays out of view
    scans = lr.Caster(threads=1).cast(walls, poses, pattern, range_max=50)
    assert scans.ranges.shape == (7, 61) and scans.ranges.dtype == np.float64
    assert scans.links.dtype == np.int32
    azimuths = np.array(pattern.azimuths)
    expected = (5.0 - xs)[:, None] / np.cos(azimuths)[None, :]
    np.testing.assert_allclose(scans.ranges, expected, rtol=0, atol=1e-9)
    assert set(scans.links.ravel()) == {walls.link_names.index("world")}


def test_points_are_the_ranges_along_the_beams(walls):
    pattern = lr.Pattern.rings(-0.5, 0.5, [-0.2, 0.0, 0.3], samples=11)
    scans = lr.Caster().cast(walls, pose(0, -4)[None], pattern, points=True, range_max=50)
    assert scans.points.shape == (1, 33, 3)
    np.testing.assert_allclose(scans.points[0], scans.ranges[0][:, None] * pattern.directions,
                               atol=1e-12)
    np.testing.assert_allclose(scans.points[0][:, 0], 5.0, atol=1e-9)  # all on the wall's face


def test_joints_and_link_poses_move_the_links(walls):
    pattern = lr.Pattern.fan(-0.01, 0.01, samples=3)
    at_slider = pose(0, 0, 0, math.atan2(2.0, 3.0))  # looking at the slider's centre
    caster = lr.Caster(threads=1)
    # At joint 0 the beam meets the slider's face x = 2.8, in front of the wall.
    r0 = caster.cast(walls, at_slider[None], pattern).ranges[0, 1]
    assert r0 == pytest.approx(2.8 * math.hypot(3, 2) / 3, abs=1e-9)
    # Slid 1 m away along y, the beam passes beside it onto the wall.
    r1 = caster.cast(walls, at_slider[None], pattern, joints={"slide": 1.0}).ranges[0, 1]
    assert r1 == pytest.approx(5.0 * math.hypot(3, 2) / 3, abs=1e-9)
    # The same by placing the link, once for all scans and per scan.
    moved = pose(3, 3)
    r2 = caster.cast(walls, at_slider[None], pattern, link_poses={"slider": moved}).ranges[0, 1]
    assert r2 == r1
    two = np.stack([pose(3, 2), pose(3, 3)])
    both = caster.cast(walls, np.stack([at_slider] * 2), pattern, link_poses={"slider": two})
    assert both.ranges[0, 1] == r0 and both.ranges[1, 1] == r1


def test_the_ranges_are_those_cast_scan_prints(tmp_path):
    scene = lr.Scene.from_urdf(DEMO_ROOM)
    pattern = lr.Pattern.fan(-2.0, 2.0, samples=201)
    sensors = [(0.0, 0.0, 0.3, 0.0), (1.0, -0.5, 0.25, 0.7), (-1.5, 1.0, 0.5, -2.0)]
    poses = np.stack([pose(x, y, z, yaw) for x, y, z, yaw in sensors])
    scans = lr.Caster().cast(scene, poses, pattern, range_min=0.1, range_max=12)
    path = tmp_path / "poses.txt"
    path.write_text("".join(f"{x!r},{y!r},{z!r},0,0,{yaw!r}\n" for x, y, z, yaw in sensors))
    out = subprocess.run(
        [cast_scan_binary(), "--urdf", DEMO_ROOM, "--poses", str(path), "--angle-min", "-2",
         "--angle-max", "2", "--samples", "201", "--range-min", "0.1", "--range-max", "12"],
        check=True, capture_output=True, text=True).stdout.splitlines()
    assert out[0] == "pose,index,angle,range,link"
    rows = [line.split(",") for line in out[1:]]
    assert len(rows) == 3 * 201
    for k, i, _, text, link in rows:
        k, i = int(k), int(i)
        assert "%.9g" % scans.ranges[k, i] == text, (k, i)
        name = scene.link_names[scans.links[k, i]] if scans.links[k, i] >= 0 else ""
        assert name == link, (k, i)


def test_any_thread_count_gives_the_same_scans():
    scene = lr.Scene.from_urdf(DEMO_ROOM)
    pattern = lr.Pattern.preset("VLP-16")
    poses = np.stack([pose(0.1 * k, 0.05 * k, 0.4, 0.3 * k) for k in range(6)])
    one = lr.Caster(threads=1).cast(scene, poses, pattern)
    two = lr.Caster(threads=2).cast(scene, poses, pattern)
    np.testing.assert_array_equal(one.ranges, two.ranges)
    np.testing.assert_array_equal(one.links, two.links)
    assert np.isfinite(one.ranges).sum() > 0.5 * one.ranges.size  # a closed room: most beams hit


def test_presets_bring_their_range_limits():
    pattern = lr.Pattern.preset("UTM-30LX")
    assert pattern.size == 1081 and pattern.elevations == [0.0]
    assert (pattern.range_min, pattern.range_max, pattern.rate) == (0.1, 30.0, 40.0)
    scene = lr.Scene.from_urdf(DEMO_ROOM)
    scans = lr.Caster().cast(scene, pose(0, 0, 0.3)[None], pattern)
    finite = scans.ranges[np.isfinite(scans.ranges)]
    assert finite.min() >= 0.1 and finite.max() <= 30.0
    assert lr.Pattern.fan(-1, 1, samples=3).range_max is None
    # A Velodyne preset fires its lasers as the user manual says (the node's preset): 1808
    # sequences of 16 in its 0.1 s turn, laser i of sequence q at q * 55.296 + i * 2.304 us.
    vlp = lr.Pattern.preset("VLP-16")
    assert vlp.off_grid and vlp.size == 16 * 1808 and vlp.elevations is None
    assert (vlp.range_min, vlp.range_max, vlp.rate) == (0.4, 100.0, 10.0)
    np.testing.assert_allclose(vlp.times[16 * 5 + 3], 5 * 55.296e-6 + 3 * 2.304e-6, rtol=1e-12)
    assert vlp.lines[:4] == [0, 8, 1, 9]  # laser ids 0..3 at -15, 1, -13, 3 deg
    # The OS1-64 as its nominal metadata file in the package places its beams: 1024 columns of 64,
    # each from its beam origin off the axis.
    os1 = lr.Pattern.preset("OS1-64")
    assert os1.off_grid and os1.size == 64 * 1024
    assert np.all(np.linalg.norm(os1.origins, axis=1) > 0.01)


def test_rep117_and_the_min_range_policy(walls):
    pattern = lr.Pattern.fan(-0.1, 0.1, samples=3)
    at = pose(4.0, -4.0)[None]  # 1 m from the wall
    assert np.all(lr.Caster().cast(walls, at, pattern, range_min=2).ranges == -np.inf)
    assert np.all(np.isnan(lr.Caster().cast(walls, at, pattern, range_min=2,
                                            min_range_policy="nan").ranges))
    far = lr.Caster().cast(walls, pose(0, 0, 0, math.pi)[None], pattern, range_max=5)
    assert np.all(far.ranges == np.inf) and np.all(far.links == -1)
    bad = np.zeros((1, 4, 4))  # not a rigid transform: nothing can be cast from it
    assert np.all(np.isnan(lr.Caster().cast(walls, bad, pattern).ranges))


def test_the_measurement_model_is_an_option(walls):
    pattern = lr.Pattern.fan(-0.3, 0.3, samples=301)
    poses = np.stack([pose(0, -4)] * 4)
    exact = lr.Caster().cast(walls, poses, pattern, range_max=50).ranges
    noisy = lr.Measurement(noise_stddev=0.05, noise_seed=7)
    a = lr.Caster().cast(walls, poses, pattern, range_max=50, measurement=noisy).ranges
    b = lr.Caster().cast(walls, poses, pattern, range_max=50, measurement=noisy).ranges
    np.testing.assert_array_equal(a, b)  # the same seed, the same draws
    assert 0.03 < np.std(a - exact) < 0.07
    assert not np.array_equal(a[0], a[1])  # the draws continue from scan to scan
    lost = lr.Caster().cast(walls, poses, pattern, range_max=50,
                            measurement=lr.Measurement(dropout_probability=0.5)).ranges
    assert 0.3 < np.mean(lost == np.inf) < 0.7
    lit = lr.Caster().cast(walls, poses[:1], pattern, range_max=50,
                           measurement=lr.Measurement(intensity=True, reflectivity={"world": 0.5}))
    expected = 0.5 * np.cos(np.array(pattern.azimuths))  # reflectivity x cos(incidence)
    np.testing.assert_allclose(lit.intensity[0], expected, atol=1e-6)
    assert exact is not None and lr.Caster().cast(walls, poses, pattern).intensity is None


def test_bad_arguments_raise_errors_that_name_them(walls):
    pattern = lr.Pattern.fan(-1, 1, samples=5)
    caster = lr.Caster()
    cases = [
        (lambda: caster.cast(walls, np.eye(3), pattern), ValueError, "sensor_poses"),
        (lambda: caster.cast(walls, "here", pattern), TypeError, "sensor_poses"),
        (lambda: caster.cast(walls, np.eye(4)[None], pattern, link_poses={"nowhere": np.eye(4)}),
         ValueError, "nowhere"),
        (lambda: caster.cast(walls, np.eye(4)[None], pattern, link_poses={"slider": "x"}),
         TypeError, "link_poses['slider']"),
        (lambda: caster.cast(walls, np.stack([np.eye(4)] * 2), pattern,
                             link_poses={"slider": np.stack([np.eye(4)] * 3)}),
         ValueError, "3 poses for 2"),
        (lambda: caster.cast(walls, np.eye(4)[None], pattern, joints={"no_joint": 1.0}),
         ValueError, "no_joint"),
        (lambda: caster.cast(walls, np.eye(4)[None], pattern, range_max=-1), ValueError,
         "range_max"),
        (lambda: caster.cast(walls, np.eye(4)[None], pattern, min_range_policy="zero"),
         ValueError, "zero"),
        (lambda: lr.Pattern.fan(-1, 1), ValueError, "samples"),
        (lambda: lr.Pattern.fan(1, -1, samples=3), ValueError, "angle_max"),
        (lambda: lr.Pattern.rings(-1, 1, [0.1, 0.1], samples=3), ValueError, "elevations"),
        (lambda: lr.Pattern.preset("VLP-17"), ValueError, "VLP-17"),
        (lambda: lr.Pattern.preset("OS1-64-realistic"), ValueError, 'Pattern.preset("OS1-64")'),
        (lambda: lr.Pattern.preset("VLP-16-realistic"), ValueError, "no realistic variant"),
        (lambda: lr.Measurement(noise_stddev=-1), ValueError, "noise_stddev"),
        (lambda: lr.Caster(threads=-2), ValueError, "threads"),
        (lambda: lr.Scene.from_urdf(WALL_URDF, geometry="both"), ValueError, "both"),
        (lambda: lr.Scene.from_urdf("/no/such/file.urdf"), lr.SceneLoadError, "/no/such/file.urdf"),
        (lambda: lr.Scene.from_urdf("<robot name='x'><link>"), lr.SceneLoadError, "URDF"),
    ]
    for call, error, words in cases:
        with pytest.raises(error) as raised:
            call()
        assert words in str(raised.value), (words, str(raised.value))


def test_a_model_that_fails_to_load_leaves_the_scene_as_it_was(walls):
    scene = lr.Scene.from_urdf(WALL_URDF)
    before = scene.bodies
    with pytest.raises(lr.SceneLoadError):
        scene.add_urdf("<robot name='broken'><link name='a'><visual><geometry>"
                       "<mesh filename='/no/such/mesh.stl'/></geometry></visual></link></robot>")
    assert scene.bodies == before
    scene.add_urdf(WALL_URDF, tf_prefix="second/")
    assert scene.bodies == 2 * before and "second/slider" in scene.link_names


def test_the_gil_is_released_while_casting():
    scene = lr.Scene.from_urdf(DEMO_ROOM)
    pattern = lr.Pattern.preset("OS1-64")
    poses = np.stack([pose(0, 0, 0.5, 0.01 * k) for k in range(40)])
    started, done = threading.Event(), threading.Event()
    took = []

    def work():
        started.set()
        t0 = time.perf_counter()
        lr.Caster(threads=1).cast(scene, poses, pattern)
        took.append(time.perf_counter() - t0)
        done.set()

    worker = threading.Thread(target=work)
    worker.start()
    started.wait()
    # This thread runs during the cast only if the cast lets go of the GIL: then it sees the clock
    # advance through most of the cast; holding it, the cast would freeze this loop until it ends.
    first = last = time.perf_counter()
    while not done.is_set():
        last = time.perf_counter()
    worker.join()
    assert took[0] > 0.05
    assert last - first > 0.5 * took[0]


def test_help_describes_the_module():
    text = pydoc.render_doc(lr, renderer=pydoc.plaintext)
    for words in ["class Scene", "from_urdf", "class Pattern", "preset", "from_calibration",
                  "from_ouster_metadata", "from_pattern_file", "class Caster",
                  "sensor_poses", "REP 117", "class Measurement", "noise_stddev"]:
        assert words in text, words


def cast_scan_rows(args):
    """cast_scan's CSV rows (after the header) as lists of fields, and the header."""
    out = subprocess.run([cast_scan_binary()] + args, check=True, capture_output=True,
                         text=True).stdout.splitlines()
    return out[0], [line.split(",") for line in out[1:]]


def test_a_pattern_file_casts_each_scan_from_its_rows_at_the_ranges_worked_out_by_hand(
        walls, tmp_path):
    # Five rows, two a scan: scan k takes rows 2k, 2k + 1, round the file's end (a loop).
    rows = [(0.0, 0.0, 90.0, 0), (1e-5, 20.0, 80.0, 1), (2e-5, -30.0, 100.0, 2),
            (3e-5, 10.0, 60.0, 3), (4e-5, -5.0, 95.0, 0)]
    path = tmp_path / "pattern.csv"
    path.write_text("Time/s,Azimuth/deg,Zenith/deg,Line\n" +
                    "".join(f"{t},{a},{z},{line}\n" for t, a, z, line in rows))
    pattern = lr.Pattern.from_pattern_file(str(path), point_rate=1000.0, points_per_scan=2)
    assert pattern.off_grid and pattern.size == 2 and pattern.azimuths is None
    assert pattern.lines == [0, 1] and pattern.times == [0.0, 0.001]
    xs = [0.0, 1.0, 2.0]
    poses = np.stack([pose(x, -4.0) for x in xs])
    scans = lr.Caster().cast(walls, poses, pattern, range_max=50, points=True)
    assert scans.ranges.shape == (3, 2)
    for k, x in enumerate(xs):
        for j in range(2):
            _, a, z, _ = rows[(2 * k + j) % len(rows)]
            a, z = math.radians(a), math.radians(z)
            # The wall's face x = 5 along (sin z cos a, sin z sin a, cos z) from (x, -4, 0).
            assert scans.ranges[k, j] == pytest.approx((5.0 - x) / (math.sin(z) * math.cos(a)),
                                                       abs=1e-9), (k, j)
            assert scans.points[k, j, 0] == pytest.approx(5.0 - x, abs=1e-9)


@pytest.mark.parametrize("flag,make", [
    ("--calibration", lambda path: lr.Pattern.from_calibration(path)),
    ("--ouster-metadata", lambda path: lr.Pattern.from_ouster_metadata(path)),
    ("--pattern-file", lambda path: lr.Pattern.from_pattern_file(path, 100000.0, 3000)),
])
def test_beams_off_a_grid_give_the_ranges_cast_scan_prints(flag, make, tmp_path):
    here = os.path.dirname(os.path.abspath(__file__))
    files = {"--calibration": os.path.join(here, "..", "data", "vlp16_calibration.yaml"),
             "--ouster-metadata": os.path.join(here, "..", "..", "config", "ouster",
                                               "os1_64_nominal.json"),
             "--pattern-file": os.path.join(here, "..", "..", "config", "patterns",
                                            "rosette_4line.csv")}
    scene = lr.Scene.from_urdf(DEMO_ROOM)
    pattern = make(files[flag])
    sensors = [(0.0, 0.0, 0.4, 0.0), (1.0, -0.5, 0.3, 0.7), (-1.2, 0.8, 0.6, -2.0)]
    poses = np.stack([pose(x, y, z, yaw) for x, y, z, yaw in sensors])
    scans = lr.Caster().cast(scene, poses, pattern, range_min=0.2, range_max=12, points=True)
    path = tmp_path / "poses.txt"
    path.write_text("".join(f"{x!r},{y!r},{z!r},0,0,{yaw!r}\n" for x, y, z, yaw in sensors))
    extra = ["--point-rate", "100000", "--points-per-scan", "3000"] if flag == "--pattern-file" \
        else []
    header, rows = cast_scan_rows(["--urdf", DEMO_ROOM, "--poses", str(path), flag, files[flag],
                                   "--range-min", "0.2", "--range-max", "12"] + extra)
    assert header == "pose,index,line,azimuth,elevation,time,range,link"
    assert len(rows) == scans.ranges.size
    lines = np.array(pattern.lines)
    for k, i, line, _, _, _, text, link in rows:
        k, i = int(k), int(i)
        assert "%.9g" % scans.ranges[k, i] == text, (k, i)
        name = scene.link_names[scans.links[k, i]] if scans.links[k, i] >= 0 else ""
        assert name == link, (k, i)
        if flag != "--pattern-file" or k == 0:
            assert int(line) == lines[i], (k, i)
    assert np.isfinite(scans.ranges).mean() > 0.5  # a closed room: most beams hit
    # Points leave from each beam's origin (a calibrated head's offsets) along its direction.
    first = scans.ranges[0]
    hit = np.isfinite(first)
    expected = pattern.origins + first[:, None] * pattern.directions
    np.testing.assert_allclose(scans.points[0][hit], expected[hit], atol=1e-12)
    assert np.all(np.isnan(scans.points[0][~hit]))


def test_off_grid_readers_raise_errors_that_name_the_argument():
    here = os.path.dirname(os.path.abspath(__file__))
    calibration = os.path.join(here, "..", "data", "vlp16_calibration.yaml")
    cases = [
        (lambda: lr.Pattern.from_calibration("/no/such/calibration.yaml"), ValueError,
         "/no/such/calibration.yaml"),
        (lambda: lr.Pattern.from_calibration(calibration, scan_time=0.0), ValueError, "scan_time"),
        (lambda: lr.Pattern.from_ouster_metadata(calibration), ValueError,
         "beam_altitude_angles"),
        (lambda: lr.Pattern.from_pattern_file(calibration, 1000.0), ValueError, calibration),
        (lambda: lr.Pattern.from_pattern_file(calibration, 0.0), ValueError, "point_rate"),
        (lambda: lr.Pattern.from_calibration(42), TypeError, "from_calibration"),
    ]
    for call, error, words in cases:
        with pytest.raises(error) as raised:
            call()
        assert words in str(raised.value), (words, str(raised.value))
