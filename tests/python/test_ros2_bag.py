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
