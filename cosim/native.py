"""The native inner loop (cosim/native/loop.c): fixed macro steps of a coupling algorithm with the
interpreter off the hot path. Python keeps the algorithm's definition (cosim.coupling) and its
state; a NativeLoop hands that state to C, runs a batch of steps, and takes it back, so a run may
mix Python and native steps and gets the same numbers either way (tests/test_native.py).
"""

from __future__ import annotations

import ctypes
from typing import Sequence

import numpy as np

from .coupling import Coupling, CouplingAlgorithm, GaussSeidel
from .fmu_instance import FmuError
from .fmus import native_library_path

_CALLS = {1: "fmi2SetReal", 2: "fmi2SetRealInputDerivatives", 3: "fmi2DoStep", 4: "fmi2GetReal",
          5: "fmi2GetRealOutputDerivatives", 6: "fmi2GetFMUstate", 7: "fmi2SetFMUstate", 8: "fmi2FreeFMUstate"}

_P = ctypes.c_void_p
_INTS, _UINTS, _DOUBLES = ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_uint), ctypes.POINTER(ctypes.c_double)


class _Instance(ctypes.Structure):
    _fields_ = [("component", _P), ("set_real", _P), ("get_real", _P), ("set_input_derivatives", _P),
                ("get_output_derivatives", _P), ("do_step", _P), ("get_state", _P), ("set_state", _P),
                ("free_state", _P),
                ("n_outputs", ctypes.c_int), ("output_offset", ctypes.c_int), ("output_vrs", _UINTS),
                ("n_inputs", ctypes.c_int), ("input_offset", ctypes.c_int), ("input_vrs", _UINTS),
                ("feed_source", _INTS), ("feed_index", _INTS), ("rate_order", ctypes.c_int),
                ("n_record", ctypes.c_int), ("record_offset", ctypes.c_int), ("record_vrs", _UINTS)]


class _Setup(ctypes.Structure):
    _fields_ = [("n_instances", ctypes.c_int), ("instances", ctypes.POINTER(_Instance)), ("sequence", _INTS),
                ("gauss_seidel", ctypes.c_int), ("order", ctypes.c_int), ("keep", ctypes.c_int),
                ("n_samples", ctypes.c_int), ("sample_time", _DOUBLES), ("samples", _DOUBLES),
                ("n_sample_values", ctypes.c_int), ("exact_rates", _DOUBLES), ("new_values", _DOUBLES),
                ("stepped", _INTS), ("input_values", _DOUBLES), ("input_rates", _DOUBLES),
                ("input_curvatures", _DOUBLES), ("n_bonds", ctypes.c_int), ("bonds", _INTS),
                ("n_columns", ctypes.c_int), ("column_of", _INTS), ("record_scratch", _DOUBLES),
                ("instance_time", _DOUBLES), ("fmi_seconds", _DOUBLES), ("order_one", _INTS), ("order_two", _INTS),
                ("failed_instance", ctypes.c_int), ("failed_call", ctypes.c_int)]


class _Adaptive(ctypes.Structure):
    _fields_ = [("h", ctypes.c_double), ("h_min", ctypes.c_double), ("h_max", ctypes.c_double),
                ("rtol", ctypes.c_double), ("atol", _DOUBLES), ("t", ctypes.c_double), ("rejected", ctypes.c_int),
                ("states", ctypes.POINTER(ctypes.c_void_p)), ("saved_time", _DOUBLES), ("saved_samples", _DOUBLES),
                ("saved_rates", _DOUBLES), ("saved_inputs", _DOUBLES), ("saved_instance_time", _DOUBLES),
                ("full", _DOUBLES)]


_library = None


def _load() -> ctypes.CDLL:
    global _library
    if _library is None:
        _library = ctypes.CDLL(str(native_library_path()))
        _library.cosim_loop_run.argtypes = [ctypes.POINTER(_Setup), ctypes.c_int, ctypes.c_double, ctypes.c_int,
                                            _DOUBLES, _DOUBLES, _DOUBLES]
        _library.cosim_loop_run.restype = ctypes.c_int
        _library.cosim_loop_adaptive.argtypes = [ctypes.POINTER(_Setup), ctypes.POINTER(_Adaptive), ctypes.c_int,
                                                 ctypes.c_double, ctypes.c_int, ctypes.c_int, _DOUBLES, _DOUBLES,
                                                 _DOUBLES]
        _library.cosim_loop_adaptive.restype = ctypes.c_int
    return _library


