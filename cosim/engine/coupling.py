"""The wiring of a system resolved onto its live instances: per instance one group of coupled
outputs and one of inputs (one FMI call each per macro step), each input's source and index, the
power bonds as indices, and which instances take input derivatives or give output derivatives.

Both the step kernel (cosim/engine/kernel.py) and the tests' Python oracle read this resolution.
"""

from __future__ import annotations

import graphlib
from typing import Mapping, Sequence

import numpy as np

from .fmi import FmuInstance
from .settings import SettingsError
from .structure import Bond, Connection


class FeedthroughLoop(SettingsError):
    """Outputs that feed through to each other at the same communication point (an algebraic loop)."""

    def __init__(self, message: str):
        super().__init__(message, "feedthrough")


class Coupling:
    """Instances and their connections, resolved into one output group and one input group per
    instance, so that each macro step makes one get and one set call per instance."""

    def __init__(self, instances: Mapping[str, FmuInstance], connections: Sequence[Connection],
                 bonds: Sequence[Bond] = (), interpolating: Mapping[str, bool] | None = None):
        """interpolating: per instance, whether it takes input derivatives (default: what its
        modelDescription declares, canInterpolateInputs)."""
        self.instances = dict(instances)
        self.names = list(self.instances)
        for c in connections:
            for name, variable in (c.source, c.target):
                if name not in self.instances:
                    raise KeyError(f"connection {c.source} -> {c.target}: no instance '{name}'")
                self.instances[name].vr(variable)  # raises with the instance and variable named
        self.sources = {n: sorted({c.source[1] for c in connections if c.source[0] == n}) for n in self.names}
        self.outputs = {n: self.instances[n].real_group(v) for n, v in self.sources.items() if v}
        targets = {n: [c for c in connections if c.target[0] == n] for n in self.names}
        self.inputs = {n: self.instances[n].real_group([c.target[1] for c in cs]) for n, cs in targets.items() if cs}
        self.input_names = {n: [c.target[1] for c in cs] for n, cs in targets.items() if cs}
        # for each target instance: (source instance, index in the source's output group) per input
        self.feeds = {n: [(c.source[0], self.sources[c.source[0]].index(c.source[1])) for c in cs]
                      for n, cs in targets.items() if cs}
        # each bond as (source, index) and (target, index) of its effort and of its flow
        def ends(c: Connection):
            return ((c.source[0], self.sources[c.source[0]].index(c.source[1])),
                    (c.target[0], self.input_names[c.target[0]].index(c.target[1])))
        for bond in bonds:
            if any(c is not None and c not in connections for c in (bond.effort, bond.flow, bond.slope)):
                raise KeyError(f"bond {bond}: its connections must be among the coupling's connections")
        self.bonds = [(ends(b.effort), ends(b.flow)) for b in bonds]
        # per bond, (target, index) of the input that takes the effort's slope, or None
        self.bond_slopes = [ends(b.slope)[1] if b.slope is not None else None for b in bonds]
        self.interpolating = {n: (interpolating or {}).get(n, self.instances[n].can_interpolate_inputs)
                              for n in self.names}
        # those that take no derivatives but extrapolate held inputs themselves: given their values at
        # t, not at the step's midpoint (which they would extrapolate from again)
        self.extrapolating = {n: not self.interpolating[n] and self.instances[n].extrapolates_inputs
                              for n in self.names}
        # sources that give their outputs' derivatives (fmi2GetRealOutputDerivatives), with the order
        self.rate_orders = {n: min(2, self.instances[n].max_output_derivative_order) for n in self.outputs
                            if self.instances[n].max_output_derivative_order > 0}

    def feedthrough(self) -> list[tuple[str, list[int], list[int]]]:
        """Direct feed-through among the coupled outputs, as steps in dependency order: (instance,
        the indices of its inputs to set, the indices of its coupled outputs to read again). An
        output feeds through when its FMU's ModelStructure lists connected inputs among its
        dependencies (no dependencies attribute: every input, as FMI 2.0 says). Raises
        FeedthroughLoop naming the outputs of a loop of such paths (an algebraic loop)."""
        depends: dict[tuple[str, str], list[int]] = {}
        for name, outputs in self.sources.items():
            inputs = self.input_names.get(name, [])
            if not outputs or not inputs:
                continue
            declared = {u.variable.name: u.dependencies for u in self.instances[name].model_description.outputs}
            for output in outputs:
                given = declared.get(output)
                names = set(inputs) if given is None else {v.name for v in given}
                indices = [i for i, n in enumerate(inputs) if n in names]
                if indices:
                    depends[(name, output)] = indices
        # an output waits for the feed-through outputs that feed the inputs it depends on
        waits = {node: {(source, self.sources[source][index]) for source, index in
                        (self.feeds[node[0]][i] for i in depends[node])} & set(depends) for node in depends}
        try:
            order = list(graphlib.TopologicalSorter(waits).static_order())
        except graphlib.CycleError as error:
            loop = sorted(f"{n}.{o}" for n, o in set(error.args[1]))
            raise FeedthroughLoop(f"an algebraic loop: the outputs {', '.join(loop)} depend on each other's values at "
                                  "the same communication point (their FMUs' declared dependencies); switch "
                                  "feedthrough off, or break the loop") from None
        steps: list[tuple[str, list[int], list[int]]] = []
        for name, output in order:
            index = self.sources[name].index(output)
            if steps and steps[-1][0] == name:
                steps[-1][1].extend(i for i in depends[(name, output)] if i not in steps[-1][1])
                steps[-1][2].append(index)
            else:
                steps.append((name, list(depends[(name, output)]), [index]))
        return steps

    def read(self) -> dict[str, np.ndarray]:
        return {n: group.read().copy() for n, group in self.outputs.items()}

    def read_rates(self, names=None) -> dict[str, list[np.ndarray]]:
        """The output derivatives (orders 1.., as far as provided) of the rate-giving sources."""
        return {n: [self.outputs[n].read_derivatives(k) for k in range(1, self.rate_orders[n] + 1)]
                for n in (self.rate_orders if names is None else names) if n in self.rate_orders}

    def bond_names(self) -> list[str]:
        """'source.effort -> target.input' for each bond."""
        names = []
        for (effort_out, effort_in), _ in self.bonds:
            source, target = effort_out[0], effort_in[0]
            names.append(f"{source}.{self.sources[source][effort_out[1]]} -> "
                         f"{target}.{self.input_names[target][effort_in[1]]}")
        return names
