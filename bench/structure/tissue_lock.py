#!/usr/bin/env python3
"""Issue #60, item 1: the LV at isobaric end-systole in scene `mechanics`, for today's
calibrated chamber walls and for the seed's tissue law as printed (docs/structure.md,
"The printed law against the calibrated walls").

For each wall, active tension {80, 120, 160} kPa x cavity pressure {80, 110} mmHg, ramped
together over structure.pressure_ramp_ms and held, damped, to equilibrium; prints one markdown
row per run and E_es = 30 mmHg / (V(110) - V(80)) per tension.

  python3 bench/structure/tissue_lock.py [--solve build/bin/systole-solve] [--out bench-out/tissue_lock]
      [--walls W1,W2,...] [--end-ms 300] [--tensions 80,120,160] [--pressures 80,110] [--extra JSON]

Walls (WALLS below): calibrated, printed, printed_capped, printed_capped_isotropic,
printed_membrane, printed_membrane_isotropic. --extra merges a JSON object into every scenario,
by section (e.g. '{"geometry": {"lv_fibre_angle_deg": 0}}').
"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "electromechanics"))
from em_run import solve_case  # noqa: E402

# The two walls. "calibrated": the LV as electromechanics builds it (structure.walls = chamber,
# every electromechanics.* and tissue.* default). "printed": eq 16-17 as printed (law fung,
# c 13.3 Pa, alpha_f 49.56, alpha_c 5.29, 1.05 g/ml, bending eq 19), active tension along the
# fibre only (no cross-fibre share, no length-tension), tension on every node, no area floor.
WALLS = {
    "calibrated": {"structure": {"walls": "chamber"}},
    "printed": {"structure": {"walls": "structure", "law": "fung", "bending": True, "area_floor": 0},
                "tissue": {"active_min_fibre_stretch": 0, "active_cross_fibre_fraction": 0,
                           "density_g_per_ml": 1.05}},
}
# The printed law with its compressive stiffening kept but bounded so that the explicit step
# survives: law fung_tension with fraction 1 (the Fung law both ways) up to alpha eps^2 = 6
# (|eps| = 0.348 at alpha_f, where eq 17 gives 92 kPa: the predicted lock is inside the cap), the
# area floor 0.5 (the spring network's in-plane collapse, which stops the literal law first), and
# optionally alpha_c = alpha_f (the cross-fibre direction otherwise holds at most c alpha_c e^alpha_c).
_CAPPED = {"law": "fung_tension", "fung_exponent_cap": 6, "fung_compression_fraction": 1, "area_floor": 0.5}
WALLS["printed_capped"] = {"structure": dict(WALLS["printed"]["structure"], **_CAPPED),
                           "tissue": dict(WALLS["printed"]["tissue"])}
# The printed law on the constant-strain membrane triangles (structure.membrane = triangles):
# eq 16's energy in the Green strain of the fibre frame, no cap, no area floor.
WALLS["printed_membrane"] = {"structure": dict(WALLS["printed"]["structure"], membrane="triangles"),
                             "tissue": dict(WALLS["printed"]["tissue"])}
WALLS["printed_membrane_isotropic"] = {"structure": dict(WALLS["printed"]["structure"], membrane="triangles"),
                                       "tissue": dict(WALLS["printed"]["tissue"], lv={"alpha_c": 49.56})}
WALLS["printed_capped_isotropic"] = {"structure": dict(WALLS["printed"]["structure"], **_CAPPED),
                                     "tissue": dict(WALLS["printed"]["tissue"], lv={"alpha_c": 49.56})}


def scenario(wall, tension_kpa, pressure_mmhg, end_ms, ramp_ms, extra):
    s = {"scene": "mechanics",
         "structure": {"body": "lv", "cavity_pressure_mmhg": pressure_mmhg, "active_tension_kpa": tension_kpa,
                       "pressure_ramp_ms": ramp_ms, "end_time_ms": end_ms, "output_interval_ms": 1,
                       "damping_per_ms": 0.1, "write_positions": False},
         "outputs": {"time_series": True}}
    for section, fields in list(WALLS[wall].items()) + list(extra.items()):
        s.setdefault(section, {}).update(json.loads(json.dumps(fields)))
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--solve", default="build/bin/systole-solve")
    ap.add_argument("--out", default="bench-out/tissue_lock")
    ap.add_argument("--walls", default="calibrated,printed,printed_capped,printed_capped_isotropic")
    ap.add_argument("--end-ms", type=float, default=300)
    ap.add_argument("--ramp-ms", type=float, default=40)
    ap.add_argument("--tensions", default="80,120,160")
    ap.add_argument("--pressures", default="80,110")
    ap.add_argument("--extra", default="{}", help="JSON merged into every scenario, by section")
    a = ap.parse_args()
    extra = json.loads(a.extra)
    tensions = [float(x) for x in a.tensions.split(",")]
    pressures = [float(x) for x in a.pressures.split(",")]
    cols = ["wall", "tau kPa", "p mmHg", "V ml", "GCS %", "GLS %", "twist deg", "fibre stretch",
            "fibre eps p05/p50/p95", "cross eps p05/p50/p95", "oblique eps p05/p50/p95", "KE/elastic", "substeps", "wall s"]
    print("| " + " | ".join(cols) + " |")
    print("|" + "---|" * len(cols))
    volumes = {}
    for wall in a.walls.split(","):
        for tau in tensions:
            for p in pressures:
                name = f"{wall}-t{tau:g}-p{p:g}"
                wall_s, err, m = solve_case(a.solve, os.path.join(a.out, name),
                                            scenario(wall, tau, p, a.end_ms, a.ramp_ms, extra))
                if m is None:
                    print(f"| {wall} | {tau:g} | {p:g} | failed: {err.replace('|', '/')} |" + " |" * (len(cols) - 4))
                    continue
                volumes[(wall, tau, p)] = m["lv_volume_final_ml"]
                trip = lambda d: "/".join(f"{m.get(f'lv_edge_strain_{d}_{q}', float('nan')):.3f}" for q in ("p05", "p50", "p95"))
                ke = m["kinetic_energy_final_uj"] / max(1e-30, m["elastic_energy_final_uj"])
                print(f"| {wall} | {tau:g} | {p:g} | {m['lv_volume_final_ml']:.1f} | {m['lv_gcs_percent']:.1f} | "
                      f"{m['lv_gls_percent']:.1f} | {m['lv_twist_deg']:.1f} | {m['lv_fibre_stretch_mean']:.3f} | "
                      f"{trip('fibre')} | {trip('cross')} | {trip('oblique')} | {ke:.1e} | {m['substeps']:.0f} | {wall_s:.0f} |",
                      flush=True)
    print()
    print("| wall | tau kPa | E_es mmHg/ml |")
    print("|---|---|---|")
    for wall in a.walls.split(","):
        for tau in tensions:
            v = [volumes.get((wall, tau, p)) for p in pressures]
            if len(v) >= 2 and None not in v[:2] and v[1] != v[0]:
                print(f"| {wall} | {tau:g} | {(pressures[1] - pressures[0]) / (v[1] - v[0]):.2f} |")
            else:
                print(f"| {wall} | {tau:g} | n/a |")


if __name__ == "__main__":
    main()
