"""The `aeroident` console script: the command line of the Rust binary, installed with the
wheel (`pip install aeroident` puts `aeroident` on the PATH)."""

import sys

from ._aeroident import cli_main


def main() -> None:
    """Runs the command line on this process's arguments and exits with its code."""
    sys.exit(cli_main(["aeroident", *sys.argv[1:]]))
