"""Stopping cleanly on Ctrl-C (SIGINT) and SIGTERM.

Python turns SIGINT into :class:`KeyboardInterrupt` wherever the interpreter happens to be. Inside a
call to a compiled (Numba) kernel that surfaces as ``SystemError: CPUDispatcher(...) returned a
result with an exception set`` with the interrupt as its cause, and a frame half-written. So:

* Around the tracking loop, :class:`StopRequests` replaces the handlers: the first SIGINT or SIGTERM
  only sets a flag that the loop reads between frames (every output stays whole); a second one
  raises at once, for a user who does not want to wait for the frame to end.
* Everywhere else, :func:`install_terminate_handler` makes SIGTERM raise :class:`Terminated` (a
  ``KeyboardInterrupt``) as SIGINT does, and :func:`interrupt_in` finds an interrupt hidden in an
  exception's cause chain, so the command line can say ``interrupted`` and exit with 128 + the
  signal number (130 for SIGINT, 143 for SIGTERM) whatever was running.
* Those handlers also remember the signal (:func:`received_signal`): an interrupt raised inside a
  library that swallows it (a bare ``except:``, an exception "ignored" in a ``__del__``) is not
  lost. The next :class:`StopRequests` starts with it already requested, and the command line
  ends with its status even if the command itself finished.

>>> interrupt_in(SystemError("wrapped")) is None
True
>>> e = SystemError("CPUDispatcher returned a result with an exception set")
>>> e.__cause__ = Terminated()
>>> exit_status(interrupt_in(e))
143
"""

from __future__ import annotations

import signal
import threading
from types import FrameType
from typing import Any, Callable


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised as an interrupt so ``finally`` blocks flush the outputs."""


def signal_of(interrupt: BaseException | None) -> int:
    """The signal an interrupt stands for: SIGTERM for :class:`Terminated`, else SIGINT."""
    return int(signal.SIGTERM) if isinstance(interrupt, Terminated) else int(signal.SIGINT)


def exit_status(interrupt: BaseException | None) -> int:
    """The shell's exit status for an interrupt: 128 + the signal number (130 or 143)."""
    return 128 + signal_of(interrupt)


def interrupt_in(exc: BaseException | None) -> KeyboardInterrupt | None:
    """``exc`` itself, or the first interrupt in its ``__cause__``/``__context__`` chain, or None."""
    seen: set[int] = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


_received: int | None = None        # the first signal the raising handlers saw since installed


def _raise_interrupt(signum: int, frame: FrameType | None) -> None:
    global _received
    if _received is None:
        _received = signum
    raise Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()


def install_terminate_handler() -> None:
    """Make SIGTERM raise :class:`Terminated` and SIGINT ``KeyboardInterrupt``, both remembered
    (:func:`received_signal`); forget any signal seen before. Main thread only; a no-op elsewhere."""
    global _received
    if threading.current_thread() is threading.main_thread():
        _received = None
        for s in (signal.SIGINT, signal.SIGTERM):
            signal.signal(s, _raise_interrupt)


def received_signal(forget: bool = False) -> int | None:
    """The first SIGINT/SIGTERM raised since :func:`install_terminate_handler`, even if whatever
    it interrupted swallowed the exception; None if none. ``forget``: it is being dealt with."""
    global _received
    signum = _received
    if forget:
        _received = None
    return signum


class StopRequests:
    """While active, the first SIGINT/SIGTERM asks the loop to stop instead of raising.

    Attributes
    ----------
    signal : int or None — the signal received (``signal.SIGINT`` or ``signal.SIGTERM``)

    Examples
    --------
    >>> import os
    >>> with StopRequests() as stop:
    ...     os.kill(os.getpid(), signal.SIGTERM)
    ...     stop.requested, stop.signal == signal.SIGTERM
    (True, True)
    """

    _SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.signal: int | None = None
        self._previous: dict[int, Callable[..., Any] | int | None] = {}

    @property
    def requested(self) -> bool:
        return self.signal is not None

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if self.signal is None:
            self.signal = signum
            return
        raise Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()

    def __enter__(self) -> "StopRequests":
        self.signal = received_signal(forget=True)     # one that something before the loop swallowed
        if threading.current_thread() is threading.main_thread():
            for s in self._SIGNALS:
                self._previous[s] = signal.signal(s, self._handle)
        return self

    def __exit__(self, *exc: object) -> None:
        for s, handler in self._previous.items():
            signal.signal(s, handler if handler is not None else signal.SIG_DFL)
        self._previous.clear()

    def interrupt(self) -> KeyboardInterrupt:
        """The exception that stands for the signal received (to re-raise after cleaning up)."""
        return Terminated() if self.signal == signal.SIGTERM else KeyboardInterrupt()


__all__ = ["StopRequests", "Terminated", "exit_status", "install_terminate_handler", "interrupt_in",
           "received_signal", "signal_of"]
