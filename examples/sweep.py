#!/usr/bin/env python3
"""Parameter study of a packed MFBD-FMU on Dask (python/mfbd/sweep.py; --help).

    python examples/sweep.py build/fmus/pendulum.fmu --grid angle0=0:1:8 --output hinge.angle
"""
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "python"))
from mfbd.sweep import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
