#!/usr/bin/env python3
"""Regenerate tests/oracles/decotengu_reference.csv with DecoTengu 0.14.1.

DecoTengu (https://pypi.org/project/decotengu/, GPL-3) is used only as an outside oracle
through its public API; none of its code is part of decophantom. Run:

    python3 -m venv /tmp/dt && /tmp/dt/bin/pip install decotengu==0.14.1
    /tmp/dt/bin/python tests/oracles/decotengu_tables.py > tests/oracles/decotengu_reference.csv
    /tmp/dt/bin/python tests/oracles/decotengu_tables.py travel \
        > tests/oracles/decotengu_travel_reference.csv

Each row is one dive in DecoTengu's default conventions (surface 1.01325 bar, 0.09985 bar/m,
water vapour 0.0627 bar, descent 20 m/min, ascent 10 m/min, 3 m stops, last stop 3 m unless
the row says 6). Columns:

    dive, model (zh-l16b | zh-l16c), gf_low, gf_high (percent), depth_m, time_min (bottom time
    including the descent), gas (bottom gas, O2/He percent), deco_gases (space-separated
    O2/He@switch_depth_m), last_stop_m, runtime_min (time of DecoTengu's last dive step),
    stops (space-separated depth_m:minutes, empty for a no-stop dive).
"""

import csv
import sys

import decotengu
from decotengu import ZH_L16B_GF, ZH_L16C_GF

assert decotengu.__version__ == '0.14.1', decotengu.__version__

# (model, gf_low, gf_high, depth, time, (o2, he), [(o2, he, switch_depth)], last_stop_m)
DIVES = [
    ('zh-l16b', 30, 85, 35, 40, (21, 0), [], 3),
    ('zh-l16c', 30, 85, 40, 30, (21, 0), [], 3),
    ('zh-l16c', 20, 80, 45, 25, (21, 0), [(50, 0, 22)], 3),
    ('zh-l16b', 50, 80, 30, 50, (21, 0), [], 3),
    ('zh-l16c', 100, 100, 50, 20, (21, 0), [], 3),
    ('zh-l16c', 30, 70, 60, 20, (18, 45), [(50, 0, 22), (100, 0, 6)], 3),
    ('zh-l16b', 20, 80, 80, 15, (17, 50), [(50, 0, 22), (100, 0, 6)], 3),
    ('zh-l16c', 40, 85, 70, 20, (18, 45), [(50, 0, 21), (100, 0, 6)], 3),
    ('zh-l16b', 100, 100, 50, 25, (21, 35), [(50, 0, 22)], 3),
    ('zh-l16c', 30, 85, 60, 15, (21, 0), [(50, 0, 22), (100, 0, 6)], 3),
    ('zh-l16b', 30, 70, 30, 10, (21, 0), [], 3),
    ('zh-l16c', 25, 75, 50, 20, (21, 0), [(36, 0, 28), (80, 0, 9)], 3),
    ('zh-l16c', 30, 85, 45, 30, (21, 0), [(50, 0, 22)], 6),
    ('zh-l16b', 20, 90, 65, 25, (16, 55), [(35, 25, 33), (100, 0, 6)], 3),
]


def gas_text(o2, he):
    return '{}/{}'.format(o2, he)


def run(model, gf_low, gf_high, depth, time, bottom, deco, last_stop):
    engine = decotengu.create()
    engine.model = ZH_L16B_GF() if model == 'zh-l16b' else ZH_L16C_GF()
    engine.model.gf_low = gf_low / 100
    engine.model.gf_high = gf_high / 100
    engine.last_stop_6m = last_stop == 6
    engine.add_gas(0, bottom[0], bottom[1])
    for o2, he, d in deco:
        engine.add_gas(d, o2, he)
    steps = list(engine.calculate(depth, time))
    stops = ' '.join(
        '{:g}:{:g}'.format(s.depth, s.time) for s in engine.deco_table
    )
    return steps[-1].time, stops


