"""The exceptions of dda3d. Their messages are the command line's one-line messages (without
its ``error: `` prefix): the file, the line when known, and the problem."""


class Dda3dError(Exception):
    """Base class of every dda3d exception (alone: a failure that is neither the input, the
    run nor a file, such as the GPU device)."""


class SceneError(Dda3dError, ValueError):
    """A bad scene: a missing or unreadable file, bad TOML, an unknown key, a value out of
    range, a bad override. ``dda3d run`` exits with status 2 on these."""


class SolverError(Dda3dError, RuntimeError):
    """The run diverged (a NaN, a runaway penetration at the smallest step, the energy
    watchdog). What was written up to then is kept; ``dda3d run`` exits with status 1."""


class StudyError(Dda3dError, ValueError):
    """A bad study file, or an output directory a study cannot use."""


class OutputError(Dda3dError, OSError):
    """An output file or directory that cannot be created or written (``dda3d run``: status
    74)."""


class GpuUnavailable(Dda3dError, RuntimeError):
    """No GPU adapter (not even the software Vulkan driver): rendering is not possible."""


__all__ = [
    "Dda3dError",
    "SceneError",
    "SolverError",
    "StudyError",
    "OutputError",
    "GpuUnavailable",
]
