#!/usr/bin/python3
"""Run time against error for scene fsi/fsei over a common window or a whole beat (issue #9,
docs/benchmarks.md).

usage: fsei_resolution_study.py OUT.png LABEL:RESULT_DIR:TIME_LOGS:RANKS[:COVERED_MS] [...]

Each run is a `fsei_case ... out=RESULT_DIR` of the same scenario at another grid, timed by
`/usr/bin/time -v` into TIME_LOGS: one log or several joined by '+', each holding one entry or
several appended with `-a` (a run made in segments from its checkpoints). Every entry's
"Elapsed (wall clock) time", "User time", "System time" and "Maximum resident set size" lines are
read (the last is the largest single process, not the ranks' sum) and its rank count from `-np N`
on its "Command being timed" line (RANKS when the line has none); the entries are summed. The
cost per beat is that sum times the beat's length over COVERED_MS, the part of the beat the logs
timed (default: the run's simulated time; give it when a part ran untimed, and say so). The last
run given is the reference (the finest grid).

Over the window all runs reached, it prints a Markdown table of the quantities below, their
relative difference from the reference, and the cost per beat: wall hours, core-hours (wall x
ranks) and the CPU time (user + system, which leaves out the waits of a run sharing its cores),
and the peak memory; it draws the differences against the CPU time per beat into OUT.png. Only
Debian's python3 and python3-matplotlib are needed.

Quantities (all read from time_series.csv and metrics.json):
  - LV peak pressure (mmHg) and aortic-root pressure at the window's end (mmHg);
  - the aortic valve's peak flow (ml/s) and the volume ejected through it (ml);
  - the velocity probe: the largest mean velocity over the disk at the closed cusps' tips (m/s);
  - the LV's leak over 20-70 ms (isovolumic): orifice flows integrated minus the volume change,
    per mean LV pressure (ml/s per mmHg): the immersed boundary's error itself;
  - when every run completed a whole beat and the window is that beat: the beat's EF (%), CO
    (l/min), the aortic valve's closing phase and the E wave's peak mitral flow (ml/s), from the
    last whole beat's metrics in metrics.json (the scene's own definitions), so each RESULT_DIR
    must hold the output written at that beat's end.
"""
import csv
import json
import os
import re
import sys


def read_series(result_dir):
    with open(os.path.join(result_dir, "time_series.csv")) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def read_time_logs(paths, ranks_default):
    """Sum of the entries of /usr/bin/time -v logs: wall s, core s (wall x ranks), CPU s, peak GB, ranks seen."""
    wall_s = core_s = cpu_s = 0.0
    rss_gb, ranks_seen, entries = 0.0, set(), 0
    for path in paths:
        with open(path) as f:
            text = f.read()
        if "Command being timed" not in text:
            sys.exit(f"{path}: no '/usr/bin/time -v' entry (was the run timed?)")
        for entry in re.split(r"(?=\tCommand being timed:)", text):
            if "Command being timed" not in entry:
                continue
            entries += 1
            np_match = re.search(r"-np (\d+)", entry)
            ranks = int(np_match.group(1)) if np_match else ranks_default
            cpu = dict(re.findall(r"(User|System) time \(seconds\): (\S+)", entry))
            wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", entry)
            if wall is None or len(cpu) != 2:
                sys.exit(f"{path}: entry {entries} lacks the '/usr/bin/time -v' wall-clock, User or System time line "
                         "(was it killed before time could write?)")
            parts = [float(p) for p in wall.group(1).split(":")]
            w = sum(p * 60 ** (len(parts) - 1 - i) for i, p in enumerate(parts))
            wall_s += w
            core_s += w * ranks
            cpu_s += float(cpu["User"]) + float(cpu["System"])
            ranks_seen.add(ranks)
            m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", entry)
            if m:
                rss_gb = max(rss_gb, int(m.group(1)) / 1024 ** 2)
    return wall_s, core_s, cpu_s, rss_gb, ranks_seen


def integrate(t_s, y, t0, t1):
    total = 0.0
    for i in range(1, len(t_s)):
        a, b = max(t_s[i - 1], t0), min(t_s[i], t1)
        if b <= a:
            continue
        f = lambda t: y[i - 1] + (y[i] - y[i - 1]) * (t - t_s[i - 1]) / (t_s[i] - t_s[i - 1])
        total += 0.5 * (b - a) * (f(a) + f(b))
    return total


def at(t_s, y, t):
    for i in range(1, len(t_s)):
        if t_s[i] >= t - 1e-12:
            w = (t - t_s[i - 1]) / (t_s[i] - t_s[i - 1])
            return y[i - 1] + w * (y[i] - y[i - 1])
    return y[-1]


