#!/usr/bin/env python3
"""Simulate a packed MFBD-FMU scene: progress, parameters, outputs, CSV,
plot, ParaView files, animation (python/mfbd/cli.py; --help for options).

    python examples/simulate.py build/fmus/pendulum.fmu --out out
"""
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "python"))
from mfbd.cli import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
