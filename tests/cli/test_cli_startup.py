"""The command line as a new user first meets it: help that answers at once, one spelling for each
thing, required options shown as required, a closed pipe that ends quietly."""

import subprocess
import sys

import pytest

from worldtrack.cli import COMMANDS, build_parser

PY = [sys.executable, "-c"]


def _imported_after(args):
    """The heavy modules loaded by ``worldtrack ARGS`` (run in a fresh interpreter)."""
    code = ("import sys\nfrom worldtrack.cli import main\ntry:\n    main(%r)\nexcept SystemExit:\n    pass\n"
            "print(sorted(m for m in ('numpy', 'scipy', 'cv2', 'numba', 'matplotlib', 'pandas') if m in sys.modules))"
            % (args,))
    out = subprocess.run([*PY, code], capture_output=True, text=True, timeout=120)
    return out.stdout.strip().splitlines()[-1]


@pytest.mark.parametrize("args", [["--help"], ["track", "--help"], ["eval", "--help"], ["calibrate", "--help"],
                                  ["scene", "--help"], ["synth", "--help"], ["background", "--help"]])
def test_help_loads_no_numerical_library(args):
    assert _imported_after(args) == "[]"


def test_the_listing_shows_each_verbs_own_help_line():
    import argparse

    for name, line in COMMANDS.items():
        parser = build_parser(name)              # this verb registered by its own module
        action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        shown = next(c.help for c in action._choices_actions if c.dest == name)
        assert shown == line, name
    assert not any("seed 00" in line for line in COMMANDS.values())


def test_calibrate_help_quotes_the_advised_number_of_points():
    from worldtrack.cli import calibrate as cli
    from worldtrack.geometry import calibrate as fit
    assert cli.ADVISED_POINTS == fit.ADVISED_POINTS


@pytest.mark.parametrize("verb, shown", [("track", "worldtrack track SCENE --video CAM=PATH"),
                                         ("synth", "worldtrack synth SCENARIO --out DIR"),
                                         ("calibrate", "worldtrack calibrate POINTS.csv")])
def test_usage_shows_what_is_required(verb, shown, capsys):
    with pytest.raises(SystemExit):
        build_parser(verb).parse_args([verb, "--help"])
    assert shown in capsys.readouterr().out


def test_one_spelling_for_sizes_and_quiet(capsys):
    for verb in ("synth", "demo", "track", "background"):
        with pytest.raises(SystemExit):
            build_parser(verb).parse_args([verb, "--help"])
        text = capsys.readouterr().out
        assert "--quiet" in text, verb
        assert "WIDTHxHEIGHT" not in text and "--no-progress" not in text, verb


def test_a_closed_pipe_ends_the_command_quietly():
    # The reader closes at once; everything the command prints meets a closed pipe.
    proc = subprocess.Popen([*PY, "import sys\nfrom worldtrack.cli import main\nsys.exit(main(['synth', '--list']))"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()
    err = proc.stderr.read().decode()
    code = proc.wait(timeout=120)
    assert err == "" and code == 141


def _run_entry_while_cli_is_imported(action: str) -> subprocess.CompletedProcess:
    """Start the program as its entry point does, running ``action`` (one statement; ``os`` and ``signal``
    imported) the moment ``worldtrack.cli`` starts to be imported: the entry point's first moments."""
    code = ("import builtins, os, signal\nreal = builtins.__import__\n"
            "def importing(name, *args, **kwargs):\n"
            f"    if name == 'worldtrack.cli':\n        {action}\n"
            "    return real(name, *args, **kwargs)\n"
            "builtins.__import__ = importing\nfrom worldtrack.entry import run\nrun()\n")
    return subprocess.run([*PY, code], capture_output=True, text=True, timeout=120)


def test_ctrl_c_while_the_command_line_is_imported_is_one_line_and_130():
    out = _run_entry_while_cli_is_imported("raise KeyboardInterrupt")
    assert (out.returncode, out.stderr) == (130, "interrupted\n")


def test_sigterm_while_the_command_line_is_imported_is_one_line_and_143():
    # Under load the import can take seconds; a SIGTERM then must not end the program silently (-15).
    out = _run_entry_while_cli_is_imported("os.kill(os.getpid(), signal.SIGTERM)")
    assert (out.returncode, out.stderr) == (143, "terminated\n")


@pytest.mark.parametrize("status, finalised", [(143, False), (130, False), (0, True), (2, True)])
def test_an_interrupted_run_ends_without_finalising_the_interpreter(status, finalised):
    # Finalising while a native library's thread is inside a call aborted one signalled start-up (-6).
    code = ("import atexit, sys\natexit.register(lambda: print('finalised', file=sys.stderr))\n"
            f"import worldtrack.cli\nworldtrack.cli.main = lambda: {status}\n"
            "print('said', file=sys.stderr, end=' ')\nfrom worldtrack.entry import run\nrun()\n")
    out = subprocess.run([*PY, code], capture_output=True, text=True, timeout=120)
    assert (out.returncode, out.stderr) == (status, "said finalised\n" if finalised else "said ")


def test_the_entry_point_imports_almost_nothing_before_it_can_catch_ctrl_c():
    code = "import sys\nimport worldtrack.entry\nprint(sorted(m for m in ('typing', 'argparse', 're', 'enum') if m in sys.modules))"
    out = subprocess.run([*PY, code], capture_output=True, text=True, timeout=120)
    assert out.stdout.strip() == "[]"
