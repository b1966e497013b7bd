"""Every FMU's outputs declare what they depend on (the modelDescription's ModelStructure, written
from each variables.h's MODEL_FEEDTHROUGH), and the declaration is the truth: perturbing one input
at a communication point, without a step, moves exactly the outputs that declare it. Measured in a
generic state (every input away from its default, 20 steps taken; the reference's derivatives
given, and not given, when the mechanics' pose_ref_rate inputs stand in) under each configuration that switches a path on (control modes, inverter models,
effects); the union over them equals the declaration, and no configuration moves an output that
does not declare the input. Tools such as OMSimulator read these dependencies to order the
outputs along the connections and to find the algebraic loops (without them, every output is
taken to depend on every input)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from cosim.engine.artifacts import fmu_path
from cosim.engine.fmi import FmuInstance
from cosim.platform.ports import POSE

CONFIGURATIONS = {
    "pmsm_drive": [{"control.mode": m, "inverter.model": i} for m in (1, 2, 3) for i in (1, 2, 3)],
    "linear_motor": [{"control.mode": m, "effects.electrical": e, "effects.friction": f, "effects.ripple": r,
                      "control.velocity_ref_input": u} for m in (1, 2, 3) for e in (True, False)
                     for f in (True, False) for r in (True, False) for u in (True, False)],
    "mechanics": [{}, {"effects.friction": False, "effects.motor_inertia": False, "effects.actuator_inertia": False}],
    "trajectory": [{}],
    "cueing": [{}, {"translation.x.break": 0.0, "tilt.gain": 0.0}],
    "oscillator_mass": [{}],
    "oscillator_coupling": [{}],
}
RATES = {"mechanics": [f"pose_ref.{a}" for a in POSE]}  # inputs given with their derivatives


def path_of(name: str) -> Path:
    return fmu_path(name, test=name.startswith("oscillator"))


def declared(path: Path) -> dict[str, set[str]]:
    """Output -> the inputs its ModelStructure entry declares."""
    md = read_model_description(str(path))
    return {unknown.variable.name: {v.name for v in unknown.dependencies} for unknown in md.outputs}


def measured(path: Path, name: str, start: dict, rates: list[str]) -> dict[str, set[str]]:
    """Output -> the inputs whose perturbation moves it at the same communication point."""
    fmu = FmuInstance(path, name)
    try:
        inputs = [n for n, v in fmu.variables.items() if v.causality == "input" and v.type == "Real"]
        outputs = [n for n, v in fmu.variables.items() if v.causality == "output" and v.type == "Real"]
        rng = np.random.default_rng(1)
        fmu.initialize(start)
        base = {}
        for n in inputs:
            x = float(fmu.variables[n].start or 0.0)
            base[n] = x + (0.01 if x == 0 else 0.01 * abs(x)) * rng.uniform(0.5, 1.5) * rng.choice([-1, 1])

        def put(values):
            fmu.set(values)
            if rates:
                fmu.set_input_derivatives(rates, [0.05 * (k + 1) for k in range(len(rates))])

        put(base)
        for _ in range(20):
            fmu.do_step(1e-3)
            put(base)
        before = {o: fmu.get(o) for o in outputs}
        found: dict[str, set[str]] = {o: set() for o in outputs}
        for n in inputs:
            put({n: base[n] * 1.01 + 1e-3})
            for o in outputs:
                if fmu.get(o) != before[o]:
                    found[o].add(n)
            put({n: base[n]})
            assert all(fmu.get(o) == before[o] for o in outputs), f"{n} put back does not restore the outputs"
        return found
    finally:
        fmu.free()


@pytest.mark.parametrize("name", list(CONFIGURATIONS))
def test_declared_dependencies_are_what_moves(name):
    path = path_of(name)
    declaration = declared(path)
    union: dict[str, set[str]] = {o: set() for o in declaration}
    for start in CONFIGURATIONS[name]:
        for rates in {(), tuple(RATES.get(name, ()))}:
            for output, inputs in measured(path, name, start, list(rates)).items():
                assert inputs <= declaration[output], (start, rates, output, inputs - declaration[output])
                union[output] |= inputs
    assert union == declaration
    if name not in ("trajectory", "cueing", "oscillator_mass"):  # no feed-through there; the others declare some
        assert any(declaration.values())


@pytest.mark.parametrize("name", list(CONFIGURATIONS))
def test_the_declarations_pass_fmpys_validation(name):
    assert validate_fmu(str(path_of(name))) == []
