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
        issues: List[Tuple[None, str, str]] = []
        plain = _plain(scene, "", issues)
        if issues:
            raise SceneError("\n".join(f"{_DICT}: {key}: {msg}" for _, key, msg in issues), _DICT, issues)
        return _DICT, _flinch.dict_to_toml(json.dumps(plain, allow_nan=False))
    if isinstance(scene, (str, os.PathLike)):
        return tuple(_flinch.read_scene(os.fspath(scene)))  # type: ignore[return-value]
    raise TypeError(f"a scene is a path, a shipped scene's name or a dict, not {type(scene).__name__}")


#: The file name a scene given as a dict has in messages.
_DICT = "<dict>"

#: TOML's integers are 64-bit signed.
_I64 = (-(2**63), 2**63 - 1)

_ALLOWED = "a scene's values are strings, finite numbers, booleans, lists and dicts (NumPy scalars and arrays of them too)"


def _plain(x: Any, key: str, issues: List[Tuple[None, str, str]]) -> Any:
    """A dict scene's value made JSON-ready for its TOML form: NumPy scalars as their Python values,
    tuples and NumPy arrays as lists. A value with no TOML form (None, NaN or infinity, an integer
    beyond 64 bits, any other type) is added to ``issues`` as (None, its dotted key, what is
    allowed), the form of the validator's issues for a dict."""
    if isinstance(x, np.ndarray):
        x = x.tolist()
    elif isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, Mapping):
        out = {}
        for k, v in x.items():
            if not isinstance(k, str):
                issues.append((None, f"{key}.{k!r}" if key else repr(k), f"a key is a string, not {type(k).__name__}"))
                continue
            out[k] = _plain(v, f"{key}.{k}" if key else k, issues)
        return out
    if isinstance(x, (list, tuple)):
        return [_plain(v, f"{key}[{i}]", issues) for i, v in enumerate(x)]
    if x is None:
        issues.append((None, key, "is None, which TOML has no form for: leave the key out (its default applies, if it has one)"))
    elif isinstance(x, bool) or isinstance(x, str):
        return x
    elif isinstance(x, int):
        if not _I64[0] <= x <= _I64[1]:
            issues.append((None, key, f"= {x} is beyond TOML's 64-bit integers ({_I64[0]} to {_I64[1]}); give it as a float if the key takes one"))
    elif isinstance(x, float):
        if not np.isfinite(x):
            issues.append((None, key, f"= {x} is not a finite number: every number of a scene is finite (docs/SCENES.md gives each key's range)"))
    else:
        issues.append((None, key, f"is a {type(x).__name__}: {_ALLOWED}"))
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


_SWEEP_FORM = "a (START, STOP, N) tuple or a \"START:STOP:N\" string"


def _num(x: Any) -> str:
    """A number of a ``vary`` tuple as the command line's text: every real number exactly (repr of
    its float), a string as given (the harness parses it). A bool or any other type is refused."""
    if isinstance(x, str):
        return x
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise TypeError(type(x).__name__)
    return repr(float(x))


def _spec_strings(vary: Any, what: str) -> List[str]:
    """``vary`` given as one ``KEY=...`` string or a list of them, as on the command line."""
    if isinstance(vary, str):
        return [vary]
    if isinstance(vary, (list, tuple)) and all(isinstance(v, str) for v in vary):
        return list(vary)
    raise InputError(f"vary = {vary!r}: give a dict of key to {what}, or a list of \"KEY=...\" strings as on the command line")


def _vary_items(vary: Mapping[str, Any]):
    for key, v in vary.items():
        if not isinstance(key, str):
            raise InputError(f"vary: the key {key!r} is a {type(key).__name__}; a key is a dotted string such as \"motion.speed\"")
        yield key, v


def _keys(keys: Any, name: str) -> List[str]:
    """A list of dotted keys; one key may be given as a string."""
    if isinstance(keys, str):
        return [keys]
    out = list(keys)
    bad = [k for k in out if not isinstance(k, str)]
    if bad:
        raise InputError(f"{name} = {keys!r}: a list of dotted keys (strings such as \"motion.speed\"), not {type(bad[0]).__name__}")
    return out


def _sweep_specs(vary: Union[Mapping[str, Any], Sequence[str], str]) -> List[str]:
    if not isinstance(vary, Mapping):
        return _spec_strings(vary, _SWEEP_FORM)
    out = []
    for key, v in _vary_items(vary):
        if isinstance(v, str):
            out.append(f"{key}={v}")
            continue
        if not (isinstance(v, (list, tuple)) and len(v) == 3):
            raise InputError(f"vary[{key!r}] = {v!r}: an axis is {_SWEEP_FORM}, e.g. (0.2, 0.4, 3)")
        start, stop, n = v
        try:
            ends = [_num(start), _num(stop)]
        except TypeError as e:
            raise InputError(f"vary[{key!r}] = {v!r}: START and STOP are numbers, not {e}") from None
        count = n if isinstance(n, str) else _whole(f"vary[{key!r}]'s N", n, 1, _U64, "the number of points")
        out.append(f"{key}={ends[0]}:{ends[1]}:{count}")
    return out


