"""`python -m binbow` is the C++ CLI: the build tree's build/bin/binbow, exec'd.

The installed faces (the console script, pip and cmake --install) are tested
by test_packaging.py.
"""
import os
import subprocess
import sys
from pathlib import Path

import binbow
import binbow._cli
import binbow._data_location
from conftest import cli


def run_module(*arguments):
    package_parent = str(Path(binbow.__file__).resolve().parents[1])
    env = dict(os.environ, PYTHONPATH=package_parent)
    return subprocess.run([sys.executable, "-m", "binbow", *arguments], env=env,
                          capture_output=True, text=True, timeout=60)


def test_the_module_runs_the_build_trees_cli():
    assert Path(binbow._cli.executable()).resolve() == cli().resolve()
    expected = subprocess.run([str(cli()), "--version"], capture_output=True, text=True)
    result = run_module("--version")
    assert (result.returncode, result.stdout) == (0, expected.stdout), result
    assert result.stdout == f"binbow {binbow.__version__}\n"


def test_errors_and_exit_status_are_the_clis():
    result = run_module("no-such-command")
    assert result.returncode == 1, result
    assert result.stderr.startswith("binbow: error:"), result.stderr


def test_a_missing_cli_is_a_clear_error(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(binbow._data_location, "CLI_EXECUTABLE", str(tmp_path / "nowhere"))
    assert binbow._cli.main() == 1
    message = capsys.readouterr().err
    assert message.startswith(f"binbow: error: {tmp_path / 'nowhere'}: the binbow command is "
                              "not installed with this Python package"), message
