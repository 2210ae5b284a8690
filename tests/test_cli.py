"""The command-line entry point."""

import subprocess
import sys

import pytest

from sigmatau.cli import main


def test_demo_prints_nbs_table(capsys):
    assert main(["demo"]) == 0
    out = capsys.readouterr().out
    # OADEV of the NBS set at tau = 1 s (NIST SP 1065 Table 31): 2.922319e-01
    assert "2.922319e-01" in out
    assert "oadev" in out


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert "sigmatau" in capsys.readouterr().out


def test_no_command_is_usage_error(capsys):
    with pytest.raises(SystemExit) as exc:
        main([])
    assert exc.value.code == 2


def test_module_entry_point_runs():
    out = subprocess.run([sys.executable, "-m", "sigmatau", "demo"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "2.922319e-01" in out.stdout
