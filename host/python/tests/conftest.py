"""Shared fixtures: the repository's paths, the `triquint` binary, and the
two paper cases planned once per session."""
import os
import pathlib

import pytest

import triquint

ROOT = pathlib.Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples"

# Paper Case I (Table 2) and Case II (Table 6) via-points, millimetres.
CASE1 = [
    [-90, 90, 680], [-90, 90, 660], [-90, 90, 640], [-60, 60, 620], [-20, 20, 620],
    [20, -20, 620], [60, -60, 620], [90, -90, 640], [90, -90, 660], [90, -90, 680],
]
CASE2 = [
    [-86, 83.66, 597.66], [-43, 97.74, 654.74], [0, 84.85, 684.85], [43, 54.74, 697.74],
    [86, -2.34, 683.66], [86, -83.66, 602.34], [43, -97.74, 545.26], [0, -84.85, 515.15],
    [-43, -54.74, 502.26], [-86, 2.34, 516.34], [-86, 83.66, 597.66],
]


def triquint_binary() -> pathlib.Path:
    """The `triquint` CLI: $TRIQUINT_BIN (scripts/test.sh sets it), else the
    workspace's release or debug build. Missing is a failure, not a skip."""
    env = os.environ.get("TRIQUINT_BIN")
    candidates = [pathlib.Path(env)] if env else [
        ROOT / "target" / "release" / "triquint",
        ROOT / "target" / "debug" / "triquint",
    ]
    for c in candidates:
        if c.is_file() and os.access(c, os.X_OK):
            return c
    pytest.fail(
        "the triquint binary is missing (looked at "
        + ", ".join(str(c) for c in candidates)
        + "): run `cargo build --release -p triquint-host` or set TRIQUINT_BIN"
    )


@pytest.fixture(scope="session")
def triquint_bin() -> pathlib.Path:
    return triquint_binary()


@pytest.fixture(scope="session")
def case1() -> "triquint.Plan":
    return triquint.plan(triquint.Job.from_toml(EXAMPLES / "paper-case1.toml"))


@pytest.fixture(scope="session")
def case2() -> "triquint.Plan":
    return triquint.plan(triquint.Job.from_toml(EXAMPLES / "paper-case2.toml"))
