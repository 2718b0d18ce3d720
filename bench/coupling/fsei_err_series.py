#!/usr/bin/env python3
# fsei_err_series.py RUN.err PERIOD_MS [LV0_ML LA0_ML] > ts.csv: the per-ms sample lines ("fsi t_ms ...") of an
# fsei_case run's stderr as a time_series.csv for fsei_beats (then: fsei_beats ts.csv PERIOD_MS), for a run still
# going (the run writes its own time_series.csv at its end).
# - The samples carry the pressures, volumes, flows and the box's kinetic energy; the series they do not carry
#   (twist, strains, tip velocities, WSS, the heart's kinetic energy) are written as 0, so fsei_beats's metrics of
#   those are meaningless here.
# - A run from t = 0 prints its first sample at 1 ms: the t = 0 row its own series starts with is added: fluid at
#   rest (pressures and flows 0) and the built chambers' volumes LV0_ML, LA0_ML (default 125 and 40 ml, the
#   procedural heart's at the default geometry).
# - The samples print 7 digits: a time within 1e-3 ms of a whole number of beats is written as that beat's end in
#   full precision, so fsei_beats finds the beats' ends.
# Checked (session 41): E1's beat 1 read from its samples equals its time_series.csv's metrics to the 4 digits
# compared (EF, EDV/ESV, LV peak, valve phases, E/A, the mitral orifice).
import sys

if len(sys.argv) not in (3, 5):
    sys.exit("usage: fsei_err_series.py RUN.err PERIOD_MS [LV0_ML LA0_ML]")
period_ms = float(sys.argv[2])
if not period_ms > 0:
    sys.exit("PERIOD_MS must be > 0, got %s" % sys.argv[2])
lv0, la0 = (sys.argv[3], sys.argv[4]) if len(sys.argv) == 5 else ("125", "40")
names = {'p_lv_mmhg': 'lv_pressure_mmhg', 'p_la_mmhg': 'la_pressure_mmhg', 'p_ao_mmhg': 'aortic_root_pressure_mmhg',
         'v_lv_ml': 'lv_volume_ml', 'v_la_ml': 'la_volume_ml', 'q_ao_ml_s': 'aortic_flow_ml_s',
         'q_mi_ml_s': 'mitral_flow_ml_s', 'ke_mj': 'kinetic_energy_mj', 'q_out_ml_s': 'aortic_outlet_flow_ml_s',
         'p_desc_mmhg': 'descending_aorta_pressure_mmhg'}
missing = ['heart_kinetic_energy_mj', 'lv_twist_deg', 'lv_longitudinal_strain', 'lv_circumferential_strain',
           'mitral_tip_velocity_m_s', 'aortic_tip_velocity_m_s', 'aortic_cusps_wss_max_pa']
rows = {}
with open(sys.argv[1]) as f:
    for line in f:
        cells = line.split()
        if len(cells) < 4 or cells[1] != 't_ms':
            continue
        rows[float(cells[2])] = {names[cells[i]]: cells[i + 1] for i in range(3, len(cells) - 1, 2) if cells[i] in names}
if not rows:
    sys.exit("no sample lines ('fsi t_ms ...') in " + sys.argv[1])
cols = list(names.values()) + missing
print(','.join(['time_s'] + cols))
if min(rows) == 1.0:
    start = {'lv_volume_ml': lv0, 'la_volume_ml': la0}
    print(','.join(['0'] + [start.get(c, '0') for c in cols]))
for t in sorted(rows):
    k = round(t / period_ms)
    t_ms = k * period_ms if k > 0 and abs(t - k * period_ms) < 1e-3 else t
    print(','.join(['%.12g' % (t_ms / 1000)] + [rows[t].get(c, '0') for c in cols]))
