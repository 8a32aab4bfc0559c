"""Shared fixtures: the `dsc-seg` command line the package is compared with."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def _find_cli():
    """DSC_SEG_BIN, else the repository's release or debug build, else PATH."""
    given = os.environ.get("DSC_SEG_BIN")
    if given:
        return given
    for build in ("release", "debug"):
        path = REPO / "target" / build / "dsc-seg"
        if path.is_file():
            return str(path)
    return shutil.which("dsc-seg")


@pytest.fixture(scope="session")
def cli():
    """Runs `dsc-seg ARGS...`, failing the test on a non-zero exit."""
    path = _find_cli()
    if path is None:
        pytest.skip("no dsc-seg binary: build it (cargo build --release) or set DSC_SEG_BIN")

    def run(*args):
        done = subprocess.run([path, *map(str, args)], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        return done

    return run
