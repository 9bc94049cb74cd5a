"""Throughput of one sample study four ways on this machine (issue 14): the `flinch sample` command
line on all cores, flinch.sample in one process (all cores, and one thread), and flinch.dask.sample
on a LocalCluster of two worker processes with one thread each. A benchmark, not a test: it prints
samples per second and the ratio of Dask to the command line; docs/python.md has the figures.

    python python/bench/dask_throughput.py --flinch target/release/flinch --samples 20000

The study is docs/sample.md's: Tables 5-7 with four varied keys.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import time

import flinch
import flinch.dask

VARY = {
    "motion.dead_time": "uniform:0.016:0.032",
    "decoupler.spring_rate": "normal:200:10",
    "decoupler.height": "normal:0.03:0.0005",
    "motion.speed": "normal:0.05:0.002",
}
SCENE = "tables5-7_bistable"


def children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def timed(f, cpu):
    """Wall time, CPU time (by `cpu`, a function returning seconds used so far) and f's result."""
    c, t = cpu(), time.perf_counter()
    out = f()
    return time.perf_counter() - t, cpu() - c, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples", type=int, default=20000)
    ap.add_argument("--flinch", default=os.environ.get("FLINCH_BIN", "flinch"), help="the flinch binary (release build)")
    ap.add_argument("--repeat", type=int, default=2, help="runs of each; the best is reported")
    a = ap.parse_args()
    n = a.samples
    print(f"{n} samples of {SCENE}, 4 keys; {os.cpu_count()} cores; load average before: {os.getloadavg()}")

    cli_args = [a.flinch, "sample", SCENE, "--samples", str(n), "--json"]
    for s in flinch._sample_specs(VARY):
        cli_args += ["--vary", s]

    results = {}

    # The machine is shared: besides the wall time, the CPU time each way used (samples per CPU
    # second is the cost, whatever else runs; the wall time depends on the cores it got).
    def best(name, f, cpu=time.process_time):
        runs = [timed(f, cpu) for _ in range(a.repeat)]
        wall, cpu_s, out = min(runs, key=lambda r: r[0])
        results[name] = (wall, cpu_s, out)
        print(f"  {name:<44} wall {wall:6.2f} s {n / wall:7.0f} samples/s | CPU {cpu_s:6.2f} s {n / cpu_s:7.0f} samples per CPU-s  (walls: {', '.join(f'{r[0]:.2f}' for r in runs)})")

    best("flinch sample (CLI, all cores)", lambda: subprocess.run(cli_args, check=True, capture_output=True, text=True).stdout, children_cpu)
    best("flinch.sample (one process, all cores)", lambda: flinch.sample(SCENE, n, VARY, rows=False).report)
    best("flinch.sample (one process, jobs=1)", lambda: flinch.sample(SCENE, n, VARY, jobs=1, rows=False).report)

    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, Client(cluster) as client:
        # Import the extension on the workers before timing.
        flinch.dask.sample(SCENE, 100, VARY, client)

        def cluster_cpu() -> float:
            # The workers' processes and this one (the client's share: submitting, gathering, merging).
            return sum(client.run(time.process_time).values()) + time.process_time()

        best("flinch.dask.sample (2 workers x 1 thread)", lambda: flinch.dask.sample(SCENE, n, VARY, client).report, cluster_cpu)

    one = results["flinch.sample (one process, all cores)"][2]
    assert results["flinch.dask.sample (2 workers x 1 thread)"][2] == one, "Dask's report differs from the single-process one"
    cli = results["flinch sample (CLI, all cores)"]
    dask = results["flinch.dask.sample (2 workers x 1 thread)"]
    print(f"Dask / CLI: wall-clock throughput {cli[0] / dask[0]:.2f}, samples per CPU-second {cli[1] / dask[1]:.2f} (target >= 0.80)")
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
