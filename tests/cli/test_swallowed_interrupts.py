"""A Ctrl-C or SIGTERM whose exception some library swallows (a bare ``except:``, an exception
"ignored" in a ``__del__``) must still stop the run: the tracking loop stops after its next frame
and the command line exits 130 / 143 instead of 0."""

import argparse
import os
import signal
import time

import pytest

import worldtrack.cli as cli
from worldtrack.interrupts import StopRequests, install_terminate_handler, received_signal


@pytest.fixture
def own_handlers():
    saved = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    yield
    for s, handler in saved.items():
        signal.signal(s, handler)


def _swallowed(signum: int) -> None:
    try:
        os.kill(os.getpid(), signum)
        time.sleep(2)                                  # the handler raises before this ends
    except BaseException:                              # what a careless library does
        pass


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_the_loop_starts_with_a_swallowed_signal_requested(own_handlers, signum):
    install_terminate_handler()
    _swallowed(signum)
    assert received_signal() == signum
    with StopRequests() as stop:
        assert stop.requested and stop.signal == signum
    assert received_signal() is None                   # dealt with by the loop: not reported twice
    install_terminate_handler()
    with StopRequests() as stop:                       # a fresh run starts with nothing pending
        assert not stop.requested


def test_the_command_line_ends_with_the_swallowed_signals_status(own_handlers, monkeypatch, capsys):
    def command(args):
        _swallowed(signal.SIGTERM)
        return 0

    parser = argparse.ArgumentParser(prog="worldtrack")
    parser.set_defaults(func=command)
    monkeypatch.setattr(cli, "build_parser", lambda verb: parser)
    assert cli.main([]) == 143
    assert capsys.readouterr().err.strip().splitlines()[-1] == "terminated"
    parser.set_defaults(func=lambda args: 0)          # the next run of main forgets it
    assert cli.main([]) == 0
