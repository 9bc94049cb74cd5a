"""flinch.sample: the report and rows of `flinch sample`, deterministic on any thread count,
chunks that merge into the whole study, refused samples counted, a failure probability whose
answer is known lies in its interval, and the body-region limit estimated for a body region."""

import io
import json

import numpy as np
import pandas as pd
import pytest

import flinch

FOUR = {
    "motion.dead_time": "uniform:0.016:0.032",
    "decoupler.spring_rate": ("normal", 200, 10),
    "decoupler.height": ("triangular", 0.029, 0.03, 0.031),
    "motion.speed": ("lognormal", -1.3, 0.05),
}
SCENE = "tables5-7_bistable_v025"


def specs(vary):
    return flinch._sample_specs(vary)


# Dead times up to 0.7 s in a 0.6 s run: some samples end before the robot stops (inconclusive).
LATE = {"motion.dead_time": "uniform:0.05:0.7"}


@pytest.mark.parametrize("scene,vary,n", [(SCENE, FOUR, 300), ("tables5-7_bistable", LATE, 40)])
def test_the_report_and_rows_are_the_command_lines(tmp_path, cli, scene, vary, n):
    r = flinch.sample(scene, n, vary, seed=5)
    if vary is LATE:
        assert 0 < r.report["inconclusive"] < n
        late = r.rows["status"] == "inconclusive"
        assert late.sum() == r.report["inconclusive"] and r.rows["stroke_exhausted"][late].isna().all()
    args = ["sample", scene, "--samples", n, "--seed", 5, "--json", "--csv", tmp_path / "rows.csv"]
    for s in specs(vary):
        args += ["--vary", s]
    code, out, err = cli(*args)
    assert code == 0, err
    want = json.loads(out)
    assert r.report == want
    csv = pd.read_csv(tmp_path / "rows.csv", keep_default_na=False, na_values=[""])
    csv["reason"] = csv["reason"].astype(object).fillna("")
    assert list(r.rows.columns) == list(csv.columns)
    for c in csv.columns:
        if c in ("status", "reason"):
            assert list(r.rows[c].astype(str)) == list(csv[c].astype(str)), c
        else:
            got = r.rows[c].astype("float64").to_numpy(na_value=np.nan)
            np.testing.assert_array_equal(got, csv[c].astype("float64").to_numpy(), err_msg=c)


def test_the_same_on_one_thread_and_two_over_more_than_a_block():
    n = flinch.BLOCK + 77
    one = flinch.sample(SCENE, n, FOUR, seed=7, jobs=1)
    two = flinch.sample(SCENE, n, FOUR, seed=7, jobs=2)
    assert one.report == two.report
    pd.testing.assert_frame_equal(one.rows, two.rows)
    assert list(one.rows["sample"]) == list(range(n))
    other = flinch.sample(SCENE, 20, FOUR, seed=8, rows=True)
    assert not np.array_equal(other.rows["motion.dead_time_s"], one.rows["motion.dead_time_s"][:20])


def test_chunks_merge_into_the_whole_study_and_merging_refuses_other_studies():
    n = 601
    whole = flinch.sample(SCENE, n, FOUR, seed=3)
    parts = [flinch.sample(SCENE, n, FOUR, seed=3, chunk=(k, 3)) for k in (3, 1, 2)]
    assert [p.report["ranges"] for p in parts] == [[[400, 601]], [[0, 200]], [[200, 400]]]
    assert flinch.merge(parts) == whole.report
    rows = pd.concat([p.rows for p in sorted(parts, key=lambda p: p.report["ranges"][0][0])], ignore_index=True)
    pd.testing.assert_frame_equal(rows, whole.rows)
    with pytest.raises(flinch.InputError, match=r"cover 401 of the 601 samples: samples 200\.\.400 are missing"):
        flinch.merge(parts[:2])
    partial = flinch.merge(parts[:2], partial=True)
    assert partial["complete"] is False and partial["drawn"] == 401
    other = flinch.sample(SCENE, n, FOUR, seed=4, chunk=(1, 3))
    with pytest.raises(flinch.InputError, match="another study"):
        flinch.merge([parts[0], other])
    with pytest.raises(flinch.InputError, match="overlap"):
        flinch.merge([parts[1], parts[1]])


def test_refused_samples_are_counted_with_their_reason_never_dropped():
    # A dead time of mean 2 ms and sd 2 ms: about 16 % of draws are below 0, which the validator refuses.
    with pytest.warns(flinch.RefusalWarning, match="outside the accepted range"):
        r = flinch.sample(SCENE, 500, {"motion.dead_time": "normal:0.002:0.002"}, seed=1)
    refused = r.rows[r.rows["status"] == "refused"]
    assert len(r.rows) == 500
    assert r.report["refused"] == len(refused) > 40
    assert (refused["motion.dead_time_s"] < 0).all()
    assert refused["reason"].str.contains("motion.dead_time").all()
    assert refused["stroke_exhausted"].isna().all() and refused["peak_robot_force_n"].isna().all()
    assert r.report["refusals"][0]["keys"] == ["motion.dead_time"]
    # A failure's runs: the samples that ran, less the inconclusive ones it was not seen in.
    for e in r.report["estimates"]:
        assert 500 - len(refused) - r.report["inconclusive"] <= e["runs"] <= 500 - len(refused)
        assert e["high_if_unrun_failed"] >= e["high"]
    e = r.estimates.loc["stroke_exhausted"]
    assert e["high_if_unrun_failed"] > e["high"]
    # Truncated to the accepted range instead: nothing refused, and the kept probability stated.
    t = flinch.sample(SCENE, 200, {"motion.dead_time": "normal:0.002:0.002"}, seed=1, truncate=True)
    assert t.report["refused"] == 0 and 0.8 < t.report["vary"][0]["kept_probability"] < 0.9


