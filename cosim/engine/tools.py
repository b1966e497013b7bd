"""What other FMI tools do with an exported system: each tool's co-simulation master and our
engine's emulation of it, an Algorithm taken at a fixed step with no finer start. The export
measures with these the step it writes for each tool (cosim.platform.run.portable);
tests/platform/test_ssp_tools.py holds the emulations to the tools themselves (Ecos and fmpy.ssp
bit for bit, libcosim to round-off, OMSimulator, which cannot be installed here, as issue 38
measured it by hand: to 5e-12 m)."""

from __future__ import annotations

from dataclasses import dataclass

from .settings import Algorithm


@dataclass(frozen=True)
class ToolMaster:
    tool: str
    master: str            # what its master does, in words
    algorithm: Algorithm   # our engine's emulation of it
    where: str             # where the export writes the step it measured for the tool


TOOL_MASTERS = (
    ToolMaster("OMSimulator", "oms-ma: fixed step, Jacobi, inputs held, outputs that feed through read again",
               Algorithm("jacobi", 0, feedthrough=True), "the system's oms:FixedStepMaster stepSize"),
    ToolMaster("libcosim", "fixed-step algorithm: Jacobi, inputs held",
               Algorithm("jacobi", 0, initial_sweeps=0), "the OSP annotation's baseStepSize (and an OSP "
               "configuration's BaseStepSize)"),
    ToolMaster("Ecos", "fixed step: Jacobi, inputs held", Algorithm("jacobi", 0, initial_sweeps=0),
               "our annotation's cosim:ToolStep (Ecos runs at the step it is given)"),
    ToolMaster("fmpy.ssp", "fixed step: Jacobi, inputs held, every connection 0 over the first step",
               Algorithm("jacobi", 0, initial_sweeps=0, zero_start=True),
               "our annotation's cosim:ToolStep (fmpy.ssp runs at the step it is given)"),
)
