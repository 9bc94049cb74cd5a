"""The README's `bash` blocks are Python commands: each runs here (in this venv, from the
repository's root) and where the README shows its output (a `text` block right after, only prose
between) the output of the block's last command must be exactly that. `pip install ./python` is
not run again: it is how this venv was made (the xtask stage "python" runs it). The `sh` blocks
are the command line's, run by host-harness/tests/readme.rs."""

import os
import subprocess
import sys

from conftest import REPO


def blocks(readme: str):
    out, last = [], None
    lines = iter(readme.splitlines())
    for line in lines:
        if not line.startswith("```"):
            continue
        lang = line[3:].strip()
        body = []
        for x in lines:
            if x.startswith("```"):
                break
            body.append(x)
        if lang == "bash":
            out.append({"commands": [c.strip() for c in body if c.strip() and not c.strip().startswith("#")], "expected": None})
            last = len(out) - 1
        elif lang in ("text", "") and last is not None:
            out[last]["expected"] = "\n".join(body) + "\n"
            last = None
        else:
            last = None
    return out


def test_every_readme_python_command_runs_and_prints_what_the_readme_shows():
    bs = blocks((REPO / "README.md").read_text())
    assert len(bs) >= 2, "the README's Python blocks were not found"
    env = dict(os.environ, PATH=os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", ""))
    ran = compared = 0
    for b in bs:
        last = None
        for c in b["commands"]:
            if c == "pip install ./python":
                continue
            assert c.startswith("python "), f"README command not understood: {c}"
            p = subprocess.run(["sh", "-c", c], cwd=REPO, env=env, capture_output=True, text=True, timeout=600)
            assert p.returncode == 0, f"README command failed ({p.returncode}): {c}\n{p.stderr}"
            assert "Traceback" not in p.stderr, f"{c}: {p.stderr}"
            ran += 1
            last = (c, p.stdout)
        if b["expected"] is not None and last is not None:
            assert last[1] == b["expected"], f"README output of `{last[0]}` differs"
            compared += 1
    assert ran >= 2 and compared >= 2, (ran, compared)
