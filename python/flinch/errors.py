"""The exceptions of the flinch package. Their messages are the ones the command line prints."""

from __future__ import annotations


class FlinchError(Exception):
    """Every error of this package."""


class SceneError(FlinchError, ValueError):
    """The scene validator refuses a scene (the messages of ``flinch run``: file, line, key, what is
    allowed), or the scene cannot be read.

    ``file`` names the scene as the messages do (``<dict>`` for a dict); ``issues`` lists every
    problem as a dict with ``line`` (1-based, ``None`` for a dict or an unreadable file), ``key``
    (dotted) and ``message``."""

    def __init__(self, message: str, file: str = "", issues=()):
        super().__init__(message)
        self.file = file
        self.issues = [{"line": line, "key": key, "message": msg} for (line, key, msg) in issues]


class InputError(FlinchError, ValueError):
    """Bad arguments (a ``vary`` spec, an unknown key, a chunk), or every point or sample refused:
    what the command line exits 2 for."""


class SolverError(FlinchError, RuntimeError):
    """The solver gave up: on the run (``flinch.run``), or at some points or samples of a sweep or a
    sample, whose whole result is then in ``result`` (the command line writes everything and exits 3)."""

    def __init__(self, message: str, result=None):
        super().__init__(message)
        self.result = result


class RefusalWarning(UserWarning):
    """A distribution puts draws outside its key's accepted range: those samples will be refused
    and counted (the note ``flinch sample`` prints before running)."""
