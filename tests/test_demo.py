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
