"""Arguments are checked before anything runs: a dict scene's values that have no TOML form name
their dotted key (SceneError, as the validator's issues for a dict do), and n, seed, jobs, chunk and
vary that are not what they must be raise InputError naming the argument and what is allowed, never
rounded, wrapped or passed on as an OverflowError or a TypeError."""

import numpy as np
import pytest

import flinch
from conftest import SCENES

V = {"motion.dead_time": "uniform:0.016:0.032"}


# ---- a dict scene's values ------------------------------------------------------------------

@pytest.mark.parametrize(
    "value, says",
    [
        (float("nan"), "not a finite number"),
        (float("inf"), "not a finite number"),
        (np.float64("nan"), "not a finite number"),
        (None, "leave the key out"),
        (2**63, "64-bit integers"),
        (-(2**63) - 1, "64-bit integers"),
        (object(), "is a object: a scene's values are strings, finite numbers"),
        (1 + 2j, "is a complex"),
    ],
)
def test_a_dict_value_with_no_toml_form_names_its_key(value, says):
    sc = flinch.scene("tables5-7_bistable")
    sc["motion"]["speed"] = value
    with pytest.raises(flinch.SceneError) as e:
        flinch.run(sc)
    assert e.value.file == "<dict>"
    assert e.value.issues == [{"line": None, "key": "motion.speed", "message": e.value.issues[0]["message"]}]
    assert says in e.value.issues[0]["message"], e.value.issues
    assert str(e.value) == f"<dict>: motion.speed: {e.value.issues[0]['message']}"
    # None's hint is for None only.
    assert ("None" in str(e.value)) == (value is None)
    # Not the internal JSON's column.
    assert "column" not in str(e.value)


def test_every_bad_value_is_listed_with_its_dotted_key_and_list_index():
    sc = flinch.scene("robot_two_link")
    sc["motion"]["speed"] = float("nan")
    sc["robot"]["direction"] = [1.0, None, float("-inf")]
    sc["tool"]["mass"] = None
    with pytest.raises(flinch.SceneError) as e:
        flinch.check(sc)
    assert [i["key"] for i in e.value.issues] == ["motion.speed", "robot.direction[1]", "robot.direction[2]", "tool.mass"]
    assert all(i["line"] is None for i in e.value.issues)
    assert len(str(e.value).splitlines()) == 4


def test_numpy_scalars_and_arrays_are_their_python_values():
    sc = flinch.scene("robot_two_link")
    sc["robot"]["urdf"] = str(SCENES / "robots" / "two_link.urdf")  # a dict's urdf is relative to the working directory
    plain = flinch.run(sc)
    sc["motion"]["speed"] = np.float64(sc["motion"]["speed"])
    sc["motion"]["dead_time"] = np.float32(0.016)  # not exactly 0.016: compared by its own value below
    sc["decoupler"]["springs"] = np.int64(sc["decoupler"]["springs"])
    sc["robot"]["direction"] = np.array([1.0, 0.0, 0.0])
    sc["robot"]["joint_stiffness"] = np.array([2.0e4, 1.0e4])
    with_numpy = flinch.run(sc)
    sc["motion"]["dead_time"] = float(np.float32(0.016))
    sc["robot"]["direction"] = [1.0, 0.0, 0.0]
    sc["robot"]["joint_stiffness"] = [2.0e4, 1.0e4]
    sc["decoupler"]["springs"] = int(sc["decoupler"]["springs"])
    assert with_numpy == flinch.run(sc)
    assert plain["safe"] == with_numpy["safe"]


def test_numpy_bools_are_bools():
    sc = flinch.scene("tables5-7_bistable")
    # A bool where a number is expected is the validator's type error, not a crash or a 1.0.
    sc["motion"]["speed"] = np.bool_(True)
    with pytest.raises(flinch.SceneError) as e:
        flinch.run(sc)
    assert e.value.issues[0]["key"] == "motion.speed"
    assert "got boolean" in str(e.value)
    # And a bool key takes one.
    sc = flinch.scene("tables5-7_bistable")
    sc["motion"]["start_at_speed"] = np.bool_(True)
    a = flinch.run(sc)
    sc["motion"]["start_at_speed"] = True
    assert a == flinch.run(sc)


# ---- n, seed, jobs, chunk ---------------------------------------------------------------------

