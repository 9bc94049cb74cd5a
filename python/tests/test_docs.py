"""docs/python.md's API example runs as written: every statement of its ```python block under
"## The API", in order, and each expression whose comment starts with a value (`# False: ...`)
gives that value."""

import ast
import re

import flinch
from conftest import REPO


def api_block() -> str:
    doc = (REPO / "docs" / "python.md").read_text()
    section = doc[doc.index("## The API"):]
    m = re.search(r"```python\n(.*?)```", section, re.S)
    assert m, "docs/python.md: no ```python block under ## The API"
    return m.group(1)


def test_the_api_example_runs_and_its_commented_values_are_what_it_gives():
    src = api_block()
    lines = src.splitlines()
    tree = ast.parse(src)
    env = {}
    claims = 0
    for stmt in tree.body:
        code = compile(ast.Module([stmt], []), "docs/python.md", "exec") if not isinstance(stmt, ast.Expr) else None
        if code is not None:
            exec(code, env)
            continue
        value = eval(compile(ast.Expression(stmt.value), "docs/python.md", "eval"), env)
        comment = lines[stmt.end_lineno - 1].partition("#")[2].strip()
        said = re.match(r"(True|False)\b", comment)
        if said:
            claims += 1
            assert value is (said.group(1) == "True"), f"docs/python.md: `{ast.unparse(stmt)}` gives {value!r}, the comment says {comment!r}"
    # The block's claim that an edited scene is unsafe is checked, not skipped.
    assert claims >= 1
    assert env["sc"]["motion"] != flinch.scene("tables5-7_bistable_v025")["motion"]


def test_the_unsafe_example_is_unsafe_because_its_stroke_runs_out_not_because_the_run_ended_early():
    # The example's edit, read from the doc, runs to a stop inside `duration`: its failure is the
    # stroke, not a run that did not conclude.
    src = api_block()
    env = {"flinch": flinch}
    edit = [l for l in src.splitlines() if l.startswith("sc = ") or l.startswith('sc["')]
    assert edit, "the example edits no scene"
    exec("\n".join(edit), env)
    s = flinch.run(env["sc"])
    assert s["safe"] is False and s["stroke_exhausted"] is True, s["failures"]
    assert s["concluded"] is True
    # The comment's "40 ms still stops in time".
    env["sc"]["motion"]["dead_time"] = 0.04
    assert flinch.run(env["sc"])["safe"] is True
    assert not any("not concluded" in f for f in s["failures"]), s["failures"]