def _ints(values) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.intc)


def _ptr(array: np.ndarray, kind):
    return array.ctypes.data_as(kind)


def _failure_messages(messages: list) -> list:
    """The messages of the failed call among those logged during a batch: its errors (the warnings
    of earlier steps in the batch are not part of the failure), or all if none is an error."""
    errors = [m for m in messages if m.status in ("error", "fatal")]
    return errors or messages


class NativeLoop:
    """Runs `algorithm` (Jacobi or GaussSeidel) on `coupling` in C, recording `columns` (instance,
    variable) after every step next to the time of instance `clock`."""

    def __init__(self, coupling: Coupling, algorithm: CouplingAlgorithm, columns: Sequence[tuple[str, str]],
                 clock: str):
        self.coupling, self.algorithm = coupling, algorithm
        self.library = _load()
        names = coupling.names
        self.index = {n: k for k, n in enumerate(names)}
        self.clock = self.index[clock]
        keep = []  # arrays the C side points into
        instances = (_Instance * len(names))()
        self.output_offset, offset, input_offset, record_offset = {}, 0, 0, 0
        self.input_offset = {}
        record_names = {n: [] for n in names}
        for instance_name, variable in columns:
            if variable not in record_names[instance_name]:
                record_names[instance_name].append(variable)
        self.column_of = []
        record_start = {}
        for k, n in enumerate(names):
            fmu = coupling.instances[n]
            c = instances[k]
            c.component = fmu.fmu.component
            for field, function in (("set_real", "fmi2SetReal"), ("get_real", "fmi2GetReal"),
                                    ("set_input_derivatives", "fmi2SetRealInputDerivatives"),
                                    ("get_output_derivatives", "fmi2GetRealOutputDerivatives"), ("do_step", "fmi2DoStep"),
                                    ("get_state", "fmi2GetFMUstate"), ("set_state", "fmi2SetFMUstate"),
                                    ("free_state", "fmi2FreeFMUstate")):
                setattr(c, field, ctypes.cast(getattr(fmu.fmu.dll, function), _P).value)
            outputs = coupling.sources[n]
            vrs = _ints([fmu.vr(v) for v in outputs]).astype(np.uintc)
            keep.append(vrs)
            c.n_outputs, c.output_offset, c.output_vrs = len(outputs), offset, _ptr(vrs, _UINTS)
            self.output_offset[n] = offset
            offset += len(outputs)
            inputs = coupling.input_names.get(n, [])
            in_vrs = _ints([fmu.vr(v) for v in inputs]).astype(np.uintc)
            sources = _ints([self.index[s] for s, _ in coupling.feeds.get(n, [])])
            indices = _ints([i for _, i in coupling.feeds.get(n, [])])
            keep += [in_vrs, sources, indices]
            c.n_inputs, c.input_offset, c.input_vrs = len(inputs), input_offset, _ptr(in_vrs, _UINTS)
            c.feed_source, c.feed_index = _ptr(sources, _INTS), _ptr(indices, _INTS)
            self.input_offset[n] = input_offset
            input_offset += len(inputs)
            c.rate_order = coupling.rate_orders.get(n, 0)
            rec = _ints([fmu.vr(v) for v in record_names[n]]).astype(np.uintc)
            keep.append(rec)
            c.n_record, c.record_offset, c.record_vrs = len(rec), record_offset, _ptr(rec, _UINTS)
            record_start[n] = record_offset
            record_offset += len(rec)
        self.column_of = _ints([record_start[n] + record_names[n].index(v) for n, v in columns])
        self.n_values, self.n_inputs = offset, input_offset
        sequence = algorithm.sequence if isinstance(algorithm, GaussSeidel) and algorithm.sequence else names
        self.sequence = _ints([self.index[n] for n in sequence])
        bonds = [x for (eo, ei), (fo, fi) in coupling.bonds
                 for x in (self.index[eo[0]], eo[1], self.index[ei[0]], ei[1],
                           self.index[fo[0]], fo[1], self.index[fi[0]], fi[1])]
        self.bonds = _ints(bonds or [0])
        n_max = max([offset, input_offset, 1])
        self.sample_time, self.samples = np.zeros(3), np.zeros((3, max(offset, 1)))
        self.exact_rates, self.new_values = np.zeros((2, max(offset, 1))), np.zeros(max(offset, 1))
        self.stepped = _ints(np.zeros(len(names)))
        self.inputs = np.zeros((3, max(input_offset, 1)))
        self.record_scratch = np.zeros(max(record_offset, 1))
        self.instance_time, self.fmi_seconds = np.zeros(len(names)), np.zeros(len(names))
        self.order_one, self.order_two = _ints(np.ones(n_max)), _ints(np.full(n_max, 2))
        self._keep, self._instances = keep, instances
        s = self.setup = _Setup()
        s.n_instances, s.instances, s.sequence = len(names), instances, _ptr(self.sequence, _INTS)
        s.gauss_seidel, s.order = int(isinstance(algorithm, GaussSeidel)), algorithm.order
        s.keep = algorithm.history.samples.maxlen
        s.sample_time, s.samples, s.n_sample_values = _ptr(self.sample_time, _DOUBLES), _ptr(self.samples, _DOUBLES), offset
        s.exact_rates, s.new_values = _ptr(self.exact_rates, _DOUBLES), _ptr(self.new_values, _DOUBLES)
        s.stepped = _ptr(self.stepped, _INTS)
        s.input_values, s.input_rates, s.input_curvatures = (_ptr(self.inputs[i], _DOUBLES) for i in range(3))
        s.n_bonds, s.bonds = len(coupling.bonds), _ptr(self.bonds, _INTS)
        s.n_columns, s.column_of = len(columns), _ptr(self.column_of, _INTS)
        s.record_scratch = _ptr(self.record_scratch, _DOUBLES)
        s.instance_time, s.fmi_seconds = _ptr(self.instance_time, _DOUBLES), _ptr(self.fmi_seconds, _DOUBLES)
        s.order_one, s.order_two = _ptr(self.order_one, _INTS), _ptr(self.order_two, _INTS)
        self.n_columns = len(columns)

    def _to_native(self) -> None:
        history = self.algorithm.history.samples
        if not 1 <= len(history) <= 3:
            raise RuntimeError("the native loop needs an initialized algorithm")
        for j, (t, outputs, _) in enumerate(history):
            self.sample_time[j] = t
            for n, offset in self.output_offset.items():
                self.samples[j, offset:offset + len(self.coupling.sources[n])] = outputs.get(n, [])
        self.setup.n_samples = len(history)
        for n, derivatives in history[-1][2].items():
            offset = self.output_offset[n]
            for order, values in enumerate(derivatives):
                self.exact_rates[order, offset:offset + len(values)] = values
        for n, (values, rates, curvatures) in self.algorithm.inputs_set.items():
            offset = self.input_offset[n]
            for i, part in enumerate((values, rates, curvatures)):
                self.inputs[i, offset:offset + len(part)] = part
        for n, k in self.index.items():
            self.instance_time[k] = self.coupling.instances[n].time
        self.fmi_seconds[:] = 0.0

    def _from_native(self, steps: int, residuals: np.ndarray, count: int | None = None) -> None:
        """Takes the history, inputs, times and FMI time back; `count` residuals (default: steps)."""
        history = self.algorithm.history
        for j in range(self.setup.n_samples if steps else 0):
            outputs = {n: self.samples[j, o:o + len(self.coupling.sources[n])].copy()
                       for n, o in self.output_offset.items() if self.coupling.sources[n]}
            rates = {n: [self.exact_rates[order, self.output_offset[n]:self.output_offset[n] + len(outputs[n])].copy()
                         for order in range(r)] for n, r in self.coupling.rate_orders.items()}
            if j == 0:
                history.samples.clear()
            history.samples.append((float(self.sample_time[j]), outputs, rates))
        if steps:
            for n in self.coupling.inputs:
                o, m = self.input_offset[n], len(self.coupling.input_names[n])
                self.algorithm.inputs_set[n] = tuple(self.inputs[i, o:o + m].copy() for i in range(3))
        for n, k in self.index.items():
            instance = self.coupling.instances[n]
            instance.time = float(self.instance_time[k])
            instance.fmi_seconds += float(self.fmi_seconds[k])
        if self.coupling.bonds:
            self.algorithm.energy_residuals.extend(residuals[:steps if count is None else count].tolist())

    def run(self, h: float, n_steps: int, rows: np.ndarray) -> None:
        """n_steps macro steps of h; rows (n_steps x (1 + columns), C order) receives the time and
        the recorded columns after each, self.bond_energy (steps x bonds x (residual, transferred))
        the bonds' energies. Raises FmuError naming the instance and call that failed; the rows of
        the steps completed (self.completed) are filled."""
        assert rows.shape == (n_steps, 1 + self.n_columns) and rows.flags.c_contiguous
        residuals = np.zeros(max(n_steps, 1))
        self.bond_energy = np.zeros((max(n_steps, 1), max(len(self.coupling.bonds), 1), 2))
        self._to_native()
        logged = {n: len(i.messages) for n, i in self.coupling.instances.items()}
        done = self.library.cosim_loop_run(ctypes.byref(self.setup), self.clock, h, n_steps, _ptr(rows, _DOUBLES),
                                           _ptr(residuals, _DOUBLES), _ptr(self.bond_energy, _DOUBLES))
        self._from_native(done, residuals)
        self.completed = done
        if done < n_steps:
            name = self.coupling.names[self.setup.failed_instance]
            instance = self.coupling.instances[name]
            raise FmuError(name, _CALLS.get(self.setup.failed_call, "?"), instance.time,
                           _failure_messages(instance.messages[logged[name]:]))

    def run_adaptive(self, control, t: float, t_end: float, record) -> float:
        """cosim.coupling.AdaptiveStep's step doubling from t to t_end in C, with the same numbers;
        record(rows) receives the accepted rows (time and columns) batch by batch. Updates control's
        h, accepted and rejected, and the algorithm's energy residuals. Returns the time reached."""
        n, names = self.n_values, self.coupling.names
        atol = np.full(max(n, 1), np.inf)
        scales = control.atol if isinstance(control.atol, dict) else dict.fromkeys(self.output_offset, control.atol)
        for name, value in scales.items():
            offset = self.output_offset[name]
            atol[offset:offset + len(self.coupling.sources[name])] = value
        a = _Adaptive()
        a.h, a.h_min, a.h_max, a.rtol, a.t, a.rejected = control.h, control.h_min, control.h_max, control.rtol, t, 0
        scratch = dict(states=(ctypes.c_void_p * len(names))(), saved_time=np.zeros(3),
                       saved_samples=np.zeros(3 * max(n, 1)), saved_rates=np.zeros(2 * max(n, 1)),
                       saved_inputs=np.zeros(3 * max(self.n_inputs, 1)), saved_instance_time=np.zeros(len(names)),
                       full=np.zeros(max(n, 1)))
        a.atol = _ptr(atol, _DOUBLES)
        a.states = scratch["states"]
        for field in ("saved_time", "saved_samples", "saved_rates", "saved_inputs", "saved_instance_time", "full"):
            setattr(a, field, _ptr(scratch[field], _DOUBLES))
        capacity = 200
        rows = np.zeros((capacity, 1 + self.n_columns))
        accepted, residuals = np.zeros(capacity), np.zeros(2 * capacity)
        while t_end - a.t > 1e-12 * max(1.0, abs(t_end)):
            self._to_native()
            logged = {name: len(i.messages) for name, i in self.coupling.instances.items()}
            done = self.library.cosim_loop_adaptive(ctypes.byref(self.setup), ctypes.byref(a), self.clock, t_end,
                                                    capacity, self.n_inputs, _ptr(rows, _DOUBLES),
                                                    _ptr(accepted, _DOUBLES), _ptr(residuals, _DOUBLES))
            failed = done < 0
            written = -1 - done if failed else done
            self._from_native(written, residuals, count=2 * written)
            control.accepted.extend(accepted[:written].tolist())
            control.rejected += a.rejected
            a.rejected = 0
            control.h = a.h
            record(rows[:written])
            if failed:
                name = names[self.setup.failed_instance]
                instance = self.coupling.instances[name]
                raise FmuError(name, _CALLS.get(self.setup.failed_call, "?"), instance.time,
                               _failure_messages(instance.messages[logged[name]:]))
        return a.t
