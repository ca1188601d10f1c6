"""Parameter studies on one machine, on Ray or on Dask, with the results of ``dda3d study``.

A study file varies keys of a base scene over a grid of cases. Each case is shipped to a worker
as its task JSON: the scene's TEXT with the case's overrides applied and the outcome settings
(a few KB), never a model. The worker runs it and sends back its record (JSON: the parameter
values, the outcomes, status, error, wall time); the driver assembles the records into
study.csv, study.json and the plots exactly as ``dda3d study`` writes them (only the
``wall_seconds`` column differs). Cases already finished in ``out`` are not run again.

    import dda3d.study
    rows = dda3d.study.run("study.toml", out="out/study")                 # threads here
    rows = dda3d.study.run_ray("study.toml", out="out/study")             # ray.init() or a cluster
    rows = dda3d.study.run_dask("study.toml", out="out/study", client=c)  # dask.distributed

Ray and Dask are imported only when used; ``pip install "dda3d[ray]"`` or ``"dda3d[dask]"``.
"""

from __future__ import annotations

import csv
import os
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Union

from . import _native
from ._errors import StudyError

PathLike = Union[str, "os.PathLike[str]"]
Row = Dict[str, Any]

BACKENDS = ("local", "ray", "dask")



def load(path: PathLike) -> "_native.Study":
    """Loads and checks a study file. The result has ``len(study)``, ``study.keys()`` (the
    varied keys), ``study.outcomes()``, ``study.task_json(k)`` (case k's task),
    ``study.assemble(out, records)``, ``study.save_record(out, record)``,
    ``study.finished_json(out)`` and ``study.pending_json(out, retry_failed)``. Raises
    ``StudyError``."""
    return _native.load_study(os.fspath(path))


def run_task_json(task: str) -> str:
    """Runs one case from its task JSON on this machine and returns its record JSON (what a
    Ray or Dask worker calls; the GIL is released while it runs). A failing case is a record
    with status "failed", not an exception."""
    return _native.run_task_json(task)


def default_out(path: PathLike) -> Path:
    """The output directory when none is given, as `dda3d study` takes it: out/<the study
    file's stem as a slug>."""
    return Path(_native.default_study_out(os.fspath(path)))


Done = Callable[[str], None]


def _local(tasks: Sequence[str], jobs: Optional[int], done: Done) -> None:
    workers = jobs or os.cpu_count() or 1
    with ThreadPoolExecutor(max_workers=workers) as pool:
        for f in as_completed([pool.submit(run_task_json, t) for t in tasks]):
            done(f.result())


def _ray(tasks: Sequence[str], jobs: Optional[int], done: Done) -> None:
    import ray

    if not ray.is_initialized():
        # RAY_ADDRESS=auto finds a cluster started with `ray start`; unset, a local one.
        ray.init(address=os.environ.get("RAY_ADDRESS"))
    # One CPU a case; `jobs` caps how many are in flight at once.
    remote = ray.remote(num_cpus=1)(run_task_json)
    todo = list(tasks)
    running: List[Any] = []
    while todo or running:
        while todo and (not jobs or len(running) < jobs):
            running.append(remote.remote(todo.pop(0)))
        ready, running = ray.wait(running, num_returns=1)
        for ref in ready:
            done(ray.get(ref))


def _dask(tasks: Sequence[str], jobs: Optional[int], client: Any, done: Done) -> None:
    from distributed import Client, LocalCluster, as_completed as finished

    own = client is None
    if own:
        cluster = LocalCluster(n_workers=jobs or os.cpu_count() or 1, threads_per_worker=1)
        client = Client(cluster)
    try:
        for f in finished(client.map(run_task_json, list(tasks), pure=False)):
            done(f.result())
    finally:
        if own:
            client.close()
            cluster.close()


def _parse(cell: str) -> Any:
    for kind in (int, float):
        try:
            return kind(cell)
        except ValueError:
            pass
    return cell


def read_table(out: PathLike) -> List[Row]:
    """study.csv in ``out`` as a list of row dicts (numbers parsed, other cells as text)."""
    with open(Path(os.fspath(out)) / "study.csv", newline="") as f:
        return [{k: _parse(v) for k, v in row.items()} for row in csv.DictReader(f)]


def run(
    path: PathLike,
    out: Optional[PathLike] = None,
    backend: str = "local",
    jobs: Optional[int] = None,
    client: Any = None,
    retry_failed: bool = False,
) -> List[Row]:
    """Runs the study file at ``path`` and writes study.csv, study.json and the plots into
    ``out`` (default out/<file stem>) as ``dda3d study`` does; returns study.csv's rows.

    ``backend``: "local" (threads in this process, ``jobs`` at once, default one a core),
    "ray" (``ray.remote`` tasks; an active ``ray.init()`` is used, else one is started, on the
    cluster of ``RAY_ADDRESS`` if set) or "dask" (``client``, a ``distributed.Client``, else a
    LocalCluster of ``jobs`` workers). Cases finished in ``out`` by an earlier run are kept;
    ``retry_failed`` runs the failed ones again.
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    study = load(path)
    out = Path(os.fspath(out)) if out is not None else default_out(path)
    kept, cases = study.pending_json(os.fspath(out), retry_failed)
    tasks = [study.task_json(k) for k in cases]
    records = list(kept)

    def done(record: str) -> None:
        # Saved as it arrives, as `dda3d study` saves each case: a stopped study resumes.
        study.save_record(os.fspath(out), record)
        records.append(record)

    if backend == "local":
        _local(tasks, jobs, done)
    elif backend == "ray":
        _ray(tasks, jobs, done)
    else:
        _dask(tasks, jobs, client, done)
    study.assemble(os.fspath(out), records)
    return read_table(out)


def run_ray(path: PathLike, out: Optional[PathLike] = None, **kw: Any) -> List[Row]:
    """``run(path, out, backend="ray", ...)``."""
    return run(path, out, backend="ray", **kw)


def run_dask(
    path: PathLike, out: Optional[PathLike] = None, client: Any = None, **kw: Any
) -> List[Row]:
    """``run(path, out, backend="dask", client=client, ...)``."""
    return run(path, out, backend="dask", client=client, **kw)


__all__ = [
    "load",
    "run",
    "run_ray",
    "run_dask",
    "run_task_json",
    "read_table",
    "default_out",
]
