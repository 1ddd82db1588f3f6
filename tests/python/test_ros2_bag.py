"""Maps from ROS 2 bags written by an independent writer (`rosbags`, pure Python CDR and MCAP).

A `qrm sim` run is read with the `mcap` package and its scans re-recorded as
`sensor_msgs/msg/LaserScan` in a rosbag2 MCAP bag, no return as +inf (REP 117) rather than
qrm's "max range + 1": the map from the bag must equal the map from qrm's own log.
"""
import json
import pathlib
import subprocess

import numpy as np
import pytest

import qrm

rosbags = pytest.importorskip("rosbags")
from mcap.reader import make_reader  # noqa: E402
from rosbags.rosbag2 import StoragePlugin, Writer  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402


def _sim(qrm_bin: str, out: pathlib.Path) -> pathlib.Path:
    subprocess.run([qrm_bin, "sim", "--scenario", "qlink-200", "--seed", "3", "--out", str(out)], check=True, capture_output=True)
    return out / "run.mcap"


def _ros2_bag_from(log: pathlib.Path, bag_dir: pathlib.Path, topic: str = "/scan") -> pathlib.Path:
    store = get_typestore(Stores.ROS2_HUMBLE)
    LaserScan = store.types["sensor_msgs/msg/LaserScan"]
    Header = store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    with Writer(bag_dir, version=8, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection(topic, LaserScan.__msgtype__, typestore=store)
        with open(log, "rb") as f:
            for _schema, channel, message in make_reader(f).iter_messages(topics=["/scan"]):
                m = json.loads(message.data)
                range_max = float(channel.metadata["range_max"])
                # qrm writes no return as null; REP 117 says +inf
                ranges = np.asarray(
                    [np.inf if r is None else r for r in m["ranges"]], dtype=np.float32
                )
                ranges[ranges > range_max] = np.inf
                n = len(ranges)
                start, end = m["start_angle"], m["end_angle"]
                msg = LaserScan(
                    header=Header(stamp=Time(sec=m["timestamp"]["sec"], nanosec=m["timestamp"]["nsec"]), frame_id="laser"),
                    angle_min=np.float32(start),
                    angle_max=np.float32(end),
                    angle_increment=np.float32((end - start) / (n - 1)),
                    time_increment=0.0,
                    scan_time=0.1,
                    range_min=0.0,
                    range_max=range_max,
                    ranges=ranges,
                    intensities=np.zeros(0, dtype=np.float32),
                )
                writer.write(conn, message.log_time, store.serialize_cdr(msg, LaserScan.__msgtype__))
    bags = sorted(bag_dir.glob("*.mcap"))
    assert len(bags) == 1
    return bags[0]


def _map(qrm_bin: str, src: pathlib.Path, out: pathlib.Path, *extra: str) -> dict:
    subprocess.run(
        [qrm_bin, "map", "--format", "mcap", "--input", str(src), "--samples", "200", "--out", str(out), *extra],
        check=True, capture_output=True,
    )
    return json.loads((out / "map.json").read_text())


def test_a_ros2_bag_of_a_sim_run_maps_exactly_as_qrms_own_log(qrm_bin, tmp_path):
    log = _sim(qrm_bin, tmp_path / "sim")
    bag = _ros2_bag_from(log, tmp_path / "bag")
    with open(bag, "rb") as f:
        schemas = {s.name: s.encoding for s in make_reader(f).get_summary().schemas.values()}
    assert schemas == {"sensor_msgs/msg/LaserScan": "ros2msg"}
    ours = _map(qrm_bin, log, tmp_path / "m_ours", "--topic", "/scan")
    theirs = _map(qrm_bin, bag, tmp_path / "m_bag")  # the bag's only topic is chosen by itself
    assert len(ours["sets"]) > 100, "the lidar scans gave a real map"
    assert ours == theirs


def test_read_observations_reads_a_ros2_bag_like_the_sim_log(qrm_bin, tmp_path):
    log = _sim(qrm_bin, tmp_path / "sim")
    bag = _ros2_bag_from(log, tmp_path / "bag", topic="/robot/scan")
    a, truth_a = qrm.read_observations(str(log), format="mcap", topic="/scan")
    b, truth_b = qrm.read_observations(str(bag), format="mcap", topic=["/robot/scan"])
    assert truth_a is None and truth_b is None, "recogniser ids are not the surveyed ids"
    assert len(a) == len(b) > 100
    for x, y in zip(a, b):
        assert x["t"] == y["t"]
        np.testing.assert_array_equal(x["ids"], y["ids"])
        np.testing.assert_array_equal(x["xy"], y["xy"])
    # Detections carry the true ids: the log's surveyed truth comes with them.
    d, truth = qrm.read_observations(str(log), format="mcap")
    assert truth is not None and set(int(i) for s in d for i in s["ids"]) <= set(truth)


def test_a_missing_topic_or_unreadable_schema_names_the_topic_and_what_is_there(qrm_bin, tmp_path):
    log = _sim(qrm_bin, tmp_path / "sim")
    with pytest.raises(qrm.InvalidInput, match=r"no topic /lidar; topics present: .*/scan \(foxglove.LaserScan"):
        qrm.read_observations(str(log), format="mcap", topic="/lidar")
    with pytest.raises(qrm.InvalidInput, match=r"topic /tf has schema `foxglove.FrameTransform`"):
        qrm.read_observations(str(log), format="mcap", topic="/tf")
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(log.read_bytes()[: 2_000_000])
    with pytest.raises(qrm.FormatError, match=r"cut.mcap: not a readable MCAP file after \d+ messages"):
        qrm.read_observations(str(cut), format="mcap")
    scans, _ = qrm.read_observations(str(cut), format="mcap", allow_truncated=True)
    assert len(scans) > 10


def _pole_bag(bag_dir: pathlib.Path, beams: int, seed: int) -> tuple:
    """A rosbag2 MCAP bag of a 360° lidar of `beams` beams (σ 2 cm, 2 % dropouts, 20 m, no
    return +inf) driven 24 m past eight poles of radius 0.25 m; returns the bag, the poles
    and the robot's poses (x, y, heading)."""
    rng = np.random.default_rng(seed)
    poles = []
    while len(poles) < 8:
        p = np.array([rng.uniform(1, 19), rng.choice([-1, 1]) * rng.uniform(2, 5)])
        if all(np.hypot(*(p - q)) >= 1.5 for q in poles):
            poles.append(p)
    poles = np.array(poles)
    radius, range_max = 0.25, 20.0
    store = get_typestore(Stores.ROS2_HUMBLE)
    LaserScan = store.types["sensor_msgs/msg/LaserScan"]
    Header = store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    angles = -np.pi + 2 * np.pi * np.arange(beams) / beams
    poses = [(-2.0 + 0.12 * k, 0.0, 0.0) for k in range(200)]
    with Writer(bag_dir, version=8, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/scan", LaserScan.__msgtype__, typestore=store)
        for k, (x, y, th) in enumerate(poses):
            d = np.stack([np.cos(angles + th), np.sin(angles + th)], axis=1)
            ranges = np.full(beams, np.inf)
            for c in poles:
                oc = c - np.array([x, y])
                b = d @ oc
                disc = b * b - (oc @ oc - radius * radius)
                t = np.where(disc >= 0, b - np.sqrt(np.maximum(disc, 0)), np.inf)
                t = np.where(t > 0, t, np.inf)
                ranges = np.minimum(ranges, t)
            ranges = ranges + rng.normal(0, 0.02, beams)
            ranges[(ranges > range_max) | (rng.random(beams) < 0.02)] = np.inf
            t_ns = 1_000_000_000 + k * 100_000_000
            msg = LaserScan(
                header=Header(stamp=Time(sec=t_ns // 10**9, nanosec=t_ns % 10**9), frame_id="laser"),
                angle_min=np.float32(angles[0]), angle_max=np.float32(angles[-1]),
                angle_increment=np.float32(2 * np.pi / beams), time_increment=0.0, scan_time=0.1,
                range_min=0.05, range_max=range_max, ranges=ranges.astype(np.float32),
                intensities=np.zeros(0, dtype=np.float32),
            )
            writer.write(conn, t_ns, store.serialize_cdr(msg, LaserScan.__msgtype__))
    return sorted(bag_dir.glob("*.mcap"))[0], poles, poses


@pytest.mark.parametrize("beams", [360, 720, 1440])
def test_a_common_2d_lidar_maps_one_id_per_pole_and_every_relation_right(qrm_bin, tmp_path, beams):
    """Issue 40: a 360-beam (1°) scanner gave an empty map with exit 0 (the extractor's
    10-return rule was a 0.25° scanner's), 720 beams dozens of ids per pole. The bag's poles,
    mapped with `qrm map --format mcap --calculus edc`: one id per pole, and the most likely
    state of every set the true one."""
    bag, poles, poses = _pole_bag(tmp_path / "bag", beams, seed=11)
    out = tmp_path / "map"
    subprocess.run([qrm_bin, "map", "--format", "mcap", "--input", str(bag), "--calculus", "edc",
                    "--samples", "400", "--out", str(out)], check=True, capture_output=True)
    m = json.loads((out / "map.json").read_text())
    # Which pole each recogniser id is: its detections' nearest pole, in the world frame.
    scans, _ = qrm.read_observations(str(bag), "mcap")
    pole_of = {}
    for s in scans:
        x, y, th = poses[round((s["t"] - 1.0) / 0.1)]  # scans too sparse to map are left out
        c, si = np.cos(th), np.sin(th)
        for i, (px, py) in zip(s["ids"], s["xy"]):
            w = np.array([x + c * px - si * py, y + si * px + c * py])
            nearest = int(np.argmin(np.hypot(*(poles - w).T)))
            assert np.hypot(*(poles[nearest] - w)) < 0.3, "a detection far from every pole"
            pole_of.setdefault(int(i), set()).add(nearest)
    ids = {int(i) for entry in m["sets"] for i in entry["set"]}
    assert len(m["sets"]) > 0, f"{beams} beams: an empty map"
    assert all(len(p) == 1 for p in pole_of.values()), pole_of
    poles_mapped = [next(iter(pole_of[i])) for i in ids]
    assert len(set(poles_mapped)) == len(ids) == 8, f"{beams} beams: {len(ids)} ids for 8 poles"
    # Right where the truth is clear of the sensor's noise: a set whose state changes for more
    # than 5 % of its configurations jittered by 3 cm (the extractor's centre error, measured
    # in sim2d/tests/scanner_resolution.rs) sits on a boundary, and there the map must only
    # give the truth a fair share.
    edc = qrm.Calculus.builtin("edc")
    rng = np.random.default_rng(0)
    wrong, ambiguous = 0, 0
    for entry in m["sets"]:
        a, b, c = (poles[next(iter(pole_of[i]))] for i in entry["set"])
        config = np.array([[*a, *b, *c]])
        truth = int(edc.classify(config)[0])
        clear = np.mean(edc.classify(config + rng.normal(0, 0.03, (2000, 6))) == truth) >= 0.95
        if clear:
            wrong += int(np.argmax(entry["log_p"])) != truth
        else:
            ambiguous += 1
            assert np.exp(entry["log_p"][truth]) >= 0.05, (entry["set"], np.exp(entry["log_p"]))
    assert wrong == 0, f"{beams} beams: {wrong} of {len(m['sets'])} sets wrong"
    assert ambiguous <= len(m["sets"]) // 5, ambiguous


def test_a_map_without_sets_says_why(qrm_bin, tmp_path):
    """Issue 40: an empty map came with exit 0 and no word. Asked for more returns per pole
    than a 1° scanner gives, the map is empty and stderr says what to look at."""
    bag, _, _ = _pole_bag(tmp_path / "bag", 360, seed=11)
    done = subprocess.run([qrm_bin, "map", "--format", "mcap", "--input", str(bag), "--calculus", "edc",
                           "--min-points", "40", "--out", str(tmp_path / "m")],
                          check=True, capture_output=True, text=True)
    assert "no sets" in done.stderr and "--min-points" in done.stderr, done.stderr
