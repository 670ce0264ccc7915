"""make demo's evaluations run on worker processes too (redundancy-gym demo --workers N): the same evaluations, so
the same figures' data."""

from redundancy_gym import demo


def test_clearance_figure_from_workers_matches_the_serial_one(tmp_path, monkeypatch) -> None:
    seen = {}
    original = demo.plot_clearance

    def capture(traces, path, title):
        seen[path.parent.name] = {label: trace.min_clearance.tolist() for label, trace in traces.items()}
        return original(traces, path, title)

    monkeypatch.setattr(demo, "plot_clearance", capture)
    serial = demo._clearance(tmp_path / "serial", episodes=2, seed=0, progress=False)
    split = demo._clearance(tmp_path / "split", episodes=2, seed=0, progress=False, workers=2)
    assert serial.is_file() and split.is_file()
    assert seen["serial"] == seen["split"]  # labels hold the collision rate and clearance, traces the whole episode


def test_the_demo_lists_each_dataset_with_its_size(tmp_path, monkeypatch) -> None:
    import json

    import pytest

    pytest.importorskip("minari", reason="the dataset extra")
    monkeypatch.setattr(demo, "DEMO_DATASETS", {"redundancy_gym/PlanarReach-v0": ("clik", {"obstacle": False}, 1)})
    listing = json.loads(demo._datasets(tmp_path, seed=3, progress=False).read_text())["datasets"]
    assert [row["dataset_id"] for row in listing] == ["redundancy_gym/PlanarReach/clik-v0"]
    row = listing[0]
    on_disk = sum(p.stat().st_size for p in (tmp_path / "datasets" / row["dataset_id"]).rglob("*") if p.is_file())
    assert row["size_bytes"] == on_disk > 0 and row["episodes"] == 1 and row["steps"] == 250
