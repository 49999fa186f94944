"""Plots of selected outputs over time: one panel per quantity and unit,
split further so that every curve's own motion fills a fair part of its
panel; legends outside the axes, a few entries at most."""
import re
import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

LEGEND_ENTRIES = 6     # more curves are summarised in one legend line
VISIBLE_SHARE = 0.05   # a curve's swing must fill this share of its panel's range
MAX_PANELS = 10
DEFAULT_QUANTITIES = {"joint coordinate", "position", "kinetic_energy", "strain_energy", "potential_energy"}
NAMED_QUANTITIES = {"kinetic_energy", "strain_energy", "potential_energy", "drive_torque", "drive_force", "drive_rate",
                    "torque", "force", "damping"}
NOISE = 1e-9           # swings below this share of the largest value are round-off


def quantity(name):
    """'rod.node4.position.x' -> ('position', 'x'); 'hinge.angle' -> ('joint coordinate', 'angle');
    'hinge.angle_rate' -> ('joint rate', 'angle_rate')."""
    parts = name.split(".")
    if len(parts) == 2 and parts[1] not in NAMED_QUANTITIES:
        return ("joint rate" if parts[1].endswith("_rate") else "joint coordinate"), parts[1]
    parts = [p for p in parts[1:] if not re.fullmatch(r"(node|element)\d+|end[12]", p)] or parts[-1:]
    if len(parts) > 1 and parts[-1] in {"x", "y", "z", "w"}:
        return ".".join(parts[:-1]), parts[-1]
    return ".".join(parts), ""


def unit_text(unit):
    return f"[{unit}]" if unit else "[1]"


def panels(result, names):
    """[(quantity, unit, [names])]: grouped by quantity and unit, then split
    so that no curve's swing is under VISIBLE_SHARE of its panel's range."""
    groups = {}
    for n in names:
        groups.setdefault((quantity(n)[0], result.units.get(n, "")), []).append(n)
    out = []
    for (q, unit), members in groups.items():
        for part in _split_by_range(result, members):
            out.append((q, unit, part))
    return out


def _split_by_range(result, names):
    """Greedy bins, largest swing first; a swing under NOISE of the group's
    largest value is round-off and counts as none."""
    scale = max((float(np.max(np.abs(result.values[n]))) for n in names if len(result.values[n])), default=0.0)
    bins = []  # [names, lo, hi, smallest swing]
    for n in sorted(names, key=lambda n: -np.ptp(result.values[n]) if len(result.values[n]) else 0):
        y = result.values[n]
        lo, hi = (float(np.min(y)), float(np.max(y))) if len(y) else (0.0, 0.0)
        swing = hi - lo if hi - lo > NOISE * scale else 0.0
        for b in bins:
            span = max(b[2], hi) - min(b[1], lo)
            if span <= NOISE * scale or min(b[3], swing if swing > 0 else b[3]) >= VISIBLE_SHARE * span:
                b[0].append(n)
                b[1], b[2] = min(b[1], lo), max(b[2], hi)
                b[3] = min(b[3], swing) if swing > 0 else b[3]
                break
        else:
            bins.append([[n], lo, hi, swing if swing > 0 else np.inf])
    return [[n for n in names if n in b[0]] for b in bins]


def curve_label(name, q):
    """The name without its quantity: 'bob.position.x' in panel 'position' -> 'bob x'."""
    label = name.replace("." + q, "", 1)
    return label.replace(".", " ")


def title_text(result):
    text = f"{result.model}: {result.description}" if result.description else result.model
    return textwrap.fill(textwrap.shorten(text, 300, placeholder=" ..."), 110)


def default_selection(result, names):
    """Without a selection: the joint coordinates, positions and energies
    that move (the CSV has every output); rates where too few move."""
    moving = [n for n in names if not _constant(result.values[n])]
    chosen = [n for n in moving if quantity(n)[0] in DEFAULT_QUANTITIES]
    if len(chosen) < 2:
        chosen += [n for n in moving if quantity(n)[0] in ("joint rate", "angular_velocity")]
    return chosen or names


def _constant(y):
    return len(y) == 0 or np.ptp(y) <= NOISE * max(1.0, float(np.max(np.abs(y))))


def plot(result, path, names=None, title=None):
    """One figure of the selected outputs over time, written to path."""
    fig = figure(result, names, title)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure(result, names=None, title=None):
    """The figure of plot(): at most MAX_PANELS panels (it says how many
    outputs were left out)."""
    names = list(names or result.values)
    groups = panels(result, names)
    left_out = sum(len(g[2]) for g in groups[MAX_PANELS:])
    groups = groups[:MAX_PANELS]
    if not groups:
        raise ValueError("nothing to plot: no outputs selected")
    fig, axes = plt.subplots(len(groups), 1, figsize=(10, 1.2 + 2.1 * len(groups)), sharex=True,
                             squeeze=False, layout="constrained")
    for ax, (q, unit, members) in zip(axes[:, 0], groups):
        for n in members:
            ax.plot(result.time, result.values[n], lw=1, label=curve_label(n, q))
        coordinates = {quantity(n)[1] for n in members}
        shown = coordinates.pop() if q.startswith("joint") and len(coordinates) == 1 else q
        ax.set_ylabel(textwrap.fill(f"{shown.replace('_', ' ')} {unit_text(unit)}", 24), fontsize=9)
        ax.grid(True, alpha=0.3)
        _legend(ax, len(members))
        if result.truncated:
            ax.axvline(result.time[-1], color="red", lw=1, ls="--")
    axes[-1, 0].set_xlabel("time [s]")
    heading = title or title_text(result)
    if result.truncated:
        heading += f"\nTRUNCATED: {result.message}"[:220]
    if left_out:
        heading += f"\n{left_out} more outputs not plotted (select them with --output)"
    fig.suptitle(heading, fontsize=9, color="red" if result.truncated else "black")
    return fig


def _legend(ax, count):
    """Outside the axes; beyond LEGEND_ENTRIES curves, a summary line."""
    handles, labels = ax.get_legend_handles_labels()
    if count <= 1 and labels:
        ax.set_title(labels[0], fontsize=8, loc="left")
        return
    if count > LEGEND_ENTRIES:
        rest = count - (LEGEND_ENTRIES - 1)
        handles = handles[:LEGEND_ENTRIES - 1] + [plt.Line2D([], [], color="none")]
        labels = labels[:LEGEND_ENTRIES - 1] + [f"... and {rest} more (CSV)"]
    ax.legend(handles, labels, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
