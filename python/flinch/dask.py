"""``flinch sample`` on a Dask cluster: the chunks of one study (``--chunk K/M``) as Dask tasks,
merged into the report of the whole study, equal field for field to ``flinch.sample`` with the same
seed on one machine (sample i's draws depend only on the seed, i and the key's position).

The scene is read here, on the client, and its text sent with each task: the workers need the
``flinch`` package installed (the same ``pip install ./python``), not the scene files. The same
call runs on a ``LocalCluster``, a ``dask_jobqueue.SLURMCluster`` or a Kubernetes cluster: only the
client changes (docs/python.md).
"""

from __future__ import annotations

import uuid
from typing import Any, Dict, List, Optional, Tuple

import pandas as pd

from . import Sample, Scene, _chunk_report, _count, _notes, _raise_for, _resolve, _sample_specs, merge


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
) -> Sample:
    """``flinch.sample`` as ``chunks`` Dask tasks on ``client`` (default: the current client,
    ``distributed.get_client()``), merged. Each task runs chunk k of ``chunks`` on ``jobs`` threads
    (default 1: Dask's threads are the parallelism; give a worker's cores when each worker runs
    one task at a time). ``chunks`` defaults to 4 per worker thread (at least one sample each), so a
    slow worker does not hold the end back. ``rows=True`` brings every row back to the client (the
    DataFrame of ``flinch.sample``); the default keeps only the reports, memory flat at any n.

    Bad input raises here, before any task is submitted. Raises InputError and SolverError as
    ``flinch.sample`` does, with the merged result in ``.result``."""
    if client is None:
        from distributed import get_client

        client = get_client()
    file, text = _resolve(scene)
    specs = _sample_specs(vary)
    n = _count(n)
    # Checks the study where the user is: a bad key or distribution is an error here, not in a worker.
    _notes(file, text, specs, n, int(seed), bool(truncate))
    m = int(chunks) if chunks is not None else 4 * _total_threads(client)
    m = max(1, min(m, n))
    token = uuid.uuid4().hex[:8]
    futures = [
        client.submit(_chunk_report, file, text, specs, n, int(seed), bool(truncate), (k, m), jobs, bool(rows), key=f"flinch-sample-{token}-{k}-of-{m}", pure=False)
        for k in range(1, m + 1)
    ]
    parts: List[Tuple[Dict[str, Any], Optional[pd.DataFrame]]] = client.gather(futures)
    report = merge([p[0] for p in parts])
    frame = pd.concat([p[1] for p in parts], ignore_index=True) if rows else None
    return _raise_for(Sample(report, frame))
