"""Shared fixtures: the CLI binary the bindings are compared with."""

import json
import os
import subprocess
from pathlib import Path
from typing import Any, Callable

import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def whycode_bin() -> Path:
    """The `whycode` binary: $WHYCODE_BIN, else built with cargo (release)."""
    given = os.environ.get("WHYCODE_BIN")
    if given:
        return Path(given)
    subprocess.run(
        ["cargo", "build", "--release", "--quiet", "--bin", "whycode"],
        cwd=REPO,
        check=True,
    )
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    return target / "release" / "whycode"


@pytest.fixture
def cli(whycode_bin: Path, tmp_path: Path) -> Callable[..., "subprocess.CompletedProcess[str]"]:
    """Runs the CLI in the test's folder; returns the finished process."""

    def run(*args: str, ok: bool = True) -> "subprocess.CompletedProcess[str]":
        done = subprocess.run(
            [str(whycode_bin), *args], cwd=tmp_path, capture_output=True, text=True
        )
        if ok and done.returncode not in (0, 2):
            raise AssertionError(f"whycode {' '.join(args)} failed: {done.stderr}")
        return done

    return run


@pytest.fixture
def cli_json(cli: Callable[..., Any]) -> Callable[..., Any]:
    """Runs the CLI and parses each line of its output as JSON."""

    def run(*args: str) -> list[Any]:
        out = cli(*args).stdout
        try:
            return [json.loads(out)]
        except json.JSONDecodeError:
            # detect prints one object per image and line
            return [json.loads(line) for line in out.splitlines() if line.strip()]

    return run
