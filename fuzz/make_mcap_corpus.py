"""Writes the seed corpus of the `mcap` fuzz target (fuzz/corpus/mcap/): three small Foxglove
LaserScan logs (zstd, lz4 and plain chunks) and a ROS 2 bag (rosbags, CDR). The fourth seed,
detections.mcap, is `qrm convert` of a five-row CSV. Run with the test venv's python:
`python fuzz/make_mcap_corpus.py fuzz/corpus/mcap`."""
import json, math, numpy as np, sys
from mcap.writer import Writer, CompressionType
from rosbags.rosbag2 import StoragePlugin, Writer as BagWriter
from rosbags.typesys import Stores, get_typestore
out = sys.argv[1]
LM = [(3.0, 1.0), (4.0, -1.5), (2.5, -0.5), (5.0, 2.0)]
def scan(dx, n=240):
    angles = [-math.pi/3 + i*(2*math.pi/3)/(n-1) for i in range(n)]
    ranges = []
    for a in angles:
        c, s = math.cos(a), math.sin(a)
        best = math.inf
        for (x, y) in LM:
            x -= dx
            b = x*c + y*s; d = b*b - (x*x + y*y - 0.0625)
            if d >= 0 and b - math.sqrt(d) > 0: best = min(best, b - math.sqrt(d))
        ranges.append(round(best, 4) if best < 30 else 31.0)
    return angles, ranges
for comp, name in [(CompressionType.ZSTD, "foxglove_zstd.mcap"), (CompressionType.LZ4, "foxglove_lz4.mcap"), (CompressionType.NONE, "foxglove_plain.mcap")]:
    with open(f"{out}/{name}", "wb") as f:
        w = Writer(f, compression=comp, chunk_size=2048)
        w.start()
        sid = w.register_schema("foxglove.LaserScan", "jsonschema", b"{}")
        cid = w.register_channel("/scan", "json", sid, {"range_max": "30"})
        for k in range(3):
            angles, ranges = scan(0.1*k)
            m = {"timestamp": {"sec": k, "nsec": 0}, "frame_id": "laser", "start_angle": angles[0], "end_angle": angles[-1], "ranges": ranges}
            w.add_message(cid, log_time=k*10**9, data=json.dumps(m).encode(), publish_time=k*10**9)
        w.add_metadata("qrm.ground_truth", {"1": "3,1", "2": "4,-1.5"})
        w.finish()
store = get_typestore(Stores.ROS2_HUMBLE)
LaserScan = store.types["sensor_msgs/msg/LaserScan"]; Header = store.types["std_msgs/msg/Header"]; Time = store.types["builtin_interfaces/msg/Time"]
import pathlib, shutil
bagdir = pathlib.Path(out) / "bagtmp"
shutil.rmtree(bagdir, ignore_errors=True)
with BagWriter(bagdir, version=8, storage_plugin=StoragePlugin.MCAP) as bw:
    conn = bw.add_connection("/scan", LaserScan.__msgtype__, typestore=store)
    for k in range(3):
        angles, ranges = scan(0.1*k, n=240)
        r = np.asarray(ranges, dtype=np.float32); r[r > 30] = np.inf
        msg = LaserScan(header=Header(stamp=Time(sec=k, nanosec=5), frame_id="laser"), angle_min=np.float32(angles[0]), angle_max=np.float32(angles[-1]),
            angle_increment=np.float32((2*math.pi/3)/239), time_increment=0.0, scan_time=0.1, range_min=0.05, range_max=30.0, ranges=r, intensities=np.zeros(0, dtype=np.float32))
        bw.write(conn, k*10**9, store.serialize_cdr(msg, LaserScan.__msgtype__))
bag = next(bagdir.glob("*.mcap"))
shutil.move(str(bag), f"{out}/ros2_laserscan.mcap")
shutil.rmtree(bagdir)
