"""Flinch from Python: the harness library (the `flinch` command line's) called directly.

* ``flinch.run(scene)``: one run; the summary of ``flinch run --json`` as a dict.
* ``flinch.sweep(scene, vary)``: a grid of one or two keys; a pandas DataFrame (``flinch sweep --csv``).
* ``flinch.sample(scene, n, vary)``: Monte Carlo (``flinch sample``); the report with each failure's
  probability and interval, and a row per sample as a DataFrame.
* ``flinch.dask.sample(scene, n, vary, client)``: the same study as chunks on a Dask cluster.

A scene is a path to a TOML file, a shipped scene's name (``"tables5-7_bistable"``), or a dict of
its keys (``flinch.scene(name)`` gives one to edit). Errors: ``flinch.SceneError`` (the validator's
file/line/key messages), ``flinch.InputError``, ``flinch.SolverError``. docs/python.md.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import pandas as pd

from . import _flinch
from .errors import FlinchError, InputError, RefusalWarning, SceneError, SolverError

__all__ = [
    "run", "sweep", "sample", "merge", "scene", "scenes", "check", "Sample",
    "FlinchError", "SceneError", "InputError", "SolverError", "RefusalWarning", "BLOCK",
]

__version__ = _flinch.VERSION

#: Samples run together and then handed over in order (``flinch sample``'s block).
BLOCK: int = _flinch.BLOCK

Scene = Union[str, "os.PathLike[str]", Mapping[str, Any]]


def _resolve(scene: Scene) -> Tuple[str, str]:
    """(the name messages use, the TOML text) of a scene argument."""
    if isinstance(scene, Mapping):
        return "<dict>", _flinch.dict_to_toml(json.dumps(_plain(scene), allow_nan=True))
    if isinstance(scene, (str, os.PathLike)):
        return tuple(_flinch.read_scene(os.fspath(scene)))  # type: ignore[return-value]
    raise TypeError(f"a scene is a path, a shipped scene's name or a dict, not {type(scene).__name__}")


def _plain(x: Any) -> Any:
    """A dict with NumPy scalars and tuples made JSON-ready."""
    if isinstance(x, Mapping):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    return x


def scenes() -> List[str]:
    """The shipped scenes' names (``flinch scenes list``)."""
    return list(_flinch.shipped_names())


def scene(name: Union[str, "os.PathLike[str]"]) -> Dict[str, Any]:
    """A scene file or a shipped scene as a dict, to edit and pass to run, sweep or sample."""
    file, text = _resolve(name)
    return json.loads(_flinch.toml_to_json(file, text))


def check(scene: Scene) -> None:
    """Validates a scene; raises SceneError with every issue the validator finds."""
    _flinch.check(*_resolve(scene))


def run(scene: Scene) -> Dict[str, Any]:
    """Runs a scene; returns its summary, the document of ``flinch run --json`` (field names with
    units, ``safe`` and ``failures`` as docs/verdicts.md defines them). An unsafe run is a summary
    with ``safe`` False, not an exception: read ``safe``."""
    return json.loads(_flinch.run(*_resolve(scene)))


def _sweep_specs(vary: Union[Mapping[str, Any], Sequence[str], str]) -> List[str]:
    if isinstance(vary, str):
        return [vary]
    if isinstance(vary, Mapping):
        out = []
        for key, v in vary.items():
            if isinstance(v, str):
                out.append(f"{key}={v}")
            else:
                start, stop, n = v
                out.append(f"{key}={float(start)!r}:{float(stop)!r}:{int(n)}")
        return out
    return list(vary)


def sweep(scene: Scene, vary, *, log: Iterable[str] = (), strict: bool = False, jobs: Optional[int] = None) -> pd.DataFrame:
    """``flinch sweep``: the scene over a grid of one or two keys, on all cores (or ``jobs``
    threads). ``vary`` is ``{"motion.speed": (0.05, 0.3, 6)}`` (start, stop, n) or ``"KEY=START:STOP:N"``
    strings as on the command line (``log:`` or ``log=[key]`` for a geometric axis). Returns the
    CSV of ``flinch sweep --csv`` as a DataFrame: the swept keys, every summary field, ``status``
    (ok, refused, failed) and ``reason``; points run with the first key varying slowest. A point the
    validator refuses is a row with status "refused" (``strict=True`` refuses the sweep instead).
    Raises SolverError, with the DataFrame in ``result``, if the solver failed at any point."""
    file, text = _resolve(scene)
    csv, points, failed, refused = _flinch.sweep(file, text, _sweep_specs(vary), list(log), strict, jobs)
    import io

    df = pd.read_csv(io.StringIO(csv), keep_default_na=False, na_values=[""])
    df["reason"] = df["reason"].astype(object).fillna("")
    if failed:
        raise SolverError(f"the solver failed at {failed} of {points} points (status and reason columns)", result=df)
    return df


