"""dda3d: three-dimensional Discontinuous Deformation Analysis of jointed rock (DDA-3a), from
Python.

Load a scene, run it, read its blocks and contacts as NumPy arrays::

    import dda3d

    scene = dda3d.Scene.from_file("scenes/slope_sliding.toml")
    sim = dda3d.Simulation(scene, out="out/slope")   # the files of `dda3d run --out`
    sim.run(until=1.0)
    blocks = sim.blocks()                            # dict of arrays, (N, 3) centroids ...
    print(sim.time, blocks["centroids"][1])
    sim.run()                                        # on to the scene's duration

Errors are exceptions with the command line's one-line messages (``SceneError``,
``SolverError``, ``OutputError``, ``StudyError``, ``GpuUnavailable``, all ``Dda3dError``).
The solver runs with the GIL released. ``dda3d.study`` runs a study file locally, on Ray or on
Dask.
"""

from __future__ import annotations

import os
from typing import Any, Optional, Union

from ._errors import (
    Dda3dError,
    GpuUnavailable,
    OutputError,
    SceneError,
    SolverError,
    StudyError,
)
from ._native import Scene, Simulation, __build__, __version__
from . import study  # light: its Ray and Dask imports wait until used

PathLike = Union[str, "os.PathLike[str]"]


def run(
    scene: Union[Scene, PathLike],
    out: Optional[PathLike] = None,
    **overrides: Any,
) -> Simulation:
    """Runs a scene to its end in one call and returns the finished ``Simulation``.

    ``scene`` is a ``Scene`` or the path of a scene file; ``out`` the directory for
    blocks.csv, contacts.csv and summary.json (as ``dda3d run --out``), or None to write
    nothing. Keyword arguments are overrides in the study key syntax with ``__`` for ``.``
    (``solver__duration=0.5`` is ``"solver.duration": 0.5``); a dict with dotted keys can be
    given as ``Scene.from_file(path, overrides={...})`` instead.
    """
    if overrides:
        pairs = {k.replace("__", "."): v for k, v in overrides.items()}
        if isinstance(scene, Scene):
            scene = Scene.from_text(scene.text, scene.origin, overrides=pairs)
        else:
            scene = Scene.from_file(scene, overrides=pairs)
    sim = Simulation(scene, out=None if out is None else os.fspath(out))
    sim.run()
    sim.close()
    return sim


__all__ = [
    "Scene",
    "Simulation",
    "run",
    "study",
    "Dda3dError",
    "SceneError",
    "SolverError",
    "StudyError",
    "OutputError",
    "GpuUnavailable",
    "__build__",
    "__version__",
]

