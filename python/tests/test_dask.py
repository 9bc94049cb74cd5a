"""flinch.dask.sample on a LocalCluster of two worker processes: the merged result equals the
single-process result for the same seed, field for field and row for row."""

import os

import pandas as pd
import pytest

import flinch
import flinch.dask
from conftest import REPO, SCENES

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
    # Arguments are checked on the client too.
    with pytest.raises(flinch.InputError, match="seed = -1"):
        flinch.dask.sample("tables5-7_bistable_v025", 100, FOUR, client, seed=-1)
    with pytest.raises(flinch.InputError, match="chunks = 0"):
        flinch.dask.sample("tables5-7_bistable_v025", 100, FOUR, client, chunks=0)
    with pytest.raises(flinch.InputError, match="jobs = True"):
        flinch.dask.sample("tables5-7_bistable_v025", 100, FOUR, client, jobs=True)


@pytest.fixture
def workers_elsewhere(client, tmp_path, monkeypatch):
    """The workers' working directory is an empty folder, as on another machine; the client's is
    the repository's root. Restored after the test."""
    monkeypatch.chdir(REPO)
    before = client.run(os.getcwd)
    client.run(os.chdir, str(tmp_path))
    assert set(client.run(os.getcwd).values()) == {str(tmp_path)}
    yield client
    for addr, cwd in before.items():
        client.run(os.chdir, cwd, workers=[addr])


URDF_VARY = {"motion.dead_time": "uniform:0.016:0.032"}


def test_a_scene_that_refers_to_a_file_is_refused_on_the_client(workers_elsewhere, monkeypatch):
    client = workers_elsewhere
    # Without the check, the tasks failed on the workers: SceneError "cannot read the URDF".
    def no_task(*a, **k):
        raise AssertionError("a task was submitted for a scene whose URDF the workers cannot read")

    monkeypatch.setattr(client, "submit", no_task)
    with pytest.raises(flinch.InputError) as e:
        flinch.dask.sample("scenes/robot_two_link.toml", 50, URDF_VARY, client)
    msg = str(e.value)
    assert msg.startswith("scenes/robot_two_link.toml: robot.urdf refers to the file scenes/robots/two_link.urdf")
    assert "shared_files=True" in msg and "flinch robot" in msg
    # shared_files=True with a relative path: a worker would resolve it against its own directory.
    with pytest.raises(flinch.InputError, match="relative path scenes/robots/two_link.urdf"):
        flinch.dask.sample("scenes/robot_two_link.toml", 50, URDF_VARY, client, shared_files=True)


def test_a_urdf_scene_runs_on_workers_elsewhere_by_absolute_path_with_shared_files(workers_elsewhere):
    client = workers_elsewhere
    path = str(SCENES / "robot_two_link.toml")
    one = flinch.sample(path, 64, URDF_VARY, seed=3, rows=False)
    on_dask = flinch.dask.sample(path, 64, URDF_VARY, client, seed=3, chunks=4, shared_files=True)
    assert on_dask.report == one.report and one.report["ran"] == 64


def test_a_shipped_urdf_scene_by_name_needs_no_files_on_the_workers(workers_elsewhere):
    # The shipped scenes' URDFs are built into the harness.
    client = workers_elsewhere
    one = flinch.sample("robot_two_link", 64, URDF_VARY, seed=3, rows=False)
    on_dask = flinch.dask.sample("robot_two_link", 64, URDF_VARY, client, seed=3, chunks=4)
    assert on_dask.report == one.report and one.report["ran"] == 64


def test_with_shared_files_a_worker_whose_copy_differs_refuses_to_run(workers_elsewhere, monkeypatch):
    # As if a node had another version of the URDF: the client's digest is not the workers' copy's.
    client = workers_elsewhere
    monkeypatch.setattr(flinch.dask, "_digest", lambda path: "0" * 64)
    with pytest.raises(flinch.InputError, match="a Dask worker's copy differs from the client's"):
        flinch.dask.sample(str(SCENES / "robot_two_link.toml"), 16, URDF_VARY, client, seed=3, chunks=2, shared_files=True)


def test_a_shipped_scene_by_name_with_its_urdf_path_present_here_is_refused_too(workers_elsewhere, tmp_path_factory, monkeypatch):
    # The harness reads robots/two_link.urdf from the working directory when it exists, the built-in
    # copy otherwise: a client that has the file would check one robot and the workers run another.
    here = tmp_path_factory.mktemp("client")
    (here / "robots").mkdir()
    (here / "robots" / "two_link.urdf").write_text((SCENES / "robots" / "two_link.urdf").read_text())
    monkeypatch.chdir(here)
    with pytest.raises(flinch.InputError, match="robot.urdf refers to the file robots/two_link.urdf"):
        flinch.dask.sample("robot_two_link", 16, URDF_VARY, workers_elsewhere, chunks=2)
