#!/usr/bin/env python3
"""What a sweep's long slides are made of: each run whose longest slip after
detection is over --min-ms (40 ms), its worst slide, and the kind of that
slide (design-notes.md, "Where the drawn terrains' long slides come from").

    build/host/hyq_sim sweep sim_host/sweeps/terrain_validation.yaml --out out/terrain_validation
    python3 docs/long_slides.py out/terrain_validation --sim build/host/hyq_sim [--min-ms 40] [--recovery off]

The runs come from the sweep's sweep.csv (its id, recovery,
terrain.generate.seed and after_detection_max_ms columns); only those with
the --recovery setting asked for (on) are read. A sweep keeps no log.csv,
so each such run is run again from its case's scenario.yaml (the same run,
tick for tick) into --work (<sweep>/long_slides). From the run's events.csv the true slips of each
foot (contact-point speed over the threshold, runs closer than 20 ms
merged, at least 5 ms long; docs/metrics.md) are matched with the flag runs
that overlap them, and the time after detection is the slip's end less the
later of its start and its first flag. The worst slide is the one closest
to the run's after_detection_max_ms. Its kind, from the
run's log.csv:

- trot: the run trots (two feet or fewer in stance on some tick);
- at a stop: a joint of the sliding leg within 0.015 rad of its stop on at
  least half the slide's ticks;
- stance in the air: the gait put the foot in stance more than 3 ms before
  it touched the ground;
- other.

Prints one line per run (terrain seed, worst slide in ms, leg, start [s],
kind, and the joint at its stop) and the count of each kind, with how many
of them are over 100 ms and the longest. Standard library only.
"""
import argparse
import csv
import math
import os
import subprocess
import sys

from touchdown_slips import read

LEGS = ["LF", "RF", "LH", "RH"]
MERGE_GAP = 0.020     # [s] true slips closer than this are one (docs/metrics.md)
MIN_SLIP = 0.005      # [s] shorter true slips are no event
MATCH_AFTER = 0.050   # [s] a flag that rises this long after a slip's end still matches it (the metric's match_after)
STOP_MARGIN = 0.015   # [rad] a joint this near its stop is at it
AIR_LEAD = 0.003      # [s] stance this much before contact: put in stance in the air
LOOK_BACK = 0.3       # [s] how far before the slide the stance and contact rises are looked for
# [rad] joint stops (HAA, HFE, KFE) of the front and hind legs (robot_params.hpp)
STOPS = {"F": [(-1.2217, 0.4363), (-0.8727, 1.2217), (-2.4435, -0.3491)],
         "H": [(-1.2217, 0.4363), (-1.2217, 0.8727), (0.3491, 2.4435)]}
JOINTS = ["haa", "hfe", "kfe"]


def events(path):
    """Each leg's true slips [start, end] and flag runs [rise, fall] from events.csv."""
    slips = {leg: [] for leg in LEGS}
    flags = {leg: [] for leg in LEGS}
    rise = {}
    with open(path) as f:
        for row in csv.reader(f):
            if not row or row[0] == "time":
                continue
            t, kind, leg = float(row[0]), row[2], row[3]
            if kind == "slip_start":
                if slips[leg] and t - slips[leg][-1][1] <= MERGE_GAP + 1e-6:
                    continue
                slips[leg].append([t, t])
            elif kind == "slip_end" and slips[leg]:
                slips[leg][-1][1] = t
            elif kind == "slip_flag_on":
                rise[leg] = t
            elif kind == "slip_flag_off" and leg in rise:
                flags[leg].append((rise.pop(leg), t))
    for leg, t in rise.items():
        flags[leg].append((t, math.inf))
    return slips, flags


def detected_slides(slips, flags):
    """(after detection [ms], leg, start, end) of every detected true slip."""
    out = []
    for leg in LEGS:
        for start, end in slips[leg]:
            if end - start < MIN_SLIP - 1e-6:
                continue
            hits = [f for f in flags[leg] if f[1] >= start and f[0] <= end + MATCH_AFTER]
            if hits:
                out.append(((end - max(hits[0][0], start)) * 1000.0, leg, start, end))
    return out


