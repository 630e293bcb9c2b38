"""The wheel installs the `aeroident` command (a console script over the Rust command line):
on the PATH of the environment the wheel went into, `--help` lists the commands, `--version`
is the package's version, a usage error exits 2 naming the argument, and a command runs."""

import os
import shutil
import subprocess
import sys

import aeroident


def installed():
    # The console script sits beside the interpreter of the environment the wheel is in.
    exe = shutil.which("aeroident", path=os.path.dirname(sys.executable))
    assert exe, "the wheel did not install an `aeroident` command beside " + sys.executable
    return exe


def test_the_wheel_installs_the_command_line():
    exe = installed()
    help_ = subprocess.run([exe, "--help"], capture_output=True, text=True)
    assert help_.returncode == 0, help_.stderr
    for command in ("replay", "run", "export", "linearize"):
        assert command in help_.stdout, help_.stdout
    version = subprocess.run([exe, "--version"], capture_output=True, text=True)
    assert version.returncode == 0 and aeroident.__version__ in version.stdout, version
    bad = subprocess.run([exe, "replay", "--no-such-flag"], capture_output=True, text=True)
    assert bad.returncode == 2 and "--no-such-flag" in bad.stderr, bad


def test_the_command_runs_a_job_and_reports_an_error_with_exit_1(tmp_path):
    exe = installed()
    out = subprocess.run([exe, "export", "jsbsim", "--summary", str(tmp_path / "absent.json")],
                         capture_output=True, text=True)
    assert out.returncode == 1 and "absent.json" in out.stderr, out
    design = subprocess.run([exe, "design", "--surfaces", "de", "--out", str(tmp_path / "d")],
                            capture_output=True, text=True)
    assert design.returncode == 0, design.stderr
    assert (tmp_path / "d" / "design.json").exists()