def main():
    w = csv.writer(sys.stdout, lineterminator='\n')
    w.writerow([
        'dive', 'model', 'gf_low', 'gf_high', 'depth_m', 'time_min', 'gas',
        'deco_gases', 'last_stop_m', 'runtime_min', 'stops',
    ])
    for i, (model, lo, hi, depth, time, bottom, deco, last) in enumerate(DIVES, 1):
        runtime, stops = run(model, lo, hi, depth, time, bottom, deco, last)
        w.writerow([
            i, model, lo, hi, depth, time, gas_text(*bottom),
            ' '.join('{}@{}'.format(gas_text(o2, he), d) for o2, he, d in deco),
            last, repr(round(runtime, 10)), stops,
        ])


if __name__ == '__main__' and sys.argv[1:] != ['travel']:
    main()


# Travel-gas dives (`travel` mode, tests/oracles/decotengu_travel_reference.csv):
# (model, gf_low, gf_high, depth, time, bottom (o2, he), [(o2, he, from_m, to_m)] travel
# gases, [(o2, he, switch_depth)] deco gases). DecoTengu breathes a travel gas on the descent
# only; decophantom offers it again on the ascent from the deep end of its range, so each
# travel gas is also given to DecoTengu as a deco gas switched at that depth (same ascent).
TRAVEL_DIVES = [
    ('zh-l16c', 30, 85, 110, 20, (10, 70), [(21, 35, 0, 60)], [(50, 0, 22), (100, 0, 6)]),
    ('zh-l16c', 50, 80, 110, 20, (10, 70), [(21, 35, 0, 60)], [(50, 0, 22), (100, 0, 6)]),
    ('zh-l16c', 30, 85, 110, 20, (10, 70), [(21, 35, 0, 40), (15, 55, 40, 70)],
     [(50, 0, 22), (100, 0, 6)]),
    ('zh-l16b', 30, 70, 100, 15, (12, 65), [(21, 35, 0, 57)], [(50, 0, 22), (100, 0, 6)]),
]


def run_travel(model, gf_low, gf_high, depth, time, bottom, travel, deco):
    engine = decotengu.create()
    engine.model = ZH_L16B_GF() if model == 'zh-l16b' else ZH_L16C_GF()
    engine.model.gf_low = gf_low / 100
    engine.model.gf_high = gf_high / 100
    for o2, he, frm, _ in travel:
        engine.add_gas(frm, o2, he, travel=True)
    engine.add_gas(travel[-1][3], bottom[0], bottom[1])
    for o2, he, _, to in travel:
        engine.add_gas(to, o2, he)
    for o2, he, d in deco:
        engine.add_gas(d, o2, he)
    steps = list(engine.calculate(depth, time))
    stops = ' '.join(
        '{:g}:{:g}'.format(s.depth, s.time) for s in engine.deco_table
    )
    return steps[-1].time, stops


def main_travel():
    w = csv.writer(sys.stdout, lineterminator='\n')
    w.writerow([
        'dive', 'model', 'gf_low', 'gf_high', 'depth_m', 'time_min', 'gas',
        'travel_gases', 'deco_gases', 'runtime_min', 'stops',
    ])
    for i, (model, lo, hi, depth, time, bottom, travel, deco) in enumerate(
            TRAVEL_DIVES, 1):
        runtime, stops = run_travel(model, lo, hi, depth, time, bottom, travel, deco)
        w.writerow([
            i, model, lo, hi, depth, time, gas_text(*bottom),
            ' '.join('{}@{}..{}'.format(gas_text(o2, he), f, t)
                     for o2, he, f, t in travel),
            ' '.join('{}@{}'.format(gas_text(o2, he), d) for o2, he, d in deco),
            repr(round(runtime, 10)), stops,
        ])


if __name__ == '__main__' and sys.argv[1:] == ['travel']:
    main_travel()
