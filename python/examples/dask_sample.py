"""flinch.dask.sample against a Dask scheduler: a LocalCluster of two worker processes by default,
or the scheduler whose address is given (`python dask_sample.py tcp://scheduler:8786`): the same
call, no code change. Prints whether the result equals flinch.sample's in this process (same
seed), then the report. docs/python.md shows the call on Slurm (dask-jobqueue) and Kubernetes.
"""

import sys

from distributed import Client, LocalCluster

import flinch
import flinch.dask

SCENE = "tables5-7_bistable_v025"
VARY = {
    "motion.dead_time": "uniform:0.016:0.032",
    "motion.speed": "normal:0.25:0.01",
    "decoupler.spring_rate": "normal:200:10",
    "decoupler.height": "normal:0.03:0.0005",
}


def main() -> None:
    if len(sys.argv) > 1:
        cluster, client = None, Client(sys.argv[1])
    else:
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None)
        client = Client(cluster)
    try:
        r = flinch.dask.sample(SCENE, 200, VARY, client, seed=1)
        workers = len(client.scheduler_info()["workers"])
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    same = r.report == flinch.sample(SCENE, 200, VARY, seed=1, rows=False).report
    print(f"{workers} Dask workers; the same report as flinch.sample in one process: {same}")
    print(r, end="")


if __name__ == "__main__":
    main()
