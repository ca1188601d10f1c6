"""`dda3d.study` on its three backends against `dda3d study`: the same study.csv, apart from
the wall times, for a 16-case study (4 friction angles x 4 random durations of the sliding
block)."""

import csv
import io
import json
import os

import pytest

import dda3d
from conftest import DATA, cli, skip_or_fail

STUDY = DATA / "slope16.toml"


def table(out):
    """study.csv without its wall_seconds column."""
    rows = list(csv.reader(io.StringIO((out / "study.csv").read_text())))
    k = rows[0].index("wall_seconds")
    return [r[:k] + r[k + 1:] for r in rows]


@pytest.fixture(scope="module")
def command_table(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "study"
    cli("study", STUDY, "--out", out, "--quiet", "--jobs", "2", check=False)
    return table(out)


def test_the_study_loads_with_its_keys_and_outcomes():
    study = dda3d.study.load(STUDY)
    assert len(study) == 16
    assert study.keys() == ["joint.friction_angle", "solver.duration"]
    assert study.outcomes()[0] == "max_displacement"
    task = study.task_json(5)
    assert json.loads(task)["case"] == 5
    # What a case ships: its scene text and settings, a few KB.
    assert len(task) < 20_000
    with pytest.raises(dda3d.StudyError):
        dda3d.study.load(DATA / "missing_study.toml")


def check_rows(rows, command_table):
    assert len(rows) == 16 and [r["case"] for r in rows] == list(range(16))
    assert {r["status"] for r in rows} == {"ok"}


def test_local_gives_the_commands_table(tmp_path, command_table):
    rows = dda3d.study.run(STUDY, out=tmp_path / "local", jobs=2)
    assert table(tmp_path / "local") == command_table
    check_rows(rows, command_table)
    # Resumed: nothing left to run, the same table.
    before = (tmp_path / "local" / "study.csv").read_text()
    dda3d.study.run(STUDY, out=tmp_path / "local", jobs=2)
    assert (tmp_path / "local" / "study.csv").read_text() == before


def test_ray_gives_the_commands_table(tmp_path, command_table):
    try:
        import ray
    except ImportError:
        skip_or_fail("ray is not installed")
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    ray.init(num_cpus=2, include_dashboard=False)
    try:
        rows = dda3d.study.run_ray(STUDY, out=tmp_path / "ray")
    finally:
        ray.shutdown()
    assert table(tmp_path / "ray") == command_table
    check_rows(rows, command_table)


def test_dask_gives_the_commands_table(tmp_path, command_table):
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        skip_or_fail("dask.distributed is not installed")
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster:
        with Client(cluster) as client:
            rows = dda3d.study.run_dask(STUDY, out=tmp_path / "dask", client=client)
    assert table(tmp_path / "dask") == command_table
    check_rows(rows, command_table)
