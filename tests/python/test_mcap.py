"""Logs of `qrm sim` read back by the `mcap` Python package (the second, independent reader)."""
import json
import subprocess

import pytest
from mcap.reader import make_reader


@pytest.mark.parametrize("scenario", ["hallway", "field", "pqrm-100"])
def test_sim_logs_read_back_with_the_mcap_package(qrm_bin, tmp_path, scenario):
    subprocess.run([qrm_bin, "sim", "--scenario", scenario, "--seed", "2", "--out", str(tmp_path)], check=True, capture_output=True)
    with open(tmp_path / "run.mcap", "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        schemas = {s.name for s in summary.schemas.values()}
        assert {"foxglove.LaserScan", "foxglove.SceneUpdate", "foxglove.FrameTransform", "foxglove.Log", "qrm.LandmarkDetections"} <= schemas
        counts = {}
        last = -1
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            body = json.loads(message.data)
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
            assert message.log_time >= last
            last = message.log_time
            if channel.topic == "/scan":
                assert len(body["ranges"]) == 1081
            if channel.topic == "/detections":
                assert all(len(d["cov"]) == 3 for d in body["detections"])
        assert sum(counts.values()) == summary.statistics.message_count
    frames = counts["/tf"]
    assert counts["/scan"] == frames == counts["/detections"]
    assert counts["/world"] == 1


@pytest.mark.parametrize("scenario", ["hallway", "field"])
def test_foxglove_draws_no_phantom_ring_for_beams_without_return(qrm_bin, tmp_path, scenario):
    """Foxglove draws a `foxglove.LaserScan` with range_min = -inf, range_max = +inf (no
    limits: `normalizeFoxgloveLaserScan` in its 3D panel) after `new Float32Array(ranges)`,
    so every number is drawn where it says; a beam without return must not be a number past
    the sensor's range (the old max range + 1 drew a ring at 31 m). Checked on every message:
    after Foxglove's own conversion, every drawn point lies within the channel's range_max,
    and beams without return (null → 0) sit at the sensor."""
    import numpy as np

    subprocess.run([qrm_bin, "sim", "--scenario", scenario, "--seed", "4", "--out", str(tmp_path)], check=True, capture_output=True)
    no_return = hits = 0
    with open(tmp_path / "run.mcap", "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(topics=["/scan"]):
            assert schema.name == "foxglove.LaserScan"
            range_max = float(channel.metadata["range_max"])
            raw = json.loads(message.data)["ranges"]
            # JavaScript's Number(null) is 0; Float32Array rounds like float32
            drawn = np.asarray([0.0 if r is None else r for r in raw], dtype=np.float32)
            assert np.all(np.isfinite(drawn))
            assert drawn.max() <= range_max, f"a point drawn at {drawn.max()} m > {range_max} m"
            no_return += sum(r is None for r in raw)
            hits += int(np.count_nonzero(drawn > 0))
    assert no_return > 0 and hits > 0, (no_return, hits)


def test_a_log_cut_midway_stays_readable_up_to_its_last_chunk(qrm_bin, tmp_path):
    """A run killed while writing leaves complete chunks readable (chunks are ≤ 256 KiB)."""
    from mcap.stream_reader import StreamReader
    from mcap.records import Message

    subprocess.run([qrm_bin, "sim", "--scenario", "field", "--seed", "2", "--out", str(tmp_path)], check=True, capture_output=True)
    data = (tmp_path / "run.mcap").read_bytes()
    assert len(data) > 4 * 256 * 1024, "the log spans several chunks"
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * 0.6)])
    read = 0
    with open(cut, "rb") as f:
        try:
            for record in StreamReader(f, skip_magic=False).records:
                if isinstance(record, Message):
                    json.loads(record.data)
                    read += 1
        except Exception:  # the cut chunk at the end: expected
            pass
    assert read > 20, f"only {read} messages recovered from the complete chunks"


