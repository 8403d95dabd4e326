"""examples/paper_figures.py: plans both cases and draws Figures 10 and 12
(matplotlib, which scripts/test.sh installs); without matplotlib it says so
and still plans."""
import pathlib
import subprocess
import sys

SCRIPT = pathlib.Path(__file__).resolve().parents[1] / "examples" / "paper_figures.py"


def run(args, block_matplotlib=False):
    code = "import runpy, sys\n"
    if block_matplotlib:
        code += "sys.modules['matplotlib'] = None  # import fails\n"
    code += f"sys.argv = {[str(SCRIPT)] + args!r}\nrunpy.run_path(sys.argv[0], run_name='__main__')\n"
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)


def test_draws_both_figures(tmp_path):
    r = run(["--out", str(tmp_path)])
    assert r.returncode == 0, r.stderr
    assert "max |jerk| 0.33252 m/s³" in r.stdout and "max |jerk| 1.53474 m/s³" in r.stdout, r.stdout
    for name in ("figure10_case1.png", "figure12_case2.png"):
        data = (tmp_path / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n", name
        assert len(data) > 50_000, (name, len(data))  # five panels of curves, not an empty canvas


def test_without_matplotlib_it_plans_and_says_so(tmp_path):
    r = run(["--out", str(tmp_path)], block_matplotlib=True)
    assert r.returncode == 0, r.stderr
    assert "matplotlib is not installed" in r.stderr
    assert "figure12_case2: 10 segments" in r.stdout
    assert not list(tmp_path.iterdir())
