"""flinch.dask.sample on a LocalCluster of two worker processes: the merged result equals the
single-process result for the same seed, field for field and row for row."""

import pandas as pd
import pytest

import flinch
import flinch.dask

distributed = pytest.importorskip("distributed") if not __import__("conftest").in_ci() else __import__("distributed")

FOUR = {
    "motion.dead_time": "uniform:0.016:0.032",
    "decoupler.spring_rate": "normal:200:10",
    "decoupler.height": "normal:0.03:0.0005",
    "motion.speed": "normal:0.25:0.01",
}


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def test_two_workers_give_the_single_process_result(client):
    assert len(client.scheduler_info()["workers"]) == 2
    n = 3001
    one = flinch.sample("tables5-7_bistable_v025", n, FOUR, seed=9)
    on_dask = flinch.dask.sample("tables5-7_bistable_v025", n, FOUR, client, seed=9, rows=True)
    assert on_dask.report == one.report
    assert on_dask.report["complete"] and on_dask.report["ranges"] == [[0, n]]
    pd.testing.assert_frame_equal(on_dask.rows, one.rows)
    # Chunks that do not divide N, and a chunk count larger than the threads.
    odd = flinch.dask.sample("tables5-7_bistable_v025", n, FOUR, client, seed=9, chunks=7)
    assert odd.report == one.report and odd.rows is None
    # Both workers ran tasks.
    who = client.run(lambda: 1)
    assert len(who) == 2


def test_refused_samples_and_a_dict_scene_on_dask(client):
    sc = flinch.scene("tables5-7_bistable_v025")
    vary = {"motion.dead_time": "normal:0.002:0.002"}
    with pytest.warns(flinch.RefusalWarning):
        one = flinch.sample(sc, 400, vary, seed=2, rows=False)
    with pytest.warns(flinch.RefusalWarning):
        on_dask = flinch.dask.sample(sc, 400, vary, client, seed=2)
    assert on_dask.report == one.report and one.report["refused"] > 0


def test_bad_input_raises_on_the_client_before_any_task(client, monkeypatch):
    def no_task(*a, **k):
        raise AssertionError("a task was submitted for bad input")

    monkeypatch.setattr(client, "submit", no_task)
    with pytest.raises(flinch.InputError, match="unknown distribution"):
        flinch.dask.sample("tables5-7_bistable_v025", 100, {"motion.speed": "gauss:1:2"}, client)
    with pytest.raises(flinch.SceneError):
        flinch.dask.sample("no_such_scene_here", 100, FOUR, client)
    with pytest.raises(flinch.InputError, match="motion.speed"):
        flinch.dask.sample("tables5-7_bistable_v025", 100, {"motion.sped": "normal:0.25:0.01"}, client)
