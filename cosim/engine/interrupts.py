"""Ctrl-C never lost inside an FMU: Python runs a signal's handler at the next bytecode, which may
be inside a function the FMU calls back (its logger); ctypes then prints the KeyboardInterrupt as
"ignored" and the run goes on. While `deferred()` holds, an interrupt that arrives inside such a
callback is kept until the run loop asks (`check`, after each batch of steps) or the block ends,
and raised there."""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager
from typing import Callable, Iterator

_CALLBACKS: set = set()  # the code of every function C calls back into
_pending = False


def callback(function: Callable) -> Callable:
    """Marks `function` as one that C calls back (an interrupt there waits until it returns)."""
    _CALLBACKS.add(function.__code__)
    return function


def _handler(signum, frame) -> None:
    global _pending
    while frame is not None:
        if frame.f_code in _CALLBACKS:
            _pending = True  # raised by check() once C has returned to the run loop
            return
        frame = frame.f_back
    raise KeyboardInterrupt


def check() -> None:
    """Raises the KeyboardInterrupt an FMU's callback held back, if one did."""
    global _pending
    if _pending:
        _pending = False
        raise KeyboardInterrupt


@contextmanager
def deferred() -> Iterator[None]:
    """Ctrl-C raised outside the FMUs' callbacks while the block runs (in the main thread; the
    handler it replaces, Python's default, comes back afterwards)."""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield  # another thread, or an interrupt someone else handles (or ignores): left as it is
        return
    signal.signal(signal.SIGINT, _handler)
    try:
        yield
        check()
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
