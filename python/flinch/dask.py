"""``flinch sample`` on a Dask cluster: the chunks of one study (``--chunk K/M``) as Dask tasks,
merged into the report of the whole study, equal field for field to ``flinch.sample`` with the same
seed on one machine (sample i's draws depend only on the seed, i and the key's position).

The scene is read here, on the client, and its text sent with each task: the workers need the
``flinch`` package installed (the same ``pip install ./python``), not the scene file. A scene that
refers to another file (``robot.urdf``: a robot given by its URDF, read relative to the scene
file) is refused here, before any task, unless ``shared_files=True`` says the workers see the same
files at the same absolute paths (the shipped scenes' URDFs are built in and need neither). The
same call runs on a ``LocalCluster``, a ``dask_jobqueue.SLURMCluster`` or a Kubernetes cluster:
only the client changes (docs/python.md).
"""

from __future__ import annotations

import json
import os
import uuid
from typing import Any, Dict, List, Optional, Tuple

import pandas as pd

from . import InputError, Sample, Scene, _chunk_report, _count, _flinch, _jobs, _notes, _raise_for, _resolve, _sample_specs, _seed, _U64, _whole, merge

#: The URDFs built into the harness (host-harness/src/scene/robot.rs, SHIPPED_URDFS): a shipped
#: scene run by its name reads them there when the path does not exist, as a worker does.
_BUILT_IN_URDFS = ("robots/two_link.urdf", "robots/viper_s650_standin.urdf")


def _files_the_workers_read(file: str, text: str) -> List[str]:
    """The files a task would read besides the scene's text (which is sent with it): the URDF of
    ``robot.urdf``, resolved as the harness resolves it (relative to the scene file's folder; to
    the working directory for a dict). Empty for a shipped scene run by name whose URDF is built in."""
    robot = json.loads(_flinch.toml_to_json(file, text)).get("robot")
    urdf = robot.get("urdf") if isinstance(robot, dict) else None
    if not isinstance(urdf, str):
        return []
    path = urdf if os.path.isabs(urdf) or file == "<stdin>" else os.path.join(os.path.dirname(file), urdf)
    if file.endswith(" (shipped)") and urdf.strip().removeprefix("./") in _BUILT_IN_URDFS and not os.path.exists(path):
        # The harness reads a file at that path first, here and on a worker: only when there is none
        # here is the built-in copy what the client checked.
        return []
    return [path]


def _digest(path: str) -> str:
    import hashlib

    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def _check_files(file: str, text: str, shared_files: bool) -> Dict[str, str]:
    """The files the tasks will read, each with the SHA-256 of the client's copy (the tasks compare
    theirs before running); refuses them unless ``shared_files`` and absolute paths."""
    files = _files_the_workers_read(file, text)
    if not files:
        return {}
    if not shared_files:
        raise InputError(
            f"{file}: robot.urdf refers to the file {files[0]}, which every Dask task would read from its worker's "
            "file system (flinch.dask sends the scene's text, not the files it refers to): on another machine, or "
            "with another working directory, the tasks would fail. Give the robot as [robot] mass, stiffness and "
            "damping (`flinch robot SCENE` prints the values the URDF reduces to), or, when the workers see the "
            "same files at the same paths (a shared file system), give the scene by its absolute path and "
            "shared_files=True"
        )
    relative = [f for f in files if not os.path.isabs(f)]
    if relative:
        raise InputError(
            f"{file}: robot.urdf resolves to the relative path {relative[0]}, which a worker would resolve against "
            "its own working directory: with shared_files=True give the scene by its absolute path "
            "(os.path.abspath) or robot.urdf as an absolute path"
        )
    return {f: _digest(f) for f in files}


def _shared_chunk(digests: Dict[str, str], *args):
    """A chunk, on a worker, of a scene that refers to files: first checks that the worker's copies
    are the client's (a node with another version of the URDF would give another robot, silently)."""
    for path, want in digests.items():
        try:
            have = _digest(path)
        except OSError as e:
            raise InputError(f"{path}: a Dask worker cannot read it ({e}); with shared_files=True every worker must see the client's files at the same paths") from None
        if have != want:
            raise InputError(f"{path}: a Dask worker's copy differs from the client's (SHA-256 {have[:12]}... against {want[:12]}...); with shared_files=True every worker must see the client's files")
    return _chunk_report(*args)


def _total_threads(client) -> int:
    info = client.scheduler_info()
    return max(1, sum(w.get("nthreads", 1) for w in info.get("workers", {}).values()))


def sample(
    scene: Scene,
    n: int,
    vary,
    client=None,
    *,
    seed: int = 1,
    truncate: bool = False,
    chunks: Optional[int] = None,
    jobs: int = 1,
    rows: bool = False,
    shared_files: bool = False,
) -> Sample:
    """``flinch.sample`` as ``chunks`` Dask tasks on ``client`` (default: the current client,
    ``distributed.get_client()``), merged. Each task runs chunk k of ``chunks`` on ``jobs`` threads
    (default 1: Dask's threads are the parallelism; give a worker's cores when each worker runs
    one task at a time). ``chunks`` defaults to 4 per worker thread (at least one sample each), so a
    slow worker does not hold the end back. ``rows=True`` brings every row back to the client (the
    DataFrame of ``flinch.sample``); the default keeps only the reports, memory flat at any n.

    A scene that refers to a file (``robot.urdf``) raises InputError here unless ``shared_files=True``
    (the workers see the same files at the same paths) and the path is absolute: the tasks carry the
    scene's text, not the files it refers to. Bad input raises here, before any task is submitted. Raises InputError and SolverError as
    ``flinch.sample`` does, with the merged result in ``.result``."""
    if client is None:
        from distributed import get_client

        client = get_client()
    file, text = _resolve(scene)
    specs = _sample_specs(vary)
    n, seed, jobs = _count(n), _seed(seed), _jobs(jobs)
    # Checks the study where the user is: a bad key or distribution is an error here, not in a worker.
    _notes(file, text, specs, n, seed, bool(truncate))
    digests = _check_files(file, text, bool(shared_files))
    m = _whole("chunks", chunks, 1, _U64, "the number of tasks") if chunks is not None else 4 * _total_threads(client)
    m = max(1, min(m, n))
    task = (_shared_chunk, digests) if digests else (_chunk_report,)
    token = uuid.uuid4().hex[:8]
    futures = [
        client.submit(*task, file, text, specs, n, seed, bool(truncate), (k, m), jobs, bool(rows), key=f"flinch-sample-{token}-{k}-of-{m}", pure=False)
        for k in range(1, m + 1)
    ]
    parts: List[Tuple[Dict[str, Any], Optional[pd.DataFrame]]] = client.gather(futures)
    report = merge([p[0] for p in parts])
    frame = pd.concat([p[1] for p in parts], ignore_index=True) if rows else None
    return _raise_for(Sample(report, frame))
