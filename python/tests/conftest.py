"""Shared fixtures of the Python package's tests: where the data and the
command-line binary are (the Rust harness, crates/locus-py/tests/python.rs,
sets LOCUS_BIN to the binary `cargo test --workspace` built)."""

import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SHARED = pathlib.Path(os.environ.get("LOCUS_SHARED", ROOT.parent / "shared"))


def shared_data(*parts: str) -> pathlib.Path:
    """A file or directory of ../shared/data, which must be there."""
    path = SHARED.joinpath("data", *parts)
    assert path.exists(), f"{path} is missing (the shared data beside the repository)"
    return path


@pytest.fixture(scope="session")
def mrclam6() -> pathlib.Path:
    return shared_data("mrclam", "MRCLAM_Dataset6")


@pytest.fixture(scope="session")
def locus_bin() -> pathlib.Path:
    path = pathlib.Path(os.environ.get("LOCUS_BIN", ROOT / "target" / "release" / "locus"))
    assert path.is_file(), f"{path} is missing: build it (cargo test --workspace builds it) or set LOCUS_BIN"
    return path


@pytest.fixture(scope="session")
def laser_wall() -> pathlib.Path:
    return shared_data("laser_wall_1d", "dataset1.txt")


@pytest.fixture(scope="session")
def intel_lab() -> pathlib.Path:
    return shared_data("intel_lab")
