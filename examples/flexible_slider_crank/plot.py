#!/usr/bin/env python3
"""F5: simulates the flexible slider-crank FMU and plots the rod's mid-span
deflection (mid node from the chord of its end nodes), the slider position
and the crank drive torque.

    python examples/flexible_slider_crank/plot.py build/fmus/flexible_slider_crank.fmu --out out
"""
import argparse
import pathlib
import sys

import numpy as np
from fmpy import read_model_description, simulate_fmu

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
from plotting import save_figure, save_table  # noqa: E402


def midspan_deflection(column, nodes):
    """Deflection of the rod's middle exposed node from the chord of its end
    nodes, in the plane of motion (m); column(name) gives an output over time."""
    first, mid, last = nodes[0], nodes[len(nodes) // 2], nodes[-1]
    p = {i: np.column_stack([column(f"rod.node{i}.position.x"), column(f"rod.node{i}.position.y")])
         for i in (first, mid, last)}
    chord = (p[last] - p[first]) / np.linalg.norm(p[last] - p[first], axis=1)[:, None]
    offset = p[mid] - 0.5 * (p[first] + p[last])
    return chord[:, 0] * offset[:, 1] - chord[:, 1] * offset[:, 0]


def exposed_nodes(md):
    return sorted({int(v.name.split(".")[1][4:]) for v in md.modelVariables if v.name.startswith("rod.node")})


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmu", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out"))
    args = parser.parse_args()
    md = read_model_description(str(args.fmu))
    r = simulate_fmu(str(args.fmu), output_interval=1e-3)
    deflection = midspan_deflection(lambda name: r[name], exposed_nodes(md))
    t = r["time"]
    columns = {"time": t, "midspan_deflection": deflection, "slider.x": r["slider.position.x"],
               "crank_drive.drive_torque": r["crank_drive.drive_torque"]}
    save_table(args.out / "flexible_slider_crank.csv", columns)
    save_figure(args.out / "flexible_slider_crank.png", t,
                [("mid-span deflection [mm]", {"rod": 1e3 * deflection}),
                 ("slider x [m]", {"slider": r["slider.position.x"]}),
                 ("crank torque [N m]", {"drive": r["crank_drive.drive_torque"]})],
                "F5 flexible slider-crank: crank spun up to 150 rad/s over 0.15 s")
    print(f"plot: largest mid-span deflection {1e3 * np.abs(deflection).max():.3f} mm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