def _sample_specs(vary: Union[Mapping[str, Any], Sequence[str], str]) -> List[str]:
    """``--vary`` specs from ``{"motion.dead_time": "uniform:0.016:0.032"}``,
    ``{"motion.dead_time": ("uniform", 0.016, 0.032)}`` or ``["motion.dead_time=uniform:0.016:0.032"]``."""
    if isinstance(vary, str):
        return [vary]
    if isinstance(vary, Mapping):
        out = []
        for key, v in vary.items():
            if isinstance(v, str):
                out.append(f"{key}={v}")
            else:
                name, *params = v
                out.append(f"{key}={name}:" + ":".join(repr(float(p)) for p in params))
        return out
    return list(vary)


@dataclass
class Sample:
    """A sample study's result: ``report`` is the document of ``flinch sample --json`` (the study,
    the counts, and under ``estimates`` each failure's probability with its 95 % interval);
    ``rows`` the rows of ``--csv`` as a DataFrame (None when not asked for)."""

    report: Dict[str, Any]
    rows: Optional[pd.DataFrame] = None

    @property
    def estimates(self) -> pd.DataFrame:
        """One row per failure (stroke_exhausted, mode_3, not_safe, body_limit_exceeded for a body
        region): failures, runs, p, the interval reported (low, high) and both intervals."""
        return pd.DataFrame(self.report["estimates"]).set_index("failure")

    def __str__(self) -> str:
        return _flinch.sample_human(json.dumps(self.report))


_STATUS = pd.CategoricalDtype(["ok", "refused", "failed"])


def _frame(cols: Dict[str, Any]) -> pd.DataFrame:
    """The column buffers of a sample as the DataFrame of its CSV (same names and order)."""
    n = cols["len"]
    data: Dict[str, Any] = {"sample": np.frombuffer(cols["sample"], dtype="<u8").astype(np.int64)}
    for name, buf in cols["values"]:
        data[name] = np.frombuffer(buf, dtype="<f8").copy()

    def flag(name: str):
        a = np.frombuffer(cols[name], dtype=np.int8)
        return pd.arrays.BooleanArray(a == 1, a < 0)

    mode = np.frombuffer(cols["mode"], dtype=np.int8)
    data["stroke_exhausted"] = flag("stroke_exhausted")
    # 1 to 3; <NA> where there is no mode (no back end-stop) or the sample did not run.
    data["mode"] = pd.arrays.IntegerArray(mode.astype(np.int8), mode <= 0)
    for name in ("peak_contact_force_n", "peak_robot_force_n", "stroke_left_min_m"):
        data[name] = np.frombuffer(cols[name], dtype="<f8").copy()
    data["safe"] = flag("safe")
    if cols["body"]:
        data["body_limits_pass"] = flag("body_limits_pass")
    data["status"] = pd.Categorical.from_codes(np.frombuffer(cols["status"], dtype=np.uint8).astype(np.int8), dtype=_STATUS)
    reason = np.full(n, "", dtype=object)
    for i, why in cols["reasons"]:
        reason[i] = why
    data["reason"] = reason
    return pd.DataFrame(data)


def _raise_for(result: Sample) -> Sample:
    """What ``flinch sample`` exits non-zero for, as exceptions carrying the result."""
    r = result.report
    if r["ran"] == 0 and r["refused"] > 0:
        first = r["refusals"][0]["first_reason"] if r["refusals"] else ""
        e = InputError(f"the validator refused all {r['refused']} samples; the first: {first}")
        e.result = result  # type: ignore[attr-defined]
        raise e
    if r["solver_failed"] > 0:
        raise SolverError(f"the solver failed at {r['solver_failed']} of {r['drawn']} samples (status and reason columns)", result=result)
    return result


