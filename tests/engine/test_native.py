"""The ctypes copies of the native libraries' structs are checked against the build at load
(cosim.engine.native): every field's offset and size and every struct's size, so that a stale
build or a field added on one side is refused with one line instead of read at the wrong offsets."""

from __future__ import annotations

import ctypes

import pytest

from cosim.engine import kernel
from cosim.engine.artifacts import library_path
from cosim.engine.native import LayoutError, check_layout, published_layout, python_layout
from cosim.platform import core as platform_core


def test_the_bindings_match_the_builds():
    """Both libraries load (their check passes) and publish every field of their structs."""
    lib, core = kernel.library(), platform_core.core_library()
    published = published_layout(lib, "kernel_layout")
    for structure, name in [(kernel._Bond, "KernelBond"), (kernel._Instance, "KernelInstance"),
                            (kernel._Kernel, "Kernel"), (kernel._Controller, "Controller")]:
        assert python_layout(structure, name).items() <= published.items()
    published = published_layout(core, "platform_core_layout")
    assert python_layout(platform_core.Platform).items() <= published.items()
    assert published["Platform.gravity"][1] == 3 * ctypes.sizeof(ctypes.c_double)


def drifted(structure: type[ctypes.Structure], change) -> type[ctypes.Structure]:
    fields = change(list(structure._fields_))
    return type(structure.__name__, (ctypes.Structure,), {"_fields_": fields})


@pytest.mark.parametrize("change,what", [
    (lambda f: f[:-1], "Kernel.feed_rates: not in Python"),                                 # a field missing
    (lambda f: f + [("extra", ctypes.c_int)], "Kernel.extra: not in C"),                   # a field too many
    (lambda f: [(n, ctypes.c_long if n == "n_bonds" else t) for n, t in f], "Kernel.n_bonds: (offset, size)"),
    (lambda f: [f[1], f[0], *f[2:]], "Kernel.instances: (offset, size)"),                  # two fields swapped
])
def test_a_drifted_copy_is_refused_with_one_line(change, what):
    """What the old hand-copied "10 ints" per bond could not notice: a copy whose fields differ."""
    lib = kernel.library()
    with pytest.raises(LayoutError) as error:
        check_layout(lib, "kernel_layout", library_path("libcosim_kernel.so"), [(drifted(kernel._Kernel, change), "Kernel")])
    message = str(error.value)
    assert what in message and "\n" not in message and "libcosim_kernel.so" in message
