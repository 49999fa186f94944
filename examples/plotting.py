"""Shared by the example scripts: a CSV of named columns and a figure of
panels over time, both under an output folder."""
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def save_table(path: pathlib.Path, columns: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savetxt(path, np.column_stack(list(columns.values())), delimiter=",", header=",".join(columns), comments="")
    print(f"wrote {path.resolve()}")


def save_figure(path: pathlib.Path, t, panels: list, title: str) -> None:
    """panels: [(y label, {curve label: values})], one axis each, shared time."""
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 2.6 * len(panels)), sharex=True, squeeze=False)
    for ax, (label, curves) in zip(axes[:, 0], panels):
        for name, y in curves.items():
            ax.plot(t, y, label=name, lw=1)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        if len(curves) > 1:
            ax.legend(fontsize=7, loc="upper right", ncol=2)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(f"wrote {path.resolve()}")
