#!/usr/bin/python3
"""Run time against error for scene "electromechanics" (issue #8, docs/benchmarks.md).

Runs one beat of the default scenario (monodomain EP at 0.1 ms, the 0-D LA) on three meshes
(geometry.target_edge_mm) x three synchronisation steps (electromechanics.sync_step_ms) with
systole-solve, and compares EF, CO, LV peak pressure and end-systolic twist with the finest run
(the smallest edge and step). Writes DIR/runtime_vs_error.csv and, when matplotlib is present,
DIR/runtime_vs_error.png.

usage: runtime_vs_error.py SYSTOLE_SOLVE OUT_DIR [--edges 2,2.5,3] [--syncs 0.5,1,2]
"""
import csv
import json
import os
import sys

from em_run import solve_case

METRICS = [("ejection_fraction_percent", "EF %"), ("cardiac_output_l_min", "CO l/min"),
           ("lv_peak_pressure_mmhg", "peak mmHg"), ("lv_twist_end_systole_deg", "twist deg")]


def run(solve, out_dir, edge_mm, sync_ms):
    scenario = {"scene": "electromechanics", "beats": 1,
                "geometry": {"target_edge_mm": edge_mm},
                "electro": {"model": "monodomain", "time_step_ms": 0.1},
                "electromechanics": {"sync_step_ms": sync_ms, "field_interval_ms": 0}}
    wall, error, m = solve_case(solve, os.path.join(out_dir, f"edge{edge_mm}_sync{sync_ms}"), scenario)
    if error:
        return {"edge_mm": edge_mm, "sync_ms": sync_ms, "wall_s": wall, "error": error[-300:]}
    row = {"edge_mm": edge_mm, "sync_ms": sync_ms, "wall_s": wall, "error": ""}
    for key, _ in METRICS:
        row[key] = m[key]
    row["lv_nodes"] = m["lv_nodes"]
    return row


def main():
    if len(sys.argv) < 3:
        print(__doc__)
        return 2
    solve, out_dir = sys.argv[1], sys.argv[2]
    edges, syncs = [2.0, 2.5, 3.0], [0.5, 1.0, 2.0]
    args = sys.argv[3:]
    for i, a in enumerate(args):
        if a == "--edges":
            edges = [float(x) for x in args[i + 1].split(",")]
        if a == "--syncs":
            syncs = [float(x) for x in args[i + 1].split(",")]
    os.makedirs(out_dir, exist_ok=True)
    rows = []
    for e in edges:
        for s in syncs:
            r = run(solve, out_dir, e, s)
            print(json.dumps(r), flush=True)
            rows.append(r)
    ok = [r for r in rows if not r["error"]]
    ref = min(ok, key=lambda r: (r["edge_mm"], r["sync_ms"])) if ok else None
    with open(os.path.join(out_dir, "runtime_vs_error.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["edge_mm", "sync_ms", "lv_nodes", "wall_s"] + [k for k, _ in METRICS] +
                   [f"diff_{k}" for k, _ in METRICS] + ["error"])
        for r in rows:
            if r["error"]:
                w.writerow([r["edge_mm"], r["sync_ms"], "", f"{r['wall_s']:.1f}"] + [""] * 8 + [r["error"]])
                continue
            diffs = [r[k] - ref[k] for k, _ in METRICS]
            w.writerow([r["edge_mm"], r["sync_ms"], int(r["lv_nodes"]), f"{r['wall_s']:.1f}"] +
                       [f"{r[k]:.3f}" for k, _ in METRICS] + [f"{d:+.3f}" for d in diffs] + [""])
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib not found: no PNG (install python3-matplotlib)")
        return 0
    fig, axes = plt.subplots(1, len(METRICS), figsize=(4 * len(METRICS), 3.6))
    for ax, (key, label) in zip(axes, METRICS):
        for e in edges:
            pts = [r for r in ok if r["edge_mm"] == e and r is not ref]
            ax.plot([r["wall_s"] for r in pts], [abs(r[key] - ref[key]) for r in pts], "o-",
                    label=f"{e:g} mm")
            for r in pts:
                ax.annotate(f"{r['sync_ms']:g}", (r["wall_s"], abs(r[key] - ref[key])), fontsize=7)
        ax.set_xlabel("wall time per beat (s)")
        ax.set_ylabel(f"|{label} - finest|")
        ax.set_title(label)
    axes[0].legend(title="edge (labels: sync ms)", fontsize=7)
    fig.suptitle(f"electromechanics, 1 beat at 70 bpm: error against the finest run "
                 f"({ref['edge_mm']:g} mm, {ref['sync_ms']:g} ms)", fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "runtime_vs_error.png"), dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main())
