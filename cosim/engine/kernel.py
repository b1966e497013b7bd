"""The step kernel (cosim/engine/kernel/kernel.c) seen from Python: hands it a resolved `Coupling`
(function pointers of each FMU, value references, wiring as indices, numpy buffers for the
history and inputs) and runs its loops. All state of a run (history, inputs as set, times) lives
in these buffers, so the kernel is the only code that advances a system.
"""

from __future__ import annotations

import ctypes
from typing import Mapping, Sequence

import numpy as np

from .artifacts import library_path
from .coupling import Coupling
from .fmi import FmuError, LogMessage
from .native import check_layout
from .settings import Algorithm, EnergyControl, StepDoubling

_CALLS = {1: "fmi2SetReal", 2: "fmi2SetRealInputDerivatives", 3: "fmi2DoStep", 4: "fmi2GetReal",
          5: "fmi2GetRealOutputDerivatives", 6: "fmi2GetFMUstate", 7: "fmi2SetFMUstate", 8: "fmi2FreeFMUstate"}

_P = ctypes.c_void_p
_INTS, _UINTS, _DOUBLES = ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_uint), ctypes.POINTER(ctypes.c_double)


class _Port(ctypes.Structure):
    _fields_ = [("instance", ctypes.c_int), ("index", ctypes.c_int)]


class _Bond(ctypes.Structure):
    _fields_ = [("effort_out", _Port), ("effort_in", _Port), ("flow_out", _Port), ("flow_in", _Port),
                ("slope_in", _Port)]


class _Feed(ctypes.Structure):
    _fields_ = [("instance", ctypes.c_int), ("first", ctypes.c_int), ("n_inputs", ctypes.c_int),
                ("n_outputs", ctypes.c_int)]


class _Instance(ctypes.Structure):
    _fields_ = [("component", _P), ("set_real", _P), ("get_real", _P), ("set_input_derivatives", _P),
                ("get_output_derivatives", _P), ("do_step", _P), ("get_state", _P), ("set_state", _P),
                ("free_state", _P),
                ("n_outputs", ctypes.c_int), ("output_offset", ctypes.c_int), ("output_vrs", _UINTS),
                ("n_inputs", ctypes.c_int), ("input_offset", ctypes.c_int), ("input_vrs", _UINTS),
                ("feed_source", _INTS), ("feed_index", _INTS), ("rate_order", ctypes.c_int),
                ("interpolating", ctypes.c_int), ("extrapolating", ctypes.c_int),
                ("n_record", ctypes.c_int), ("record_offset", ctypes.c_int), ("record_vrs", _UINTS)]


class _Fmi3Component(ctypes.Structure):
    """An FMI 3.0 instance as the kernel calls it (kernel/fmi3.c): the instance and its fmi3 functions."""
    _fields_ = [("instance", _P), ("set_float64", _P), ("get_float64", _P), ("get_output_derivatives", _P),
                ("do_step", _P), ("get_state", _P), ("set_state", _P), ("free_state", _P),
                ("derivative_span", ctypes.c_uint)]


class _Kernel(ctypes.Structure):
    _fields_ = [("n_instances", ctypes.c_int), ("instances", ctypes.POINTER(_Instance)), ("sequence", _INTS),
                ("gauss_seidel", ctypes.c_int), ("order", ctypes.c_int), ("keep", ctypes.c_int),
                ("n_samples", ctypes.c_int), ("sample_time", _DOUBLES), ("samples", _DOUBLES),
                ("n_sample_values", ctypes.c_int), ("exact_rates", _DOUBLES), ("new_values", _DOUBLES),
                ("stepped", _INTS), ("n_inputs_total", ctypes.c_int), ("input_values", _DOUBLES),
                ("input_rates", _DOUBLES), ("input_curvatures", _DOUBLES), ("n_bonds", ctypes.c_int),
                ("bonds", ctypes.POINTER(_Bond)), ("n_columns", ctypes.c_int), ("column_of", _INTS), ("record_scratch", _DOUBLES),
                ("instance_time", _DOUBLES), ("fmi_seconds", _DOUBLES), ("order_one", _INTS), ("order_two", _INTS),
                ("states", ctypes.POINTER(ctypes.c_void_p)),
                ("startup_states", ctypes.POINTER(ctypes.c_void_p)), ("guess", _DOUBLES), ("saved_time", _DOUBLES),
                ("failed_instance", ctypes.c_int), ("failed_call", ctypes.c_int), ("threads", ctypes.c_int),
                ("stage_end", _INTS), ("helper", ctypes.c_void_p),
                ("n_feeds", ctypes.c_int), ("feeds", ctypes.POINTER(_Feed)), ("feed_indices", _INTS),
                ("feed_vrs", _UINTS), ("feed_values", _DOUBLES), ("feed_rates", _DOUBLES)]


