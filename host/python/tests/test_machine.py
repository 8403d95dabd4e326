"""The machine file from Python: the CLI's reader, and plans held to it."""

import json

import pytest

import triquint
from conftest import EXAMPLES

ESC1 = EXAMPLES / "machines" / "b-g431b-esc1.toml"
POINTS = [[-60, 60, 620], [60, -40, 660]]


def test_the_default_machine_is_the_paper_file():
    m = triquint.Machine.from_toml(str(EXAMPLES / "machines" / "paper.toml"))
    d = triquint.Machine()
    assert m.robot == d.robot == triquint.Robot()
    assert m.travel == d.travel == {"min": [0.05] * 3, "max": [0.415] * 3}
    assert m.ceilings == d.ceilings


def test_the_esc1_machine_scales_its_encoders_from_its_counts():
    m = triquint.Machine.from_toml(str(ESC1))
    assert m.counts_per_metre == [4096 / 0.010] * 3
    assert m.ceilings["torque"] == pytest.approx(0.75)


def test_a_refused_file_names_line_key_and_range():
    with pytest.raises(triquint.InvalidJobError) as e:
        triquint.Machine.from_text("[axis.1]\ndirection = 2\n")
    assert "line 2: `axis.1.direction` = 2: must be 1 or -1" in str(e.value)
    assert e.value.field == "machine"


def test_plans_are_held_to_the_machine():
    m = triquint.Machine.from_toml(str(ESC1))
    with pytest.raises(triquint.InvalidJobError) as e:
        triquint.plan(POINTS, machine=m)  # torque 10 N·m by default
    assert e.value.field == "limits.torque"
    with pytest.raises(triquint.InvalidJobError) as e:
        triquint.plan(POINTS, machine=m, torque=0.7, robot=triquint.Robot(lead=0.012))
    assert e.value.field == "robot.lead"
    p = triquint.plan(POINTS, machine=m, torque=0.7, objective="min-time", starts=2)
    assert all(r["ok"] for r in p.check())
    assert json.loads(p.to_json())["ceilings"]["torque"] == pytest.approx(0.75)
