"""Shared fixtures of the Python package's tests (scripts/test.sh python runs them in .venv-python).

The CLI they compare with is POSEMFA_CLI, else target/release/posemfa (scripts/test.sh builds it); the research
data is POSEMFA_SHARED/data, else ../shared/data beside the repository. A test that needs what is absent skips
and says why, except under CI=true, where it fails (as the Rust tests do: CONTRIBUTING.md)."""

import os
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def missing(what):
    if os.environ.get("CI") == "true":
        pytest.fail(f"{what} is absent, and CI=true (scripts/setup.sh and POSEMFA_SHARED provide it in CI)")
    pytest.skip(f"SKIPPED(needs {what})")


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("POSEMFA_CLI") or os.path.join(ROOT, "target", "release", "posemfa")
    if not os.access(path, os.X_OK):
        missing(f"the posemfa CLI at {path} (cargo build --release)")
    return path


@pytest.fixture(scope="session")
def shared_data():
    base = os.environ.get("POSEMFA_SHARED") or os.path.join(os.path.dirname(ROOT), "shared")
    return os.path.join(base, "data")


@pytest.fixture(scope="session")
def quadruped(tmp_path_factory, cli):
    """A generated population written as OBJ files by the CLI (2 000 vertices, 10 poses)."""
    out = tmp_path_factory.mktemp("quadruped")
    subprocess.run([cli, "generate", "quadruped", "--vertices", "2000", "--poses", "10", "--out", str(out)],
                   check=True, capture_output=True)
    return str(out)
