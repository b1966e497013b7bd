"""Shared fixtures: the built FMUs (built on demand) and drive instances that are freed after use."""

from __future__ import annotations

from pathlib import Path

import pytest
from fmpy import extract

from cosim.platform.parameter_sets import load as load_parameter_set
from cosim.engine.fmi import FmuInstance
from cosim.engine.artifacts import fmu_path


@pytest.fixture(scope="session")
def pmsm_fmu() -> Path:
    return fmu_path("pmsm_drive")


@pytest.fixture(scope="session")
def pmsm_unzip_dir(pmsm_fmu, tmp_path_factory) -> Path:
    return Path(extract(str(pmsm_fmu), unzipdir=str(tmp_path_factory.mktemp("pmsm_drive"))))


@pytest.fixture(scope="session")
def meng_params() -> dict:
    return load_parameter_set("meng2010")


@pytest.fixture
def make_drive(pmsm_fmu, pmsm_unzip_dir):
    """make_drive(start_values, initialize=True) -> FmuInstance of pmsm_drive, freed after the test."""
    made = []

    def make(start_values: dict | None = None, initialize: bool = True, name: str = "leg1") -> FmuInstance:
        drive = FmuInstance(pmsm_fmu, name, unzip_dir=pmsm_unzip_dir)
        made.append(drive)
        if initialize:
            drive.initialize(start_values or {})
        return drive

    yield make
    for drive in made:
        drive.free()