def test_the_demo_log_has_the_navigation_topics(qrm_bin, tmp_path):
    subprocess.run([qrm_bin, "demo", "--out", str(tmp_path)], check=True, capture_output=True)
    with open(tmp_path / "run.mcap", "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        schemas = {s.name for s in summary.schemas.values()}
        assert {"qrm.Plan", "qrm.MapBeliefs", "qrm.ControllerState", "foxglove.SceneUpdate"} <= schemas
        seen = {}
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            body = json.loads(message.data)
            seen.setdefault(channel.topic, []).append(body)
    beliefs = seen["/map/beliefs"][0]["elements"]
    assert beliefs and all(abs(sum(e["p"]) - 1.0) < 1e-9 for e in beliefs)
    assert seen["/plan"][0]["goal"] == json.loads((tmp_path / "summary.json").read_text())["goal"]
    assert len(seen["/controller"]) >= 1
    navigation = [e for m in seen["/navigation"] for e in m["entities"]]
    assert any(e["id"] == "trajectory" for e in navigation)
    # issue 19: the plan in 3D, and every pipeline step on /log
    plan = [e for e in navigation if e["id"] == "plan"]
    assert plan and plan[0]["lines"] and all(len(line["points"]) == 4 for line in plan[0]["lines"])
    messages = [m["message"] for m in seen["/log"]]
    for step in ("mapped by lidar", "plan to landmark", "transition ", "navigation to landmark"):
        assert any(step in m for m in messages), (step, messages)


def test_detections_are_drawn_in_3d_as_well(qrm_bin, tmp_path):
    """/detections (a custom schema, Raw Messages only in Foxglove) is mirrored on
    /detections/scene as foxglove.SceneUpdate spheres at the same positions (issue 19)."""
    subprocess.run([qrm_bin, "sim", "--scenario", "hallway", "--seed", "2", "--out", str(tmp_path)], check=True, capture_output=True)
    dets, scenes = {}, {}
    with open(tmp_path / "run.mcap", "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(topics=["/detections", "/detections/scene"]):
            body = json.loads(message.data)
            if channel.topic == "/detections":
                dets[message.log_time] = body["detections"]
            else:
                assert schema.name == "foxglove.SceneUpdate"
                scenes[message.log_time] = body["entities"][0]
    assert dets.keys() == scenes.keys() and any(dets.values())
    for t, d in dets.items():
        e = scenes[t]
        assert e["frame_id"] == "base_link" and len(e["spheres"]) == len(d) == len(e["texts"])
        for det, sphere, text in zip(d, e["spheres"], e["texts"]):
            assert (sphere["pose"]["position"]["x"], sphere["pose"]["position"]["y"]) == (det["x"], det["y"])
            assert text["text"] == str(det["id"])


def _messages_against_their_schemas(path):
    """Every message of the log at `path` checked against the JSON Schema its channel
    embeds, by a real validator; returns how many per schema, and the failures."""
    import jsonschema

    counts, failures = {}, []
    with open(path, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            assert schema is not None and schema.encoding == "jsonschema", channel.topic
            validator = jsonschema.Draft202012Validator(json.loads(schema.data))
            errors = list(validator.iter_errors(json.loads(message.data)))
            counts[schema.name] = counts.get(schema.name, 0) + 1
            if errors:
                failures.append(f"{channel.topic} ({schema.name}): {errors[0].message}")
    return counts, failures


def test_every_message_of_every_log_qrm_writes_validates_against_its_schema(qrm_bin, tmp_path, mrclam_dir):
    """Issue 40: every `/scan` message of the demo's log broke its own schema (ranges declared
    numbers, no return written as null); mcapcheck checked well-formed JSON only. The sim, the
    demo and a converted recording, every message, a real JSON Schema validator."""
    runs = {
        "sim": [qrm_bin, "sim", "--scenario", "field", "--seed", "2", "--out", str(tmp_path / "sim")],
        "demo": [qrm_bin, "demo", "--out", str(tmp_path / "demo")],
        "convert": [qrm_bin, "convert", "--from", "mrclam", "--input", str(mrclam_dir),
                    "--out", str(tmp_path / "convert.mcap")],
    }
    seen = set()
    for name, args in runs.items():
        subprocess.run(args, check=True, capture_output=True)
        path = tmp_path / "convert.mcap" if name == "convert" else tmp_path / name / "run.mcap"
        counts, failures = _messages_against_their_schemas(path)
        assert not failures, f"{name}: {len(failures)} messages break their schema, e.g. {failures[:3]}"
        assert sum(counts.values()) > 0, name
        seen |= set(counts)
    # every kind of message qrm writes was checked
    assert {"foxglove.LaserScan", "foxglove.SceneUpdate", "foxglove.FrameTransform", "foxglove.Log",
            "qrm.LandmarkDetections", "qrm.MapEntropy", "qrm.Plan"} <= seen, seen


@pytest.mark.parametrize("compression", ["ZSTD", "LZ4"])
def test_chunks_compressed_by_the_mcap_package_map_exactly_as_plain_ones(qrm_bin, tmp_path, compression):
    """qrm decodes zstd and lz4 chunks with pure-Rust decoders (issue 40: no C in the build).

    A `qrm sim` log (plain chunks) is re-written by the `mcap` package — the C zstd and lz4
    libraries behind it — in small chunks (many per file, frames across chunk boundaries
    never shared), and must map byte for byte as the original.
    """
    from mcap.writer import CompressionType, Writer

    subprocess.run([qrm_bin, "sim", "--scenario", "hallway", "--seed", "4", "--out", str(tmp_path / "sim")], check=True, capture_output=True)
    plain = tmp_path / "sim" / "run.mcap"
    packed = tmp_path / f"{compression}.mcap"
    with open(plain, "rb") as f, open(packed, "wb") as g:
        reader = make_reader(f)
        writer = Writer(g, chunk_size=16 * 1024, compression=getattr(CompressionType, compression))
        writer.start()
        schema_ids, channel_ids = {}, {}
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            if schema.id not in schema_ids:
                schema_ids[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channel_ids:
                channel_ids[channel.id] = writer.register_channel(
                    channel.topic, channel.message_encoding, schema_ids[schema.id], channel.metadata
                )
            writer.add_message(channel_ids[channel.id], message.log_time, message.data, message.publish_time)
        for record in reader.iter_metadata():
            writer.add_metadata(record.name, record.metadata)
        writer.finish()
    with open(packed, "rb") as g:
        chunks = make_reader(g).get_summary().chunk_indexes
        assert len(chunks) > 5 and {c.compression for c in chunks} == {compression.lower()}

    def mapped(src):
        out = tmp_path / f"map-{src.stem}"
        subprocess.run(
            [qrm_bin, "map", "--format", "mcap", "--input", str(src), "--calculus", "edc", "--samples", "100", "--out", str(out)],
            check=True, capture_output=True,
        )
        return (out / "map.json").read_bytes()

    assert mapped(packed) == mapped(plain)
