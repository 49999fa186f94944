"""A result as CSV (and Parquet): a truncated run says so in its first
line (CSV) or metadata (Parquet)."""
import pathlib

import numpy as np


def write_csv(result, path):
    path = pathlib.Path(path)
    names = ["time"] + list(result.values)
    data = np.column_stack([result.time] + [result.values[n] for n in result.values])
    with open(path, "w") as f:
        if result.truncated:
            f.write(f"# TRUNCATED: {result.message}\n")
        f.write(",".join(names) + "\n")
        np.savetxt(f, data, delimiter=",", fmt="%.17g")


def write_parquet(result, path):
    import pyarrow as pa
    import pyarrow.parquet as pq
    columns = {"time": result.time, **result.values}
    meta = {"model": result.model, "truncated": str(result.truncated).lower(), "message": result.message}
    meta.update({f"unit:{n}": u for n, u in result.units.items()})
    table = pa.table(columns).replace_schema_metadata(meta)
    pq.write_table(table, path)


def read_csv(path):
    """(header names, data, truncation message or '')."""
    with open(path) as f:
        first = f.readline()
        message = first[len("# TRUNCATED: "):].strip() if first.startswith("# TRUNCATED") else ""
        header = f.readline() if message else first
        data = np.loadtxt(f, delimiter=",", ndmin=2)
    return header.strip().split(","), data, message
