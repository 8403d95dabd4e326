"""Every Python example in docs/python.md runs: each ```python block in
a fresh folder, in order, as a user would paste it."""
import pathlib
import re
import runpy

DOC = pathlib.Path(__file__).resolve().parents[3] / "docs" / "python.md"


def blocks():
    return re.findall(r"^```python\n(.*?)^```", DOC.read_text(), flags=re.S | re.M)


def test_the_page_has_examples():
    assert len(blocks()) >= 1


def test_every_example_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    for i, code in enumerate(blocks()):
        script = tmp_path / f"example{i}.py"
        script.write_text(code)
        runpy.run_path(str(script), run_name="__main__")
    out = capsys.readouterr().out
    # Three lines: the plan's figures, IK/FK, and the infeasible job's
    # binding limit (printed by the `except`, so the error was raised).
    assert len(out.strip().splitlines()) == 3, out
    # It writes the plan file it says it writes.
    assert (tmp_path / "plan.json").stat().st_size > 1000
