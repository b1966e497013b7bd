"""FMUs next to each other in threads (libcosim steps instances in a thread pool): six instances of
each FMU stepped on six threads give bit for bit what they give one after another, and six
trajectories reading their tables at the same moment each read their own (the table reader once
used strtok, whose hidden state the threads shared). ctypes releases the interpreter lock during
every FMI call, so the threads do run the FMUs' code at the same time."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from cosim.engine.artifacts import fmu_path
from shipped import MODELS
from cosim.engine.fmi import FmuInstance

INPUTS = {"pmsm_drive": ["angle_ref"], "linear_motor": ["position_ref"], "mechanics": ["leg[1].torque"],
          "trajectory": [], "cueing": ["specific_force.x"]}
OUTPUTS = {"pmsm_drive": ["torque", "current.q"], "linear_motor": ["force", "current"],
           "mechanics": ["pose.z", "leg[1].length"], "trajectory": ["pose_ref.x", "pose_ref.z"],
           "cueing": ["pose_ref.x", "pose_ref.pitch"]}


def run(name: str, k: int, steps: int = 200) -> np.ndarray:
    """One instance's outputs over `steps` steps, with an input that depends on k."""
    fmu = FmuInstance(fmu_path(name), f"{name}{k}")
    try:
        fmu.initialize({"x.sine[1].amplitude": 0.01 * (k + 1), "x.sine[1].frequency": 1.0} if name == "trajectory"
                       else {})
        inputs, outputs = fmu.real_group(INPUTS[name]), fmu.real_group(OUTPUTS[name])
        rows = []
        for step in range(steps):
            if INPUTS[name]:
                inputs.write([0.01 * (k + 1) * np.sin(0.01 * step)])
            fmu.do_step(1e-3)
            rows.append(outputs.read().copy())
        return np.array(rows)
    finally:
        fmu.free()


def in_threads(target, count: int = 6) -> list:
    results, failures = [None] * count, []

    def work(k: int) -> None:
        try:
            results[k] = target(k)
        except BaseException as error:  # noqa: BLE001 (reported below)
            failures.append(error)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(count)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    assert not failures, failures
    return results


@pytest.mark.parametrize("name", MODELS)
def test_six_instances_on_six_threads_equal_sequential_runs(name):
    sequential = [run(name, k) for k in range(6)]
    for _ in range(3):
        parallel = in_threads(lambda k: run(name, k))
        for k in range(6):
            assert np.array_equal(parallel[k], sequential[k]), (name, k)


def test_six_tables_read_at_once_are_each_read_right(tmp_path):
    tables = []
    for k in range(6):
        path = tmp_path / f"table{k}.csv"
        t = np.linspace(0.0, 1.0, 2001)
        rows = np.c_[t, (k + 1) * 0.001 * t, (k + 1) * 0.01 + 0 * t]
        np.savetxt(path, rows, delimiter=",", fmt="%.17g", header="time, x ,z", comments="")
        tables.append(path)

    def load(k: int) -> tuple[float, float, float]:
        fmu = FmuInstance(fmu_path("trajectory"), f"table{k}")
        try:
            fmu.initialize({"table.file": str(tables[k]), "z.offset": 0.0, "table.interpolation": 1})
            fmu.do_step(0.5)
            return fmu.get("table.rows"), fmu.get("pose_ref.x"), fmu.get("pose_ref.z")
        finally:
            fmu.free()

    for _ in range(20):
        for k, (rows, x, z) in enumerate(in_threads(load)):
            assert rows == 2001 and x == pytest.approx((k + 1) * 0.0005, rel=1e-12)
            assert z == pytest.approx((k + 1) * 0.01, rel=1e-12)
