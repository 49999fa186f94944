"""Python tools over packed MFBD-FMU scenes: simulate with progress, plot,
write ParaView files, animate, and sweep parameters on Dask.

    python -m mfbd simulate FMU ...   (examples/simulate.py is the same)
    python -m mfbd sweep FMU ...
"""
