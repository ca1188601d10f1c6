"""Shared helpers of the Python package's tests (run by `tests/python_package.rs`, which sets
DDA3D_BIN to the `dda3d` binary of the same build, or by hand: `python -m pytest python/tests`).

Policy: a test that needs something optional (Ray, Dask, a GPU adapter, the study module) is
skipped when it is missing, unless the environment demands it (DDA3D_REQUIRE_PYTHON=1 for Ray,
Dask and the study module, DDA3D_REQUIRE_GPU=1 for the GPU), and then it fails."""

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parent / "data"


def required(var: str) -> bool:
    return os.environ.get(var, "").strip() not in ("", "0", "false", "False")


def skip_or_fail(reason: str, var: str = "DDA3D_REQUIRE_PYTHON") -> None:
    if required(var):
        pytest.fail(f"{reason} (required: {var}=1)")
    pytest.skip(reason)


def dda3d_bin() -> Path:
    path = Path(os.environ.get("DDA3D_BIN") or REPO / "target" / "release" / "dda3d")
    if not path.exists():
        pytest.fail(f"no dda3d binary at {path}: build it, or set DDA3D_BIN")
    return path


def cli(*args, check=True) -> subprocess.CompletedProcess:
    """`dda3d ARGS`, its output captured as text."""
    done = subprocess.run(
        [str(dda3d_bin()), *map(str, args)], capture_output=True, text=True, cwd=REPO
    )
    if check and done.returncode != 0:
        raise AssertionError(f"dda3d {' '.join(map(str, args))}: {done.stderr}")
    return done


def cli_error(*args) -> "tuple[int, str]":
    """The exit status and the one-line message (without `error: `) of a failing command."""
    done = cli(*args, check=False)
    assert done.returncode != 0, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith("error: "), lines[0]
    return done.returncode, lines[0][len("error: "):]


def shortened(src: Path, dest: Path, duration: float) -> Path:
    """A copy of scene `src` whose `[solver] duration` is `duration`."""
    lines = src.read_text().splitlines(keepends=True)
    k = next(i for i, l in enumerate(lines) if l.startswith("duration ="))
    lines[k] = f"duration = {duration}\n"
    dest.write_text("".join(lines))
    return dest