def test_every_sample_refused_raises_with_the_result():
    # 99.9 % of the draws are below 0 s: each of these 20 is (a distribution entirely outside is
    # refused before running instead).
    with pytest.raises(flinch.InputError, match="refused all 20 samples") as e, pytest.warns(flinch.RefusalWarning):
        flinch.sample(SCENE, 20, {"motion.dead_time": "normal:-0.006:0.002"})
    assert e.value.result.report["refused"] == 20
    with pytest.raises(flinch.InputError, match="every sample would be refused"):
        flinch.sample(SCENE, 20, {"motion.dead_time": "uniform:-0.01:-0.001"})


def test_a_probability_known_by_construction_lies_in_its_interval_and_each_sample_fails_when_it_should():
    # Tables 5-7 at 0.28 m/s: the stroke runs out when the dead time exceeds a threshold DT*.
    # Bisect DT* with single runs, then sample DT uniformly on [16, 40] ms.
    sc = flinch.scene(SCENE)
    sc["motion"]["speed"] = 0.28

    def exhausted(dt):
        sc["motion"]["dead_time"] = dt
        return flinch.run(sc)["stroke_exhausted"]

    lo, hi = 0.016, 0.040
    assert not exhausted(lo) and exhausted(hi)
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if exhausted(mid) else (mid, hi)
    p_true = (0.040 - hi) / 0.024
    sc["motion"]["dead_time"] = 0.02
    r = flinch.sample(sc, 1000, {"motion.dead_time": "uniform:0.016:0.040"}, seed=11)
    e = r.estimates.loc["stroke_exhausted"]
    assert e["low"] <= p_true <= e["high"], (p_true, e)
    dt = r.rows["motion.dead_time_s"]
    fails = r.rows["stroke_exhausted"].astype(bool)
    assert (fails == (dt > hi)).all() or ((fails != (dt > hi)) & ((dt - hi).abs() > 1e-6)).sum() == 0
    assert e["failures"] == fails.sum() and e["runs"] == 1000


def test_the_body_region_limit_is_estimated_for_a_body_region_only():
    r = flinch.sample("body_hand", 300, {"motion.speed": ("uniform", 0.1, 0.6)}, seed=2)
    est = r.estimates
    assert "body_limit_exceeded" in est.index
    # <NA> where a run ended before the robot stopped without the limit exceeded yet (unknown).
    over = (r.rows["body_limits_pass"] == False).fillna(False).astype(bool)  # noqa: E712
    exceeded = int(over.sum())
    assert 0 < exceeded < 300
    assert est.loc["body_limit_exceeded", "failures"] == exceeded
    e = est.loc["body_limit_exceeded"]
    assert e["runs"] == 300 - int(r.rows["body_limits_pass"].isna().sum())
    assert e["low"] < exceeded / e["runs"] < e["high"]
    # A body limit exceeded makes the run not safe (docs/verdicts.md).
    assert (~r.rows.loc[over, "safe"].astype(bool)).all()
    # Not a body region: not estimated (0 of N would read as evidence), no column.
    plain = flinch.sample(SCENE, 10, FOUR)
    assert "body_limit_exceeded" not in plain.estimates.index
    assert "body_limits_pass" not in plain.rows.columns
    # Chunks of a body-region study merge with the body estimate.
    parts = [flinch.sample("body_hand", 300, {"motion.speed": ("uniform", 0.1, 0.6)}, seed=2, chunk=(k, 2), rows=False) for k in (1, 2)]
    assert flinch.merge(parts) == r.report


def test_the_csv_of_a_body_region_study_has_the_column(tmp_path, cli):
    code, out, err = cli("sample", "body_hand", "--samples", 20, "--vary", "motion.speed=uniform:0.1:0.6", "--csv", "-")
    assert code == 0, err
    csv = pd.read_csv(io.StringIO(out))
    assert list(csv.columns) == list(flinch.sample("body_hand", 20, {"motion.speed": "uniform:0.1:0.6"}).rows.columns)
    assert "body_limits_pass" in csv.columns


def test_bad_input_raises_before_running():
    with pytest.raises(flinch.InputError, match="unknown distribution"):
        flinch.sample(SCENE, 10, {"motion.speed": "gauss:1:2"})
    with pytest.raises(flinch.InputError, match="motion.speed"):
        flinch.sample(SCENE, 10, {"motion.sped": "normal:0.25:0.01"})
    with pytest.raises(flinch.InputError, match="nothing to vary"):
        flinch.sample(SCENE, 10, {})
    with pytest.raises(flinch.InputError):
        flinch.sample(SCENE, 0, FOUR)
    with pytest.raises(flinch.InputError):
        flinch.sample(SCENE, 10, FOUR, chunk=(3, 2))
    with pytest.raises(flinch.SceneError):
        flinch.sample({"name": "x"}, 10, FOUR)


def test_without_rows_only_the_report_and_str_is_the_human_summary():
    r = flinch.sample(SCENE, 100, FOUR, rows=False)
    assert r.rows is None
    text = str(r)
    assert "probability (95 % interval, over the 100 runs)" in text and "stroke_exhausted" in text
