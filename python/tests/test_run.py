"""A run from Python against `dda3d run`: the same CSV files byte for byte, the arrays'
documented shapes, and bad input raising the documented exceptions with the command's
messages."""

import json
import threading
import time

import numpy as np
import pytest

import dda3d
from conftest import DATA, REPO, cli, cli_error, required, shortened

SLOPE = REPO / "scenes" / "slope_sliding.toml"
ROCKFALL = REPO / "scenes" / "rock_column_rockfall.toml"


def same_outputs(a, b):
    """blocks.csv and contacts.csv identical; summary.json equal but for the wall times."""
    for name in ("blocks.csv", "contacts.csv"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    sa, sb = (json.loads((d / "summary.json").read_text()) for d in (a, b))
    for s in (sa, sb):
        s.pop("wall_seconds")
        s.pop("timings")
    assert sa == sb


@pytest.mark.parametrize("scene,duration", [(SLOPE, None), (ROCKFALL, None)])
def test_run_writes_the_commands_files(tmp_path, scene, duration):
    if duration is not None:
        scene = shortened(scene, tmp_path / scene.name, duration)
    cli("run", scene, "--out", tmp_path / "cli", "--quiet")
    sim = dda3d.Simulation(dda3d.Scene.from_file(scene), out=tmp_path / "py")
    assert sim.run() == pytest.approx(sim.duration)
    assert sim.finished
    same_outputs(tmp_path / "cli", tmp_path / "py")
    summary = json.loads((tmp_path / "py" / "summary.json").read_text())
    assert summary["status"] == "completed" and summary["steps"] == sim.steps


def test_stepping_and_stopping_midway_write_the_same_rows(tmp_path):
    scene = shortened(SLOPE, tmp_path / "slope.toml", 0.5)
    cli("run", scene, "--out", tmp_path / "cli", "--quiet")
    with dda3d.Simulation(str(scene), out=str(tmp_path / "py")) as sim:
        assert sim.run(until=0.2) >= 0.2
        while sim.step():
            pass
        assert sim.time == pytest.approx(0.5)
        assert not sim.step(), "no step past the end"
    same_outputs(tmp_path / "cli", tmp_path / "py")
    # Closed before the end: the rows so far, and a summary saying so.
    with dda3d.Simulation(str(scene), out=str(tmp_path / "early")) as sim:
        sim.run(until=0.1)
    summary = json.loads((tmp_path / "early" / "summary.json").read_text())
    assert summary["status"] == "interrupted", summary
    rows = (tmp_path / "early" / "blocks.csv").read_text().splitlines()
    full = (tmp_path / "cli" / "blocks.csv").read_text().splitlines()
    assert rows == full[: len(rows)] and len(rows) == 1 + 2 * (sim.steps + 1)


def test_arrays_have_the_documented_shapes(tmp_path):
    scene = dda3d.Scene.from_file(SLOPE)
    assert scene.block_names == ["slope", "block"]
    assert scene.duration == 2.0 and scene.method == "alm"
    assert scene.name == "Block sliding on a 30 degree slope (paper Table 2)"
    sim = dda3d.Simulation(scene)
    sim.run(until=0.5)
    b = sim.blocks()
    assert b["names"] == ["slope", "block"]
    assert b["fixed"].dtype == np.bool_ and b["fixed"].tolist() == [True, False]
    for key in ("centroids", "velocities", "displacements"):
        assert b[key].shape == (2, 3) and b[key].dtype == np.float64, key
    assert b["volumes"].shape == (2,) and b["volumes"][1] == pytest.approx(8.0)
    assert [v.shape for v in b["vertices"]] == [(6, 3), (8, 3)]
    assert [len(f) for f in b["faces"]] == [5, 6]
    # The block slides down the slope (toward +x), a = g tan 15° along it (README §3.1).
    s = np.linalg.norm(b["displacements"][1])
    assert s == pytest.approx(0.5 * 9.8 * np.tan(np.radians(15)) * sim.time**2, rel=0.02)
    c = sim.contacts()
    m = len(c["state"])
    assert m >= 3, c
    for key in ("block_i", "block_j"):
        assert c[key].shape == (m,) and c[key].dtype == np.int64
    for key in ("points", "normals"):
        assert c[key].shape == (m, 3) and c[key].dtype == np.float64
    for key in ("normal_force", "shear_force", "penetration"):
        assert c[key].shape == (m,) and c[key].dtype == np.float64
    assert set(c["state"]) <= {"lock", "slide"} and len(c["mode"]) == m
    assert np.allclose(np.linalg.norm(c["normals"], axis=1), 1.0)
    # The normal forces carry the block's weight across the slope: m g cos 30°.
    assert c["normal_force"].sum() == pytest.approx(22000 * 9.8 * np.cos(np.radians(30)), rel=0.02)


def test_a_missing_file_is_a_scene_error_with_the_commands_message(tmp_path):
    missing = tmp_path / "nowhere.toml"
    status, message = cli_error("run", missing, "--out", tmp_path / "o")
    assert status == 2
    with pytest.raises(dda3d.SceneError) as e:
        dda3d.Scene.from_file(missing)
    assert str(e.value) == message
    assert isinstance(e.value, ValueError) and isinstance(e.value, dda3d.Dda3dError)
    with pytest.raises(dda3d.SceneError):
        dda3d.Simulation(str(missing))


@pytest.mark.parametrize(
    "text,needle",
    [
        ('name = "x"\n[solver\nmethod = "alm"\n', "line 2"),
        ((DATA / "cube.toml").read_text() + 'colour = "red"\n', "colour"),
        ((DATA / "cube.toml").read_text().replace('"rock"\nbox', '"basalt"\nbox'), "basalt"),
    ],
)
def test_bad_scenes_raise_scene_error_with_the_commands_message(tmp_path, text, needle):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    status, message = cli_error("run", path, "--out", tmp_path / "o")
    assert status == 2 and needle in message
    with pytest.raises(dda3d.SceneError) as e:
        dda3d.Scene.from_file(path)
    assert str(e.value) == message
    with pytest.raises(dda3d.SceneError) as e:
        dda3d.Scene.from_text(text, origin=str(path))
    assert str(e.value) == message


def test_from_dict_reads_the_scene_structure():
    d = {
        "name": "one cube",
        "solver": {"duration": 0.05},
        "materials": {"rock": {"density": 2750.0, "young_modulus": 2e10, "poisson_ratio": 0.25}},
        "blocks": [{"name": "a", "material": "rock", "box": {"size": [1, 1, 1], "center": [0, 0, 0.5]}}],
    }
    scene = dda3d.Scene.from_dict(d)
    assert (scene.name, scene.block_names, scene.duration) == ("one cube", ["a"], 0.05)
    sim = dda3d.run(scene)
    # Free fall from rest: z = 0.5 - g t² / 2.
    z = sim.blocks()["centroids"][0, 2]
    assert z == pytest.approx(0.5 - 0.5 * 9.8 * sim.time**2, rel=1e-6)
    with pytest.raises(dda3d.SceneError, match="colour"):
        dda3d.Scene.from_dict({**d, "colour": "red"})
    with pytest.raises(dda3d.SceneError, match="NaN or infinite"):
        dda3d.Scene.from_dict({**d, "solver": {"duration": float("nan")}})


def test_a_diverging_run_raises_solver_error_and_keeps_its_files(tmp_path):
    path = tmp_path / "fast.toml"
    path.write_text((DATA / "fast.toml").read_text())
    status, message = cli_error("run", path, "--out", tmp_path / "cli")
    assert status == 1 and "diverged" in message
    sim = dda3d.Simulation(str(path), out=str(tmp_path / "cli"))
    with pytest.raises(dda3d.SolverError) as e:
        sim.run()
    assert str(e.value) == message
    assert isinstance(e.value, RuntimeError)
    summary = json.loads((tmp_path / "cli" / "summary.json").read_text())
    assert summary["status"] == "diverged"
    with pytest.raises(dda3d.SolverError):
        sim.step()
    assert sim.finished


def test_an_output_directory_that_is_a_file_is_an_output_error(tmp_path):
    taken = tmp_path / "taken"
    taken.write_text("not a directory")
    status, message = cli_error("run", SLOPE, "--out", taken, "--duration", "0.05")
    assert status == 74
    with pytest.raises(dda3d.OutputError) as e:
        dda3d.Simulation(str(SLOPE), out=str(taken))
    assert str(e.value).startswith(message.split(";")[0]) and isinstance(e.value, OSError)


def test_overrides_change_the_scene(tmp_path):
    cli("run", SLOPE, "--duration", "0.3", "--out", tmp_path / "cli", "--quiet")
    dda3d.run(str(SLOPE), out=tmp_path / "py", solver__duration=0.3)
    same_outputs(tmp_path / "cli", tmp_path / "py")
    scene = dda3d.Scene.from_file(SLOPE, overrides={"joint.friction_angle": 40.0})
    sim = dda3d.run(scene, solver__duration=0.3)
    # φ = 40° > 30°: the block holds.
    assert np.linalg.norm(sim.blocks()["displacements"][1]) < 1e-3
    with pytest.raises(dda3d.SceneError, match="blocks.nothing"):
        dda3d.Scene.from_file(SLOPE, overrides={"blocks.nothing.velocity[0]": 1.0})


def test_the_gil_is_released_while_the_solver_runs(tmp_path):
    # A struck wall of 60 blocks, run in slices of 0.2 s until a whole second of
    # solver work has passed: a faster solver (or machine) runs more slices, so
    # the test does not depend on how long one slice takes.
    cli("generate", "column", "--blocks", "60", "--out", tmp_path / "wall.toml")
    sim = dda3d.Simulation(str(tmp_path / "wall.toml"))
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    calls = []
    try:
        start = time.perf_counter()
        until = 0.0
        while time.perf_counter() - start < 1.0 and until < 60.0:
            until += 0.2
            before = time.perf_counter()
            sim.run(until=until)
            calls.append((before, time.perf_counter()))
        end = time.perf_counter()
    finally:
        stop.set()
        t.join()
    assert end - start >= 1.0, "a second of solver work, enough to tell"
    # Ticks inside the solver calls only: between calls Python holds the GIL anyway.
    inside = [x for x in ticks if any(a <= x <= b for a, b in calls)]
    busy = sum(b - a for a, b in calls)
    # Held for a call, the GIL would stop the counter for the whole call: about
    # one tick per call, where a released GIL gives one per millisecond or so.
    assert len(inside) > max(50, 5 * len(calls)), (len(inside), len(calls), busy)
    longest = max(np.diff(sorted(inside + [a for a, _ in calls])))
    assert longest < 0.1, (longest, len(calls), busy)


def test_render_gives_an_image_or_says_there_is_no_gpu(tmp_path):
    sim = dda3d.Simulation(str(SLOPE))
    try:
        image = sim.render(320, 240)
    except dda3d.GpuUnavailable as e:
        if required("DDA3D_REQUIRE_GPU"):
            raise
        pytest.skip(str(e))
    assert image.shape == (240, 320, 4) and image.dtype == np.uint8
    assert len(np.unique(image.reshape(-1, 4), axis=0)) > 10, "a picture, not a blank"
    again = sim.render(320, 240, camera="-60,25")
    assert again.shape == (240, 320, 4)
    sim.render_png(tmp_path / "frame.png", 320, 240, camera={"azimuth": 30, "elevation": 20})
    assert (tmp_path / "frame.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError):
        sim.render(0, 10)
