"""Shared by the tests of the flinch package.

Tests that compare with the command line need the `flinch` binary: FLINCH_BIN names it (the xtask
stage "python" builds it and sets it). Without it they are skipped, except in CI (CI set), where
a missing binary fails them: nothing is skipped quietly there.
"""

import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
SCENES = REPO / "scenes"


def in_ci() -> bool:
    v = os.environ.get("CI", "")
    return v not in ("", "0", "false")


@pytest.fixture(scope="session")
def cli():
    """Runs `flinch ARGS...`; returns (exit code, stdout, stderr)."""
    exe = os.environ.get("FLINCH_BIN")
    if not exe or not os.path.exists(exe):
        if in_ci():
            pytest.fail(f"FLINCH_BIN={exe!r} is not the flinch binary: the comparison with the command line cannot run")
        pytest.skip("FLINCH_BIN not set: no flinch binary to compare with")

    def run(*args, cwd=None):
        p = subprocess.run([exe, *map(str, args)], capture_output=True, text=True, cwd=cwd)
        return p.returncode, p.stdout, p.stderr

    return run
