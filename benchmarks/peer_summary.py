#!/usr/bin/env python3
"""Wall time at matched error, from the CSVs of the peer studies
(peer_r1_pendulum.py, peer_f1_end_moment.py, peer_f3_vibration.py,
peer_f4_spin_up.py, the rigid + flexible ones of issue 5:
peer_f4_motor.py, peer_f5_slider_crank.py, peer_f6_four_bar.py,
peer_tip_mass.py, and the rigid ones of issue 3: peer_r2_double_pendulum.py,
peer_r3_n_four_bar.py, peer_r4_bricard.py, peer_r5_slider_crank.py,
peer_r6_flyball_governor.py): for each problem, metric and error level, the cheapest
run of each code and model that reached the level (no interpolation), and
the ratio of our wall time to the fastest Exudyn model's. Our series are
each a model: the fixed substeps and, where a study has it, ours driven by
fmi2SetupExperiment's tolerance ("by tolerance"; its setting the tolerance,
and the mesh for flexible problems). ours_over_fastest_exudyn is, on our
rows, that row's own ratio (on Exudyn's rows, empty);
best_ours_over_fastest_exudyn, on every row, that of our fastest series at
the level. Writes peer_summary.csv and prints the same as a Markdown table.
"""
import argparse
import csv
import pathlib

from peer_common import EXUDYN, OURS, cheapest_at, read_csv, series_label

# problem -> (csv, [(metric column, description, error levels)])
STUDIES = {
    "R1 pendulum": ("r1_pendulum_precision.csv", [("error", "bob position at 10 s [m]", [1e-3, 1e-4, 1e-5, 1e-6, 1e-7])]),
    "R2 double pendulum": ("r2_double_pendulum_precision.csv",
                           [("error", "energy drift over 10 s [m g L]", [1e-2, 1e-3, 1e-4, 1e-5])]),
    "R3 N-four-bar (0-0.6 s)": ("r3_n_four_bar_precision.csv",
                                [("error", "crank angle, max over 0-0.6 s [rad]", [1e-4, 1e-5, 1e-6, 1e-7]),
                                 ("energy_drift", "energy drift [m g L]", [1e-3, 1e-4, 1e-5, 1e-6])]),
    "R4 Bricard": ("r4_bricard_precision.csv", [("error", "energy drift over 10 s [m g L]", [1e-5, 1e-6, 1e-7])]),
    "R5 slider-crank": ("r5_slider_crank_precision.csv",
                        [("error", "slider position [m]", [1e-12]),
                         ("velocity_error", "slider velocity [m/s]", [1e-3, 1e-4, 1e-5, 1e-6])]),
    "R6 flyball governor": ("r6_flyball_governor_precision.csv",
                            [("error", "slider position, max over 10 s [m]", [1e-3, 1e-4, 1e-5])]),
    "F1 end moment": ("f1_end_moment_precision.csv", [("error", "tip position [m]", [1e-3, 1e-4, 1e-5])]),
    "F3 vibration": ("f3_vibration_precision.csv", [("error", "f1, relative", [1e-2, 2e-3, 5e-4, 1e-4, 3e-5, 1e-5])]),
    "F4 spin-up": ("f4_spin_up_precision.csv", [("error", "tip deflection at 7 s [m]", [1e-2, 1e-3, 1e-4, 1e-5]),
                                                ("elongation_error", "steady elongation [m]", [1e-5, 1e-6, 1e-7])]),
    "F4 motor-driven hub": ("f4_motor_precision.csv", [("error", "tip deflection at 7 s [m]", [1e-2, 1e-3, 1e-4])]),
    "F5 slider-crank": ("f5_slider_crank_precision.csv",
                        [("error", "mid-span deflection, max over 0.4 s [m]", [1e-3, 3e-4, 1e-4, 3e-5, 1e-5])]),
    "F6 four-bar": ("f6_four_bar_precision.csv",
                    [("error", "drive torque away from the snaps [N m]", [2e-1, 5e-2, 2e-2, 5e-3, 1e-4])]),
    "Tip mass": ("tip_mass_precision.csv", [("error", "f1, relative", [1e-2, 2e-3, 5e-4, 1e-4, 3e-5, 1e-5])]),
}


def setting(row):
    tolerance, h = row.get("tolerance"), row.get("h_s")
    if tolerance not in (None, ""):
        elements = row.get("elements")
        return f"tol={float(tolerance):g}" + (f", n={elements}" if elements not in (None, "") else "")
    return f"n={row['h_or_elements']}, h={float(h):.3g}" if h else f"{float(row['h_or_elements']):g}"


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("benchmarks/results"))
    args = parser.parse_args()
    summary = []  # one row per problem, metric, error level, code and model
    for problem, (name, metrics) in STUDIES.items():
        path = args.out / name
        if not path.exists():
            print(f"(no {name}: skipped)")
            continue
        rows = read_csv(path)
        models = list(dict.fromkeys(series_label(r) for r in rows))
        for metric, description, levels in metrics:
            for level in levels:
                entries = []
                for label in models:
                    best = cheapest_at([r for r in rows if series_label(r) == label], level, metric)
                    entries.append(dict(problem=problem, metric=description, error_level=level,
                                        code=label.split(": ")[0], model=label.split(": ", 1)[-1],
                                        wall_time_s=float(best["wall_time_s"]) if best else "",
                                        setting=setting(best) if best else "not reached"))
                ours = [e["wall_time_s"] for e in entries if e["code"] == OURS and e["wall_time_s"] != ""]
                exudyn = [e["wall_time_s"] for e in entries if e["code"] == EXUDYN and e["wall_time_s"] != ""]
                for e in entries:
                    mine = e["code"] == OURS and e["wall_time_s"] != ""
                    e["ours_over_fastest_exudyn"] = e["wall_time_s"] / min(exudyn) if mine and exudyn else ""
                    e["best_ours_over_fastest_exudyn"] = min(ours) / min(exudyn) if ours and exudyn else ""
                summary += entries
    with open(args.out / "peer_summary.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(summary[0]))
        w.writeheader()
        for e in summary:
            w.writerow({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in e.items()})
    print_markdown(summary)
    print(f"wrote {(args.out / 'peer_summary.csv').resolve()}")


def print_markdown(summary):
    print("| problem, error | level | MFBD-FMU (ours / fastest Exudyn) | Exudyn | best ours / fastest Exudyn |")
    print("|---|---|---|---|---|")
    groups = {}
    for e in summary:
        groups.setdefault((e["problem"], e["metric"], e["error_level"]), []).append(e)
    for (problem, metric, level), entries in groups.items():
        def cell(e):
            time = f"{e['wall_time_s'] * 1e3:.3g} ms" if e["wall_time_s"] != "" else "not reached"
            return f"{time} ({e['setting']})" if e["wall_time_s"] != "" else time
        def ratio_of(e):
            return f" [{e['ours_over_fastest_exudyn']:.2g}]" if e["ours_over_fastest_exudyn"] != "" else ""
        several = sum(e["code"] == OURS for e in entries) > 1
        ours = "; ".join((f"{e['model']}: " if several else "") + cell(e) + ratio_of(e)
                         for e in entries if e["code"] == OURS)
        exudyn = "; ".join(f"{e['model']}: {cell(e)}" for e in entries if e["code"] == EXUDYN)
        ratio = entries[0]["best_ours_over_fastest_exudyn"]
        print(f"| {problem}, {metric} | {level:g} | {ours} | {exudyn} | {f'{ratio:.2g}' if ratio != '' else '-'} |")


if __name__ == "__main__":
    main()
