"""The Monte Carlo study from Python, and sharding: shards merge into the single run (what a
Ray sweep does; see docs/distributed.md)."""
import qrm


def test_shards_merge_into_the_single_run():
    cfg = qrm.monte_carlo_config(quick=True, trials=4, sigmas=[0.0, 25.0], samples=60, seed=3)
    whole = qrm.monte_carlo(cfg)
    shards = [qrm.monte_carlo_shard(cfg, start, 1) for start in (3, 1, 0, 2)]
    assert qrm.monte_carlo_aggregate(cfg, shards) == whole
    edc = [l for l in whole["levels"] if l["calculus"] == "edc"]
    assert edc[0]["error_rate"]["mean"] == 0.0  # σ = 0


def test_the_ray_example_logic_runs_without_ray():
    import importlib.util, pathlib
    path = pathlib.Path(__file__).resolve().parents[2] / "examples" / "python" / "ray_sweep.py"
    spec = importlib.util.spec_from_file_location("ray_sweep", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    cfg = qrm.studies.config("monte-carlo")
    cfg.update(trials=3, sigmas=[0.0, 30.0], samples=40)
    run = mod.sweep("monte-carlo", cfg, backend="local")
    levels = run["output"]["levels"]
    assert len(levels) == 6 * 4  # six calculi × (0, 30, and the 1 m and 50 m detail levels)
    assert run == qrm.studies.run("monte-carlo", cfg)
