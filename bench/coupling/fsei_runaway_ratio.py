#!/usr/bin/python3
"""The slow-runaway guard's two quantities along runs of scene fsi/fsei (docs/fsei.md, session 28).

usage: fsei_runaway_ratio.py [--density 1060] [--aortic-radius-mm 9.5] [--mitral-radius-mm 12] RUN.err [...]

Reads the sample lines a run prints on stderr ("fsi t_ms ... ke_mj ... v_lv_ml ... v_la_ml ...
q_ao_ml_s ... q_mi_ml_s ...") and recomputes, sample by sample, what the guard in
solver/scene/fsei_scene.cc checks: the box's kinetic energy as a mean speed of the LV's and LA's
blood, sqrt(2E / (rho V)), and its ratio to the largest mean velocity through a valve's orifice
so far (|flow| / orifice area). Prints per run the last sample, the largest speed and the largest
ratio among samples whose speed exceeds the floor, and the first sample where both bounds hold
(the guard's stop at the defaults, 1 m/s and 1). The defaults are the procedural heart's
(MODEL.md §1: orifices of 19 and 24 mm) and the blood's density.
"""
import argparse
import math


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--density", type=float, default=1060.0)
    ap.add_argument("--aortic-radius-mm", type=float, default=9.5)
    ap.add_argument("--mitral-radius-mm", type=float, default=12.0)
    ap.add_argument("--floor-m-s", type=float, default=1.0)
    ap.add_argument("--ratio", type=float, default=1.0)
    a = ap.parse_args()
    a_ao = math.pi * a.aortic_radius_mm ** 2
    a_mi = math.pi * a.mitral_radius_mm ** 2
    print("| run | last sample (ms) | largest mean speed (m/s) | largest ratio above the floor | first stop (ms) |")
    print("|---|---|---|---|---|")
    for path in a.runs:
        orifice, top_speed, top_ratio, stop, last = 0.0, 0.0, 0.0, None, None
        with open(path) as f:
            for line in f:
                w = line.split()
                if len(w) < 3 or w[1] != "t_ms":
                    continue
                d = {w[i]: w[i + 1] for i in range(len(w) - 1)}
                t = float(d["t_ms"])
                blood_m3 = 1e-6 * (float(d["v_lv_ml"]) + float(d["v_la_ml"]))
                speed = math.sqrt(2e-3 * float(d["ke_mj"]) / (a.density * blood_m3))
                orifice = max(orifice, abs(float(d["q_ao_ml_s"])) / a_ao, abs(float(d["q_mi_ml_s"])) / a_mi)
                top_speed = max(top_speed, speed)
                if speed > a.floor_m_s and orifice > 0:
                    top_ratio = max(top_ratio, speed / orifice)
                if stop is None and speed > a.floor_m_s and speed > a.ratio * orifice:
                    stop = t
                last = t
        print(f"| {path} | {last} | {top_speed:.3f} | {top_ratio:.3f} | {stop if stop is not None else '-'} |")


if __name__ == "__main__":
    main()
