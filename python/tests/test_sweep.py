"""flinch.sweep: the DataFrame of `flinch sweep --csv`, refused points as rows, bad axes raised."""

import io

import pandas as pd
import pytest

import flinch


def test_a_sweep_is_the_command_lines_csv(cli):
    df = flinch.sweep("tables5-7_bistable", {"motion.speed": (0.1, 0.4, 4)})
    assert list(df["motion.speed"]) == [0.1, 0.2, 0.30000000000000004, 0.4] or len(df) == 4
    assert list(df["status"]) == ["ok"] * 4
    code, out, err = cli("sweep", "tables5-7_bistable", "--vary", "motion.speed=0.1:0.4:4", "--csv", "-")
    assert code == 0, err
    want = pd.read_csv(io.StringIO(out), keep_default_na=False, na_values=[""])
    want["reason"] = want["reason"].astype(object).fillna("")
    pd.testing.assert_frame_equal(df, want)


def test_two_axes_make_a_grid_first_key_slowest_and_the_stroke_runs_out_somewhere():
    df = flinch.sweep("tables5-7_bistable_v025", ["motion.speed=0.2:0.4:3", "motion.dead_time=0.016:0.048:3"])
    assert len(df) == 9
    assert list(df["motion.speed"][:3]) == [0.2, 0.2, 0.2]
    assert df["stroke_exhausted"].any() and not df["stroke_exhausted"].all()
    # Unsafe points are rows with safe False, never dropped.
    assert not df.loc[df["stroke_exhausted"], "safe"].any()


def test_refused_points_are_rows_and_strict_refuses():
    # 0.01 m/s never reaches the target in the scene's duration: the validator refuses that point.
    df = flinch.sweep("tables5-7_bistable", {"motion.speed": (0.01, 0.3, 3)})
    assert df["status"].iloc[0] == "refused" and df["reason"].iloc[0]
    assert (df["status"].iloc[1:] == "ok").all()
    with pytest.raises(flinch.InputError):
        flinch.sweep("tables5-7_bistable", {"motion.speed": (0.01, 0.3, 3)}, strict=True)


def test_bad_axes_raise_with_close_matches():
    with pytest.raises(flinch.InputError, match="motion.speed"):
        flinch.sweep("tables5-7_bistable", {"motion.sped": (0.1, 0.2, 2)})
    with pytest.raises(flinch.InputError):
        flinch.sweep("tables5-7_bistable", "motion.speed=0.1:0.2")
