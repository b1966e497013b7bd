"""An FMU's instances (cosim.engine.fmi): fmpy reads every FMI function's signature for each
instance it makes; ours read them once per class, and every later instance's functions carry
exactly what fmpy's own reading gives them (argument names and types, result type), FMI 2.0 and
FMI 3.0, and run."""

from __future__ import annotations

import pytest
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

from cosim.engine.artifacts import fmu_path
from cosim.engine.fmi import FmuInstance


@pytest.mark.parametrize("fmi", [2, 3])
def test_later_instances_carry_fmpys_own_signatures(fmi):
    path = fmu_path("pmsm_drive", fmi=fmi)
    instances = [FmuInstance(path, f"drive{k}") for k in range(3)]
    try:
        description, folder = instances[0].model_description, instances[0].unzip_dir
        plain = (FMU3Slave if fmi == 3 else FMU2Slave)(
            guid=description.guid, unzipDirectory=str(folder), instanceName="plain",
            modelIdentifier=description.coSimulation.modelIdentifier)
        expected = {name: (f.argnames, f.argtypes, f.restype) for name, f in plain._functions.items()}
        assert len(expected) > 20
        for instance in instances[1:]:
            got = {name: (f.argnames, f.argtypes, f.restype) for name, f in instance.fmu._functions.items()}
            assert got == expected
            assert instance.fmu._functions["fmi3DoStep" if fmi == 3 else "fmi2DoStep"] is not \
                instances[0].fmu._functions["fmi3DoStep" if fmi == 3 else "fmi2DoStep"]  # each its own library's
        for instance in instances:  # and they run: initialized, a step taken, a value read
            instance.initialize()
            instance.do_step(1e-3)
            assert instance.get("current.q") == pytest.approx(instances[0].get("current.q"), abs=0.0)
    finally:
        for instance in instances:
            instance.free()