def quantities(s, t_end, metrics=None):
    t = s["time_s"]
    keep = [i for i, x in enumerate(t) if x <= t_end + 1e-9]
    clip = lambda k: [s[k][i] for i in keep]
    lost = (integrate(t, s["mitral_flow_ml_s"], 0.02, 0.07) - integrate(t, s["aortic_flow_ml_s"], 0.02, 0.07)) - (
        at(t, s["lv_volume_ml"], 0.07) - at(t, s["lv_volume_ml"], 0.02))
    p_mean = integrate(t, s["lv_pressure_mmhg"], 0.02, 0.07) / 0.05
    q = {
        "LV peak pressure (mmHg)": max(clip("lv_pressure_mmhg")),
        "root pressure at end (mmHg)": at(t, s["aortic_root_pressure_mmhg"], t_end),
        "aortic peak flow (ml/s)": max(clip("aortic_flow_ml_s")),
        "ejected volume (ml)": integrate(t, [max(q, 0.0) for q in s["aortic_flow_ml_s"]], 0.0, t_end),
        "cusp-tip velocity max (m/s)": max(clip("aortic_tip_velocity_m_s")),
        "LV leak 20-70 ms (ml/s per mmHg)": lost / 0.05 / p_mean,
    }
    if metrics is not None:  # a whole beat: the scene's own beat metrics
        for name, key in (("EF (%)", "ejection_fraction_percent"), ("CO (l/min)", "cardiac_output_l_min"),
                          ("aortic valve closes (T)", "aortic_valve_close_phase"),
                          ("E wave peak (ml/s)", "mitral_e_peak_flow_ml_s")):
            if key not in metrics:
                sys.exit(f"metrics.json lacks '{key}' although a beat completed")
            q[name] = metrics[key]
    return q


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    out_png = sys.argv[1]
    runs = []
    for spec in sys.argv[2:]:
        parts = spec.split(":")
        if len(parts) not in (4, 5):
            sys.exit(f"run '{spec}': expected LABEL:RESULT_DIR:TIME_LOGS:RANKS[:COVERED_MS]")
        label, result_dir, time_logs, ranks = parts[:4]
        with open(os.path.join(result_dir, "metrics.json")) as f:
            metrics = json.load(f)
        metrics = metrics.get("metrics", metrics)
        wall_s, core_s, cpu_s, rss_gb, ranks_seen = read_time_logs(time_logs.split("+"), int(ranks))
        covered_ms = float(parts[4]) if len(parts) == 5 else metrics["simulated_time_ms"]
        if not 0 < covered_ms <= metrics["simulated_time_ms"] + 1e-6:
            sys.exit(f"run '{label}': COVERED_MS {covered_ms} is outside (0, its simulated {metrics['simulated_time_ms']} ms]")
        runs.append(dict(label=label, series=read_series(result_dir), metrics=metrics, wall_s=wall_s, core_s=core_s,
                         rss_gb=rss_gb, cpu_s=cpu_s, ranks="/".join(str(n) for n in sorted(ranks_seen)),
                         covered_ms=covered_ms))
    t_end = min(r["series"]["time_s"][-1] for r in runs)
    if t_end < 0.07:
        sys.exit(f"the common window ends at {1e3 * t_end:.1f} ms: the leak needs 70 ms")
    beat_s = 60.0 / runs[-1]["metrics"]["heart_rate_bpm"]
    # the beat metrics in metrics.json are the last whole beat's: compare them only when every run ends at beat 1's end
    whole_beat = all(abs(r["series"]["time_s"][-1] - beat_s) < 1e-4 for r in runs)
    for r in runs:
        r["q"] = quantities(r["series"], t_end, r["metrics"] if whole_beat else None)
        per_beat = beat_s / r["covered_ms"] * 1e3
        r["cpu_h_per_beat"] = r["core_s"] * per_beat / 3600
        r["wall_h_per_beat"] = r["wall_s"] * per_beat / 3600
        r["cpu_time_h_per_beat"] = r["cpu_s"] * per_beat / 3600
    ref = runs[-1]
    names = list(ref["q"])
    print(f"window 0-{1e3 * t_end:.0f} ms{' (a whole beat)' if whole_beat else ''}; reference: {ref['label']}\n")
    print("| run | grid cells | markers | ranks | timed (ms) | wall (min) | wall h per beat | core-h per beat (wall x ranks) | "
          "CPU time h per beat (user + sys) | peak memory (GB) | "
          + " | ".join(names) + " |")
    print("|" + "---|" * (10 + len(names)))
    for r in runs:
        cells = []
        for n in names:
            v = r["q"][n]
            cell = f"{v:.4g}"
            if r is not ref and ref["q"][n] != 0:
                cell += f" ({100 * (v - ref['q'][n]) / abs(ref['q'][n]):+.1f} %)"
            cells.append(cell)
        print(f"| {r['label']} | {int(r['metrics']['grid_cells'])} | {int(r['metrics']['markers'])} | {r['ranks']} | "
              f"{r['covered_ms']:.0f} | {r['wall_s'] / 60:.1f} | {r['wall_h_per_beat']:.2f} | {r['cpu_h_per_beat']:.2f} | "
              f"{r['cpu_time_h_per_beat']:.2f} | {r['rss_gb']:.2f} | " + " | ".join(cells) + " |")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for n in names:
        xs = [r["cpu_time_h_per_beat"] for r in runs[:-1]]
        ys = [max(1e-4, abs(r["q"][n] - ref["q"][n]) / abs(ref["q"][n])) for r in runs[:-1]]
        ax.loglog(xs, ys, "o-", label=n)
    band = ax.get_xaxis_transform()  # x in data, y in axes fractions: labels stay inside the axes
    ax.axvline(ref["cpu_time_h_per_beat"], color="0.4", ls=":")
    ax.text(ref["cpu_time_h_per_beat"], 0.03, f" {ref['label']} (the reference)", rotation=90, va="bottom",
            fontsize=8, transform=band)
    ax.axvline(1500, color="k", ls="--")
    ax.text(1500, 0.03, " seed: 1500 CPU-h", rotation=90, va="bottom", fontsize=8, transform=band)
    ax.axvspan(3, 10, color="0.85")
    ax.text(3.2, 0.03, " FSEI-GPU 3-10 GPU-h", rotation=90, va="bottom", fontsize=8, transform=band)
    ax.set_xlabel("CPU-hours per beat (user + sys" + (")" if whole_beat else ", extrapolated from the window)"))
    ax.set_ylabel(f"|difference| from {ref['label']} (relative)")
    ax.set_title("scene fsi: run time against error, " + ("a whole beat" if whole_beat else f"0-{1e3 * t_end:.0f} ms of the beat"))
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out_png, dpi=110)
    print(f"\nwrote {out_png}")


if __name__ == "__main__":
    main()