@pytest.mark.parametrize(
    "kwargs, says",
    [
        ({"n": True}, "n = True: n is the number of samples: a whole number from 1 to 18,446,744,073,709,551,615, not a bool"),
        ({"n": 0}, "n = 0: n is the number of samples"),
        ({"n": -5}, "n = -5"),
        ({"n": 2.5}, "n = 2.5"),
        ({"n": float("nan")}, "n = nan"),
        ({"n": 2**64}, "n = 18446744073709551616"),
        ({"n": "100"}, "not a str"),
        ({"seed": 1.7}, "seed = 1.7: seed is the seed of the draws: a whole number from 0"),
        ({"seed": -1}, "seed = -1"),
        ({"seed": 2**64}, "seed = 18446744073709551616"),
        ({"seed": False}, "not a bool"),
        ({"jobs": -1}, "jobs = -1: jobs is the number of threads (None: all cores): a whole number from 1 to 4,096"),
        ({"jobs": 0}, "jobs = 0"),
        ({"jobs": 10**6}, "jobs = 1000000"),
        ({"jobs": 1.5}, "jobs = 1.5"),
        ({"chunk": (-1, 2)}, "chunk's K = -1"),
        ({"chunk": (3, 2)}, "1 <= K <= M"),
        ({"chunk": (1, 2**64)}, "chunk's M = 18446744073709551616"),
        ({"chunk": (1, True)}, "not a bool"),
        ({"chunk": "1/2"}, "a chunk is (K, M)"),
        ({"chunk": (1, 2, 3)}, "a chunk is (K, M)"),
    ],
)
def test_bad_counts_seeds_jobs_and_chunks_are_input_errors(kwargs, says):
    args = {"n": 10, **kwargs}
    n = args.pop("n")
    with pytest.raises(flinch.InputError) as e:
        flinch.sample("tables5-7_bistable_v025", n, V, rows=False, **args)
    assert says in str(e.value)


def test_whole_numbers_are_taken_exactly_and_numpy_integers_and_whole_floats_are_accepted():
    r = flinch.sample("tables5-7_bistable_v025", np.int64(3), V, seed=np.uint64(2**64 - 1), jobs=np.int32(1), chunk=(np.int64(1), 2.0), rows=False)
    assert r.report["samples"] == 3 and r.report["seed"] == 2**64 - 1
    assert r.report["ranges"] == [[0, 1]]
    # 1e4 as a float is 10,000; an int beyond 2**53 is not rounded through a float.
    assert flinch._count(1e4) == 10_000
    assert flinch._count(10**17 + 1) == 10**17 + 1
    assert flinch._seed(2**64 - 1) == 2**64 - 1


def test_sweep_jobs_are_checked_too():
    with pytest.raises(flinch.InputError, match="jobs = -1"):
        flinch.sweep("tables5-7_bistable_v025", {"motion.speed": (0.2, 0.3, 2)}, jobs=-1)


# ---- vary -------------------------------------------------------------------------------------

@pytest.mark.parametrize(
    "vary, says",
    [
        ({"motion.dead_time": 0.02}, "vary['motion.dead_time'] = 0.02: give a distribution: \"normal:MEAN:SD\" or the tuple (\"normal\", MEAN, SD)"),
        ({"motion.dead_time": 0.02}, "to fix a key at one value, set it in the scene"),
        ({"motion.dead_time": ("uniform", 0.016, None)}, "parameters are numbers, not NoneType"),
        ({"motion.dead_time": ("uniform", True, 0.03)}, "not bool"),
        ({"motion.dead_time": (0.016, 0.032)}, "give a distribution"),
        ({1: "uniform:0.016:0.032"}, "the key 1 is a int"),
        ([("motion.dead_time", "uniform:0.016:0.032")], "a list of \"KEY=...\" strings"),
        (42, "vary = 42"),
    ],
)
def test_a_bad_sample_vary_is_an_input_error(vary, says):
    with pytest.raises(flinch.InputError) as e:
        flinch.sample("tables5-7_bistable_v025", 10, vary, rows=False)
    assert says in str(e.value)


def test_a_distribution_tuple_takes_numpy_numbers():
    a = flinch.sample("tables5-7_bistable_v025", 5, {"motion.dead_time": ("uniform", np.float64(0.016), np.float32(0.5) / 16)}, rows=False)
    b = flinch.sample("tables5-7_bistable_v025", 5, {"motion.dead_time": "uniform:0.016:0.03125"}, rows=False)
    assert a.report == b.report


@pytest.mark.parametrize(
    "vary, says",
    [
        ({"motion.speed": 0.2}, "vary['motion.speed'] = 0.2: an axis is a (START, STOP, N) tuple"),
        ({"motion.speed": (0.2, 0.3)}, "an axis is a (START, STOP, N) tuple"),
        ({"motion.speed": (0.2, 0.3, 2.5)}, "vary['motion.speed']'s N = 2.5"),
        ({"motion.speed": (0.2, 0.3, True)}, "not a bool"),
        ({"motion.speed": (None, 0.3, 2)}, "START and STOP are numbers, not NoneType"),
    ],
)
def test_a_bad_sweep_vary_is_an_input_error(vary, says):
    with pytest.raises(flinch.InputError) as e:
        flinch.sweep("tables5-7_bistable_v025", vary)
    assert says in str(e.value)


def test_a_sweep_log_key_may_be_one_string():
    a = flinch.sweep("tables5-7_bistable_v025", {"motion.speed": (0.1, 0.4, 3)}, log="motion.speed")
    b = flinch.sweep("tables5-7_bistable_v025", {"motion.speed": (0.1, 0.4, 3)}, log=["motion.speed"])
    assert a.equals(b)
    assert a["motion.speed"].iloc[1] == pytest.approx(0.2)
