"""flinch.run, flinch.scene, flinch.check: the summary of `flinch run --json`, scenes as paths,
shipped names and dicts, and the validator's messages as SceneError."""

import json

import pytest

import flinch
from conftest import SCENES


def test_a_shipped_scene_runs_and_its_summary_is_the_command_lines(cli):
    s = flinch.run("tables5-7_bistable")
    code, out, err = cli("run", "tables5-7_bistable", "--json")
    assert code == 0, err
    assert s == json.loads(out)


def test_a_path_a_name_and_a_dict_are_the_same_scene():
    by_name = flinch.run("tables5-7_bistable")
    by_path = flinch.run(SCENES / "tables5-7_bistable.toml")
    by_dict = flinch.run(flinch.scene("tables5-7_bistable"))
    assert by_name == by_path == by_dict
    assert by_name["safe"] is True and by_name["stroke_exhausted"] is False


def test_an_edited_dict_that_exhausts_the_stroke_is_reported_unsafe_not_raised():
    sc = flinch.scene("tables5-7_bistable_v025")
    sc["motion"]["speed"] = 0.28
    sc["motion"]["dead_time"] = 0.04
    s = flinch.run(sc)
    assert s["stroke_exhausted"] is True
    assert s["safe"] is False and s["failures"], s["failures"]


def test_scene_errors_carry_the_command_lines_file_line_key_message(tmp_path, cli):
    text = (SCENES / "tables5-7_bistable.toml").read_text()
    lines = text.splitlines()
    at = next(i for i, l in enumerate(lines) if l.strip().startswith("speed"))
    lines[at] = "speed = -0.2"
    bad = tmp_path / "bad.toml"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(flinch.SceneError) as e:
        flinch.run(bad)
    assert e.value.file == str(bad)
    assert e.value.issues[0]["line"] == at + 1
    assert e.value.issues[0]["key"] == "motion.speed"
    assert str(e.value).startswith(f"{bad}:{at + 1}: motion.speed: ")
    code, out, err = cli("run", bad)
    assert code == 2
    assert err.strip() == f"error: {e.value}"
    # A SceneError is a ValueError too.
    assert isinstance(e.value, ValueError)


def test_a_dict_scene_error_names_the_key_without_a_line():
    sc = flinch.scene("tables5-7_bistable")
    sc["decoupler"]["spring_rate"] = -5.0
    sc["motion"]["speeed"] = 1.0
    with pytest.raises(flinch.SceneError) as e:
        flinch.run(sc)
    keys = {i["key"] for i in e.value.issues}
    assert {"decoupler.spring_rate", "motion.speeed"} <= keys, e.value.issues
    assert all(i["line"] is None for i in e.value.issues)
    assert e.value.file == "<dict>"
    assert "<dict>: decoupler.spring_rate: " in str(e.value)
    assert "speed" in str(e.value)  # the unknown key's close match


def test_unreadable_scenes_are_scene_errors():
    with pytest.raises(flinch.SceneError, match="no such file, and no shipped scene"):
        flinch.run("tables5-7_bistabel")
    with pytest.raises(flinch.SceneError, match="tables5-7_bistable"):
        flinch.run("tables5-7_bistabel")  # the close name is suggested
    sc = flinch.scene("tables5-7_bistable")
    sc["motion"]["speed"] = None
    with pytest.raises(flinch.SceneError, match="None"):
        flinch.run(sc)
    with pytest.raises(TypeError):
        flinch.run(42)


def test_check_and_the_list_of_shipped_scenes():
    assert "tables5-7_bistable" in flinch.scenes()
    flinch.check("tables5-7_bistable")
    with pytest.raises(flinch.SceneError):
        flinch.check({"name": "x"})
