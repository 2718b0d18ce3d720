#!/usr/bin/python3
"""One beat of scene "electromechanics" on the default heart, with the time split per module
(issue #8's cost goal: <= 60 s wall on 2 cores; results in docs/benchmarks.md).

Runs systole-solve on {"scene": "electromechanics", "beats": 1} (every other field at its
default: the 2 mm heart, bidomain EP at 0.05 ms, the 0-D LA) and, for comparison, the same
scenario with monodomain EP at 0.1 ms. Prints one Markdown row per run: wall time of the
process, the scene's own per-module wall times (ep_wall_s, structure_wall_s, lumped_wall_s),
structure substeps, coupling passes per interval, and the beat's EF / peak pressure so that a
faster run can be checked against a slower one.

usage: one_beat.py SYSTOLE_SOLVE OUT_DIR [--only default|monodomain]
"""
import os
import sys

from em_run import solve_case

CASES = {
    "default": {},
    "monodomain": {"electro": {"model": "monodomain", "time_step_ms": 0.1}},
}


def run(solve, out_dir, name, overrides):
    scenario = {"scene": "electromechanics", "beats": 1,
                "electromechanics": {"field_interval_ms": 0}}
    scenario.update(overrides)
    wall_s, error, m = solve_case(solve, os.path.join(out_dir, name), scenario)
    if error:
        sys.exit(f"{name}: systole-solve failed ({error})")
    return wall_s, m


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    solve, out_dir = argv[1], argv[2]
    only = argv[4] if len(argv) > 4 and argv[3] == "--only" else None
    if only is not None and only not in CASES:
        sys.exit(f"--only: '{only}' is not one of {', '.join(CASES)}")
    print("| EP | wall (s) | EP (s) | structure (s) | 0-D (s) | substeps | passes / interval | EF % | peak mmHg |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, overrides in CASES.items():
        if only is not None and name != only:
            continue
        wall_s, m = run(solve, out_dir, name, overrides)
        print(f"| {name} | {wall_s:.1f} | {m['ep_wall_s']:.1f} | {m['structure_wall_s']:.1f} | "
              f"{m['lumped_wall_s']:.2f} | {m['structure_substeps']:.0f} | "
              f"{m['coupling_passes_per_interval']:.2f} | {m['ejection_fraction_percent']:.2f} | "
              f"{m['lv_peak_pressure_mmhg']:.1f} |", flush=True)


if __name__ == "__main__":
    main(sys.argv)
