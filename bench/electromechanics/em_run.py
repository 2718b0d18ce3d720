"""One systole-solve run of a scenario in its own directory, shared by the electromechanics
bench scripts (one_beat.py, runtime_vs_error.py)."""
import json
import os
import subprocess
import time


def solve_case(solve, case_dir, scenario):
    """Writes case_dir/scenario.json, runs `solve scenario.json --out case_dir --quiet`.
    Returns (wall seconds, error text or "", metrics dict or None)."""
    if not (os.path.isfile(solve) and os.access(solve, os.X_OK)):
        raise SystemExit(f"systole-solve: '{solve}' is not an executable file (build first: deploy/setup)")
    os.makedirs(case_dir, exist_ok=True)
    path = os.path.join(case_dir, "scenario.json")
    with open(path, "w") as f:
        json.dump(scenario, f)
    start = time.monotonic()
    proc = subprocess.run([solve, path, "--out", case_dir, "--quiet"], capture_output=True, text=True)
    wall_s = time.monotonic() - start
    if proc.returncode != 0:
        return wall_s, f"rc {proc.returncode}: {proc.stderr.strip()[-400:]}", None
    with open(os.path.join(case_dir, "metrics.json")) as f:
        m = json.load(f)
    return wall_s, "", m.get("metrics", m)