def last_rise(values):
    """Index of the last 0 -> 1 step in values, or None."""
    found = None
    for i in range(1, len(values)):
        if values[i] and not values[i - 1]:
            found = i
    return found


def kind_of(cols, rows, leg, start, end):
    """The slide's kind and the joint at its stop ('' if none)."""
    li = LEGS.index(leg)
    if any(bin(int(r[cols["stance_mask"]])).count("1") <= 2 for r in rows):
        return "trot", ""
    stops = STOPS[leg[1]]
    during = [r for r in rows if start - 1e-6 <= r[0] <= end + 1e-6]
    at_stop, joint = 0, ""
    for r in during:
        for j, (lo, hi) in enumerate(stops):
            q = r[cols[f"q_{leg}_{JOINTS[j]}"]]
            if q < lo + STOP_MARGIN or q > hi - STOP_MARGIN:
                at_stop += 1
                joint = JOINTS[j]
                break
    if during and 2 * at_stop >= len(during):
        return "at a stop", joint
    before = [r for r in rows if start - LOOK_BACK <= r[0] <= start + 0.01]
    contact = last_rise([r[cols[f"{leg}_contact"]] > 0.5 for r in before])
    stance = last_rise([(int(r[cols["stance_mask"]]) >> li) & 1 for r in before])
    if contact is not None and stance is not None and before[contact][0] - before[stance][0] > AIR_LEAD:
        return "stance in the air", ""
    return "other", ""


def rerun(case_dir, work, sim):
    """The case run again with its log, into work/<case>; its folder."""
    out = os.path.join(work, os.path.basename(case_dir))
    if not os.path.exists(os.path.join(out, "log.csv")):
        cmd = [sim, "run", os.path.join(case_dir, "scenario.yaml"), "--quiet", "--out", out]
        subprocess.run(cmd, check=True)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sweep")
    ap.add_argument("--sim", default="build/host/hyq_sim")
    ap.add_argument("--min-ms", type=float, default=40.0)
    ap.add_argument("--work")
    ap.add_argument("--recovery", choices=["on", "off"], default="on")
    a = ap.parse_args()
    work = a.work or os.path.join(a.sweep, "long_slides")
    os.makedirs(work, exist_ok=True)
    counts = {}
    with open(os.path.join(a.sweep, "sweep.csv")) as f:
        cases = sorted(csv.DictReader(f), key=lambda c: c["id"])
    for c in cases:
        if c["recovery"] != a.recovery or not c["after_detection_max_ms"]:
            continue
        worst = float(c["after_detection_max_ms"])
        if worst <= a.min_ms:
            continue
        case, case_dir = c["id"], os.path.join(a.sweep, "cases", c["id"])
        run = rerun(case_dir, work, a.sim)
        slides = detected_slides(*events(os.path.join(run, "events.csv")))
        if not slides:
            continue
        _, leg, start, end = min(slides, key=lambda s: abs(s[0] - worst))
        names = ["time", "stance_mask", f"{leg}_contact"] + [f"q_{leg}_{j}" for j in JOINTS]
        cols, rows = read(os.path.join(run, "log.csv"), names)
        kind, joint = kind_of(cols, rows, leg, start, end)
        seed = c.get("terrain.generate.seed") or "-"
        print(f"{case} terrain {seed}: {worst:.0f} ms, {leg} at {start:.3f} s, {kind} {joint}")
        n = counts.setdefault(kind, [0, 0, 0.0])
        n[0] += 1
        n[1] += worst > 100.0
        n[2] = max(n[2], worst)
    print(f"\nruns over {a.min_ms:.0f} ms after detection, by their worst slide:")
    for kind, (n, over, top) in sorted(counts.items()):
        print(f"  {kind}: {n} runs, {over} over 100 ms, longest {top:.0f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