class _Controller(ctypes.Structure):
    _fields_ = [("h", ctypes.c_double), ("h_min", ctypes.c_double), ("h_max", ctypes.c_double),
                ("rtol", ctypes.c_double), ("atol", _DOUBLES), ("atol_energy", ctypes.c_double),
                ("k_i", ctypes.c_double), ("k_p", ctypes.c_double), ("previous", ctypes.c_double),
                ("safety", ctypes.c_double), ("change_min", ctypes.c_double), ("change_max", ctypes.c_double),
                ("t", ctypes.c_double), ("rejected", ctypes.c_int), ("accepted_count", ctypes.c_int),
                ("force_reject", _INTS), ("n_force_reject", ctypes.c_int),
                ("saved_time", _DOUBLES), ("saved_samples", _DOUBLES), ("saved_rates", _DOUBLES),
                ("saved_inputs", _DOUBLES), ("saved_instance_time", _DOUBLES), ("full", _DOUBLES)]


_library = None


def library() -> ctypes.CDLL:
    """The step kernel's native library (cosim/engine/kernel/), loaded and its layouts checked once."""
    global _library
    if _library is None:
        path = library_path("libcosim_kernel.so")
        lib = ctypes.CDLL(str(path), use_errno=True)  # a write's errno (a full disk) reaches cosim.engine.results
        from .realtime import _RealTime
        check_layout(lib, "kernel_layout", path, [(_Port, "KernelPort"), (_Bond, "KernelBond"),
                                                  (_Instance, "KernelInstance"), (_Kernel, "Kernel"), (_Feed, "KernelFeed"),
                                                  (_Controller, "Controller"), (_RealTime, "RealTime")])
        check_layout(lib, "fmi3_layout", path, [(_Fmi3Component, "Fmi3Component")])
        K, C = ctypes.POINTER(_Kernel), ctypes.POINTER(_Controller)
        lib.kernel_initialize.argtypes = [K, ctypes.c_double, ctypes.c_int, ctypes.c_int]
        lib.kernel_record.argtypes = [K, ctypes.c_int, _DOUBLES]
        lib.kernel_run_fixed.argtypes = [K, ctypes.POINTER(_RealTime), ctypes.c_int, ctypes.c_double, ctypes.c_int,
                                         _DOUBLES, _DOUBLES, _DOUBLES, _DOUBLES, _DOUBLES]
        for name in ("kernel_run_doubling", "kernel_run_energy"):
            getattr(lib, name).argtypes = [K, C, ctypes.c_int, ctypes.c_double, ctypes.c_int, _DOUBLES, _DOUBLES,
                                           _DOUBLES, _DOUBLES]
        lib.table_write_csv.argtypes = [ctypes.c_char_p, ctypes.c_char_p, _DOUBLES, ctypes.c_int, ctypes.c_int]
        lib.kernel_release.argtypes = [K]
        lib.kernel_release.restype = None
        for name in ("kernel_initialize", "kernel_record", "kernel_run_fixed", "kernel_run_doubling",
                     "kernel_run_energy", "table_write_csv"):
            getattr(lib, name).restype = ctypes.c_int
        _library = lib
    return _library


def _ints(values) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.intc)


def _ptr(array: np.ndarray, kind):
    return array.ctypes.data_as(kind)


def stages(sequence: Sequence[str], feeds: dict[str, list[tuple[str, int]]]) -> list[int]:
    """Per position j of the Gauss-Seidel sequence, where its stage ends: consecutive components
    none of which feeds another of them (the platform's six drives), which may step concurrently."""
    sources = {n: {source for source, _ in feeds.get(n, [])} for n in sequence}
    ends, j = [0] * len(sequence), 0
    while j < len(sequence):
        members, end = {sequence[j]}, j + 1
        while end < len(sequence) and not (sources[sequence[end]] & members) and \
                not any(sequence[end] in sources[m] for m in members):
            members.add(sequence[end])
            end += 1
        for position in range(j, end):
            ends[position] = end
        j = end
    return ends


