"""The plan file: JSON, save/load, pickle, and both ways with the CLI."""
import json
import pickle
import subprocess

import numpy as np
import pytest

import triquint
from conftest import EXAMPLES


def test_json_round_trip(case1):
    text = case1.to_json()
    doc = json.loads(text)
    assert doc["format"] == "triquint-plan/3"
    assert set(doc) == {"format", "objective", "robot", "limits", "travel", "ceilings", "via_points_m", "knots_m", "intervals_s",
                        "total_time_s", "segments", "max_abs", "solver"}
    back = triquint.Plan.from_json(text)
    assert back == case1
    assert back.to_json() == text


def test_save_and_load(case2, tmp_path):
    path = tmp_path / "case2.json"
    case2.save(path)
    assert path.read_text().endswith("}\n")
    assert triquint.Plan.load(path) == case2
    assert triquint.Plan.load(str(path)) == case2
    assert [p.name for p in tmp_path.iterdir()] == ["case2.json"]  # no temporary left
    with pytest.raises(FileNotFoundError):
        triquint.Plan.load(tmp_path / "missing.json")


def test_pickle(case1):
    for proto in range(2, pickle.HIGHEST_PROTOCOL + 1):
        back = pickle.loads(pickle.dumps(case1, protocol=proto))
        assert isinstance(back, triquint.Plan)
        assert back == case1
        np.testing.assert_array_equal(back.at(1.234).q, case1.at(1.234).q)
    r = triquint.Robot(payload_mass=0.25, lead=0.012)
    assert pickle.loads(pickle.dumps(r)) == r
    assert triquint.Robot.from_dict(r.to_dict()) == r


def test_not_a_plan():
    with pytest.raises(triquint.PlanFileError) as e:
        triquint.Plan.from_json("{\"format\": 3}")
    assert e.value.kind == "json" and "line 1" in str(e.value)
    with pytest.raises(triquint.PlanFileError) as e:
        triquint.Plan.from_json("{\"format\": \"triquint-plan/9\"}")
    assert e.value.kind == "format"
    assert isinstance(e.value, ValueError)


def test_tampered_plan_is_refused(case1):
    doc = json.loads(case1.to_json())
    doc["segments"][2]["duration_s"] += 1e-4
    with pytest.raises(triquint.PlanFileError) as e:
        triquint.Plan.from_json(json.dumps(doc))
    assert e.value.kind == "invalid" and "segment 3" in str(e.value)


def test_python_plan_passes_triquint_check(case2, triquint_bin, tmp_path):
    path = tmp_path / "py.json"
    case2.save(path)
    r = subprocess.run([str(triquint_bin), "check", str(path)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    # Python's check() is the same table, all ok.
    rows = case2.check()
    assert rows and all(row["ok"] for row in rows)
    assert {"what", "value", "bound", "ok"} == set(rows[0])
    # A plan whose jerk limit is below its jerk fails both checks.
    doc = json.loads(case2.to_json())
    doc["limits"]["jerk"] = 0.5 * max(doc["max_abs"]["jerk"])
    tight = triquint.Plan.from_json(json.dumps(doc))
    bad = [row for row in tight.check() if not row["ok"]]
    assert bad and any(row["what"].startswith("max |jerk") for row in bad)
    tight.save(path)
    r = subprocess.run([str(triquint_bin), "check", str(path)], capture_output=True, text=True)
    assert r.returncode == 1, r.stdout + r.stderr


def test_cli_plan_loads_with_the_same_figures(case1, triquint_bin, tmp_path):
    out = tmp_path / "cli.json"
    r = subprocess.run([str(triquint_bin), "plan", str(EXAMPLES / "paper-case1.toml"), "-o", str(out), "--quiet"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    cli = triquint.Plan.load(out)
    assert cli.duration == case1.duration
    for key in ("velocity", "acceleration", "jerk", "torque"):
        np.testing.assert_allclose(cli.max_abs[key], case1.max_abs[key], rtol=1e-12, atol=0)
    # Same job, starts and seed: the same plan (up to the solver's timing).
    np.testing.assert_allclose(cli.segments.coeffs, case1.segments.coeffs, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(cli.segments.durations, case1.segments.durations)
    t = np.linspace(0, cli.duration, 777)
    np.testing.assert_allclose(cli.at(t).q, case1.at(t).q, rtol=0, atol=1e-15)