def sweep(scene: Scene, vary, *, log: Iterable[str] = (), strict: bool = False, jobs: Optional[int] = None) -> pd.DataFrame:
    """``flinch sweep``: the scene over a grid of one or two keys, on all cores (or ``jobs``
    threads). ``vary`` is ``{"motion.speed": (0.05, 0.3, 6)}`` (start, stop, n) or ``"KEY=START:STOP:N"``
    strings as on the command line (``log:`` or ``log=[key]`` for a geometric axis). Returns the
    CSV of ``flinch sweep --csv`` as a DataFrame: the swept keys, every summary field, ``status``
    (ok, refused, failed) and ``reason``; points run with the first key varying slowest. A point the
    validator refuses is a row with status "refused" (``strict=True`` refuses the sweep instead).
    Raises SolverError, with the DataFrame in ``result``, if the solver failed at any point."""
    file, text = _resolve(scene)
    csv, points, failed, refused = _flinch.sweep(file, text, _sweep_specs(vary), _keys(log, "log"), bool(strict), _jobs(jobs))
    import io

    df = pd.read_csv(io.StringIO(csv), keep_default_na=False, na_values=[""])
    df["reason"] = df["reason"].astype(object).fillna("")
    if failed:
        raise SolverError(f"the solver failed at {failed} of {points} points (status and reason columns)", result=df)
    return df


_DIST_FORM = "a distribution: \"normal:MEAN:SD\" or the tuple (\"normal\", MEAN, SD) (also lognormal, uniform, triangular; docs/sample.md)"


def _sample_specs(vary: Union[Mapping[str, Any], Sequence[str], str]) -> List[str]:
    """``--vary`` specs from ``{"motion.dead_time": "uniform:0.016:0.032"}``,
    ``{"motion.dead_time": ("uniform", 0.016, 0.032)}`` or ``["motion.dead_time=uniform:0.016:0.032"]``."""
    if not isinstance(vary, Mapping):
        return _spec_strings(vary, _DIST_FORM)
    out = []
    for key, v in _vary_items(vary):
        if isinstance(v, str):
            out.append(f"{key}={v}")
            continue
        if not (isinstance(v, (list, tuple)) and len(v) >= 1 and isinstance(v[0], str)):
            fixed = " (to fix a key at one value, set it in the scene: flinch.scene(name) gives a dict to edit)" if isinstance(v, (int, float, np.number)) else ""
            raise InputError(f"vary[{key!r}] = {v!r}: give {_DIST_FORM}{fixed}")
        name, *params = v
        try:
            out.append(f"{key}={name}:" + ":".join(_num(p) for p in params))
        except TypeError as e:
            raise InputError(f"vary[{key!r}] = {v!r}: a distribution's parameters are numbers, not {e}") from None
    return out


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


_STATUS = pd.CategoricalDtype(["ok", "refused", "failed", "inconclusive"])


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
    n, seed, chunk, jobs = _count(n), _seed(seed), _chunk(chunk), _jobs(jobs)
    _notes(file, text, specs, n, seed, bool(truncate))
    report, cols = _flinch.sample(file, text, specs, n, seed, bool(truncate), chunk, jobs, bool(rows))
    result = Sample(json.loads(report), _frame(cols) if cols is not None else None)
    return _raise_for(result)


def _notes(file: str, text: str, specs: List[str], n: int, seed: int, truncate: bool) -> None:
    """Checks a study before it runs (raising what ``flinch sample`` refuses) and warns, as its
    notes do, of distributions that put draws outside their keys' accepted ranges."""
    import warnings

    _, notes = _flinch.sample_check(file, text, specs, n, seed, truncate)
    for note in notes:
        warnings.warn(note, RefusalWarning, stacklevel=3)


#: The largest u64: the harness counts samples and seeds in 64 bits.
_U64 = 2**64 - 1

#: More threads than any machine has cores; each is an OS thread.
MAX_JOBS = 4096


def _whole(name: str, x: Any, lo: int, hi: int, what: str) -> int:
    """``x`` as an int in [lo, hi]: a Python or NumPy integer, or a float with no fractional part
    (``1e6``). A bool, a fraction, a string or a number out of range is an InputError naming
    ``name`` and what is allowed; never rounded, never wrapped."""
    allowed = f"{name} is {what}: a whole number from {lo:,} to {hi:,}"
    if isinstance(x, (bool, np.bool_)):
        raise InputError(f"{name} = {x!r}: {allowed}, not a bool")
    if isinstance(x, (int, np.integer)):
        v = int(x)
    elif isinstance(x, (float, np.floating)):
        if not (np.isfinite(x) and float(x).is_integer()):
            raise InputError(f"{name} = {x!r}: {allowed}")
        v = int(x)
    else:
        raise InputError(f"{name} = {x!r}: {allowed}, not a {type(x).__name__}")
    if not lo <= v <= hi:
        raise InputError(f"{name} = {x!r}: {allowed}")
    return v


def _count(n: Any) -> int:
    return _whole("n", n, 1, _U64, "the number of samples")


def _seed(seed: Any) -> int:
    return _whole("seed", seed, 0, _U64, "the seed of the draws")


def _jobs(jobs: Any) -> Optional[int]:
    return None if jobs is None else _whole("jobs", jobs, 1, MAX_JOBS, "the number of threads (None: all cores)")


def _chunk(chunk: Any) -> Optional[Tuple[int, int]]:
    if chunk is None:
        return None
    if isinstance(chunk, (str, bytes)) or not isinstance(chunk, Sequence) or len(chunk) != 2:
        raise InputError(f"chunk = {chunk!r}: a chunk is (K, M), chunk K of M, with 1 <= K <= M")
    k = _whole("chunk's K", chunk[0], 1, _U64, "the chunk's number (chunk K of M)")
    m = _whole("chunk's M", chunk[1], 1, _U64, "the number of chunks (chunk K of M)")
    if k > m:
        raise InputError(f"chunk = ({k}, {m}): a chunk is (K, M), chunk K of M, with 1 <= K <= M")
    return k, m


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