def _failure_messages(messages: list[LogMessage]) -> list[LogMessage]:
    """The messages of the failed call among those logged during a batch: its errors (warnings of
    earlier steps are not part of the failure), or all if none is an error."""
    errors = [m for m in messages if m.status in ("error", "fatal")]
    return errors or messages


class Batch:
    """What one kernel call produced: rows (time and recorded columns, one per accepted step), the
    accepted steps, the largest bond energy residual per macro step (two per row under step
    doubling: the halves), and per bond the residual and the energy transferred; under real time,
    per step how late it started and how far past the next deadline it ended [s]."""

    def __init__(self, rows: np.ndarray, steps: np.ndarray, residuals: np.ndarray, bond_energy: np.ndarray,
                 lateness: np.ndarray | None = None, finish: np.ndarray | None = None):
        self.rows, self.steps, self.residuals, self.bond_energy = rows, steps, residuals, bond_energy
        self.lateness, self.finish = lateness, finish


class Kernel:
    """`coupling` run by `algorithm` in C, recording `columns` ((instance, variable) pairs) after
    every accepted step next to the time of instance `clock`."""

    def __init__(self, coupling: Coupling, algorithm: Algorithm, columns: Sequence[tuple[str, str]], clock: str):
        self.coupling, self.algorithm = coupling, algorithm
        self.library = library()
        names = coupling.names
        self.index = {n: k for k, n in enumerate(names)}
        self.clock = self.index[clock]
        self._keep: list = []  # arrays the C side points into
        self._instances = (_Instance * len(names))()
        record_offset = self._bind_instances(columns)
        self.n_bonds = len(coupling.bonds)
        sequence = algorithm.sequence if algorithm.kind == "gauss-seidel" and algorithm.sequence else names
        self.sequence = _ints([self.index[n] for n in sequence])
        self.stage_end = _ints(stages(list(sequence), coupling.feeds))
        self._bind_bonds()
        self._allocate(record_offset)
        self._fill_setup(len(columns))
        self._set_feedthrough(coupling.feedthrough() if algorithm.feedthrough else [])
        self._controller: _Controller | None = None

    def _bind_instances(self, columns: Sequence[tuple[str, str]]) -> int:
        """Per instance its FMI functions (FMI 3.0 through the kernel's adapters), its outputs,
        inputs with their sources, and what it records, each at its offset in the kernel's arrays;
        the recorded columns' places. Returns the number of recorded values."""
        coupling, names, instances = self.coupling, self.coupling.names, self._instances
        self.output_offset: dict[str, int] = {}
        offset = input_offset = record_offset = 0
        record_names: dict[str, list[str]] = {n: [] for n in names}
        for instance_name, variable in columns:
            coupling.instances[instance_name].vr(variable)  # raises naming the instance and variable
            if variable not in record_names[instance_name]:
                record_names[instance_name].append(variable)
        record_start = {}
        for k, n in enumerate(names):
            fmu = coupling.instances[n]
            c = instances[k]
            self._bind_functions(fmu, c)
            outputs = coupling.sources[n]
            vrs = _ints([fmu.vr(v) for v in outputs]).astype(np.uintc)
            c.n_outputs, c.output_offset, c.output_vrs = len(outputs), offset, _ptr(vrs, _UINTS)
            self.output_offset[n] = offset
            offset += len(outputs)
            inputs = coupling.input_names.get(n, [])
            in_vrs = _ints([fmu.vr(v) for v in inputs]).astype(np.uintc)
            sources = _ints([self.index[s] for s, _ in coupling.feeds.get(n, [])])
            indices = _ints([i for _, i in coupling.feeds.get(n, [])])
            c.n_inputs, c.input_offset, c.input_vrs = len(inputs), input_offset, _ptr(in_vrs, _UINTS)
            c.feed_source, c.feed_index = _ptr(sources, _INTS), _ptr(indices, _INTS)
            input_offset += len(inputs)
            c.rate_order = coupling.rate_orders.get(n, 0)
            c.interpolating = int(coupling.interpolating[n])
            c.extrapolating = int(coupling.extrapolating[n])
            rec = _ints([fmu.vr(v) for v in record_names[n]]).astype(np.uintc)
            c.n_record, c.record_offset, c.record_vrs = len(rec), record_offset, _ptr(rec, _UINTS)
            record_start[n] = record_offset
            record_offset += len(rec)
            self._keep += [vrs, in_vrs, sources, indices, rec]
        self.column_of = _ints([record_start[n] + record_names[n].index(v) for n, v in columns])
        self.n_values, self.n_inputs, self.n_columns = offset, input_offset, len(columns)
        return record_offset

    def _bind_functions(self, fmu, c: _Instance) -> None:
        """The instance's component and FMI functions as the kernel calls them (an FMI 3.0 one's
        through the kernel's adapters, kernel/fmi3.c, with the instance and its functions behind)."""
        if fmu.fmi3:
            adapted = _Fmi3Component(fmu.fmu.component, *(ctypes.cast(getattr(fmu.fmu.dll, f), _P).value for f in (
                "fmi3SetFloat64", "fmi3GetFloat64", "fmi3GetOutputDerivatives", "fmi3DoStep", "fmi3GetFMUState",
                "fmi3SetFMUState", "fmi3FreeFMUState")), fmu.input_derivative_span)
            self._keep.append(adapted)
            c.component = ctypes.addressof(adapted)
            for field in ("set_real", "get_real", "set_input_derivatives", "get_output_derivatives", "do_step",
                          "get_state", "set_state", "free_state"):
                setattr(c, field, ctypes.cast(getattr(self.library, f"fmi3_{field}"), _P).value)
            return
        c.component = fmu.fmu.component
        for field, function in (("set_real", "fmi2SetReal"), ("get_real", "fmi2GetReal"),
                                ("set_input_derivatives", "fmi2SetRealInputDerivatives"),
                                ("get_output_derivatives", "fmi2GetRealOutputDerivatives"),
                                ("do_step", "fmi2DoStep"), ("get_state", "fmi2GetFMUstate"),
                                ("set_state", "fmi2SetFMUstate"), ("free_state", "fmi2FreeFMUstate")):
            setattr(c, field, ctypes.cast(getattr(fmu.fmu.dll, function), _P).value)

    def _bind_bonds(self) -> None:
        """Each power bond's four ports (and its slope, where the interface Jacobian has one)."""
        self.bonds = (_Bond * max(self.n_bonds, 1))()
        for bond, ((eo, ei), (fo, fi)), slope in zip(self.bonds, self.coupling.bonds, self.coupling.bond_slopes):
            for port, (name, index) in (("effort_out", eo), ("effort_in", ei), ("flow_out", fo), ("flow_in", fi)):
                setattr(bond, port, _Port(self.index[name], index))
            bond.slope_in = _Port(self.index[slope[0]], slope[1]) if slope else _Port(-1, -1)

    def _allocate(self, record_offset: int) -> None:
        """The arrays the C side works in: samples and rates of the outputs, inputs, the record
        row, per instance its time, FMI seconds and saved states."""
        names, n, m = self.coupling.names, max(self.n_values, 1), max(self.n_inputs, 1)
        self.sample_time, self.samples = np.zeros(3), np.zeros((3, n))
        self.exact_rates, self.new_values, self.guess = np.zeros((2, n)), np.zeros(n), np.zeros(n)
        self.stepped = _ints(np.zeros(len(names)))
        self.inputs = np.zeros((3, m))
        self.record_scratch = np.zeros(max(record_offset, 1))
        self.instance_time = np.array([self.coupling.instances[n].time for n in names])
        for k, name in enumerate(names):  # what an FMU logs inside a kernel call carries its time then
            self.coupling.instances[name].clock = (lambda k=k: float(self.instance_time[k]))
        self.fmi_seconds, self.saved_time = np.zeros(len(names)), np.zeros(len(names))
        self.order_one, self.order_two = _ints(np.ones(max(n, m))), _ints(np.full(max(n, m), 2))
        self.states = (ctypes.c_void_p * len(names))()
        self.startup_states = (ctypes.c_void_p * len(names))()

    def _fill_setup(self, n_columns: int) -> None:
        """The C kernel's own struct, pointing into the arrays above."""
        algorithm = self.algorithm
        s = self.setup = _Kernel()
        s.n_instances, s.instances, s.sequence = len(self.coupling.names), self._instances, _ptr(self.sequence, _INTS)
        s.gauss_seidel, s.order = int(algorithm.kind == "gauss-seidel"), algorithm.order
        s.threads, s.stage_end = algorithm.threads, _ptr(self.stage_end, _INTS)
        s.keep = max(algorithm.order + 1, 2)
        s.sample_time, s.samples = _ptr(self.sample_time, _DOUBLES), _ptr(self.samples, _DOUBLES)
        s.n_sample_values = self.n_values
        s.exact_rates, s.new_values = _ptr(self.exact_rates, _DOUBLES), _ptr(self.new_values, _DOUBLES)
        s.stepped = _ptr(self.stepped, _INTS)
        s.n_inputs_total = self.n_inputs
        s.input_values, s.input_rates, s.input_curvatures = (_ptr(self.inputs[i], _DOUBLES) for i in range(3))
        s.n_bonds, s.bonds = self.n_bonds, self.bonds
        s.n_columns, s.column_of = n_columns, _ptr(self.column_of, _INTS)
        s.record_scratch = _ptr(self.record_scratch, _DOUBLES)
        s.instance_time, s.fmi_seconds = _ptr(self.instance_time, _DOUBLES), _ptr(self.fmi_seconds, _DOUBLES)
        s.order_one, s.order_two = _ptr(self.order_one, _INTS), _ptr(self.order_two, _INTS)
        s.states, s.startup_states = self.states, self.startup_states
        s.guess, s.saved_time = _ptr(self.guess, _DOUBLES), _ptr(self.saved_time, _DOUBLES)

    def _set_feedthrough(self, plan: list[tuple[str, list[int], list[int]]]) -> None:
        """The feed-through resolution's steps (cosim.engine.coupling.Coupling.feedthrough)."""
        self.feedthrough_plan = plan
        self.feeds = (_Feed * max(len(plan), 1))()
        indices, longest = [], 1
        for feed, (name, inputs, outputs) in zip(self.feeds, plan):
            feed.instance, feed.first, feed.n_inputs, feed.n_outputs = self.index[name], len(indices), len(inputs), len(outputs)
            indices += [*inputs, *outputs]
            longest = max(longest, len(inputs), len(outputs))
        self.feed_indices = _ints(indices or [0])
        self.feed_vrs = np.zeros(longest, dtype=np.uintc)
        self.feed_values, self.feed_rates = np.zeros(longest), np.zeros(2 * longest)
        s = self.setup
        s.n_feeds, s.feeds, s.feed_indices = len(plan), self.feeds, _ptr(self.feed_indices, _INTS)
        s.feed_vrs, s.feed_values = _ptr(self.feed_vrs, _UINTS), _ptr(self.feed_values, _DOUBLES)
        s.feed_rates = _ptr(self.feed_rates, _DOUBLES)

    # -- bookkeeping -----------------------------------------------------------------------------

    def release(self) -> None:
        """Ends the kernel's second thread (threads = 2), before the instances are freed."""
        self.library.kernel_release(ctypes.byref(self.setup))

    def _call(self, function, *args) -> int:
        logged = {n: len(i.messages) for n, i in self.coupling.instances.items()}
        self.fmi_seconds[:] = 0.0
        done = function(ctypes.byref(self.setup), *args)
        for n, k in self.index.items():
            instance = self.coupling.instances[n]
            instance.time = float(self.instance_time[k])
            instance.fmi_seconds += float(self.fmi_seconds[k])
        self._logged = logged
        return done

    def _raise_failure(self) -> None:
        name = self.coupling.names[self.setup.failed_instance]
        instance = self.coupling.instances[name]
        raise FmuError(name, _CALLS.get(self.setup.failed_call, "?"), instance.time,
                       _failure_messages(instance.messages[self._logged[name]:]))

    @property
    def time(self) -> float:
        return float(self.instance_time[self.clock])

    # -- the loops -------------------------------------------------------------------------------

    def initialize(self) -> np.ndarray:
        """Consistent outputs at the start and the first history sample; returns the first row."""
        if not self._call(self.library.kernel_initialize, self.time, self.algorithm.initial_sweeps,
                          int(self.algorithm.zero_start)):
            self._raise_failure()
        row = np.zeros(1 + self.n_columns)
        if not self._call(self.library.kernel_record, self.clock, _ptr(row, _DOUBLES)):
            self._raise_failure()
        return row

    def run_fixed(self, h: float, n_steps: int, real_time=None) -> Batch:
        """n_steps macro steps of h, paced, streamed and driven from outside by `real_time` (a
        cosim.engine.realtime.Session) if given. Raises FmuError (with .batch: the steps
        completed) on failure."""
        rows = np.zeros((n_steps, 1 + self.n_columns))
        residuals = np.zeros(max(n_steps, 1))
        bond_energy = np.zeros((max(n_steps, 1), max(self.n_bonds, 1), 2))
        lateness, finish = np.zeros(max(n_steps, 1)), np.zeros(max(n_steps, 1))
        done = self._call(self.library.kernel_run_fixed, real_time.pointer if real_time else None, self.clock, h,
                          n_steps, _ptr(rows, _DOUBLES), _ptr(residuals, _DOUBLES), _ptr(bond_energy, _DOUBLES),
                          _ptr(lateness, _DOUBLES), _ptr(finish, _DOUBLES))
        batch = Batch(rows[:done], np.full(done, h), residuals[:done], bond_energy[:done, :self.n_bonds],
                      *((lateness[:done], finish[:done]) if real_time else ()))
        if real_time:
            real_time.add(batch.lateness, batch.finish)
        if done < n_steps:
            self._fail(batch)
        return batch

    def _fail(self, batch: Batch) -> None:
        try:
            self._raise_failure()
        except FmuError as error:
            error.batch = batch
            raise

    def start_controller(self, control: StepDoubling | EnergyControl) -> None:
        """Sets up the step controller's state in C (kept over batches)."""
        n = max(self.n_values, 1)
        a = _Controller()
        a.h, a.h_min, a.h_max, a.rtol, a.t = control.step, control.h_min, control.h_max, control.rtol, self.time
        a.previous, a.rejected, a.accepted_count = 1.0, 0, 0
        scratch = dict(saved_time=np.zeros(3), saved_samples=np.zeros(3 * n), saved_rates=np.zeros(2 * n),
                       saved_inputs=np.zeros(3 * max(self.n_inputs, 1)),
                       saved_instance_time=np.zeros(len(self.index)), full=np.zeros(n))
        if isinstance(control, StepDoubling):
            atol = np.full(n, np.inf)
            scales = control.atol if isinstance(control.atol, Mapping) else dict.fromkeys(self.output_offset,
                                                                                            control.atol)
            for name, value in scales.items():
                if name not in self.output_offset:
                    raise KeyError(f"step doubling: atol names '{name}', which is no component of the system")
                offset = self.output_offset[name]
                atol[offset:offset + len(self.coupling.sources[name])] = value
            scratch["atol"] = atol
            a.atol = _ptr(atol, _DOUBLES)
            forced = _ints(list(control.force_reject) or [-1])
            scratch["force_reject"] = forced
            a.force_reject, a.n_force_reject = _ptr(forced, _INTS), len(control.force_reject)
        else:
            if not self.n_bonds:
                raise ValueError("energy step control needs power bonds in the system")
            a.atol_energy, a.k_i, a.k_p = control.atol, control.k_i, control.k_p
            a.safety, a.change_min, a.change_max = control.safety, control.change_min, control.change_max
        for field in ("saved_time", "saved_samples", "saved_rates", "saved_inputs", "saved_instance_time", "full"):
            setattr(a, field, _ptr(scratch[field], _DOUBLES))
        self._controller, self._controller_scratch = a, scratch
        self._doubling = isinstance(control, StepDoubling)

    @property
    def rejected(self) -> int:
        return self._controller.rejected if self._controller else 0

    def run_controlled(self, t_end: float, max_rows: int) -> Batch:
        """Accepted steps of the controller towards t_end, at most max_rows."""
        a = self._controller
        per_row = 2 if self._doubling else 1
        rows = np.zeros((max_rows, 1 + self.n_columns))
        steps, residuals = np.zeros(max_rows), np.zeros(per_row * max_rows)
        bond_energy = np.zeros((per_row * max_rows, max(self.n_bonds, 1), 2))
        function = self.library.kernel_run_doubling if self._doubling else self.library.kernel_run_energy
        done = self._call(function, ctypes.byref(a), self.clock, t_end, max_rows, _ptr(rows, _DOUBLES),
                          _ptr(steps, _DOUBLES), _ptr(residuals, _DOUBLES), _ptr(bond_energy, _DOUBLES))
        written = -1 - done if done < 0 else done
        batch = Batch(rows[:written], steps[:written], residuals[:per_row * written],
                      bond_energy[:per_row * written, :self.n_bonds])
        if done < 0:
            self._fail(batch)
        return batch

    @property
    def controller_time(self) -> float:
        return self._controller.t