def sample(
    scene: Scene,
    n: int,
    vary,
    *,
    seed: int = 1,
    truncate: bool = False,
    chunk: Optional[Tuple[int, int]] = None,
    jobs: Optional[int] = None,
    rows: bool = True,
) -> Sample:
    """``flinch sample``: ``n`` samples of the scene with the keys of ``vary`` drawn from their
    distributions (docs/sample.md), on all cores (or ``jobs`` threads); deterministic for a seed
    whatever the threads. ``vary`` maps a key to ``"normal:MEAN:SD"`` (or ``("normal", MEAN, SD)``;
    also lognormal, uniform, triangular, and :LO:HI bounds), or is a list of ``KEY=DIST`` strings.
    ``chunk=(k, m)`` runs chunk k of m only (``--chunk k/m``); ``flinch.merge`` adds chunks up.
    ``rows=False`` keeps no rows (memory flat at any n).

    Returns a Sample (``.report``, ``.rows``, ``.estimates``). Raises InputError (with ``.result``)
    when every sample was refused and SolverError (with ``.result``) when the solver failed at any
    sample, as the command line exits 2 and 3."""
    file, text = _resolve(scene)
    specs = _sample_specs(vary)
    _notes(file, text, specs, _count(n), int(seed), bool(truncate))
    report, cols = _flinch.sample(file, text, specs, _count(n), int(seed), bool(truncate), _chunk(chunk), jobs, bool(rows))
    result = Sample(json.loads(report), _frame(cols) if cols is not None else None)
    return _raise_for(result)


def _notes(file: str, text: str, specs: List[str], n: int, seed: int, truncate: bool) -> None:
    """Checks a study before it runs (raising what ``flinch sample`` refuses) and warns, as its
    notes do, of distributions that put draws outside their keys' accepted ranges."""
    import warnings

    _, notes = _flinch.sample_check(file, text, specs, n, seed, truncate)
    for note in notes:
        warnings.warn(note, RefusalWarning, stacklevel=3)


def _count(n: Any) -> int:
    x = float(n)
    if not (x >= 1 and x == int(x)):
        raise InputError(f"n = {n!r}: the number of samples is a whole number of at least 1")
    return int(x)


def _chunk(chunk: Optional[Tuple[int, int]]) -> Optional[Tuple[int, int]]:
    if chunk is None:
        return None
    k, m = chunk
    return int(k), int(m)


def merge(reports: Sequence[Union[Dict[str, Any], Sample]], *, partial: bool = False) -> Dict[str, Any]:
    """``flinch sample --merge``: the reports of chunks of one study merged into the report of their
    union (the whole study's, field for field, when every chunk is there). Refuses reports of
    another study, overlapping chunks and reports whose counts do not add up (InputError), and,
    unless ``partial=True`` (``--partial``), reports that do not cover the whole study (a chunk
    missing or interrupted): the error names the samples missing."""
    texts = [json.dumps(r.report if isinstance(r, Sample) else r) for r in reports]
    merged = json.loads(_flinch.merge(texts))
    if not merged["complete"] and not partial:
        missing, at = [], 0
        for lo, hi in merged["ranges"]:
            if lo > at:
                missing.append(f"{at}..{lo}")
            at = max(at, hi)
        if at < merged["samples"]:
            missing.append(f"{at}..{merged['samples']}")
        raise InputError(
            f"merge: the reports cover {merged['drawn']} of the {merged['samples']} samples: samples "
            f"{', '.join(missing)} are missing (a chunk not given, or one interrupted); give every "
            "chunk's report, or partial=True to merge these anyway (the estimate is then over the "
            "samples covered)"
        )
    return merged


def _chunk_report(file: str, text: str, specs: List[str], n: int, seed: int, truncate: bool, chunk: Tuple[int, int], jobs: Optional[int], rows: bool):
    """One chunk of a study, as a Dask task runs it: (its report, its rows or None). Never raises for
    refused or failed samples: they are counted in the report, which the merge adds up."""
    report, cols = _flinch.sample(file, text, specs, n, seed, truncate, chunk, jobs, rows)
    return json.loads(report), (_frame(cols) if cols is not None else None)


def __getattr__(name: str):
    # `flinch.dask` without importing Dask for everyone else.
    if name == "dask":
        import importlib

        return importlib.import_module(".dask", __name__)
    raise AttributeError(f"module 'flinch' has no attribute {name!r}")
